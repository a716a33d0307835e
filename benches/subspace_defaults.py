"""Subspace defaults on real records: B, D from the regression on the factor (``fit()``)
against B, D, x0 by least squares on the data (``fit(x0=True)``), and the ``ssest`` start.

    .venv/bin/python benches/subspace_defaults.py        # about a minute

Records: the DaISy records bundled with the package (``sysid.datasets``) and, while not yet
bundled, the same files from ``/work/shared/data/daisy`` (DaISy, KU Leuven; unmodified copies,
see that folder's README for sources and checksums). Estimation mean removed (the same mean from
the validation part); the score is the validation simulation fit (%) with the initial state
fitted by least squares (``sysid.compare``), averaged over the outputs.
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import sysid
from sysid.subspace.estimator import SubspaceEstimator

SHARED = Path("/work/shared/data/daisy")

# name, input columns, output columns (0-based), estimation samples, order, feedthrough, note
RECORDS = [
    ("dryer", [0], [1], 500, 4, False, "issue 11 split"),
    ("robot_arm", [0], [1], 800, 6, False, "issue 11 split"),
    ("winding", [0, 1, 2, 3, 4], [5, 6], 1500, 6, True, "issue 11 split"),
    ("flutter", [0], [1], 700, 6, False, "README order"),
    ("thermic_res_wall", [0, 1], [2], 1200, 3, False, "README split"),
    ("cstr", [1], [2, 3], 5000, 5, False, "README order; column 1 is time"),
]


def load(name: str) -> np.ndarray:
    if name in sysid.datasets.NAMES:
        return np.loadtxt(sysid.datasets.path(name))
    return np.loadtxt(SHARED / f"{name}.dat")


def fit_pct(model: sysid.StateSpaceModel, val: sysid.IOData) -> float:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return float(np.mean(sysid.compare(model, val).fit))
    except Exception:  # noqa: BLE001 - an unusable model scores -inf
        return float("-inf")


def main() -> None:
    rows = []
    for name, ins, outs, n_est, order, ft, note in RECORDS:
        d = load(name)
        u, y = d[:, ins], d[:, outs]
        u, y = u - u[:n_est].mean(0), y - y[:n_est].mean(0)
        est = sysid.IOData(u=u[:n_est], y=y[:n_est])
        val = sysid.IOData(u=u[n_est:], y=y[n_est:])
        row = {"record": name, "order": order, "note": note}
        sub = SubspaceEstimator(est, None)
        for method in ("moesp", "n4sid", "cva"):
            on_est = {}
            for x0 in (False, True):
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    m = sub.fit(order, method=method, feedthrough=ft, x0=x0)
                key = f"{method}{'+x0' if x0 else ''}"
                row[key] = fit_pct(m, val)
                row[key + " stable"] = bool(np.max(np.abs(m.poles())) < 1)
                on_est[key] = fit_pct(m, est)
            # the rule: keep the one that simulates the estimation data better
            row[method + " picked"] = row[max(on_est, key=lambda k: on_est[k])]
        t = time.perf_counter()
        for focus in ("prediction", "simulation"):
            m = sysid.ssest(est, order, feedthrough=ft, focus=focus)
            row[f"ssest {focus} start"] = (m.info["start"]["method"]
                                           + ("+x0" if m.info["start"]["bd_x0"] else ""))
            row[f"ssest {focus}"] = fit_pct(m, val)
        row["ssest s"] = time.perf_counter() - t
        rows.append(row)
        print(json.dumps(row), file=sys.stderr, flush=True)
    keys = [f"{m}{s}" for m in ("moesp", "n4sid", "cva") for s in ("", "+x0")]
    print("| record (order) | " + " | ".join(keys)
          + " | ssest prediction (start) | ssest simulation (start) |")
    print("|---" * (len(keys) + 3) + "|")
    for r in rows:
        cells = [(f"{r[k]:.1f}" if r[k] > -1e3 else "diverges")
                 + ("" if r[k + " stable"] else " (unstable A)") for k in keys]
        print(f"| {r['record']} ({r['order']}) | " + " | ".join(cells)
              + f" | {r['ssest prediction']:.1f} ({r['ssest prediction start']}) | "
              + f"{r['ssest simulation']:.1f} ({r['ssest simulation start']}) |")
    print("\nRegret (validation fit below the better of the two, points; mean / worst over the "
          "stable record-weighting pairs):")
    for rule, pick in (("fit() (B, D from the factor)", lambda r, m: r[m]),
                       ("fit(x0=True)", lambda r, m: r[m + "+x0"]),
                       ("the better on the estimation data", lambda r, m: r[m + " picked"])):
        reg = [max(r[m], r[m + "+x0"]) - pick(r, m) for r in rows
               for m in ("moesp", "n4sid", "cva") if r[m + " stable"] and r[m + "+x0 stable"]]
        print(f"- {rule}: {np.mean(reg):.2f} / {np.max(reg):.2f}")
    wins = sum(max(r[f"{m}+x0"] for m in ("moesp", "n4sid", "cva"))
               > max(r[m] for m in ("moesp", "n4sid", "cva")) for r in rows)
    print(f"\nfit(x0=True) best on {wins} of {len(rows)} records")


if __name__ == "__main__":
    main()
