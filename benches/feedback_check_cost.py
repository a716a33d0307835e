"""What the output-error fits' feedback check (:mod:`sysid.validation.output_error`) costs
beside the fit: per shipped record and on a 50 000-sample synthetic record, the seconds of
the check alone (``feedback_test``, the median of 5) and of each fit with it (the median of 3),
and the check's share of the fit.

Usage::

    PYTHONPATH=python python benches/feedback_check_cost.py
"""

from __future__ import annotations

import time
import warnings

import numpy as np

import sysid
from sysid.validation.output_error import feedback_test


def records() -> dict:
    d = sysid.datasets
    out = {name: getattr(d, f"load_{name}")() for name in
           ("dryer", "robot_arm", "winding", "ballbeam", "ph")}
    out["f16 (decimated 8)"] = sysid.decimate(d.load_f16(), 8)
    out["f16_level3 (decimated 8)"] = sysid.decimate(d.load_f16_level3(), 8)
    rng = np.random.default_rng(0)
    n = 50_000
    r, e = rng.standard_normal(n), 0.5 * rng.standard_normal(n)
    u, y, x = np.zeros(n), np.zeros(n), 0.0
    for t in range(n):
        y[t] = x + e[t]
        u[t] = r[t] - 0.5 * y[t - 1] if t else r[t]
        x = 0.9 * x + 0.5 * u[t]
    out["synthetic closed loop, 50 000"] = sysid.IOData(u=u, y=y, dt=1.0)
    return out


def median_time(fn, k: int) -> float:
    ts = []
    for _ in range(k):
        t = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t)
    return float(np.median(ts))


def main() -> None:
    print("| record | N | check s | fit | fit s (with the check) | check share |")
    print("|---|---|---|---|---|---|")
    for name, data in records().items():
        data = sysid.detrend(data, "constant")
        siso = data.n_inputs == 1 and data.n_outputs == 1
        fits = {"ssest(4, focus='simulation')":
                lambda d=data: sysid.ssest(d, 4, focus="simulation")}
        if siso:
            fits["oe(3,3,1)"] = lambda d=data: sysid.oe(d, 3, 3, 1)
            fits["tfest(3)"] = lambda d=data: sysid.tfest(d, 3)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            check = median_time(lambda d=data: feedback_test(d), 5)
            for fit_name, fit in fits.items():
                t = median_time(fit, 3)
                print(f"| {name} | {data.n_samples} | {check:.3f} | {fit_name} | {t:.2f} | "
                      f"{100 * check / t:.1f} % |", flush=True)


if __name__ == "__main__":
    main()
