"""Reading the named numeric columns of a large table in blocks (:func:`read_columns`):
CSV through pyarrow's streaming reader, Parquet by record batches, with a progress bar and
the in-memory reader's rules (``sysid.data.table``): its names, comments, bad cells named by
line and column, a logger's units row and date-time stamps in the time column. The command
line reads files over ``sysid.cli.load.STREAM_BYTES`` through it."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..errors import DataError
from .table import (
    REPAIR,
    ForwardReader,
    Uncommented,
    decompressing,
    first_bad_cell,
    first_rows,
    header,
    stamps_ns,
    units_row,
)

__all__ = ["read_columns", "STREAM_BLOCK"]

#: Bytes per block of that reader (at least one line).
STREAM_BLOCK = 16 << 20


class _CountingFile(ForwardReader):
    """A binary file that advances a progress bar by the bytes read through it."""

    def __init__(self, path: Path, bar: Any) -> None:
        self._src, self._bar = open(path, "rb"), bar  # noqa: SIM115 (closed by close())

    def read(self, n: int = -1) -> bytes:
        b = self._src.read(n)
        self._bar.update(len(b))
        return b


def read_columns(path: str | Path, columns: list[str], *, delimiter: str | None = None,
                 progress: bool | None = None, block_size: int | None = None,
                 stamps: str | None = None, decimal: str = ".", hint: str = "",
                 missing: list[str] | None = None) -> np.ndarray:
    """Read the named numeric columns of a large CSV or Parquet file in blocks.

    CSV goes through pyarrow's streaming reader (``pyarrow.csv.open_csv``, blocks of
    ``block_size`` bytes, default :data:`STREAM_BLOCK` = 16 MB, only the named columns
    converted, to float64) with a progress bar over the file's bytes (rate and time left);
    a file ending in ``.gz``, ``.bz2``, ``.xz`` or ``.lzma`` is decompressed as it is read.
    The columns are named as by :func:`sysid.cli.read_csv` (``sysid.data.table.header``):
    a file whose first line is all numbers has no header, and its columns are ``"0", "1",
    ...``. Parquet through ``ParquetFile.iter_batches`` with a bar over the rows. Only the
    requested columns are held in memory, as float64. As the in-memory reader, a CSV file
    may have a logger's row of units under its header (no number in it: skipped), and the
    column ``stamps`` (the time column) may hold date-time stamps (ISO 8601, ``Z`` or
    ``+hh:mm`` offsets), returned as seconds after the first. ``decimal=","`` reads decimal
    commas (CSV); ``hint`` says how to ask for them in a number's error.

    Every value must be a finite number, but in the columns ``missing``, where an empty cell or
    ``nan`` is read as NaN (for the caller to repair). A CSV cell that is not (text, empty,
    ``nan``, ``inf``) raises the :class:`~sysid.DataError` of :func:`sysid.cli.read_csv`, naming
    its file line (the header counted) and column: the file is read again from the block that
    held it, line by line, by the in-memory reader's rules (``sysid.data.table``). A Parquet
    value that is not finite is named by its row and column.

    Examples
    --------
    >>> import os, tempfile
    >>> from sysid.data.blocks import read_columns
    >>> path = os.path.join(tempfile.mkdtemp(), "d.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("t,u,y\\n0,1,2\\n1,3,4\\n")
    >>> read_columns(path, ["y", "u"], progress=False)
    array([[2., 1.],
           [4., 3.]])
    """
    from .._progress import Bar, show

    path = Path(path)
    try:
        import pyarrow as pa
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError("reading large files in blocks needs pyarrow: pip install pyarrow") \
            from exc
    parts: list[np.ndarray] = []
    text: str | None = None  # a column of date-time stamps, read as text
    t0: list[int] = []  # the file's first stamp (ns)
    rows = 0  # data rows read whole: the bad cell is in the block after them
    gaps = np.array([c in (missing or ()) for c in columns], dtype=bool)  # NaN allowed

    def values(batch: Any, c: str) -> np.ndarray:
        col = batch.column(batch.schema.names.index(c))
        if c != text:
            return col.to_numpy(zero_copy_only=False).astype(float)
        cells = [str(v) for v in col.to_pylist()]  # stamps: seconds after the file's first
        ns, bad = stamps_ns(cells)
        if ns is None or bad >= 0:
            at = max(bad, 0)
            raise DataError(f"{path.name} data row {rows + at + 1}, column {c!r}: "
                            f"{cells[at]!r} is not a date-time stamp like the first; fix or "
                            "remove that row")
        t0[:] = t0 or [int(ns[0])]
        return (ns - t0[0]) * 1e-9

    def take(batch: Any) -> bool:
        """Keep a block's columns as float64; whether they are all finite."""
        parts.append(np.column_stack([values(batch, c) for c in columns]) if columns
                     else np.zeros((batch.num_rows, 0)))
        ok = np.isfinite(parts[-1])
        if gaps.any():
            ok |= np.isnan(parts[-1]) & gaps
        return bool(ok.all())

    if path.suffix.lower() in (".parquet", ".pq"):
        import pyarrow.parquet as pq

        pf = pq.ParquetFile(path)
        absent = [c for c in columns if c not in pf.schema_arrow.names]
        if absent:
            raise DataError(f"{path.name}: no column(s) {absent}; the file has "
                            f"{pf.schema_arrow.names}")
        with Bar(pf.metadata.num_rows, f"reading {path.name}", unit="rows", unit_scale=True,
                 enabled=show(progress)) as bar:
            done = 0
            for batch in pf.iter_batches(batch_size=1 << 20, columns=columns):
                if not take(batch):
                    r, c = np.argwhere(~np.isfinite(parts[-1]))[0]
                    raise DataError(
                        f"{path.name} row {done + r + 1}, column {columns[c]!r}: "
                        f"{parts[-1][r, c]} is not a finite number; fix or remove that row "
                        f"({REPAIR})")
                done += batch.num_rows
                bar.update(batch.num_rows)
    else:
        import pyarrow.csv as pacsv

        head = header(path, delimiter, decimal=decimal)
        delim = head.delimiter
        # a headerless file's first line is data: its names are read_table's "0", "1", ...
        # (the trailing empty fields of a trailing delimiter named so as to be asked by none)
        names = (head.names + [f"\0{i}" for i in range(len(head.names), head.width)]
                 if head.headerless else None)
        # a logger's units row under the header (read_table's rule), and the time column
        # read as text when its first cell is a date-time stamp
        ahead = first_rows(path, head, 3)
        units = (not head.headerless
                 and len(units_row(ahead, decimal)[0].rows) < len(ahead.rows))
        first = ahead.rows[int(units)] if len(ahead.rows) > int(units) else []
        k = head.names.index(stamps) if stamps in head.names and stamps in columns else -1
        if 0 <= k < len(first) and stamps_ns([first[k]])[0] is not None:
            text = stamps
        with Bar(path.stat().st_size, f"reading {path.name}", unit="B", unit_scale=True,
                 enabled=show(progress)) as bar:
            raw = _CountingFile(path, bar)
            src = Uncommented(decompressing(path, raw), path)  # comments go, wherever
            try:
                reader = pacsv.open_csv(
                    src,
                    read_options=pacsv.ReadOptions(
                        block_size=block_size or STREAM_BLOCK, column_names=names,
                        skip_rows_after_names=int(units)),
                    parse_options=pacsv.ParseOptions(delimiter=delim,
                                                     invalid_row_handler=_skip_comment),
                    convert_options=pacsv.ConvertOptions(
                        include_columns=columns, decimal_point=decimal,
                        column_types={c: pa.string() if c == text else pa.float64()
                                      for c in columns}))
                for batch in reader:
                    if not take(batch):
                        raise _bad_cell(path, columns, delim, rows + int(units),
                                        "a value that is not a finite number", decimal, hint)
                    rows += batch.num_rows
            except (pa.ArrowInvalid, KeyError) as e:
                if src.error is not None:  # pyarrow's error for the damaged stream
                    raise src.error from None
                raise _bad_cell(path, columns, delim, rows + int(units),
                                f"{e}; check the column names and that every field is a "
                                "number", decimal, hint) from None
            finally:
                src.close()
                raw.close()
    return np.concatenate(parts) if parts else np.zeros((0, len(columns)))


def _bad_cell(path: Path, columns: list[str], delimiter: str, rows: int,
              what: str, decimal: str = ".", hint: str = "") -> DataError:
    """The error for a block of a streamed CSV file that did not convert: its bad cell by
    line and column (read again from data row ``rows`` by the in-memory reader's rules),
    else ``what`` (pyarrow's message)."""
    return (first_bad_cell(path, columns, delimiter=delimiter, start=rows, decimal=decimal,
                           hint=hint)
            or DataError(f"{path.name}: {what} (after data row {rows})"))


def _skip_comment(row: Any) -> str:
    """pyarrow's handler of a row with the wrong number of fields: a blank line (white
    space) is skipped, as ``read_table`` skips it (the ``#`` comments, whatever their
    fields, are gone before: ``sysid.data.table.Uncommented``); anything else is an error."""
    text = row.text or ""
    return "skip" if not text.strip() else "error"


