"""Persistent excitation read from the input's spectrum: how many frequencies the input excites.

A quasi-stationary signal is persistently exciting of order ``n`` exactly when its spectrum
is nonzero at ``n`` or more frequencies of ``(-pi, pi]`` (Ljung 1999, section 13.2;
Söderström & Stoica 1989, section 5.4): a constant excites order 1, one sinusoid order 2,
a multisine with ``p`` lines order ``2 p``, white noise every order. So the order is a count
of excited lines of the two-sided spectrum, and a band-limited multisine with 59 lines is
persistently exciting of order 118 however narrow its band.

The count uses the periodogram of the whole record (segments of :data:`SEGMENT` samples
averaged on longer ones) under a 4-term Blackman-Harris window, whose leakage (sidelobes
below -92 dB) stays under the threshold: a bin is excited when its power is above ``tol``
(default ``1e-5``, 50 dB) times that of the strongest bin. The window widens every line
to a run of :func:`_lobe` bins, so a run of ``w`` consecutive excited bins counts
``w - lobe + 1`` lines (at least one): ``p`` adjacent lines make a run of ``p + lobe - 1``.
Content more than 50 dB below the strongest line (round-off, a quantiser, sensor noise on a
measured sine) is not excitation; raise ``tol`` for noisier inputs.

Each channel's mean is removed (a nonzero mean is one line, at zero frequency) and its
variation scaled to unit power, so units do not matter. Several inputs: the vector signal
is exciting of order ``n`` only if every direction of the inputs is. The count is the
smallest over the channels, over the principal directions of the inputs' covariance (a
combination that never moves, such as two identical inputs, counts 0), and over the rank
of the cross-spectral matrices summed over the bins divided by the number of inputs (each
bin adds as many directions as its spectral matrix has rank).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["excited_lines", "input_spectrum", "spectral_excitation_order"]

#: Longest periodogram segment; longer records average segments of this length (Welch).
SEGMENT = 1 << 16
#: Segment of the cross-spectral matrices of several inputs (``m x m`` per bin: memory
#: ``16 m^2`` bytes per bin).
JOINT_SEGMENT = 1 << 12
#: Default relative power threshold of an excited bin (50 dB below the strongest).
TOL = 1e-5
#: Relative eigenvalue floor of the Gram matrix of an input's stacked lags above which the
#: input counts as plainly rich without reading its spectrum (a spectrum within 30 dB of
#: flat over those lags: :meth:`sysid.SubspaceEstimator._excitation_order`'s fast path).
FLAT_LAGS = 1e-3
#: ... and the floor of the rank test when only a data matrix's factor is at hand (rounding).
RANK_LAGS = 1e-9
#: Mismatch between periods (relative to the variance) below which an input counts as
#: periodic and its lines are counted exactly: a generated input repeats to rounding (a
#: sinusoid of a period that is not a whole number of samples does not).
EXACT_PERIOD = 1e-9


#: the 4-term Blackman-Harris window's cosine coefficients
BLACKMAN_HARRIS = (0.35875, 0.48829, 0.14128, 0.01168)


def _window(n: int) -> np.ndarray:
    """The periodic Blackman-Harris window of ``n`` points (``scipy.signal.get_window(
    "blackmanharris", n)``, written out: importing ``scipy.signal`` costs a second, and
    every ``sysid.identify`` call checks the excitation)."""
    if n <= 1:
        return np.ones(n)
    x = 2.0 * np.pi * np.arange(n) / n
    return sum((-1) ** j * a * np.cos(j * x) for j, a in enumerate(BLACKMAN_HARRIS))


def _segments(n: int, longest: int = SEGMENT) -> tuple[int, list[int]]:
    seg = min(n, longest)
    return seg, ([0] if seg == n else list(range(0, n - seg + 1, seg // 2)))


def _centred(w: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``w x`` minus the window-weighted mean of each column: no zero-frequency lobe."""
    return w * (x - (w * x).sum(axis=0) / w.sum())


def _power(x: np.ndarray, longest: int = SEGMENT) -> np.ndarray:
    """Two-sided windowed periodogram of the variation of the columns of ``x`` (``(nfft,
    k)``, window-weighted mean removed), averaged over segments of at most ``longest``
    samples (half overlapping; records of that length or more share one frequency grid)."""
    seg, starts = _segments(x.shape[0], longest)
    w = _window(seg)[:, None]
    out = np.zeros((seg, x.shape[1]))
    for s in starts:
        out += np.abs(np.fft.fft(_centred(w, x[s:s + seg]), axis=0)) ** 2
    return out / len(starts)


def input_spectrum(data: Any, segment: int) -> np.ndarray | None:
    """One-sided windowed periodogram of a record's inputs (``(segment // 2 + 1, m)``,
    segments of ``segment`` samples), its experiments weighted by their length; those
    shorter than a segment are left out (``None`` when none is long enough).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.data.excitation import input_spectrum
    >>> u = np.sin(2 * np.pi * 0.25 * np.arange(256))
    >>> int(np.argmax(input_spectrum(sysid.IOData(u=u, y=u), 64)[:, 0]))  # bin 16 of 64
    16
    """
    parts = [_power(np.asarray(u, float), segment)[:segment // 2 + 1] * u.shape[0]
             for u, _ in data.experiments if u.shape[0] >= segment]
    return sum(parts[1:], parts[0]) if parts else None


_LOBES: dict[tuple[int, float], int] = {}


def _lobe(n: int, tol: float) -> int:
    """Bins above ``tol`` of the peak for one pure tone under the window (the wider of a
    tone on a bin and half-way between bins)."""
    key = (n, tol)
    if key not in _LOBES:
        t = np.arange(n)
        widths = []
        for f in (n // 4, n // 4 + 0.5):
            p = _power(np.exp(2j * np.pi * f * t / n)[:, None])[:, 0]
            widths.append(int(np.sum(p > tol * p.max())))
        _LOBES[key] = max(widths)
    return _LOBES[key]


def _count_runs(mask: np.ndarray, lobe: int) -> int:
    """Lines in a circular boolean mask of excited bins: each run of ``w`` bins holds
    ``max(1, w - lobe + 1)``; a mask that is all true holds every bin."""
    n = mask.size
    if mask.all():
        return n
    if not mask.any():
        return 0
    start = int(np.argmin(mask))         # a bin that is not excited: runs do not wrap past it
    m = np.roll(mask, -start).astype(np.int8)
    edges = np.diff(np.r_[0, m, 0])
    widths = np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)
    return int(np.sum(np.maximum(1, widths - lobe + 1)))


def excited_lines(x: Any, tol: float = TOL, top: float | None = None) -> int:
    """Number of excited lines of the two-sided spectrum of the variation of a single
    signal (its window-weighted mean removed: an offset is counted by the caller): bins
    above ``tol`` times ``top`` (default: the signal's own strongest bin).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(1000)
    >>> excited_lines(np.sin(0.3 * t)), excited_lines(np.ones(1000))
    (2, 0)
    """
    v = np.asarray(x, dtype=float).reshape(-1, 1)
    p = _power(v)[:, 0]
    top = float(p.max()) if top is None else float(top)
    if top <= 0:
        return 0
    return _count_runs(p > tol * top, _lobe(p.size, tol))


def _joint_rank_count(us: list[np.ndarray], tol: float) -> int:
    """Sum over bins of the numerical rank of the inputs' cross-spectral matrix, over all
    experiments (the largest count), for several inputs."""
    best = 0
    for u in us:
        m = u.shape[1]
        seg, starts = _segments(u.shape[0], JOINT_SEGMENT)
        w = _window(seg)[:, None]
        S = np.zeros((seg, m, m), complex)
        for s in starts:
            F = np.fft.fft(_centred(w, u[s:s + seg]), axis=0)
            S += F[:, :, None] * F[:, None, :].conj()
        ev = np.linalg.eigvalsh(S)
        top = float(ev.max())
        if top <= 0:
            continue
        rank = np.sum(ev > tol * top, axis=1)
        lobe = _lobe(seg, tol)
        # the window spreads every line over a lobe: count the rank-weighted runs
        count = sum(_count_runs(rank >= r, lobe) for r in range(1, m + 1))
        best = max(best, count)
    return best


def _periodic_lines(x: np.ndarray, period: int, tol: float) -> tuple[list[int], int]:
    """Excited lines of a periodic input's variation ``x`` (``(N, m)``, whole periods from the
    start), exactly: the DFT of its period average has no leakage. Per channel and principal
    direction (against the strongest bin of all), and the bins where any channel is
    excited (each holds one direction: the spectral matrix of one period is of rank one)."""
    k = x.shape[0] // period
    one = x[: k * period].reshape(k, period, -1).mean(axis=0)
    F = np.fft.fft(one - one.mean(axis=0), axis=0)  # its mean is the offset, counted apart
    cols = [F[:, j] for j in range(F.shape[1])]
    if F.shape[1] > 1:
        _, vecs = np.linalg.eigh(x.T @ x)
        cols += [F @ vecs[:, j] for j in range(F.shape[1])]
    power = [np.abs(c) ** 2 for c in cols]
    top = max(float(p.max()) for p in power)
    if top <= 0:
        return [0] * len(cols), 0
    return ([int(np.sum(p > tol * top)) for p in power],
            int(np.sum(np.any(np.abs(F) ** 2 > tol * top, axis=1))))


def spectral_excitation_order(us: list[np.ndarray], tol: float = TOL) -> int:
    """Persistent-excitation order of the inputs (a list of ``(n_samples, m)`` experiments)
    from their spectra; see the module notes. Experiments count separately and the best
    one decides (each is a record of its own). An experiment whose input repeats exactly (at
    least two whole periods, to :data:`EXACT_PERIOD`) counts the lines of one period's
    DFT exactly: under the window a short periodic record's lines merged into one run (a
    period-7 PRBS of 35 samples counted 20 lines, not 7).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(2048)
    >>> lines = np.arange(5, 64)     # 59 lines in the lowest 3 % of the band
    >>> u = np.cos(2 * np.pi * np.outer(t, lines) / 2048 + lines ** 2).sum(1)
    >>> spectral_excitation_order([u[:, None]])
    118
    """
    from .periodicity import period_of

    counts, normalised, dcs, joints = [], [], [], []
    m = us[0].shape[1]
    for u in us:
        w = _window(u.shape[0])[:, None]
        mean = (w * u).sum(axis=0) / w.sum()
        x = u - mean
        rms = np.sqrt(np.mean(x * x, axis=0))
        # units do not matter: every channel's variation is scaled to unit power
        x = x / np.where(rms > 0, rms, 1.0)
        scale = max(float(rms.max()), float(np.abs(mean).max()))
        # an offset is one line, at zero frequency (window-weighted: a sine has none), when
        # it stands above the chance mean of the variation (3 rms / sqrt(N))
        floor = np.maximum(np.sqrt(tol) * scale, 3.0 * rms / np.sqrt(u.shape[0]))
        dc = int(scale > 0 and bool(np.any(np.abs(mean) > floor)))
        dcs.append(dc)
        # (records up to one segment: longer ones resolve their lines under the window, and
        # the period search's FFT would grow with the record)
        period = period_of(u, EXACT_PERIOD, 2)[0] if 4 <= u.shape[0] <= SEGMENT else None
        if period is not None:
            lines, union = _periodic_lines(x, period, tol)
            # the mean of whole periods is exact, not a chance one: an offset line above tol
            whole = u[: u.shape[0] // period * period].mean(axis=0)
            dc = int(scale > 0 and bool(np.any(np.abs(whole) > np.sqrt(tol) * scale)))
            dcs[-1] = dc
            counts.append(dc + min(lines))
            joints.append(dc + union // m)
            continue
        normalised.append(x)
        cols = [x[:, j] for j in range(x.shape[1])]
        if x.shape[1] > 1:
            # a direction is measured against the strongest channel: a combination of
            # the inputs that never moves has no excited line at all
            _, vecs = np.linalg.eigh(x.T @ x)
            cols += [x @ vecs[:, k] for k in range(x.shape[1])]
        top = float(_power(x).max())
        counts.append(dc + min(excited_lines(c, tol, top) for c in cols))
    order = max(counts)
    if m > 1:
        if normalised:
            joints.append(max(dcs) + _joint_rank_count(normalised, tol) // m)
        order = min(order, max(joints))
    return int(order)
