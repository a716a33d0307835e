"""Prediction-error refinement: sysid.pem against a plain SciPy least_squares refinement.

    .venv/bin/python benches/pem.py            # about four minutes on a shared machine

The SciPy refinement is written as a user would: all entries of A, B, C, K and x0 as
parameters, the prediction errors of the innovation predictor as residuals, a finite-difference
Jacobian, method="trf". Both start from the same perturbed true model and are given the same
iteration budget. Large cases are timed per Gauss-Newton iteration on a shortened record and
scaled linearly in N (both methods are linear in N); peak memory is measured in a subprocess
at two record lengths to show it does not grow with N.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time

import numpy as np
from scipy.optimize import least_squares

import sysid


def system(n: int, m: int, l: int, seed: int) -> sysid.StateSpaceModel:
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    B = rng.standard_normal((n, m))
    C = rng.standard_normal((l, n))
    K = 0.1 * rng.standard_normal((n, l))
    while max(abs(np.linalg.eigvals(A - K @ C))) >= 0.95:
        K *= 0.5
    return sysid.StateSpaceModel(A, B, C, np.zeros((l, m)), K)


def record(true: sysid.StateSpaceModel, N: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    m, l = true.ninputs, true.noutputs
    u = rng.standard_normal((N, m))
    e = 0.1 * rng.standard_normal((N, l))
    Ba, Da = np.hstack([true.B, true.K]), np.hstack([true.D, np.eye(l)])
    y = sysid._sysid.simulate(true.A, Ba, true.C, Da, np.hstack([u, e]), None)
    return u, y


def perturbed(true: sysid.StateSpaceModel, eps: float, seed: int) -> sysid.StateSpaceModel:
    rng = np.random.default_rng(seed)
    A = true.A + eps * rng.standard_normal(true.A.shape)
    A *= min(1.0, 0.95 / max(abs(np.linalg.eigvals(A))))
    return sysid.StateSpaceModel(A, true.B + eps * rng.standard_normal(true.B.shape),
                                 true.C + eps * rng.standard_normal(true.C.shape), true.D, true.K)


def scipy_refine(start: sysid.StateSpaceModel, u: np.ndarray, y: np.ndarray,
                 max_nfev: int) -> tuple[float, int]:
    """The plain refinement a user would write (returns seconds and Jacobian evaluations)."""
    n, m, l = start.nstates, start.ninputs, start.noutputs

    def unpack(th):
        o = 0
        out = []
        for r, c in ((n, n), (n, m), (l, n), (n, l), (n, 1)):
            out.append(th[o:o + r * c].reshape(r, c))
            o += r * c
        return out

    def resid(th):
        A, B, C, K, x0 = unpack(th)
        try:
            yh = sysid._sysid.predict(A, B, C, np.zeros((l, m)), K, u, y, x0[:, 0], 1)
        except sysid.NumericalError:  # an unstable predictor: a large residual
            return np.full(y.size, 1e3)
        return (y - yh).ravel()

    th0 = np.concatenate([start.A.ravel(), start.B.ravel(), start.C.ravel(), start.K.ravel(),
                          np.zeros(n)])
    t = time.perf_counter()
    r = least_squares(resid, th0, method="trf", max_nfev=max_nfev)
    return time.perf_counter() - t, int(r.njev)


def sysid_refine(start, u, y, max_iter):
    t = time.perf_counter()
    m = sysid.pem((u, y), start, max_iter=max_iter, weighting="identity")
    return time.perf_counter() - t, m.info["pem"]


def case(n, m, l, N, iters, run_scipy=True):
    true = system(n, m, l, 1)
    u, y = record(true, N, 2)
    start = perturbed(true, 0.02, 3)
    ts, info = sysid_refine(start, u, y, iters)
    out = {"n": n, "m": m, "l": l, "N": N, "sysid_s": ts, "sysid_iterations": info["iterations"],
           "sysid_s_per_iteration": ts / max(info["iterations"], 1)}
    if run_scipy:
        tsc, njev = scipy_refine(start, u, y, iters)
        out.update({"scipy_s": tsc, "scipy_jacobians": njev,
                    "scipy_s_per_jacobian": tsc / max(njev, 1)})
    return out


def peak_rss(N: int) -> float:
    """Peak resident memory (MB) of a fresh process that refines one iteration on N samples."""
    r = subprocess.run([sys.executable, __file__, "--rss", str(N)], capture_output=True,
                       text=True, check=True)
    return float(r.stdout.strip())


def _rss_child(N: int) -> None:
    t = system(8, 3, 3, 1)
    u, y = record(t, N, 2)
    sysid_refine(perturbed(t, 0.02, 3), u, y, 1)
    # VmHWM (not ru_maxrss, which Linux carries over from the parent across exec)
    with open("/proc/self/status") as f:
        hwm = next(line for line in f if line.startswith("VmHWM"))
    print(int(hwm.split()[1]) / 1024)


def subspace_start(u: np.ndarray, y: np.ndarray, n: int) -> sysid.StateSpaceModel:
    """The start a user (and ``sysid.ssest``) refines: a subspace estimate with its K."""
    from sysid.subspace.estimator import SubspaceEstimator

    return SubspaceEstimator(sysid.IOData(u=u, y=y), None).fit(n, method="moesp",
                                                               feedthrough=False)


def timed_pem(u, y, start, **kw):
    """Refine, recording the time and cost of every iteration."""
    marks = []
    t = time.perf_counter()
    m = sysid.pem((u, y), start, progress=lambda it, cost, *a: marks.append(
        (it, round(time.perf_counter() - t, 2), cost)), **kw)
    return time.perf_counter() - t, m, marks


def main() -> None:
    res = {}
    res["small 4x(2,2) N=2000"] = case(4, 2, 2, 2000, 20)
    # order 20, 2 inputs, 28 outputs, N = 6000, from the subspace start; W = I so that both
    # minimise the same cost. SciPy: one finite-difference Jacobian on 600 samples, x10.
    true = system(20, 2, 28, 1)
    u, y = record(true, 6000, 2)
    start = subspace_start(u, y, 20)
    ts, m, marks = timed_pem(u, y, start, max_iter=10, weighting="identity")
    info = m.info["pem"]
    big = {"start_cost": info["weighted_cost"][0], "noise_floor": 0.5 * y.size * 0.01,
           "sysid_s": ts, "iterations (it, s, cost)": marks, "sysid_stop": info["stop"],
           "jacobians": info.get("evaluations")}
    tsc, njev = scipy_refine(start, u[:600], y[:600], 1)
    big["scipy_s_per_jacobian_N6000"] = 10 * tsc / max(njev, 1)
    res["order 20 (2,28) N=6000"] = big
    # the same with the default (determinant) criterion
    ts, m, marks = timed_pem(u, y, start, max_iter=10)
    res["order 20 (2,28) N=6000, determinant criterion"] = {
        "sysid_s": ts, "iterations (it, s, cost)": marks, "stop": m.info["pem"]["stop"]}
    # order 8, 3 inputs, 3 outputs, N = 1e6: measured, default options, subspace start
    true = system(8, 3, 3, 1)
    u, y = record(true, 1_000_000, 2)
    t = time.perf_counter()
    start = subspace_start(u, y, 8)
    t_sub = time.perf_counter() - t
    ts, m, marks = timed_pem(u, y, start)
    res["order 8 (3,3) N=1e6"] = {"subspace_s": t_sub, "pem_s": ts, "stop": m.info["pem"]["stop"],
                                  "iterations (it, s, cost)": marks}
    key = "peak RSS MB, order 8 (3,3), N=1e4 / 1e5 (record: 0.5 / 4.6 MB)"
    res[key] = [peak_rss(10_000), peak_rss(100_000)]
    print(json.dumps(res, indent=1))


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--rss":
        _rss_child(int(sys.argv[2]))
    else:
        main()
