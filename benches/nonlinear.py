"""Nonlinear benchmarks: best linear model, nlarx, nlhw, pnlss and nlssest on the F-16 ground
vibration test, the Bouc-Wen hysteresis benchmark and the pH neutralisation record.

Reports the test RMSE (in the output's units, over all outputs) and the fit (NRMSE %, mean
over outputs) of each model's simulation, and the wall time of each fit. Every model is
simulated from rest; for the periodic F-16 validation record one period is simulated first
and discarded (steady state), as for all models alike. Settings are the documented defaults
scaled to each record's size, not tuned on the test data. The best linear model is the better
of the linear rows (``ssest`` on the simulation error with its initial state estimated; for one
input and output also ``oe``, fitted from rest).

    .venv/bin/python benches/nonlinear.py [--only boucwen,ph,f16] [--out FILE]
        [--models PREFIXES] [--nlssest "regularization=1e-3"]

Bouc-Wen needs ../shared/data/boucwen/*.h5 and h5py (bench-only: pip install h5py).
"""

from __future__ import annotations

import argparse
import ast
import os
import sys
import time
import traceback

import numpy as np

import sysid

_ROOT = os.path.dirname(os.path.abspath(__file__))
SHARED = os.environ.get("SYSID_SHARED_DATA") or next(
    (p for p in (os.path.join(_ROOT, "..", "..", "shared", "data"),
                 os.path.join(_ROOT, "..", "..", "..", "shared", "data")) if os.path.isdir(p)),
    os.path.join(_ROOT, "..", "..", "shared", "data"))


def metrics(y, yh):
    e = y - yh
    rmse = float(np.sqrt(np.mean(e ** 2)))
    fit = float(np.mean(100 * (1 - np.linalg.norm(e, axis=0)
                               / np.linalg.norm(y - y.mean(axis=0), axis=0))))
    return rmse, fit


def sim(model, u, warm=None):
    if warm is not None:
        return np.asarray(model.simulate(np.vstack([u[-warm:], u])))[warm:]
    return np.asarray(model.simulate(u))


def boucwen():
    import h5py

    def load(f, g):
        with h5py.File(os.path.join(SHARED, "boucwen", f)) as h:
            return np.asarray(h[g]["u"]).reshape(-1, 1), np.asarray(h[g]["y"]).reshape(-1, 1), \
                float(np.asarray(h[g]["fs"]).ravel()[0])
    u, y, fs = load("train.h5", "multisine")
    train = sysid.IOData(u, y, 1 / fs)
    tests = {k: load("test.h5", k)[:2] for k in ("multisine", "sinesweep")}
    return train, tests, None, dict(order=3, na=3, nb=3, hidden=16, lags=10, periods=None)


def ph():
    d = sysid.datasets.load_ph()
    n = d.u.shape[0]
    cut = int(n * 0.6)
    train = sysid.IOData(d.u[:cut], d.y[:cut], d.dt)
    return train, {"last 40 %": (d.u[cut:], d.y[cut:])}, None, \
        dict(order=3, na=3, nb=3, hidden=16, lags=6, periods=None)


def f16():
    l1 = sysid.datasets.load_f16()
    l3 = sysid.datasets.load_f16_level3()
    l2 = sysid.datasets.load_f16_level2()
    P = 8192
    train = sysid.IOData([l1.u[P:], l3.u], [l1.y[P:], l3.y], l1.dt)
    return train, {"level 2": (l2.u, l2.y)}, P, \
        dict(order=10, na=4, nb=4, hidden=16, lags=20, periods=[8, 3])


class Offset:
    """A baseline fitted on the record with its training means removed (pnlss and nlssest
    remove them themselves); simulate adds them back."""

    def __init__(self, d, fit):
        u = np.vstack([e[0] for e in d.experiments])
        y = np.vstack([e[1] for e in d.experiments])
        self.u0, self.y0 = u.mean(axis=0), y.mean(axis=0)
        self.model = fit(sysid.IOData([e[0] - self.u0 for e in d.experiments],
                                      [e[1] - self.y0 for e in d.experiments], d.dt))

    def simulate(self, u):
        return np.asarray(self.model.simulate(u - self.u0)).reshape(len(u), -1) + self.y0


MODELS: list[str] = []  # name prefixes to fit (empty: all)
NLSSEST: dict = {}  # extra keyword arguments of nlssest (--nlssest), named in its row
BUDGET = 540.0  # seconds of training per model (the bound: 10 minutes on 2 cores)


class Budget:
    """A progress callable that stops an iterative fit after ``BUDGET`` seconds (the
    estimators return their best model so far and say they were cancelled)."""

    def __init__(self):
        self.t0 = time.perf_counter()
        self.hit = False

    def __call__(self, *_):
        if time.perf_counter() - self.t0 > BUDGET:
            self.hit = True
            return False
        return None


def fits(train, s):
    m, l_ = train.n_inputs, train.n_outputs
    n = s["order"]
    out = {}

    def timed(name, f):
        if MODELS and not any(name.startswith(p) for p in MODELS):
            return
        t0 = time.perf_counter()
        try:
            out[name] = (f(), time.perf_counter() - t0)
        except Exception as e:  # report, do not hide
            out[name] = (e, time.perf_counter() - t0)
            traceback.print_exc()
        print(f"  {name}: {out[name][1]:.1f} s", file=sys.stderr, flush=True)

    timed("linear (ssest, simulation focus)",
          lambda: Offset(train, lambda d: sysid.ssest(d, n, focus="simulation",
                                                      progress=False)))
    if m == 1 and l_ == 1:
        # a second linear bar: the simulation-error fit from rest (no initial state in its
        # criterion, as every model here is scored); on an integrating plant the two differ
        # (EMPS: the free initial state of ssest's criterion holds the integrator's start)
        timed("linear (oe, nb = nf = order)",
              lambda: Offset(train, lambda d: sysid.oe(d, n, n, 1, progress=False)))
        timed("nlarx (polynomial degree 3, FROLS)",
              lambda: Offset(train, lambda d: sysid.nlarx(d, s["na"], s["nb"],
                                                          basis=sysid.PolynomialBasis(3),
                                                          max_terms=20)))
        timed("nlhw (sigmoid in/out, 3 units)",
              lambda: sysid.nlhw(train, s["nb"], s["na"], input_nl=sysid.SigmoidNetwork(3),
                                 output_nl=sysid.SigmoidNetwork(3), progress=False))
    else:
        timed("nlarx (polynomial degree 3, FROLS)",
              lambda: Offset(train, lambda d: sysid.nlarx(
                  d, [s["na"]] * l_, [s["nb"]] * m, [1] * m, basis=sysid.PolynomialBasis(3),
                  max_terms=20)))
        timed(f"nlhw (nlhw_ss, sigmoid in/out, 3 units; at most {BUDGET:.0f} s)",
              lambda: Offset(train, lambda d: sysid.nlhw_ss(
                  d, n, input_nl=sysid.SigmoidNetwork(3), output_nl=sysid.SigmoidNetwork(3),
                  progress=Budget())))
    # all monomials for small models; else those of the output-aligned states and inputs
    terms = "full" if n + m <= 5 else "outputs"
    timed(f"pnlss (degree 2-3, {terms}, linear out)",
          lambda: sysid.pnlss(train, n, degree=3, terms=terms, output_terms="none",
                              max_iter=50, progress=Budget()))
    if terms == "full":  # the automatic degree costs about ten fits: small models only
        timed("pnlss (degree auto, full, linear out)",
              lambda: sysid.pnlss(train, n, terms=terms, output_terms="none", max_iter=50,
                                  progress=Budget()))
    if s["periods"] is not None:
        timed(f"pnlss weighted (degree 2-3, {terms}, weighting='bla')",
              lambda: sysid.pnlss(train, n, degree=3, terms=terms, output_terms="none",
                                  periods=s["periods"], weighting="bla", max_iter=50,
                                  progress=Budget()))
    r = max(2, n // 2)
    timed(f"pnlss decoupled (degree 2-3, {r} branches)",
          lambda: sysid.pnlss(train, n, degree=3, branches=r, max_iter=50,
                              progress=Budget()))
    extra = "".join(f", {k}={v!r}" for k, v in NLSSEST.items())
    timed(f"nlssest (hidden {s['hidden']}, lags {s['lags']}{extra})",
          lambda: sysid.nlssest(train, n, hidden=s["hidden"], lags=s["lags"], epochs=150,
                                progress=Budget(), **NLSSEST))
    return out


def stop(mod):
    """Why an iterative fit stopped (from the model's info), '-' otherwise."""
    info = getattr(getattr(mod, "model", mod), "info", None) or {}
    for key in ("fit", "training", "search", "optimizer"):
        if isinstance(info.get(key), dict) and "stop" in info[key]:
            return str(info[key]["stop"])
    return str(info.get("stop", "-"))


def run(name, loader, lines):
    train, tests, warm, s = loader()
    print(f"{name}: training {train}", file=sys.stderr, flush=True)
    models = fits(train, s)
    lines += [f"\n### {name}\n", f"training: {train}; order {s['order']}\n",
              "| model | " + " | ".join(f"{k} RMSE | {k} fit %" for k in tests)
              + " | fit time (s) | stop |",
              "|---|" + "---|---|" * len(tests) + "---|---|"]
    for mname, (mod, t) in models.items():
        cells = []
        for u, y in tests.values():
            if isinstance(mod, Exception):
                cells += ["failed", type(mod).__name__]
                continue
            try:
                r, f = metrics(y, sim(mod, u, warm))
                cells += [f"{r:.4g}", f"{f:.1f}"]
            except Exception as e:
                cells += ["diverged" if "diverg" in str(e) else "failed", type(e).__name__]
        lines.append(f"| {mname} | " + " | ".join(cells) + f" | {t:.1f} | {stop(mod)} |")
    print("\n".join(lines[-len(models) - 2:]), flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--only", default="boucwen,ph,f16")
    ap.add_argument("--out", default=None)
    ap.add_argument("--models", default=None,
                    help="comma-separated name prefixes of the models to fit (default: all)")
    ap.add_argument("--nlssest", default="",
                    help="extra nlssest keyword arguments, e.g. 'regularization=1e-3,seed=1' "
                         "(values read as Python literals)")
    a = ap.parse_args()
    MODELS[:] = [] if a.models is None else a.models.split(",")
    NLSSEST.update({k.strip(): ast.literal_eval(v) for k, v in
                    (kv.split("=", 1) for kv in a.nlssest.split(",") if kv.strip())})
    lines = [f"sysid {sysid.__version__}; command: .venv/bin/python benches/nonlinear.py "
             f"--only {a.only}" + (f" --models {a.models}" if a.models else "")
             + f"; {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}"]
    for name in a.only.split(","):
        run(name, {"boucwen": boucwen, "ph": ph, "f16": f16}[name], lines)
    if a.out:
        with open(a.out, "a") as f:
            f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
