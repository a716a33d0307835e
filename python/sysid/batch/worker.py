"""The work on one record, run by a worker of :func:`sysid.identify_many`: read, fit,
describe the model in one row; any exception becomes an error row."""

from __future__ import annotations

import json
import os
import time
import traceback
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from .records import Columns, load

__all__ = ["SCHEMA_FIELDS", "default_fit", "run_one", "error_row", "one_thread",
           "one_thread_env"]

SCHEMA_FIELDS = ("record_id", "family", "order", "fit", "stable", "max_abs_pole",
                 "n_parameters", "parameters", "n_samples", "seconds", "cpu_seconds", "error",
                 "attempts")


def default_fit(data: Any) -> Any:
    """The fit used when none is given: ``sysid.identify`` when the package has it, else the
    subspace estimate's automatic order refined by :func:`sysid.ssest`."""
    import sysid

    ident = getattr(sysid, "identify", None)
    if callable(ident):
        out = ident(data)
        return out if isinstance(out, sysid.Model) else out.model
    order = sysid.SubspaceEstimator(data).auto_order
    return sysid.ssest(data, order)


def _row(rid: str, model: Any, data: Any, seconds: float, cpu: float,
         attempts: int) -> dict[str, Any]:
    import sysid
    from sysid.validation.compare import compare_quiet

    fit = float(np.mean(compare_quiet(model, data).fit))  # the table shows -inf
    try:
        p = np.asarray(model.poles(), dtype=complex)
        rho = float(np.max(np.abs(p))) if p.size else 0.0
        stable: bool | None = bool(rho < 1) if model.dt else bool(np.all(p.real < 0))
    except Exception:  # noqa: BLE001 - a family without poles
        rho, stable = float("nan"), None
    try:
        params = json.dumps(sysid.model_to_dict(model))
    except Exception as e:  # noqa: BLE001 - a family that cannot be saved
        params = json.dumps({"unsaved": f"{type(e).__name__}: {e}"})
    order = getattr(model, "nstates", None)
    return {"record_id": rid, "family": (model.info or {}).get("method",
                                                             type(model).__name__),
            "order": None if order is None else int(order), "fit": fit, "stable": stable,
            "max_abs_pole": rho, "n_parameters": int(model.n_parameters),
            "parameters": params, "n_samples": int(data.n_samples), "seconds": seconds,
            "cpu_seconds": cpu, "error": None, "attempts": attempts}


def error_row(rid: str, error: str, attempts: int, seconds: float = float("nan"),
              n_samples: int | None = None) -> dict[str, Any]:
    return {"record_id": rid, "family": None, "order": None, "fit": None, "stable": None,
            "max_abs_pole": None, "n_parameters": None, "parameters": None,
            "n_samples": n_samples, "seconds": seconds, "cpu_seconds": None, "error": error,
            "attempts": attempts}


def run_one(rid: str, source: Any, fit: Callable[[Any], Any], cols: Columns,
            attempts: int = 1) -> dict[str, Any]:
    """One record, on a worker: read, fit, describe; any exception becomes an error row."""
    t0, c0 = time.perf_counter(), time.process_time()
    n = None
    try:
        data = load(source, cols, rid)
        n = data.n_samples
        model = fit(data)
        return _row(rid, model, data, time.perf_counter() - t0, time.process_time() - c0,
                    attempts)
    except Exception as e:  # noqa: BLE001 - a bad record must not stop the batch
        where = traceback.extract_tb(e.__traceback__)[-1]
        return error_row(rid, f"{type(e).__name__}: {e} ({Path(where.filename).name}:"
                              f"{where.lineno})", attempts, time.perf_counter() - t0, n)


#: the thread pools a worker's libraries start: OpenBLAS/MKL/Accelerate (numpy, SciPy),
#: OpenMP, and the Rust core's rayon pool. Each reads its variable once, when it loads.
THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS",
                    "VECLIB_MAXIMUM_THREADS", "RAYON_NUM_THREADS")


@contextmanager
def one_thread_env() -> Iterator[None]:
    """The environment the worker processes are spawned with: one thread in every pool.

    The pools read their variable when the library loads, which in a spawned worker happens
    before any initialiser runs (importing the fit imports numpy), so the variables must be
    in the environment the process starts with. Without them each worker's BLAS calls use
    every core, and two workers on two cores fight over them. The caller's own environment
    is restored on exit (its already-loaded libraries are not affected either way).
    """
    saved = {k: os.environ.get(k) for k in THREAD_VARIABLES}
    os.environ.update({k: "1" for k in THREAD_VARIABLES})
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def one_thread() -> None:
    """Worker initialiser: one compute thread per process (the processes are the
    parallelism; results do not depend on the thread count), and Ctrl-C left to the caller,
    which stops the workers itself."""
    import signal

    os.environ["RAYON_NUM_THREADS"] = "1"
    signal.signal(signal.SIGINT, signal.SIG_IGN)
