"""Raw records: NaN/Inf drop-outs and irregular sampling.

:func:`repair_nan` interpolates short gaps and cuts a record at long ones;
:meth:`IOData.from_raw <sysid.IOData.from_raw>` and
:meth:`IOData.from_irregular <sysid.IOData.from_irregular>` build a clean, uniformly sampled
record from raw arrays (plain functions of the class, bound as its class methods in
:mod:`sysid.data.iodata`); :func:`resample_stamps` is the readers' ``resample=`` (a CSV file
or DataFrame of jittered stamps) on the same interpolation, and :class:`Resampling` what it
did, kept on the record (``IOData.resampling``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._checks import as_2d, as_dt, check_elements, real_array, user_stacklevel
from ..errors import DataError, InsufficientDataError, NonFiniteError, ShapeError
from .layout import time_first
from .units import sample_time

__all__ = ["repair_nan", "Resampling", "resample_stamps"]


@dataclass(frozen=True)
class Resampling:
    """What interpolation onto a uniform grid did to a record (``IOData.resampling``, set by
    :meth:`IOData.from_irregular <sysid.IOData.from_irregular>` and the readers'
    ``resample=``; ``None`` on a record read as it was sampled).

    Attributes
    ----------
    dt : float
        The grid's sample time (seconds).
    method : str
        ``"linear"`` or ``"cubic"``.
    n_stamps, n_samples : int
        Time stamps read, and samples on the grid (over every experiment).
    largest_gap : float
        The longest interval between two stamps the interpolation bridged (seconds).
    gap_after : float
        The time stamp that interval starts at.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> t = np.array([0.0, 0.1, 0.2, 0.35, 0.4, 0.5])
    >>> r = sysid.IOData.from_irregular(t, None, 2 * t, dt=0.1).resampling
    >>> r.n_stamps, r.n_samples, round(r.largest_gap, 9), r.gap_after
    (6, 6, 0.15, 0.2)
    >>> str(r)[:52]
    'resampled 6 time stamps onto 6 samples at dt = 0.1 s'
    """

    dt: float
    method: str
    n_stamps: int
    n_samples: int
    largest_gap: float
    gap_after: float

    def __str__(self) -> str:
        return (f"resampled {self.n_stamps} time stamps onto {self.n_samples} samples at "
                f"dt = {self.dt:g} s ({self.method} interpolation); the longest interval "
                f"bridged: {self.largest_gap:g} s after t = {self.gap_after:g} s")



# --------------------------------------------------------------------------------------------
# runs and gaps
# --------------------------------------------------------------------------------------------


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Half-open ``(start, stop)`` of every run of True in a 1-D boolean array."""
    m = np.concatenate([[False], np.asarray(mask, dtype=bool), [False]])
    d = np.diff(m.astype(np.int8))
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist()))


def _fill(x: np.ndarray, bad: np.ndarray) -> np.ndarray:
    """Linear interpolation over the samples flagged ``bad`` (per column; ends held)."""
    out = x.copy()
    k = np.arange(x.shape[0])
    for j in range(x.shape[1]):
        b = bad[:, j]
        if b.any():
            good = ~b
            if not good.any():
                raise NonFiniteError(f"channel {j} has no valid sample to interpolate from")
            out[b, j] = np.interp(k[b], k[good], x[good, j])
    return out


def repair_nan(
    u: np.ndarray | None,
    y: np.ndarray,
    *,
    nan: str = "interpolate",
    max_gap: int = 5,
    min_length: int = 2,
) -> list[tuple[np.ndarray | None, np.ndarray, int]]:
    """Handle NaN/Inf drop-outs in raw ``(samples, channels)`` arrays.

    Parameters
    ----------
    u, y : ndarray
        Raw inputs (or ``None``) and outputs of one experiment.
    nan : {"error", "interpolate", "split"}
        ``"error"``: raise :class:`~sysid.NonFiniteError` naming the first bad sample.
        ``"interpolate"``: fill gaps of at most ``max_gap`` samples (linearly, per channel)
        and cut the record at longer ones, and at gaps without a valid sample on one side
        (at the record's ends, or next to where another channel's long gap cuts it).
        ``"split"``: cut at every gap.
    max_gap : int
        Longest gap to interpolate.
    min_length : int
        Clean runs shorter than this are dropped.

    Returns
    -------
    list of (u, y, start)
        The clean runs and the sample where each starts in the raw record.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.data.raw import repair_nan
    >>> y = np.array([[0.0], [np.nan], [2.0], [3.0]])
    >>> repair_nan(None, y)[0][1].ravel()
    array([0., 1., 2., 3.])
    """
    if nan not in ("error", "interpolate", "split"):
        raise DataError(f"nan must be 'error', 'interpolate' or 'split', got {nan!r}")
    if not isinstance(max_gap, (int, np.integer)) or max_gap < 0:
        raise DataError(f"max_gap must be a non-negative integer, got {max_gap!r}")
    if not isinstance(min_length, (int, np.integer)) or min_length < 1:
        raise DataError(f"min_length must be a positive integer, got {min_length!r}")
    y = real_array(y, "y")
    u = None if u is None else real_array(u, "u")
    for name, a in (("u", u), ("y", y)):
        if a is not None and (a.ndim != 2 or y.ndim != 2 or a.shape[0] != y.shape[0]):
            raise ShapeError(f"{name} must be a (samples, channels) array with y's samples, "
                             f"got shape {a.shape} (y {y.shape}); reshape 1-D signals with "
                             "x[:, None]")
    time_first(y, "y")
    if u is not None:
        time_first(u, "u")
    ua = np.zeros((y.shape[0], 0)) if u is None else u
    bad = np.concatenate([~np.isfinite(ua), ~np.isfinite(y)], axis=1)
    if not bad.any():
        return [(u, y, 0)]
    if nan == "error":
        i, j = np.argwhere(bad)[0]
        raise NonFiniteError(
            f"non-finite value at sample {i} ({'u' if j < ua.shape[1] else 'y'} channel "
            f"{j if j < ua.shape[1] else j - ua.shape[1]}), {int(bad.any(axis=1).sum())} bad "
            "sample(s) in all; pass nan='interpolate' (gaps of up to max_gap samples "
            "filled) or nan='split' (the record cut into experiments there) to the reader "
            "(IOData.from_csv, from_pandas or from_raw), or repair them with "
            "sysid.repair_nan"
        )
    x = np.concatenate([ua, y], axis=1)
    any_bad = np.asarray(bad.any(axis=1), dtype=bool)
    cut: np.ndarray = any_bad.copy()
    if nan == "interpolate":
        # gaps are per channel; a long gap in any channel cuts the record there
        long_gap = np.zeros_like(any_bad)
        for j in range(x.shape[1]):
            for a, b in _runs(bad[:, j]):
                if b - a > max_gap or a == 0 or b == len(any_bad):
                    long_gap[a:b] = True
        # a short gap next to a cut (another channel's long gap) has no valid sample on that
        # side, like a gap at the record's ends: it is cut too, not filled by holding the last
        # value (which made up samples); a new cut can reach another channel's short gap
        grown = True
        while grown:
            grown = False
            for j in range(x.shape[1]):
                for a, b in _runs(bad[:, j] & ~long_gap):
                    if a == 0 or long_gap[a - 1] or b == len(any_bad) or long_gap[b]:
                        long_gap[a:b] = grown = True
        cut = long_gap
        fillable = bad & ~long_gap[:, None]
        x = np.where(bad, 0.0, x)
        for a, b in _runs(~long_gap):
            x[a:b] = _fill(x[a:b], fillable[a:b])
    out = []
    for a, b in _runs(~cut):
        if b - a >= min_length:
            seg = x[a:b]
            out.append((None if u is None else seg[:, : ua.shape[1]], seg[:, ua.shape[1]:], a))
    if not out:
        raise InsufficientDataError(
            f"no clean stretch of at least {min_length} samples is left after removing the "
            "non-finite values"
        )
    return out


def from_raw(
    cls: Any,
    u: Any,
    y: Any,
    dt: float | None = None,
    *,
    time: Any = None,
    nan: str = "error",
    max_gap: int = 5,
    min_length: int = 2,
    input_names: Sequence[str] | None = None,
    output_names: Sequence[str] | None = None,
    input_units: Sequence[str] | None = None,
    output_units: Sequence[str] | None = None,
) -> Any:
    """A record from raw arrays that may contain NaN drop-outs.

    Parameters
    ----------
    u, y : array_like
        One experiment each, ``(n_samples, channels)``; ``u`` may be ``None``.
    dt, time : optional
        Sample time or time vector, as for :class:`IOData`.
    nan : {"error", "interpolate", "split"}
        ``"error"`` raises on any NaN/Inf; ``"interpolate"`` fills gaps of at most
        ``max_gap`` consecutive samples linearly (per channel) and splits the record at
        longer ones and at gaps without a valid sample on one side (at the ends, or next to
        another channel's long gap); ``"split"`` cuts the record at every gap, each clean
        run becoming its own experiment.
    max_gap : int
        Longest gap (samples) that ``"interpolate"`` fills.
    min_length : int
        Clean runs shorter than this are dropped.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> y = np.arange(12.0); y[3] = np.nan; y[6:9] = np.nan
    >>> sysid.IOData.from_raw(None, y, nan="interpolate", max_gap=1).lengths
    [6, 3]
    >>> sysid.IOData.from_raw(None, y, nan="split").lengths
    [3, 2, 3]
    """
    ua = None if u is None else _raw2d(u, "u")
    ya = _raw2d(y, "y")
    if ua is not None and ua.shape[0] != ya.shape[0]:
        raise ShapeError(f"u has {ua.shape[0]} samples but y has {ya.shape[0]}")
    if dt is not None:  # dt = 0 said "time repeats at sample 1"
        dt = as_dt(dt)
    t0 = 0.0
    if time is not None:
        t = np.asarray(time, dtype=float).ravel()
        if t.size != ya.shape[0]:
            raise ShapeError(f"time has {t.size} instants but y has {ya.shape[0]} samples")
        h = sample_time(np.asarray(time).ravel())  # in its own type: its resolution
        if dt is not None and abs(dt - h) > 0.01 * h:
            raise DataError(f"dt = {dt} disagrees with the time vector (median {h:g} s)")
        # a dt that agrees is kept (1/60, where the time vector reads 0.0166666666667)
        dt, t0 = h if dt is None else dt, float(t[0])
    runs = repair_nan(ua, ya, nan=nan, max_gap=max_gap, min_length=min_length)
    h = 1.0 if dt is None else float(dt)
    return cls(
        None if ua is None else [r[0] for r in runs],
        [r[1] for r in runs],
        h,
        time=[t0 + r[2] * h + np.arange(len(r[1])) * h for r in runs],
        input_names=input_names,
        output_names=output_names,
        input_units=input_units,
        output_units=output_units,
    )


def from_irregular(
    cls: Any,
    time: Any,
    u: Any,
    y: Any,
    dt: float | None = None,
    *,
    method: str = "linear",
    max_gap: float | None = None,
    input_names: Sequence[str] | None = None,
    output_names: Sequence[str] | None = None,
    input_units: Sequence[str] | None = None,
    output_units: Sequence[str] | None = None,
) -> Any:
    """A uniformly sampled record interpolated from irregularly timed samples.

    Parameters
    ----------
    time : array_like
        Strictly increasing sample instants (repeats are an error: remove them first).
    u, y : array_like
        Values at those instants (``u`` may be ``None``).
    dt : float, optional
        New sample time; default the median spacing of ``time``.
    method : {"linear", "cubic"}
        Interpolation (``"cubic"``: SciPy's ``CubicSpline``). No anti-alias filter is
        applied: choose ``dt`` no longer than the typical spacing.
    max_gap : float, optional
        Longest interval between instants (seconds) that is bridged; default ``5 dt``. At a
        longer gap (an outage) the record is cut into experiments, with a warning, rather
        than filled with a straight line the data never showed.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> t = np.array([0.0, 0.1, 0.2, 0.35, 0.4, 0.5])
    >>> d = sysid.IOData.from_irregular(t, None, 2 * t, dt=0.1)
    >>> d.y.ravel()
    array([0. , 0.2, 0.4, 0.6, 0.8, 1. ])
    """
    t = np.asarray(time, dtype=float).ravel()
    ya = as_2d(y, "y")
    ua = None if u is None else as_2d(u, "u")
    if t.size != ya.shape[0] or (ua is not None and ua.shape[0] != t.size):
        raise ShapeError("time, u and y must have the same number of samples")
    if t.size < 2 or not np.isfinite(t).all():
        raise DataError("time must hold at least 2 finite instants")
    d = np.diff(t)
    if (d <= 0).any():
        i = int(np.flatnonzero(d <= 0)[0])
        raise DataError(
            f"time is not strictly increasing at sample {i + 1} ({t[i]:g} then {t[i + 1]:g});"
            " sort the samples and remove duplicates first"
        )
    h = float(np.median(d)) if dt is None else float(dt)
    if not np.isfinite(h) or h <= 0:
        raise DataError(f"dt must be positive, got {dt}")
    with np.errstate(over="ignore"):
        n_float = min(float(np.floor((t[-1] - t[0]) / h + 1e-9)) + 1, 1e300)
    nch = ya.shape[1] + (0 if ua is None else ua.shape[1])
    check_elements(n_float * (nch + 1), f"dt = {h:g} over a span of {t[-1] - t[0]:g} "
                   f"({n_float:.3g} samples)", "pass a dt near the typical spacing of time")
    if method not in ("linear", "cubic"):
        raise DataError(f"method must be 'linear' or 'cubic', got {method!r}")
    gap = 5.0 * h if max_gap is None else float(max_gap)
    if not (np.isfinite(gap) and gap > 0):
        raise DataError(f"max_gap must be a positive number of seconds, got {max_gap!r}")
    cuts = np.flatnonzero(d > gap) + 1
    pieces = [(a, b) for a, b in zip(np.r_[0, cuts], np.r_[cuts, t.size])
              if b - a >= 2 and t[b - 1] - t[a] >= h]
    if cuts.size:
        import warnings

        from ..errors import SysidWarning

        warnings.warn(
            f"time has {cuts.size} gap(s) longer than max_gap = {gap:g} s (the longest "
            f"{float(d.max()):g} s, after {t[int(np.argmax(d))]:g} s): the record is cut into "
            f"{len(pieces)} experiment(s) there instead of bridged by interpolation; pass a "
            "larger max_gap to bridge them", SysidWarning, stacklevel=user_stacklevel())
    if not pieces:
        raise DataError(f"no stretch of time between gaps longer than max_gap = {gap:g} s "
                        f"holds two instants dt = {h:g} s apart: nothing to interpolate")
    us, ys, grids = [], [], []
    for a, b in pieces:
        ts = t[a:b]
        grid = ts[0] + np.arange(int(np.floor((ts[-1] - ts[0]) / h + 1e-9)) + 1) * h
        grids.append(grid)
        ys.append(_interpolate(ts, ya[a:b], grid, method))
        us.append(None if ua is None else _interpolate(ts, ua[a:b], grid, method))
    one = len(pieces) == 1
    rec = cls(
        us[0] if one else (None if ua is None else us),
        ys[0] if one else ys,
        h,
        time=grids[0] if one else grids,
        input_names=input_names,
        output_names=output_names,
        input_units=input_units,
        output_units=output_units,
    )
    bridged = [(float(d[k]), float(t[k])) for a, b in pieces for k in range(a, b - 1)]
    wide = max(bridged)
    rec.resampling = Resampling(h, method, int(t.size), sum(g.size for g in grids), *wide)
    return rec


def resample_stamps(
    cls: Any,
    parts: list[tuple[np.ndarray, np.ndarray | None, np.ndarray]],
    resample: float | str,
    resample_gap: float,
    kw: dict[str, Any],
    *,
    nan: str = "error",
    option: str = "resample_gap=",
) -> Any:
    """The readers' ``resample=``: the experiments ``parts`` (``(time, u, y)``, time in
    seconds, jittered or with gaps) interpolated linearly onto one uniform grid each by
    :meth:`IOData.from_irregular <sysid.IOData.from_irregular>`, the record noting it
    (:class:`Resampling`).

    Parameters
    ----------
    cls : type
        :class:`~sysid.IOData`.
    parts : list of (time, u, y)
        One experiment each; ``u`` may be ``None``.
    resample : float or "median"
        The new sample time in seconds, or ``"median"``: the median spacing of the stamps
        (over every experiment).
    resample_gap : float
        Longest interval between two stamps that is bridged, in multiples of the new sample
        time; a longer one (an outage) is refused with a :class:`~sysid.DataError` naming it
        and where it starts (``numpy.inf`` bridges every gap).
    kw : dict
        Channel names and units, passed on to the record.
    nan : {"error", "interpolate", "split"}
        Samples with a NaN or empty value: ``"error"`` refuses them; otherwise they are left
        out and the interval around them interpolated (within ``resample_gap``).
    option : str
        How the refusal says to pass a larger gap limit (``"resample_gap="``; the command
        line's ``"--resample-gap "``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.data.raw import resample_stamps
    >>> t = np.array([0.0, 0.11, 0.19, 0.3, 0.42, 0.5])
    >>> d = resample_stamps(sysid.IOData, [(t, None, 2 * t)], 0.1, 5.0, {})
    >>> d.y.ravel(), d.resampling.n_samples
    (array([0. , 0.2, 0.4, 0.6, 0.8, 1. ]), 6)
    """
    if nan not in ("error", "interpolate", "split"):
        raise DataError(f"nan must be 'error', 'interpolate' or 'split', got {nan!r}")
    clean = []
    for k, (t, u, y) in enumerate(parts):
        t = np.asarray(t, dtype=float).ravel()
        y = real_array(y, "y").reshape(t.size, -1)
        u = None if u is None else real_array(u, "u").reshape(t.size, -1)
        x = y if u is None else np.concatenate([u, y], axis=1)
        if not np.isfinite(t).all():
            i = int(np.flatnonzero(~np.isfinite(t))[0])
            raise NonFiniteError(f"time has no value at sample {i}: every sample to resample "
                                 "needs its time stamp")
        ok = np.isfinite(x).all(axis=1)
        if not ok.all() and nan == "error":
            i = int(np.flatnonzero(~ok)[0])
            raise NonFiniteError(f"a non-finite or empty value at sample {i} (t = {t[i]:g} s);"
                                 " pass nan='interpolate' to leave such samples out and "
                                 "interpolate across them")
        clean.append((t[ok], None if u is None else u[ok], y[ok], k))
    if isinstance(resample, str):
        if resample != "median":
            raise DataError(f"resample must be a sample time in seconds or 'median', got "
                            f"{resample!r}")
        steps = np.concatenate([np.diff(t) for t, *_ in clean])
        h = float(np.median(steps[steps > 0])) if np.any(steps > 0) else np.nan
    else:
        h = as_dt(resample)
    gap, name = float(resample_gap), option.rstrip("= ")
    if not gap > 0:  # NaN too
        raise DataError(f"{name} must be a positive number of sample times, got "
                        f"{resample_gap!r}")
    for t, _, _, k in clean:
        d = np.diff(t)
        if d.size and d.max() > gap * h:
            i = int(np.argmax(d))
            exp = f" of experiment {k}" if len(clean) > 1 else ""
            raise DataError(
                f"the time stamps{exp} jump by {d[i]:g} s ({d[i] / h:.3g} sample times of "
                f"{h:g} s) after t = {t[i]:g} s (sample {i}): a gap longer than {name} = "
                f"{gap:g} sample times, which interpolation would bridge with a straight line "
                f"the data never showed; cut the record there (IOData.from_irregular cuts it "
                f"into experiments at such gaps), or pass {option}"
                f"{int(np.ceil(d.max() / h))} (or more) to bridge it")
    # no interval is longer than the limit: one piece each, nothing cut
    recs = [from_irregular(cls, t, u, y, h, max_gap=max(float(np.max(np.diff(t), initial=h)),
                                                        h), **kw) for t, u, y, _ in clean]
    if len(recs) == 1:
        return recs[0]
    widest = max(recs, key=lambda r: r.resampling.largest_gap).resampling
    rec = cls([r.u for r in recs] if clean[0][1] is not None else None, [r.y for r in recs],
              h, time=[r.time for r in recs], **kw)
    rec.resampling = Resampling(h, "linear", sum(r.resampling.n_stamps for r in recs),
                                rec.n_samples, widest.largest_gap, widest.gap_after)
    return rec


def _interpolate(t: np.ndarray, x: np.ndarray, grid: np.ndarray, method: str) -> np.ndarray:
    """The columns of ``x`` (at instants ``t``) on ``grid``, linearly or by a cubic spline."""
    if method == "cubic":
        from scipy.interpolate import CubicSpline

        return np.asarray(CubicSpline(t, x, axis=0)(grid))
    return np.column_stack([np.interp(grid, t, c) for c in x.T]).reshape(grid.size, x.shape[1])


def _raw2d(x: Any, name: str) -> np.ndarray:
    arr = real_array(x, name).copy()
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] == 0:
        raise ShapeError(f"{name} must be a non-empty (samples, channels) array, got {arr.shape}")
    return arr
