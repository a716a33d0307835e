"""A new user's pass of the nonlinear state-space defaults over the real records of the sixth to
eleventh sweeps (``benches/realdata_records.py``, ``FRESH6`` to ``FRESH11``; the records are not
shipped: each sweep's ``results/realdata_fresh<k>.md`` says where they come from).

For every record: ``ssest(est, n, focus="simulation")`` (the linear reference),
``pnlss(est, n)`` and ``nlssest(est, n)`` with no other settings, ``n = 3``; the validation
simulation fit (``sysid.compare``, mean over outputs), the seconds and every warning, one JSON
line per record. The split is the sweeps' (a separate validation file, else the first 2/3 to
estimate). Session 63's table is in ``results/nonlinear.md``.

    .venv/bin/python benches/nonlinear_fresh_pass.py OUT.jsonl --dirs \\
        FRESH6=DIR6,FRESH7=DIR7,FRESH8=DIR8,FRESH9=DIR9,FRESH10=DIR10,FRESH11=DIR11 \\
        [--order 3] [--only rec1,rec2] [--models linear,pnlss,nlssest]
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path

import numpy as np
import realdata_records as rr

import sysid


def _load(folder: str, name: str) -> tuple[np.ndarray, np.ndarray, float]:
    z = np.load(Path(folder) / f"{name}.npz")
    return z["u"], z["y"], float(z["dt"])


def _run(fn):
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as ws:
        warnings.simplefilter("always")
        try:
            out, err = fn(), None
        except Exception as e:  # noqa: BLE001 - reported, not hidden
            out, err = None, f"{type(e).__name__}: {str(e)[:200]}"
    said = [f"{w.category.__name__}: {str(w.message)[:220]}" for w in ws]
    return out, err, said, round(time.perf_counter() - t0, 1)


def _fit(model, val):
    if model is None:
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return round(float(np.mean(np.asarray(sysid.compare(val, model).fit))), 1)
        except Exception as e:  # noqa: BLE001
            return type(e).__name__


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--dirs", required=True, help="TABLE=DIR pairs, comma-separated")
    ap.add_argument("--order", type=int, default=3)
    ap.add_argument("--only", default=None)
    ap.add_argument("--models", default="linear,pnlss,nlssest")
    a = ap.parse_args()
    dirs = dict(kv.split("=", 1) for kv in a.dirs.split(","))
    only = None if a.only is None else set(a.only.split(","))
    n = a.order
    calls = {"linear": lambda est: sysid.ssest(est, n, focus="simulation"),
             "pnlss": lambda est: sysid.pnlss(est, n, progress=False),
             "nlssest": lambda est: sysid.nlssest(est, n, progress=False)}
    models = a.models.split(",")
    with open(a.out, "a") as out:
        for table, folder in dirs.items():
            for name, (ef, vf) in getattr(rr, table).items():
                if only is not None and name not in only:
                    continue
                u, y, dt = _load(folder, ef)
                if vf is None:
                    k = 2 * u.shape[0] // 3
                    est, val = sysid.IOData(u[:k], y[:k], dt), sysid.IOData(u[k:], y[k:], dt)
                else:
                    uv, yv, _ = _load(folder, vf)
                    est, val = sysid.IOData(u, y, dt), sysid.IOData(uv, yv, dt)
                row = {"record": name, "N": int(est.u.shape[0]), "m": est.n_inputs,
                       "l": est.n_outputs, "order": n}
                for label in models:
                    m, err, said, s = _run(lambda f=calls[label], e=est: f(e))
                    dc = {} if m is None or label != "pnlss" else m.info.get("degree_choice", {})
                    row[label] = {"fit": _fit(m, val), "s": s, "err": err, "w": said,
                                  "choice": dc.get("reason"),
                                  # the held-out table and each candidate's per-block fits
                                  "table": {str(k): v for k, v in dc.get("table", {}).items()},
                                  "folds": {str(k): v for k, v in dc.get("folds", {}).items()}}
                print(json.dumps(row), file=out, flush=True)
                print(name, {k: (row[k]["fit"], row[k]["s"]) for k in models}, flush=True)


if __name__ == "__main__":
    main()
