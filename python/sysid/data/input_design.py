"""Test signals for identification experiments and a check of persistent excitation.

Every generator returns a float array shaped ``(n_samples, n_channels)``. Random ones take a
``seed`` (an int or a ``numpy.random.Generator``) so experiments are reproducible.

An input is *persistently exciting of order n* when its spectrum is nonzero at ``n``
frequencies (equivalently, the ``n m x n m`` covariance of ``n`` stacked lags
``[u(t); u(t+1); ...; u(t+n-1)]`` of a stationary input is nonsingular); it is read from the
input's spectrum (:mod:`sysid.data.excitation`). A system of order ``n`` needs an input
persistently exciting of order ``2 n`` to be identifiable from the data (one sinusoid
excites order 2; white noise every order).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .._checks import (
    as_2d,
    as_dt,
    as_int,
    as_nonnegative,
    as_real,
    check_elements,
    check_magnitudes,
    user_stacklevel,
)
from ..errors import DataError, ExcitationWarning, is_record

__all__ = [
    "prbs",
    "random_binary",
    "random_gaussian",
    "multisine",
    "chirp",
    "crest_factor",
    "persistent_excitation_order",
    "check_excitation",
]


def _n(n: Any, name: str = "n_samples") -> int:
    return as_int(n, name)


def _levels(levels: Any) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in levels)
    except (TypeError, ValueError):
        raise DataError(f"levels must be a pair (low, high), got {levels!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi)):
        raise DataError(f"levels must be finite numbers, got {levels!r}")
    if not lo < hi:
        raise DataError(f"levels must satisfy low < high, got {levels!r}")
    return lo, hi


def _finite(x: Any, name: str) -> Any:
    """A finite real number (:func:`as_real`), or an array of them (one per channel)."""
    if np.ndim(x) == 0:
        return as_real(x, name)
    a = np.asarray(x)
    if a.dtype.kind not in "iuf" or not np.all(np.isfinite(a)):
        raise DataError(f"{name} must hold finite numbers, got {x!r}")
    return a


def _band(band: Any) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in band)
    except (TypeError, ValueError):
        raise DataError(f"band must be a pair (low, high), got {band!r}") from None
    if not 0.0 <= lo < hi <= 1.0:
        raise DataError(
            f"band {band} must satisfy 0 <= low < high <= 1 (fractions of the Nyquist frequency)"
        )
    return lo, hi


def prbs(
    n_samples: int,
    *,
    n_bits: int | None = None,
    hold: int = 1,
    levels: tuple[float, float] = (-1.0, 1.0),
    n_channels: int = 1,
) -> np.ndarray:
    """Pseudo-random binary sequence: a maximum-length shift-register sequence.

    Parameters
    ----------
    n_samples : int
        Length of the output (the sequence is repeated periodically if longer).
    n_bits : int, optional
        Shift-register length; period ``2**n_bits - 1`` bits. Default: the smallest period
        covering ``n_samples / hold`` (at most 2**20 - 1).
    hold : int
        Samples each bit is held (clock divider): concentrates power below
        ``1 / (hold dt)`` Hz.
    levels : (low, high)
    n_channels : int
        Channels are circular shifts of one sequence by ``period // n_channels`` bits,
        nearly uncorrelated (cross-correlation ``-1/period`` over a full period).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = sysid.prbs(63, n_bits=6)
    >>> u.shape, np.unique(u).tolist()
    ((63, 1), [-1.0, 1.0])
    >>> int(u.sum())
    1
    """
    n = _n(n_samples)
    hold = _n(hold, "hold")
    m = _n(n_channels, "n_channels")
    lo, hi = _levels(levels)
    check_elements(n * m, f"n_samples = {n} with {m} channel(s)", "pass a shorter n_samples")
    n_sym = -(-n // hold)
    if n_bits is None:
        n_bits = max(2, min(20, int(np.ceil(np.log2(n_sym + 1)))))
    if not isinstance(n_bits, (int, np.integer)) or not 2 <= n_bits <= 32:
        raise DataError(f"n_bits must be an integer in 2..32, got {n_bits!r}")
    from scipy import signal

    seq = signal.max_len_seq(int(n_bits))[0].astype(float)
    period = seq.size
    shift = max(1, period // m)
    cols = []
    for j in range(m):
        s = np.roll(seq, -j * shift)
        # sample i holds bit i // hold (only the n samples returned are built)
        cols.append(s[(np.arange(n) // hold) % period])
    bits = np.column_stack(cols)
    return lo + (hi - lo) * bits


def _rng(seed: Any) -> np.random.Generator:
    return seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)


def _bandlimit(x: np.ndarray, band: tuple[float, float]) -> np.ndarray:
    """Zero out FFT bins outside ``band`` (fractions of Nyquist), as an ideal filter."""
    lo, hi = band
    if lo == 0.0 and hi == 1.0:
        return x
    n = x.shape[0]
    X = np.fft.rfft(x, axis=0)
    f = np.arange(X.shape[0]) / (n / 2.0)  # fraction of Nyquist
    out = (f < lo) | (f > hi)
    if not np.any(~out & (f > 0)):
        raise DataError(
            f"the band {lo:g}..{hi:g} (fractions of Nyquist) holds no frequency line of a "
            f"{n}-sample signal (the lines are {2.0 / n:.3g} apart); widen the band or "
            "lengthen the signal")
    X[out] = 0.0
    return np.fft.irfft(X, n, axis=0)


def random_binary(
    n_samples: int,
    *,
    band: tuple[float, float] = (0.0, 1.0),
    levels: tuple[float, float] = (-1.0, 1.0),
    n_channels: int = 1,
    seed: Any = None,
) -> np.ndarray:
    """Random binary signal: the sign of (band-limited) Gaussian noise.

    ``band`` gives the pass band as fractions of the Nyquist frequency (the signal's
    spectrum follows it only roughly: taking the sign spreads power).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = sysid.random_binary(1000, n_channels=2, seed=0)
    >>> u.shape, np.unique(u).tolist()
    ((1000, 2), [-1.0, 1.0])
    """
    n, m = _n(n_samples), _n(n_channels, "n_channels")
    lo, hi = _levels(levels)
    check_elements(n * m, f"n_samples = {n} with {m} channel(s)", "pass a shorter n_samples")
    e = _bandlimit(_rng(seed).standard_normal((n, m)), _band(band))
    return np.where(e >= 0.0, hi, lo)


def random_gaussian(
    n_samples: int,
    *,
    band: tuple[float, float] = (0.0, 1.0),
    std: float = 1.0,
    mean: float = 0.0,
    n_channels: int = 1,
    seed: Any = None,
) -> np.ndarray:
    """Gaussian noise, optionally band-limited (ideal filter; fractions of Nyquist),
    rescaled to the given standard deviation.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = sysid.random_gaussian(4000, band=(0.0, 0.5), std=2.0, seed=1)
    >>> round(float(u.std()), 6)
    2.0
    """
    n, m = _n(n_samples), _n(n_channels, "n_channels")
    std = as_real(std, "std", positive=True)
    mean = _finite(mean, "mean")
    check_elements(n * m, f"n_samples = {n} with {m} channel(s)", "pass a shorter n_samples")
    e = _bandlimit(_rng(seed).standard_normal((n, m)), _band(band))
    e = e - e.mean(axis=0)
    return mean + std * e / e.std(axis=0)


def multisine(
    n_samples: int,
    *,
    band: tuple[float, float] = (0.0, 1.0),
    lines: Any = None,
    n_channels: int = 1,
    phases: str = "schroeder",
    rms: float = 1.0,
    periods: int = 1,
    seed: Any = None,
    grid: str = "full",
    group: int = 4,
    grid_seed: int = 0,
) -> np.ndarray:
    """Sum of sinusoids on the FFT grid of one period, with a low crest factor.

    Parameters
    ----------
    n_samples : int
        Samples per period (the output has ``periods * n_samples`` samples).
    band : (low, high)
        Excited band as fractions of Nyquist (used when ``lines`` is None).
    lines : array_like of int, optional
        FFT bins to excite (``1 .. n_samples // 2 - 1``), instead of ``band``; a
        non-integer bin raises a :class:`~sysid.DataError`.
    n_channels : int
        Channels get interleaved lines (channel ``j`` the ``j``-th of every ``n_channels``),
        so every frequency is excited by one input only and the MIMO frequency response is
        obtained line by line.
    phases : {"schroeder", "random"}
        Schroeder's phases ``-pi k (k - 1) / K`` (low crest factor for a flat spectrum) or
        random phases (``seed``).
    rms : float
        Root-mean-square value of each channel.
    periods : int
        Number of repeated periods (steady state: drop the first when identifying).
    seed : int or numpy.random.Generator, optional
        Random phases (``phases="random"``); the random-odd grid comes from ``grid_seed``.
    grid : {"full", "odd", "random-odd"}
        Which lines of the band are excited: all, the odd ones only (even nonlinear
        distortions then fall on unexcited lines), or the odd ones with one line chosen at
        random left out of every ``group`` consecutive odd lines (odd distortions then show
        on the left-out lines too; Pintelon & Schoukens 2012, Section 3.4).
    group : int
        Group size of the random-odd grid.
    grid_seed : int
        Seed of the random-odd choice, separate from ``seed`` so that realisations with
        different random phases (``seed``) share one grid, as the robust BLA expects.

    Examples
    --------
    >>> import sysid
    >>> u = sysid.multisine(1024, band=(0.0, 0.5))
    >>> bool(sysid.crest_factor(u)[0] < 1.8)
    True

    A random-odd multisine with random phases (one realisation per seed):

    >>> u = sysid.multisine(64, band=(0, 1), phases="random", grid="random-odd", seed=1)
    >>> k = np.flatnonzero(np.abs(np.fft.rfft(u[:, 0])) > 1e-8)
    >>> bool(np.all(k % 2 == 1)), k.size
    (True, 12)
    """
    n = _n(n_samples)
    m = _n(n_channels, "n_channels")
    p = _n(periods, "periods")
    rms = as_real(rms, "rms", positive=True)
    check_elements(p * n * m, f"periods = {p} of n_samples = {n} with {m} channel(s)",
                   "pass fewer periods (or a shorter period)")
    if lines is None:
        lo, hi = _band(band)
        k_all = np.arange(1, n // 2 + (n % 2))
        frac = k_all / (n / 2.0)
        k_all = k_all[(frac >= lo) & (frac <= hi) & (k_all < n / 2.0)]
    else:
        raw = np.asarray(lines).ravel()
        if raw.dtype.kind not in "iuf" or raw.dtype.kind == "f" and not (
                np.all(np.isfinite(raw)) and np.all(raw == np.round(raw))):
            bad = raw if raw.dtype.kind not in "iuf" else raw[
                ~np.isfinite(raw) | (raw != np.round(raw))]
            raise DataError(
                f"lines are FFT bin numbers (integers), got {bad.tolist()[:5]}; for "
                f"frequencies f in Hz use round(f * n_samples * dt)"
            )
        k_all = np.unique(raw.astype(int))
        if k_all.size and (k_all.min() < 1 or k_all.max() >= n / 2.0):
            raise DataError(f"lines must lie in 1..{int(np.ceil(n / 2.0)) - 1} for period {n}")
    rng = _rng(seed)
    k_all = _grid_lines(k_all, grid, group, np.random.default_rng(grid_seed))
    if k_all.size < m:
        raise DataError(
            f"only {k_all.size} FFT line(s) in the band for {m} channel(s); widen the band "
            "or lengthen the period"
        )
    if phases not in ("schroeder", "random"):
        raise DataError(f"phases must be 'schroeder' or 'random', got {phases!r}")
    t = np.arange(n)
    out = np.empty((n, m))
    for j in range(m):
        kj = k_all[j::m]
        K = kj.size
        if phases == "schroeder":
            ph = -np.pi * np.arange(1, K + 1) * np.arange(K) / K
        else:
            ph = rng.uniform(-np.pi, np.pi, K)
        x = np.cos(2 * np.pi * np.outer(t, kj) / n + ph).sum(axis=1)
        out[:, j] = rms * x / np.sqrt(np.mean(x * x))
    return np.tile(out, (p, 1))


def _grid_lines(k: np.ndarray, grid: str, group: int, rng: Any) -> np.ndarray:
    """The excited lines of a full, odd or random-odd grid."""
    if grid == "full":
        return k
    if grid not in ("odd", "random-odd"):
        raise DataError(f"grid must be 'full', 'odd' or 'random-odd', got {grid!r}")
    k = k[k % 2 == 1]
    if grid == "random-odd":
        g = _n(group, "group")
        if g < 2:
            raise DataError(f"group must be at least 2 for a random-odd grid, got {group}")
        keep = np.ones(k.size, bool)
        for s in range(0, k.size - g + 1, g):
            keep[s + rng.integers(g)] = False
        k = k[keep]
    return k


def chirp(
    n_samples: int,
    dt: float,
    f0: float,
    f1: float,
    *,
    amplitude: float = 1.0,
    method: str = "logarithmic",
) -> np.ndarray:
    """Frequency sweep from ``f0`` to ``f1`` Hz over the record (``scipy.signal.chirp``).

    Linear and quadratic sweeps may start (or end) at 0 Hz; logarithmic (the default) and
    hyperbolic ones need both frequencies positive. A one-sample record has no sweep and
    raises a :class:`~sysid.DataError`, as does a sample time that is not a positive number.

    Examples
    --------
    >>> import sysid
    >>> sysid.chirp(500, 0.01, 0.1, 10.0).shape
    (500, 1)
    >>> float(sysid.chirp(500, 0.01, 0.0, 10.0, method="linear")[0, 0])   # cos(0)
    1.0
    """
    n = _n(n_samples)
    dt = as_dt(dt)
    amplitude = _finite(amplitude, "amplitude")
    check_elements(n, f"n_samples = {n}", "pass a shorter n_samples")
    if n < 2:
        raise DataError(f"a chirp sweeps over its record: it needs at least 2 samples, got {n}")
    nyq = 0.5 / dt
    if method not in ("linear", "logarithmic", "quadratic", "hyperbolic"):
        raise DataError(f"unknown chirp method {method!r}: use 'linear', 'logarithmic', "
                        "'quadratic' or 'hyperbolic'")
    f0, f1 = _finite(f0, "f0"), _finite(f1, "f1")
    if not (0 <= f0 <= nyq and 0 <= f1 <= nyq) or f0 == f1:
        raise DataError(f"f0, f1 must be two different frequencies in [0, {nyq:g}] Hz (the "
                        f"Nyquist frequency of dt = {dt:g} s), got {f0:g} and {f1:g}")
    if min(f0, f1) == 0 and method in ("logarithmic", "hyperbolic"):
        raise DataError(f"a {method} sweep cannot start or end at 0 Hz (its frequency is a "
                        "ratio of them); give a positive f0 (e.g. a tenth of the slowest "
                        "frequency of interest) or method='linear'")
    t = np.arange(n) * dt
    from scipy import signal

    return amplitude * signal.chirp(t, f0, t[-1], f1, method=method)[:, None]


def crest_factor(u: Any) -> np.ndarray:
    """Peak over RMS of each channel (``sqrt(2)`` for one sinusoid).

    An all-zero channel has no crest factor and raises a :class:`~sysid.DataError`.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> np.round(sysid.crest_factor(np.cos(2 * np.pi * np.arange(100) / 10)), 4)
    array([1.4142])
    """
    from .layout import time_first

    x = time_first(as_2d(u, "u"), "u")
    rms = np.sqrt(np.mean(x * x, axis=0))
    if np.any(rms == 0):
        raise DataError(f"channel(s) {np.flatnonzero(rms == 0).tolist()} are all zero: an "
                        "all-zero signal has no crest factor (peak over RMS)")
    return np.max(np.abs(x), axis=0) / rms


def _lag_gram(us: list[np.ndarray], mo: int) -> tuple[np.ndarray, int]:
    """``sum H^T H`` over experiments, ``H`` the ``(K, mo m)`` matrix of ``mo`` stacked lags,
    and the total number of Hankel columns ``K``."""
    m = us[0].shape[1]
    G = np.zeros((mo * m, mo * m))
    cols = 0
    for x in us:
        n = x.shape[0]
        K = n - mo + 1  # Hankel columns of this experiment
        if K < 1:
            continue
        # G[i, j] = sum_{t<K} x(t+i) x(t+j)^T from one lagged product per lag tau = j - i
        # (O(N mo m^2) instead of O(N mo^2 m^2)), minus the short head and tail each block
        # does not cover
        for tau in range(mo):
            S = x[: n - tau].T @ x[tau:]
            for i in range(mo - tau):
                j = i + tau
                blk = S - x[:i].T @ x[tau : tau + i] - x[i + K : n - tau].T @ x[i + K + tau :]
                G[i * m : (i + 1) * m, j * m : (j + 1) * m] += blk
                if tau:
                    G[j * m : (j + 1) * m, i * m : (i + 1) * m] += blk.T
        cols += K
    return G, cols


def persistent_excitation_order(u: Any, max_order: int = 20, *, method: str = "spectrum",
                                tol: float | None = None) -> int:
    """The order of persistent excitation of an input, up to ``max_order``.

    ``method="spectrum"`` (default) counts the excited lines of the input's two-sided
    spectrum: a signal is persistently exciting of order ``n`` exactly when its spectrum is
    nonzero at ``n`` frequencies (one sinusoid: 2, a multisine with ``p`` lines: ``2 p``,
    white noise: every order), a bin counting as excited above ``tol`` (default ``1e-5``)
    times the strongest one; several inputs count the weakest direction
    (:mod:`sysid.data.excitation`). ``method="covariance"`` is MATLAB's ``pexcit`` rule: the
    largest ``n`` for which the ``n m x n m`` sample covariance of ``n`` stacked lags is
    nonsingular (smallest eigenvalue above ``tol``, default ``1e-9``, times the largest). It
    calls a band-limited input poorly exciting (its lag covariance is ill-conditioned
    however many lines it has) and a sine with a little noise richly exciting.

    Several experiments (a list of arrays, or a record's): the best one decides
    (``"spectrum"``), or their lag columns count together (``"covariance"``).

    Parameters
    ----------
    u : array_like, list of array_like or IOData
        ``(n_samples, n_inputs)``; a record's inputs (MATLAB's ``pexcit(data)``).
    max_order : int
        Largest order reported (the answer ``max_order`` means "at least").
    method : {"spectrum", "covariance"}
    tol : float, optional
        Relative threshold (see above), finite and ``>= 0``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> t = np.arange(500)
    >>> sysid.persistent_excitation_order(np.sin(0.3 * t), 10)
    2
    >>> sysid.persistent_excitation_order(np.random.default_rng(0).standard_normal(500), 10)
    10
    >>> lines = np.arange(5, 64)       # 59 lines in the lowest 3 % of the band
    >>> ms = np.cos(2 * np.pi * np.outer(np.arange(2048), lines) / 2048 + lines ** 2).sum(1)
    >>> sysid.persistent_excitation_order(ms, 20)
    20
    >>> sysid.persistent_excitation_order(ms, 20, method="covariance")
    4
    """
    mo = _n(max_order, "max_order")
    if is_record(u):  # a record: its inputs
        u = [x for x, _ in u.experiments]
    us = [as_2d(x, "u") for x in (u if isinstance(u, list) else [u])]
    m = us[0].shape[1]
    if m == 0:
        raise DataError("the record has no inputs; persistent excitation concerns inputs")
    if any(x.shape[1] != m for x in us):
        raise DataError("all experiments must have the same number of inputs")
    # the estimators' range check (inputs near 1e300 failed inside LAPACK)
    check_magnitudes([(x, x[:, :0]) for x in us], "persistent_excitation_order")
    if tol is not None:
        tol = as_nonnegative(tol, "tol")
    if method == "spectrum":
        from .excitation import TOL, spectral_excitation_order

        return min(mo, spectral_excitation_order(us, TOL if tol is None else float(tol)))
    if method != "covariance":
        raise DataError(f"method must be 'spectrum' or 'covariance', got {method!r}")
    return _covariance_order(us, mo, 1e-9 if tol is None else float(tol))


def _covariance_order(us: list[np.ndarray], mo: int, tol: float) -> int:
    """MATLAB ``pexcit``'s rule: rank of the stacked-lag covariance (see above)."""
    m = us[0].shape[1]
    mo = min(mo, max(x.shape[0] for x in us))
    # the lag covariance of n m rows needs at least n m lag columns, else it is singular by
    # construction: a larger max_order would lower the answer (white noise of 100 samples:
    # max_order 50 -> 50, 100 -> 1); the record shows at most that order
    while mo > 1 and sum(max(x.shape[0] - mo + 1, 0) for x in us) < mo * m:
        mo -= 1
    G, cols = _lag_gram(us, mo)
    if cols == 0:
        raise DataError(f"every experiment is shorter than max_order = {mo}")
    G /= cols
    top = np.linalg.eigvalsh(G)[-1]
    if top <= 0:
        return 0
    order = 0
    for n in range(1, mo + 1):
        ev = np.linalg.eigvalsh(G[: n * m, : n * m])
        if ev[0] > tol * top:
            order = n
        else:
            break
    return order


def warn_excitation(got: int, order: int, *, stacklevel: int | None = None) -> None:
    """Issue the :class:`~sysid.ExcitationWarning` for an input of excitation order ``got``
    asked to support a model of ``order`` (which needs ``2 * order``); silent otherwise."""
    need = 2 * order
    if got < need:
        warnings.warn(
            ExcitationWarning(
                f"the input is persistently exciting of order {got} only, but a model of order "
                f"{order} needs order {need}: the estimate is not determined by the data. "
                "Use a richer input (white noise, PRBS, a multisine with more lines) or a lower "
                "order"
            ),
            stacklevel=user_stacklevel() if stacklevel is None else stacklevel + 1,
        )


def model_excitation_order(us: list[np.ndarray], needed: int) -> int:
    """Persistent-excitation order of the inputs ``us`` (a list of ``(n_samples, m)``
    experiments) up to ``needed``, by the subspace estimator's rule: the rank of the lag
    covariance of the inputs scaled to unit root mean square first (full rank: persistently
    exciting), and only where it falls short the excited lines of the spectrum, which take a
    band-limited multisine for what it is however many lines it has
    (:mod:`sysid.data.excitation`).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.data.input_design import model_excitation_order
    >>> t = np.arange(1000)[:, None]
    >>> model_excitation_order([np.sin(0.3 * t) + np.sin(0.9 * t)], 10)
    4
    """
    from .excitation import spectral_excitation_order

    scaled = []
    for u in us:
        rms = np.sqrt(np.mean(u * u, axis=0))
        scaled.append(u / np.where(rms > 0, rms, 1.0))
    mo = min(needed, max(u.shape[0] for u in scaled))
    got = _covariance_order(scaled, mo, 1e-9) if mo >= 1 else 0
    if got < needed:
        got = min(needed, spectral_excitation_order([np.ascontiguousarray(u) for u in us]))
    return got


def check_model_excitation(data: Any, needed: int, who: str, needs: str, fix: str) -> int:
    """Warn (:class:`~sysid.ExcitationWarning`) when the inputs of ``data`` (a record, or
    ``(u, y)`` experiments) are persistently exciting of a lower order than ``needed``, the
    number of parameters of the input channel of ``who``'s model (Ljung's condition for an
    input-output model: ``nb + nf`` for OE and BJ, ``na + nb`` for ARMAX, the numerator and
    denominator coefficients of a transfer function); ``needs`` says how it is counted and
    ``fix`` what to lower. Returns the order found (up to ``needed``).

    Examples
    --------
    >>> import numpy as np, sysid, warnings
    >>> from sysid.data.input_design import check_model_excitation
    >>> t = np.arange(1000)
    >>> d = sysid.IOData(u=np.sin(0.3 * t) + np.sin(0.7 * t), y=np.zeros(1000) + t % 3)
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     check_model_excitation(d, 6, "oe", "nb + nf = 3 + 3", "lower nb and nf")
    4
    >>> w[0].category.__name__
    'ExcitationWarning'
    """
    exps = data.experiments if is_record(data) else data
    us = [as_2d(u, "u") for u, _ in exps]
    if not us or us[0].shape[1] == 0 or needed < 1:
        return needed
    # too few samples for the parameters, an input that never moves, inputs that depend on
    # each other: the estimator's own checks refuse the record with the reason, and no
    # warning should come first
    stacked = np.vstack(us)
    if sum(u.shape[0] for u in us) < 2 * needed * us[0].shape[1] + 2 or not np.all(
            np.ptp(stacked, axis=0) > 0) or np.linalg.matrix_rank(
            stacked - stacked.mean(axis=0)) < stacked.shape[1]:
        return needed  # (an input recorded twice: refused as dependent inputs)
    got = model_excitation_order(us, int(needed))
    if got < needed:
        warnings.warn(ExcitationWarning(
            f"the input is persistently exciting of order {got} only, but the {who} model "
            f"needs order {needed} ({needs}): its parameters are not determined by the data "
            f"(the fit can look good, the model between the excited frequencies means "
            f"nothing). Use a richer input (white noise, PRBS, a multisine with more lines) "
            f"or {fix}"), stacklevel=user_stacklevel())
    return got


def check_polynomial_excitation(exps: Any, method: str, na_v: list[int],
                                nb_g: list[list[int]], nf_g: list[list[int]]) -> None:
    """The :class:`~sysid.ExcitationWarning` when the input cannot determine the input path
    of the largest channel: persistently exciting of a lower order than its ``na + nb + nf``
    parameters (a narrow-band input under oe(5, 5, 1) fitted silently before); ``na_v`` per
    output, ``nb_g`` and ``nf_g`` per output and input.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.data.input_design import check_polynomial_excitation
    >>> u = np.random.default_rng(0).standard_normal((500, 1))
    >>> check_polynomial_excitation([(u, u)], "oe", [0], [[3]], [[3]])  # white: silent
    """
    channels = [(na_v[i] + nb + nf_g[i][j], i, j) for i in range(len(nb_g))
                for j, nb in enumerate(nb_g[i])]
    if not channels:  # a time series: no input to excite anything
        return
    need, i, j = max(channels)
    terms = [(k, v) for k, v in (("na", na_v[i]), ("nb", nb_g[i][j]), ("nf", nf_g[i][j])) if v]
    needs = " + ".join(k for k, _ in terms) + " = " + " + ".join(str(v) for _, v in terms)
    check_model_excitation(exps, need, method, needs,
                           f"lower {' and '.join(k for k, _ in terms)}")


def check_excitation(u: Any, order: int, *, stacklevel: int | None = None) -> int:
    """Warn (:class:`~sysid.ExcitationWarning`) if ``u`` (the inputs, or a record) cannot
    support a model of ``order``: its persistent-excitation order is below ``2 * order``.
    Returns that order.

    Examples
    --------
    >>> import numpy as np, sysid, warnings
    >>> u = np.random.default_rng(0).standard_normal((300, 1))
    >>> sysid.check_excitation(u, order=3)
    6
    """
    order = as_int(order, "order", 1)
    need = 2 * order
    got = persistent_excitation_order(u, need)
    warn_excitation(got, int(order), stacklevel=None if stacklevel is None else stacklevel + 1)
    return got
