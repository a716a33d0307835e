"""Where the records of :func:`sysid.identify_many` come from, as picklable tasks.

A task is ``(record id, source)``; the source is an :class:`~sysid.IOData`, a file path
(CSV or Parquet, read by the worker), or a pandas frame of one record (from a Dask
dataframe partitioned by record id). :func:`load` turns a source into an ``IOData`` on the
worker, so a corrupt file fails there, as an error row, not in the caller.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import DataError

__all__ = ["Columns", "tasks", "load", "SUFFIXES"]

SUFFIXES = (".csv", ".parquet", ".pq", ".txt")


@dataclass(frozen=True)
class Columns:
    """How a table becomes a record: input and output columns, sample time or time column."""

    inputs: tuple[str, ...] | None = None
    outputs: tuple[str, ...] | None = None
    dt: float | None = None
    time: str | None = None

    def record(self, names: list[str], values: np.ndarray, what: str) -> IOData:
        if self.outputs is None:
            raise DataError(f"{what}: give outputs=[column names] (and inputs=[...]) to read "
                            "records from tables")
        missing = [c for c in (self.inputs or ()) + self.outputs + (
            (self.time,) if self.time else ()) if c not in names]
        if missing:
            raise DataError(f"{what}: no column(s) {missing}; it has {names}")
        col = {c: values[:, names.index(c)] for c in names}
        u = np.column_stack([col[c] for c in self.inputs]) if self.inputs else None
        y = np.column_stack([col[c] for c in self.outputs])
        t = col[self.time] if self.time else None
        return IOData(u=u, y=y, dt=self.dt if t is None else None, time=t,
                      input_names=list(self.inputs or ()), output_names=list(self.outputs))


def _frame_record(frame: Any, cols: Columns, what: str) -> IOData:
    names = [str(c) for c in frame.columns]
    use = [c for c in names if c in set((cols.inputs or ()) + (cols.outputs or ()) + (
        (cols.time,) if cols.time else ()))]
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
            import pyarrow.parquet as pq

            try:
                frame = pq.read_table(path).to_pandas()
            except Exception as e:  # noqa: BLE001 - any reader failure is a bad record
                raise DataError(f"{path.name}: not a readable Parquet file ({e})") from None
            return _frame_record(frame, cols, path.name)
        from ..cli import read_csv

        names, values = read_csv(path)
        return cols.record(names, values, path.name)
    if hasattr(source, "columns"):  # one record of a dataframe
        return _frame_record(source, cols, f"record {rid}")
    if isinstance(source, tuple) and len(source) == 2:
        return IOData(*source, dt=cols.dt)
    raise DataError(f"record {rid}: cannot make a record of a {type(source).__name__}; give "
                    "IOData, (u, y), a CSV/Parquet path or a dataframe")


def tasks(records: Any, record_id: str) -> Iterator[tuple[str, Any]]:
    """``(record id, source)`` for each record of a list, a mapping, a folder or a Dask
    collection (bag items: IOData, ``(id, IOData)`` or paths; dataframe: grouped by the
    ``record_id`` column, one group per record, partitions computed one at a time)."""
    if isinstance(records, (str, Path)):
        root = Path(records)
        if not root.is_dir():
            raise DataError(f"{str(root)!r} is not a folder of record files")
        files = sorted(p for p in root.iterdir() if p.suffix.lower() in SUFFIXES)
        if not files:
            raise DataError(f"no CSV or Parquet files in {str(root)!r}")
        for p in files:
            yield p.stem, str(p)
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
