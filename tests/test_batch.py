"""identify_many: a model per record on local processes and on a two-process Dask cluster,
streamed to Parquet; a killed worker and a corrupt record cost only their own rows."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import sysid
from sysid.batch.stream import DIED

pytest.importorskip("pyarrow")

TRUE = sysid.StateSpaceModel([[0.8, 0.1], [0.0, 0.5]], [[1.0], [0.5]], [[1.0, 0.0]], dt=0.1)
DIE = 0.777  # first input sample of a record whose fit kills its worker every time
DIE_ONCE = 0.555  # ... kills its worker the first time only (marker file)


def record(seed: int, first: float | None = None) -> sysid.IOData:
    u = np.random.default_rng(seed).standard_normal((400, 1))
    y = TRUE.simulate(u) + 0.01 * np.random.default_rng(seed + 100).standard_normal((400, 1))
    if first is not None:
        u[0, 0] = first
    return sysid.IOData(u=u, y=y, dt=0.1, input_names=["u"], output_names=["y"])


def fit_or_die(data: sysid.IOData):
    """n4sid of order 2, or the worker process dies (a native crash, an OOM kill)."""
    first = data.u[0, 0]
    if first == DIE:
        os._exit(1)
    if first == DIE_ONCE:
        marker = Path(os.environ["SYSID_TEST_MARKER"])
        if not marker.exists():
            marker.write_text("died once")
            os._exit(1)
    return sysid.n4sid(data, 2)


def fit_reports_threads(data: sysid.IOData):
    """Fails on purpose with the worker's thread settings, which the error row then shows."""
    from sysid.batch.worker import THREAD_VARIABLES

    raise RuntimeError(" ".join(f"{k}={os.environ.get(k)}" for k in THREAD_VARIABLES))


def check_rows(df, good: list[str]) -> None:
    ok = df[df["error"].isna()]
    assert sorted(ok["record_id"]) == sorted(good)
    assert (ok["order"] == 2).all() and (ok["fit"] > 95).all() and ok["stable"].all()
    assert (ok["family"] == "n4sid").all() and (ok["n_samples"] == 400).all()
    model = sysid.model_from_dict(__import__("json").loads(ok["parameters"].iloc[0]))
    assert np.allclose(np.sort(np.abs(model.poles())), [0.5, 0.8], atol=0.02)


def test_local_processes_survive_a_killed_worker_and_a_corrupt_record(tmp_path, monkeypatch):
    monkeypatch.setenv("SYSID_TEST_MARKER", str(tmp_path / "marker"))
    recs = {f"r{i}": record(i) for i in range(5)}
    recs["dies"] = record(10, DIE)
    recs["dies-once"] = record(11, DIE_ONCE)
    recs["corrupt"] = (np.zeros((50, 1)), np.zeros((40, 1)))  # u and y lengths differ
    res = sysid.identify_many(recs, fit=fit_or_die, workers=2, retries=1,
                              out=tmp_path / "out.parquet", progress=False)
    df = res.to_pandas()
    assert len(df) == len(recs) and set(df["record_id"]) == set(recs)
    check_rows(df, [f"r{i}" for i in range(5)] + ["dies-once"])
    err = df.set_index("record_id")["error"]
    assert err["dies"] == DIED
    assert df.set_index("record_id").loc["dies", "attempts"] == 2  # tried again, alone
    assert err["corrupt"].startswith("ShapeError: u has 50 samples but y has 40")
    assert res.n_ok == 6 and res.n_failed == 2 and "2 local processes" in repr(res)
    assert res.model("r3").nstates == 2


def test_local_workers_start_with_one_thread_in_every_pool(tmp_path, monkeypatch):
    # a worker whose BLAS pool has every core makes two workers on two cores fight (measured:
    # twice the CPU time for the same wall time); the pools read their variable at load
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "8")
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    res = sysid.identify_many({"a": record(0)}, fit=fit_reports_threads, workers=1,
                              out=tmp_path / "t.parquet", progress=False)
    err = res.to_pandas()["error"].iloc[0]
    from sysid.batch.worker import THREAD_VARIABLES

    for k in THREAD_VARIABLES:
        assert f"{k}=1" in err
    # the caller's environment is back as it was
    assert os.environ["OPENBLAS_NUM_THREADS"] == "8" and "OMP_NUM_THREADS" not in os.environ


def test_folder_of_files_in_this_process(tmp_path):
    folder = tmp_path / "records"
    folder.mkdir()
    for i in range(3):
        d = record(i)
        np.savetxt(folder / f"run{i}.csv", np.hstack([d.u, d.y]), delimiter=",",
                   header="u,y", comments="")
    (folder / "broken.csv").write_text("u,y\n1.0,2.0\n0.5,abc\n")
    res = sysid.identify_many(folder, fit=fit_or_die, workers=0, inputs=["u"],
                              outputs=["y"], dt=0.1, out=tmp_path / "t.parquet",
                              progress=False)
    df = res.to_pandas()
    check_rows(df, ["run0", "run1", "run2"])
    bad = df.set_index("record_id").loc["broken", "error"]
    assert "line 3, column 'y': 'abc' is not a number" in bad


def test_bad_arguments_are_named():
    with pytest.raises(sysid.DataError, match="not a folder"):
        sysid.identify_many("/no/such/folder", progress=False)


distributed = pytest.importorskip("distributed")


def test_dask_cluster_killed_worker_corrupt_record_bag_and_dataframe(tmp_path, monkeypatch):
    """Two worker processes: a worker killed once (the scheduler reruns its record
    elsewhere), one killed every time (KilledWorker: an error row), a corrupt file; then the
    same client fits a Dask bag and a Dask dataframe partitioned by record id."""
    import dask
    import dask.bag as db
    import dask.dataframe as dd
    import pandas as pd

    monkeypatch.setenv("SYSID_TEST_MARKER", str(tmp_path / "marker"))
    folder = tmp_path / "records"
    folder.mkdir()
    for i, first in enumerate([None, None, None, DIE, DIE_ONCE]):
        d = record(i, first)
        np.savetxt(folder / f"run{i}.csv", np.hstack([d.u, d.y]), delimiter=",",
                   header="u,y", comments="")
    (folder / "corrupt.parquet").write_bytes(b"PAR1 this is not parquet")
    with dask.config.set({"distributed.scheduler.allowed-failures": 1}), \
            distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                     dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        res = sysid.identify_many(folder, fit=fit_or_die, inputs=["u"], outputs=["y"],
                                  dt=0.1, out=tmp_path / "c.parquet", progress=False)
        assert res.workers.startswith("dask: tcp://")
        df = res.to_pandas()
        check_rows(df, ["run0", "run1", "run2", "run4"])
        err = df.set_index("record_id")["error"]
        assert err["run3"] == DIED
        assert err["corrupt"].startswith("DataError: corrupt.parquet: not a readable Parquet")

        bag = db.from_sequence([(f"b{i}", record(i)) for i in range(4)], npartitions=2)
        dfb = sysid.identify_many(bag, fit=fit_or_die, out=tmp_path / "b.parquet",
                                  progress=False).to_pandas()
        check_rows(dfb, ["b0", "b1", "b2", "b3"])

        frames = []
        for i in range(4):
            d = record(20 + i)
            frames.append(pd.DataFrame({"rec": f"d{i}", "u": d.u[:, 0], "y": d.y[:, 0]}))
        ddf = dd.from_pandas(pd.concat(frames).set_index("rec", drop=False), npartitions=2)
        dfd = sysid.identify_many(ddf, fit=fit_or_die, record_id="rec", inputs=["u"],
                                  outputs=["y"], dt=0.1, out=tmp_path / "d.parquet",
                                  progress=False).to_pandas()
        check_rows(dfd, ["d0", "d1", "d2", "d3"])


CTRL_C = '''
import os, sys, time
from pathlib import Path
import numpy as np
import sysid

def slow_fit(data):
    (Path(sys.argv[2]) / f"{os.getpid()}.pid").write_text("")
    time.sleep(0.4)
    return sysid.n4sid(data, 1)

if __name__ == "__main__":
    m = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]])
    u = np.random.default_rng(0).standard_normal((300, 1))
    recs = [sysid.IOData(u=u, y=m.simulate(u)) for _ in range(200)]
    sysid.identify_many(recs, fit=slow_fit, workers=2, out=sys.argv[1], flush_every=1,
                        progress=False)
'''


def test_ctrl_c_stops_the_workers_and_keeps_the_finished_rows(tmp_path):
    """SIGINT to the calling process: it stops within seconds, its worker processes are
    gone, and the rows finished before are in the table."""
    import signal
    import subprocess
    import sys
    import time

    import pandas as pd

    script, out, pids = tmp_path / "run.py", tmp_path / "out", tmp_path / "pids"
    script.write_text(CTRL_C)
    pids.mkdir()
    env = {**os.environ, "PYTHONPATH": str(Path(sysid.__file__).parents[1])}
    with subprocess.Popen([sys.executable, str(script), str(out), str(pids)], env=env,
                          stderr=subprocess.PIPE, text=True) as proc:
        deadline = time.monotonic() + 120
        while len(list(out.glob("part-*.parquet"))) < 3 and time.monotonic() < deadline:
            time.sleep(0.1)
        assert proc.poll() is None
        t0 = time.monotonic()
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    assert time.monotonic() - t0 < 30 and proc.returncode != 0
    assert "KeyboardInterrupt" in err
    df = pd.read_parquet(out)
    assert 3 <= len(df) < 200 and df["error"].isna().all()
    time.sleep(1.0)
    for p in pids.glob("*.pid"):  # every worker that ran is gone
        with pytest.raises(ProcessLookupError):
            os.kill(int(p.stem), 0)


def test_guide_runs(tmp_path, monkeypatch, capsys):
    """docs/batch.md's example runs and prints the table it describes."""
    import re

    monkeypatch.chdir(tmp_path)
    text = (Path(__file__).parents[1] / "docs" / "batch.md").read_text()
    for i, block in enumerate(re.findall(r"```python\n(.*?)```", text, re.S)):
        exec(compile(block, f"docs/batch.md[{i}]", "exec"), {})
    out = capsys.readouterr().out
    assert "loop3" in out and "record_id" in out and (tmp_path / "loops.parquet").is_dir()


UNGUARDED = '''
import sys
import numpy as np
import sysid

def fit(data):
    return sysid.n4sid(data, 1)

m = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]])
u = np.random.default_rng(0).standard_normal((300, 1))
recs = [sysid.IOData(u=u, y=m.simulate(u)) for _ in range(3)]
sysid.identify_many(recs, fit=fit, workers=2, out=sys.argv[1], progress=False)
'''


def test_a_top_level_call_without_the_main_guard_says_so(tmp_path):
    """A script that calls identify_many(workers=...) at its top level: each spawned worker
    imports it and calls again. Every record was written as 'WorkerDied' (a crash in native
    code?); the call now fails at once, naming the `if __name__ == "__main__":` guard."""
    import subprocess
    import sys

    script = tmp_path / "run.py"
    script.write_text(UNGUARDED)
    env = {**os.environ, "PYTHONPATH": str(Path(sysid.__file__).parents[1])}
    done = subprocess.run([sys.executable, str(script), str(tmp_path / "out")], env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode != 0
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith("sysid.errors.SysidError") and '__name__ == "__main__"' in last


def test_ctrl_c_is_deferred_to_a_point_outside_the_futures_locks():
    """In the process pool's loop SIGINT is recorded, not raised where it lands (inside
    concurrent.futures.wait it could leave a future's lock held and hang the exit); the
    loop raises KeyboardInterrupt itself, and the previous handler comes back after."""
    import signal
    import threading
    import time

    from sysid.batch.stream import deferred_interrupt

    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signal handlers are set in the main thread only")
    before = signal.getsignal(signal.SIGINT)
    with deferred_interrupt() as got:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)  # the handler runs between bytecodes: no KeyboardInterrupt here
        assert got == [signal.SIGINT]
    assert signal.getsignal(signal.SIGINT) is before
