"""``sysid.identify`` on long records: wall and CPU time, and the share spent scoring the
candidates on their held-out blocks (simulation with the initial state and offsets fitted,
:func:`sysid.validation.crossval.simulation_errors`).

Each case draws a random stable plant (``n`` states, poles of modulus at most 0.95, a random
state basis), a white input of ``N`` samples and 10 % white output noise, and runs
``sysid.identify(data)`` once. One JSON line per case on stdout.

    .venv/bin/python benches/identify_long.py                 # 100 000 (3 x 3) and 300 000 (2 x 4)
    .venv/bin/python benches/identify_long.py 30000:1:1:4     # N:inputs:outputs:states

To compare two versions, run it with the older package first on the path
(``PYTHONPATH=<checkout>/python``, a compiled module that has what it calls copied in).
"""

from __future__ import annotations

import importlib
import json
import sys
import time
import warnings

import numpy as np

import sysid
import sysid.validation.crossval as crossval

CASES = ["100000:3:3:6", "300000:2:4:8"]


def record(N: int, m: int, l: int, n: int) -> sysid.IOData:
    rng = np.random.default_rng(0)
    A = rng.standard_normal((n, n))
    A *= 0.95 / np.max(np.abs(np.linalg.eigvals(A)))
    true = sysid.StateSpaceModel(A, rng.standard_normal((n, m)), rng.standard_normal((l, n)),
                                 dt=1.0)
    u = rng.standard_normal((N, m))
    y = true.simulate(u)
    return sysid.IOData(u=u, y=y + 0.1 * y.std(0) * rng.standard_normal((N, l)))


def main(cases: list[str]) -> None:
    spent = [0.0, 0]
    real = crossval.simulation_errors

    def timed(*a, **kw):  # the held-out scoring's own time
        t = time.perf_counter()
        try:
            return real(*a, **kw)
        finally:
            spent[0] += time.perf_counter() - t
            spent[1] += 1
    crossval.simulation_errors = timed
    # the board imported the name: patch it there too (sysid.identify is the function)
    importlib.import_module("sysid.identify.board").simulation_errors = timed
    for case in cases:
        N, m, l, n = (int(v) for v in case.split(":"))
        data = record(N, m, l, n)
        spent[:] = [0.0, 0]
        t, c = time.perf_counter(), time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = sysid.identify(data, progress=False)
        print(json.dumps({
            "case": case, "wall_s": round(time.perf_counter() - t, 1),
            "cpu_s": round(time.process_time() - c, 1),
            "scoring_s": round(spent[0], 1), "scorings": spent[1],
            "choice": repr(res).split("(", 1)[1].split(";")[0]}), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:] or CASES)
