"""A model per record, in parallel, streamed to Parquet: :func:`identify_many`.

The caller's process schedules and writes; workers read (files are read where the fit runs)
and fit. Local processes by default (spawned, one compute thread each); the active
``dask.distributed`` client when there is one. Every record ends as one row: its model's
family, order, fit, stability and parameters (the model as JSON, reloadable with
:func:`sysid.model_from_dict`), or the error that stopped it. A worker that dies takes only
the records it was running: they are run again, alone, and the record that killed its worker
gets an error row after ``retries`` deaths; rows already written stay in the file. Ctrl-C
stops the workers and closes the file.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .._checks import as_dt, as_int
from .._progress import show
from ..data.iodata import IOData
from ..errors import DataError
from .records import Columns, tasks
from .stream import BatchResult, run_batch
from .worker import default_fit

__all__ = ["identify_many"]


def identify_many(records: Any, *, fit: Callable[[Any], Any] | None = None,
                  out: str | Path = "identify_many.parquet", workers: int | None = None,
                  inputs: list[str] | None = None, outputs: list[str] | None = None,
                  dt: float | None = None, time_column: str | None = None,
                  resample: float | str | None = None, resample_gap: float = 5.0,
                  record_id: str = "record_id", retries: int = 1,
                  progress: bool | None = None, flush_every: int = 32) -> BatchResult:
    """Fit a model per record, in parallel, and stream one row per record to Parquet.

    Parameters
    ----------
    records : list, iterator, dict, folder, Dask bag or Dask dataframe
        A list (or a lazy iterator: records made as workers take them) of
        :class:`~sysid.IOData` (ids ``"0", "1", ...``) or of ``(id, IOData)``; a
        dict ``{id: IOData}``; a folder of CSV/Parquet files (one record per file, id = file
        name without suffix; text tables compressed as ``.gz``, ``.bz2``, ``.xz`` too, id
        ``r`` for ``r.csv.gz``; columns by ``inputs``/``outputs``); a Dask bag of such items; a
        Dask dataframe partitioned by record id (column ``record_id``; a record must not span
        partitions).
    fit : callable, optional
        ``fit(IOData) -> model``; default :func:`default_fit` (``sysid.identify`` when
        available, else ``ssest`` at the subspace automatic order). Must be picklable (a
        module-level function) to run in other processes.
    out : str or Path
        The folder of the Parquet table (a dataset of ``part-NNNNN.parquet`` files, one per
        ``flush_every`` rows, each complete when it appears; earlier parts are replaced;
        read it with ``pandas.read_parquet(out)``). Columns: ``record_id, family, order, fit``
        (simulation fit % on the record), ``stable, max_abs_pole, n_parameters,
        parameters`` (the model as JSON), ``n_samples, seconds, cpu_seconds`` (wall and CPU
        time of read + fit + describe in the worker),
        ``error`` (null when fitted: a file that cannot be read, such as a damaged or
        truncated compressed one, is an error row naming the file and the damage, as a
        failed fit is), ``attempts``.
    workers : int, optional
        Local processes (default: the machine's cores); ignored with a Dask client.
    inputs, outputs, dt, time_column : optional
        How tables become records (file and dataframe sources). Without ``dt`` or
        ``time_column``, a column named as a time column (``time``, ``t``, ``Time [s]``,
        ``timestamp``, ...; not an input or output) gives the sample time, as
        :meth:`IOData.from_csv` takes it; without one, dt = 1 s.
    resample, resample_gap : optional
        Time stamps with jitter or gaps: interpolated onto a uniform grid, as
        :meth:`IOData.from_csv`'s (file and dataframe sources).
    record_id : str
        The record id column of a dataframe.
    retries : int
        Times a record whose worker died is tried again before its error row.
    progress : bool, optional
        A bar over the whole batch (default: on a terminal).
    flush_every : int
        Rows per part file (or every 5 s): what a crash of the calling process can lose.

    Returns
    -------
    BatchResult
        The file, the counts, ``.to_pandas()``, ``.model(record_id)``.

    Examples
    --------
    >>> import os, tempfile, numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]])
    >>> u = np.random.default_rng(0).standard_normal((2, 400, 1))
    >>> recs = {f"r{i}": sysid.IOData(u=u[i], y=m.simulate(u[i])) for i in range(2)}
    >>> def first_order(d):
    ...     return sysid.n4sid(d, 1)
    >>> res = sysid.identify_many(recs, fit=first_order, workers=0,
    ...                           out=os.path.join(tempfile.mkdtemp(), "t.parquet"))
    >>> res.n_ok, res.to_pandas()["order"].tolist()
    (2, [1, 1])
    """
    dt = None if dt is None else as_dt(dt)
    retries = as_int(retries, "retries", 0)
    flush_every = as_int(flush_every, "flush_every")
    if workers is not None:
        workers = as_int(workers, "workers", 0, alt="None (the machine's cores)")
    if progress is not None and not isinstance(progress, (bool, np.bool_)):
        raise DataError(f"progress must be True, False or None (on a terminal), got "
                        f"{progress!r}")
    if not isinstance(record_id, str):
        raise DataError(f"record_id must be the name of the record id column (a string), "
                        f"got {record_id!r}")
    _refuse_table_options(records, inputs=inputs, outputs=outputs, dt=dt,
                          time_column=time_column, resample=resample)
    if resample is not None:
        from ..data.formats import _resample_args

        _resample_args(dt, True, "", "")  # a sample time of its own and dt=: refused
    cols = Columns(tuple(inputs) if inputs else None, tuple(outputs) if outputs else None,
                   dt, time_column, resample, resample_gap)
    work = tasks(records, record_id)
    if hasattr(records, "__len__") or isinstance(records, (str, Path)):  # a known total
        work = list(work)  # type: ignore[assignment]
    return run_batch(work, fit or default_fit, cols, Path(out), workers, retries,
                     show(progress), flush_every)


def _refuse_table_options(records: Any, **given: Any) -> None:
    """Refuse the table options (how a table becomes a record) for records that are IOData
    already: they would be ignored."""
    items = records.values() if isinstance(records, Mapping) else \
        records if isinstance(records, (list, tuple)) else ()
    if not any(isinstance(x, IOData) or (isinstance(x, tuple) and len(x) == 2
                                         and isinstance(x[1], IOData)) for x in items):
        return
    named = [k for k, v in given.items() if v is not None]
    if named:
        raise DataError(f"{', '.join(named)} say how a table becomes a record, but these "
                        "records are IOData already and would ignore them: select channels "
                        "(data.select) or resample before, or leave them out")
