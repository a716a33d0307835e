"""CPU time of each stage of one default fit (3 in, 3 out, horizon 20, order 8, N = 10^5).

    OPENBLAS_NUM_THREADS=1 RAYON_NUM_THREADS=1 python benches/fit_stages.py [--n 100000] [--reps 10]

Times (process CPU, so that a loaded machine inflates them less than wall time) the calls
that ``SubspaceEstimator(IOData(u, y), horizon=20).fit(order=8)`` makes, one by one, then
the public call itself; prints the minimum and median over the repetitions. With one thread
each the CPU time is the work done (docs/performance.md, "Per-fit cost").
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=100_000)
    ap.add_argument("--reps", type=int, default=10)
    a = ap.parse_args()
    sys.path.insert(0, str(HERE))
    from data import generate

    import sysid
    from sysid import _sysid
    from sysid.analysis.feedback import feedback_pvalues
    from sysid.estimate import subspace as S

    (HERE / ".data").mkdir(exist_ok=True)
    path = HERE / ".data" / f"stages_n{a.n}.npy"
    if not path.exists():
        generate(path, a.n, 3, 3, 8, 2024)
    z = np.load(path)
    u, y = np.ascontiguousarray(z[:, :3]), np.ascontiguousarray(z[:, 3:])
    pt = time.process_time

    def stages() -> dict[str, float]:
        r: dict[str, float] = {}

        def timed(name: str, fn, *args):  # type: ignore[no-untyped-def]
            t = pt()
            out = fn(*args)
            r[name] = pt() - t
            return out

        d = timed("IOData", lambda: sysid.IOData(u=u, y=y))
        timed("channel checks", S._check_signals, d)
        f = timed("compression", _sysid.compress, d.experiments, 20, 20, None, "auto")
        sub = timed("weighted SVD", _sysid.Subspace, f, "moesp")
        timed("feedback test", feedback_pvalues, f)
        est = S.SubspaceEstimator.__new__(S.SubspaceEstimator)
        est.factor, est._pe_cache = f, {}
        timed("excitation check", est._excitation_order, 16)
        timed("A, B, C, D, K", sub.fit, 8, True, True, False)
        timed("whole public call",
              lambda: sysid.SubspaceEstimator(d, horizon=20).fit(order=8))
        return r

    stages()
    acc: dict[str, list[float]] = {}
    for _ in range(a.reps):
        for k, v in stages().items():
            acc.setdefault(k, []).append(v)
    for k, v in acc.items():
        v.sort()
        print(f"{k:20s} min {v[0] * 1e3:7.2f} ms   median {v[len(v) // 2] * 1e3:7.2f} ms")


if __name__ == "__main__":
    main()
