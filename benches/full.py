"""Every benchmark figure of issue 16 from one run, or part by part.

    python benches/full.py                        # everything (about 25 min on 2 idle cores)
    python benches/full.py --parts sippy floor    # some parts; the others keep their rows
    python benches/full.py --smoke                # small sizes, a few minutes: checks the run

Parts (each in fresh subprocesses; results merged into benches/results/<name>.json and the
report benches/results/<name>.md rewritten from all parts, each with its command and the
load average at its start and end):

``gemm``    the machine's dense GEMM rate (NumPy's BLAS, 1500 x 1500, all cores and one),
            measured first in every run: the compute floors below use it
``sippy``   the default (``compressor="auto"``) against SIPPY's N4SID, 3 in, 3 out, horizon
            20, order 8, N = 10^4, 10^5, 10^6 (and the exact ``"qr"`` compressor); time of the
            first identification in a fresh process (cold: lazy imports, thread pool start)
            and the best of the next ones (warm), pole error and validation fit
``floor``   the default on 8 in, 8 out, horizon 20, N = 10^6 against the compute floor
            ``4 i (m + l)^2 N`` flops at the measured GEMM rate
``threads`` 1 vs 2 threads (``RAYON_NUM_THREADS``) for ``qr``, ``correlation`` and ``auto``
            (N = 2 10^5, 3 x 3, horizon 10) and for the default at 8 x 8, N = 10^6
``grid``    the default over N = 10^4..10^7, (m, l) = (1, 1), (3, 3), (8, 8), horizons 10,
            20, 40 (time and ratio to the floor)
``memmap``  10^8 samples (2 in, 2 out, 3.2 GB .npy) read from a memmap by
            ``compress_stream``: one plain read, then both compressors; time, peak memory
``dask``    the same 10^8 samples as partitioned Parquet (50 files) compressed by
            ``compress_dask`` on a ``LocalCluster(processes=True)`` with 1 and 2 workers

Large files go to a temporary folder under benches/.data (free space is checked with
``df`` first and recorded) and are deleted at the end of their part.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
DATA = HERE / ".data"
PARTS = ("sippy", "floor", "threads", "grid", "memmap", "dask")

sys.path.insert(0, str(HERE))

from run import DATA as RUN_DATA  # noqa: E402
from run import ensure_peers, pole_error, run_one  # noqa: E402

ENV = {"PYTHONPATH": f"{ROOT / 'python'}:{HERE}", "PATH": "/usr/bin:/bin"}


def load() -> float:
    return round(os.getloadavg()[0], 2)


def disk_free_gb(path: Path) -> float:
    return shutil.disk_usage(path).free / 1e9


GEMM_CHILD = r"""
import json, time, numpy as np
n = 1500
a = np.random.default_rng(0).standard_normal((n, n))
a @ a
best = min((lambda t: (a @ a, time.perf_counter() - t)[1])(time.perf_counter()) for _ in range(5))
print(json.dumps({"gflops": 2 * n**3 / best / 1e9}))
"""


def gemm_rates() -> dict:
    """GEMM rate with all cores and with one (BLAS threads from the environment)."""
    out = {}
    for label, threads in (("all", None), ("one", "1")):
        env = dict(os.environ)
        if threads:
            for v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
                env[v] = threads
        r = subprocess.run([sys.executable, "-c", GEMM_CHILD], env=env, capture_output=True,
                           text=True, check=True)
        out[label] = json.loads(r.stdout.strip().splitlines()[-1])["gflops"]
    return out


def case_data(
    n: int, m: int, l: int, order: int, seed: int = 2024
) -> tuple[Path, Path, np.ndarray]:
    """The seeded record of benches/run.py (cached in benches/.data) and its validation."""
    from data import generate

    RUN_DATA.mkdir(exist_ok=True)
    path = RUN_DATA / f"rec_n{n}_m{m}_l{l}_x{order}_s{seed}.npy"
    poles = path.with_suffix(".poles.npy")
    if not (path.exists() and poles.exists()):
        np.save(poles, generate(path, n, m, l, order, seed))
    val = RUN_DATA / f"val_m{m}_l{l}_x{order}_s{seed}.npy"
    if not val.exists():
        generate(val, 10_000, m, l, order, seed, noise_seed=seed + 99)
    return path, val, np.load(poles)


def identify(tool: str, n: int, m: int, l: int, i: int, order: int, repeat: int,
             py: Path | None = None, timeout: float = 900.0, processes: int = 1) -> dict:
    """One case in `processes` fresh processes of `repeat` identifications each: `seconds`
    is the median of the cold (first) runs, all of them in `cold_runs`; `warm_seconds` the
    best later run of any process; the other fields come from the median process."""
    path, val, true = case_data(n, m, l, order)
    case = dict(n=n, m=m, l=l, i=i, order=order)
    if py is None:
        res = {"tool": tool, "ok": False, "error": "peer environment unavailable"}
    else:
        runs = [run_one(py, tool, path, val, case, timeout, 14.0, repeat=repeat)
                for _ in range(processes)]
        ok = [r for r in runs if r.get("ok")]
        if len(ok) < len(runs) or len(runs) == 1:
            res = next((r for r in runs if not r.get("ok")), runs[0])
        else:
            ok.sort(key=lambda r: r["seconds"])
            res = dict(ok[len(ok) // 2])
            res["cold_runs"] = [r["seconds"] for r in runs]
            warm = [r["warm_seconds"] for r in ok if "warm_seconds" in r]
            if warm:
                res["warm_seconds"] = min(warm)
    res.update(case, load=load())
    if res.get("ok"):
        res["pole_error"] = pole_error(res.pop("poles"), true)
    print(json.dumps(res), flush=True)
    return res


def part_sippy(a: argparse.Namespace, rates: dict) -> dict:
    sizes = (10**4, 10**5) if a.smoke else (10**4, 10**5, 10**6)
    peers = ensure_peers()
    rows = []
    for n in sizes:
        rows.append(identify("sysid-auto", n, 3, 3, 20, 8, repeat=5, py=Path(sys.executable),
                             processes=3))
        rows.append(identify("sysid-qr", n, 3, 3, 20, 8, repeat=1, py=Path(sys.executable)))
        rows.append(identify("sippy", n, 3, 3, 20, 8, repeat=1, py=peers))
    return {"rows": rows}


def part_floor(a: argparse.Namespace, rates: dict) -> dict:
    n = 10**5 if a.smoke else 10**6
    rows = [identify("sysid-auto", n, 8, 8, 20, 8, repeat=3, py=Path(sys.executable),
                     processes=3)]
    for r in rows:
        r["floor_seconds"] = 4 * r["i"] * (r["m"] + r["l"]) ** 2 * r["n"] / (rates["all"] * 1e9)
    return {"rows": rows}


def part_grid(a: argparse.Namespace, rates: dict) -> dict:
    sizes = (10**4, 10**5) if a.smoke else (10**4, 10**5, 10**6, 10**7)
    rows = []
    for n in sizes:
        for m, l in ((1, 1), (3, 3), (8, 8)):
            for i in (10, 20, 40):
                order = 4 if (m, l) == (1, 1) else 8
                r = identify("sysid-auto", n, m, l, i, order, repeat=2, py=Path(sys.executable))
                r["floor_seconds"] = 4 * i * (m + l) ** 2 * n / (rates["all"] * 1e9)
                rows.append(r)
            if n >= 10**7:
                for f in RUN_DATA.glob(f"rec_n{n}_m{m}_l{l}_*"):
                    f.unlink()
    return {"rows": rows}


def part_threads(a: argparse.Namespace, rates: dict) -> dict:
    from threads import CHILD

    configs = [(2 * 10**4 if a.smoke else 2 * 10**5, 3, 3, 10, ("qr", "correlation", "auto"), 3),
               (10**5 if a.smoke else 10**6, 8, 8, 20, ("auto",), 3)]
    rows = []
    for n, m, l, i, comps, reps in configs:
        for comp in comps:
            for th in (1, 2):
                env = dict(os.environ, RAYON_NUM_THREADS=str(th))
                l0 = load()
                r = subprocess.run(
                    [sys.executable, "-c", CHILD, str(n), str(m), str(l), str(i), str(reps), comp],
                    env=env, capture_output=True, text=True, check=True)
                out = json.loads(r.stdout.strip().splitlines()[-1])
                ts = sorted(out["times"])
                row = dict(n=n, m=m, l=l, i=i, compressor=comp, threads=th, min=ts[0],
                           median=ts[len(ts) // 2], source=out["source"], sha=out["sha"],
                           load=[l0, load()])
                rows.append(row)
                print(json.dumps(row), flush=True)
    return {"rows": rows}


def big_record(n: int, folder: Path) -> tuple[Path, np.ndarray]:
    from data import generate

    path = folder / "big.npy"
    t0 = time.perf_counter()
    true = generate(path, n, 2, 2, 4, seed=7)
    print(f"generated {path} ({path.stat().st_size / 1e9:.2f} GB) in "
          f"{time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
    return path, true


def scratch(a: argparse.Namespace, need_gb: float) -> Path:
    DATA.mkdir(exist_ok=True)
    free = disk_free_gb(DATA)
    df = subprocess.run(["df", "-h", str(DATA)], capture_output=True, text=True).stdout
    print(df, file=sys.stderr, flush=True)
    if free < need_gb + 5:
        raise SystemExit(f"only {free:.0f} GB free under {DATA}; this part needs {need_gb:.0f} GB")
    return Path(tempfile.mkdtemp(prefix="bench-", dir=DATA))


def part_memmap(a: argparse.Namespace, rates: dict) -> dict:
    from memmap_big import CHILD

    n = 10**6 if a.smoke else 10**8
    shared = getattr(a, "shared", None)
    folder = scratch(a, 0 if shared else n * 32 / 1e9)
    rows = []
    try:
        path, true = shared if shared else big_record(n, folder)
        for mode in ("read", "correlation", "qr"):
            l0 = load()
            r = subprocess.run([sys.executable, "-c", CHILD, mode, str(path), "20", "4"],
                               capture_output=True, text=True, env=ENV)
            if r.returncode != 0:
                res = {"mode": mode, "error": (r.stderr.strip().splitlines() or ["?"])[-1]}
            else:
                res = json.loads(r.stdout.strip().splitlines()[-1])
                if "poles" in res:
                    res["pole_error"] = pole_error(res.pop("poles"), true)
            res.update(n=n, load=[l0, load()])
            rows.append(res)
            print(json.dumps(res), flush=True)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    floor = 4 * 20 * 16 * n / (rates["all"] * 1e9)
    return {"rows": rows, "n": n, "floor_seconds": floor}


DASK_CHILD = r"""
import glob, json, os, sys, time
import numpy as np
import dask, dask.array as da, distributed
import pyarrow.parquet as pq
import sysid
folder, workers, horizon, order = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
files = sorted(glob.glob(os.path.join(folder, "*.parquet")))
rows = [pq.ParquetFile(f).metadata.num_rows for f in files]

def load(f):
    t = pq.read_table(f)
    return np.column_stack([t.column(c).to_numpy() for c in ("u0", "u1", "y0", "y1")])

z = da.concatenate([da.from_delayed(dask.delayed(load)(f), shape=(r, 4), dtype=np.float64)
                    for f, r in zip(files, rows)])
with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                              dashboard_address=None) as cluster, distributed.Client(cluster) as c:
    pids = set(c.run(os.getpid).values())
    t0 = time.perf_counter()
    f = sysid.compress_dask(z[:, :2], z[:, 2:], past=horizon)
    t1 = time.perf_counter()
model = sysid.SubspaceEstimator.from_factor(f, dt=1.0).fit(order=order)
print(json.dumps({"workers": workers, "processes": len(pids), "seconds": t1 - t0,
                  "files": len(files), "samples": int(sum(rows)), "source": f.source,
                  "poles": [[float(p.real), float(p.imag)] for p in np.asarray(model.poles())]}))
"""


def write_parquet(npy: Path, folder: Path, parts: int) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    z = np.load(npy, mmap_mode="r")
    n = z.shape[0]
    step = -(-n // parts)
    for k, s in enumerate(range(0, n, step)):
        blk = np.asarray(z[s : s + step])
        t = pa.table({c: blk[:, j] for j, c in enumerate(("u0", "u1", "y0", "y1"))})
        pq.write_table(t, folder / f"part-{k:04d}.parquet", compression="none")


def part_dask(a: argparse.Namespace, rates: dict) -> dict:
    n = 10**6 if a.smoke else 10**8
    shared = getattr(a, "shared", None)
    folder = scratch(a, (1 if shared else 2) * n * 32 / 1e9)
    rows = []
    try:
        path, true = shared if shared else big_record(n, folder)
        pq_dir = folder / "parquet"
        pq_dir.mkdir()
        t0 = time.perf_counter()
        write_parquet(path, pq_dir, 50)
        if not shared:
            path.unlink()
        print(f"wrote 50 Parquet files in {time.perf_counter() - t0:.0f} s", file=sys.stderr)
        for workers in (1, 2):
            env = dict(ENV, RAYON_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1",
                       OMP_NUM_THREADS="1")
            l0 = load()
            r = subprocess.run([sys.executable, "-c", DASK_CHILD, str(pq_dir), str(workers),
                                "20", "4"], capture_output=True, text=True, env=env)
            if r.returncode != 0:
                res = {"workers": workers, "error": (r.stderr.strip().splitlines() or ["?"])[-1]}
            else:
                res = json.loads(r.stdout.strip().splitlines()[-1])
                res["pole_error"] = pole_error(res.pop("poles"), true)
            res.update(n=n, load=[l0, load()])
            rows.append(res)
            print(json.dumps(res), flush=True)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return {"rows": rows, "n": n}


RUNNERS = {"sippy": part_sippy, "floor": part_floor, "threads": part_threads,
           "grid": part_grid, "memmap": part_memmap, "dask": part_dask}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--parts", nargs="*", choices=PARTS, default=list(PARTS))
    ap.add_argument("--smoke", action="store_true",
                    help="small sizes (10^4-10^5; 10^6 for the memmap and Dask parts)")
    ap.add_argument("--name", default=None, help="results name (default: full, or smoke)")
    a = ap.parse_args()
    name = a.name or ("smoke" if a.smoke else "full")
    out_json = HERE / "results" / f"{name}.json"
    results = json.loads(out_json.read_text()) if out_json.exists() else {"parts": {}}
    cmd = "python benches/full.py" + (" --smoke" if a.smoke else "") + (
        f" --name {a.name}" if a.name else "")
    t_run = time.perf_counter()
    rates = gemm_rates()
    print(json.dumps({"gemm_gflops": rates, "load": load()}), flush=True)
    shared_dir = None
    if "memmap" in a.parts and "dask" in a.parts:
        # one 10^8-sample record for both parts (generated once, deleted at the end)
        n = 10**6 if a.smoke else 10**8
        shared_dir = scratch(a, n * 32 / 1e9)
        a.shared = big_record(n, shared_dir)
    try:
        run_parts(a, name, cmd, rates, results, out_json)
    finally:
        if shared_dir is not None:
            shutil.rmtree(shared_dir, ignore_errors=True)
    print(f"whole run {time.perf_counter() - t_run:.0f} s", file=sys.stderr)


def run_parts(a: argparse.Namespace, name: str, cmd: str, rates: dict, results: dict,
              out_json: Path) -> None:
    for part in a.parts:
        l0, t0 = load(), time.perf_counter()
        started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
        res = RUNNERS[part](a, rates)
        res.update(command=f"{cmd} --parts {part}", started=started, gemm_gflops=rates,
                   load=[l0, load()], wall_seconds=time.perf_counter() - t0,
                   cpus=os.cpu_count(), machine=platform.machine())
        results["parts"][part] = res
        out_json.write_text(json.dumps(results, indent=1))
        write_report(name, results)


def write_report(name: str, results: dict) -> None:
    from full_report import report

    (HERE / "results" / f"{name}.md").write_text(report(results))
    print(f"wrote benches/results/{name}.md", file=sys.stderr)


if __name__ == "__main__":
    main()
