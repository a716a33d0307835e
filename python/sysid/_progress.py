"""One progress machinery for long work: compression of streams, reading large files, order
sweeps and iterative estimators.

``progress=None`` (the default everywhere) shows a bar only when stderr is a terminal;
``True`` asks for it anyway (in a log: the bar is drawn once at the start and once at the
end, one line), ``False`` silences it. Bars are tqdm's (rate and time left); without tqdm a
plain counter line is written instead.
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, Callable

__all__ = ["Bar", "show", "iteration_callback", "iteration_printer", "stop_requested",
           "stopped_by"]

#: per thread: the event that stops the iterative estimators running in it (see stopped_by)
_local = threading.local()


def stop_requested() -> bool:
    """Whether this thread's work is to stop (:func:`stopped_by`'s event is set): asked by
    the Rust core's long computations every few milliseconds, as the main thread asks for
    Ctrl-C.

    Examples
    --------
    >>> from sysid._progress import stop_requested
    >>> stop_requested()
    False
    """
    stop = getattr(_local, "stop", None)
    return stop is not None and stop.is_set()


@contextmanager
def stopped_by(event: threading.Event) -> Iterator[None]:
    """Inside the block, every iterative estimator started in this thread stops at its next
    iteration once ``event`` is set (as when its progress callable returns False): how a
    worker thread's fits are stopped on Ctrl-C, which only the main thread receives.

    Examples
    --------
    >>> import threading
    >>> from sysid._progress import iteration_callback, stopped_by
    >>> stop = threading.Event()
    >>> with stopped_by(stop):
    ...     cb, close = iteration_callback(False, "fit", 10)
    >>> cb(1, 2.0) is not False
    True
    >>> stop.set()
    >>> cb(2, 1.0)
    False
    """
    saved = getattr(_local, "stop", None)
    _local.stop = event
    try:
        yield
    finally:
        _local.stop = saved


def show(progress: bool | None) -> bool:
    """Whether to draw: ``progress`` if given, else whether stderr is a terminal."""
    if progress is None:
        return bool(getattr(sys.stderr, "isatty", lambda: False)())
    return bool(progress)


class Bar:
    """A progress bar on stderr (tqdm if installed), silent when ``enabled`` is false.

    Examples
    --------
    >>> from sysid._progress import Bar
    >>> with Bar(3, "work", enabled=False) as bar:
    ...     for _ in range(3):
    ...         bar.update(1)
    >>> bar.done
    3
    """

    def __init__(self, total: int | None, desc: str, *, unit: str = "it",
                 enabled: bool = True, unit_scale: bool = False) -> None:
        self.total, self.desc, self.unit, self.enabled, self.done = total, desc, unit, enabled, 0
        self._bar: Any = None
        if enabled:
            try:
                from tqdm.auto import tqdm
            except ImportError:
                return
            live = bool(getattr(sys.stderr, "isatty", lambda: False)())
            # a word ("candidates") needs its space: tqdm writes "117candidates" otherwise
            word = " " + unit if len(unit) > 2 and not unit.startswith(" ") else unit
            self._bar = tqdm(total=total, desc=desc, unit=word, unit_scale=unit_scale,
                             file=sys.stderr, dynamic_ncols=live,
                             mininterval=0.1 if live else 1e9, maxinterval=0 if not live else 10)

    def update(self, n: int = 1, **postfix: Any) -> None:
        """Advance by ``n`` (and show ``postfix`` values, e.g. the cost)."""
        self.done += n
        if not self.enabled:
            return
        if self._bar is not None:
            if postfix:
                self._bar.set_postfix(postfix, refresh=False)
            self._bar.update(n)
        else:
            tot = f"/{self.total:,}" if self.total else ""
            sys.stderr.write(f"\r{self.desc}: {self.done:,}{tot} {self.unit}")
            sys.stderr.flush()

    def close(self) -> None:
        if not self.enabled:
            return
        if self._bar is not None:
            self._bar.close()
        else:
            sys.stderr.write("\n")
        self.enabled = False

    def __enter__(self) -> Bar:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def iteration_printer(desc: str, criterion: str) -> Callable[..., None]:
    """One line per iteration on stdout (the ``log_line`` of :func:`iteration_callback`).

    Examples
    --------
    >>> from sysid._progress import iteration_printer
    >>> iteration_printer("oe", "sum of squares")(1, 2.5, 0.1, 1e-3, 1e-4)
    oe iteration   1: cost 2.5 (sum of squares)  step 0.1  gradient 0.001  damping 0.0001
    """
    def line(it: int, cost: float, step: float, grad: float, damping: float) -> None:
        print(f"{desc} iteration {it:3d}: cost {cost:.6g} ({criterion})  step {step:.3g}  "
              f"gradient {grad:.3g}  damping {damping:.2g}", file=sys.stdout)
    return line


def iteration_callback(
    progress: bool | None | Callable[..., Any],
    desc: str,
    max_iter: int,
    log_line: Callable[..., None] | None = None,
    *,
    unit: str = "it",
    postfix: Callable[..., dict[str, str]] | None = None,
) -> tuple[Callable[..., Any] | None, Callable[[], None]]:
    """The per-iteration callback of an iterative estimator and a function closing it.

    ``progress`` may be a callable (used as is: ``callable(iteration, cost, step_norm,
    gradient_norm, damping)`` after every accepted step of the shared optimiser, a ``False``
    return stops the estimator, an exception stops it and is re-raised), ``None`` (a bar on a
    terminal, else nothing), ``True`` (a bar on a terminal; in a log, ``log_line`` per
    iteration when given) or ``False``. The bar counts ``unit`` against ``max_iter`` and
    shows ``postfix(*callback_arguments)`` (default: the current cost, the second argument).

    Examples
    --------
    >>> from sysid._progress import iteration_callback
    >>> cb, close = iteration_callback(False, "fit", 10)
    >>> cb is None
    True
    >>> mine = lambda *a: None
    >>> iteration_callback(mine, "fit", 10)[0] is mine
    True
    """
    cb, close = _callback(progress, desc, max_iter, log_line, unit, postfix)
    stop = getattr(_local, "stop", None)
    if stop is None:
        return cb, close

    def stoppable(*args: Any) -> Any:
        if stop.is_set():
            return False
        return None if cb is None else cb(*args)
    return stoppable, close


def _callback(progress: Any, desc: str, max_iter: int, log_line: Callable[..., None] | None,
              unit: str, postfix: Callable[..., dict[str, str]] | None
              ) -> tuple[Callable[..., Any] | None, Callable[[], None]]:
    if callable(progress):
        return progress, lambda: None
    if progress is not None and not isinstance(progress, bool):
        from .errors import DataError

        raise DataError(f"progress must be True, False, None or a callable, got {progress!r}")
    if not show(progress):
        return None, lambda: None
    terminal = bool(getattr(sys.stderr, "isatty", lambda: False)())
    if not terminal and log_line is not None:
        return log_line, lambda: None
    bar = Bar(max_iter, desc, unit=unit)
    shown = postfix if postfix is not None else _cost

    def cb(*args: Any) -> None:
        bar.update(1, **shown(*args))

    return cb, bar.close


def _cost(it: int, cost: float, *rest: Any) -> dict[str, str]:
    return {"cost": f"{cost:.6g}"}
