"""Every real record of the sweeps in one run: ``sysid.identify`` re-run on all of them with the
code as it stands, against the other tools' rows of the committed tables, and the goal's tally
(issue 26: stable, and within 0.5 fit points of the best other wherever one is positive).

    SYSID_SHARED=/work/shared .venv/bin/python benches/realdata_tally.py ROOT RUNS
    .venv/bin/python benches/realdata_tally.py ROOT RUNS --no-run        # tally RUNS only
    .venv/bin/python benches/realdata_tally.py ROOT RUNS --against BASE  # what moved
    .venv/bin/python benches/realdata_tally.py ROOT RUNS_R --split reversed  # (docstring)

ROOT holds one folder per sweep, named as the sweep's option of ``benches/realdata.py``
(``more``, ``fresh``, ``fresh2``, ..., the files ``--<sweep>-records`` reads; how each is made:
the sweep's account in ``results/``) and ``daisy`` (the DaISy files ``--unshipped`` reads); a
folder that is missing is left out and named. The shipped records are read as
``benches/realdata.py`` reads them (``SYSID_SHARED``). For each group the bench runs
``realdata.py --no-peers --tools identify`` into ``RUNS/<group>.json`` (kept when it holds
every record already, so an interrupted run resumes). The other tools' rows are those of the
committed table of each group (their default split), as last run; only identify is re-run.
``--split reversed`` estimates on the last part and validates on the first (``realdata.py``'s
``--split``), on the records of the groups whose committed table has a reversed split
(``<table>_reversed.json``: the records of one run; a record with a validation run of its
own keeps it under every split and is not repeated).

The tally prints the goal per group, every miss with its gap, the goal against the effective
number of held-out blocks identify scores on (``checks["held_out_evidence"]`` is "thin" below
2), and the records whose identify fit moved by more than 0.5 points from the committed
table's (or, with ``--against BASE``, from another run: a change weighed on every record).
Run from the repository's root; ``--out FILE`` also writes the tally as markdown.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import realdata as R  # noqa: E402
import realdata_records as RR  # noqa: E402


def groups(root: Path) -> tuple[dict[str, tuple[list[str], str, dict]], list[str]]:
    """``{group: (realdata.py options, committed table stem, record names)}`` of the groups
    found under ``root`` (the shipped records always), and the sweeps whose folder is
    missing."""
    out = {"shipped": ([], "realdata", {n: None for n in R.RECORDS})}
    if (root / "daisy").is_dir():
        out["daisy"] = (["--unshipped", str(root / "daisy")], "realdata_unshipped",
                        R.UNSHIPPED)
    missing = []
    for sweep, (table, stem) in RR.SWEEPS.items():
        if (root / sweep).is_dir():
            out[sweep] = ([f"--{sweep}-records", str(root / sweep)], stem, getattr(RR, table))
        else:
            missing.append(sweep)
    return out, missing


def identify_rows(path: Path) -> dict[str, dict]:
    """identify's rows of a results file, by record."""
    if not path.exists():
        return {}
    return {r["record"]: r for r in json.loads(path.read_text()) if r["tool"] == "identify"}


def table_rows(stem: str, split: str) -> list[dict] | None:
    """The committed table's rows of ``split`` (``None`` when it has no such table)."""
    path = HERE / "results" / (f"{stem}.json" if split == "default" else f"{stem}_{split}.json")
    if not path.exists():
        return None
    return [r for r in json.loads(path.read_text()) if r.get("split", "default") == split]


def own_validation(group: str, name: str, names: dict) -> bool:
    """Whether the record has a validation run of its own (kept under every split): a sweep's
    second file, or the F-16 levels' validation file."""
    entry = names[name]
    return name.startswith("f16_") if group == "shipped" else (
        isinstance(entry, tuple) and len(entry) == 2 and entry[1] is not None)


def scored(group: str, names: dict, rows: list[dict], split: str) -> list[str]:
    """The group's records the tally runs and scores: those of its committed table, without
    (on another split) the ones that keep their validation run."""
    return [n for n in names if any(r["record"] == n for r in rows)
            and not (split != "default" and own_validation(group, n, names))]


def run(group: str, options: list[str], names, runs: Path, split: str) -> None:
    """identify on the records ``names`` into ``runs/<group>.json`` unless already there."""
    if set(names) <= set(identify_rows(runs / f"{group}.json")):
        return
    cmd = [sys.executable, str(HERE / "realdata.py"), *options, "--records", *names,
           "--split", split, "--no-peers", "--tools", "identify",
           "--out", str(runs / f"{group}.md")]
    print("running", " ".join(cmd[1:]), flush=True)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)


def effective_blocks(load) -> float:
    """The effective number of identify's held-out blocks on the record's estimation part (by
    each block's share of the output variation: :meth:`sysid.identify.board.Board.
    effective_blocks` on the blocks identify holds out)."""
    import sysid
    from sysid._progress import Bar
    from sysid.data.offsets import remove_means
    from sysid.identify.board import Board, informative
    from sysid.validation.crossval import record_folds

    (ue, ye), _ = load()
    centred = remove_means(sysid.IOData(u=ue, y=ye))[0]
    parts, _ = informative(record_folds(centred), centred)
    return Board(parts, Bar(None, "tally", enabled=False)).effective_blocks()


def tally(root: Path, runs: Path, against: Path | None, split: str = "default") -> list[str]:
    R.SPLIT = split
    found, missing = groups(root)
    tables = {g: table_rows(stem, split) for g, (_, stem, _) in found.items()}
    missing += [f"{g} (no {split} table)" for g, t in tables.items() if t is None]
    found = {g: v for g, v in found.items() if tables[g] is not None}
    loads = R.record_loaders(argparse.Namespace(
        unshipped=str(root / "daisy") if "daisy" in found else None,
        **{f"{s}_records": (str(root / s) if s in found else None) for s in RR.SWEEPS}))
    lines = [f"Split: {split}. Groups: {', '.join(found)}"
             + (f"; left out: {', '.join(missing)}" if missing else ""), ""]
    per, misses, moved, evidence = [], [], [], []
    met_all = n_all = 0
    for group, (_, _, names) in found.items():
        table = tables[group]
        mine = identify_rows(runs / f"{group}.json")
        base = identify_rows(against / f"{group}.json") if against else {
            r["record"]: r for r in table if r["tool"] == "identify"}
        met = n = 0
        for rec in scored(group, names, table, split):
            others = [r for r in table if r["record"] == rec and r["tool"] != "identify"]
            if rec not in mine or not others:
                continue
            me, n = mine[rec], n + 1
            ok = R.goal_met(me, others) != "no" and not me.get("error")
            met += ok
            stable = [r for r in others if r["max_pole"] < 1 and r["fit"] > 0]
            # the nearer reference of the two the goal is judged against
            best = max(stable or others, key=lambda r: r["fit"])
            if not ok:
                misses.append((me["fit"] - best["fit"], group, rec, me, best))
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    evidence.append((effective_blocks(loads[rec]), ok))
                except Exception:  # noqa: BLE001 - a record identify refuses has no blocks
                    pass
            old = base.get(rec)
            if old is not None and abs(float(old["fit"]) - me["fit"]) > 0.5:
                moved.append((group, rec, float(old["fit"]), me, old))
        per.append(f"{group} {met}/{n}")
        met_all, n_all = met_all + met, n_all + n
    lines += [f"Goal met on {met_all} of {n_all} records: " + ", ".join(per) + ".", "",
              "| record | identify | best (stable) other | gap | identify's choice |",
              "|---|---|---|---|---|"]
    for gap, group, rec, me, best in sorted(misses, key=lambda m: m[0]):
        flag = " (refused)" if me.get("error") else "" if me["max_pole"] < 1 else " (unstable)"
        lines.append(f"| {group}/{rec} | {me['fit']:.1f}{flag} | {best['fit']:.1f} "
                     f"({best['tool']}, n={best['order']}) | {gap:+.1f} | "
                     f"{(me.get('choice') or me.get('error', ''))[:60]} |")
    lines += ["", "| effective held-out blocks | records | goal met |", "|---|---|---|"]
    # (records whose blocks cannot be cut, as identify refuses them, are not in this table)
    for lo, hi in ((0.0, 2.0), (2.0, 3.0), (3.0, 4.0), (4.0, np.inf)):
        s = [ok for e, ok in evidence if lo <= e < hi]
        lines.append(f"| {lo:g} to {hi:g} | {len(s)} | {sum(s)} |")
    what = f"the run in {against}" if against else "the committed tables"
    lines += ["", f"identify moved by more than 0.5 points from {what}: {len(moved)}", "",
              "| record | before | now | choice before -> now |", "|---|---|---|---|"]
    for group, rec, old, me, o in moved:
        lines.append(f"| {group}/{rec} | {old:.1f} | {me['fit']:.1f} | "
                     f"{o.get('choice', '')[:40]} -> {me.get('choice', '')[:40]} |")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("root", type=Path, help="one folder per sweep (and daisy)")
    ap.add_argument("runs", type=Path, help="where identify's results go, one file per group")
    ap.add_argument("--no-run", action="store_true", help="tally the runs already in RUNS")
    ap.add_argument("--against", type=Path, default=None,
                    help="another RUNS folder: list what moved from it (a change weighed)")
    ap.add_argument("--out", type=Path, default=None, help="also write the tally here (.md)")
    ap.add_argument("--split", choices=("default", "reversed"), default="default",
                    help="realdata.py's split (reversed: the groups with a reversed table)")
    args = ap.parse_args()
    if not args.root.is_dir():
        sys.exit(f"ROOT {args.root} is not a folder (one folder per sweep: see the docstring)")
    args.runs.mkdir(parents=True, exist_ok=True)
    if not args.no_run:
        for group, (options, stem, names) in groups(args.root)[0].items():
            rows = table_rows(stem, args.split)
            if rows is not None:
                run(group, options, scored(group, names, rows, args.split), args.runs,
                    args.split)
    lines = tally(args.root, args.runs, args.against, args.split)
    print("\n".join(lines))
    if args.out:
        args.out.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
