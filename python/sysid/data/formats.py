"""Readers and writers: pandas DataFrames, CSV, NumPy ``.npz`` and MATLAB ``.mat`` files.

They are methods of :class:`~sysid.IOData` (``from_pandas``/``to_pandas``,
``from_csv``/``to_csv``, ``from_npz``/``to_npz``, ``from_mat``/``to_mat``): plain functions
of the record (or of its class, for readers), bound as methods in :mod:`sysid.data.iodata`;
this module never imports that one. Every writer keeps names, units, sample time, experiments
and start times, and the matching reader gives the record back unchanged. ``.npz`` and
``.mat`` files also keep what resampling did (``IOData.resampling``); a CSV file holds no
record-level notes (its header names the columns and their units), and a record read back
from one was not resampled.
"""

from __future__ import annotations

import gzip
import warnings
import zipfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .._atomic import atomic_path
from .._checks import user_stacklevel
from ..errors import DataError, SysidWarning
from .raw import Resampling, resample_stamps
from .table import datetime_seconds, numeric, read_table, units_row
from .units import check_dt_against_time, split_header, time_column, time_unit_seconds

__all__: list[str] = []


def _pandas() -> Any:
    try:
        import pandas as pd
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("this needs pandas: pip install 'sysid[pandas]'") from e
    return pd


def _index_is_time(index: Any) -> bool:
    """A numeric index that holds time: float values, or integers under a time-like name
    (``time``, ``t``, ``seconds``, ...: :data:`sysid.data.units.TIME_NAMES`, any case,
    a ``[unit]`` allowed). Other integers are
    row labels (left by ``iloc[::2]``, ``dropna()`` or ``read_csv(index_col=0)`` of a
    ``sample`` column), not seconds."""
    if index.dtype.kind == "f":
        return True
    return (index.dtype.kind in "iu" and index.name is not None
            and time_column([str(index.name)]) == 0)


def _warn_dropped_rows(index: Any, timed: bool) -> None:
    """Rows missing from an unnamed integer index (``dropna()``, a filter) in a frame without
    time: the record would close the gaps silently."""
    if timed or index.dtype.kind not in "iu" or index.name is not None or len(index) < 2:
        return
    step = np.diff(index.to_numpy())
    if np.all(step == 1):
        return
    k = int(np.flatnonzero(step != 1)[0])
    warnings.warn(
        f"the DataFrame's row labels skip from {index[k]} to {index[k + 1]}"
        + (f" ({int(np.sum(step != 1))} places)" if np.sum(step != 1) > 1 else "")
        + ": rows were dropped or reordered (dropna(), a filter, iloc[::2]), and without "
        "a time column the record treats the rows left as consecutive samples; fill the "
        "gaps instead (IOData.from_pandas(df, nan='interpolate') on the full frame), or "
        "give the time (time='column' or a time index)",
        SysidWarning, stacklevel=user_stacklevel())


def _seconds(x: Any, first: Any, unit: str = "") -> np.ndarray:
    """Time values in seconds: numbers in the unit of their name or ``unit`` (``time [ms]``,
    ``time_ms``: :func:`sysid.data.units.time_unit_seconds`; seconds without one); datetime64
    and timedelta64 stamps (a column or a ``DatetimeIndex``/``TimedeltaIndex``) as seconds
    since the first stamp of ``first`` (the first experiment's), not as their raw nanosecond
    counts."""
    pd = _pandas()
    idx = pd.Index(x)
    if idx.dtype.kind not in "mM":
        return idx.to_numpy(dtype=float) * time_unit_seconds(str(getattr(x, "name", "") or ""),
                                                             unit)
    return np.asarray((idx - pd.Index(first)[0]).total_seconds(), dtype=float)


def grid_dt(ts: list[np.ndarray], candidates: list[Any], rtol: float = 0.0) -> float | None:
    """The first candidate sample time whose grid ``t0 + k dt`` gives every time vector
    back within its rounding (a few units in the last place, or ``rtol`` of the largest
    instant): a stored dt such as 1/60, which the time vector alone would read as the
    shortest decimal that fits its spacing (0.0166666666667). None when none fits."""
    ts = [np.asarray(t, dtype=float) for t in ts]
    if not ts or any(t.size < 2 for t in ts):
        return None
    for c in candidates:
        try:
            c = float(c)
        except (TypeError, ValueError):
            continue
        if not (np.isfinite(c) and c > 0):
            continue
        if all(np.max(np.abs(t - (t[0] + np.arange(t.size) * c)))
               <= max(4 * np.spacing(np.max(np.abs(t)) + c), rtol * np.max(np.abs(t)))
               for t in ts):
            return c
    return None


def _time_column(df: Any, channels: list[Any]) -> Any:
    """The frame's time column, not one of ``channels``: under a usual name (``time``, ``t``,
    ``Time [s]``, ``timestamp``, ...: :func:`sysid.data.units.time_column`), else the one
    column of date-times or durations whatever its name (``stamp``, ``recorded_at``: its
    type says what it is)."""
    names = [str(c) for c in df.columns]
    k = time_column(names, [names.index(str(c)) for c in channels if str(c) in names])
    if k is not None:
        return df.columns[k]
    used = {str(c) for c in channels}
    stamps = [c for c in df.columns if str(c) not in used and df[c].dtype.kind in "mM"]
    return stamps[0] if len(stamps) == 1 else None


def to_pandas(data: Any) -> Any:
    """A DataFrame: one column per channel plus ``experiment``, indexed by ``time``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> df = sysid.IOData(u=np.ones(3), y=np.zeros(3), dt=0.5).to_pandas()
    >>> list(df.columns)
    ['experiment', 'u0', 'y0']
    """
    pd = _pandas()
    frames = []
    for k, (e, t) in enumerate(zip(data._exps, data.times)):
        cols: dict[str, Any] = {"experiment": np.full(len(t), k)}
        for j, n in enumerate(data.input_names):
            cols[n] = e.u[:, j]
        for j, n in enumerate(data.output_names):
            cols[n] = e.y[:, j]
        frames.append(pd.DataFrame(cols, index=pd.Index(t, name="time")))
    df = pd.concat(frames)
    df.attrs.update(
        {
            "dt": data.dt,
            "inputs": list(data.input_names),
            "outputs": list(data.output_names),
            "units": dict(zip(data.input_names + data.output_names,
                              data.input_units + data.output_units)),
        }
    )
    return df


def from_pandas(
    cls: Any,
    df: Any,
    inputs: Sequence[str] | None = None,
    outputs: Sequence[str] | None = None,
    *,
    time: str | None = None,
    dt: float | None = None,
    experiment: str | None = None,
    units: dict[str, str] | None = None,
    nan: str = "error",
    max_gap: int = 5,
    resample: float | str | None = None,
    resample_gap: float = 5.0,
) -> Any:
    """A record from a DataFrame's columns.

    Parameters
    ----------
    df : pandas.DataFrame
    inputs, outputs : list of str
        Column names. Default: those stored by :meth:`to_pandas` in ``df.attrs``.
    time : str, optional
        Column holding the time in seconds; default the index when it is numeric and
        ``dt`` is not given. Date-times and time deltas (``datetime64``/``timedelta64``
        columns, a ``DatetimeIndex`` or ``TimedeltaIndex``) are converted to seconds from
        the first stamp.
    dt : float, optional
        Sample time (when there is no time information).
    experiment : str, optional
        Column numbering the experiments (default ``"experiment"`` if present).
    units : dict, optional
        Unit per column name.
    nan, max_gap :
        Handling of missing values (single-experiment frames), as in :meth:`from_raw`.
    resample, resample_gap : optional
        Time stamps with jitter or gaps: as :meth:`from_csv`'s.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.ones(3), y=np.arange(3.0), dt=0.5)
    >>> sysid.IOData.from_pandas(d.to_pandas()) == d
    True
    """
    pd = _pandas()
    if not isinstance(df, pd.DataFrame):
        raise DataError(f"from_pandas takes a pandas DataFrame, got {type(df).__name__}")
    inputs = list(df.attrs.get("inputs", [])) if inputs is None else list(inputs)
    if outputs is None:
        if "outputs" not in df.attrs:
            raise DataError("name the output columns: IOData.from_pandas(df, inputs, outputs)")
        outputs = list(df.attrs["outputs"])
    outputs = list(outputs)
    missing = [c for c in inputs + outputs if c not in df.columns]
    if missing:
        raise DataError(
            f"column(s) {missing} not in the DataFrame (columns: {list(df.columns)})"
        )
    for arg, col in (("experiment", experiment), ("time", time)):
        if col is not None and col not in df.columns:
            raise DataError(f"{arg} column {col!r} is not in the DataFrame (columns: "
                            f"{list(df.columns)}); name one of them, or leave {arg}=None")
    units = dict(df.attrs.get("units", {})) if units is None else dict(units)
    if resample is not None:
        _resample_args(dt, True, "", "")
    if experiment is None and "experiment" in df.columns:
        experiment = "experiment"
    groups = [df] if experiment is None else [g for _, g in df.groupby(experiment, sort=True)]
    us, ys, ts = [], [], []
    for g in groups:
        us.append(g[inputs].to_numpy(dtype=float) if inputs else None)
        ys.append(g[outputs].to_numpy(dtype=float))
        if time is not None:
            ts.append(_seconds(g[time], groups[0][time], units.get(time, "")))
        elif dt is None and g.index.dtype.kind in "mM":
            ts.append(_seconds(g.index, groups[0].index))
        elif dt is None and _index_is_time(g.index):
            ts.append(g.index.to_numpy(dtype=float)
                      * time_unit_seconds(str(g.index.name or "")))
        elif dt is None and (tc := _time_column(g, inputs + outputs)) is not None:
            ts.append(_seconds(g[tc], groups[0][tc], units.get(tc, "")))
    for g in groups:
        _warn_dropped_rows(g.index, time is not None or bool(ts))
    if (dt is not None and time is None and experiment is None
            and (tc := _time_column(df, inputs + outputs)) is not None):
        check_dt_against_time(_seconds(df[tc], df[tc], units.get(tc, "")), float(dt), str(tc))
    kw: dict[str, Any] = {
        "input_names": inputs,
        "output_names": outputs,
        "input_units": [units.get(c, "") for c in inputs],
        "output_units": [units.get(c, "") for c in outputs],
    }
    if resample is not None:
        _resample_args(dt, bool(ts), "the DataFrame", "time='column' or a time index")
        return resample_stamps(cls, list(zip(ts, us, ys)), resample, resample_gap, kw, nan=nan)
    if dt is None and ts and "dt" in df.attrs:
        # the stored dt (to_pandas) when the time agrees with it: 1/60, not 0.0166666666667
        dt = grid_dt(ts, [df.attrs["dt"]], rtol=1e-9)
    if dt is None and not ts:
        dt = df.attrs.get("dt")
        if dt is None:
            named = df.index.name is not None and df.index.dtype.kind in "iu"
            warnings.warn(
                "the DataFrame carries no sample time (no dt=, no time column, "
                + (f"an integer index named {df.index.name!r}, read as row numbers"
                   if named else "a default 0, 1, 2, ... index")
                + "): assuming dt = 1 s; pass dt=... or time='column'",
                SysidWarning, stacklevel=user_stacklevel(),
            )
    if nan != "error":
        if len(groups) != 1:
            raise DataError("nan= repairs single-experiment frames; split them first")
        return cls.from_raw(us[0], ys[0], dt, time=ts[0] if ts else None, nan=nan,
                            max_gap=max_gap, **kw)
    return cls(
        us if inputs else None,
        ys,
        dt,
        time=ts if ts else None,
        **kw,
    )


def to_csv(data: Any, path: str | Path) -> None:
    """Write a CSV file: header ``time,experiment,<inputs>,<outputs>``, one row a sample.

    Units are written into the header as ``name [unit]``; :meth:`from_csv` reads them back.
The record's ``resampling`` (what ``resample=`` did) has no place in the file: the samples
are written, on their uniform grid, and the record read back has ``resampling = None``
(:meth:`to_npz` and :meth:`to_mat` keep it).
    A name ending in ``.gz`` writes a gzip-compressed file. The file is written whole or not
    at all (see ``sysid._atomic``).
    """
    head = ["time", "experiment"] + [
        f"{n} [{u}]" if u else n
        for n, u in zip(data.input_names + data.output_names,
                        data.input_units + data.output_units)
    ]
    rows = [
        np.column_stack([t, np.full(len(t), k), e.u, e.y])
        for k, (e, t) in enumerate(zip(data._exps, data.times))
    ]
    path = Path(path)
    with atomic_path(path) as tmp, (
        gzip.open(tmp, "wb") if path.name.endswith(".gz") else open(tmp, "wb")
    ) as f:
        np.savetxt(
            f, np.vstack(rows), delimiter=",", header=",".join(head), comments="",
            fmt="%.17g",
        )


def from_csv(
    cls: Any,
    path: str | Path,
    inputs: Sequence[str | int] | None = None,
    outputs: Sequence[str | int] | None = None,
    *,
    time: str | int | None = None,
    dt: float | None = None,
    experiment: str | int | None = None,
    delimiter: str | None = None,
    decimal: str = ".",
    nan: str = "error",
    max_gap: int = 5,
    resample: float | str | None = None,
    resample_gap: float = 5.0,
) -> Any:
    """Read a CSV file (the format of :meth:`to_csv`, or any other) or a white-space
    separated ``.dat`` file.

    The first line is a header of names unless every field in it is a number: then it is
    the first sample, the columns are chosen by 0-based index (or ``"0"``, ``"1"``, ...)
    and the channels get the default names (``u0``, ``y0``, ...). Columns are chosen by
    header name (as written, or without its ``[unit]``) or 0-based index; ``name [unit]``
    headers give units, and so does a row of units under the header (a logger's ``s, W,
    degC``: no number in it). A time column may hold date-time stamps (ISO 8601, ``Z`` or
    ``+hh:mm`` offsets), read as seconds after the first. Without
    ``inputs``/``outputs``, a file written by :meth:`to_csv` is read back whole. Empty
    fields become NaN and are handled as ``nan`` says (see :meth:`from_raw`; only for
    single-experiment files); a field that is not a number raises a
    :class:`~sysid.DataError` naming its line and column. Quoted fields, a trailing
    delimiter, empty lines, ``#`` comment lines and a UTF-8 byte-order mark are allowed.
    The delimiter is guessed from the first line (semicolon, comma, tab, else white space,
    as in ``.dat`` files) unless given; ``decimal=","`` reads decimal commas (then the
    delimiter is a semicolon, tab or white space). Files ending in ``.gz``, ``.bz2`` or
    ``.xz`` are decompressed while reading. The same reader serves the command line
    (``sysid.data.table``). Without ``time`` or ``dt``, a column named as a time column
    (``time``, ``t``, ``Time [s]``, ``timestamp``, ...; not an input or output) is the time
    column; without one, dt = 1 s is assumed with a warning.

    A time column with gaps or jitter (a logger's stamps) is refused unless ``resample``
    is given: then every channel is interpolated linearly onto a uniform grid of that sample
    time in seconds (``"median"``: the stamps' median spacing), as
    :meth:`from_irregular` does, and the record notes it (``record.resampling``: the sample
    time, the samples, the longest interval bridged). An interval between stamps longer
    than ``resample_gap`` sample times (an outage) is refused, naming it and where it
    starts: pass a larger ``resample_gap`` to bridge it (``numpy.inf``: every one). With
    ``resample``, samples with an empty value are left out and interpolated across
    (within ``resample_gap``) when ``nan`` is not ``"error"``.

    Examples
    --------
    >>> import numpy as np, sysid, tempfile, os
    >>> d = sysid.IOData(u=np.arange(4.0), y=np.ones(4), dt=0.5, output_units=["m"])
    >>> f = os.path.join(tempfile.mkdtemp(), "rec.csv.gz")
    >>> d.to_csv(f)
    >>> back = sysid.IOData.from_csv(f, inputs=["u0"], outputs=["y0"])
    >>> back == d, back.output_units
    (True, ['m'])
    """
    p = Path(path)
    if resample is not None:
        _resample_args(dt, True, "", "")
    if decimal not in (".", ","):
        raise DataError(f"decimal must be '.' or ',', got {decimal!r}")
    table, row_units = units_row(read_table(p, delimiter, decimal=decimal), decimal)
    names, unit_of = [], {}
    for k, h in enumerate(table.names):
        n, unit_of_h = split_header(h, row_units.get(k, ""))
        names.append(n)
        unit_of[n] = unit_of_h

    def col(c: str | int) -> int:
        if isinstance(c, (int, np.integer)):
            if not 0 <= c < len(names):
                hint = "" if len(names) > 1 else (
                    "; the header was read as one column with "
                    + (f"delimiter={delimiter!r}" if delimiter else "the guessed delimiter")
                    + ": "
                    "pass delimiter=... (e.g. ' ' or '\\t')"
                )
                raise DataError(
                    f"column {c} out of range: the file has {len(names)} columns{hint}"
                )
            return int(c)
        if c not in names and c in table.names:  # the header as written, "name [unit]"
            return table.names.index(c)
        if c not in names:
            raise DataError(f"no column {c!r} in {p.name}; its columns are {names}")
        return names.index(c)

    if inputs is None and outputs is None and names[:2] == ["time", "experiment"]:
        # our own format: which are inputs is not stored, so everything after is outputs
        raise DataError(
            f"{p.name}: say which columns are inputs and outputs, e.g. "
            f"IOData.from_csv(path, inputs=[...], outputs=[...]); columns: {names[2:]}"
        )
    if outputs is None:
        raise DataError(f"name the output columns of {p.name}; its columns are {names}")
    iu = [col(c) for c in (inputs or [])]
    iy = [col(c) for c in outputs]
    if time is None and dt is None:  # a column named time, t, Time [s], timestamp, ...
        time = time_column(table.names, iu + iy)
    if experiment is None and "experiment" in names:
        experiment = "experiment"
    tcol = None if time is None else col(time)
    ecol = None if experiment is None else col(experiment)
    kw: dict[str, Any] = {
        # a headerless file (a .dat) names no channels: the record's defaults u0, y0, ...
        "input_names": None if table.headerless else [names[i] for i in iu],
        "output_names": None if table.headerless else [names[i] for i in iy],
        "input_units": [unit_of[names[i]] for i in iu],
        "output_units": [unit_of[names[i]] for i in iy],
    }
    used = sorted(set(iu + iy + [c for c in (tcol, ecol) if c is not None]))
    data = np.full((len(table.rows), len(names)), np.nan)
    stamps = None if tcol is None else datetime_seconds(table, tcol, decimal)
    if stamps is not None:  # date-time stamps: seconds after the first
        data[:, tcol] = stamps
        used = [c for c in used if c != tcol]
    data[:, used] = numeric(table, used, missing=True, decimal=decimal,
                            hint="pass decimal=','")
    if tcol is not None and stamps is None:  # numbers in the column's unit: to seconds
        data[:, tcol] *= time_unit_seconds(table.names[tcol], unit_of[names[tcol]])
    elif tcol is None and dt is not None:
        _check_dt_against_time(table, names, unit_of, iu + iy, float(dt), decimal, p.name)
    if tcol is None and dt is None:
        warnings.warn(
            f"{p.name} has no time column and no dt= was given: assuming dt = 1 s; pass "
            "dt=... or time='column'", SysidWarning, stacklevel=user_stacklevel())
    if resample is not None:
        _resample_args(dt, tcol is not None, p.name, "time='column'")
        qs = [data] if ecol is None else [data[data[:, ecol] == k] for k in
                                          np.unique(data[:, ecol])]
        return resample_stamps(cls, [(q[:, tcol], q[:, iu] if iu else None, q[:, iy])
                                     for q in qs], resample, resample_gap, kw, nan=nan)
    if tcol is not None and dt is None and np.isfinite(data[:, tcol]).all():
        # the dt the time column was written with (to_csv): its shortest decimal (0.1) or,
        # for a rate such as 1/60, its mean spacing, when that grid gives the column back
        ks = [data[:, tcol]] if ecol is None else [
            data[data[:, ecol] == k, tcol] for k in np.unique(data[:, ecol])]
        if all(t.size >= 2 and np.all(np.diff(t) > 0) for t in ks):
            spans = [(t[-1] - t[0]) / (t.size - 1) for t in ks]
            dt = grid_dt(ks, [float(f"{spans[0]:.12g}"), *spans])
    if ecol is not None:
        ks = data[:, ecol]
        parts = [data[ks == k] for k in np.unique(ks)]
        return cls(
            [q[:, iu] for q in parts] if iu else None,
            [q[:, iy] for q in parts],
            dt,
            time=None if tcol is None else [q[:, tcol] for q in parts],
            **kw,
        )
    return cls.from_raw(
        data[:, iu] if iu else None,
        data[:, iy],
        dt,
        time=None if tcol is None else data[:, tcol],
        nan=nan,
        max_gap=max_gap,
        **kw,
    )


def _resample_args(dt: Any, timed: bool, what: str, how: str) -> None:
    """``resample=`` needs the time stamps (``timed``) and no ``dt=`` (it is the new sample
    time); ``timed=True`` checks ``dt`` alone."""
    if dt is not None:
        raise DataError("give resample= (the new sample time, or 'median') or dt=, not both")
    if not timed:
        raise DataError(f"{what} has no time column to resample: name it ({how})")


def _check_dt_against_time(table: Any, names: list[str], unit_of: dict[str, str],
                           channels: list[int], dt: float, decimal: str, file: str) -> None:
    """``dt=`` given while the file has a time column (not read then): they must agree, as
    ``IOData(dt=, time=)`` requires (a 0.1 s column read at dt = 0.2 was taken silently)."""
    k = time_column(table.names, channels)
    if k is None:
        return
    try:
        t = numeric(table, [k], missing=True, decimal=decimal, hint="")[:, 0]
    except DataError:
        return  # not numbers (date-time stamps or text): nothing to compare
    check_dt_against_time(t * time_unit_seconds(table.names[k], unit_of[names[k]]), dt,
                          table.names[k], f"{file}: ")


def _arrays(data: Any) -> dict[str, Any]:
    out: dict[str, Any] = {
        "dt": data.dt,
        "t0": np.array([e.t0 for e in data._exps]),
        "input_names": np.array(data.input_names, dtype=str),
        "output_names": np.array(data.output_names, dtype=str),
        "input_units": np.array(data.input_units, dtype=str),
        "output_units": np.array(data.output_units, dtype=str),
        "n_experiments": data.n_experiments,
    }
    for k, e in enumerate(data._exps):
        out[f"u_{k}"] = e.u
        out[f"y_{k}"] = e.y
    r = data.resampling
    if r is not None:  # what resample= / from_irregular did: absent on a record as sampled
        out["resampling"] = np.array([r.dt, r.n_stamps, r.n_samples, r.largest_gap,
                                      r.gap_after], dtype=float)
        out["resampling_method"] = np.array([r.method], dtype=str)
    return out


def _resampling(get: Any, strs: Any) -> Resampling | None:
    """The :class:`~sysid.data.raw.Resampling` :func:`_arrays` wrote, ``None`` when the
    record was not resampled (or the file predates it)."""
    try:
        v = np.asarray(get("resampling"), dtype=float).ravel()
        method = strs("resampling_method")
    except KeyError:
        return None
    if v.size != 5 or len(method) != 1:
        raise DataError(f"the record's resampling is malformed: {v.size} numbers and "
                        f"{len(method)} method(s) (want 5 and 1); write it again with IOData")
    return Resampling(float(v[0]), method[0], int(v[1]), int(v[2]), float(v[3]), float(v[4]))


def _from_arrays(cls: Any, get: Any, what: str) -> Any:
    try:
        n = int(np.asarray(get("n_experiments")).ravel()[0])
        dt = float(np.asarray(get("dt")).ravel()[0])
        t0 = np.asarray(get("t0"), dtype=float).ravel()

        def strs(key: str) -> list[str]:
            out = []
            for s in np.asarray(get(key), dtype=object).ravel():
                while isinstance(s, np.ndarray):  # MATLAB cells arrive nested
                    s = s.ravel()[0] if s.size else ""
                out.append(str(s).strip())
            return out

        us = [np.asarray(get(f"u_{k}"), dtype=float) for k in range(n)]
        ys = [np.asarray(get(f"y_{k}"), dtype=float) for k in range(n)]
    except KeyError as e:
        raise DataError(f"{what} was not written by IOData (missing {e}); "
                        "read it with numpy or scipy.io and build IOData yourself") from None
    in_names = strs("input_names") if us[0].size and us[0].shape[-1] else []
    us = [u.reshape(len(y), len(in_names)) for u, y in zip(us, ys)]
    out_names = strs("output_names")
    ys = [y.reshape(-1, len(out_names)) for y in ys]
    rec = cls(
        us if in_names else None,
        ys,
        dt,
        time=[t + np.arange(len(y)) * dt for t, y in zip(t0, ys)],
        input_names=in_names,
        output_names=out_names,
        input_units=strs("input_units")[: len(in_names)] if in_names else [],
        output_units=strs("output_units")[: len(out_names)],
    )
    rec.resampling = _resampling(get, strs)
    return rec


def to_npz(data: Any, path: str | Path) -> None:
    """Save to a NumPy ``.npz`` archive (all experiments, names, units, dt, start times and
    the record's ``resampling``, when it was resampled);
    ``.npz`` is appended to a name without it, as :func:`numpy.savez` does. The file is
    written whole or not at all (see ``sysid._atomic``)."""
    path = Path(path)
    if not path.name.endswith(".npz"):
        path = path.with_name(path.name + ".npz")
    arrays = _arrays(data)
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        np.savez(f, **arrays)


def from_npz(cls: Any, path: str | Path) -> Any:
    """Load a record saved by :meth:`to_npz`.

    Examples
    --------
    >>> import numpy as np, sysid, tempfile, os
    >>> d = sysid.IOData(u=np.ones((4, 2)), y=np.arange(4.0), dt=0.1, output_units=["m"])
    >>> f = os.path.join(tempfile.mkdtemp(), "rec.npz")
    >>> d.to_npz(f)
    >>> sysid.IOData.from_npz(f) == d
    True
    """
    not_ours = DataError(f"{path} is not a sysid .npz record (an archive written by "
                         "IOData.to_npz); for other NumPy files, load the arrays with np.load "
                         "and pass them to sysid.IOData(u, y, dt)")
    # the file is opened here so that it is closed whatever np.load makes of it
    with open(path, "rb") as fh:
        try:
            z = np.load(fh, allow_pickle=False)
        except ValueError:  # not an archive of plain arrays (NumPy suggests pickle: never)
            raise not_ours from None
        except (EOFError, zipfile.BadZipFile) as e:  # an empty or cut-off file
            raise DataError(f"{path} is empty or cut off ({type(e).__name__}: {e}): not a "
                            "whole .npz archive; write it again (IOData.to_npz writes whole "
                            "files or nothing)") from None
        if not isinstance(z, np.lib.npyio.NpzFile):
            raise not_ours
        with z:
            if "n_experiments" not in z.files:
                raise not_ours
            return _from_arrays(cls, lambda k: z[k], str(path))


def to_mat(data: Any, path: str | Path) -> None:
    """Save to a MATLAB ``.mat`` file (``scipy.io.savemat``): what :meth:`to_npz` saves
    (with the record's ``resampling``); one experiment also gets the plain variables ``u``,
    ``y``, ``dt`` that MATLAB users expect. The file is written whole
    or not at all (see ``sysid._atomic``)."""
    from scipy.io import savemat

    d = _arrays(data)
    d = {k: (np.array(list(v), dtype=object) if k.endswith(("names", "units")) else v)
         for k, v in d.items()}
    if data.n_experiments == 1:
        d["u"], d["y"] = data._exps[0].u, data._exps[0].y
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        savemat(f, d)


def from_mat(
    cls: Any,
    path: str | Path,
    *,
    u: str | None = "u",
    y: str = "y",
    dt: float | str | None = None,
    input_names: Sequence[str] | None = None,
    output_names: Sequence[str] | None = None,
) -> Any:
    """Load a MATLAB ``.mat`` file: one written by :meth:`to_mat`, or any file with
    input/output matrices under the variable names ``u`` and ``y`` (samples in rows).

    ``dt`` may be a number or the name of a variable holding it; without it, a scalar
    variable named ``Ts`` (MATLAB's ``iddata`` property), ``dt`` or ``ts`` is the sample
    time, and without one dt = 1 s is assumed with a warning (it was assumed silently). A
    variable ``u`` or ``y`` that is not in the file raises a :class:`~sysid.DataError`
    listing the file's variables; output-only data (a time series) is read with ``u=None``.
    """
    from scipy.io import loadmat
    from scipy.io.matlab import MatReadError

    try:
        m = loadmat(path)
    except (MatReadError, ValueError, TypeError, NotImplementedError) as e:
        raise DataError(f"{path} is not a readable MATLAB .mat file ({e}); save it from "
                        "MATLAB with save(file, 'u', 'y') (format -v7 or older: -v7.3 files "
                        "are HDF5, read them with h5py)") from None
    if "n_experiments" in m and dt is None and u == "u" and y == "y":
        return _from_arrays(cls, lambda k: m[k], str(path))
    if y not in m:
        have = sorted(k for k in m if not k.startswith("__"))
        raise DataError(f"no variable {y!r} in {path}; it holds {have}")
    if isinstance(dt, str):
        if dt not in m:
            raise DataError(f"no variable {dt!r} (sample time) in {path}")
        dt = float(np.asarray(m[dt]).ravel()[0])
    if u is not None and u not in m:
        have = sorted(k for k in m if not k.startswith("__"))
        raise DataError(f"no input variable {u!r} in {path}; it holds {have}: name it with "
                        "u='...', or pass u=None for output-only (time-series) data")
    uu = None if u is None else m[u]
    yy = np.asarray(m[y], dtype=float)
    if yy.ndim == 2 and yy.shape[0] < yy.shape[1] and yy.shape[0] <= 16:
        raise DataError(
            f"{y!r} in {path} has shape {yy.shape}: samples must be rows; transpose it"
        )
    if dt is None:  # the file's own sample time, under MATLAB's name or ours
        ts = next((k for k in ("Ts", "dt", "ts") if k in m and np.size(m[k]) == 1), None)
        if ts is not None:
            dt = float(np.asarray(m[ts]).ravel()[0])
        else:
            warnings.warn(f"{Path(path).name} holds no sample time (a scalar Ts or dt) and no "
                          "dt= was given: assuming dt = 1 s; pass dt=... (seconds, or the name "
                          "of the variable holding it)", SysidWarning, stacklevel=user_stacklevel())
    return cls(uu, yy, dt, input_names=input_names, output_names=output_names)
