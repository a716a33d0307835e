"""Polynomial estimators against SIPPY (sippy-unipi): time, peak memory, validation fit.

    .venv/bin/python benches/polynomial.py [--sizes 1000 10000 100000 1000000] [--timeout 240]
        [--cases ARX OE ...]

Every case runs in a fresh process (sysid in .venv, SIPPY in benches/.venv-peers) so the peak
resident memory (ru_maxrss, which includes the interpreter and imports) belongs to that case
alone. The data: u white, y = B/F u(t-1) + C/D e with B = 0.5 + 0.3 q^-1,
F = 1 - 1.2 q^-1 + 0.5 q^-2, C = 1 + 0.4 q^-1, D = 1 - 0.6 q^-1, e with std 0.1; the fit is
the simulation fit (percent) on a separate 5000-sample validation record. Structures at the
true orders: ARX(2,2,1), ARMAX(2,2,2,1) (SIPPY ILLS and OPT), OE(2,2,1), BJ(2,1,1,2,1).
Short runs on a shared machine: read the ratios, not the absolute times; the CPU columns
(user + system time of the estimating call, summed over threads) are less sensitive to the
load than the wall times, and the load average is printed first. SIPPY cases that exceed
``--timeout`` are reported as such (at 10^6 samples its CasADi routes do not finish).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE))
from run import ensure_peers  # noqa: E402

COMMON = r"""
import json, resource, sys, time
import numpy as np
from scipy import signal
n, case = int(sys.argv[1]), sys.argv[2]
def make(n, seed):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n); e = 0.1 * rng.standard_normal(n)
    y = signal.lfilter([0, 0.5, 0.3], [1, -1.2, 0.5], u) + signal.lfilter([1, 0.4], [1, -0.6], e)
    return u, y
u, y = make(n, 1)
uv, yv = make(5000, 2)
def fit(ys):
    return float(100 * (1 - np.linalg.norm(yv - ys) / np.linalg.norm(yv - yv.mean())))
"""

SYSID = (
    COMMON
    + r"""
import sysid
d = sysid.IOData(u[:, None], y[:, None], 1.0)
t0, c0 = time.perf_counter(), time.process_time()
if case == "ARX": m = sysid.arx(d, 2, 2, 1)
elif case == "ARMAX": m = sysid.armax(d, 2, 2, 2, 1)
elif case == "OE": m = sysid.oe(d, 2, 2, 1)
elif case == "BJ": m = sysid.bj(d, 2, 1, 1, 2, 1)
sec, cpu = time.perf_counter() - t0, time.process_time() - c0
f = fit(m.simulate(uv[:, None])[:, 0])
print(json.dumps({"seconds": sec, "cpu": cpu, "fit": f,
                  "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""
)

SIPPY = (
    COMMON
    + r"""
from sippy_unipi import system_identification as si
import control
t0, c0 = time.perf_counter(), time.process_time()
if case == "ARX": m = si(y, u, "ARX", ARX_orders=[2, 2, 0])
elif case == "ARMAX-ILLS": m = si(y, u, "ARMAX", ARMAX_orders=[2, 2, 2, 0], ARMAX_mod="ILLS")
elif case == "ARMAX-OPT": m = si(y, u, "ARMAX", ARMAX_orders=[2, 2, 2, 0], ARMAX_mod="OPT")
elif case == "OE": m = si(y, u, "OE", OE_orders=[2, 2, 0], OE_mod="OPT")
elif case == "BJ": m = si(y, u, "BJ", BJ_orders=[2, 1, 1, 2, 0])
sec, cpu = time.perf_counter() - t0, time.process_time() - c0
ys = np.asarray(control.forced_response(m.G, U=uv).outputs).ravel()
print(json.dumps({"seconds": sec, "cpu": cpu, "fit": fit(ys),
                  "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""
)

CASES = [
    ("ARX", "ARX"),
    ("ARMAX", "ARMAX-ILLS"),
    ("ARMAX", "ARMAX-OPT"),
    ("OE", "OE"),
    ("BJ", "BJ"),
]


def run(py: str, code: str, n: int, case: str, timeout: float) -> dict:
    try:
        r = subprocess.run(
            [py, "-c", code, str(n), case], capture_output=True, text=True, timeout=timeout
        )
    except subprocess.TimeoutExpired:
        return {"error": f"timeout {timeout:.0f} s"}
    if r.returncode != 0:
        return {"error": (r.stderr.strip().splitlines() or ["failed"])[-1][:80]}
    return json.loads(r.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000, 100000, 1000000])
    ap.add_argument("--timeout", type=float, default=240)
    ap.add_argument("--cases", nargs="+", default=None,
                    help="SIPPY routes to run (ARX ARMAX-ILLS ARMAX-OPT OE BJ); default all")
    args = ap.parse_args()
    peers = ensure_peers()
    ours_py = sys.executable
    cases = [c for c in CASES if args.cases is None or c[1] in args.cases]
    print(f"load average at start: {' '.join(f'{v:.2f}' for v in os.getloadavg())} "
          f"on {os.cpu_count()} CPUs\n")
    print(
        "| N | structure | sysid s | sysid CPU s | SIPPY route | SIPPY s | SIPPY CPU s "
        "| speed-up | sysid MB | SIPPY MB | sysid fit % | SIPPY fit % |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    done: dict = {}
    for n in args.sizes:
        for ours_case, peer_case in cases:
            key = (n, ours_case)
            if key not in done:
                done[key] = run(ours_py, SYSID, n, ours_case, args.timeout)
            a = done[key]
            b = run(str(peers), SIPPY, n, peer_case, args.timeout) if peers else {"error": "-"}

            def g(r: dict, k: str, f: str) -> str:
                return format(r[k], f) if k in r else r.get("error", "-")

            ratio = (
                f"{b['seconds'] / a['seconds']:.0f}x" if "seconds" in a and "seconds" in b else "-"
            )
            print(
                f"| {n} | {ours_case} | {g(a, 'seconds', '.3f')} | {g(a, 'cpu', '.3f')} | "
                f"{peer_case} | {g(b, 'seconds', '.3f')} | {g(b, 'cpu', '.3f')} | {ratio} | "
                f"{g(a, 'peak_mb', '.0f')} | "
                f"{g(b, 'peak_mb', '.0f')} | {g(a, 'fit', '.2f')} | {g(b, 'fit', '.2f')} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
