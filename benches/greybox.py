"""Time of grey-box estimation: the gyroplane lateral/directional structure (4 states, 2
inputs, 4 outputs, 10 free derivatives, 1200 samples, 5 % noise) as a linear grey-box and as a
nonlinear ODE (RK4 vectorised / per column, adaptive vectorised).

Run: ``.venv/bin/python benches/greybox.py`` (about a minute). Prints a Markdown table.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from test_greybox import KNOWN, TRUE, _sweeps, lateral, lateral_ode, states  # noqa: E402

import sysid  # noqa: E402


def main() -> None:
    dt, n = 0.05, 1200
    u = _sweeps(n, dt)
    y0 = sysid.GreyBox(lateral, {**TRUE, **KNOWN}).model(dt=dt).simulate(u)
    y = y0 + 0.05 * y0.std(axis=0) * np.random.default_rng(0).standard_normal(y0.shape)
    data = sysid.IOData(u=u, y=y, dt=dt)
    start = {**{k: 1.3 * v for k, v in TRUE.items()}, **KNOWN}
    rows = []
    for _ in range(2):  # the first linear run includes imports
        t0 = time.perf_counter()
        lin = sysid.greyest(data, sysid.GreyBox(lateral, start), x0="zero")
        t_lin = time.perf_counter() - t0
    rows.append(("linear GreyBox (ZOH, Fréchet chain rule)", t_lin, lin.info["iterations"], "-"))
    cases = [("NonlinearGreyBox rk4, vectorised", dict(vectorized=True)),
             ("NonlinearGreyBox rk4, per column", dict(vectorized=False)),
             ("NonlinearGreyBox adaptive (DOPRI45), vectorised",
              dict(vectorized=True, integrator="adaptive"))]
    for name, kw in cases:
        nl = sysid.NonlinearGreyBox(lateral_ode, states, start, nx=4, **kw)
        t0 = time.perf_counter()
        fit = sysid.greyest(data, nl)
        t = time.perf_counter() - t0
        worst = max(abs(fit.parameters[k]["value"] - lin.parameters[k]["value"])
                    / lin.parameters[k]["std"] for k in TRUE)
        rows.append((f"{name} (max diff/std {worst:.1e})", t, fit.info["iterations"],
                     f"{fit.info['rhs_calls']} ({t / fit.info['rhs_calls'] * 1e6:.0f} µs each)"))
    print("| case | time | iterations | calls of f |")
    print("|---|---|---|---|")
    for name, t, it, calls in rows:
        print(f"| {name} | {t:.2f} s | {it} | {calls} |")


if __name__ == "__main__":
    main()
