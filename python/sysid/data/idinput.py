"""MATLAB's ``idinput``: one call for the four classic identification inputs.

``idinput(n, type, band, levels)`` follows the System Identification Toolbox's conventions
so that a MATLAB script ports line by line: ``n`` is ``N``, ``(N, nu)`` or ``(period, nu,
n_periods)``; ``band`` is a pair of fractions of the Nyquist frequency (for ``"prbs"``,
``(0, B)`` with clock period ``1 / B`` samples); ``levels`` is ``(low, high)`` (for
``"rgs"``: mean minus and plus one standard deviation). The signals come from the
generators in :mod:`sysid.data.input_design`; a periodic request builds one period (band
limits applied circularly, so the periods join without a seam) and repeats it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_int, check_elements
from ..errors import DataError
from .input_design import _band, _levels, _rng, prbs, random_binary, random_gaussian

__all__ = ["idinput"]

_TYPES = ("rbs", "rgs", "prbs", "sine")


def _shape(n: Any) -> tuple[int, int, int]:
    """``(period, nu, n_periods)`` from MATLAB's ``N``, ``[N nu]`` or ``[P nu M]``."""
    if isinstance(n, (int, np.integer)) and not isinstance(n, (bool, np.bool_)):
        return as_int(n, "n"), 1, 1
    try:
        v = list(np.asarray(n, dtype=object).ravel())
    except (TypeError, ValueError):
        v = []
    if not 1 <= len(v) <= 3:
        raise DataError(f"n must be N, (N, nu) or (period, nu, n_periods), got {n!r}")
    names = ("n[0] (samples or period)", "n[1] (inputs)", "n[2] (periods)")
    # MATLAB's [N nu] is a row of doubles: whole floats count as the integers they are
    vals = [as_int(int(x) if isinstance(x, (float, np.floating)) and float(x).is_integer()
                   else x, names[i]) for i, x in enumerate(v)]
    return (vals + [1, 1])[0], (vals + [1, 1])[1], (vals + [1, 1, 1])[2]


def _prbs_clock(band: Any) -> int:
    try:
        lo, hi = (float(v) for v in band)
    except (TypeError, ValueError):
        raise DataError(f"band must be a pair (0, B), got {band!r}") from None
    if lo != 0.0 or not 0.0 < hi <= 1.0:
        raise DataError(
            f"a 'prbs' band is (0, B) with 0 < B <= 1, B the inverse of the clock period in "
            f"samples (B = 0.25 holds each bit 4 samples), got {band!r}")
    hold = int(round(1.0 / hi))
    if abs(hold - 1.0 / hi) > 1e-9 * hold:
        raise DataError(
            f"a 'prbs' band (0, B) needs 1 / B to be a whole number of samples (the clock "
            f"period), got B = {hi:g}: pass B = 1/{hold}")
    return hold


def _prbs_period(period: int, hold: int) -> int:
    """The shift-register length whose maximum-length period is ``period`` samples."""
    bits = period // hold + 1 if period % hold == 0 else 0
    k = int(np.log2(bits)) if bits > 2 else 0
    if 2 <= k <= 32 and 2**k == bits:
        return k
    valid = [hold * (2**j - 1) for j in range(2, 33)]
    near = [p for p in valid if p < period][-1:] + [p for p in valid if p > period][:1]
    raise DataError(
        f"a periodic 'prbs' repeats a maximum-length sequence, whose period is "
        f"clock period x (2**k - 1) samples; {period} is not one for clock period {hold}: "
        f"pass period {' or '.join(map(str, near))}")


def _sine(period: int, nu: int, band: tuple[float, float], sine: Any,
          rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """One period of a sum of sinusoids per channel and its frequencies (rad/sample)."""
    try:
        n_sines, n_trials, skip = (as_int(x, f"sine[{i}]") for i, x in enumerate(sine))
    except (TypeError, ValueError):
        raise DataError(
            f"sine must be (n_sinusoids, n_trials, grid_skip), got {sine!r}") from None
    k = np.arange(1, (period + 1) // 2)  # the lines strictly between 0 and Nyquist
    frac = 2.0 * k / period
    k = k[(frac >= band[0]) & (frac <= band[1]) & (k % skip == 0)]
    need = n_sines * nu
    if k.size < need:
        raise DataError(
            f"{need} sinusoid(s) ({n_sines} for each of {nu} input(s)) need as many lines "
            f"of the period's grid (2 pi k / {period}) in the band {band[0]:g}..{band[1]:g} "
            f"with grid skip {skip}, but it holds {k.size}: pass fewer sinusoids, a longer "
            "period, a wider band or a smaller grid skip")
    pick = k[np.unique(np.round(np.linspace(0, k.size - 1, need)).astype(int))]
    t = np.arange(period)[:, None]
    u = np.empty((period, nu))
    freqs = np.empty((n_sines, nu))
    for j in range(nu):
        kj = pick[j::nu]  # interleaved: every line excites one input only
        w = 2.0 * np.pi * kj / period
        best = None
        for _ in range(n_trials):  # MATLAB's trials: keep the phases with the lowest peak
            x = np.sin(t * w + rng.uniform(0.0, 2.0 * np.pi, kj.size)).sum(axis=1)
            if best is None or np.abs(x).max() < np.abs(best).max():
                best = x
        u[:, j] = best / np.abs(best).max()
        freqs[:, j] = w
    return u, freqs


def idinput(
    n: Any,
    type: str = "rbs",
    band: tuple[float, float] = (0.0, 1.0),
    levels: tuple[float, float] = (-1.0, 1.0),
    sine: tuple[int, int, int] = (10, 10, 1),
    *,
    seed: Any = None,
    return_frequencies: bool = False,
) -> Any:
    """An identification input as MATLAB's ``idinput`` makes it.

    Parameters
    ----------
    n : int or tuple
        ``N`` samples of one input, ``(N, nu)`` for ``nu`` inputs, or ``(period, nu,
        n_periods)`` for a periodic signal of ``period * n_periods`` samples.
    type : {"rbs", "rgs", "prbs", "sine"}
        Random binary (the sign of band-limited Gaussian noise), random Gaussian,
        pseudo-random binary (a maximum-length sequence) or a sum of sinusoids.
    band : (low, high)
        Pass band as fractions of the Nyquist frequency (an ideal filter, applied over one
        period). For ``"prbs"``: ``(0, B)``, each bit held ``1 / B`` samples (the clock
        period); a periodic ``"prbs"`` needs ``period = (2**k - 1) / B``.
    levels : (low, high)
        The two values of ``"rbs"``/``"prbs"``; the range a ``"sine"`` fills; mean minus
        and plus one standard deviation for ``"rgs"``.
    sine : (n_sinusoids, n_trials, grid_skip)
        For ``"sine"``: sinusoids per input, spread evenly over the band on the grid
        ``2 pi k / period`` (``k`` a multiple of ``grid_skip``; the inputs take interleaved
        lines); ``n_trials`` random phase sets are drawn and the one with the lowest peak
        kept. MATLAB's default ``(10, 10, 1)``.
    seed : int or numpy.random.Generator, optional
        For reproducible random signals (MATLAB draws from its global generator).
    return_frequencies : bool
        For ``"sine"``: also return the frequencies (rad/sample), one column per input, as
        MATLAB's ``[u, freq] = idinput(...)``.

    Returns
    -------
    numpy.ndarray
        ``(period * n_periods, nu)``; with ``return_frequencies``, ``(u, freq)``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = sysid.idinput((127, 2, 3), "prbs", levels=(0, 5))
    >>> u.shape, np.unique(u).tolist(), bool(np.array_equal(u[:127], u[127:254]))
    ((381, 2), [0.0, 5.0], True)
    >>> u, w = sysid.idinput(200, "sine", (0, 0.5), sine=(4, 10, 1), seed=0,
    ...                      return_frequencies=True)
    >>> u.shape, w.ravel().round(3).tolist(), float(np.abs(u).max())
    ((200, 1), [0.031, 0.534, 1.068, 1.571], 1.0)
    """
    period, nu, n_periods = _shape(n)
    kind = str(type).lower() if isinstance(type, str) else type
    if kind not in _TYPES:
        raise DataError(f"type must be one of {', '.join(map(repr, _TYPES))}, got {type!r}")
    check_elements(period * nu * n_periods,
                   f"n = ({period}, {nu}, {n_periods}): {period * n_periods} samples of "
                   f"{nu} input(s)", "pass a shorter period or fewer periods")
    lo, hi = _levels(levels)
    if return_frequencies and kind != "sine":
        raise DataError("return_frequencies applies to type 'sine' only")
    freqs = None
    if kind == "prbs":
        hold = _prbs_clock(band)
        bits = _prbs_period(period, hold) if n_periods > 1 else None
        one = prbs(period, n_bits=bits, hold=hold, levels=(lo, hi), n_channels=nu)
    else:
        b = _band(band)
        if kind == "rbs":
            one = random_binary(period, band=b, levels=(lo, hi), n_channels=nu, seed=seed)
        elif kind == "rgs":
            one = random_gaussian(period, band=b, std=(hi - lo) / 2.0, mean=(lo + hi) / 2.0,
                                  n_channels=nu, seed=seed)
        else:
            x, freqs = _sine(period, nu, b, sine, _rng(seed))
            one = (lo + hi) / 2.0 + (hi - lo) / 2.0 * x
    u = np.tile(one, (n_periods, 1)) if n_periods > 1 else one
    return (u, freqs) if return_frequencies else u
