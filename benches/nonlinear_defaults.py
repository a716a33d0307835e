"""The nonlinear estimators' automatic structures on real records: ``nlarx`` (``basis="auto"``)
and ``nlhw_ss`` (nonlinearities ``"auto"``) against each of their two candidates fitted alone.

    SYSID_SHARED=/path/to/shared .venv/bin/python benches/nonlinear_defaults.py
    ... --unshipped DIR --more-records DIR --nonlinear-records DIR   # records not shipped
    ... --splits default reversed --out results/nonlinear_defaults.md

Per record and split (``benches/realdata.py``'s records, splits and loaders; order 2, pH 3),
the validation simulation fit (``sysid.compare``, initial state fitted, % mean over outputs,
at least -100 % so that one runaway record does not decide a sum) of:

- ``nlarx(data, n, n)`` at its default, which chooses between the two next ones on held-out
  blocks of the estimation record; ``nlarx(..., basis=PolynomialBasis(2))`` (the old
  default); the linear ARX model of the same lags (degree 1, every term, least squares);
- ``nlhw_ss(data, n)`` at its default; with the identity on both sides (the old default);
  with 3-unit sigmoid networks on both sides.

The last row sums each column: what each rule, applied to every record, would have given.
Nothing here is tuned: the rule (``sysid.validation.crossval.insists``) is the one
``pnlss``'s automatic degree uses.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, os.path.dirname(__file__))

import realdata as rd  # noqa: E402

import sysid  # noqa: E402
from sysid.validation.crossval import held_out_fit  # noqa: E402

ORDER = {"ph": 3}
SHIPPED = ["dryer", "robot_arm", "thermic_res_wall", "winding", "cstr", "ballbeam", "ph"]


def candidates(d: sysid.IOData, n: int) -> dict:
    """Column name: (fit, the structure chosen or None)."""
    m, p = d.n_inputs, d.n_outputs
    sig = {"input_nl": [sysid.SigmoidNetwork(3) for _ in range(m)],
           "output_nl": [sysid.SigmoidNetwork(3) for _ in range(p)]}
    return {
        "nlarx auto": lambda: sysid.nlarx(d, n, n),
        "nlarx degree 2": lambda: sysid.nlarx(d, n, n, basis=sysid.PolynomialBasis(2)),
        "linear ARX": lambda: sysid.nlarx(d, n, n, basis=sysid.PolynomialBasis(1),
                                          criterion=None, max_terms=1000, err_tol=0.0),
        "nlhw_ss auto": lambda: sysid.nlhw_ss(d, n, progress=False),
        "nlhw_ss identity": lambda: sysid.nlhw_ss(d, n, input_nl=None, output_nl=None,
                                                  progress=False),
        "nlhw_ss sigmoid": lambda: sysid.nlhw_ss(d, n, progress=False, **sig),
    }


def run(name: str, load, split: str) -> dict:
    rd.SPLIT = split
    (ue, ye), (uv, yv) = load()
    d, v = sysid.IOData(u=ue, y=ye), sysid.IOData(u=uv, y=yv)
    n = ORDER.get(name, 2)
    row = {"record": name, "split": split, "order": n, "fit": {}, "seconds": {}, "chose": {}}
    for col, fit in candidates(d, n).items():
        t = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                model = fit()
                row["fit"][col] = round(held_out_fit(model, v), 2)
                kind = {**model.info.get("basis_choice", {}),
                        **model.info.get("nonlinearity_choice", {})}.get("kind")
                if kind is not None:
                    row["chose"][col] = kind
            except sysid.SysidError as e:
                row["fit"][col] = -100.0
                row["chose"][col] = f"error: {str(e)[:60]}"
        row["seconds"][col] = round(time.perf_counter() - t, 2)
    return row


def table(rows: list[dict], command: str) -> str:
    cols = list(rows[0]["fit"])
    out = ["# Nonlinear estimators' automatic structures on real records", "",
           f"Command: `{command}` ({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}). "
           "Validation simulation fit (%, at least -100); the automatic columns name the "
           "structure chosen. See the docstring of benches/nonlinear_defaults.py.", "",
           "| record | split | " + " | ".join(cols) + " |",
           "|---|---|" + "---|" * len(cols)]
    for r in rows:
        cells = [f"{r['fit'][c]:.1f}" + (f" ({r['chose'][c]})" if c in r["chose"] else "")
                 for c in cols]
        out.append(f"| {r['record']} | {r['split']} | " + " | ".join(cells) + " |")
    out.append("| **sum** | | " + " | ".join(f"**{sum(r['fit'][c] for r in rows):.1f}**"
                                             for c in cols) + " |")
    secs = {c: max(r["seconds"][c] for r in rows) for c in cols}
    out += ["", "Longest fit per column (s): "
            + ", ".join(f"{c} {s:.1f}" for c, s in secs.items()), ""]
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", nargs="*", default=SHIPPED)
    ap.add_argument("--splits", nargs="*", default=["default", "reversed"])
    ap.add_argument("--unshipped", default=None, metavar="DIR")
    ap.add_argument("--more-records", default=None, metavar="DIR")
    ap.add_argument("--nonlinear-records", default=None, metavar="DIR")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    loads = {name: rd.RECORDS[name] for name in args.records}
    if args.unshipped:
        loads.update({k: (lambda k=k: rd._unshipped(Path(args.unshipped), k))
                      for k in ("exchanger", "heating_system", "dryer2")})
    if args.more_records:
        loads.update({k: (lambda k=k: rd._more(Path(args.more_records), k))
                      for k in ("gas_furnace", "buck", "dc_motor", "mr_damper")})
    # records whose validation part is a separate test record keep it: one split
    fixed = {k for k, (_, val) in rd.MORE.items() if val is not None}
    if args.nonlinear_records:
        loads.update({k: (lambda k=k: rd._nonlinear(args.nonlinear_records, k))
                      for k in rd.NONLINEAR_TESTS})
        fixed |= set(rd.NONLINEAR_TESTS)
    rows = []
    for name, load in loads.items():
        for split in (["default"] if name in fixed else args.splits):
            row = run(name, load, split)
            print(json.dumps(row), flush=True)
            rows.append(row)
    command = "benches/nonlinear_defaults.py " + " ".join(sys.argv[1:])
    text = table(rows, command)
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n")
        Path(args.out).with_suffix(".json").write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
