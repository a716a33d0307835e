"""1 vs 2 threads for both compressors (and the default), each in a fresh process.

    python benches/threads.py                 # N = 2e5, 3 x 3, horizon 10, 5 repetitions
    python benches/threads.py --n 1000000 --m 8 --l 8 --horizon 20 --reps 3

The rayon pool size is read from RAYON_NUM_THREADS once per process, so every
(compressor, threads) pair runs in its own subprocess: it compresses the same record
``--reps`` times and reports the minimum and the median wall time of the compression alone.
The factor's SHA-256 is printed too: it must be the same for every thread count. The load
average of the machine at the start and end is recorded (the machine is shared: timings on
a loaded machine are upper bounds). Results: benches/results/threads.md.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent

CHILD = r"""
import hashlib, json, sys, time
import numpy as np
from sysid import _sysid
n, m, l, i, reps, comp = (int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]),
                          int(sys.argv[4]), int(sys.argv[5]), sys.argv[6])
rng = np.random.default_rng(0)
u = rng.standard_normal((n, m))
y = np.zeros((n, l))
# a stable mixing filter: well-conditioned data, no fallback
y[1:] = 0.5 * u[:-1, :1] + 0.1 * rng.standard_normal((n - 1, l))
for t in range(1, 4):
    y[t:] += 0.3 ** t * np.roll(u, t, axis=0)[t:, :1]
times = []
for _ in range(reps):
    t0 = time.perf_counter()
    f = _sysid.compress([(u, y)], i, i, None, comp)
    times.append(time.perf_counter() - t0)
print(json.dumps({"times": times, "source": f.source,
                  "sha": hashlib.sha256(np.ascontiguousarray(f.l).tobytes()).hexdigest()[:16]}))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--n", type=int, default=200_000)
    ap.add_argument("--m", type=int, default=3)
    ap.add_argument("--l", type=int, default=3)
    ap.add_argument("--horizon", type=int, default=10)
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--threads", type=int, nargs="*", default=[1, 2])
    ap.add_argument("--compressors", nargs="*", default=["qr", "correlation", "auto"])
    ap.add_argument("--name", default="threads")
    a = ap.parse_args()
    load0 = os.getloadavg()
    rows = []
    for comp in a.compressors:
        for th in a.threads:
            env = dict(os.environ, RAYON_NUM_THREADS=str(th))
            r = subprocess.run(
                [sys.executable, "-c", CHILD, str(a.n), str(a.m), str(a.l), str(a.horizon),
                 str(a.reps), comp], env=env, capture_output=True, text=True, check=True,
            )
            out = json.loads(r.stdout.strip().splitlines()[-1])
            ts = sorted(out["times"])
            row = dict(compressor=comp, threads=th, min=ts[0], median=ts[len(ts) // 2],
                       source=out["source"], sha=out["sha"])
            rows.append(row)
            print(json.dumps(row), flush=True)
    load1 = os.getloadavg()
    cmd = " ".join(["python benches/threads.py", *sys.argv[1:]])
    lines = [
        "# 1 vs 2 threads",
        "",
        f"Command: `{cmd}`; {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; "
        f"{os.cpu_count()} cores; load average {load0[0]:.1f} at the start, {load1[0]:.1f} at "
        "the end (shared machine: other jobs compete for the cores, so these are upper bounds "
        "and the 2-thread rows gain least).",
        "",
        f"N = {a.n}, m = {a.m}, l = {a.l}, horizon {a.horizon}; wall seconds of the compression "
        f"alone, {a.reps} repetitions in one process per row. `factor` is the first 16 hex "
        "digits of the SHA-256 of L: identical across thread counts.",
        "",
        "| compressor | threads | min (s) | median (s) | speed-up (min) | source | factor |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        one = next(x for x in rows if x["compressor"] == r["compressor"] and x["threads"] == 1)
        lines.append(
            f"| {r['compressor']} | {r['threads']} | {r['min']:.3f} | {r['median']:.3f} | "
            f"{one['min'] / r['min']:.2f}x | {r['source']} | `{r['sha']}` |"
        )
    out = HERE / "results" / f"{a.name}.md"
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
