"""The engine of :func:`sysid.identify_many`: schedule records on workers, write rows.

Three ways to run, one row writer: in this process (``workers=0``), local spawned processes
(:func:`_local`), or the active ``dask.distributed`` client (:func:`_dask`). Rows are
written to Parquet in row groups of ``flush_every`` (or every few seconds), so a finished
record is on disk soon after it finishes, and the file is closed on any exit (Ctrl-C too).
"""

from __future__ import annotations

import json
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from .._atomic import atomic_path
from .._progress import Bar
from ..errors import DataError, SysidError
from .records import Columns
from .worker import SCHEMA_FIELDS, error_row, one_thread, one_thread_env, run_one

__all__ = ["run_batch", "RowWriter", "DIED", "BatchResult"]


class BatchResult:
    """What :func:`identify_many` did: the Parquet table and the counts.

    Attributes
    ----------
    path : Path
        The folder of Parquet parts (one row per record; ``pandas.read_parquet(path)``).
    n_ok, n_failed : int
    seconds : float
        Wall time of the batch.
    workers : str
        Where it ran (``"4 local processes"``, ``"dask: tcp://..."``).
    """

    def __init__(self, path: Path, n_ok: int, n_failed: int, seconds: float,
                 workers: str) -> None:
        self.path, self.n_ok, self.n_failed = path, n_ok, n_failed
        self.seconds, self.workers = seconds, workers

    def to_pandas(self) -> Any:
        """The table (read back from the Parquet parts)."""
        import pyarrow.parquet as pq

        return pq.read_table(sorted(str(p) for p in self.path.glob("part-*.parquet"))
                             ).to_pandas()

    def model(self, record_id: str) -> Any:
        """The model of one record, rebuilt from its ``parameters`` JSON."""
        import sysid

        df = self.to_pandas()
        row = df[df["record_id"] == str(record_id)]
        if row.empty or row["parameters"].isna().all():
            raise DataError(f"no model for record {record_id!r} (see its error column)")
        return sysid.model_from_dict(json.loads(row["parameters"].iloc[0]))

    def __repr__(self) -> str:
        return (f"BatchResult({self.n_ok} models, {self.n_failed} errors, "
                f"{self.seconds:.1f} s on {self.workers}; {self.path})")

    def _repr_html_(self) -> str:
        """Notebook display: the counts and the table without the model JSON."""
        from .._display import _wrap, frame_table

        return _wrap(repr(self), frame_table(self.to_pandas().drop(columns=["parameters"])))


DIED = ("WorkerDied: the process fitting this record exited (killed, out of memory, or a "
        "crash in native code)")


class RowWriter:
    """Rows to a Parquet dataset: a folder of ``part-NNNNN.parquet`` files, one per flush,
    each complete when it appears (written aside, then renamed), so a crash of any process
    loses at most the rows not yet flushed. Earlier parts in the folder are removed."""

    def __init__(self, path: Path, flush_every: int) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        self.schema = pa.schema([
            ("record_id", pa.string()), ("family", pa.string()), ("order", pa.int64()),
            ("fit", pa.float64()), ("stable", pa.bool_()), ("max_abs_pole", pa.float64()),
            ("n_parameters", pa.int64()), ("parameters", pa.string()),
            ("n_samples", pa.int64()), ("seconds", pa.float64()),
            ("cpu_seconds", pa.float64()), ("error", pa.string()), ("attempts", pa.int64())])
        if path.exists() and not path.is_dir():
            raise DataError(f"out={str(path)!r} is a file; identify_many writes a folder of "
                            "Parquet parts (read it with pandas.read_parquet(folder))")
        path.mkdir(parents=True, exist_ok=True)
        for old in path.glob("part-*.parquet"):
            old.unlink()
        self.path, self.flush_every = path, max(1, int(flush_every))
        self._pa, self._pq = pa, pq
        # a table written to memory now: what the first write imports (pyarrow's parquet
        # module, pandas) would otherwise delay the last flush after Ctrl-C by 0.3-0.4 s
        pq.write_table(self.schema.empty_table(), pa.BufferOutputStream())
        self._rows: list[dict[str, Any]] = []
        self._last = time.monotonic()
        self.n_ok = self.n_failed = self.parts = 0

    def add(self, row: dict[str, Any]) -> None:
        self._rows.append(row)
        if row["error"] is None:
            self.n_ok += 1
        else:
            self.n_failed += 1
        if len(self._rows) >= self.flush_every or time.monotonic() - self._last > 5.0:
            self.flush()

    def flush(self) -> None:
        if self._rows:
            cols = {k: [r[k] for r in self._rows] for k in SCHEMA_FIELDS}
            name = self.path / f"part-{self.parts:05d}.parquet"
            with atomic_path(name) as tmp:  # a reader never sees half a part
                self._pq.write_table(self._pa.table(cols, schema=self.schema), str(tmp))
            self.parts += 1
            self._rows = []
        self._last = time.monotonic()

    def close(self) -> None:
        self.flush()
        if self.parts == 0:  # an empty batch: still a readable table
            self._rows = []
            with atomic_path(self.path / "part-00000.parquet") as tmp:
                self._pq.write_table(self.schema.empty_table(), str(tmp))


def run_batch(work: Iterable[tuple[str, Any]], fit: Callable[[Any], Any], cols: Columns,
              out: Path, workers: int | None, retries: int, bars: bool,
              flush_every: int) -> BatchResult:
    """Run every task and write its row (see :func:`sysid.identify_many`)."""
    import multiprocessing
    import os

    if getattr(multiprocessing.current_process(), "_inheriting", False):
        # a spawned worker importing the user's script, which calls identify_many at its top
        # level: said before the row writer touches ``out`` (multiprocessing's own error, in
        # every worker, left the parent with nothing but dead workers)
        raise SysidError(START_GUARD)
    total = len(work) if hasattr(work, "__len__") else None  # type: ignore[arg-type]
    client = _client()
    if client is not None:
        where = f"dask: {client.scheduler.address}"
    elif workers == 0:
        where = "this process"
    else:
        workers = workers or os.cpu_count() or 1
        where = f"{workers} local process{'es' * (workers != 1)}"
    writer = RowWriter(out, flush_every)
    t0 = time.perf_counter()
    try:
        with Bar(total, "identifying records", unit="record", enabled=bars) as bar:
            def done(row: dict[str, Any]) -> None:
                writer.add(row)
                bar.update(1, failed=writer.n_failed)

            if client is not None:
                _dask(client, iter(work), fit, cols, done)
            elif workers == 0:
                for rid, src in work:
                    done(run_one(rid, src, fit, cols))
            else:
                with one_thread_env():
                    _local(iter(work), fit, cols, int(workers), retries, done)
    finally:
        writer.close()
    return BatchResult(out, writer.n_ok, writer.n_failed, time.perf_counter() - t0, where)


def _client() -> Any:
    """The active ``dask.distributed`` client, or None."""
    try:
        from distributed import default_client
    except ImportError:
        return None
    try:
        return default_client()
    except ValueError:  # no client
        return None


def _local(work: Iterator[tuple[str, Any]], fit: Callable[[Any], Any], cols: Columns,
           n: int, retries: int, done: Callable[[dict[str, Any]], None]) -> None:
    """Spawned processes, a window of ``2 n`` records in flight. When a worker dies, the
    records in flight are *suspects*: each is run again alone, so the one that kills its
    worker is known; after ``retries`` such deaths it gets an error row."""
    import multiprocessing

    ctx = multiprocessing.get_context("spawn")
    with deferred_interrupt() as interrupted:
        _pool_loop(work, fit, cols, n, retries, done, ctx, interrupted)


#: seconds between looks at a deferred Ctrl-C while the pool works
POLL = 0.1


@contextmanager
def deferred_interrupt() -> Iterator[list[int]]:
    """Ctrl-C (SIGINT) recorded in the list yielded instead of raised where it lands, in the
    main thread; the loop raises ``KeyboardInterrupt`` itself within :data:`POLL` seconds.
    A ``KeyboardInterrupt`` raised inside ``concurrent.futures.wait`` can leave a future's
    lock held (its locks are taken one by one, CPython's bpo-20319): the pool's manager
    thread then blocks forever on that future, and so does the interpreter's exit, which
    joins it (seen once under load: the test of Ctrl-C hung). Elsewhere (not the main
    thread) nothing changes."""
    import signal
    import threading

    got: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield got
        return
    previous = signal.signal(signal.SIGINT, lambda signum, frame: got.append(signum))
    try:
        yield got
    finally:
        signal.signal(signal.SIGINT, previous)


def _pool_loop(work: Iterator[tuple[str, Any]], fit: Callable[[Any], Any], cols: Columns,
               n: int, retries: int, done: Callable[[dict[str, Any]], None], ctx: Any,
               interrupted: list[int]) -> None:
    """:func:`_local`'s loop over pools (a new one after a worker died)."""
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    suspects: deque[tuple[str, Any]] = deque()
    deaths: dict[str, int] = {}
    exhausted = False
    first = True
    while True:
        pool = ProcessPoolExecutor(n, mp_context=ctx, initializer=one_thread)
        if first:  # workers that cannot start fail every record alike: say why, once
            first = False
            try:
                pool.submit(_started).result()
            except BrokenProcessPool:
                _stop(pool)
                raise SysidError(START_FAILED) from None
            if interrupted:
                _stop(pool)
                raise KeyboardInterrupt
        inflight: dict[Any, tuple[str, Any]] = {}
        broken = False
        try:
            while True:
                limit = 1 if suspects else 2 * n
                while len(inflight) < limit and (suspects or not exhausted):
                    if suspects:
                        rid, src = suspects.popleft()
                    else:
                        nxt = next(work, None)
                        if nxt is None:
                            exhausted = True
                            break
                        rid, src = nxt
                    fut = pool.submit(run_one, rid, src, fit, cols, deaths.get(rid, 0) + 1)
                    inflight[fut] = (rid, src)
                if not inflight:
                    return
                alone = len(inflight) == 1  # then a dead worker was running this record
                finished, _ = wait(inflight, timeout=POLL, return_when=FIRST_COMPLETED)
                for f in finished:
                    rid, src = inflight.pop(f)
                    try:
                        done(f.result())
                    except BrokenProcessPool:
                        broken = True
                        _suspect(rid, src, alone, deaths, retries, suspects, done)
                if interrupted:  # Ctrl-C, raised here: outside the futures' locks
                    raise KeyboardInterrupt
                if broken:
                    for rid, src in inflight.values():  # also lost with the pool
                        _suspect(rid, src, False, deaths, retries, suspects, done)
                    break
        finally:
            _stop(pool)
        if not broken and not inflight and exhausted and not suspects:
            return


def _started() -> bool:
    """A worker's first task: it started (imported the caller's script and sysid)."""
    return True


#: a spawned worker imports the caller's script: a top-level call starts workers of its own
START_GUARD = (
    "identify_many(workers=...) was called while a worker process was starting: the workers "
    "are spawned and import your script, so a call at its top level runs again in each of "
    "them. Put it under `if __name__ == \"__main__\":` (or pass workers=0 to fit in this "
    "process)")
START_FAILED = (
    "the worker processes of identify_many exited before fitting any record. If you call it "
    "at the top level of a script, put the call under `if __name__ == \"__main__\":` (the "
    "workers are spawned and import your script); the fit function must be importable by "
    "them (defined in a module, not in a notebook cell). Or pass workers=0 to fit in this "
    "process")


def _suspect(rid: str, src: Any, alone: bool, deaths: dict[str, int], retries: int,
             suspects: deque[tuple[str, Any]], done: Callable[[dict[str, Any]], None]) -> None:
    """A record in flight when a worker died: run it again alone; count the death when it
    was running alone (then it is the cause)."""
    if alone:
        deaths[rid] = deaths.get(rid, 0) + 1
        if deaths[rid] > retries:
            done(error_row(rid, DIED, deaths[rid]))
            return
    suspects.append((rid, src))


def _stop(pool: Any) -> None:
    """Shut the pool down now: queued work cancelled, live workers terminated (Ctrl-C)."""
    procs = list(getattr(pool, "_processes", {}) .values())
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(timeout=5)


def _dask(client: Any, work: Iterator[tuple[str, Any]], fit: Callable[[Any], Any],
          cols: Columns, done: Callable[[dict[str, Any]], None]) -> None:
    """The active client: a window of ``4 x workers`` records in flight. A task whose worker
    dies is rescheduled by the scheduler (``distributed.scheduler.allowed-failures``), then
    fails with ``KilledWorker``; as a record running beside the culprit can fail so too, each
    such record is run again alone at the end, and gets its error row only if it fails
    alone."""
    import uuid

    from distributed import as_completed

    n = max(1, len(client.scheduler_info().get("workers", {})))
    tag = uuid.uuid4().hex[:8]
    meta: dict[str, tuple[str, Any]] = {}
    futures: list[Any] = []
    suspects: list[tuple[str, Any]] = []

    def submit(rid: str, src: Any, pending: Any) -> None:
        f = client.submit(run_one, rid, src, fit, cols, 1 + (pending is None),
                          key=f"sysid-{tag}-{len(meta)}", pure=False)
        meta[f.key] = (rid, src)
        futures.append(f)
        if pending is not None:
            pending.add(f)
        return f

    def settle(f: Any, alone: bool) -> None:
        rid, src = meta[f.key]
        try:
            done(f.result())
        except Exception as e:  # noqa: BLE001 - KilledWorker and other task failures
            kind = type(e).__name__
            if kind == "KilledWorker" and not alone:
                suspects.append((rid, src))
            else:
                done(error_row(rid, DIED if kind == "KilledWorker" else f"{kind}: {e}",
                               2 if alone else 1))
        f.release()

    try:
        pending = as_completed()
        for _ in range(4 * n):
            nxt = next(work, None)
            if nxt is None:
                break
            submit(*nxt, pending)
        for f in pending:
            settle(f, alone=False)
            nxt = next(work, None)
            if nxt is not None:
                submit(*nxt, pending)
        for rid, src in suspects:
            f = submit(rid, src, None)
            f.exception()  # wait
            settle(f, alone=True)
    finally:
        client.cancel([f for f in futures if not f.done()])
