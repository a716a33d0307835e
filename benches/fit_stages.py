"""CPU time of each stage of one default fit (horizon 20, order 8), cold and warm.

    OPENBLAS_NUM_THREADS=1 RAYON_NUM_THREADS=1 python benches/fit_stages.py [--n 100000] [--reps 10]
    python benches/fit_stages.py --m 8 --l 8 --n 1000000 --reps 3     # the 8 x 8 floor case

Times (process CPU, so that a loaded machine inflates them less than wall time) the calls
that ``SubspaceEstimator(IOData(u, y), horizon=20).fit(order=8)`` makes, one by one, then
the public call itself; prints the first round (``cold``: the first fit of the process,
right after ``import sysid``) and the minimum and median over the next repetitions. With one
thread each the CPU time is the work done (docs/performance.md, "Per-fit cost"); wall times
are printed beside (they include waiting for threads on a loaded machine). The record is
the seeded one of benches/full.py (``benches/.data/rec_n<N>_m<m>_l<l>_x8_s2024.npy``,
created when missing).
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
    ap.add_argument("--m", type=int, default=3)
    ap.add_argument("--l", type=int, default=3)
    ap.add_argument("--reps", type=int, default=10)
    a = ap.parse_args()
    sys.path.insert(0, str(HERE))
    from data import generate

    import sysid
    from sysid import _sysid
    from sysid.subspace import estimator as S
    from sysid.validation.feedback import feedback_pvalues

    (HERE / ".data").mkdir(exist_ok=True)
    path = HERE / ".data" / f"rec_n{a.n}_m{a.m}_l{a.l}_x8_s2024.npy"
    if not path.exists():
        np.save(path.with_suffix(".poles.npy"), generate(path, a.n, a.m, a.l, 8, 2024))
    z = np.load(path)
    u, y = np.ascontiguousarray(z[:, : a.m]), np.ascontiguousarray(z[:, a.m :])
    del z
    pt, wt = time.process_time, time.perf_counter

    def stages() -> dict[str, tuple[float, float]]:
        r: dict[str, tuple[float, float]] = {}

        def timed(name: str, fn, *args):  # type: ignore[no-untyped-def]
            t, w = pt(), wt()
            out = fn(*args)
            r[name] = (pt() - t, wt() - w)
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

    cold = stages()
    acc: dict[str, list[tuple[float, float]]] = {}
    for _ in range(a.reps):
        for k, v in stages().items():
            acc.setdefault(k, []).append(v)
    print(f"{a.m} in, {a.l} out, N = {a.n}, horizon 20, order 8; CPU (wall) in ms")
    print(f"{'stage':20s} {'cold':>17s} {'min':>17s} {'median':>17s}")
    for k, v in acc.items():
        cpu = sorted(c for c, _ in v)
        wall = sorted(w for _, w in v)
        h = len(v) // 2
        print(f"{k:20s} {cold[k][0] * 1e3:8.2f} ({cold[k][1] * 1e3:7.2f})"
              f" {cpu[0] * 1e3:8.2f} ({wall[0] * 1e3:7.2f})"
              f" {cpu[h] * 1e3:8.2f} ({wall[h] * 1e3:7.2f})")


if __name__ == "__main__":
    main()
