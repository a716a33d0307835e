"""The chirp follow-up of issue 26 (results/chirp_feedback.md): on every real record of
``realdata.py`` (shipped DaISy and F-16, the unshipped DaISy files, and the sweeps read from
``DIR/<name>.npz``), both splits,

- ``feedback``: the feedback test's combined p-value, the share of the input's innovation and
  of its variance that the past output innovations explain (largest over the inputs);
- ``coverage``: :func:`sysid.validation.coverage.input_coverage` of the validation part
  against the estimation part (per input, % of the validation input's power outside);
- ``folds``: the subspace order choice (``SubspaceEstimator.order_selection``, D = 0) with the
  contiguous held-out blocks against interleaved ones (each fold ``pieces`` short pieces spread
  over the record), and the validation simulation fit (clipped at -100 %) of the order chosen.

Usage::

    python benches/chirp_feedback.py feedback --daisy-dir /tmp/daisy2 --more /tmp/s49/more \\
        --fresh /tmp/s52/fresh --fresh2 /tmp/s52/fresh2 --fresh3 /tmp/s53/fresh3 \\
        --fresh4 /tmp/s53/fresh4
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import realdata as rd

import sysid
from sysid import _sysid
from sysid.subspace.estimator import SubspaceEstimator
from sysid.validation import crossval as cv
from sysid.validation.coverage import input_coverage
from sysid.validation.feedback import default_lags, f_sf

SWEEPS = (("more", "MORE"), ("fresh", "FRESH"), ("fresh2", "FRESH2"), ("fresh3", "FRESH3"),
          ("fresh4", "FRESH4"))


def records(args: argparse.Namespace):
    """(name, loader) of every record whose files are given; a loader reads the current
    ``rd.SPLIT``."""
    for name in rd.RECORDS:
        yield name, rd.RECORDS[name]
    if args.daisy_dir:
        for name in rd.UNSHIPPED:
            yield name, lambda n=name: rd._unshipped(Path(args.daisy_dir), n)
    for flag, table in SWEEPS:
        folder = getattr(args, flag)
        if folder:
            tab = getattr(rd, table)
            for name in tab:
                yield name, lambda n=name, t=tab, f=folder: rd._more(Path(f), n, t)


def feedback_row(u: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """(combined p, largest share of an input's innovation, largest share of its variance)."""
    d = sysid.IOData(u=u, y=y)
    lags = default_lags(d)
    exps = [(a - a.mean(0), b - b.mean(0)) for a, b in d.experiments]
    fac = _sysid.compress(exps, lags, 1, None, "qr")
    rr, rf, r_r, r_f, tot = _sysid.feedback_regressions(fac, 1e-9)
    q, df2 = r_f - r_r, int(fac.n_columns) - r_f
    ps, inn, var = [], [0.0], [0.0]
    for i in range(d.n_inputs):
        rss_r, rss_f, t = float(rr[i]), float(rf[i]), float(tot[i])
        if q <= 0 or df2 <= 0 or t <= 0 or rss_r <= 1e-10 * t:
            ps.append(1.0)
            continue
        F = max(rss_r - rss_f, 0.0) / q / (max(rss_f, 1e-300) / df2)
        ps.append(f_sf(F, q, df2))
        inn.append((rss_r - rss_f) / rss_r)
        var.append((rss_r - rss_f) / t)
    return min(1.0, len(ps) * min(ps)), max(inn), max(var)


def interleaved_folds(data: sysid.IOData, pieces: int) -> list:
    """Each of ``fold_count`` folds holds out ``pieces`` short pieces spread over the record
    (one experiment; the contiguous folds otherwise)."""
    if data.n_experiments > 1:
        return ORIGINAL_FOLDS(data)
    k = cv.fold_count(data)
    u, y = data.experiments[0]
    n = u.shape[0]
    total = k * pieces
    if n // total < max(cv.MIN_BLOCK, 8 * (data.n_inputs + data.n_outputs)):
        return ORIGINAL_FOLDS(data)
    kw = {"dt": data.dt, "input_names": data.input_names, "output_names": data.output_names}
    edges = np.linspace(0, n, total + 1).astype(int)
    out = []
    for i in range(k):
        held = set(range(i, total, k))
        rest, run = [], None
        for j in range(total):
            if j in held:
                if run is not None:
                    rest.append(run)
                run = None
            else:
                run = (edges[j], edges[j + 1]) if run is None else (run[0], edges[j + 1])
        if run is not None:
            rest.append(run)
        out.append((cv._io([(u[a:b], y[a:b]) for a, b in rest], kw),
                    cv._io([(u[edges[j]:edges[j + 1]], y[edges[j]:edges[j + 1]])
                            for j in sorted(held)], kw)))
    return out


ORIGINAL_FOLDS = cv.record_folds


def order_and_fit(est: sysid.IOData, val: sysid.IOData) -> tuple[int | None, float, float]:
    t = time.time()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            e = SubspaceEstimator(est)
            n = int(e.order_selection(feedthrough=False)["order"])
            fit = max(-100.0, cv.simulation_fit(e.fit(n), val))
    except Exception:  # noqa: BLE001 - recorded as a failure
        return None, float("nan"), time.time() - t
    return n, fit, time.time() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=("feedback", "coverage", "folds"))
    ap.add_argument("--daisy-dir")
    for flag, _ in SWEEPS:
        ap.add_argument(f"--{flag}")
    ap.add_argument("--pieces", type=int, default=4)
    args = ap.parse_args()
    for name, load in records(args):
        for split in ("default", "reversed"):
            rd.SPLIT = split
            (ue, ye), (uv, yv) = load()
            ue, ye = np.asarray(ue, float), np.asarray(ye, float)
            ue, ye = ue.reshape(len(ue), -1), ye.reshape(len(ye), -1)
            uv, yv = np.asarray(uv, float), np.asarray(yv, float)
            uv, yv = uv.reshape(len(uv), -1), yv.reshape(len(yv), -1)
            head = f"{name:20s} {split[:3]} N={ue.shape[0]:6d}"
            if args.what == "feedback":
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    p, inn, var = feedback_row(ue, ye)
                print(f"{head} p={p:9.2g} innovation={100 * inn:8.3g} % variance="
                      f"{100 * var:8.3g} %", flush=True)
            elif args.what == "coverage":
                c = input_coverage((ue, ye), (uv, yv))
                print(f"{head} outside={np.round(100 * c.outside, 1).tolist()} "
                      f"{'EXTRAPOLATES' if c.extrapolates else ''}", flush=True)
            else:
                est, val = sysid.IOData(u=ue, y=ye), sysid.IOData(u=uv, y=yv)
                cv.record_folds = ORIGINAL_FOLDS
                a = order_and_fit(est, val)
                cv.record_folds = lambda d: interleaved_folds(d, args.pieces)
                b = order_and_fit(est, val)
                cv.record_folds = ORIGINAL_FOLDS
                print(f"{head} contiguous n={a[0]} val={a[1]:7.1f} ({a[2]:.1f} s) | "
                      f"interleaved n={b[0]} val={b[1]:7.1f} ({b[2]:.1f} s)", flush=True)


if __name__ == "__main__":
    sys.exit(main())
