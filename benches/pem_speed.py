"""Prediction-error refinement speed (issue 28): sysid.pem against a plain SciPy refinement
and against the compute floor, on real and synthetic records.

    .venv/bin/python benches/pem_speed.py                 # all cases, about 10 minutes
    .venv/bin/python benches/pem_speed.py winding cstr    # some cases
    SYSID_SHARED=/path/to/shared .venv/bin/python benches/pem_speed.py   # where ../shared is

Every case refines the same subspace start (MOESP with D, the case's order) by simulation
errors (``focus="simulation"``, ``feedthrough=True``, x0 estimated, ``weighting="identity"``
so that both tools minimise the same sum of squares), as issue 28's table does. Reported per
case, in one run: wall and process CPU time, iterations, evaluations, stop reason and final
cost of ``sysid.pem``; the same for ``scipy.optimize.least_squares`` written as a user would
(all entries of A, B, C, D and x0 as parameters, residuals from ``scipy.signal.dlsim``,
finite-difference Jacobian, ``method="trf"``), run to convergence or for ``SCIPY_BUDGET``
seconds (then marked ``>= ... (stopped)`` with the lowest cost it had reached); when a single
Jacobian takes longer than that, its time is given as a lower bound: seconds per
finite-difference Jacobian (``p + 1`` simulations, measured) times the iterations sysid needed
(marked ``>=``). The floor is the flops of one Gauss-Newton product in identifiable
coordinates (``N l p_id^2``, ``p_id = n (m + l) + l m + n``), times sysid's iterations, at the
GEMM rate numpy reaches in the same run.

Records: the shipped F-16 level 1 (1 x 3, order 20, periods 2-9: 65 536 samples) and winding
(5 x 2, order 6); CSTR (1 x 2, order 5) from ../shared/data/daisy/cstr.dat when present;
synthetic 2 x 28 order 20 (N = 6000) and 6 x 6 order 12 (N = 36 000).
"""

from __future__ import annotations

import json
import os
import sys
import time
import warnings

import numpy as np
from scipy import signal
from scipy.optimize import least_squares

sys.path.insert(0, os.path.dirname(__file__))

from pem import record, system  # noqa: E402

import sysid  # noqa: E402

SCIPY_BUDGET = 60.0  # seconds SciPy may run per case (and one Jacobian may take)
# ../shared next to the checkout (SYSID_SHARED overrides: a worktree sits deeper)
SHARED = os.environ.get("SYSID_SHARED",
                        os.path.join(os.path.dirname(__file__), "..", "..", "shared"))
CSTR = os.path.join(SHARED, "data", "daisy", "cstr.dat")


def gemm_rate() -> float:
    """Flops per second of numpy's matrix product (2 n^3 flops), best of three."""
    a = np.random.default_rng(0).standard_normal((1500, 1500))
    best = np.inf
    for _ in range(3):
        t = time.perf_counter()
        a @ a
        best = min(best, time.perf_counter() - t)
    return 2 * 1500**3 / best


def cases() -> dict[str, tuple[np.ndarray, np.ndarray, int]]:
    out = {}
    f16 = sysid.datasets.load_f16()
    out["f16"] = (f16.u[8192:], f16.y[8192:], 20)
    w = np.loadtxt(sysid.datasets.path("winding"))
    out["winding"] = (w[:, :5], w[:, 5:7], 6)
    if os.path.exists(CSTR):
        c = np.loadtxt(CSTR)
        out["cstr"] = (c[:, 1:2], c[:, 2:4], 5)
    for key, (n, m, l, N) in {"synthetic 2x28": (20, 2, 28, 6000),
                              "synthetic 6x6": (12, 6, 6, 36000)}.items():
        u, y = record(system(n, m, l, 1), N, 2)
        out[key] = (u, y, n)
    return {k: (u - u.mean(0), y - y.mean(0), n) for k, (u, y, n) in out.items()}


def start_model(u, y, n):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return sysid.SubspaceEstimator(sysid.IOData(u=u, y=y)).fit(n, method="moesp",
                                                                   feedthrough=True)


def run_sysid(u, y, start):
    c0, t0 = time.process_time(), time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", getattr(sysid, "IterationLimitWarning", UserWarning))
        m = sysid.pem((u, y), start, focus="simulation", feedthrough=True,
                      weighting="identity", max_iter=100)
    info = m.info["pem"]
    return {"wall_s": round(time.perf_counter() - t0, 2),
            "cpu_s": round(time.process_time() - c0, 2), "iterations": info["iterations"],
            "evaluations": info["evaluations"], "stop": info["stop"],
            "start_cost": info["cost"][0], "final_cost": info["cost"][-1]}


def scipy_problem(u, y, start):
    """The refinement a user writes: every entry a parameter, dlsim residuals."""
    n, m, l = start.nstates, start.ninputs, start.noutputs
    shapes = ((n, n), (n, m), (l, n), (l, m), (n, 1))

    def unpack(th):
        o, out = 0, []
        for r, c in shapes:
            out.append(th[o:o + r * c].reshape(r, c))
            o += r * c
        return out

    def resid(th):
        A, B, C, D, x0 = unpack(th)
        _, yh, _ = signal.dlsim((A, B, C, D, 1.0), u, x0=x0[:, 0])
        r = (y - yh).ravel()
        return r if np.all(np.isfinite(r)) else np.full(y.size, 1e6)

    x0 = np.zeros(n)
    th0 = np.concatenate([start.A.ravel(), start.B.ravel(), start.C.ravel(), start.D.ravel(),
                          x0])
    return resid, th0


class _OutOfTime(Exception):
    pass


def run_scipy(u, y, start, sysid_iterations):
    """least_squares to convergence, or until SCIPY_BUDGET seconds (then the lowest cost it
    had evaluated, marked as stopped); a lower bound from one Jacobian's cost when even one
    Jacobian exceeds the budget."""
    resid, th0 = scipy_problem(u, y, start)
    t = time.perf_counter()
    resid(th0)
    per_jac = (time.perf_counter() - t) * (th0.size + 1)
    if per_jac > SCIPY_BUDGET:
        return {"s_per_jacobian": round(per_jac, 2),
                "wall_s": f">= {per_jac * sysid_iterations:.0f}", "iterations": None,
                "final_cost": None}
    best = [np.inf, 0]
    c0, t0 = time.process_time(), time.perf_counter()

    def timed(th):
        if time.perf_counter() - t0 > SCIPY_BUDGET:
            raise _OutOfTime
        r = resid(th)
        best[0] = min(best[0], 0.5 * float(r @ r))
        best[1] += 1
        return r

    out = {"s_per_jacobian": round(per_jac, 2)}
    try:
        r = least_squares(timed, th0, method="trf")
        out.update(wall_s=round(time.perf_counter() - t0, 2), iterations=int(r.njev),
                   final_cost=float(r.cost), status=r.message)
    except _OutOfTime:
        out.update(wall_s=f">= {SCIPY_BUDGET:.0f} (stopped)", iterations=None,
                   final_cost=best[0], evaluations=best[1])
    out["cpu_s"] = round(time.process_time() - c0, 2)
    return out


def floor_s(u, y, n, iterations, rate):
    N, m = u.shape
    l = y.shape[1]
    p_id = n * (m + l) + l * m + n
    return N * l * p_id**2 * max(iterations, 1) / rate


def main(which: list[str]) -> None:
    rate = gemm_rate()
    print(json.dumps({"gemm_gflops": round(rate / 1e9, 1), "load": os.getloadavg()[0]}),
          flush=True)
    for name, (u, y, n) in cases().items():
        if which and name.split()[0] not in which and name not in which:
            continue
        start = start_model(u, y, n)
        s = run_sysid(u, y, start)
        sc = run_scipy(u, y, start, s["iterations"])
        fl = floor_s(u, y, n, s["iterations"], rate)
        row = {"case": name, "N": len(u), "m": u.shape[1], "l": y.shape[1], "n": n,
               "sysid": s, "scipy": sc, "floor_s": round(fl, 3),
               "sysid_over_floor": round(s["wall_s"] / fl, 1)}
        if isinstance(sc["wall_s"], float):
            row["speedup_vs_scipy"] = round(sc["wall_s"] / s["wall_s"], 1)
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
