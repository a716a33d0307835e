"""Grey-box estimation on the excited lines of periodic data (``greyest(..., periods=)``) or
of an FRD with its noise variance (``greyest(frd, structure)``).

The sampled structure's response ``G(e^{j w_k}) = C (e^{j w_k} I - A)^-1 B + D`` (a
continuous structure through its discretisation with the structure's hold, as in the time
domain; input delays as shift-register states) is fitted to the measured ``G_k`` on the
lines, each entry weighted by the inverse of its noise variance (from the spread over the
periods, :func:`sysid.bla`):

.. code-block:: text

    minimise  1/2 sum_k sum_ij 2 |G_ij(e^{j w_k}; p) - G_k,ij|^2 / s2_k,ij

The Rust core (``sysid_core::greybox::frequency``) forms the residuals and their
sensitivities to the entries of ``A, B, C, D`` (those of ``sysid.pem``'s frequency path) and
the shared optimiser searches ``p`` through the chain rule with ``d(A, B, C, D)/dp`` from the
structure (analytic, central differences, Fréchet derivative of the matrix exponential). The
covariance of ``p`` is ``c s (J^T W J)^-1`` with ``s = 2 V / (residuals - rank)`` and ``c``
the factor for variances estimated from the periods
(:func:`sysid.pem.periodic.sample_variance_factor`: ``(M - 2) / (M - 3)`` with ``M``
periods, ``info["sample_variance_factor"]``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import _sysid
from ..errors import DataError
from ..models.frd import FRD
from ..pem.periodic import CRITERION, line_weights, sample_variance_factor
from .delays import tap_states
from .greybox import GreyBox
from .outer import OuterParameters, model_of
from .results import GreyEstimate

__all__: list[str] = []


class _LineFit(OuterParameters):
    """One grey-box fit to the lines of ``frd``: the map ``z -> (A, B, C, D)`` with its
    Jacobian, the core call and the estimate."""

    def __init__(self, s: GreyBox, frd: FRD) -> None:
        super().__init__(s)
        if frd.dt is None:
            raise DataError("the FRD has no sample time (frd.dt): the structure is sampled "
                            "at it; build the FRD with dt=")
        self.dt = dt = float(frd.dt)
        if (frd.n_inputs, frd.n_outputs) != (s.ninputs, s.noutputs):
            raise DataError(f"the structure has {s.ninputs} input(s) and {s.noutputs} "
                            f"output(s), the frequency response {frd.n_inputs} and "
                            f"{frd.n_outputs}")
        if s.dt is not None and not s.continuous and abs(s.dt - dt) > 1e-9 * dt:
            raise DataError(f"the structure's dt={s.dt} differs from the data's dt={dt}: "
                            "give the structure the data's sample time")
        self.taps = s.input_taps(dt)
        zero = {k: np.zeros_like(v) for k, v in s.sampled_taps(None, dt)[0].items()
                if k in ("A", "B", "C", "D")}
        # the shift-register part of the delay states: constant in the parameters
        self.shift = [np.asarray(x) for x in tap_states(zero, self.taps, s.ninputs)[:4]]
        self.n, self.m, self.l = self.shift[0].shape[0], s.ninputs, s.noutputs
        nk = frd.omega.size
        self.omega = np.ascontiguousarray(frd.omega * dt)
        if np.any(self.omega < 0) or np.any(self.omega > np.pi * (1 + 1e-12)):
            raise DataError("the lines must lie in [0, pi/dt] (up to the Nyquist frequency)")
        self.omega = np.clip(self.omega, 0.0, np.pi)
        g = frd.response.reshape(nk, -1)
        self.re, self.im = np.ascontiguousarray(g.real), np.ascontiguousarray(g.imag)
        self.weight = np.ascontiguousarray(line_weights(frd).reshape(nk, -1))
        self.factor = sample_variance_factor(frd, "greyest")
        self.names_io = {"input_names": frd.input_names, "output_names": frd.output_names}

    def theta(self, z: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
        vals = self.values(z)
        base, ders = self.s.sampled_taps(vals, self.dt, self.free if jac else None)
        mats = tap_states(base, self.taps, self.m)[:4]
        th = np.concatenate([np.asarray(x).ravel() for x in mats])
        if not jac:
            return th, None
        M = np.zeros((th.size, z.size))
        for j, d in enumerate(ders):
            dm = tap_states(d, self.taps, self.m)[:4]
            M[:, j] = np.concatenate([(np.asarray(x) - s0).ravel()
                                      for x, s0 in zip(dm, self.shift)]) * self.scale[j]
        return th, M

    def run(self, z0: np.ndarray, max_iter: int, tol: float, cb: Any) -> dict[str, Any]:
        res = _sysid.greybox_frequency(
            (self.n, self.m, self.l), self.omega, self.re, self.im, self.weight,
            lambda z, jac: self.theta(z, jac), list(map(float, z0)),
            search={"lower": list(self.lower), "upper": list(self.upper),
                    "max_iter": max_iter, "tol_cost": tol}, progress=cb)
        res["start"] = z0
        return res

    def result(self, res: dict[str, Any], starts: list[float | None],
               extra: dict[str, Any]) -> GreyEstimate:
        info = {
            "method": "greyest", "domain": "frequency", "iterations": res["iterations"],
            "evaluations": res["evaluations"], "cost": list(res["history"]),
            "criterion": CRITERION, "weighted_cost": list(res["weighted_history"]),
            "stop": res["stop"], "condition": res["condition"], "rank": int(res["rank"]),
            "n_free": self.nf, "lines": int(self.omega.size),
            "n_residuals": int(res["n_residuals"]),
            "residual_scale": float(res["residual_scale"]),
            "sample_variance_factor": self.factor,
            "spectral_radius": float(res["spectral_radius"]), "focus": "simulation",
            "noise": "none", "x0_values": [], "multistart": starts, **extra,
        }
        res = {**res, "covariance": np.asarray(res["covariance"]) * self.factor}
        table, cov, est, model = self.estimate(
            res, lambda s, v, inf: model_of(s, v, self.dt, None, self.names_io, None, inf),
            info)
        return GreyEstimate(table, cov, list(self.free), model, est, [], info)


def greyest_lines(frd: FRD, structure: GreyBox, *, multistart: int, rng: Any, max_iter: int,
                  tol: float, progress: Any, extra: dict[str, Any]) -> GreyEstimate:
    """:func:`sysid.greyest` on the lines of ``frd`` (internal: the caller checked the
    options; ``extra`` goes to ``info``: the periods, the transient, the detection)."""
    fit = _LineFit(structure, frd)
    best, starts = fit.best_of_starts(max_iter, tol, progress, multistart, rng, "cost")
    return fit.result(best, starts, extra)
