"""Which selection rule would ``sysid.identify`` need to choose better-validating models? A
measurement on the real records of ``benches/realdata.py`` (results at the top of
``results/identify_candidates.md``); no library code is changed.

    .venv/bin/python benches/identify_rules.py capture OUT.json --splits default reversed \
        [--unshipped DIR] [--more-records DIR] [--records NAME ...] [--top 15]
    .venv/bin/python benches/identify_rules.py compare OUT.json [MORE.json ...]

``capture`` runs ``sysid.identify`` (no settings) on the estimation part of every record x
split (the records, splits and loaders of ``realdata.py``: the shipped records, with
``--unshipped`` the DaISy records it does not ship, with ``--more-records`` the others; the
records with a separate validation record keep their split, so they run under ``default``
only), catches its leaderboard by wrapping ``sysid.identify.core._choose`` (the board is read,
never changed: the choice is identify's own), and for the candidates that scored on every
held-out block with stable block models (the ``--top`` best by held-out score, the three best
by each score below and every one identify re-fitted for its BIC) re-fits each on the whole
estimation part as identify does (``row["refit"]`` on the very centred record object
identify re-fits on: a refinement uses its block fits as further starts only there) and
scores it on the validation part as the bench does (``realdata.score``: simulation fit,
initial state by least squares). It writes one JSON object per record x split: identify's
own validation fit and choice, the block shares and every scored row (block fits, held-out
score, BIC where identify computed one, parameter count, order, the re-fit's stability and
validation fit).

``compare`` applies, offline, each rule below to the rows whose re-fit on the whole record is
stable and reports per split: in how many record-splits the rule's pick meets the bench's goal
(``realdata.write_md``: stable and within 0.5 points of the best *other* tool of the bench's
JSON tables ``results/realdata*.json``, or no other tool above 0 %; "+ s.o." also counts the
bench's weaker "stable others: yes"), how often it is within 0.5 points of the best
candidate on the board, and its mean, median and worst regret against that best candidate
(none when the pick validates above it: identify's own pick can be an unstable model the
data insist on, outside the stable candidates the rules pick among).

- R0: identify's actual choice (its returned model, as the bench scores it);
- R1: the best held-out score (the board's: pooled over the blocks without the best and worst);
- R1m: the best plain mean of the block fits;
- R2: the best fit on the last (most recent) block;
- R3: the best recency-weighted block mean (weights 1, 2, ..., K in time order);
- R4: one-standard-error rule: the lowest order within one paired standard error
  (``Board.paired_se``) of R1's pick's score (ties: the better score);
- R5: the lowest BIC among the candidates identify re-fitted (its near-best set), else R1;
- oracle: the best validation fit among the scored candidates (an upper bound for any rule
  that picks among them).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import realdata as rd  # noqa: E402

#: records whose validation part is a separate record: the same split under every --split
SEPARATE = {"f16_level1", "f16_level3", "buck", "ind_robot"}


# -- capture ----------------------------------------------------------------------------------
def _recency(fits: list[float]) -> float:
    f = np.asarray(fits, float)
    w = np.arange(1, f.size + 1, dtype=float)
    return float(np.sum(w * f) / np.sum(w)) if f.size and np.all(np.isfinite(f)) else -np.inf


def capture_one(load, name: str, split: str, top: int) -> dict:
    """identify's board on one record x split and the validation fits of its candidates."""
    import sysid
    from sysid.identify import core

    rd.SPLIT = split
    (ue, ye), (uv, yv) = load(name)
    cap: dict = {}
    original = core._choose

    def spy(board, ranked, data, stable_only):
        model, row = original(board, ranked, data, stable_only)
        cap["board"], cap["chosen"], cap["data"] = board, row, data
        return model, row

    core._choose = spy
    try:
        t = time.perf_counter()
        res = sysid.identify(sysid.IOData(u=ue, y=ye), progress=False)
        secs = time.perf_counter() - t
    finally:
        core._choose = original
    b = cap["board"]
    # the record object identify re-fits on (a refinement's re-fit takes its block fits as
    # further starts only on that very object, ``board.whole``)
    centred, (_, mu, my) = cap["data"], core._offsets(sysid.IOData(u=ue, y=ye))
    m = res.model.statespace
    fit0, rho0, _ = rd.score((m.A, m.B, m.C, m.D), res.model.remove_offsets((uv, yv)), 1.0)
    full = [r for r in b.rows if np.isfinite(r["held_out_fit"]) and r["stable"]
            and len(r.get("fold_fits") or []) == len(b.folds)]
    pick = {id(r) for r in sorted(full, key=lambda r: -r["held_out_fit"])[:top]}
    for key in (lambda r: r["fold_fits"][-1], lambda r: _recency(r["fold_fits"]),
                lambda r: r["mean_fit"]):
        pick |= {id(r) for r in sorted(full, key=lambda r: -key(r))[:3]}
    pick |= {id(r) for r in b.rows if "bic" in r} | {id(cap["chosen"])}
    rows = []
    for i, r in enumerate(b.rows):
        if id(r) not in pick:
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                mm = r["refit"](centred)
            vf, rho, _ = rd.score((mm.A, mm.B, mm.C, mm.D), (uv - mu, yv - my), 1.0)
            whole_stable, err = bool(mm.is_stable()), ""
        except Exception as e:  # noqa: BLE001 - a failed re-fit is listed, not raised
            vf, rho, whole_stable, err = -np.inf, float("nan"), False, f"{type(e).__name__}"
        rows.append({
            "index": i, "family": r["family"], "order": int(r["order"]),
            "feedthrough": bool(r["feedthrough"]), "focus": r["focus"],
            "criterion": r["criterion"], "note": r["note"][:120],
            "held_out_fit": float(r["held_out_fit"]), "mean_fit": float(r["mean_fit"]),
            "fold_fits": [float(x) if np.isfinite(x) else None for x in r["fold_fits"]],
            "stable": bool(r["stable"]), "max_abs_pole": float(r["max_abs_pole"]),
            "bic": float(r["bic"]) if np.isfinite(r.get("bic", np.nan)) else None,
            "eligible": bool(b.eligible(r, True)),
            "worse_than_start": bool(r.get("worse_than_start")),
            "parameters": int(b.parameters(r)), "chosen": r is cap["chosen"],
            "val_fit": float(vf) if np.isfinite(vf) else None, "val_max_pole": float(rho),
            "whole_stable": whole_stable, "refit_error": err})
    return {"record": name, "split": split, "identify_seconds": secs, "choice": res.choice,
            "identify_val_fit": float(fit0) if np.isfinite(fit0) else None,
            "identify_max_pole": float(rho0), "shares": [float(x) for x in b.shares],
            "n_folds": len(b.folds), "n_rows": len(b.rows), "rows": rows}


# -- compare ----------------------------------------------------------------------------------
def _table(name: str, split: str) -> list[dict]:
    stem = ("realdata" if name in rd.RECORDS else "realdata_more" if name in rd.MORE
            else "realdata_unshipped")
    f = HERE / "results" / f"{stem}{'' if split == 'default' else '_' + split}.json"
    return [r for r in json.loads(f.read_text()) if r["record"] == name] if f.exists() else []


def _ff(r: dict) -> np.ndarray:
    return np.array([-np.inf if x is None else x for x in r["fold_fits"]], float)


def _paired_se(a: dict, b: dict, shares: list[float]) -> float:
    """``Board.paired_se`` on captured rows."""
    x, y, w = _ff(a), _ff(b), np.asarray(shares, float)
    if x.shape != w.shape or y.shape != w.shape or not np.all(np.isfinite(x - y)):
        return 0.0
    w = w / w.sum()
    d = x - y
    keff = 1.0 / np.sum(w ** 2)
    return float(np.sqrt(np.sum(w * (d - np.sum(w * d)) ** 2) / max(keff - 1.0, 1.0)))


RULES = ("R0", "R1", "R1m", "R2", "R3", "R4", "R5", "oracle")


def picks(board: dict) -> dict[str, tuple[float, float]]:
    """(validation fit, largest pole modulus) of each rule's pick on one board."""
    U = [r for r in board["rows"] if r["stable"] and r["whole_stable"]
         and r["val_fit"] is not None and len(r["fold_fits"]) == board["n_folds"]]
    if not U:
        return {}
    r1 = max(U, key=lambda r: r["held_out_fit"])
    within = [r for r in U
              if r["held_out_fit"] >= r1["held_out_fit"] - _paired_se(r, r1, board["shares"])]
    bic = [r for r in U if r["bic"] is not None]
    chosen = {
        "R1": r1,
        "R1m": max(U, key=lambda r: r["mean_fit"]),
        "R2": max(U, key=lambda r: _ff(r)[-1]),
        "R3": max(U, key=lambda r: _recency(_ff(r))),
        "R4": min(within, key=lambda r: (r["order"], -r["held_out_fit"])),
        "R5": min(bic, key=lambda r: r["bic"]) if bic else r1,
        "oracle": max(U, key=lambda r: r["val_fit"]),
    }
    out = {"R0": (board["identify_val_fit"] if board["identify_val_fit"] is not None
                  else -np.inf, board["identify_max_pole"])}
    out.update({k: (r["val_fit"], r["val_max_pole"]) for k, r in chosen.items()})
    return out


def goal(fit: float, pole: float, others: list[dict]) -> str:
    """The bench's goal column (``realdata.write_md``): yes, stable others (s.o.), no."""
    best = max(r["fit"] for r in others)
    stable = [r["fit"] for r in others if r["max_pole"] < 1]
    best_s = max(stable) if stable else -np.inf
    if best <= 0 or (pole < 1 and fit >= best - 0.5):
        return "yes"
    return "s.o." if best_s <= 0 or (pole < 1 and fit >= best_s - 0.5) else "no"


def compare(boards: list[dict]) -> str:
    per: dict[tuple[str, str], list] = {}
    detail = []
    for B in boards:
        others = [r for r in _table(B["record"], B["split"]) if r["tool"] != "identify"]
        p = picks(B)
        if not others or not p:
            continue
        for r in others:
            r["fit"], r["max_pole"] = float(r["fit"]), float(r["max_pole"])
        top = p["oracle"][0]
        cells = []
        for k in RULES:
            f, rho = p[k]
            g = goal(f, rho, others)
            # identify's own pick may lie outside the scored stable candidates (an unstable
            # model the data insist on) and validate above them: no negative regret
            per.setdefault((k, B["split"]), []).append((g, max(top - f, 0.0)))
            cells.append(f"{f:.1f}" + {"yes": "", "s.o.": "°", "no": "*"}[g])
        detail.append(f"| {B['record']} | {B['split']} | "
                      f"{max(r['fit'] for r in others):.1f} | " + " | ".join(cells) + " |")
    lines = ["| rule | split | record-splits | goal met (+ s.o.) | within 0.5 of best on board "
             "| mean regret | median regret | worst regret |", "|---" * 8 + "|"]
    for k in RULES:
        for s in ("default", "reversed", "swap"):
            st = per.get((k, s))
            if not st:
                continue
            reg = np.array([x[1] for x in st])
            reg = np.where(np.isfinite(reg), reg, np.inf)
            yes = sum(x[0] == "yes" for x in st)
            so = sum(x[0] == "s.o." for x in st)
            lines.append(f"| {k} | {s} | {len(st)} | {yes} (+{so}) | {int(np.sum(reg <= 0.5))} "
                         f"| {np.mean(reg):.2f} | {np.median(reg):.2f} | {np.max(reg):.2f} |")
    lines += ["", "Validation fit of each rule's pick (`*`: goal not met, `°`: met only against "
              "the stable others):", "",
              "| record | split | best other | " + " | ".join(RULES) + " |",
              "|---" * (3 + len(RULES)) + "|"] + detail
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("capture")
    c.add_argument("out")
    c.add_argument("--splits", nargs="*", default=["default", "reversed"])
    c.add_argument("--records", nargs="*", default=None)
    c.add_argument("--unshipped", default=None, metavar="DIR")
    c.add_argument("--more-records", default=None, metavar="DIR")
    c.add_argument("--top", type=int, default=15)
    k = sub.add_parser("compare")
    k.add_argument("boards", nargs="+")
    args = ap.parse_args()
    if args.cmd == "compare":
        boards = [b for f in args.boards for b in json.loads(Path(f).read_text())]
        print(compare(boards))
        return
    loaders = {n: (lambda n: rd.RECORDS[n]()) for n in rd.RECORDS}
    if args.unshipped:
        loaders = {n: (lambda n: rd._unshipped(Path(args.unshipped), n)) for n in rd.UNSHIPPED}
    if args.more_records:
        loaders = {n: (lambda n: rd._more(Path(args.more_records), n)) for n in rd.MORE}
    out = []
    for name in args.records or list(loaders):
        for split in args.splits:
            if name in SEPARATE and split != "default":
                continue
            out.append(capture_one(loaders[name], name, split, args.top))
            print(name, split, f"{out[-1]['identify_seconds']:.1f} s", flush=True)
            Path(args.out).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
