"""Geodesic acceleration (Transtrum & Sethna 2012) against plain Levenberg-Marquardt on the
cases of ``pem_speed.py`` (issue 28): the same start and call, ``geodesic`` off and on.

    SYSID_SHARED=/work/shared nice -n 10 .venv/bin/python benches/pem_geodesic.py [cases] \
        [--max-iter N]

Per case and setting: final cost, iterations, evaluations, stop reason, process CPU seconds
of the ``sysid.pem`` call, what the acceleration did (``info["pem"]["geodesic"]``) and, for
the F-16, the validation fit on the shipped level-2 record.
"""

from __future__ import annotations

import json
import os
import sys
import time
import warnings

sys.path.insert(0, os.path.dirname(__file__))

from pem_speed import cases, start_model, validation_fit  # noqa: E402

import sysid  # noqa: E402


def refine(u, y, start, geodesic: bool, max_iter: int) -> tuple[dict, object]:
    time.sleep(0.3)
    trace: list[tuple[float, float]] = []
    c0 = time.process_time()

    def seen(it, cost, *rest):
        trace.append((round(time.process_time() - c0, 3), cost))

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = sysid.pem((u, y), start, focus="simulation", feedthrough=True,
                      weighting="identity", max_iter=max_iter, geodesic=geodesic,
                      progress=seen)
    cpu = time.process_time() - c0
    info = m.info["pem"]
    return {"geodesic": geodesic, "cpu_s": round(cpu, 2), "iterations": info["iterations"],
            "evaluations": info["evaluations"], "stop": info["stop"],
            "final_cost": info["cost"][-1], "start_cost": info["cost"][0],
            "accel": info["geodesic"], "trace": trace}, m


def main(argv: list[str]) -> None:
    max_iter = 100
    if "--max-iter" in argv:
        i = argv.index("--max-iter")
        max_iter = int(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    which = argv
    for name, (u, y, n) in cases().items():
        if which and name.split()[0] not in which and name not in which:
            continue
        start = start_model(u, y, n)
        rows = []
        for geo in (False, True):
            row, m = refine(u, y, start, geo, max_iter)
            row["case"] = name
            row["max_iter"] = max_iter
            row["validation_fit"] = validation_fit(name, m)
            rows.append(row)
        # the cost each reached within the other's CPU time (the iteration callback's clock)
        for a, b in (rows, rows[::-1]):
            within = [c for t, c in a["trace"] if t <= b["cpu_s"]]
            a["cost_within_other_cpu"] = min(within) if within else a["start_cost"]
        for row in rows:
            trace = row.pop("trace")
            row["cost_every_10"] = [round(c, 3) for _, c in trace[9::10]]
            row["cpu_every_10"] = [t for t, _ in trace[9::10]]
            print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
