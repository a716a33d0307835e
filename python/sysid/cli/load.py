"""Reading the command's record: the table in memory or, over :data:`STREAM_BYTES`, in
blocks; the columns asked for by name; the time column found or checked."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Callable

import numpy as np

from ..data.blocks import read_columns
from ..data.table import header, numeric, read_table, text_bytes, units_row
from ..data.units import time_column
from ..errors import DataError
from .progress import _bars
from .time_column import (
    DECIMAL_HINT,
    _check_dt,
    _check_dt_streamed,
    _streamed_time_scale,
    _time_seconds,
)

#: CSV files holding more text than this (decompressed) are read by pyarrow's streaming
#: reader, in blocks.
STREAM_BYTES = 8 << 20


def read_csv(path: str | Path, delimiter: str | None = None) -> tuple[list[str], np.ndarray]:
    r"""Read a numeric table: ``(column names, values (rows, columns))``.

    The first line is a header of names unless every field in it is a number (then the
    columns are named ``"0", "1", ...``). The delimiter is guessed (semicolon, comma, tab,
    else white space) unless given; a trailing delimiter at the end of every line is
    allowed, and fields may be quoted. Empty lines and lines starting with ``#`` are
    skipped. A field that is not a number raises a :class:`~sysid.DataError` naming its
    column and line. The same reader serves :meth:`sysid.IOData.from_csv`
    (``sysid.data.table``).

    Examples
    --------
    >>> import os, tempfile
    >>> from sysid.cli import read_csv
    >>> path = os.path.join(tempfile.mkdtemp(), "d.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("u,y,\n1,2,\n3,4,\n")
    >>> read_csv(path)
    (['u', 'y'], array([[1., 2.],
           [3., 4.]]))
    """
    table = read_table(path, delimiter)
    return table.names, numeric(table, list(range(len(table.names))))


def _columns(spec: str, names: list[str], what: str) -> list[int]:
    want = [s.strip() for s in spec.split(",") if s.strip()]
    if not want:
        raise DataError(f"--{what} is empty; give column names separated by commas")
    idx = []
    for w in want:
        if w in names:
            idx.append(names.index(w))
        else:
            one = len(names) == 1 and any(d in names[0] for d in (",", ";", "|", "\t"))
            raise DataError(f"{what[:-1]} column {w!r} not found; the file has columns: "
                            + ", ".join(names)
                            + ("; the header was read as one column: the file's delimiter is "
                               "not the one used (give it with --delimiter)" if one else ""))
    return idx



def _load(args: argparse.Namespace, say: Callable[[str], None]) -> tuple[
        list[str], list[int], list[int], np.ndarray, np.ndarray, np.ndarray | None]:
    """Names, input and output column indices, u, y and the time column if asked, in seconds
    (numbers in the unit of the column's header, units row or name, as
    :meth:`sysid.IOData.from_csv` reads them: ``time_ms``, ``Time [ms]``); a ``--dt`` given
    beside a time column is checked against it, as the readers check ``dt=``."""
    path = Path(args.data)
    # the size that counts is the text's, decompressed; white-space separated files go to
    # read_table (pyarrow splits on one character)
    big = path.is_file() and (path.suffix.lower() in (".parquet", ".pq")
                              or (text_bytes(path, STREAM_BYTES) > STREAM_BYTES
                                  and header(path, args.delimiter, decimal=args.decimal
                                             ).delimiter not in (" ", "\t")))
    if big:
        say(f"reading {args.data} in blocks")
        names = _header(path, args.delimiter, args.decimal)
        ui = _columns(args.inputs, names, "inputs") if args.inputs else []
        yi = _columns(args.outputs, names, "outputs")
        _find_time(args, names, ui + yi, say)
        _check_dt_streamed(args, path, names, ui + yi)
        ti = [_columns(args.time, names, "times")[0]] if args.time is not None else []
        z = read_columns(path, [names[i] for i in ui + yi + ti], delimiter=args.delimiter,
                         progress=_bars(args), stamps=args.time and names[ti[0]],
                         decimal=args.decimal, hint=DECIMAL_HINT)
        u, y = z[:, :len(ui)], z[:, len(ui):len(ui) + len(yi)]
        t = z[:, -1] * _streamed_time_scale(args, path, names[ti[0]]) if ti else None
        return names, ui, yi, u, y, t
    say(f"reading {args.data}")
    dec = args.decimal  # a logger's units row skipped; decimal commas if asked
    table, row_units = units_row(read_table(args.data, args.delimiter, decimal=dec), dec)
    names = table.names
    ui = _columns(args.inputs, names, "inputs") if args.inputs else []
    yi = _columns(args.outputs, names, "outputs")
    say(f"{len(table.rows)} samples; converting {len(ui)} input and {len(yi)} output "
        "column(s)")
    _find_time(args, names, ui + yi, say)
    _check_dt(args, table, row_units, ui + yi)
    u = numeric(table, ui, decimal=dec, hint=DECIMAL_HINT)
    y = numeric(table, yi, decimal=dec, hint=DECIMAL_HINT)
    t = None
    if args.time is not None:
        ti = _columns(args.time, names, "times")[0]
        t = _time_seconds(table, ti, row_units, dec)
    return names, ui, yi, u, y, t



def _find_time(args: argparse.Namespace, names: list[str], used: list[int],
               say: Callable[[str], None]) -> None:
    """Without --time or --dt: the file's time column (``time``, ``t``, ``Time [s]``, ...;
    not an input or output) gives the sample time, said on stderr; without one, dt = 1 s
    is assumed with a warning (a silent dt = 1 made every frequency, time constant and
    continuous-time model of the report wrong by the true sample time)."""
    if args.time is not None or args.dt is not None:
        return
    k = time_column(names, used)
    if k is not None:
        args.time = names[k]
        say(f"sample time from the time column {names[k]!r} (--time names another; a --dt "
            "must agree with it)")
        return
    # printed as the command's warnings are (--quiet silences progress, not this)
    print(f"sysid: warning: {Path(args.data).name} has no time column (time, t, Time [s], "
          "timestamp, ...) and no --dt or --time was given: assuming a sample time of 1 s "
          "(the report's frequencies and time constants are then per sample); pass --dt "
          "SECONDS or --time COLUMN", file=sys.stderr)



def _header(path: Path, delimiter: str | None, decimal: str = ".") -> list[str]:
    """The column names of a file read in blocks (a text table's as ``read_table`` names
    them: ``"0", "1", ...`` without a header)."""
    if path.suffix.lower() in (".parquet", ".pq"):
        import pyarrow.parquet as pq

        return list(pq.ParquetFile(path).schema_arrow.names)
    return header(path, delimiter, decimal=decimal).names

