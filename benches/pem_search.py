"""Where the prediction-error search ends, on records where its path matters (issues 26, 28).

    .venv/bin/python benches/pem_search.py                 # both sets, about 2 minutes
    .venv/bin/python benches/pem_search.py --out a.json    # keep the rows (for an A/B)
    .venv/bin/python benches/pem_search.py --compare a.json b.json

Two sets, each refined with ``sysid.pem`` at its defaults but ``max_iter``:

- ``unstable``: the warning audit's unstable scenario (``benches/warning_audit.py``, seed 55,
  40 records: orders 2-6, one real pole at 1.01-1.03, N <= 800), the default prediction search
  from ``ssest``'s start (``max_iter=0``), and the same search run on (``max_iter=1000``,
  ``tol=1e-10``) and in the full parameterisation (``local_coordinates=False``) as references.
  Reported: the searches stopped at the cap, and the gap of each to the best reference in
  weighted-cost units (half residual variances).
- ``shipped``: the shipped records (dryer, ball and beam, robot arm, winding, pH, F-16 level
  2), the first half of each (at most 4 096 samples), means removed, ``n4sid`` with D at
  orders 2, 3, 4, 6 and 8 as the start, both focuses, ``max_iter=100``: 60 fits, each final
  criterion, iterations and stop.

``--compare`` prints, fit by fit, where two runs (two builds) differ by more than 0.1 % in the
final criterion, and the counts.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))

import sysid  # noqa: E402


def unstable_rows(runs: int = 40) -> list[dict]:
    from warning_audit import scenario_record

    rows = []
    for r in range(runs):
        est, _, facts, _ = scenario_record("unstable", r, 55)
        start = sysid.ssest(est, facts["order"], max_iter=0)
        fits = {}
        for name, kw in (("default", {}), ("long", dict(max_iter=1000, tol=1e-10)),
                         ("full", dict(local_coordinates=False, max_iter=1000, tol=1e-10))):
            t = time.perf_counter()
            m = sysid.pem(est, start, **kw)
            p = m.info["pem"]
            fits[name] = dict(cost=p["weighted_cost"][-1], iterations=p["iterations"],
                              stop=p["stop"], seconds=time.perf_counter() - t)
        best = min(f["cost"] for f in fits.values())
        rows.append(dict(set="unstable", record=r, order=facts["order"], **{
            f"{k}_{q}": v for k, f in fits.items() for q, v in f.items()},
            gap=fits["default"]["cost"] - best))
    return rows


def shipped_rows() -> list[dict]:
    ds = sysid.datasets
    recs = {"dryer": ds.load_dryer(), "ballbeam": ds.load_ballbeam(),
            "robot_arm": ds.load_robot_arm(), "winding": ds.load_winding(), "ph": ds.load_ph(),
            "f16": ds.load_f16_level2()}
    rows = []
    for name, d in recs.items():
        u, y = np.asarray(d.u), np.asarray(d.y)
        N = min(len(u) // 2, 4096)
        e = sysid.IOData(u=u[:N] - u[:N].mean(0), y=y[:N] - y[:N].mean(0), dt=1.0)
        for n in (2, 3, 4, 6, 8):
            start = sysid.n4sid(e, n, feedthrough=True)
            for focus in ("prediction", "simulation"):
                t = time.perf_counter()
                m = sysid.pem(e, start, focus=focus, max_iter=100)
                p = m.info["pem"]
                rows.append(dict(set="shipped", record=name, order=n, focus=focus,
                                 cost=p["cost"][-1], iterations=p["iterations"],
                                 stop=p["stop"], seconds=time.perf_counter() - t))
    return rows


def summary(rows: list[dict]) -> None:
    un = [r for r in rows if r["set"] == "unstable"]
    if un:
        capped = sum(r["default_stop"] == "maximum iterations" for r in un)
        far = sum(r["gap"] > 0.05 for r in un)
        its = sum(r["default_iterations"] for r in un)
        print(f"unstable: {len(un)} records, default search at its cap on {capped}, more than "
              f"0.05 above the best reference on {far}, {its} iterations in all")
    sh = [r for r in rows if r["set"] == "shipped"]
    if sh:
        capped = sum(r["stop"] == "maximum iterations" for r in sh)
        print(f"shipped: {len(sh)} fits, {sum(r['iterations'] for r in sh)} iterations, "
              f"{capped} at the cap")


def compare(a: list[dict], b: list[dict]) -> None:
    better = worse = 0
    for ra, rb in zip(a, b):
        if ra["set"] != "shipped":
            continue
        rel = (rb["cost"] - ra["cost"]) / abs(ra["cost"])
        if abs(rel) > 1e-3:
            better += rel < 0
            worse += rel > 0
            print(f"{ra['record']:10s} {ra['order']} {ra['focus']:10s} {ra['cost']:.6g} -> "
                  f"{rb['cost']:.6g} ({rel:+.1%}), iterations {ra['iterations']} -> "
                  f"{rb['iterations']}")
    print(f"shipped: second run lower by more than 0.1 % in {better} fits, higher in {worse}")
    for rows, label in ((a, "first"), (b, "second")):
        print(f"{label}: ", end="")
        summary(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="write the rows as JSON")
    ap.add_argument("--compare", nargs=2, metavar=("A", "B"), help="two --out files")
    args = ap.parse_args()
    if args.compare:
        a, b = (json.load(open(f)) for f in args.compare)
        compare(a, b)
        return
    warnings.simplefilter("ignore")
    rows = unstable_rows() + shipped_rows()
    summary(rows)
    if args.out:
        with open(args.out, "w") as f:
            json.dump(rows, f)


if __name__ == "__main__":
    main()
