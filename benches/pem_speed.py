"""Prediction-error refinement speed (issue 28): sysid.pem against a plain SciPy refinement
and against the compute floor, on real and synthetic records.

    .venv/bin/python benches/pem_speed.py                 # all cases, about 10 minutes
    .venv/bin/python benches/pem_speed.py winding cstr    # some cases
    .venv/bin/python benches/pem_speed.py "synthetic 2x28" --scipy-budget=900  # SciPy longer
    .venv/bin/python benches/pem_speed.py f16 --converge  # a capped search also run to its end
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
synthetic 2 x 28 order 20 (N = 6000) and 6 x 6 order 12 (N = 36 000). The F-16 case has a
second row: the same start refined in the frequency domain on the excited lines of its 8
periods (``sysid.pem(data, start, periods=8)``), and a third: the same time-domain search
from the start ``sysid.ssest(data, 20, focus="simulation", feedthrough=True)`` takes (on
this periodic record the fit to its averaged lines scores best of its candidates), SciPy
from that start too; the F-16 rows report the validation simulation fit on the shipped
level-2 record.

The other estimators that share the optimiser (``greyest``, ``oe``, ``nlhw``) are measured on
synthetic records (see :func:`other_cases`) against ``least_squares`` over the same parameters
from the same start; each row also gives the SciPy residual's cost at sysid's solution, the
check that both minimise the same sum of squares. ``nlhw``'s call also fits its linear start
and searches from several starts: its row gives the chosen start's search alone too
(``search_wall_s``), the time to set against SciPy's from that start.
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
CONVERGE = False  # --converge (below)
# ../shared next to the checkout (SYSID_SHARED overrides: a worktree sits deeper)
SHARED = os.environ.get("SYSID_SHARED",
                        os.path.join(os.path.dirname(__file__), "..", "..", "shared"))
CSTR = os.path.join(SHARED, "data", "daisy", "cstr.dat")
# periodic records: whole periods in each case's estimation record (a second row refines the
# same start in the frequency domain on the excited lines, ``sysid.pem(..., periods=P)``)
PERIODS = {"f16": 8}


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


def ssest_start(u, y, n):
    """The start ``sysid.ssest(..., focus="simulation", feedthrough=True)`` takes (the
    subspace weightings and, when the input repeats, the fit to the averaged lines, scored
    by the simulation loss), returned by a call with ``max_iter=0``, and its name."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = sysid.ssest(sysid.IOData(u=u, y=y), n, focus="simulation", feedthrough=True,
                        max_iter=0)
    return m, m.info["start"]["method"]


def converged_cost(u, y, start, max_iter=3000):
    """``--converge``: the same time-domain search run to its own convergence (up to
    ``max_iter`` iterations): the lowest cost it reaches, against which the capped row's
    final cost is judged (issue 28's "within 0.1 % of the best cost")."""
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = sysid.pem((u, y), start, focus="simulation", feedthrough=True,
                      weighting="identity", max_iter=max_iter)
    info = m.info["pem"]
    return {"cost": info["cost"][-1], "iterations": info["iterations"], "stop": info["stop"],
            "wall_s": round(time.perf_counter() - t0, 1)}, m


def run_sysid(u, y, start, periods=None):
    """sysid.pem from ``start``: simulation errors in the time domain, or (``periods``) the
    frequency-domain fit on the excited lines of the periodic record; returns (row, model)."""
    # the process CPU clock also counts threads an earlier NumPy/SciPy call left spinning
    # (OpenBLAS's idle workers spin ~0.1 s after each threaded call): let them settle
    time.sleep(0.3)
    c0, t0 = time.process_time(), time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", getattr(sysid, "IterationLimitWarning", UserWarning))
        if periods is None:
            m = sysid.pem((u, y), start, focus="simulation", feedthrough=True,
                          weighting="identity", max_iter=100)
        else:
            m = sysid.pem(sysid.IOData(u=u, y=y), start, periods=periods, feedthrough=True,
                          max_iter=100)
    info = m.info["pem"]
    row = {"wall_s": round(time.perf_counter() - t0, 2),
           "cpu_s": round(time.process_time() - c0, 2), "iterations": info["iterations"],
           "evaluations": info["evaluations"], "stop": info["stop"],
           "criterion": info["criterion"], "start_cost": info["cost"][0],
           "final_cost": info["cost"][-1]}
    if periods is not None:
        # the time-domain criterion of the other row (1/2 sum |e|^2 of the simulation errors,
        # x0 fitted) at this model, so that both rows can be compared on one cost
        td = sysid.pem_loss((u, y), m, focus="simulation", feedthrough=True,
                            weighting="identity")
        row.update(lines=info["lines"], residual_scale=round(info["residual_scale"], 2),
                   time_domain_cost=td)
    return row, m


def validation_fit(name, model):
    """Validation simulation fit (%, mean over outputs, x0 fitted by least squares) on the
    case's validation record: for the F-16, the shipped level-2 record (periods 2-3), means
    removed."""
    if name != "f16":
        return None
    v = sysid.datasets.load_f16_level2()
    val = sysid.IOData(u=v.u - v.u.mean(0), y=v.y - v.y.mean(0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return round(float(np.mean(sysid.compare(model, val).fit)), 2)


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
    return {"s_per_jacobian": round(per_jac, 2), **_scipy_fit(resid, th0)}


def floor_s(u, y, n, iterations, rate):
    N, m = u.shape
    l = y.shape[1]
    p_id = n * (m + l) + l * m + n
    return N * l * p_id**2 * max(iterations, 1) / rate


# --- the other estimators on the same optimiser (issue 28: "measure each") -----------------

def _two_mass(p, dt=None):
    """Two masses, springs k1, k2 and dampers c1, c2: force on mass 1, position of mass 2."""
    k1, k2, c1, c2 = p.k1, p.k2, p.c1, p.c2
    A = [[0, 1, 0, 0], [-(k1 + k2), -(c1 + c2), k2, c2], [0, 0, 0, 1], [k2, c2, -k2, -c2]]
    return A, [[0], [1], [0], [0]], [[0, 0, 1, 0]], [[0]]


GREY_TRUE = {"k1": 4.0, "k2": 2.5, "c1": 0.08, "c2": 0.05}
GREY_START = {"k1": 3.4, "k2": 2.9, "c1": 0.15, "c2": 0.02}


def other_cases() -> dict[str, tuple]:
    """greyest (two-mass structure, 4 parameters, N = 20 000), oe (4th order, one input,
    N = 20 000) and nlhw (saturation before a 2nd-order OE block, N = 20 000)."""
    rng = np.random.default_rng(7)
    N, dt = 20000, 0.1
    out = {}
    u = rng.standard_normal((N, 1))
    true = sysid.GreyBox(_two_mass, GREY_TRUE).model(dt=dt)
    y = true.simulate(u) + 0.01 * rng.standard_normal((N, 1))
    out["greyest"] = (u, y, dt)
    b, f = [0.0, 0.5, 0.3, 0.2, 0.1], [1.0, -1.6, 1.45, -0.6, 0.2]
    u = rng.standard_normal(N)
    y = signal.lfilter(b, f, u) + 0.1 * rng.standard_normal(N)
    out["oe"] = (u[:, None], y[:, None], 1.0)
    u = rng.uniform(-1, 1, N)
    w = np.clip(u, -0.4, 0.6)
    y = signal.lfilter([0.0, 0.5, 0.25], [1.0, -1.2, 0.5], w) + 0.02 * rng.standard_normal(N)
    out["nlhw"] = (u[:, None], y[:, None], 1.0)
    return out


def _timed(fn):
    time.sleep(0.3)  # as in run_sysid: idle BLAS threads of an earlier call settle first
    c0, t0 = time.process_time(), time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = fn()
    return out, round(time.perf_counter() - t0, 2), round(time.process_time() - c0, 2)


def _scipy_fit(resid, th0):
    """least_squares as a user writes it, to convergence or SCIPY_BUDGET seconds (then the
    lowest cost it had evaluated and the evaluations, marked as stopped)."""
    best = [np.inf, 0]
    c0, t0 = time.process_time(), time.perf_counter()

    def timed(th):
        if time.perf_counter() - t0 > SCIPY_BUDGET:
            raise _OutOfTime
        r = resid(th)
        best[0] = min(best[0], 0.5 * float(r @ r))
        best[1] += 1
        return r

    try:
        r = least_squares(timed, th0, method="trf")
        out = {"wall_s": round(time.perf_counter() - t0, 2), "iterations": int(r.njev),
               "final_cost": float(r.cost), "status": r.message}
    except _OutOfTime:
        out = {"wall_s": f">= {SCIPY_BUDGET:.0f} (stopped)", "iterations": None,
               "final_cost": best[0], "evaluations": best[1]}
    out["cpu_s"] = round(time.process_time() - c0, 2)
    return out


def run_other(name, u, y, dt):
    """(sysid result, SciPy result, the SciPy residual's cost at sysid's solution: the check
    that both tools minimise the same sum of squares)."""
    data = sysid.IOData(u=u, y=y, dt=dt)
    if name == "greyest":
        s = sysid.GreyBox(_two_mass, GREY_START)
        est, wall, cpu = _timed(lambda: sysid.greyest(data, s, focus="simulation", x0="zero",
                                                      weighting="identity", max_iter=100))
        info = est.info

        def resid(th):
            m = sysid.GreyBox(_two_mass, dict(zip(GREY_START, th))).model(dt=dt)
            r = (y - signal.dlsim((m.A, m.B, m.C, m.D, dt), u)[1]).ravel()
            return r if np.all(np.isfinite(r)) else np.full(y.size, 1e6)
        th0 = np.array(list(GREY_START.values()))
        th_sysid = np.asarray(est.parameters.value, float)
        cost, it = info["cost"][-1], info["iterations"]
    elif name == "oe":
        arx = sysid.arx(data, 4, 4, 1)
        m, wall, cpu = _timed(lambda: sysid.oe(data, 4, 4, 1, init=arx, max_iter=100))
        info = m.info

        def resid(th):
            r = y[:, 0] - signal.lfilter(np.r_[0.0, th[:4]], np.r_[1.0, th[4:]], u[:, 0])
            return r if np.all(np.isfinite(r)) else np.full(y.size, 1e6)
        th0 = np.r_[np.ravel(arx.b[0][0])[-4:], np.ravel(arx.a[0][0])[-4:]]
        th_sysid = np.r_[np.ravel(m.b[0][0])[-4:], np.ravel(m.f[0][0])[-4:]]
        cost, it = info["cost"][0][-1], info["iterations"][0]
    else:
        m, wall, cpu = _timed(lambda: sysid.nlhw(data, 2, 2, 1, input_nl=sysid.Saturation(),
                                                 output_nl=None, max_iter=100))
        info = m.info

        def resid(th):
            w = np.clip(u[:, 0], th[0], th[1])
            r = y[:, 0] - signal.lfilter(np.r_[0.0, th[2:4]], np.r_[1.0, th[4:6]], w)
            return r if np.all(np.isfinite(r)) else np.full(y.size, 1e6)
        th0 = np.asarray(info["theta0"], float)
        th_sysid = np.r_[m.input_nl.params, m.b, m.f]
        cost, it = info["cost"][-1], info["iterations"]
    r = resid(th_sysid)
    check = 0.5 * float(r @ r)
    s_out = {"wall_s": wall, "cpu_s": cpu, "iterations": it, "stop": info["stop"],
             "final_cost": cost}
    if name == "nlhw":  # the call's time holds its linear start and every start's search;
        # SciPy runs from the chosen start alone, as this search did
        sec = info["seconds"]
        s_out.update(linear_start_s=round(sec["linear_start"], 3),
                     searches_s=[round(t, 3) for t in sec["searches"]],
                     search_wall_s=round(sec["chosen_start_search"], 3))
    return s_out, _scipy_fit(resid, th0), check


def greyest_periodic() -> dict:
    """The greyest case made periodic: the two-mass structure under a multisine of 2000
    samples per period, 10 periods in steady state (N = 20 000, dt = 0.1, output noise 0.01),
    fitted in the time domain (simulation errors, x0 estimated, the noise weighting) and on
    the excited lines (``periods=10``), from the same start."""
    dt, n_per, P = 0.1, 2000, 10
    u = sysid.multisine(n_per, band=(0, 0.5), periods=P, seed=3)
    true = sysid.GreyBox(_two_mass, GREY_TRUE).model(dt=dt)
    y = true.simulate(np.vstack([np.tile(u[:n_per], (5, 1)), u]))[5 * n_per:]
    y = y + 0.01 * np.random.default_rng(8).standard_normal(y.shape)
    data = sysid.IOData(u=u, y=y, dt=dt)
    s = sysid.GreyBox(_two_mass, GREY_START)
    out = {"case": "greyest periodic (two-mass, N = 20 000, 10 periods)"}
    for key, kw in (("time", {"focus": "simulation", "x0": "estimate"}),
                    ("frequency", {"periods": P})):
        est, wall, cpu = _timed(lambda kw=kw: sysid.greyest(data, s, max_iter=100, **kw))
        out[key] = {"wall_s": wall, "cpu_s": cpu, "iterations": est.info["iterations"],
                    "evaluations": est.info["evaluations"], "stop": est.info["stop"],
                    "parameters": [round(v, 6) for v in est.parameters.value],
                    "std": [float(f"{v:.3g}") for v in est.parameters.std]}
    t, f = out["time"], out["frequency"]
    out["difference_in_std"] = [round(abs(a - b) / np.hypot(sa, sb), 2) for a, b, sa, sb
                                in zip(t["parameters"], f["parameters"], t["std"], f["std"])]
    out["cpu_ratio"] = round(t["cpu_s"] / max(f["cpu_s"], 1e-3), 1)
    return out


def time_domain_row(name, u, y, n, start, s, model, rate):
    """Print one time-domain case: sysid's search from ``start`` (``s``), the same search
    run to its end (``--converge``), SciPy from the same start and the floor."""
    if CONVERGE and s["stop"] == "maximum iterations":
        s["converged"], cmodel = converged_cost(u, y, start)
        s["converged"]["validation_fit"] = validation_fit(name.split()[0], cmodel)
        s["final_over_converged"] = round(s["final_cost"] / s["converged"]["cost"], 3)
    sc = run_scipy(u, y, start, s["iterations"])
    fl = floor_s(u, y, n, s["iterations"], rate)
    row = {"case": name, "N": len(u), "m": u.shape[1], "l": y.shape[1], "n": n,
           "sysid": s, "scipy": sc, "floor_s": round(fl, 3),
           "sysid_over_floor": round(s["wall_s"] / fl, 1)}
    if isinstance(sc["wall_s"], float):
        row["speedup_vs_scipy"] = round(sc["wall_s"] / s["wall_s"], 1)
    print(json.dumps(row), flush=True)


def main(which: list[str]) -> None:
    rate = gemm_rate()
    print(json.dumps({"gemm_gflops": round(rate / 1e9, 1), "load": os.getloadavg()[0]}),
          flush=True)
    for name, (u, y, n) in cases().items():
        if which and name.split()[0] not in which and name not in which:
            continue
        start = start_model(u, y, n)
        s, model = run_sysid(u, y, start)
        s["validation_fit"] = validation_fit(name, model)
        s["start_validation_fit"] = validation_fit(name, start)
        if name in PERIODS:
            fd, fmodel = run_sysid(u, y, start, PERIODS[name])
            fd["validation_fit"] = validation_fit(name, fmodel)
            print(json.dumps({"case": f"{name} (frequency domain, periods={PERIODS[name]})",
                              "N": len(u), "m": u.shape[1], "l": y.shape[1], "n": n,
                              "sysid": fd}), flush=True)
        time_domain_row(name, u, y, n, start, s, model, rate)
        if name in PERIODS:
            # the start a user's ssest takes on this periodic record (the averaged lines' fit
            # is one of its candidates), refined by the same time-domain search
            start2, how = ssest_start(u, y, n)
            s2, model2 = run_sysid(u, y, start2)
            s2["validation_fit"] = validation_fit(name, model2)
            s2["start_validation_fit"] = validation_fit(name, start2)
            time_domain_row(f"{name} (time domain, ssest's start: {how})", u, y, n, start2,
                            s2, model2, rate)
    for name, (u, y, dt) in other_cases().items():
        if which and name not in which:
            continue
        s, sc, check = run_other(name, u, y, dt)
        row = {"case": name, "N": len(u), "sysid": s, "scipy": sc,
               "scipy_cost_at_sysid_solution": check}
        if isinstance(sc["wall_s"], float):
            row["speedup_vs_scipy"] = round(sc["wall_s"] / max(s["wall_s"], 1e-3), 1)
            if "search_wall_s" in s:  # the same start's search against SciPy's
                row["search_speedup_vs_scipy"] = round(
                    sc["wall_s"] / max(s["search_wall_s"], 1e-3), 1)
        print(json.dumps(row), flush=True)
    if not which or "greyest-periodic" in which:
        print(json.dumps(greyest_periodic()), flush=True)


if __name__ == "__main__":
    # --converge: a case stopped at the cap is also run to convergence (minutes on the F-16)
    CONVERGE = "--converge" in sys.argv[1:]
    args = [a for a in sys.argv[1:] if not a.startswith("--scipy-budget=") and a != "--converge"]
    for a in sys.argv[1:]:
        if a.startswith("--scipy-budget="):  # a longer budget for SciPy (seconds per case)
            SCIPY_BUDGET = float(a.split("=", 1)[1])
    main(args)
