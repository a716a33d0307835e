"""The check behind ``FeedthroughWarning`` on real records: does a direct term that halves the
one-step prediction errors of a subspace fit also make it simulate new data better?

    SYSID_SHARED=/work/shared .venv/bin/python benches/feedthrough_check.py
    ... benches/feedthrough_check.py --unshipped DIR --more-records DIR2 --nonlinear-records DIR3

For every record of ``benches/realdata.py`` (the shipped ones; with the options also the
records the project does not ship, read as that bench reads them) and orders 2, 4 and 8:
the MOESP fit without and with ``D`` on the estimation part (means removed), the ratio of
their one-step prediction errors on it (what :func:`sysid.subspace.feedthrough.
warn_if_left_out` compares with ``LEFT_OUT_RATIO``), and their simulation fits on the
validation part. The summary counts, above and below the threshold, the fits whose
validation fit is higher with ``D``.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import realdata as rd  # noqa: E402

import sysid  # noqa: E402
from sysid.subspace.feedthrough import LEFT_OUT_RATIO, _prediction_error  # noqa: E402

ORDERS = (2, 4, 8)


def records(args: argparse.Namespace) -> dict[str, object]:
    out = {name: load for name, load in rd.RECORDS.items()
           if name not in ("destill", "f16_level1", "f16_level3")}  # too short / too long
    if args.unshipped:
        out |= {n: (lambda n=n: rd._unshipped(Path(args.unshipped), n)) for n in rd.UNSHIPPED}
    if args.more_records:
        out |= {n: (lambda n=n: rd._more(Path(args.more_records), n)) for n in rd.MORE}
    if args.nonlinear_records:
        out |= {n: (lambda n=n: rd._nonlinear(args.nonlinear_records, n))
                for n in rd.NONLINEAR_TESTS}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--unshipped", default=None, metavar="DIR")
    ap.add_argument("--more-records", default=None, metavar="DIR")
    ap.add_argument("--nonlinear-records", default=None, metavar="DIR")
    args = ap.parse_args()
    rows = []
    print("| record | order | error ratio without / with D | validation fit without D | "
          "with D |\n|---|---|---|---|---|")
    for name, load in records(args).items():
        (ue, ye), (uv, yv) = load()
        mu, my = np.mean(ue, axis=0), np.mean(ye, axis=0)
        est_data = sysid.IOData(u=np.asarray(ue) - mu, y=np.asarray(ye) - my)
        val = sysid.IOData(u=np.asarray(uv) - mu, y=np.asarray(yv) - my)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            est = sysid.SubspaceEstimator(est_data)
            for n in ORDERS:
                if n > est.max_order:
                    continue
                models = [est.fit(n, feedthrough=ft) for ft in (False, True)]
                ratio = (_prediction_error(models[0], est_data)
                         / _prediction_error(models[1], est_data))
                fits = [float(np.mean(sysid.compare(val, m).fit)) for m in models]
                rows.append((ratio, fits))
                print(f"| {name} | {n} | {ratio:.2f} | {fits[0]:.1f} | {fits[1]:.1f} |",
                      flush=True)
    for above in (True, False):
        sel = [f for r, f in rows if (r >= LEFT_OUT_RATIO) == above]
        better = sum(f[1] > f[0] for f in sel)
        gains = [f[1] - f[0] for f in sel if np.isfinite(f[1] - f[0])]
        side = "at or above" if above else "below"
        print(f"\nratio {side} {LEFT_OUT_RATIO:g}: {len(sel)} fits, validation fit higher with "
              f"D in {better}" + (f" (gain from {min(gains):.1f} to {max(gains):.1f} points)"
                                  if gains else ""))


if __name__ == "__main__":
    main()
