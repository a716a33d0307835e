"""The period of a periodic excitation, found from the input's repetition (issue 28).

An input has period ``L`` when ``u[t + L] = u[t]`` for every ``t``. The mean squared mismatch
at lag ``L``, relative to the input's variance (each channel),

.. code-block:: text

    m(L) = mean_{t < N - L} (u[t + L] - u[t])^2 / (2 var(u))        (1 - autocorrelation)

is zero at the period and its multiples; noise on a measured input raises it to the noise
variance over the input's. The period is the smallest ``L >= 2`` where, in every input
channel that varies, ``m(L) <= tol`` (the input repeats) and ``m(L)`` is at most half of
``m(L - 1)`` and ``m(L + 1)`` (a sharp dip: a smooth input, which changes little over a few
samples, is not taken for a periodic one). A constant input has no period; a random one,
white or smooth, has ``m(L)`` near 1 beyond its correlation time and no dip. A pure sinusoid
whose period rounds to a whole number of samples within ``tol`` counts as periodic (its
DFT lines then hold it up to that rounding). The output is not used: its first period may
carry the transient (``sysid.pem(..., periods="auto")`` drops it).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from ..errors import DataError
from .iodata import IOData
from .layout import time_first

__all__ = ["Periodicity", "detect_period", "whole_periods"]

#: Default tolerance on ``m(L)``: a generated input repeats to rounding (``m`` ~ 1e-30);
#: a measured one up to its noise (the F-16 shaker force: ~1e-5; 1 % noise: 1e-4), while a
#: random input stays near 1 and a narrow-band random one would need a damping ratio below
#: 1e-4 to reach it.
TOL = 1e-3


class Periodicity(NamedTuple):
    """What :func:`detect_period` found."""

    #: Samples per period.
    period: int
    #: Whole periods in every experiment (the smallest count when experiments differ).
    periods: int
    #: Samples after the last of those whole periods, per experiment (a trailing partial
    #: period; :func:`sysid.pem` with ``periods="auto"`` drops them).
    unused: tuple[int, ...]
    #: Largest ``m(L)`` over the channels and experiments.
    mismatch: float


def _varying(x: np.ndarray) -> np.ndarray:
    """Variance of each column of the centred ``x``, NaN where the column is constant."""
    var = np.mean(x * x, axis=0)
    return np.where(var > 1e-24 * np.maximum(np.max(np.abs(x), axis=0), 1e-300) ** 2 + 1e-300,
                    var, np.nan)


def _mismatch(x: np.ndarray, var: np.ndarray) -> np.ndarray:
    """``m(L)`` for ``L = 0 .. N - 1`` of the centred ``x``, the largest over the channels
    that vary (from the autocorrelation by FFT)."""
    n = x.shape[0]
    nfft = 1 << int(2 * n - 1).bit_length()
    f = np.fft.rfft(x, nfft, axis=0)
    r = np.fft.irfft(np.abs(f) ** 2, nfft, axis=0)[:n]          # sum_t x[t] x[t + L]
    c = np.vstack([np.zeros((1, x.shape[1])), np.cumsum(x * x, axis=0)])
    lags = np.arange(n)
    s = c[n - lags] + (c[n] - c[lags])                          # sum x[t]^2 + x[t + L]^2
    d = np.maximum(s - 2.0 * r, 0.0) / np.maximum(n - lags, 1)[:, None]
    ok = np.isfinite(var)
    return np.max(d[:, ok] / (2.0 * var[ok]), axis=1)


def _exact(x: np.ndarray, var: np.ndarray, lag: int) -> float:
    """``m(lag)`` computed directly (no FFT rounding), the largest over the varying
    channels."""
    ok = np.isfinite(var)
    d = np.mean((x[lag:, ok] - x[:-lag, ok]) ** 2, axis=0)
    return float(np.max(d / (2.0 * var[ok])))


def period_of(u: np.ndarray, tol: float, min_periods: int) -> tuple[int | None, float, str]:
    """The period of one experiment's input ``(N, m)``: ``(period or None, mismatch,
    reason)`` (internal: :func:`detect_period` and ``sysid.pem(..., periods="auto")``)."""
    n = u.shape[0]
    if u.shape[1] == 0:
        return None, np.inf, "the data have no input"
    top = n // min_periods
    if top < 2:
        return None, np.inf, f"{n} samples cannot hold {min_periods} periods of 2 or more"
    x = u - u.mean(axis=0)
    var = _varying(x)
    if not np.any(np.isfinite(var)):
        return None, np.inf, "the input is constant"
    r = _mismatch(x, var)
    # screen with the FFT values (rounding ~1e-13 of the variance), confirm directly
    lags = np.arange(2, top + 1)
    near = r[lags] <= tol + 1e-9
    near &= 2.0 * r[lags] <= np.minimum(r[lags - 1], r[lags + 1]) + 1e-9
    for lag in lags[near]:
        e = _exact(x, var, int(lag))
        if e <= tol and all(2.0 * e <= _exact(x, var, int(k)) for k in (lag - 1, lag + 1)):
            return int(lag), e, f"the input repeats every {lag} samples"
    best = int(np.argmin(r[2:top + 1])) + 2
    return None, float(r[best]), (f"the input does not repeat: no lag L in 2..{top} where "
                                  f"the mismatch m(L) is below tol = {tol:g} and a sharp dip "
                                  f"(smallest m(L): {r[best]:.3g}, at L = {best})")


def detect_period(data: Any, *, tol: float = TOL, min_periods: int = 2) -> Periodicity | None:
    """The period of a periodic input (a multisine, a repeated PRBS), or ``None``.

    The period is the smallest ``L >= 2`` after which the input repeats: the mean squared
    mismatch ``mean (u[t + L] - u[t])^2`` is at most ``2 tol var(u)`` and at most half of
    its value at ``L - 1`` and ``L + 1``, in every input channel that varies (see
    :mod:`sysid.data.periodicity`).
    Only the input is used, so a transient in the output's first period does not matter. A
    constant or random input has no period; a record that ends inside a period has its whole
    periods counted and the rest reported in ``unused``.

    Parameters
    ----------
    data : IOData or array_like
        The data (every experiment must repeat with the same period) or an input ``(N,)`` or
        ``(N, m)``.
    tol : float
        Largest mismatch ``m(L)`` accepted, relative to the input's variance (default
        ``1e-3``: a generated input repeats to rounding, a measured one up to its noise,
        which must then stay below ~3 % of the input's RMS).
    min_periods : int
        Whole periods the record must hold (default 2).

    Returns
    -------
    Periodicity or None
        ``period`` (samples), ``periods`` (whole periods, the smallest count over the
        experiments), ``unused`` (samples after them, per experiment) and ``mismatch``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = sysid.multisine(200, band=(0, 0.5), periods=9, seed=0)
    >>> sysid.detect_period(u[:1650])                      # 8 periods and 50 samples
    Periodicity(period=200, periods=8, unused=(50,), mismatch=0.0)
    >>> sysid.detect_period(np.random.default_rng(0).standard_normal(1600)) is None
    True
    """
    tol = float(tol)
    if not (np.isfinite(tol) and 0 <= tol < 1):
        raise DataError(f"tol must lie in [0, 1), got {tol}")
    from .._checks import as_int

    min_periods = as_int(min_periods, "min_periods", 2)
    found = detect(data, tol, min_periods)
    return found[0]


def detect(data: Any, tol: float = TOL, min_periods: int = 2) -> tuple[Periodicity | None, str]:
    """:func:`detect_period` with the reason (internal: ``info`` of ``periods="auto"``)."""
    if isinstance(data, IOData):
        inputs = [u for u, _ in data.experiments]
    else:
        u = np.asarray(data, dtype=float)
        if u.ndim not in (1, 2) or not np.all(np.isfinite(u)) or u.shape[0] == 0:
            raise DataError(f"give an IOData or a finite input (N,) or (N, m) with samples; "
                            f"got shape {u.shape}")
        inputs = [time_first(u.reshape(u.shape[0], -1), "u")]
    lags, worst = set(), 0.0
    for i, u in enumerate(inputs):
        lag, mis, why = period_of(u, tol, min_periods)
        if lag is None:
            return None, (why if len(inputs) == 1 else f"experiment {i}: {why}")
        lags.add(lag)
        worst = max(worst, mis)
    if len(lags) > 1:
        return None, f"the experiments repeat with different periods {sorted(lags)}"
    lag = lags.pop()
    counts = [u.shape[0] // lag for u in inputs]
    k = min(counts)
    unused = tuple(int(u.shape[0] - k * lag) for u in inputs)
    return (Periodicity(lag, k, unused, worst),
            f"the input repeats every {lag} samples: {k} whole periods")


def whole_periods(data: IOData, found: Any) -> IOData:
    """``data`` cut to the whole periods :func:`detect_period` found in every experiment
    (``found``: its result); ``data`` itself when no sample is left over.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.data.periodicity import detect_period, whole_periods
    >>> u = np.tile(np.random.default_rng(0).standard_normal(50), 3)[:130]
    >>> d = sysid.IOData(u=u, y=u)
    >>> whole_periods(d, detect_period(d)).n_samples
    100
    """
    if not any(found.unused):
        return data
    cut = found.period * found.periods
    return IOData([u[:cut] for u, _ in data.experiments],
                  [y[:cut] for _, y in data.experiments], data.dt,
                  input_names=data.input_names, output_names=data.output_names,
                  input_units=data.input_units, output_units=data.output_units)
