"""numpy's and SciPy's BLAS threads while sysid works: one (the default) against the pools
left as the caller has them (``SYSID_BLAS_THREADS=keep``), on an idle machine and with
``--load`` other processes keeping cores busy.

Each setting runs in a fresh process (``sysid.identify`` or ``ssest(data, "auto")`` on every
shipped real record of ``benches/realdata.py``, its estimation part); the table gives the
wall and CPU seconds summed over the records and whether every chosen model is the same.

    SYSID_SHARED=../shared python benches/blas_threads.py --tool identify --load 2 \
        --out benches/results/blas_threads.md
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent

WORKER = r"""
import json, sys, time, warnings
warnings.simplefilter("ignore")
sys.path.insert(0, sys.argv[1])
import numpy as np
import realdata as rd
import sysid
tool = sys.argv[2]
out = {}
for name, load in rd.RECORDS.items():
    (ue, ye), _ = load()
    d = sysid.IOData(u=ue, y=ye)
    t, c = time.perf_counter(), time.process_time()
    if tool == "identify":
        m = sysid.identify(d).model
    else:
        m = sysid.ssest(sysid.detrend(d), "auto")
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    ss = m.to_statespace() if hasattr(m, "to_statespace") else m
    key = float(np.sum(np.abs(ss.markov(20)))) if hasattr(ss, "markov") else None
    out[name] = {"wall": wall, "cpu": cpu, "key": key}
print(json.dumps(out))
"""


def run(tool: str, setting: str) -> dict:
    env = dict(os.environ)
    env["SYSID_BLAS_THREADS"] = setting
    p = subprocess.run([sys.executable, "-c", WORKER, str(HERE), tool], env=env,
                       capture_output=True, text=True, check=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def busy(n: int) -> list[subprocess.Popen]:
    loop = "while True: pass"
    return [subprocess.Popen([sys.executable, "-c", loop]) for _ in range(n)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tool", choices=["identify", "ssest"], default="identify")
    ap.add_argument("--load", type=int, default=2, help="busy processes for the loaded rows")
    ap.add_argument("--out", type=Path, default=None)
    a = ap.parse_args()
    rows = []
    for load in (0, a.load) if a.load else (0,):
        hogs = busy(load)
        try:
            time.sleep(0.5 if load else 0)
            res = {s: run(a.tool, s) for s in ("keep", "1")}
        finally:
            for h in hogs:
                h.kill()
        same = all(res["keep"][k]["key"] == res["1"][k]["key"] for k in res["1"])
        for s, label in (("keep", "as the caller has them"), ("1", "one (default)")):
            r = res[s]
            rows.append(f"| {load} | {label} | {sum(v['wall'] for v in r.values()):.1f} | "
                        f"{sum(v['cpu'] for v in r.values()):.1f} | {'yes' if same else 'NO'} |")
    text = "\n".join([
        f"# BLAS threads while sysid works (`{a.tool}`, every shipped record)", "",
        "Command: `SYSID_SHARED=../shared python benches/blas_threads.py "
        f"--tool {a.tool} --load {a.load}` "
        f"({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {os.cpu_count()} cores)", "",
        "| busy processes | BLAS threads | wall s | CPU s | same models |",
        "|---|---|---|---|---|", *rows, ""])
    print(text)
    if a.out:
        a.out.write_text(text if not a.out.exists() else a.out.read_text() + "\n" + text)


if __name__ == "__main__":
    main()
