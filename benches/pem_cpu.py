"""CPU seconds per ``sysid.pem`` call on the cases of ``benches/pem_speed.py``, without the
SciPy comparison: the bench's call (simulation errors, ``feedthrough=True``, x0 estimated,
``weighting="identity"``, ``max_iter=100``) from its MOESP start, repeated (five times for
the small cases, once for the F-16 and the 2 x 28 record), with iterations, evaluations, the
final cost to the last digit and the floor ratio at the GEMM rate measured in the same run.

    SYSID_SHARED=/path/to/shared .venv/bin/python benches/pem_cpu.py winding cstr
    SYSID_SHARED=/path/to/shared .venv/bin/python benches/pem_cpu.py     # all five cases

Compare two builds by running it with each extension in turn (alternating processes: the
machine's load moves CPU times by 10-20 %).
"""

from __future__ import annotations

import json
import os
import sys
import time
import warnings

sys.path.insert(0, os.path.dirname(__file__))

import pem_speed as ps  # noqa: E402

import sysid  # noqa: E402

ONCE = ("f16", "synthetic 2x28")


def main(which: list[str]) -> None:
    names = which or ["winding", "cstr", "synthetic 6x6", "synthetic 2x28", "f16"]
    rate = ps.gemm_rate()
    print(json.dumps({"gemm_gflops": round(rate / 1e9, 1), "load": os.getloadavg()[0]}),
          flush=True)
    cases = ps.cases()
    for name in names:
        u, y, n = cases[name]
        start = ps.start_model(u, y, n)
        cpus = []
        for _ in range(1 if name in ONCE else 5):
            time.sleep(0.3)  # let idle BLAS threads of the start's fit settle
            c0 = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                m = sysid.pem((u, y), start, focus="simulation", feedthrough=True,
                              weighting="identity", max_iter=100)
            cpus.append(time.process_time() - c0)
        info = m.info["pem"]
        floor = ps.floor_s(u, y, n, info["iterations"], rate)
        print(json.dumps({"case": name, "cpu_s": [round(c, 4) for c in cpus],
                          "iterations": info["iterations"],
                          "evaluations": info["evaluations"], "stop": info["stop"],
                          "final_cost": repr(info["cost"][-1]), "floor_s": round(floor, 5),
                          "cpu_over_floor": round(min(cpus) / floor, 1)}), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
