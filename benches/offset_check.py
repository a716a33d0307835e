"""The shared offset check against the fit an offset costs, on every record of the realdata
tables (issue 26): per record the largest ``|mean| / std`` of a channel the check looks at
(``sysid.data.offsets``), the statistic of the check, and the validation fit of ``n4sid``,
``oe`` and ``arx`` fitted on the raw records against the same fitted on the records with the
estimation means removed (the validation part with the same means removed), on the bench
split of ``benches/realdata.py``.

    PYTHONPATH=python .venv/bin/python benches/offset_check.py --unshipped /tmp/daisy2 \\
        --more-records DIR --fresh-records DIR --fresh2-records DIR [--split reversed]

Rows go to stdout as JSON lines and a Markdown table at the end.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import realdata as rd  # noqa: E402


def _fit(model, val) -> float:
    import sysid

    try:
        with np.errstate(all="ignore"):
            f = float(sysid.compare(model, val).mean_fit)
    except Exception:  # noqa: BLE001 - a diverging model scores -inf
        return -np.inf
    return f if np.isfinite(f) else -np.inf


def measure(name: str, load) -> dict:
    import sysid
    from sysid.data import offsets as off

    (ue, ye), (uv, yv) = load()
    mu, my = ue.mean(0), ye.mean(0)
    raw, rval = sysid.IOData(u=ue, y=ye), sysid.IOData(u=uv, y=yv)
    cen, cval = sysid.IOData(u=ue - mu, y=ye - my), sysid.IOData(u=uv - mu, y=yv - my)
    # the largest |mean| / std of every non-constant channel, and of those the check looks at
    ratio = max(float(np.max(np.abs(x.mean(0)) / np.where(x.std(0) > 0, x.std(0), np.inf)))
                for x in (ue, ye))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = time.perf_counter()
        flagged = off.offsets(raw)  # the check as it is now
        # the ratio rule alone (before issue 26's fix): the channels flagged by it, which the
        # check returns alone whenever there are any
        old = [r for r in flagged if abs(r[2]) > off.OFFSET_RATIO * r[3]]
        effect = off.offset_effect(raw)
        t_effect = time.perf_counter() - t
    row = {"record": name, "split": rd.SPLIT, "N": int(ue.shape[0]), "nu": int(ue.shape[1]),
           "ny": int(ye.shape[1]), "max_ratio": ratio,
           "checked_ratio": max([abs(m) / s for _, _, m, s in flagged], default=0.0),
           "ratio_rule": bool(old), "check_warns": bool(flagged), "effect": effect,
           "effect_s": t_effect}
    fits = {
        "n4sid": lambda d: sysid.n4sid(d),
        "oe": lambda d: sysid.oe(d, 2, 2, 1),
        "arx": lambda d: sysid.arx(d, 2, 2, 1),
    }
    for tool, fn in fits.items():
        for kind, d, v in (("raw", raw, rval), ("centred", cen, cval)):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    row[f"{tool}_{kind}"] = _fit(fn(d), v)
                except Exception as e:  # noqa: BLE001 - recorded
                    row[f"{tool}_{kind}"] = None
                    row[f"{tool}_{kind}_error"] = f"{type(e).__name__}: {e}"[:80]
    return row


def _f(x) -> str:
    return "-" if x is None else ("-inf" if not np.isfinite(x) else f"{x:.1f}")


def table(rows: list[dict]) -> str:
    out = ["| record | max abs(mean)/std | ratio rule (> 10) | effect | check now "
           "| n4sid raw / centred | oe raw / centred | arx raw / centred | largest loss |",
           "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        losses = [r[f"{t}_centred"] - r[f"{t}_raw"] for t in ("n4sid", "oe", "arx")
                  if r.get(f"{t}_raw") is not None and r.get(f"{t}_centred") is not None
                  and np.isfinite(r[f"{t}_centred"])]
        loss = max(losses, default=None)
        loss_s = "-" if loss is None else ("inf" if not np.isfinite(loss) else f"{loss:.1f}")
        out.append(
            f"| {r['record']} | {r['max_ratio']:.2f} | {'warns' if r['ratio_rule'] else '-'}"
            f" | {r['effect']:.3f} | {'warns' if r['check_warns'] else '-'}"
            f" | {_f(r['n4sid_raw'])} / {_f(r['n4sid_centred'])}"
            f" | {_f(r['oe_raw'])} / {_f(r['oe_centred'])}"
            f" | {_f(r['arx_raw'])} / {_f(r['arx_centred'])} | {loss_s} |")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--split", choices=rd.SPLITS, default="default")
    rd.add_record_options(ap)
    ap.add_argument("--records", nargs="*", default=None, help="only these records")
    ap.add_argument("--json", default=None, help="also write the rows to this file")
    args = ap.parse_args()
    rd.SPLIT = args.split
    loads = rd.record_loaders(args)
    rows = []
    for name, load in loads.items():
        if args.records and name not in args.records:
            continue
        r = measure(name, load)
        rows.append(r)
        print(json.dumps(r), flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    print(table(rows))


if __name__ == "__main__":
    main()
