"""The automatic structures' fold fits (sysid.validation.crossval.held_out_folds) run on
the cores at hand: the same held-out fits and choice as one after another, one thread where
RAYON_NUM_THREADS=1 asks for it (identify_many's workers), and a fit on a worker thread
stops promptly when the main thread is interrupted (the event of sysid._progress.stopped_by,
asked by the Rust core as the main thread asks for Ctrl-C)."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

import sysid
from sysid import _parallel
from sysid._progress import stop_requested, stopped_by
from sysid.validation import crossval


def _wiener(n: int = 3000) -> sysid.IOData:
    """test_hammerstein_choice's saturating Wiener record (its networks are chosen)."""
    from test_hammerstein_choice import _wiener as record

    return record(n=n)


def test_parallel_folds_give_the_sequential_choice(monkeypatch) -> None:
    d = _wiener()
    seen: dict[str, object] = {}
    for threads in ("1", "2"):
        monkeypatch.setenv("RAYON_NUM_THREADS", threads)
        assert _parallel.fold_workers(5) == int(threads)
        m = sysid.nlhw_ss(d, 2, progress=False)
        seen[threads] = (m.info["nonlinearity_choice"], m.simulate(d.u))
    (c1, y1), (c2, y2) = seen["1"], seen["2"]
    assert c1 == c2  # the same per-block fits, to the bit, and the same choice
    assert c1["kind"] == "sigmoid"
    np.testing.assert_array_equal(y1, y2)


def test_fold_workers_follow_the_environment_and_the_thread(monkeypatch) -> None:
    monkeypatch.setenv("RAYON_NUM_THREADS", "3")
    assert _parallel.fold_workers(5) == 3 and _parallel.fold_workers(2) == 2
    monkeypatch.delenv("RAYON_NUM_THREADS")
    assert 1 <= _parallel.fold_workers(5) <= 5
    got: list[int] = []
    t = threading.Thread(target=lambda: got.append(_parallel.fold_workers(5)))
    t.start()
    t.join()
    assert got == [1]  # a fold fit's own folds run in its thread


@pytest.mark.serial
def test_a_worker_threads_rust_fit_stops_when_its_event_is_set() -> None:
    rng = np.random.default_rng(1)
    true = sysid.StateSpaceModel(np.diag([0.9, 0.5, -0.3]), np.ones((3, 1)), np.ones((1, 3)))
    u = rng.standard_normal((300_000, 1))
    d = sysid.IOData(u=u, y=true.simulate(u) + 0.1 * rng.standard_normal((300_000, 1)))
    stop = threading.Event()
    out: list[object] = []

    def work() -> None:
        with stopped_by(stop):
            t = time.perf_counter()
            try:
                sysid.ssest(d, 3, max_iter=100_000, tol=1e-300, progress=False)
                out.append("finished")
            except KeyboardInterrupt:
                out.append(time.perf_counter() - t)

    t = threading.Thread(target=work)
    t.start()
    time.sleep(0.3)  # the fit takes about 1 s on a fast machine: stop it well inside
    set_at = time.perf_counter()
    stop.set()
    t.join(30)
    assert not t.is_alive()
    assert len(out) == 1 and out[0] != "finished", out
    assert time.perf_counter() - set_at < 1.0
    assert not stop_requested()  # the main thread's own work is not stopped


@pytest.mark.parametrize("threads", ["1", "2"])
def test_a_fit_error_on_a_part_is_scored_at_the_floor(monkeypatch, threads) -> None:
    monkeypatch.setenv("RAYON_NUM_THREADS", threads)
    d = _wiener(1000)
    pairs = crossval.record_folds(d)

    def fit(part: sysid.IOData, k: int, fitted: dict) -> object:
        if part is pairs[1][0]:
            raise sysid.errors.DataError("this part cannot be fitted")
        return sysid.n4sid(part, k)

    folds, failed = crossval.held_out_folds(pairs, [2], fit, floor=-100.0)
    assert folds[2][1] == -100.0 and len(failed[2]) == 1
    assert all(f > 50 for i, f in enumerate(folds[2]) if i != 1)


def test_identify_refines_on_threads_with_the_same_board(monkeypatch) -> None:
    """identify's refinements are fitted on the blocks in parallel: the same leaderboard and
    model as one block after another."""
    rng = np.random.default_rng(4)
    true = sysid.StateSpaceModel([[0.85, 0.3], [-0.3, 0.85]], [[1.0], [0.4]], [[1.0, 0.0]])
    u = rng.standard_normal((1500, 1))
    d = sysid.IOData(u=u, y=true.simulate(u) + 0.2 * rng.standard_normal((1500, 1)))
    seen = {}
    for threads in ("1", "2"):
        monkeypatch.setenv("RAYON_NUM_THREADS", threads)
        r = sysid.identify(d, progress=False)
        board = [(x["family"], x["order"], x["feedthrough"], x.get("focus"),
                  x["held_out_fit"], x.get("note", "")) for x in r.leaderboard]
        seen[threads] = (board, r.model.to_statespace().markov(20))
    assert any(b[0] == "pem" for b in seen["1"][0])  # refinements were scored
    assert seen["1"][0] == seen["2"][0]
    np.testing.assert_array_equal(seen["1"][1], seen["2"][1])
