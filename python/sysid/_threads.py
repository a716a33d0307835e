"""BLAS threads while sysid works: one, unless the user says otherwise.

The heavy loops of every estimator run in the Rust core, which chooses its own threads. What
numpy and SciPy compute on sysid's behalf are small products and factorisations (state
matrices, parameter blocks, a few columns of a record), where OpenBLAS's threads cost more
than they save: its idle threads spin, which added 28 % to the CPU time of `identify` on an
idle 2-core machine and, with the cores busy with other work, made it 1.6 times as slow (wall
clock) and charged its CPU-time budget for the spinning (``benches/blas_threads.py``).

:func:`one_blas_thread` wraps the public estimators: for the duration of the outermost call,
numpy's and SciPy's BLAS pools run one thread (through ``threadpoolctl``), and the caller's
setting is restored afterwards. ``SYSID_BLAS_THREADS`` (an integer, read at each outermost
call) sets another count; ``SYSID_BLAS_THREADS=keep`` leaves the pools alone. Results do not
depend on the count: it only moves where the time goes.

The pools' size is one setting for the whole process, and OpenBLAS lets only the main thread
raise it again; so the limit is applied to calls from the main thread only. Calls from other
threads (a thread pool of the user's, a Dask worker) run with the pools as they find them:
set ``OPENBLAS_NUM_THREADS=1`` there, as Dask's workers do by default.
"""

from __future__ import annotations

import functools
import os
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, Callable, TypeVar

__all__ = ["one_blas_thread", "blas_limit"]

F = TypeVar("F", bound=Callable[..., Any])

_state: dict[str, Any] = {"depth": 0, "limiter": None, "controller": None}


def _threads() -> int | None:
    """The BLAS thread count asked for (``SYSID_BLAS_THREADS``), None to leave the pools be."""
    raw = os.environ.get("SYSID_BLAS_THREADS", "1").strip().lower()
    if raw in ("keep", ""):
        return None
    try:
        n = int(raw)
    except ValueError:
        return 1
    return n if n > 0 else None


def _controller() -> Any:
    """threadpoolctl's view of the loaded BLAS libraries (numpy's and SciPy's), made once;
    None without threadpoolctl."""
    if _state["controller"] is None:
        try:
            import scipy.linalg  # noqa: F401 - loads SciPy's own BLAS, so it is seen too
            from threadpoolctl import ThreadpoolController
        except ImportError:
            _state["controller"] = False
        else:
            _state["controller"] = ThreadpoolController()
    return _state["controller"] or None


@contextmanager
def blas_limit() -> Iterator[None]:
    """numpy's and SciPy's BLAS at one thread (or ``SYSID_BLAS_THREADS``) inside the block,
    when entered from the main thread; nested blocks share one limit, lifted when the
    outermost ends. A block entered from another thread leaves the pools as they are.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid._threads import blas_limit
    >>> with blas_limit():
    ...     float(np.ones((3, 3)) @ np.ones(3) @ np.ones(3))
    9.0
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    if _state["depth"] == 0:
        n = _threads()
        c = _controller() if n is not None else None
        _state["limiter"] = c.limit(limits=n, user_api="blas") if c is not None else None
    _state["depth"] += 1
    try:
        yield
    finally:
        _state["depth"] -= 1
        if _state["depth"] == 0 and _state["limiter"] is not None:
            _state["limiter"].restore_original_limits()
            _state["limiter"] = None


def one_blas_thread(fn: F) -> F:
    """Decorator: ``fn`` runs inside :func:`blas_limit`.

    Examples
    --------
    >>> from sysid._threads import one_blas_thread
    >>> @one_blas_thread
    ... def double(x):
    ...     return 2 * x
    >>> double(21)
    42
    """
    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with blas_limit():
            return fn(*args, **kwargs)
    return wrapper  # type: ignore[return-value]
