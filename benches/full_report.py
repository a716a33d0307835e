"""The Markdown report of benches/full.py, written from its JSON (all parts run so far)."""

from __future__ import annotations


def _f(x: float | None, spec: str = ".3g") -> str:
    return "-" if x is None else format(x, spec)


def _head(p: dict) -> list[str]:
    g = p["gemm_gflops"]
    return [
        f"Command: `{p['command']}`; started {p['started']}; {p['cpus']} cores "
        f"({p['machine']}); GEMM rate measured in this run {g['all']:.1f} GFLOP/s "
        f"(one core {g['one']:.1f}); load average {p['load'][0]} at the start, "
        f"{p['load'][1]} at the end; {p['wall_seconds']:.0f} s.",
        "",
    ]


def _cold(r: dict) -> str:
    """The cold time, with the range over fresh processes when there were several."""
    runs = r.get("cold_runs")
    if not runs or len(runs) < 2:
        return _f(r.get("seconds"))
    return f"{_f(r.get('seconds'))} ({_f(min(runs))}-{_f(max(runs))})"


def _sippy(p: dict) -> list[str]:
    out = ["## The default against SIPPY (3 in, 3 out, horizon 20, order 8)", ""] + _head(p)
    out += [
        "Cold: the first identification in a fresh process (`SubspaceEstimator(IOData(u, y), "
        "horizon=20).fit(order=8)`, data in memory, `import sysid` done), the median of three "
        "fresh processes (their range in brackets); warm: the best of the next four in any of "
        "them; ratios use the median. SIPPY: `system_identification(y.T, u.T, "
        "\"N4SID\", SS_fixed_order=8, SS_f=20, SS_p=20)`, once. Pole error: largest distance "
        "of an identified pole from its matched true one; fit: simulation fit on a fresh "
        "record.",
        "",
        "| N | default cold (s) | default warm (s) | `qr` (s) | SIPPY (s) | SIPPY / cold | "
        "SIPPY / warm | pole error default / SIPPY | fit % default / SIPPY | default took |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    rows = p["rows"]
    for n in sorted({r["n"] for r in rows}):
        by = {r["tool"]: r for r in rows if r["n"] == n}
        d, q, s = by.get("sysid-auto", {}), by.get("sysid-qr", {}), by.get("sippy", {})
        cold, warm, ss = d.get("seconds"), d.get("warm_seconds"), s.get("seconds")
        out.append(
            f"| {n:.0e} | {_cold(d)} | {_f(warm)} | {_f(q.get('seconds'))} | "
            f"{_f(ss) if s.get('ok') else 'failed: ' + s.get('error', '?')[:60]} | "
            f"{_f(ss / cold if ss and cold else None, '.0f')}x | "
            f"{_f(ss / warm if ss and warm else None, '.0f')}x | "
            f"{_f(d.get('pole_error'), '.1e')} / {_f(s.get('pole_error'), '.1e')} | "
            f"{_f(d.get('fit'), '.2f')} / {_f(s.get('fit'), '.2f')} | {d.get('source', '-')} |"
        )
    return out + [""]


def _floor(p: dict) -> list[str]:
    out = ["## The default against the compute floor (8 in, 8 out, horizon 20)", ""] + _head(p)
    out += [
        "Floor: `4 i (m + l)^2 N` flops (the lagged sums) at the GEMM rate above. Whole: the "
        "identification (cold: the first in a fresh process, median of three processes with "
        "their range; warm: the best of two more in the same processes); compression: the "
        "`SubspaceEstimator(...)` call of the median cold run.",
        "",
        "| N | floor (s) | whole cold (s) | whole warm (s) | compression, cold (s) | "
        "cold / floor | warm / floor | compression / floor | pole error |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in p["rows"]:
        fl = r["floor_seconds"]
        cold, warm = r.get("seconds"), r.get("warm_seconds")
        out.append(
            f"| {r['n']:.0e} | {fl:.3f} | {_cold(r)} | {_f(warm)} | "
            f"{_f(r.get('compress_seconds'))} | {_f(cold / fl if cold else None, '.2f')}x | "
            f"{_f(warm / fl if warm else None, '.2f')}x | "
            f"{_f(r['compress_seconds'] / fl if r.get('compress_seconds') else None, '.2f')}x | "
            f"{_f(r.get('pole_error'), '.1e')} |"
        )
    return out + [""]


def _threads(p: dict) -> list[str]:
    out = ["## 1 vs 2 threads", ""] + _head(p)
    out += [
        "Compression alone (`_sysid.compress`), `RAYON_NUM_THREADS` = 1 or 2, each pair in a "
        "fresh process, 3 repetitions (min and median). `factor`: first 16 hex digits of the "
        "SHA-256 of L (the same for both thread counts: bit-identical results).",
        "",
        "| N | m x l | i | compressor | 1 thread min (s) | 2 threads min (s) | speed-up | "
        "factor identical | load |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    rows = p["rows"]
    seen = set()
    for r in rows:
        key = (r["n"], r["m"], r["l"], r["i"], r["compressor"])
        if key in seen:
            continue
        seen.add(key)
        pair = {x["threads"]: x for x in rows
                if (x["n"], x["m"], x["l"], x["i"], x["compressor"]) == key}
        one, two = pair.get(1), pair.get(2)
        if not (one and two):
            continue
        out.append(
            f"| {r['n']:.0e} | {r['m']} x {r['l']} | {r['i']} | {r['compressor']} "
            f"({one['source']}) | {one['min']:.3f} | {two['min']:.3f} | "
            f"{one['min'] / two['min']:.2f}x | {'yes' if one['sha'] == two['sha'] else 'NO'} | "
            f"{one['load'][0]}-{two['load'][1]} |"
        )
    return out + [""]


def _grid(p: dict) -> list[str]:
    out = ["## The default over the grid", ""] + _head(p)
    out += [
        "Whole identification with the default compressor, cold (first in a fresh process) "
        "and warm (second); x floor: warm time over `4 i (m + l)^2 N` flops at the GEMM rate.",
        "",
        "| N | m | l | i | order | cold (s) | warm (s) | x floor (warm) | pole error | source |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in p["rows"]:
        w = r.get("warm_seconds")
        out.append(
            f"| {r['n']:.0e} | {r['m']} | {r['l']} | {r['i']} | {r['order']} | "
            f"{_f(r.get('seconds'))} | {_f(w)} | "
            f"{_f(w / r['floor_seconds'] if w else None, '.1f')} | "
            f"{_f(r.get('pole_error'), '.1e')} | "
            f"{r.get('source', 'failed: ' + str(r.get('error', ''))[:60])} |"
        )
    return out + [""]


def _memmap(p: dict) -> list[str]:
    out = [f"## {p['n']:.0e} samples from a memmap (2 in, 2 out, horizon 20, order 4)", ""]
    out += _head(p)
    out += [
        "Each step in a fresh process: one plain sequential read of the .npy (the I/O "
        "floor), then `compress_stream((z[:, :2], z[:, 2:]), 20, compressor=...)` and "
        "`SubspaceEstimator.from_factor(f).fit(order=4)`. Peak: the whole process's VmHWM "
        f"(interpreter included). Compute floor of the lagged sums: "
        f"{p['floor_seconds']:.2f} s.",
        "",
        "| step | time (s) | compression (s) | peak memory (MB) | pole error | source | load |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in p["rows"]:
        if "error" in r:
            out.append(f"| {r['mode']} | failed: {r['error'][:80]} | | | | | |")
            continue
        out.append(
            f"| {r['mode']} | {r['seconds']:.2f} | {_f(r.get('compress_seconds'), '.2f')} | "
            f"{r['peak_mb']:.0f} | {_f(r.get('pole_error'), '.1e')} | {r.get('source', '-')} | "
            f"{r['load'][0]}-{r['load'][1]} |"
        )
    return out + [""]


def _dask(p: dict) -> list[str]:
    out = [f"## Dask: {p['n']:.0e} samples from partitioned Parquet, 1 vs 2 workers", ""]
    out += _head(p)
    out += [
        "50 Parquet files (columns u0, u1, y0, y1; one Dask task per file reads it with "
        "pyarrow); `sysid.compress_dask(z[:, :2], z[:, 2:], past=20)` on a "
        "`LocalCluster(n_workers=w, threads_per_worker=1, processes=True)` (cluster start "
        "not timed; one thread per worker process).",
        "",
        "| workers | worker processes | time (s) | speed-up | pole error | source | load |",
        "|---|---|---|---|---|---|---|",
    ]
    one = next((r for r in p["rows"] if r.get("workers") == 1 and "seconds" in r), None)
    for r in p["rows"]:
        if "error" in r:
            out.append(f"| {r['workers']} | failed: {r['error'][:80]} | | | | | |")
            continue
        sp = one["seconds"] / r["seconds"] if one else None
        out.append(
            f"| {r['workers']} | {r['processes']} | {r['seconds']:.2f} | {_f(sp, '.2f')}x | "
            f"{_f(r.get('pole_error'), '.1e')} | {r['source']} | "
            f"{r['load'][0]}-{r['load'][1]} |"
        )
    return out + [""]


SECTIONS = {"sippy": _sippy, "floor": _floor, "threads": _threads, "memmap": _memmap,
            "dask": _dask, "grid": _grid}


def report(results: dict) -> str:
    lines = [
        "# sysid benchmark: every figure of issue 16",
        "",
        "Produced by `python benches/full.py` (`make bench-full`); each section says the "
        "command that re-runs it alone (`--parts NAME`), when, the load average and the GEMM "
        "rate measured in that run. Wall times: on a shared or loaded machine they are upper "
        "bounds.",
        "",
    ]
    for name, fn in SECTIONS.items():
        if name in results["parts"]:
            lines += fn(results["parts"][name])
    return "\n".join(lines) + "\n"
