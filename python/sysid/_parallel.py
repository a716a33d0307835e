"""Independent fits on the cores at hand, their results in order: the held-out blocks of the
automatic structures (:func:`sysid.validation.crossval.held_out_folds`) and of
:func:`sysid.identify`'s refinements.

The Rust core releases the GIL while it computes, so fits of different parts of a record run
in parallel on threads; each is independent of the others, so the results are the same as
one after another. Ctrl-C reaches only the main thread: :func:`ordered` then sets the stop
event of the fits still running (:func:`sysid._progress.stopped_by`, read by their iteration
callbacks and by the Rust core's signal polls), waits for them and raises.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterator, Sequence
from contextvars import copy_context
from typing import Any

from ._progress import stopped_by

__all__ = ["fold_workers", "ordered"]


def fold_workers(tasks: int) -> int:
    """Threads for ``tasks`` independent fits: the cores this process may use
    (``RAYON_NUM_THREADS`` when set, as the Rust core reads it: one compute thread in
    :func:`sysid.identify_many`'s workers), at most ``tasks``; one when called from a
    thread other than the main one (a fit's own folds run in its thread).

    Examples
    --------
    >>> from sysid._parallel import fold_workers
    >>> 1 <= fold_workers(5) <= 5, fold_workers(1)
    (True, 1)
    """
    if threading.current_thread() is not threading.main_thread():
        return 1
    try:
        n = int(os.environ.get("RAYON_NUM_THREADS", "0"))
    except ValueError:
        n = 0
    if n <= 0:
        n = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (
            os.cpu_count() or 1)
    return max(1, min(n, tasks))


def ordered(tasks: Sequence[Callable[[], Any]], workers: int | None = None) -> Iterator[Any]:
    """The results of ``tasks``, in order, computed on ``workers`` threads
    (:func:`fold_workers` by default) at most ``workers`` ahead of the one consumed. A task's
    exception is raised when its result is reached. Closing the iterator early (``break``,
    an exception, Ctrl-C) stops the tasks still running at their next iteration and waits
    for them; those not started are not run. With one worker the tasks run in the
    consumer's thread, one at a time, when reached.

    Examples
    --------
    >>> from sysid._parallel import ordered
    >>> list(ordered([lambda i=i: i * i for i in range(5)], workers=2))
    [0, 1, 4, 9, 16]
    """
    n = fold_workers(len(tasks)) if workers is None else max(1, min(workers, len(tasks)))
    if n <= 1:
        for task in tasks:
            yield task()
        return
    from concurrent.futures import ThreadPoolExecutor

    stop = threading.Event()

    def run(task: Callable[[], Any]) -> Any:
        if stop.is_set():
            return None
        with stopped_by(stop):
            return task()

    pool = ThreadPoolExecutor(n, thread_name_prefix="sysid-fit")
    try:
        # each task in a copy of the caller's context (a ContextVar such as
        # sysid.validation.output_error.feedback_checked holds in the threads too)
        ctx = copy_context()
        futures = [pool.submit(ctx.copy().run, run, t) for t in tasks[:n]]
        for i in range(len(tasks)):
            if i + n < len(tasks):
                futures.append(pool.submit(ctx.copy().run, run, tasks[i + n]))
            yield futures[i].result()
    finally:
        stop.set()  # early close or an error: the rest stop (no-op once all are done)
        pool.shutdown(wait=True, cancel_futures=True)
