"""Where the records of :func:`sysid.identify_many` come from, as picklable tasks.

A task is ``(record id, source)``; the source is an :class:`~sysid.IOData`, a file path
(CSV or Parquet, read by the worker), or a pandas frame of one record (from a Dask
dataframe partitioned by record id). :func:`load` turns a source into an ``IOData`` on the
worker, so a corrupt file fails there, as an error row, not in the caller.

A fit takes its record whole, in memory (``fit(IOData)``, and the row's fit % simulates
the model over it), so a file is read whole too; but only the columns named by ``inputs``,
``outputs`` and the time column are read, after their size is checked against
:data:`MAX_RECORD_BYTES` and the memory available (:func:`check_record_size`): a Parquet
file's rows from its metadata, a text table's bounded by its lines, counted first.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from .._checks import MAX_BYTES
from ..data.iodata import IOData
from ..errors import DataError

__all__ = ["Columns", "tasks", "load", "SUFFIXES", "MAX_RECORD_BYTES", "check_record_size"]

SUFFIXES = (".csv", ".parquet", ".pq", ".txt")

#: Compressions a text record of a folder may have (``r.csv.gz``), as the readers take them.
COMPRESSED = (".gz", ".bz2", ".xz", ".lzma")


def _record_file(p: Path) -> str | None:
    """The record id of a folder's file (its name without the table and compression
    suffixes), or ``None`` for a file that is no record."""
    name = p.name
    if p.suffix.lower() in COMPRESSED:  # a compressed text table: r.csv.gz
        name = p.stem
        if Path(name).suffix.lower() not in (".csv", ".txt"):
            return None
    elif p.suffix.lower() not in SUFFIXES:
        return None
    return Path(name).stem

#: Largest record a worker reads from a file, in bytes of its float64 values (the package's
#: 4 GiB per matrix); a smaller bound is taken from the memory available when it is known.
MAX_RECORD_BYTES = MAX_BYTES
#: The share of the available memory one record's values may take: the fit holds copies of
#: it (the record, its parts, simulations), and other workers hold theirs.
MEMORY_SHARE = 0.25


@dataclass(frozen=True)
class Columns:
    """How a table becomes a record: input and output columns, sample time or time column."""

    inputs: tuple[str, ...] | None = None
    outputs: tuple[str, ...] | None = None
    dt: float | None = None
    time: str | None = None
    #: jittered stamps onto a uniform grid (``IOData.from_csv``'s ``resample=``)
    resample: float | str | None = None
    resample_gap: float = 5.0

    def wanted(self) -> tuple[str, ...]:
        """The columns a record is made of: inputs, outputs and the time column."""
        return (self.inputs or ()) + (self.outputs or ()) + ((self.time,) if self.time else ())

    def timed(self, names: list[str]) -> Columns:
        """These columns with the table's time column (``time``, ``t``, ``Time [s]``, ...,
        not an input or output) when neither ``dt`` nor ``time`` was given, as
        :meth:`sysid.IOData.from_csv` and the command line take it."""
        if self.dt is not None or self.time is not None:
            return self
        from ..data.units import time_column

        used = [names.index(c) for c in (self.inputs or ()) + (self.outputs or ())
                if c in names]
        k = time_column(names, used)
        return self if k is None else replace(self, time=names[k])

    def check(self, names: list[str], what: str) -> None:
        """Refuse a table without outputs named, or without a named column."""
        if self.outputs is None:
            raise DataError(f"{what}: give outputs=[column names] (and inputs=[...]) to read "
                            "records from tables")
        missing = [c for c in self.wanted() if c not in names]
        if missing:
            raise DataError(f"{what}: no column(s) {missing}; it has {names}")

    def record(self, names: list[str], values: np.ndarray, what: str) -> IOData:
        self.check(names, what)
        col = {c: values[:, names.index(c)] for c in names}
        u = np.column_stack([col[c] for c in self.inputs]) if self.inputs else None
        y = np.column_stack([col[c] for c in self.outputs])
        t = col[self.time] if self.time else None
        names = {"input_names": list(self.inputs or ()), "output_names": list(self.outputs)}
        if self.resample is None:
            return IOData(u=u, y=y, dt=self.dt if t is None else None, time=t, **names)
        if t is None:
            raise DataError(f"{what}: no time column to resample (name it: time_column=...)")
        from ..data.raw import resample_stamps

        return resample_stamps(IOData, [(t, u, y)], self.resample, self.resample_gap, names)


def _frame_record(frame: Any, cols: Columns, what: str) -> IOData:
    names = [str(c) for c in frame.columns]
    cols = cols.timed(names)
    use = [c for c in names if c in set(cols.wanted())]
    try:
        values = frame[use].to_numpy(dtype=float)
    except (TypeError, ValueError) as e:
        raise DataError(f"{what}: a column is not numeric ({e})") from None
    return cols.record(use, values, what)


def load(source: Any, cols: Columns, rid: str) -> IOData:
    """The record of a task source (on the worker)."""
    if isinstance(source, IOData):
        return source
    if isinstance(source, (str, Path)):
        path = Path(source)
        if path.suffix.lower() in (".parquet", ".pq"):
            return _parquet_record(path, cols)
        return _text_record(path, cols)
    if hasattr(source, "columns"):  # one record of a dataframe
        return _frame_record(source, cols, f"record {rid}")
    if isinstance(source, tuple) and len(source) == 2:
        return IOData(*source, dt=cols.dt)
    raise DataError(f"record {rid}: cannot make a record of a {type(source).__name__}; give "
                    "IOData, (u, y), a CSV/Parquet path or a dataframe")


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation (Linux ``MemAvailable``, else the free
    physical pages); ``None`` where neither is known."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        return None


def check_record_size(what: str, rows: int, columns: int, *, at_most: bool = False) -> None:
    """Refuse a record of ``rows`` by ``columns`` float64 values larger than
    :data:`MAX_RECORD_BYTES` or :data:`MEMORY_SHARE` of the available memory, before it is
    read: the error names the record, its size and the fix. ``at_most``: ``rows`` is a bound
    (a text file's lines), and the error says so.

    Examples
    --------
    >>> from sysid.batch.records import check_record_size
    >>> check_record_size("small.parquet", 1000, 3)
    >>> check_record_size("huge.parquet", 10**12, 3)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: huge.parquet: 1000000000000 rows x 3 columns need 22351.7 GiB ...
    """
    need = rows * columns * 8
    avail = available_memory()
    limit, why = MAX_RECORD_BYTES, f"the {MAX_RECORD_BYTES / 2**30:.3g} GiB limit per record"
    if avail is not None and MEMORY_SHARE * avail < limit:
        limit = int(MEMORY_SHARE * avail)
        why = (f"{MEMORY_SHARE:.0%} of the {avail / 2**30:.3g} GiB of memory available (the "
               "fit holds copies of the record)")
    if need > limit:
        raise DataError(
            f"{what}: {'at most ' if at_most else ''}{rows} rows x {columns} columns need "
            f"{need / 2**30:.1f} GiB as float64, more than {why}; identify_many fits each "
            "record in memory: cut the record into shorter ones, or compress it in blocks "
            "with sysid.compress_stream(path, past, input_columns=..., output_columns=...) "
            "and fit SubspaceEstimator.from_factor")


def _text_record(path: Path, cols: Columns) -> IOData:
    """A text table's record (CSV, semicolon, tab or white-space separated, compressed or
    not; the rules of :func:`sysid.cli.read_csv`): only the columns it is made of, read line
    by line into an array of as many rows as the file has lines, after that size is checked
    (the lines are counted first, in blocks; no row is held before)."""
    from ..data.table import count_lines, header, read_named, text_bytes

    if not path.is_file():
        raise DataError(f"no data file at {str(path)!r}")
    text_bytes(path, 0)  # refuses a file that is not text, as read_csv does
    head = header(path)
    cols = cols.timed(head.names)
    cols.check(head.names, path.name)
    use = list(dict.fromkeys(cols.wanted()))
    rows = max(count_lines(path) - (head.line - head.headerless), 0)
    check_record_size(path.name, rows, len(use), at_most=True)
    return cols.record(use, read_named(path, use, rows, delimiter=head.delimiter), path.name)


def _parquet_record(path: Path, cols: Columns) -> IOData:
    """A Parquet file's record: only the columns it is made of, read after their size is
    checked (its metadata holds the row count)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        pf = pq.ParquetFile(path)
        names, rows = list(pf.schema_arrow.names), int(pf.metadata.num_rows)
    except Exception as e:  # noqa: BLE001 - any reader failure is a bad record
        raise DataError(f"{path.name}: not a readable Parquet file ({e})") from None
    cols = cols.timed(names)
    cols.check(names, path.name)
    use = list(dict.fromkeys(cols.wanted()))
    check_record_size(path.name, rows, len(use))
    try:
        table = pf.read(columns=use)
    except Exception as e:  # noqa: BLE001 - any reader failure is a bad record
        raise DataError(f"{path.name}: not a readable Parquet file ({e})") from None
    try:
        values = np.column_stack([
            table.column(c).to_numpy(zero_copy_only=False).astype(np.float64, copy=False)
            for c in use]) if use else np.zeros((rows, 0))
    except (TypeError, ValueError, pa.ArrowException) as e:
        raise DataError(f"{path.name}: a column is not numeric ({e})") from None
    return cols.record(use, values, path.name)


def tasks(records: Any, record_id: str) -> Iterator[tuple[str, Any]]:
    """``(record id, source)`` for each record of a list, a mapping, a folder or a Dask
    collection (bag items: IOData, ``(id, IOData)`` or paths; dataframe: grouped by the
    ``record_id`` column, one group per record, partitions computed one at a time)."""
    if isinstance(records, (str, Path)):
        root = Path(records)
        if not root.is_dir():
            raise DataError(f"{str(root)!r} is not a folder of record files")
        files: dict[str, Path] = {}
        for p in sorted(root.iterdir()):
            rid = _record_file(p)
            if rid is None or not p.is_file():
                continue
            if rid in files:
                raise DataError(f"{files[rid].name} and {p.name} in {str(root)!r} are both "
                                f"record {rid!r}: keep one of them (or rename one)")
            files[rid] = p
        if not files:
            raise DataError(f"no CSV or Parquet files in {str(root)!r}")
        for rid, p in files.items():
            yield rid, str(p)
        return
    if isinstance(records, Mapping):
        for k, v in records.items():
            yield str(k), v
        return
    kind = type(records).__module__.split(".")[0]
    if kind == "dask" and hasattr(records, "columns"):  # a Dask dataframe
        if record_id not in records.columns:
            raise DataError(f"the dataframe has no column {record_id!r}; name the record id "
                            f"column with record_id= (columns: {list(records.columns)})")
        for part in records.to_delayed():
            frame = part.compute()
            for rid, group in frame.groupby(frame[record_id].to_numpy(), sort=False):
                yield str(rid), group.drop(columns=[record_id])
        return
    if kind == "dask":  # a Dask bag
        count = 0
        for part in records.to_delayed():
            for item in part.compute():
                yield _item(item, count)
                count += 1
        return
    for i, item in enumerate(records):
        yield _item(item, i)


def _item(item: Any, i: int) -> tuple[str, Any]:
    if isinstance(item, tuple) and len(item) == 2 and isinstance(item[0], (str, int)):
        return str(item[0]), item[1]
    return str(i), item
