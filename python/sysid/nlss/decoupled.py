"""Decoupled PNLSS models: a few univariate polynomials of linear forms instead of all
monomials.

.. code-block:: text

    x(t+1) = A x + B u + W g(V [x; u]) + e0       y(t) = C x + D u + f0
    g_k(s) = sum_d c[k, d] s^d

in scaled channels. ``r`` branches cost ``r (2 nx + nu + n_degrees)`` parameters, against
``nx`` times the number of monomials (which grows as ``(nx + nu)^degree``) for the coupled
model: the form of Fakhrizadeh Esfahani, Dreesen, Tiels, Noël & Schoukens (MSSP 2018) and of
Csurcsia & De Troyer (SYSID 2021), here trained directly in decoupled form on the
simulation error (:func:`sysid.pnlss` with ``branches=``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .. import _sysid
from ..errors import DataError
from ..models.protocol import ModelMixin
from ..models.serialize import register_model
from ..models.statespace import StateSpaceModel
from .common import (
    LinearPart,
    channels,
    check_parameters,
    clamp_box,
    envelope,
    fit_summary,
    held_stable,
    linear_states,
    signal,
)

__all__ = ["DecoupledPNLSSModel"]

STARTS, STARTS_ITER = 3, 8  # random starts of the branch directions, iterations each


@register_model
class DecoupledPNLSSModel(LinearPart, ModelMixin):
    """A decoupled polynomial nonlinear state-space model (see the module documentation),
    from :func:`sysid.pnlss` with ``branches=``.

    Parameters
    ----------
    A, B, C, D : array_like
        Linear part (scaled channels).
    V : array_like
        ``branches x (nstates + ninputs)``: the branch arguments ``s = V [x; u]``.
    W : array_like
        ``nstates x branches``: how the branches enter the state equation.
    c : array_like
        ``branches x len(degrees)``: the branch polynomials' coefficients.
    e0, f0 : array_like
        Constants of the state and output equations.
    degrees : list of int
        Degrees of the branch polynomials (each at least 2).
    scaling : dict, optional
        ``u_offset, u_scale, y_offset, y_scale`` of the channels.
    clamp : tuple of array_like, optional
        ``(lo, hi)`` per branch: the branch arguments are clamped to it (``None``: not).
    dt : float
    input_names, output_names : list of str, optional
    info : dict, optional

    Examples
    --------
    >>> import sysid
    >>> m = sysid.DecoupledPNLSSModel([[0.5]], [[1.0]], [[1.0]], [[0.0]], V=[[1.0, 1.0]],
    ...                               W=[[-0.1]], c=[[1.0]], degrees=[2])
    >>> m.simulate([1.0, 0.0, 0.0])[:, 0]
    array([0.   , 0.9  , 0.369])
    >>> m.n_parameters
    8
    """

    def __init__(self, A: Any, B: Any, C: Any, D: Any, *, V: Any, W: Any, c: Any,
                 degrees: Any, e0: Any = None, f0: Any = None,
                 scaling: dict[str, Any] | None = None, clamp: Any = None, dt: float = 1.0,
                 input_names: Any = None, output_names: Any = None,
                 info: dict[str, Any] | None = None) -> None:
        a2 = lambda v: np.atleast_2d(np.asarray(v, float))  # noqa: E731
        self.A, self.B, self.C, self.D = a2(A), a2(B), a2(C), a2(D)
        n, m, l_ = self.A.shape[0], self.B.shape[1], self.C.shape[0]
        self.degrees = sorted({int(d) for d in np.ravel(degrees)})
        self.V, self.W, self.c = a2(V), a2(W), a2(c)
        r = self.V.shape[0]
        self.e0 = np.zeros(n) if e0 is None else np.asarray(e0, float).ravel()
        self.f0 = np.zeros(l_) if f0 is None else np.asarray(f0, float).ravel()
        if self.A.shape != (n, n) or self.B.shape[0] != n or self.C.shape[1] != n \
                or self.D.shape != (l_, m) or self.V.shape != (r, n + m) \
                or self.W.shape != (n, r) or self.c.shape != (r, len(self.degrees)) \
                or self.e0.size != n or self.f0.size != l_:
            raise DataError(f"A {self.A.shape}, B {self.B.shape}, C {self.C.shape}, D "
                            f"{self.D.shape}, V {self.V.shape}, W {self.W.shape} and c "
                            f"{self.c.shape} do not fit together")
        self.scaling, self.input_names, self.output_names = channels(
            scaling, m, l_, input_names, output_names)
        self.clamp = None if clamp is None else clamp_box(clamp, r)
        self.dt = float(dt)
        self.info = dict(info or {"method": "pnlss (decoupled)"})

    nstates = property(lambda self: self.A.shape[0])
    ninputs = property(lambda self: self.B.shape[1])
    noutputs = property(lambda self: self.C.shape[0])
    branches = property(lambda self: self.V.shape[0])

    @property
    def n_parameters(self) -> int:
        """Number of coefficients (the state basis and the branch scales make ``nstates^2 +
        branches`` of them redundant)."""
        return int(self.theta.size - self.nstates ** 2 - self.branches)

    @property
    def theta(self) -> np.ndarray:
        """``[A, B, C, D, V, W, c, e0, f0]`` row-major (the core's parameter vector)."""
        return np.concatenate([np.ravel(a) for a in (self.A, self.B, self.C, self.D, self.V,
                                                     self.W, self.c, self.e0, self.f0)])

    def _struct(self) -> dict[str, Any]:
        rng = None if self.clamp is None else (list(self.clamp[0]), list(self.clamp[1]))
        return {"dims": (self.nstates, self.ninputs, self.noutputs), "branches": self.branches,
                "degrees": self.degrees, "range": rng}

    def _run(self, u: Any, x0: Any) -> tuple[np.ndarray, np.ndarray]:
        a = signal(u, self.ninputs, "u")
        x = None if x0 is None else [float(v) for v in np.ravel(x0)]
        y, xs = _sysid.pnlss_simulate(self._struct(), list(self.theta), self.scaling.u(a), x)
        return np.asarray(y).reshape(-1, self.noutputs), np.asarray(xs).reshape(-1, self.nstates)

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        """Output ``(n_samples, noutputs)`` from ``x0`` (scaled-state coordinates; zero by
        default). Raises :class:`~sysid.NumericalError` when the state diverges."""
        return self.scaling.y_back(self._run(u, x0)[0])

    def states(self, u: Any, x0: Any = None) -> np.ndarray:
        """Simulated states ``(n_samples, nstates)`` (scaled coordinates)."""
        return self._run(u, x0)[1]

    def linear(self) -> StateSpaceModel:
        """The linear part ``(A, B, C, D)`` in engineering units."""
        return self.scaling.to_units(self.A, self.B, self.C, self.D, self)

    def to_dict(self) -> dict[str, Any]:
        return {"A": self.A, "B": self.B, "C": self.C, "D": self.D, "V": self.V, "W": self.W,
                "c": self.c, "e0": self.e0, "f0": self.f0, "degrees": self.degrees,
                "scaling": self.scaling.to_dict(),
                "clamp": None if self.clamp is None else [self.clamp[0], self.clamp[1]],
                "dt": self.dt, "input_names": self.input_names,
                "output_names": self.output_names, "info": self.info}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> DecoupledPNLSSModel:
        return cls(d["A"], d["B"], d["C"], d["D"], V=d["V"], W=d["W"], c=d["c"],
                   degrees=d["degrees"], e0=d["e0"], f0=d["f0"], scaling=d["scaling"],
                   clamp=d.get("clamp"), dt=d["dt"], input_names=d["input_names"],
                   output_names=d["output_names"], info=d.get("info"))

    def summary(self) -> str:
        return fit_summary(self)

    def __repr__(self) -> str:
        return (f"DecoupledPNLSSModel(nstates={self.nstates}, ninputs={self.ninputs}, "
                f"noutputs={self.noutputs}, branches={self.branches}, "
                f"degrees={self.degrees}, dt={self.dt:g})")


def n_parameters(n: int, m: int, l_: int, branches: int, n_degrees: int) -> int:
    """Parameters of a decoupled model: ``A, B, C, D``, and per branch its direction, its
    state and output weights and one coefficient per degree, plus the constant terms."""
    return n * n + n * m + l_ * n + l_ * m + branches * (2 * n + m + n_degrees) + n + l_


def fit_decoupled(lin: StateSpaceModel, us: list[np.ndarray], recs: list[tuple[Any, ...]],
                  degrees: list[int], branches: int, clamp: bool, max_iter: int, tol: float,
                  progress: Any, seed: int = 0, weights: Any = None,
                  significance: float = 0.0) -> tuple[Callable[[np.ndarray], dict[str, Any]],
                                                      dict[str, Any]]:
    """The decoupled fit from the linear start ``lin`` (scaled channels): branch directions
    drawn at random (seeded) and scaled to unit variance on the linear start's ``[x; u]``,
    ``W = 0`` (each start is the linear model); ``STARTS`` short fits, the best continued;
    ``weights`` (lines and weights, :mod:`sysid.nlss.freqweight`): the frequency-weighted cost;
    ``significance``: the time-domain search's (``_sysid.pnlss_estimate``).
    Returns the model's keyword arguments (without scaling and names) as a function of the
    parameters (the result's or any of the report's ``iterates``: the best start's path, then
    its continuation's, one row per entry of ``history``) and the optimiser's report."""
    n, m_, l_ = lin.nstates, lin.ninputs, lin.noutputs
    r = int(branches)
    if r < 1:
        raise DataError(f"branches must be a positive integer, got {branches!r}")
    nd = len(degrees)
    check_parameters(n_parameters(n, m_, l_, r, nd), recs,
                     "branches, the degrees or the order")
    Z = np.hstack([np.vstack(linear_states(lin, us)), np.vstack(us)])

    def start(k: int) -> np.ndarray:
        V = np.random.default_rng([seed, k]).standard_normal((r, n + m_))
        V /= np.maximum((Z @ V.T).std(axis=0), 1e-12)[:, None]
        return np.concatenate([np.ravel(a) for a in (lin.A, lin.B, lin.C, lin.D, V,
                                                     np.zeros((n, r)), np.ones((r, nd)),
                                                     np.zeros(n), np.zeros(l_))])

    # The problem is not convex in the branch directions: a few short fits from different
    # random directions (seeded), the best of them continued. The branch directions move
    # during the fit, so a box on their arguments would not stay meaningful: the fit rejects
    # diverging steps instead, and the returned model clamps to the range its own arguments
    # cover on the estimation data.
    struct = {"dims": (n, m_, l_), "branches": r, "degrees": degrees}
    def fit(th0: np.ndarray, it: int, st: dict[str, Any] = struct) -> dict[str, Any]:
        if weights is None:
            return _sysid.pnlss_estimate(st, recs, th0, max_iter=it, tol=tol,
                                         progress=progress, iterates=True,
                                         significance=significance)
        return _sysid.pnlss_estimate_weighted(st, recs, weights, th0, max_iter=it, tol=tol,
                                              progress=progress, iterates=True)

    trials = []
    for k in range(STARTS):  # a cancelled trial (progress returned False) ends the fit
        th0 = start(k)
        trials.append(fit(th0, min(STARTS_ITER, max_iter)))
        trials[-1]["iterates"] = np.vstack([th0[None, :], trials[-1]["iterates"]])
        if trials[-1]["stop"] == "cancelled":
            break
    best = min(trials, key=lambda t: t["cost"])
    cancelled = trials[-1]["stop"] == "cancelled"
    if cancelled:
        best["stop"] = "cancelled"
    res = best if cancelled or max_iter <= STARTS_ITER else \
        fit(np.asarray(best["theta"]), max_iter - STARTS_ITER)
    # the work over every start, then the returned path's own (as its history counts it)
    more = (res is not best) * res["iterations"], (res is not best) * res["evaluations"]
    res["iterations_all_trials"] = sum(t["iterations"] for t in trials) + more[0]
    res["evaluations_all_trials"] = sum(t["evaluations"] for t in trials) + more[1]
    if res is not best:  # the best start's path, then its continuation's
        res["iterations"] += best["iterations"]
        res["evaluations"] += best["evaluations"]
        res["history"] = list(best["history"]) + list(res["history"])[1:]
        res["iterates"] = np.vstack([best["iterates"], res["iterates"]])
    if clamp and not cancelled:  # the returned model clamps: an unstable A runs away
        stable = {**struct, "stable": True}
        res = held_stable(res, n, lambda th0, it: fit(th0, it, stable), max_iter,
                          max(r[0].shape[0] for r in recs))

    def kw_of(th: np.ndarray) -> dict[str, Any]:
        o = np.cumsum([0, n * n, n * m_, l_ * n, l_ * m_, r * (n + m_), n * r, r * nd, n, l_])
        p = [th[o[i]:o[i + 1]] for i in range(9)]
        kw: dict[str, Any] = {"A": p[0].reshape(n, n), "B": p[1].reshape(n, m_),
                              "C": p[2].reshape(l_, n), "D": p[3].reshape(l_, m_),
                              "V": p[4].reshape(r, n + m_), "W": p[5].reshape(n, r),
                              "c": p[6].reshape(r, nd), "e0": p[7], "f0": p[8],
                              "degrees": degrees, "clamp": None}
        if clamp:
            xs = [np.asarray(_sysid.pnlss_simulate(struct, list(th), u)[1]).reshape(-1, n)
                  for u in us]
            S = np.hstack([np.vstack(xs), np.vstack(us)]) @ kw["V"].T
            kw["clamp"] = envelope([S[:, :0]], [S], 0.1)
        return kw

    return kw_of, res
