"""numpy's and SciPy's BLAS run one thread while a sysid estimator works (their spinning idle
threads doubled `identify`'s CPU time and slowed it under load), and the caller's setting is
back afterwards; ``SYSID_BLAS_THREADS`` overrides the count."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

import sysid
from sysid._threads import blas_limit


def blas_threads() -> set[int]:
    """The thread counts of every loaded BLAS library (numpy's and SciPy's)."""
    return {int(i["num_threads"]) for i in threadpool_info() if i["user_api"] == "blas"}


@pytest.fixture
def two_threads():
    """BLAS at two threads (the default on a 2-core machine), whatever the environment."""
    import scipy.linalg  # noqa: F401 - SciPy's BLAS loaded, so both libraries are set

    with threadpool_limits(limits=2, user_api="blas"):
        yield blas_threads()


def data() -> sysid.IOData:
    rng = np.random.default_rng(0)
    true = sysid.StateSpaceModel([[0.8, 0.2], [0.0, 0.5]], [[1.0], [0.5]], [[1.0, 0.3]])
    u = rng.standard_normal((400, 1))
    return sysid.IOData(u=u, y=true.simulate(u) + 0.05 * rng.standard_normal((400, 1)))


def test_estimator_runs_one_blas_thread_and_restores(two_threads) -> None:
    seen: list[set[int]] = []

    def progress(*_: object) -> bool:
        seen.append(blas_threads())
        return True

    d = data()
    sysid.pem(d, sysid.n4sid(d, 2), progress=progress)
    assert seen and all(s == {1} for s in seen)
    assert blas_threads() == two_threads


def test_nested_limits_lift_once(two_threads) -> None:
    with blas_limit():
        with blas_limit():
            assert blas_threads() == {1}
        assert blas_threads() == {1}  # the outer block still holds it
    assert blas_threads() == two_threads


def test_other_threads_leave_the_pools_alone(two_threads) -> None:
    """OpenBLAS lets only the main thread raise its count again: another thread's block
    must not lower it (it could not restore it)."""
    seen: list[set[int]] = []

    def other() -> None:
        with blas_limit():
            seen.append(blas_threads())
        d = data()
        sysid.n4sid(d, 2)
        seen.append(blas_threads())

    t = threading.Thread(target=other)
    t.start()
    t.join(30)
    assert seen == [two_threads, two_threads]
    assert blas_threads() == two_threads


@pytest.mark.parametrize(("value", "expect"), [("keep", None), ("2", 2), ("1", 1)])
def test_environment_sets_the_count(monkeypatch, two_threads, value, expect) -> None:
    monkeypatch.setenv("SYSID_BLAS_THREADS", value)
    with blas_limit():
        assert blas_threads() == (two_threads if expect is None else {expect})
    assert blas_threads() == two_threads
