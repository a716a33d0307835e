"""The frequency weighting of a PNLSS fit on periodic records, and ``pnlss``'s other handling
of them (its ``periods=`` per experiment, ``average=True``'s averaged periods).

On periodic data the classic PNLSS cost (Paduart et al., Automatica 46, 2010) is the
simulation error of the steady state, averaged over the periods, on the DFT lines of one
period (excited or not: the nonlinear distortions show on the others too), each line
weighted by the inverse noise variance of the measured output's averaged spectrum:

.. code-block:: text

    V = 1/2 sum_k sum_i |Ybar_i(k) - Yhat_i(k)|^2 / s2_i(k),
    s2_i(k) = var_p(Y_i,p(k)) / P'

over the ``P'`` steady-state periods ``p``. This module computes the lines and weights; the
Rust core evaluates the cost and its Gauss-Newton terms.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import DataError
from ..nonparametric.bla import _periods

__all__ = ["averaged_periods", "cost_weights", "experiment_periods", "line_weights"]

SMOOTH = 4  # the variance of each line is averaged with this many excited neighbours per side
FLOOR = 1e-10  # relative to the output's mean line power: noise-free data weigh lines alike


def line_weights(sd: IOData, periods: list[int],
                 skips: list[int]) -> list[tuple[int, list[int], list[float]]] | None:
    """``(period, lines, weights)`` per experiment (weights ``len(lines) x ny`` row-major),
    or ``None`` when an experiment has fewer than two whole periods after its transient (no
    noise variance) or a transient that is not whole periods.

    The lines are all those of one period, ``0 .. P // 2``; the noise variance of each is
    averaged over ``SMOOTH`` neighbours on each side (a variance from few periods is itself
    noisy) and floored at ``FLOOR`` times the output's mean line power.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = sysid.multisine(64, band=(0, 0.5), phases="random", seed=0, periods=4)
    >>> y = np.convolve(u[:, 0], [1.0, 0.5])[:256, None]
    >>> y = y + 0.01 * np.random.default_rng(0).standard_normal(y.shape)
    >>> (P, lines, w), = line_weights(sysid.IOData(u, y, 1.0), [4], [64])
    >>> P, lines[0], lines[-1], len(w) == len(lines)
    (64, 0, 32, True)
    """
    out = []
    for (u, y), p, skip in zip(sd.experiments, periods, skips):
        n = u.shape[0]
        if p < 2 or n % p:
            return None
        P = n // p
        if skip % P or p - skip // P < 2:
            return None
        T = skip // P
        k = np.arange(P // 2 + 1)
        Yk = _periods(y, P, p, T)[:, k, :]  # (p - T, K, l)
        s2 = np.var(Yk, axis=0, ddof=1) / Yk.shape[0]  # (K, l): of the period average
        s2 = _smooth(s2)
        power = np.mean(np.abs(Yk.mean(axis=0)) ** 2, axis=0)
        s2 = np.maximum(s2, FLOOR * np.where(power > 0, power, 1.0))
        out.append((P, [int(v) for v in k], list((1.0 / s2).ravel())))
    return out


def _smooth(s2: np.ndarray) -> np.ndarray:
    """Running mean over ``2 SMOOTH + 1`` neighbouring lines (fewer at the ends), line 0
    (the mean) kept apart."""
    if s2.shape[0] <= 2:
        return s2
    body = s2[1:]
    c = np.cumsum(np.vstack([np.zeros((1, body.shape[1])), body]), axis=0)
    i = np.arange(body.shape[0])
    lo, hi = np.maximum(i - SMOOTH, 0), np.minimum(i + SMOOTH + 1, body.shape[0])
    return np.vstack([s2[:1], (c[hi] - c[lo]) / (hi - lo)[:, None]])


def cost_weights(weighting: str, sd: IOData, pers: list[int] | None, recs: list[Any],
                 averaged: bool) -> Any:
    """The lines and weights of the frequency-weighted cost, or ``None`` (time domain)."""
    if weighting == "none":
        return None
    if pers is None or averaged:
        raise DataError("weighting='bla' needs periods= and the whole records, not "
                        "average=True (give periods=, drop average=, or use 'none')")
    w = line_weights(sd, pers, [r[2] for r in recs])
    if w is None:
        raise DataError("weighting='bla' needs at least two whole periods after a transient "
                        "of whole periods in every experiment; give more periods, a "
                        "transient= of whole periods, or weighting='none'")
    return w


def experiment_periods(periods: Any, n_exp: int) -> list[int] | None:
    """``periods=`` of a fit as one period length per experiment (``None``: not periodic)."""
    if periods is None:
        return None
    ps = [periods] * n_exp if np.ndim(periods) == 0 else list(periods)
    if len(ps) != n_exp or not all(isinstance(p, (int, np.integer)) and p >= 1 for p in ps):
        raise DataError(f"periods must be a positive integer or one per experiment ({n_exp}), "
                        f"got {periods!r}")
    return [int(p) for p in ps]


def averaged_periods(sd: IOData, pers: list[int] | None) -> list[Any]:
    """Each experiment's average over its periods after the first, twice (the first copy the
    transient)."""
    if not pers or min(pers) < 2:
        raise DataError("average=True needs periods= of at least 2 (the first is dropped)")
    out = []
    for (u, y), p in zip(sd.experiments, pers):
        N = u.shape[0]
        if N % p:
            raise DataError(f"an experiment of {N} samples is not {p} whole periods")
        P = N // p
        ua = u[P:].reshape(p - 1, P, -1).mean(axis=0)
        ya = y[P:].reshape(p - 1, P, -1).mean(axis=0)
        out.append((np.ascontiguousarray(np.vstack([ua, ua])),
                    np.ascontiguousarray(np.vstack([ya, ya])), P))
    return out
