"""Audit of sysid's warnings: how often each fires where nothing is wrong (false alarms), how
often it stays silent where it is due (misses), and which fire on the real records.

Monte Carlo on synthetic records whose truth is known, through the default paths a user takes
(``sysid.identify``, ``ssest(data, n)``, ``ssest(data)``, ``n4sid``, ``arx``, ``oe``, ``armax``,
``tfest``, ``poles(std=True)``, ``compare``, ``residuals``). Every warning is counted by class
and by message (digits blanked). The statistical tests at a stated level (the feedback test of
``check_feedback`` at its ``alpha``, the residual whiteness and independence tests at theirs)
are counted as rejections, to be set against their level.

Scenarios where no warning is due (``clean-*``): random stable systems (orders 2-6, poles
0.15 apart, every channel's zeros 0.15 from its poles: no near cancellation), 1 x 1 or 2 x 2,
inputs white, PRBS, multisine or low-pass filtered noise (cycled), SNR 10-40 dB, N 500-5000,
zero-mean or with offsets added and removed by ``detrend(kind="constant")``.
Scenarios where one is due: ``closed`` (a proportional controller on the measured output, the
loop kept stable, output noise 5-20 dB, the reference of the cycled input kinds:
FeedbackWarning), ``offset`` (offsets 20 x the variation left in: OffsetWarning),
``narrow`` (two sines, order 4-6: ExcitationWarning), ``unstable`` (one real pole at 1.01-1.03:
StabilityWarning whenever an unstable model is returned), ``capped`` (``max_iter=2``:
IterationLimitWarning whenever the capped fit falls 0.1 point short of the full search's),
``feedthrough`` (a direct term as large as the dynamic gain: FeedthroughWarning from
``ssest(data, n)``, which leaves D out).

Usage::

    python benches/warning_audit.py --runs 200 --out results/warning_audit.jsonl
    python benches/warning_audit.py --quick        # 12 runs per scenario, a smoke check
    python benches/warning_audit.py --real         # the real-record firing table
    python benches/warning_audit.py --table results/warning_audit.jsonl   # the tables
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
import warnings
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np
from scipy.linalg import block_diag

import sysid

HERE = Path(__file__).resolve().parent
INPUTS = ("white", "prbs", "multisine", "filtered")
CLEAN = ("clean-1x1", "clean-2x2")
ONLY: set[str] = set()  # --only: the calls to make (all when empty)
FITTED = ("oe", "tfest")  # calls whose validation fit (worst output) is recorded
DUE = {"closed": "FeedbackWarning", "offset": "OffsetWarning", "narrow": "ExcitationWarning",
       "unstable": "StabilityWarning", "capped": "IterationLimitWarning",
       "feedthrough": "FeedthroughWarning"}


# -- synthetic records ---------------------------------------------------------------------
def random_system(rng: np.random.Generator, n: int, nu: int, ny: int,
                  unstable: bool = False) -> sysid.StateSpaceModel:
    """A random stable system of order ``n`` with distinct poles (pairs at modulus 0.5-0.95,
    a real pole at 0.2-0.9 when ``n`` is odd); with ``unstable`` one real pole at 1.01-1.03."""
    blocks = []
    k = n
    if unstable:
        blocks.append(np.array([[rng.uniform(1.01, 1.03)]]))
        k -= 1
    if k % 2:
        blocks.append(np.array([[rng.uniform(0.2, 0.9)]]))
        k -= 1
    angles = np.sort(rng.uniform(0.15, 2.6, k // 2))
    angles += 0.15 * np.arange(k // 2)  # keep the pairs apart
    for th in angles:
        r = rng.uniform(0.5, 0.95)
        blocks.append(r * np.array([[np.cos(th), np.sin(th)], [-np.sin(th), np.cos(th)]]))
    A = block_diag(*blocks)
    B = rng.standard_normal((n, nu))
    C = rng.standard_normal((ny, n))
    return sysid.StateSpaceModel(A, B, C, np.zeros((ny, nu)), dt=1.0)


def separated(true: sysid.StateSpaceModel, gap: float = 0.15) -> bool:
    """Whether every input-output channel of ``true`` keeps its zeros ``gap`` away from its
    poles and its poles ``gap`` apart: no near pole-zero cancellation (a mode the channel
    hardly shows), which the data could not determine and an IdentifiabilityWarning would
    rightly name."""
    A, B, C = np.asarray(true.A), np.asarray(true.B), np.asarray(true.C)
    poles = np.linalg.eigvals(A)
    d = np.abs(poles[:, None] - poles[None])
    if np.min(d + np.eye(len(poles)) * 9) < gap:
        return False
    den = np.poly(A)
    for i in range(C.shape[0]):
        for j in range(B.shape[1]):
            num = np.trim_zeros(np.poly(A - np.outer(B[:, j], C[i])) - den, "f")
            zeros = np.roots(num) if num.size > 1 else np.zeros(0)
            if zeros.size and np.min(np.abs(zeros[:, None] - poles[None])) < gap:
                return False
    return True


def make_input(rng: np.random.Generator, kind: str, N: int, nu: int) -> np.ndarray:
    """Zero-mean input of ``kind`` (INPUTS, or ``narrow``: two sines)."""
    if kind == "white":
        return rng.standard_normal((N, nu))
    if kind == "prbs":
        return np.sign(rng.standard_normal((N // 3 + 1, nu))).repeat(3, axis=0)[:N]
    if kind == "filtered":  # low-pass: first-order filter at 0.8
        e = rng.standard_normal((N + 200, nu))
        u = np.zeros_like(e)
        for t in range(1, e.shape[0]):
            u[t] = 0.8 * u[t - 1] + e[t]
        return u[200:]
    t = np.arange(N)[:, None]
    if kind == "multisine":  # lines on a 256-sample period over (0, 0.9 pi)
        P = 256
        lines = np.arange(1, int(0.45 * P))
        out = np.zeros((N, nu))
        for j in range(nu):
            ph = rng.uniform(0, 2 * np.pi, lines.size)
            out[:, j] = np.sum(np.cos(2 * np.pi * lines[None] * t / P + ph), axis=1)
        return out / out.std(0)
    if kind == "narrow":
        w = rng.uniform(0.2, 1.0, (2, nu))
        return np.sin(w[0] * t) + np.sin(w[1] * t + 1.0)
    raise ValueError(kind)


def noisy(rng: np.random.Generator, y0: np.ndarray, snr: float) -> np.ndarray:
    """White output noise ``snr`` dB below the output's first 200 samples (an unstable
    truth's output grows: its noise is set where it starts)."""
    return y0 + y0[:200].std(0) * 10 ** (-snr / 20) * rng.standard_normal(y0.shape)


def scenario_record(scenario: str, run: int, seed: int):
    """(estimation IOData, validation IOData, facts) of run ``run`` of ``scenario``."""
    rng = np.random.default_rng([seed, run, sum(map(ord, scenario))])
    nu = ny = 2 if scenario == "clean-2x2" else 1
    n = int(rng.integers(2, 7))
    N = int(rng.integers(500, 5001))
    snr = float(rng.uniform(10, 40))
    kind = INPUTS[run % len(INPUTS)]
    facts = {"scenario": scenario, "run": run, "order": n, "N": N, "snr": round(snr, 1),
             "input": kind, "detrended": bool(run % 2)}
    if scenario == "narrow":
        kind, n = "narrow", int(rng.integers(4, 7))
        facts.update(input=kind, order=n)
    true = random_system(rng, n, nu, ny, unstable=scenario == "unstable")
    if scenario.startswith("clean"):  # nothing due: no near pole-zero cancellation either
        for _ in range(200):
            if separated(true):
                break
            true = random_system(rng, n, nu, ny)
    if scenario == "unstable":
        N = min(N, 800)
        facts["N"] = N
    if scenario == "feedthrough":
        g = np.abs(true.freqresp(np.array([0.0]))).max()
        true = sysid.StateSpaceModel(true.A, true.B, true.C, [[float(g) * rng.choice([-1, 1])]],
                                     dt=1.0)
    M = 2 * N
    u = make_input(rng, kind, M, nu)
    if scenario == "closed":  # u = r - k y(t-1): the controller sees the last output
        r, x = u, np.zeros(n)
        gain = float(np.real(true.C @ np.linalg.solve(np.eye(n) - true.A, true.B))[0, 0])
        k = rng.uniform(0.5, 1.5) / (gain if abs(gain) > 1e-3 else 1e-3)
        for _ in range(30):  # the loop [x; y(t-1)] stable: halve the gain until it is
            Acl = np.block([[true.A, -k * true.B], [true.C, np.zeros((1, 1))]])
            if np.max(np.abs(np.linalg.eigvals(Acl))) < 0.98:
                break
            k /= 2
        y0 = np.zeros((M, 1))
        u = np.zeros((M, 1))
        # noise on the measured output, snr 5-20 dB below the open-loop response to r: the
        # controller feeds it back into u, which biases open-loop methods
        snr = float(rng.uniform(5, 20))
        facts["snr"] = round(snr, 1)
        e = rng.standard_normal(M) * true.simulate(r).std() * 10 ** (-snr / 20)
        for t in range(M):
            y0[t] = true.C @ x
            u[t] = r[t] - (k * (y0[t - 1, 0] + e[t - 1]) if t else 0.0)
            x = true.A @ x + true.B[:, 0] * u[t, 0]
        y = y0 + e[:, None]
        facts["loop_gain"] = round(float(k * gain), 3)
    else:
        y = noisy(rng, true.simulate(u), snr)
    if scenario == "offset":
        u = u + 20 * u.std(0)
        y = y + 20 * y.std(0)
    est = sysid.IOData(u=u[:N], y=y[:N], dt=1.0)
    val = sysid.IOData(u=u[N:], y=y[N:], dt=1.0)
    if scenario.startswith("clean") and facts["detrended"]:
        off_u, off_y = rng.uniform(-50, 50, nu), rng.uniform(-50, 50, ny)
        est = sysid.detrend(sysid.IOData(u=u[:N] + off_u, y=y[:N] + off_y, dt=1.0), "constant")
        val = sysid.detrend(sysid.IOData(u=u[N:] + off_u, y=y[N:] + off_y, dt=1.0), "constant")
    return est, val, facts, true


# -- the calls ----------------------------------------------------------------------------
def key(w: warnings.WarningMessage) -> str:
    """Class and message with digits blanked, cut at 90 characters."""
    msg = re.sub(r"[-+]?\d[\d.e+-]*", "#", str(w.message))
    return f"{w.category.__name__}: {msg[:90]}"


def caught(fn):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        try:
            out = fn()
            err = None
        except Exception as e:  # noqa: BLE001 - an error is counted, not raised
            out, err = None, f"{type(e).__name__}: {str(e)[:80]}"
    return out, [key(x) for x in w], err


def unstable(m) -> bool:
    """A pole on or outside the unit circle (discrete) or in the closed right half-plane."""
    try:
        p = np.asarray(m.poles())
        if not getattr(m, "dt", 1.0):
            return bool(np.max(p.real) >= 0.0)
        return bool(np.max(np.abs(p)) >= 1.0)
    except Exception:  # noqa: BLE001
        return False


def run_calls(scenario: str, est, val, facts: dict, with_identify: bool) -> dict:
    """Every default call on ``est`` (validation on ``val``) with its warnings."""
    n, nu = facts["order"], est.n_inputs
    out: dict = {"facts": facts, "calls": {}, "tests": {}}

    def rec(name, fn):
        if ONLY and name not in ONLY:
            return None
        t = time.perf_counter()
        m, ws, err = caught(fn)
        out["calls"][name] = {"warnings": ws, "error": err,
                              "unstable": unstable(m) if hasattr(m, "poles") else None,
                              "seconds": round(time.perf_counter() - t, 3)}
        if name in FITTED and m is not None:  # the validation fit, worst output
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    fit = float(np.min(sysid.compare(val, m).fit))
                except Exception:  # noqa: BLE001
                    fit = float("nan")
            out["calls"][name]["fit"] = round(fit, 2) if np.isfinite(fit) else None
        return m

    capped = scenario == "capped"
    it = {"max_iter": 2} if capped else {}
    if with_identify and not capped:
        rec("identify", lambda: sysid.identify(est).model)
    m_ss = rec("ssest(n)", lambda: sysid.ssest(est, n, **it))
    if not capped:
        rec("ssest(n,sim)", lambda: sysid.ssest(est, n, focus="simulation"))
        rec("ssest(auto)", lambda: sysid.ssest(est))
        rec("n4sid", lambda: sysid.n4sid(est))
    if nu == 1 or not capped:
        na = n
        rec("arx", lambda: sysid.arx(est, na, na, 1))
        m_oe = rec("oe", lambda: sysid.oe(est, n, n, 1, **it))
        m_am = rec("armax", lambda: sysid.armax(est, n, n, n, 1, **it))
        m_tf = rec("tfest", lambda: sysid.tfest(est, n, **it))
        if nu == 1:  # F held stable too, beside a noise model (session 61)
            rec("bj", lambda: sysid.bj(est, n, 1, 1, n, 1, **it))
    if capped:  # the same searches uncapped: was a warning due?
        full = {"ssest(n)": lambda: sysid.ssest(est, n), "oe": lambda: sysid.oe(est, n, n, 1),
                "armax": lambda: sysid.armax(est, n, n, n, 1), "tfest": lambda: sysid.tfest(est, n)}
        for name, m in (("ssest(n)", m_ss), ("oe", m_oe), ("armax", m_am), ("tfest", m_tf)):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    mf = full[name]()
                    fit_c = sysid.compare(est, m).fit.mean() if m is not None else np.nan
                    fit_f = sysid.compare(est, mf).fit.mean()
                except Exception:  # noqa: BLE001
                    fit_c = fit_f = np.nan
            # due: the capped model's estimation fit falls short of the full search's by 0.1 point
            out["calls"][name]["due"] = bool(fit_f - fit_c > 0.1)
            out["calls"][name]["fits"] = [round(float(fit_c), 2), round(float(fit_f), 2)]
    if m_ss is not None and (scenario.startswith("clean") or scenario == "feedthrough"):
        rec("poles(std)", lambda: m_ss.poles(std=True))
        rec("compare", lambda: sysid.compare(val, m_ss))
        r = rec("residuals", lambda: sysid.residuals(m_ss, val))
        if r is not None:
            out["tests"]["white_rejected"] = [not bool(x) for x in np.atleast_1d(r.whiteness)]
            out["tests"]["indep_rejected"] = [x is False for x in r.independence]
            out["tests"]["resid_alpha"] = r.alpha
    fb, _, _ = caught(lambda: sysid.check_feedback(est))
    if fb is not None:
        out["tests"]["feedback_detected"] = bool(fb.detected)
        out["tests"]["feedback_alpha"] = fb.alpha
    return out


# -- tables --------------------------------------------------------------------------------
def wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    if n == 0:
        return (np.nan, np.nan)
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return max(0.0, c - h), min(1.0, c + h)


def rate(k: int, n: int) -> str:
    lo, hi = wilson(k, n)
    return f"{k}/{n} = {100 * k / max(n, 1):.1f} % [{100 * lo:.1f}, {100 * hi:.1f}]"


def tables(rows: list[dict]) -> str:
    out = []
    by = defaultdict(list)
    for r in rows:
        by[r["facts"]["scenario"]].append(r)
    out.append("### Firing rates: runs in which a call raised the class (95 % Wilson interval)\n")
    for sc, rs in by.items():
        calls = sorted({c for r in rs for c in r["calls"]})
        classes = sorted({w.split(":")[0] for r in rs for c in r["calls"].values()
                          for w in c["warnings"]})
        out.append(f"**{sc}** ({len(rs)} runs)\n")
        if not classes:
            out.append("no warning from any call\n")
        else:
            out.append("| call | " + " | ".join(classes) + " | errors |")
            out.append("|---" * (len(classes) + 2) + "|")
            for c in calls:
                rr = [r["calls"][c] for r in rs if c in r["calls"]]
                cells = [rate(sum(any(w.startswith(k + ":") for w in x["warnings"]) for x in rr),
                              len(rr)) for k in classes]
                errs = sum(x["error"] is not None for x in rr)
                out.append(f"| {c} | " + " | ".join(cells) + f" | {errs} |")
        out.append("")
        if sc in DUE:
            cls = DUE[sc]
            out.append(f"Misses of {cls}:\n")
            for c in calls:
                rr = [r["calls"][c] for r in rs if c in r["calls"]]
                if sc == "offset" and c == "identify":
                    out.append("- identify: removes the offsets itself (no warning due)")
                    continue
                if sc == "narrow" and c == "arx":  # ARX needs order nb = n of the input only
                    rr = [r["calls"][c] for r in rs if c in r["calls"]
                          and r["facts"]["order"] > 4]
                    extra0 = " (due where nb = n > 4 only)"
                else:
                    extra0 = ""
                refused = sum(x["error"] is not None for x in rr)
                rr = [x for x in rr if x["error"] is None]  # an error is a refusal, no miss
                if sc == "unstable":
                    due = [x for x in rr if x["unstable"]]
                elif sc == "capped":
                    due = [x for x in rr if x.get("due")]
                else:
                    due = rr
                said = [any(w.startswith(cls) or (cls == "IterationLimitWarning" and
                                                  w.startswith("ConvergenceWarning"))
                            for w in x["warnings"]) for x in due]
                miss = sum(not s for s in said)
                extra = (f"; unstable model returned in {len(due)}/{len(rr)}"
                         if sc == "unstable" else "")
                if sc == "capped":
                    fired = sum(any(w.startswith(("IterationLimitWarning", "ConvergenceWarning"))
                                    for w in x["warnings"]) for x in rr if not x.get("due"))
                    extra = f"; fired where the full search gained < 0.1 point: {fired}"
                if refused:
                    extra += f"; refused with an error in {refused} runs"
                out.append(f"- {c}{extra0}: missed {rate(miss, len(due))}{extra}")
            out.append("")
        tests = [r["tests"] for r in rs]
        fbd = [t["feedback_detected"] for t in tests if "feedback_detected" in t]
        if fbd:
            out.append(f"check_feedback detected (alpha={tests[0].get('feedback_alpha')}): "
                       f"{rate(sum(fbd), len(fbd))}")
        wr = [any(t["white_rejected"]) for t in tests if "white_rejected" in t]
        if wr:
            a = next(t["resid_alpha"] for t in tests if "resid_alpha" in t)
            ir = [any(t["indep_rejected"]) for t in tests if "indep_rejected" in t]
            ny = len(next(t["white_rejected"] for t in tests if "white_rejected" in t))
            out.append(f"residuals(ssest(n), validation) at alpha={a} ({ny} output(s), any "
                       f"rejects): whiteness {rate(sum(wr), len(wr))}; independence "
                       f"{rate(sum(ir), len(ir))}")
        out.append("")
        for c in FITTED:
            fits = [r["calls"][c].get("fit") for r in rs if c in r["calls"]
                    and "fit" in r["calls"][c]]
            if fits:
                f = np.array([-np.inf if x is None else x for x in fits])
                secs = [r["calls"][c]["seconds"] for r in rs if c in r["calls"]]
                out.append(f"{c}: validation fit (worst output) median {np.median(f):.1f} %, "
                           f"10th percentile {np.percentile(f, 10):.1f} %, below 50 %: "
                           f"{int(np.sum(f < 50))}/{f.size}; seconds per call: mean "
                           f"{np.mean(secs):.2f}, max {np.max(secs):.2f}")
        msgs = Counter(w for r in rs for c in r["calls"].values() for w in set(c["warnings"]))
        if msgs:
            out.append("Messages (runs x calls):\n")
            out += [f"- {k} x {v}" for k, v in msgs.most_common(12)]
            out.append("")
    return "\n".join(out)


def by_input(rows: list[dict]) -> str:
    """Clean scenarios: runs with any warning, by input kind and call."""
    out = ["| scenario | input | runs | runs with a warning (any call) | classes |",
           "|---|---|---|---|---|"]
    for sc in CLEAN:
        for kind in INPUTS:
            rs = [r for r in rows if r["facts"]["scenario"] == sc and r["facts"]["input"] == kind]
            if not rs:
                continue
            k = sum(any(c["warnings"] for c in r["calls"].values()) for r in rs)
            cls = Counter(w.split(":")[0] for r in rs for c in r["calls"].values()
                          for w in set(c["warnings"]))
            out.append(f"| {sc} | {kind} | {len(rs)} | {rate(k, len(rs))} | "
                       + ", ".join(f"{a} {b}" for a, b in cls.most_common()) + " |")
    return "\n".join(out)


# -- real records --------------------------------------------------------------------------
def real_records() -> dict:
    """The shipped records (benches/realdata.py's loaders: shared DaISy and F-16 files)."""
    sys.path.insert(0, str(HERE))
    import realdata

    return realdata.RECORDS


def real_record(name: str, est, val) -> dict:
    """The default calls on one real record, with the warnings of each."""
    res: dict = {"record": name, "calls": {}}
    t0 = time.perf_counter()

    def rec(call, fn):
        if ONLY and call not in ONLY:
            return None
        m, ws, err = caught(fn)
        res["calls"][call] = {"warnings": sorted(set(ws)), "error": err,
                              "unstable": unstable(m) if hasattr(m, "poles") else None}
        return m

    ident = rec("identify", lambda: sysid.identify(est))
    n = int(ident.model.nstates) if ident is not None else 4
    res["identify_order"] = n
    m = rec("ssest(n)", lambda: sysid.ssest(est, n))
    rec("ssest(auto)", lambda: sysid.ssest(est))
    rec("ssest(n,sim)", lambda: sysid.ssest(est, n, focus="simulation"))
    rec("n4sid", lambda: sysid.n4sid(est))
    if est.n_inputs == 1 and est.n_outputs == 1:
        rec("arx(4,4,1)", lambda: sysid.arx(est, 4, 4, 1))
        rec("oe(3,3,1)", lambda: sysid.oe(est, 3, 3, 1))
        rec("armax(3,3,3,1)", lambda: sysid.armax(est, 3, 3, 3, 1))
        rec("tfest(3)", lambda: sysid.tfest(est, 3))
        rec("bj(3,1,1,3,1)", lambda: sysid.bj(est, 3, 1, 1, 3, 1))
    if m is not None:
        rec("poles(std)", lambda: m.poles(std=True))
        rec("compare", lambda: sysid.compare(val, m))
        rec("residuals", lambda: sysid.residuals(m, val))
    fb, _, _ = caught(lambda: sysid.check_feedback(est))
    res["check_feedback_p"] = None if fb is None else float(fb.p_value)
    res["seconds"] = round(time.perf_counter() - t0, 1)
    return res


def real_table(names: list[str] | None, out: str | None) -> list[dict]:
    """:func:`real_record` on the records of benches/realdata.py (``names``, or all)."""
    loads = real_records()
    rows = []
    for name in names or list(loads):
        (ue, ye), (uv, yv) = loads[name]()
        res = real_record(name, sysid.IOData(u=ue, y=ye, dt=1.0),
                          sysid.IOData(u=uv, y=yv, dt=1.0))
        print(json.dumps(res), flush=True)
        if out:
            with open(out, "a") as f:
                f.write(json.dumps(res) + "\n")
        rows.append(res)
    return rows


def real_md(rows: list[dict]) -> str:
    """The real-record firing table: per record and call, the warning classes."""
    out = ["| record | call | warnings (class: message start) |", "|---|---|---|"]
    for r in rows:
        for c, v in r["calls"].items():
            said = "; ".join(w[:120] for w in v["warnings"]) or "-"
            if v.get("error"):
                said += f" (error: {v['error']})"
            if v.get("unstable"):
                said += " [model unstable]"
            out.append(f"| {r['record']} | {c} | {said} |")
    return "\n".join(out)


def calibration(runs: int, seed: int) -> str:
    """The tests at a stated level where the truth is known to meet their null hypothesis, on
    clean 1 x 1 records: ``check_feedback`` (open loop, alpha 0.01) and the residual tests of
    the TRUE model on the validation part (alpha 0.01): rejections against the level."""
    fb, white, indep = [], [], []
    by_kind: dict[str, list[bool]] = defaultdict(list)
    for i in range(runs):
        est, val, facts, true = scenario_record("clean-1x1", i, seed)
        d = bool(sysid.check_feedback(est).detected)
        fb.append(d)
        by_kind[facts["input"]].append(d)
        r = sysid.residuals(true, val)
        white.append(not bool(r.is_white))
        indep.append(any(x is False for x in r.independence))
    out = [f"check_feedback detected (alpha 0.01, open loop): {rate(sum(fb), runs)}"]
    out += [f"- {k}: {rate(sum(v), len(v))}" for k, v in by_kind.items()]
    out.append(f"residuals of the true model (alpha 0.01): whiteness rejected "
               f"{rate(sum(white), runs)}, independence rejected {rate(sum(indep), runs)}")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=200)
    ap.add_argument("--only", nargs="*", default=[], help="make these calls only (tfest ...)")
    ap.add_argument("--first", type=int, default=0, help="index of the first run (to extend)")
    ap.add_argument("--quick", action="store_true", help="12 runs per scenario")
    ap.add_argument("--scenarios", nargs="*", default=list(CLEAN) + list(DUE))
    ap.add_argument("--identify-every", type=int, default=1,
                    help="run sysid.identify on every k-th run of the clean scenarios")
    ap.add_argument("--seed", type=int, default=55)
    ap.add_argument("--out", default=None, help="JSON lines, one per run (appended)")
    ap.add_argument("--real", nargs="*", default=None, help="the real-record table")
    ap.add_argument("--table", default=None, help="print the tables of a JSON-lines file")
    ap.add_argument("--calibration", action="store_true",
                    help="the stated-level tests on records meeting their null (--runs)")
    args = ap.parse_args()
    if args.table:
        rows = [json.loads(x) for x in Path(args.table).read_text().splitlines() if x.strip()]
        if rows and "record" in rows[0]:
            print(real_md(rows))
            return
        print(tables(rows))
        print()
        print(by_input(rows))
        return
    if args.calibration:
        print(calibration(args.runs, args.seed))
        return
    if args.real is not None:
        ONLY.update(args.only)
        print(real_md(real_table(args.real, args.out)))
        return
    ONLY.update(args.only)
    runs = 12 if args.quick else args.runs
    f = open(args.out, "a") if args.out else None
    rows = []
    for sc in args.scenarios:
        for i in range(args.first, args.first + runs):
            est, val, facts, _ = scenario_record(sc, i, args.seed)
            ident = (sc.startswith("clean") or sc in ("closed", "offset")) \
                and i % args.identify_every == 0
            r = run_calls(sc, est, val, facts, ident)
            rows.append(r)
            if f:
                f.write(json.dumps(r) + "\n")
                f.flush()
    if f:
        f.close()
    print(tables(rows))
    print()
    print(by_input(rows))


if __name__ == "__main__":
    main()
