"""Residual bootstrap of subspace estimates: the parameter uncertainty of a subspace model.

Subspace estimates have no Gauss-Newton Hessian to invert, so their uncertainty is taken from
a residual bootstrap (not from the asymptotic formulas): the innovations ``e = y - y_hat`` of
the estimated model (one-step Kalman predictor, centred) are resampled with replacement, new
outputs are simulated from the estimated innovation form ``x+ = A x + B u + K e*``,
``y* = C x + D u + e*`` with the measured inputs, and the same subspace fit is repeated on each
record. Every bootstrap model is brought into the estimate's state basis by the similarity
``T`` that best matches its extended observability matrix to the estimate's
(``O_b T^-1 ~ O``): its matrices are then local coordinates around the estimate, and their
sample covariance is the covariance of the parameters ``vec(A, B, C, D, K)`` attached as a
:class:`~sysid.ParameterUncertainty` (``method="bootstrap"``).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_int
from ..data.iodata import IOData
from ..errors import DataError, NumericalError
from ..models.statespace import StateSpaceModel
from ..models.uncertainty import ParameterUncertainty

__all__ = ["bootstrap_uncertainty"]


def _observability(A: np.ndarray, C: np.ndarray, rows: int) -> np.ndarray:
    blocks, ca = [], C
    for _ in range(rows):
        blocks.append(ca)
        ca = ca @ A
    return np.vstack(blocks)


def _align(m: StateSpaceModel, O_ref: np.ndarray, rows: int) -> StateSpaceModel | None:
    """``m`` in the state basis of the reference (``T^-1 = pinv(O_m) O_ref``); ``None`` when
    the alignment is singular."""
    Om = _observability(m.A, m.C, rows)
    Ti = np.linalg.lstsq(Om, O_ref, rcond=None)[0]
    if np.linalg.cond(Ti) > 1e10:
        return None
    T = np.linalg.inv(Ti)
    K = None if m.K is None else T @ m.K
    return StateSpaceModel(T @ m.A @ Ti, T @ m.B, m.C @ Ti, m.D, K, dt=m.dt)


def _vector(m: StateSpaceModel, with_k: bool) -> np.ndarray:
    parts = [m.A, m.B, m.C, m.D] + ([m.K] if with_k else [])
    return np.concatenate([np.asarray(p, float).ravel() for p in parts])


#: a simulated record whose output spread exceeds the data's this many times is no resample
RUNAWAY = 100.0


def _runs_away(model: StateSpaceModel, exps: list[tuple[np.ndarray, np.ndarray]],
               pooled: np.ndarray, simulated: Callable[[np.ndarray, np.ndarray], np.ndarray],
               rng: np.random.Generator) -> bool:
    """Whether records simulated from an unstable estimate (resampled innovations, measured
    inputs) grow beyond the data: their output's standard deviation above :data:`RUNAWAY`
    times the measured one on some channel (always False for a stable estimate: its
    records look like the data). One trial record per experiment, from a generator of its
    own (the bootstrap draws stay those of a stable estimate)."""
    if model.nstates == 0 or np.max(np.abs(np.linalg.eigvals(model.A))) < 1.0:
        return False
    trial = np.random.default_rng(rng.integers(2**63))
    for u, y in exps:
        e = pooled[trial.integers(0, pooled.shape[0], y.shape[0])]
        try:
            ys = simulated(u, e)
        except NumericalError:  # the simulation overflowed
            return True
        with np.errstate(all="ignore"):
            spread = np.std(ys, axis=0)
        if np.any(~(spread <= RUNAWAY * np.maximum(np.std(y, axis=0), 1e-300))):
            return True
    return False


def bootstrap_uncertainty(estimator: Any, model: StateSpaceModel,
                          refit: Callable[[IOData], StateSpaceModel], n_boot: int = 100,
                          rng: Any = None) -> ParameterUncertainty:
    """Residual-bootstrap :class:`~sysid.ParameterUncertainty` of a subspace ``model``.

    Parameters
    ----------
    estimator : SubspaceEstimator
        The estimator that produced ``model`` (its data, horizons and weighting are reused).
    model : StateSpaceModel
        The estimate (with ``K``: ``kalman=True``).
    refit : callable
        ``refit(record) -> StateSpaceModel``: the same fit (horizons, weighting, order,
        options) on a resampled record.
    n_boot : int
        Bootstrap records (at least 20; 100-200 for standard deviations good to ~5-7 %).
    rng : seed or numpy Generator

    Returns
    -------
    ParameterUncertainty
        Parameters ``vec(A), vec(B), vec(C), vec(D), vec(K)`` (row-major) in the estimate's
        basis, their bootstrap covariance, and ``info``-style attributes ``n_boot`` and
        ``n_failed``.
    """
    n_boot = as_int(n_boot, "n_boot", 20)
    if model.K is None:
        raise DataError("uncertainty='bootstrap' resamples the innovations and needs the noise "
                        "model: fit with kalman=True")
    if getattr(estimator, "_from_factor", False):
        raise DataError("uncertainty='bootstrap' needs the data; this estimator was built from a "
                        "factor")
    rng = np.random.default_rng(rng)
    data: IOData = estimator.data
    exps = data.experiments
    resid = [y - model.predict(u if u.shape[1] else None, y) for u, y in exps]
    pooled = np.vstack(resid)
    pooled = pooled - pooled.mean(axis=0)
    n, l = model.nstates, model.noutputs
    rows = max(n, estimator.future)
    O_ref = _observability(model.A, model.C, rows)
    Ba = np.hstack([model.B, model.K])
    Da = np.hstack([model.D, np.eye(l)])

    def simulated(u: np.ndarray, e: np.ndarray) -> np.ndarray:
        return np.asarray(_sysid.simulate(model.A, Ba, model.C, Da,
                                          np.ascontiguousarray(np.hstack([u, e])), None))
    fixed = _runs_away(model, exps, pooled, simulated, rng)
    draws, failed = [], 0
    for _ in range(n_boot):
        us, ys = [], []
        for (u, y), r in zip(exps, resid):
            e = pooled[rng.integers(0, pooled.shape[0], y.shape[0])]
            # fixed design: the one-step predictions of the measured record plus resampled
            # innovations (the recursive records of an unstable estimate grow without bound
            # where the data do not, and their refits look far more certain than the data)
            ys.append(y - r + e if fixed else simulated(u, e))
            us.append(u)
        rec = IOData(u=us if len(us) > 1 else us[0], y=ys if len(ys) > 1 else ys[0],
                     dt=data.dt)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # excitation warnings repeat the original fit's
                mb = refit(rec)
        except Exception:  # noqa: BLE001 - a failed resample is counted, not fatal
            failed += 1
            continue
        mb = _align(mb, O_ref, rows) if mb.K is not None else None
        if mb is None:
            failed += 1
            continue
        draws.append(_vector(mb, True))
    if len(draws) < max(10, n_boot // 2):
        raise DataError(f"the bootstrap failed on {failed} of {n_boot} resampled records; the "
                        "model is too poorly determined for a bootstrap (lower the order)")
    X = np.asarray(draws)
    theta = _vector(model, True)
    cov = np.cov(X, rowvar=False)
    m_, dt = model.ninputs, model.dt

    def build(t: np.ndarray) -> StateSpaceModel:
        t = np.asarray(t, float)
        o = 0
        out = []
        for r, c in ((n, n), (n, m_), (l, n), (l, m_), (n, l)):
            out.append(t[o:o + r * c].reshape(r, c))
            o += r * c
        return StateSpaceModel(*out, dt=dt)

    names = [f"{k}[{i},{j}]" for k, r, c in (("A", n, n), ("B", n, m_), ("C", l, n),
                                              ("D", l, m_), ("K", n, l))
             for i in range(r) for j in range(c)]
    method = "bootstrap" + (" (fixed design: the estimate is unstable and its simulated "
                            "records grow far beyond the data)" if fixed else "")
    unc = ParameterUncertainty(theta, cov, build, names=names, method=method)
    unc.n_boot = len(draws)  # type: ignore[attr-defined]
    unc.n_failed = failed  # type: ignore[attr-defined]
    return unc
