"""Many records at once: sysid.identify_many with 1 and 2 worker processes.

    python benches/fleet.py                       # the issue's size: 1000 records
    python benches/fleet.py --records 40          # a short run
    python benches/fleet.py --fit identify        # identify_many's default fit (slower)

Records: random stable 3 x 3 systems of order 4 (poles 0.5..0.95), white-noise inputs,
10 000 samples, output noise 10 %; made lazily in the calling process as workers take them.
Fit (``--fit``): ``ssest`` (the default here) refines the order-4 subspace estimate by
prediction errors, as a fleet of loops of known structure is fitted; ``identify`` is
identify_many's own default, the automatic path (several seconds a record).
Reported: records per second with 1 and 2 local worker processes
and their ratio (goal >= 1.7); the per-record overhead = wall time x workers / records minus
the mean in-worker time (read + fit + describe, the table's ``seconds``), relative to that
time (goal < 10 %); and the same records fitted in this process in a plain loop (no workers,
no Parquet, one compute thread as in the workers), the floor the workers are
measured against. Results go to
benches/results/fleet.md.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

# one compute thread in every pool of this process too, as in the workers, set before numpy
# loads: the floor is the same fit, unshared
for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "RAYON_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402

import sysid  # noqa: E402
from sysid.batch.worker import default_fit  # noqa: E402

HERE = Path(__file__).resolve().parent
N_SAMPLES, ORDER, M, L = 10_000, 4, 3, 3


def system(seed: int) -> sysid.StateSpaceModel:
    rng = np.random.default_rng(seed)
    r = rng.uniform(0.5, 0.95, ORDER // 2)
    th = rng.uniform(0.1, 1.2, ORDER // 2)
    A = np.zeros((ORDER, ORDER))
    for k in range(ORDER // 2):
        c, s = r[k] * np.cos(th[k]), r[k] * np.sin(th[k])
        A[2 * k:2 * k + 2, 2 * k:2 * k + 2] = [[c, -s], [s, c]]
    T = rng.standard_normal((ORDER, ORDER)) + 3 * np.eye(ORDER)
    A = T @ A @ np.linalg.inv(T)
    return sysid.StateSpaceModel(A, rng.standard_normal((ORDER, M)),
                                 rng.standard_normal((L, ORDER)), dt=1.0)


def record(seed: int) -> sysid.IOData:
    rng = np.random.default_rng(10_000 + seed)
    u = rng.standard_normal((N_SAMPLES, M))
    y = system(seed).simulate(u)
    y += 0.1 * y.std(0) * rng.standard_normal(y.shape)
    return sysid.IOData(u=u, y=y)


def ssest_known_order(data: sysid.IOData) -> sysid.StateSpaceModel:
    """The fleet's structure is known (order 4): subspace start, prediction-error refinement."""
    return sysid.ssest(data, ORDER)


FITS = {"ssest": ssest_known_order, "identify": default_fit}


def records(n: int) -> Iterator[tuple[str, sysid.IOData]]:
    for i in range(n):
        yield f"rec{i:05d}", record(i)


def run(n: int, workers: int, out: Path, fit) -> dict[str, float]:
    t0 = time.perf_counter()
    res = sysid.identify_many(records(n), fit=fit, workers=workers, out=out, progress=False)
    wall = time.perf_counter() - t0
    df = res.to_pandas()
    fit_s = float(df["seconds"].mean())
    cpu = float(df["cpu_seconds"].sum())
    overhead = wall * workers / n - fit_s
    return {"wall": wall, "rate": n / wall, "fit_s": fit_s, "overhead": overhead,
            "cpu_s": cpu / n, "cores": cpu / wall,
            "ok": res.n_ok, "failed": res.n_failed,
            "mean_fit": float(df["fit"].mean()), "orders": sorted(set(df["order"].dropna()))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--records", type=int, default=1000)
    ap.add_argument("--fit", choices=sorted(FITS), default="ssest")
    ap.add_argument("--out", default=str(HERE / "results" / "fleet.md"))
    args = ap.parse_args()
    n, fit = args.records, FITS[args.fit]
    tmp = Path(tempfile.mkdtemp())
    t0 = time.perf_counter()
    k = min(n, 10)
    for i in range(k):  # the floor: a plain loop in this process on the first records
        fit(record(i))
    floor = (time.perf_counter() - t0) / k
    r1 = run(n, 1, tmp / "w1.parquet", fit)
    r2 = run(n, 2, tmp / "w2.parquet", fit)
    ratio = r2["rate"] / r1["rate"]
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines = [
        "# identify_many: 1 and 2 worker processes",
        "",
        f"Command: `python benches/fleet.py --records {n} --fit {args.fit}` "
        f"({time.strftime('%Y-%m-%d %H:%M')}"
        f" UTC, {platform.machine()}, {os.cpu_count()} cores, load average {load:.1f} at the "
        "end: the machine was shared).",
        "",
        f"{n} records of {N_SAMPLES} samples, {M} inputs x {L} outputs, order {ORDER}; fit: "
        f"`{args.fit}` ({fit.__doc__.splitlines()[0].strip()})",
        "",
        "| workers | wall [s] | records/s | in-worker s/record | in-worker CPU s/record | "
        "CPU cores obtained | overhead s/record | overhead / in-worker | ok | errors |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for w, r in ((1, r1), (2, r2)):
        lines.append(f"| {w} | {r['wall']:.1f} | {r['rate']:.3f} | {r['fit_s']:.3f} | "
                     f"{r['cpu_s']:.3f} | {r['cores']:.2f} | "
                     f"{r['overhead']:.3f} | {100 * r['overhead'] / r['fit_s']:.1f} % | "
                     f"{r['ok']} | {r['failed']} |")
    lines += [
        "",
        f"Throughput ratio, 2 workers / 1 worker: **{ratio:.2f}x** (goal >= 1.7x). CPU cores "
        f"obtained = CPU seconds of all workers / wall time: {r1['cores']:.2f} with one "
        f"worker, {r2['cores']:.2f} with two (the share of the machine the workers got).",
        "",
        f"Plain loop in the calling process (first {k} records, one compute thread as in the "
        "workers, no processes, no Parquet): "
        f"{floor:.3f} s/record, so one worker process runs at "
        f"{100 * floor / (r1['wall'] / n):.0f} % of the in-process rate.",
        "",
        f"Models: orders chosen {r1['orders']}, mean simulation fit {r1['mean_fit']:.1f} %.",
    ]
    text = "\n".join(lines) + "\n"
    Path(args.out).write_text(text)
    print(text)


if __name__ == "__main__":
    main()
