"""What the second start of ``oe`` and ``bj`` costs: one input and output, each fitted from
Steiglitz-McBride alone (the estimators' search before they also tried a subspace start)
and as ``sysid.oe`` / ``sysid.bj`` fit now (both starts, the lower criterion kept), on the
data of benches/polynomial.py (OE(2,2,1) and BJ(2,1,1,2,1) at their true orders), best of 3
runs (1 at 10^6 samples), in one process.

    .venv/bin/python benches/polynomial_starts.py [--sizes 1000 10000 100000 1000000]
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np
from scipy import signal

import sysid
from sysid.polynomial.estimators import _pem


def make(n: int, seed: int) -> sysid.IOData:
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n)
    e = 0.1 * rng.standard_normal(n)
    y = signal.lfilter([0, 0.5, 0.3], [1, -1.2, 0.5], u) + signal.lfilter([1, 0.4], [1, -0.6], e)
    return sysid.IOData(u[:, None], y[:, None], 1.0)


def best_time(f, repeats: int):
    best, m = np.inf, None
    for _ in range(repeats):
        t = time.perf_counter()
        m = f()
        best = min(best, time.perf_counter() - t)
    return best, m


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000, 100000, 1000000])
    sizes = ap.parse_args().sizes
    print("| N | structure | one start s | two starts s | ratio | same model | start kept |")
    print("|---|---|---|---|---|---|---|")
    warnings.simplefilter("ignore")
    for n in sizes:
        d = make(n, 1)
        cases = (("OE", lambda d=d: _pem(d, 0, 2, 0, 0, 2, 1, "oe", 100, False, None),
                  lambda d=d: sysid.oe(d, 2, 2, 1, progress=False)),
                 ("BJ", lambda d=d: _pem(d, 0, 2, 1, 1, 2, 1, "bj", 100, False, None),
                  lambda d=d: sysid.bj(d, 2, 1, 1, 2, 1, progress=False)))
        for name, one, two in cases:
            r = 3 if n < 10**6 else 1
            t1, m1 = best_time(one, r)
            t2, m2 = best_time(two, r)
            same = m1.info["cost"][0][-1] == m2.info["cost"][0][-1]
            print(f"| {n} | {name} | {t1:.3f} | {t2:.3f} | {t2 / t1:.2f} | {same} | "
                  f"{m2.info['start']} |", flush=True)


if __name__ == "__main__":
    main()
