"""Time of the order-20, 2-input, 28-output, N = 6000 refinement (issue 11), to convergence.

    .venv/bin/python benches/pem_speed.py            # both weightings, about 1-3 minutes
    SYSID_PROFILE=1 .venv/bin/python benches/pem_speed.py identity 2> prof.txt

Measured from the subspace start (as ``sysid.ssest`` does), default options; wall time and the
process CPU time (user + system: on a shared machine the wall time depends on the load, the CPU
time much less). With ``SYSID_PROFILE=1`` the Rust core prints one ``PROF <what> <seconds>``
line per evaluation (``full``, ``gradient``, ``cost``), search step and final covariance.
"""

from __future__ import annotations

import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(__file__))

from pem import record, subspace_start, system  # noqa: E402

import sysid  # noqa: E402


def run(weighting: str | None) -> dict:
    true = system(20, 2, 28, 1)
    u, y = record(true, 6000, 2)
    c0, t0 = time.process_time(), time.perf_counter()
    start = subspace_start(u, y, 20)
    kw = {} if weighting is None else {"weighting": weighting}
    marks: list = []
    m = sysid.pem((u, y), start, progress=lambda it, cost, *a: marks.append(
        (it, round(time.perf_counter() - t0, 2), round(cost, 4))), **kw)
    info = m.info["pem"]
    return {"weighting": info["weighting"], "wall_s": round(time.perf_counter() - t0, 2),
            "cpu_s": round(time.process_time() - c0, 2), "iterations": info["iterations"],
            "evaluations": info["evaluations"], "stop": info["stop"],
            "cost": [round(info["weighted_cost"][0], 4), round(info["weighted_cost"][-1], 4)],
            "marks (iteration, s, cost)": marks, "load": os.getloadavg()[0]}


if __name__ == "__main__":
    which = sys.argv[1:] or ["identity", "default"]
    for w in which:
        print(json.dumps(run(None if w == "default" else w)), flush=True)
