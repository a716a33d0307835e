"""The record's time column: in seconds (the unit of its header, units row or name), and
``--dt`` checked against it as the readers check ``dt=``."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ..data.table import Table, datetime_seconds, first_rows, header, numeric, stamps_ns, units_row
from ..data.units import check_dt_against_time, split_header, time_column, time_unit_seconds
from ..errors import DataError

#: how the command says to read decimal commas (in a number's error)
DECIMAL_HINT = "pass --decimal ,"


def _seconds_per_unit(name: str, row_unit: str = "") -> float:
    """Seconds per unit of a numeric time column named ``name``, as
    :meth:`sysid.IOData.from_csv` takes it: the ``[unit]`` of its header, else the logger's
    units row (``row_unit``), else its name (``(ms)``, ``time_ms``): one function,
    :func:`sysid.data.units.time_unit_seconds`; seconds without one."""
    return time_unit_seconds(name, split_header(name, row_unit)[1])


def _time_seconds(table: Table, k: int, row_units: dict[int, str], dec: str) -> np.ndarray:
    """Column ``k`` of ``table`` in seconds: date-time stamps as seconds after the first,
    numbers in the column's unit (:func:`_seconds_per_unit`)."""
    t = datetime_seconds(table, k, dec)
    if t is not None:
        return t
    return (numeric(table, [k], decimal=dec, hint=DECIMAL_HINT)[:, 0]
            * _seconds_per_unit(table.names[k], row_units.get(k, "")))


def _check_dt(args: argparse.Namespace, table: Table, row_units: dict[int, str],
              used: list[int]) -> None:
    """``--dt`` given while the file has a time column (``time``, ``time_ms``, ``Time [s]``,
    ...: not an input or output, and not read then): they must agree, as
    ``IOData.from_csv(dt=...)`` requires of the same file (a column 10 ms apart read at
    --dt 10, or at a --dt off by the column's unit, was taken silently). A column that is
    not numbers or date-time stamps is not compared."""
    k = time_column(table.names, used)
    if args.dt is None or args.time is not None or k is None:
        return
    try:
        t = _time_seconds(table, k, row_units, args.decimal)
    except DataError:
        return  # text, not times: nothing to compare
    _refuse_dt(args, t, table.names[k], _seconds_per_unit(table.names[k],
                                                          row_units.get(k, "")))


def _refuse_dt(args: argparse.Namespace, t: np.ndarray, name: str, unit: float) -> None:
    """The readers' test (:func:`sysid.data.units.check_dt_against_time`) of ``--dt``
    against the time column ``name`` (``t`` in seconds; ``unit``: seconds per its unit),
    its error in the command's terms."""
    try:
        check_dt_against_time(t, float(args.dt), name)
    except DataError:
        spacing = float(np.median(np.diff(t)))
        raise DataError(
            f"{Path(args.data).name}: --dt {args.dt:g} s disagrees with its time column "
            f"{name!r}, whose samples are {spacing:g} s apart"
            + (f" (its numbers are in units of {unit:g} s)" if unit != 1.0 else "")
            + "; leave --dt out (the time column gives the sample time), or correct it "
            "(--dt is in seconds)") from None


def _check_dt_streamed(args: argparse.Namespace, path: Path, names: list[str],
                       used: list[int]) -> None:
    """:func:`_check_dt` for a file read in blocks: on its first rows (CSV), or on its time
    column when that holds numbers (Parquet)."""
    k = time_column(names, used)
    if args.dt is None or args.time is not None or k is None:
        return
    if path.suffix.lower() in (".parquet", ".pq"):
        import pyarrow as pa
        import pyarrow.parquet as pq

        pf = pq.ParquetFile(path)
        kind = pf.schema_arrow.field(names[k]).type
        if pa.types.is_integer(kind) or pa.types.is_floating(kind):
            col = pf.read(columns=[names[k]]).column(0).to_numpy(zero_copy_only=False)
            unit = _seconds_per_unit(names[k])
            _refuse_dt(args, np.asarray(col, float) * unit, names[k], unit)
        return
    head = header(path, args.delimiter, decimal=args.decimal)
    table, row_units = units_row(first_rows(path, head, _CHECK_ROWS), args.decimal)
    _check_dt(args, table, row_units, used)


#: rows at the start of a file read in blocks on which a --dt is checked against its time
#: column (the median spacing of the whole column is the same on a uniformly sampled record)
_CHECK_ROWS = 2000


def _streamed_time_scale(args: argparse.Namespace, path: Path, name: str) -> float:
    """Seconds per unit of the time column ``name`` of a file read in blocks (1 when it holds
    date-time stamps, which the block reader returns in seconds; a Parquet file has no
    units row)."""
    if path.suffix.lower() in (".parquet", ".pq"):
        return _seconds_per_unit(name)
    head = header(path, args.delimiter, decimal=args.decimal)
    table, row_units = units_row(first_rows(path, head, 3), args.decimal)
    k = head.names.index(name)
    if table.rows and k < len(table.rows[0]) and stamps_ns([table.rows[0][k]])[0] is not None:
        return 1.0
    return _seconds_per_unit(name, row_units.get(k, ""))

