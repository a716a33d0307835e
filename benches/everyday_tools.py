"""Everyday MATLAB-style tools on real records, called as a new user calls them (issue 26).

Checks, per record and tool, with small default-ish orders: no Rust panic; an error is a
``SysidError`` (its message is kept for judging); no NaN/inf in the model or its standard
deviations; an unstable returned model comes with a ``StabilityWarning``; an iterative fit's
final cost is not above its start's; a fit stopped at its cap warns; the warnings raised (kept
for judging); the validation simulation fit against ``n4sid`` at order 2; ``summary()`` and
``repr`` render. The polynomial tools run MISO (every input, first output), the SISO tools
(``tfest``, ``procest``, ``delayest``, recursive estimators) the first input-output pair.
Estimation: the first 2/3, validation: the last 1/3; first on the raw record (as a new user
would), then detrended (``sysid.detrend(est, "constant", return_trend=True)``, the estimation
record's trend applied to the validation part by ``Trend.apply``).

Command (the records' folders as in ``benches/realdata.py``)::

    nice .venv/bin/python benches/everyday_tools.py --unshipped /tmp/daisy2 \\
        --more-records /tmp/s49/more --fresh-records /tmp/s52/fresh \\
        --fresh2-records /tmp/s52/fresh2 --fresh3-records /tmp/s53/fresh3 \\
        --fresh4-records /tmp/s53/fresh4 --out benches/results/everyday_tools.jsonl

``--table FILE.jsonl`` writes the markdown table from a results file (no fitting).
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import time
import traceback
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import realdata as rd  # noqa: E402

import sysid  # noqa: E402

MAX_EST = 20000  # estimation samples kept (the first ones), so a sweep stays in minutes
CALL_LIMIT = 120  # seconds per call (SIGALRM; a Rust call is stopped when it returns)


class _Timeout(Exception):
    pass


def _alarm(signum, frame):  # noqa: ARG001
    raise _Timeout


def _finite(x) -> bool:
    """No NaN/inf in an array, a list/dict of arrays, or None."""
    if x is None:
        return True
    if isinstance(x, dict):
        return all(_finite(v) for v in x.values())
    if isinstance(x, (list, tuple)):
        return all(_finite(v) for v in x)
    try:
        a = np.asarray(x, dtype=complex)
    except (TypeError, ValueError):
        return True
    return bool(np.all(np.isfinite(a)))


def _model_arrays(m):
    """The model's numbers (state space or polynomial or transfer function)."""
    out = []
    for name in ("A", "B", "C", "D", "K", "a", "b", "c", "d", "f", "num", "den"):
        v = getattr(m, name, None)
        if v is not None and not callable(v):
            out.append(v)
    params = getattr(m, "parameters", None)
    if isinstance(params, dict):
        out.append(list(params.values()))
    return out


def _std_of(m):
    s = getattr(m, "std", None)
    if callable(s):
        return None
    return s


def _stable(m):
    f = getattr(m, "is_stable", None)
    try:
        return bool(f() if callable(f) else f) if f is not None else None
    except Exception:  # noqa: BLE001
        return None


def _costs(m):
    info = getattr(m, "info", None) or {}
    start = info.get("cost_start")
    cost = info.get("cost")
    if start is None and isinstance(cost, (list, np.ndarray)):
        c = np.atleast_2d(np.asarray(cost, float))  # per output, cost history
        if c.shape[1] >= 2:
            return float(c[0, 0]), float(c[0, -1])
        return None, None
    try:
        return (None if start is None else float(np.ravel(start)[0]),
                None if cost is None else float(np.ravel(cost)[-1]))
    except (TypeError, ValueError):
        return None, None


def _fit(m, val) -> float | None:
    c = sysid.compare(val, m)
    return float(np.mean(c.fit))


def run_call(rec, split, tool, fn, val, ref_fit):
    """One call: its result row."""
    row = {"record": rec, "split": split, "tool": tool}
    t0 = time.process_time()
    signal.alarm(CALL_LIMIT)
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        try:
            m = fn()
            row["ok"] = True
        except _Timeout:
            row.update(ok=False, error="timeout")
            m = None
        except sysid.SysidError as ex:
            row.update(ok=False, error=f"{type(ex).__name__}: {ex}"[:300])
            m = None
        except BaseException as ex:  # noqa: BLE001 (a Rust panic is a BaseException)
            row.update(ok=False, error=f"NOT-SYSID {type(ex).__name__}: {ex}"[:300],
                       tb=traceback.format_exc()[-600:])
            m = None
        finally:
            signal.alarm(0)
        row["cpu"] = round(time.process_time() - t0, 2)
        if m is not None and not isinstance(m, (dict, str)):
            _inspect(row, m, val, ref_fit)
        elif isinstance(m, dict):
            row.update(m)
    row["warnings"] = sorted({f"{x.category.__name__}: {str(x.message)[:160]}" for x in w})
    return row


def _inspect(row, m, val, ref_fit):
    row["finite"] = _finite(_model_arrays(m))
    try:
        row["std_finite"] = _finite(_std_of(m))
    except Exception as ex:  # noqa: BLE001
        row["std_finite"] = f"err {type(ex).__name__}: {ex}"[:120]
    row["stable"] = _stable(m)
    c0, c1 = _costs(m)
    row["cost_start"], row["cost"] = c0, c1
    info = getattr(m, "info", None) or {}
    stop = info.get("stop")
    row["stop"] = str(np.ravel(stop)[0])[:40] if stop is not None else None
    if val is not None and hasattr(m, "simulate"):
        try:
            with warnings.catch_warnings(record=True) as w2:
                warnings.simplefilter("always")
                row["fit"] = _fit(m, val)
            row["compare_warnings"] = sorted({x.category.__name__ for x in w2})
        except Exception as ex:  # noqa: BLE001
            row["fit_error"] = f"{type(ex).__name__}: {ex}"[:200]
    row["ref_fit"] = ref_fit
    for what in ("summary", "repr"):
        try:
            s = m.summary() if what == "summary" else repr(m)
            row[f"{what}_ok"] = isinstance(s, str) and "nan" not in s.lower().replace(
                "n/a", "")
        except Exception as ex:  # noqa: BLE001
            row[f"{what}_ok"] = f"err {type(ex).__name__}: {ex}"[:120]


def tools(est, val, siso_est):
    """(name, callable) for each tool on one record."""
    miso = est if est.y.shape[1] == 1 else sysid.IOData(u=est.u, y=est.y[:, :1], dt=est.dt)
    nu = est.u.shape[1]

    def arxs():
        t = sysid.arxstruc(miso, range(1, 6), range(1, 6), range(1, 4))
        return {"selstruc": str(sysid.selstruc(t, "aic"))}

    def recursive(cls):  # RecursiveARX / RecursiveOE (2, 2, 1): the late error's size
        def run():
            r = cls(2, 2, 1)
            res = r.run(siso_est.u, siso_est.y)
            return {"finite": _finite(res.yhat) and _finite(r.parameters),
                    "rel_err": float(np.std(res.error[len(res.error) // 2:])
                                     / (np.std(siso_est.y) + 1e-300))}
        return run

    def spa():
        g = sysid.spa(est)
        return {"finite": _finite(g.response)}

    def etfe():
        g = sysid.etfe(est)
        return {"finite": _finite(g.response)}

    def era():
        mk = sysid.impulse_response(est)
        return sysid.era(mk, 2).model

    def okid():
        mk = sysid.okid(est, 4)
        return sysid.era(mk, 2).model

    def step_info():
        m = sysid.n4sid(siso_est, 2)
        r = sysid.step(m)
        info = sysid.stepinfo(m)
        return {"finite": _finite(r.y), "stepinfo": repr(info)[:120]}

    def resid():
        m = sysid.oe(miso, 2, [2] * nu, [1] * nu)
        r = sysid.residuals(m, sysid.IOData(u=val.u, y=val.y[:, :1], dt=val.dt))
        return {"finite": _finite(r.e), "summary_ok": bool(r.summary())}

    def multi():
        ms = [sysid.arx(miso, 2, [2] * nu, [1] * nu), sysid.oe(miso, [2] * nu, [2] * nu,
                                                                [1] * nu),
              sysid.n4sid(miso, 2)]
        c = sysid.compare(sysid.IOData(u=val.u, y=val.y[:, :1], dt=val.dt), *ms)
        return {"fits": [round(float(f), 1) for f in np.ravel(c.mean_fit)]}

    def loss():
        m = sysid.n4sid(est, 2)
        v = sysid.pem_loss(est, m)
        return {"finite": bool(np.isfinite(v)), "loss": float(v)}

    def fc():
        m = sysid.ar(siso_est.y[:, 0], 4)
        f = sysid.forecast(m, siso_est.y[-200:, 0], 20)
        return {"finite": _finite(f.mean if hasattr(f, "mean") else f.y)}

    def delay():
        return {"delay": str(sysid.delayest(siso_est))}

    return [
        ("arx 2 2 1", lambda: sysid.arx(miso, 2, [2] * nu, [1] * nu)),
        ("armax 2 2 2 1", lambda: sysid.armax(miso, 2, [2] * nu, 2, [1] * nu)),
        ("oe 2 2 1", lambda: sysid.oe(miso, [2] * nu, [2] * nu, [1] * nu)),
        ("bj 2 2 2 2 1", lambda: sysid.bj(miso, [2] * nu, 2, 2, [2] * nu, [1] * nu)),
        ("polyest 2 2 1 1 2 1", lambda: sysid.polyest(miso, 2, [2] * nu, 1, 1, [2] * nu,
                                                       [1] * nu)),
        ("iv4 2 2 1", lambda: sysid.iv4(miso, 2, [2] * nu, [1] * nu)),
        ("tfest np=2", lambda: sysid.tfest(siso_est, 2)),
        ("procest P1D", lambda: sysid.procest(siso_est, "P1D")),
        ("procest P2", lambda: sysid.procest(siso_est, "P2")),
        ("ssregest", lambda: sysid.ssregest(est)),
        ("arxstruc+selstruc", arxs),
        ("delayest", delay),
        ("ar 4 (y)", lambda: sysid.ar(siso_est.y[:, 0], 4)),
        ("arma 2 1 (y)", lambda: sysid.arma(siso_est.y[:, 0], 2, 1)),
        ("spa", spa),
        ("etfe", etfe),
        ("impulse_response+era 2", era),
        ("okid+era 2", okid),
        ("step/stepinfo", step_info),
        ("residuals(oe)", resid),
        ("compare arx,oe,n4sid", multi),
        ("RecursiveARX", recursive(sysid.RecursiveARX)),
        ("RecursiveOE", recursive(sysid.RecursiveOE)),
        ("pem_loss", loss),
        ("forecast(ar)", fc),
    ]


def _data(u, y):
    u = np.asarray(u, float).reshape(len(u), -1)
    y = np.asarray(y, float).reshape(len(y), -1)
    return sysid.IOData(u=u, y=y, dt=1.0)


def sweep(loads, out: Path, only=None, tools_only=None) -> None:
    signal.signal(signal.SIGALRM, _alarm)
    with out.open("a") as fh:
        for rec, load in loads.items():
            if only and rec not in only:
                continue
            try:
                (ue, ye), (uv, yv) = load()
            except Exception as ex:  # noqa: BLE001
                print(rec, "load failed:", ex, flush=True)
                continue
            est_raw, val_raw = _data(ue[:MAX_EST], ye[:MAX_EST]), _data(uv, yv)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                est_dt, tr = sysid.detrend(est_raw, "constant", return_trend=True)
                val_dt = tr.apply(val_raw)
            for split, est, val in (("raw", est_raw, val_raw), ("detrended", est_dt, val_dt)):
                siso = sysid.IOData(u=est.u[:, :1], y=est.y[:, :1], dt=est.dt)
                val1 = sysid.IOData(u=val.u, y=val.y[:, :1], dt=val.dt)
                val11 = sysid.IOData(u=val.u[:, :1], y=val.y[:, :1], dt=val.dt)
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        ref = sysid.n4sid(sysid.IOData(u=est.u, y=est.y[:, :1], dt=est.dt), 2)
                        ref_fit = _fit(ref, val1)
                        ref11 = sysid.n4sid(siso, 2)
                        ref_fit11 = _fit(ref11, val11)
                        ref_full = _fit(sysid.n4sid(est, 2), val)
                except Exception:  # noqa: BLE001
                    ref_fit = ref_fit11 = ref_full = None
                for tool, fn in tools(est, val, siso):
                    if tools_only and not any(tool.startswith(t) for t in tools_only):
                        continue
                    is_siso = tool.split()[0] in ("tfest", "procest")
                    full = tool == "ssregest" or "era" in tool
                    v = val11 if is_siso else (val if full else val1)
                    rf = ref_fit11 if is_siso else (ref_full if full else ref_fit)
                    if tool.startswith(("ar ", "arma ")):
                        v, rf = None, None
                    row = run_call(rec, split, tool, fn, v, rf)
                    row["shape"] = [int(est.n_samples if hasattr(est, "n_samples")
                                        else est.u.shape[0]), est.u.shape[1], est.y.shape[1]]
                    fh.write(json.dumps(row, default=str) + "\n")
                    fh.flush()
                    print(rec, split, tool, row.get("fit"), row.get("error", "")[:60],
                          row["cpu"], flush=True)


SHORT = {"StabilityWarning": "Stab", "OffsetWarning": "Off", "IdentifiabilityWarning": "Ident",
         "FeedthroughWarning": "Fthr", "FeedbackWarning": "Fbk", "BoundWarning": "Bound",
         "DelayWarning": "Delay", "IterationLimitWarning": "Iter", "ConvergenceWarning": "Conv",
         "SysidWarning": "Sysid", "ExcitationWarning": "Exc", "UncertaintyWarning": "Unc"}


def flags(r: dict) -> list[str]:
    """The trust checks one call failed (the docstring's list)."""
    out = []
    if not r.get("ok"):
        out.append("ERROR " + r.get("error", "")[:70].replace("|", "/"))
    if r.get("finite") is False:
        out.append("non-finite model")
    if r.get("std_finite") not in (None, True):
        out.append("std: " + str(r["std_finite"])[:40])
    if r.get("stable") is False and not any("StabilityWarning" in w for w in r["warnings"]):
        out.append("unstable, no warning")
    c0, c1 = r.get("cost_start"), r.get("cost")
    if c0 is not None and c1 is not None and c1 > c0 * (1 + 1e-9):
        out.append(f"cost rose {c0:.3g}->{c1:.3g}")
    if r.get("stop") and "iter" in str(r["stop"]).lower() and not any(
            k in w for w in r["warnings"] for k in ("IterationLimit", "Convergence")):
        out.append("cap, no warning")
    if r.get("fit_error"):
        out.append("compare: " + r["fit_error"][:50])
    if r.get("summary_ok") not in (None, True) or r.get("repr_ok") not in (None, True):
        out.append("summary/repr")
    return out


def _cell(r: dict | None) -> tuple[str, str, str]:
    if r is None:
        return "", "", ""
    fit = r.get("fit")
    f = "" if fit is None else f"{fit:.1f}"
    if fit is not None and r.get("ref_fit") is not None:
        f += f" ({r['ref_fit']:.1f})"
    if r.get("stable") is False:
        f += " U"
    ws = sorted({SHORT.get(w.split(":")[0], w.split(":")[0]) for w in r["warnings"]})
    return f, " ".join(ws), "; ".join(flags(r))


def table(path: Path) -> str:
    """Markdown: per record and tool, the raw and detrended calls side by side."""
    rows = [json.loads(s) for s in path.read_text().splitlines() if s.strip()]
    by = {(r["record"], r["split"], r["tool"]): r for r in rows}
    keys = list(dict.fromkeys((r["record"], r["tool"]) for r in rows))
    lines = ["| record | tool | raw: fit (n4sid 2) | raw: warnings | detrended: fit (n4sid 2) | "
             "detrended: warnings | cpu s (raw/det) | failed checks |",
             "|---|---|---|---|---|---|---|---|"]
    for rec, tool in keys:
        a, b = by.get((rec, "raw", tool)), by.get((rec, "detrended", tool))
        fa, wa, xa = _cell(a)
        fb, wb, xb = _cell(b)
        cpu = "/".join(str(r["cpu"]) if r else "" for r in (a, b))
        x = "; ".join(t for t in (("raw: " + xa) if xa else "", ("det: " + xb) if xb else "")
                      if t)
        lines.append(f"| {rec} | {tool} | {fa} | {wa} | {fb} | {wb} | {cpu} | {x} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    rd.add_record_options(ap)
    ap.add_argument("--records", nargs="*", default=None)
    ap.add_argument("--tools", nargs="*", default=None, help="tool name prefixes")
    ap.add_argument("--out", default="benches/results/everyday_tools.jsonl")
    ap.add_argument("--table", default=None, help="print the table of a results .jsonl")
    args = ap.parse_args()
    if args.table:
        print(table(Path(args.table)))
        return
    sweep(rd.record_loaders(args), Path(args.out), args.records, args.tools)


if __name__ == "__main__":
    main()
