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
                         decimal=args.decimal, hint=DECIMAL_HINT,
                         missing=[names[i] for i in ui + yi]
                         if getattr(args, "fill_gaps", None) is not None else None)
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
    gaps = getattr(args, "fill_gaps", None) is not None  # missing cells come as NaN
    u = numeric(table, ui, decimal=dec, hint=DECIMAL_HINT, missing=gaps)
    y = numeric(table, yi, decimal=dec, hint=DECIMAL_HINT, missing=gaps)
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


def fill_gaps(u: np.ndarray, y: np.ndarray, t: np.ndarray | None, max_gap: int | None,
              names: list[str], say: Callable[[str], None]
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, dict | None]:
    """``--fill-gaps N``: the missing cells (NaN) of ``u`` and ``y`` filled linearly in runs of
    at most ``max_gap`` samples of a channel (:func:`sysid.repair_nan`), rows at the start or
    end that miss a cell dropped (``t`` with them), and what was done for the report (None:
    nothing was missing). A longer run inside the record is refused, naming its channel,
    rows and length: a block of made-up samples is not data (cut the file there, or read it
    with ``IOData.from_csv(..., nan="split")``, which makes each part an experiment).

    Examples
    --------
    >>> import numpy as np
    >>> u, y = np.arange(6.0)[:, None], np.array([[np.nan], [1], [np.nan], [3], [4], [5]])
    >>> u2, y2, _, note = fill_gaps(u, y, None, 2, ["u", "y"], lambda s: None)
    >>> y2.ravel().tolist(), note["filled_cells"], note["rows_kept"]
    ([1.0, 2.0, 3.0, 4.0, 5.0], 1, [1, 6])
    """
    if max_gap is None:
        return u, y, t, None
    if max_gap < 1:
        raise DataError(f"--fill-gaps must be a positive number of samples, got {max_gap}")
    x = np.concatenate([u, y], axis=1)
    bad = np.isnan(x)
    if not bad.any():
        return u, y, t, None
    from ..data.raw import _runs, repair_nan

    rows = bad.any(axis=1)
    if rows.all():
        raise DataError("every row misses a cell of the inputs or outputs: nothing to fill "
                        "from")
    first = int(np.argmin(rows))  # the first and last complete rows
    last = len(rows) - int(np.argmin(rows[::-1]))
    for j in range(x.shape[1]):
        for a, b in _runs(bad[first:last, j]):
            if b - a > max_gap:
                raise DataError(
                    f"column {names[j]!r} misses {b - a} samples in a row (data rows "
                    f"{first + a + 1}-{first + b}), more than --fill-gaps {max_gap}: a longer "
                    "run is not filled with made-up samples; cut the file there, or read it "
                    "in Python with sysid.IOData.from_csv(path, nan='split', ...), which makes "
                    "each part an experiment")
    (uu, yy, _), = repair_nan(u[first:last], y[first:last], nan="interpolate",
                              max_gap=max_gap)
    filled = int(bad[first:last].sum())
    note = {"filled_cells": filled, "max_gap": int(max_gap),
            "rows_kept": [first, last], "rows_in_file": len(rows)}
    dropped = first + len(rows) - last
    say(f"filled {filled} missing cell(s) linearly (runs of at most {max_gap} samples)"
        + (f"; dropped {dropped} row(s) at the start or end that miss one" if dropped else ""))
    return (np.asarray(uu, float), np.asarray(yy, float), None if t is None else t[first:last],
            note)
