"""Nonlinear models on DaISy records the project does not ship, at generic settings, scored
by ``sysid.compare`` on the last third (its default initial state and from rest).

    .venv/bin/python benches/nonlinear_daisy.py DIR

``DIR`` holds the DaISy ``.dat`` files (exchanger, heating_system, CD_player_arm, evaporator,
glassfurnace; columns as in ``UNSHIPPED`` of benches/realdata.py). First 2/3 estimate, last
1/3 validate; ``nlarx(d, 2, 2, 1, basis=PolynomialBasis(2))`` and ``pnlss(d, 3, degree=2,
max_iter=50)``, nothing tuned on these records.
"""

from __future__ import annotations

import os
import sys
import time
import warnings

import numpy as np

import sysid

RECORDS = {"exchanger": ("exchanger.dat", [1], [2]),
           "heating_system": ("heating_system.dat", [1], [2]),
           "cd_player": ("CD_player_arm.dat", [0, 1], [2, 3]),
           "evaporator": ("evaporator.dat", [0, 1, 2], [3, 4, 5]),
           "glassfurnace": ("glassfurnace.dat", [1, 2, 3], [4, 5, 6, 7, 8, 9])}
MODELS = {"nlarx": lambda e: sysid.nlarx(e, 2, 2, 1, basis=sysid.PolynomialBasis(2)),
          "pnlss": lambda e: sysid.pnlss(e, 3, degree=2, max_iter=50, progress=False)}


def main() -> None:
    warnings.simplefilter("ignore")
    print("| record | " + " | ".join(f"{m} (from rest) | {m} s" for m in MODELS) + " |")
    print("|---|" + "---|---|" * len(MODELS))
    for name, (f, ui, yi) in RECORDS.items():
        a = np.loadtxt(os.path.join(sys.argv[1], f))
        k = 2 * len(a) // 3
        est = sysid.IOData(a[:k, ui], a[:k, yi], 1.0)
        val = sysid.IOData(a[k:, ui], a[k:, yi], 1.0)
        cells = []
        for fit in MODELS.values():
            t = time.perf_counter()
            m = fit(est)
            s = time.perf_counter() - t
            fe, fz = (sysid.compare(m, val, x0=x).fit.mean() for x in ("estimate", "zero"))
            cells.append(f"{fe:.1f} ({fz:.1f}) | {s:.1f}")
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
