"""Physical units of channels and the time base of records.

:func:`check_unit` validates a unit string (SI symbols with prefixes and the usual
engineering units); :func:`sample_time` reads the sample time off a time vector and refuses
non-uniform sampling with a message that names the first offending sample.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from typing import Any

import numpy as np

from .._checks import as_nonnegative
from ..errors import DataError, NonFiniteError, ShapeError

__all__ = ["check_unit", "sample_time", "stamp_resolution"]


# --------------------------------------------------------------------------------------------
# units
# --------------------------------------------------------------------------------------------

_PREFIXABLE = {
    "m", "g", "s", "A", "K", "mol", "cd", "N", "Pa", "J", "W", "V", "Ohm", "ohm", "Hz",
    "rad", "bar", "L", "l", "T", "Wb", "C", "F", "S", "H", "lm", "lx", "Wh", "VA", "t",
}
_PLAIN = {
    "deg", "degC", "degF", "°", "°C", "°F", "%", "-", "1", "rpm", "min", "h", "d", "ft",
    "in", "mi", "nmi", "lbf", "lb", "lbs", "kt", "kn", "kts", "psi", "g0", "G", "counts",
    "count", "bit", "bits", "dB", "dBm", "ppm", "pH", "mmHg", "inHg", "atm", "rev", "cycle",
    "cycles", "sample", "samples", "unit", "units", "pu", "p.u.", "m3", "m2", "cm", "mm",
}
_PREFIXES = ("k", "M", "G", "m", "u", "µ", "n", "p", "c", "d", "h")
_UNIT_TOKEN = re.compile(r"[*/·\s()]+")


def _known_symbol(sym: str) -> bool:
    sym = re.sub(r"\^?-?\d+$", "", sym)  # exponent: m^2, s-1, m2
    if sym in _PLAIN or sym in _PREFIXABLE:
        return True
    return any(sym.startswith(p) and sym[len(p):] in _PREFIXABLE for p in _PREFIXES)


def check_unit(unit: Any, channel: str = "channel") -> str:
    """Validate a unit string such as ``"m/s^2"``, ``"deg/s"``, ``"N*m"`` or ``""`` (none).

    Units are products and quotients of known symbols (SI with prefixes, ``deg``, ``degC``,
    ``%``, ``rpm``, ``ft``, ``kt``, ``psi``, ``g0``, ``counts``, ``-`` for dimensionless...)
    with optional integer exponents. An unknown symbol raises :class:`~sysid.DataError`.

    Examples
    --------
    >>> from sysid.data.units import check_unit
    >>> check_unit("m/s^2", "y0")
    'm/s^2'
    >>> check_unit("furlong", "y0")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: unknown unit 'furlong' for channel y0 (symbol 'furlong'); ...
    """
    if unit is None:
        return ""
    if not isinstance(unit, str):
        raise DataError(f"the unit of channel {channel} must be a string, got {unit!r}")
    u = unit.strip()
    if u == "":
        return ""
    for sym in _UNIT_TOKEN.split(u):
        if sym and not _known_symbol(sym):
            raise DataError(
                f"unknown unit {unit!r} for channel {channel} (symbol {sym!r}); use SI symbols "
                "with prefixes (e.g. 'm/s^2', 'deg/s', 'N*m', 'V'), '-' for dimensionless, "
                "or '' for none"
            )
    return u


# --------------------------------------------------------------------------------------------
# sample time
# --------------------------------------------------------------------------------------------


_COARSEST = 0.1  # the coarsest stamp resolution accepted, as a fraction of the spacing


def stamp_resolution(raw: np.ndarray, t: np.ndarray) -> tuple[str, float]:
    """The floating-point type time stamps were stored in and its resolution at their
    largest magnitude (``np.spacing`` in that type).

    The type is the array's own when it is a floating type narrower than float64, float32
    when every stamp is a float32 value (float32 stamps read back through float64: a CSV
    column, a DataFrame), else float64.

    Parameters
    ----------
    raw : numpy.ndarray
        The time stamps as given.
    t : numpy.ndarray
        The same as float64, finite.

    Returns
    -------
    tuple of (str, float)
        The type's name and the spacing of its representable numbers at ``max |t|``.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.data.units import stamp_resolution
    >>> t = np.float32(1e4) + np.arange(5, dtype=np.float32) * np.float32(0.01)
    >>> stamp_resolution(t, t.astype(float))
    ('float32', 0.0009765625)
    >>> stamp_resolution(t.astype(float), t.astype(float))[0]
    'float32'
    """
    if raw.dtype.kind == "f" and raw.dtype.itemsize < 8:
        dtype = raw.dtype.type
    else:
        with np.errstate(over="ignore"):
            single = bool(np.all(t.astype(np.float32) == t))
        dtype = np.float32 if single else np.float64
    top = float(np.max(np.abs(t)))
    return np.dtype(dtype).name, float(np.spacing(dtype(top)))


#: what a refusal of irregular sampling suggests (:func:`sample_time`'s ``remedy``)
RESAMPLE_REMEDY = ("resample onto a uniform grid: IOData.from_csv(..., resample='median') or "
                   "IOData.from_pandas(..., resample='median') (resample=SECONDS for another "
                   "sample time), sysid.IOData.from_irregular(time, u, y, dt) for arrays")


def sample_time(time: Any, *, rtol: float = 0.01, remedy: str = RESAMPLE_REMEDY) -> float:
    """The sample time of a time vector: its mean spacing, after checking it is uniform.

    Parameters
    ----------
    time : array_like
        Sample instants in seconds, 1-D, at least two.
    rtol : float
        Largest accepted relative deviation of any spacing from the median spacing, beyond
        the rounding of the stamps: two units of their floating-point resolution at their
        magnitude (``np.spacing`` in their type, see :func:`stamp_resolution`) are rounding,
        not jitter (float32 seconds near 1e4 are 0.98 ms apart).
    remedy : str
        What the refusal of gaps or jitter suggests (the command line names its
        ``--resample``).

    Returns
    -------
    float
        The mean spacing ``(t[-1] - t[0]) / (n - 1)``, as the shortest decimal within the
        rounding of the instants (single-precision instants included:
        ``np.arange(300, dtype=np.float32) * 0.1`` gives 0.1, where their median spacing
        is 0.10000038).

    Raises
    ------
    DataError
        If the vector repeats or goes back in time, or has gaps or jitter beyond ``rtol``
        (the message names the first offending sample and ends in ``remedy``: by default
        the readers' ``resample=`` and :meth:`IOData.from_irregular`, which resample onto a
        uniform grid); or if the stamps'
        resolution is coarser than a tenth of their spacing (float32 stamps far from zero,
        such as Unix seconds: the message says to store them as float64 or relative to the
        first stamp).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> sysid.sample_time(np.arange(100) * 0.02 + 5.0)
    0.02
    >>> sysid.sample_time((np.arange(300) * 0.1).astype(np.float32))
    0.1
    """
    rtol = as_nonnegative(rtol, "rtol")  # a NaN accepted any jitter
    raw = np.asarray(time)
    t = np.asarray(raw, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise ShapeError(f"time must be a 1-D vector of at least 2 instants, got shape {t.shape}")
    if not np.isfinite(t).all():
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise NonFiniteError(f"time has a non-finite value at sample {i}")
    kind, ulp = stamp_resolution(raw, t)
    span = float(t[-1] - t[0]) / (t.size - 1)
    d = np.diff(t)
    pos = d[d > 0]
    # stamps too coarse to resolve the spacing: their mean spacing within a few units of
    # their resolution, or (all rounded together) repeats between steps of whole units
    fix = ("Store the time as float64, or relative to the first stamp (t - t[0], computed in "
           "float64 before any conversion to float32), or pass dt=... and leave the time out")
    coarse = (ulp > _COARSEST * span if span > 0 else raw.dtype.kind == "f"
              and raw.dtype.itemsize < 8) or (
        bool(np.any(d == 0)) and pos.size > 0 and ulp > _COARSEST * float(np.min(pos)))
    # stamps on an exact grid lost nothing to rounding, whatever type holds them: float64
    # multiples of 1/1024 s are float32 values too, and a 1024 Hz record of 1100 s was
    # refused as "float32 stamps"
    exact = bool(d.size and d[0] > 0 and np.all(d == d[0]))
    if coarse and not exact:
        raise DataError(
            f"time stamps near {np.max(np.abs(t)):g} s stored as {kind} are {ulp:g} s apart at "
            f"best (the resolution of {kind} there), more than a tenth of the sample spacing "
            f"({span:g} s on average): rounding at that resolution cannot be told from jitter, "
            f"repeats or gaps, and the sample time cannot be read off them. {fix}"
        )
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        i = int(bad[0])
        what = "repeats" if d[i] == 0 else "goes back"
        # every stamp equal and every one a float32 value: perhaps float32 stamps all
        # rounded to one value (Unix seconds: 128 s apart)
        hint = (f"; if the stamps were stored as {kind}, they are {ulp:g} s apart at best "
                f"there, which may have merged them: {fix[0].lower()}{fix[1:]}"
                if span == 0 and kind != "float64" else "")
        raise DataError(
            f"time {what} at sample {i + 1} (t[{i}] = {t[i]:g}, t[{i + 1}] = {t[i + 1]:g}; "
            f"{bad.size} such place(s)); remove duplicate samples or sort the record first"
            f"{hint}"
        )
    h = float(np.median(d))
    # each spacing is a difference of two rounded stamps (off by up to one unit of their
    # resolution), and so is the median: that much is rounding, not jitter
    dev = np.abs(d - h) > rtol * h + 2 * ulp
    if dev.any():
        # a gap: a spacing that could hold a lost sample (half a step longer, at least); a
        # clock jittering by 2 % (a plant's trend recorder) was called "a gap at sample 1",
        # the first spacing off, and told to cut the record at it
        gaps = np.flatnonzero(d > 1.5 * h)
        i = int(gaps[0]) if gaps.size else int(np.flatnonzero(dev)[0])
        kind = "a gap" if gaps.size else "jitter"
        raise DataError(
            f"irregular sampling: {kind} at sample {i + 1} (spacing {d[i]:g} s against the "
            f"median {h:g} s; {int(dev.sum())} spacing(s) off by more than {rtol:.0%}"
            + (f", {gaps.size} of them gaps (over 1.5 times the median)" if gaps.size else "")
            + f"); {remedy}" + ("; or cut the record at the gap" if gaps.size else "")
        )
    # the mean spacing, from the end points: the median of single-precision instants is off
    # by their rounding (float32 seconds at 0.1 s: 0.10000038 s), the mean by it / (n - 1)
    h = float(t[-1] - t[0]) / (t.size - 1)
    # the shortest decimal the instants cannot tell from h (their rounding: float32 when
    # every instant is a float32 value), else the 12-digit one within 1e-9 (summed steps)
    eps = np.finfo(np.float32 if kind == "float32" else
                   raw.dtype if kind == "float16" else np.float64).eps
    res = 2 * eps * max(abs(t[0]), abs(t[-1])) / (t.size - 1)
    for digits in range(1, 16):
        r = float(f"{h:.{digits}g}")
        if abs(r - h) <= res:
            return r
    r = float(f"{h:.12g}")
    return r if abs(r - h) <= 1e-9 * h else h


#: the word "time" in the languages loggers are set to most often (German, French,
#: Spanish, Italian and Portuguese, Dutch, the Scandinavian ones) is a time column too
TIME_NAMES = ("time", "t", "time_s", "t_s", "seconds", "sec", "timestamp", "datetime",
              "date_time", "elapsed_time", "zeit", "temps", "tiempo", "tempo", "tijd", "tid",
              "time_ms", "t_ms", "time_us", "t_us", "time_ns", "t_ns", "timestamp_ms")

#: Seconds per unit of a time column: its header's ``[unit]``/``(unit)`` (or a units row), or
#: a name such as ``time_ms``.
TIME_UNITS = {"s": 1.0, "sec": 1.0, "secs": 1.0, "second": 1.0, "seconds": 1.0,
              "ms": 1e-3, "msec": 1e-3, "millisecond": 1e-3, "milliseconds": 1e-3,
              "us": 1e-6, "\u00b5s": 1e-6, "\u03bcs": 1e-6, "usec": 1e-6, "microsecond": 1e-6,
              "microseconds": 1e-6, "ns": 1e-9, "nanosecond": 1e-9, "nanoseconds": 1e-9,
              "min": 60.0, "mins": 60.0, "minute": 60.0, "minutes": 60.0, "h": 3600.0,
              "hr": 3600.0, "hrs": 3600.0, "hour": 3600.0, "hours": 3600.0}


def split_header(header: str, row_unit: str = "") -> tuple[str, str]:
    """``(name, unit)`` of a column header ``"name [unit]"``; without brackets, the header
    itself and ``row_unit`` (its entry in a logger's units row), as the CSV readers and the
    command line take a column's unit.

    Examples
    --------
    >>> from sysid.data.units import split_header
    >>> split_header("Time [ms]"), split_header("temp", "degC")
    (('Time', 'ms'), ('temp', 'degC'))
    """
    m = re.fullmatch(r"(.*?)\s*\[(.*)\]", str(header))
    return (m.group(1), m.group(2)) if m else (str(header), row_unit)


def time_unit_seconds(name: str, unit: str = "") -> float:
    """Seconds per unit of a numeric time column called ``name``: ``unit`` when given (a CSV
    file's units), else the ``[unit]`` or ``(unit)`` after the name, else a suffix of the name
    (``time_ms``); 1 without one. A unit that is not one of time raises a
    :class:`~sysid.DataError` (read as seconds it would scale every time constant).

    Examples
    --------
    >>> from sysid.data.units import time_unit_seconds
    >>> time_unit_seconds("time [ms]"), time_unit_seconds("t_us"), time_unit_seconds("Time")
    (0.001, 1e-06, 1.0)
    """
    u = str(unit or "").strip()
    if not u:
        m = re.search(r"[\[(]\s*([^\])]*?)\s*[\])]\s*$", str(name))
        u = m.group(1) if m else ""
    if not u:
        m = re.fullmatch(r"(?:time|t|timestamp)_(ms|us|ns|s)", str(name).strip().lower())
        u = m.group(1) if m else ""
    if not u:
        return 1.0
    key = u.lower()
    if key not in TIME_UNITS:
        raise DataError(f"the time column {name!r} is in {u!r}, which sysid does not read as a "
                        "unit of time (s, ms, us, ns, min, h): convert it to seconds, or pass "
                        "dt= (and time=None)")
    return TIME_UNITS[key]


def time_column(names: list[str], exclude: Iterable[int] = ()) -> int | None:
    """The index of the first column named as a time column (``time``, ``t``, ``Time [s]``,
    ``timestamp``, ...: :data:`TIME_NAMES` in any case, a ``[unit]`` or ``(unit)`` after
    it allowed) that is not in ``exclude`` (the chosen inputs and outputs), or ``None``.

    Examples
    --------
    >>> from sysid.data.units import time_column
    >>> time_column(["Time [s]", "u", "y"]), time_column(["u", "y"]), time_column(["t"], [0])
    (0, None, None)
    """
    skip = set(exclude)
    for k, name in enumerate(names):
        bare = re.sub(r"\s*[\[(].*[\])]\s*$", "", str(name)).strip().lower()
        if k not in skip and bare in TIME_NAMES:
            return k
    return None


def check_dt_against_time(t: np.ndarray, dt: float, column: str, where: str = "") -> None:
    """``dt=`` given beside a time column the reader does not read (``t``, seconds): a
    :class:`~sysid.DataError` when the column's median spacing says otherwise, as
    ``IOData(dt=, time=)`` requires (a 0.1 s column read at dt = 0.2 was taken silently).
    Columns that are not increasing (several experiments) are not compared."""
    step = np.diff(np.asarray(t, dtype=float))
    step = step[np.isfinite(step)]
    if not step.size or np.any(step <= 0):
        return
    spacing = float(np.median(step))
    if abs(spacing - dt) > 1e-6 * max(spacing, dt):
        raise DataError(f"{where}dt = {dt:g} s disagrees with its time column {column!r} "
                        f"(samples {spacing:g} s apart); pass one of them (dt= alone, or "
                        "time= without dt=)")
