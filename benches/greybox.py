"""Time of grey-box estimation: the gyroplane lateral/directional structure (4 states, 2
inputs, 4 outputs, 10 free derivatives, 1200 samples, 5 % noise) as a linear grey-box and as a
nonlinear ODE (RK4 vectorised / per column, adaptive vectorised; Jacobian by forward
differences or by the sensitivity equations with the user's derivatives or with central
differences of f).

Run: ``.venv/bin/python benches/greybox.py`` (a few minutes on a loaded machine). Prints a
Markdown table with wall and CPU (process) time.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from test_greybox import KNOWN, TRUE, _sweeps, lateral, lateral_ode, states  # noqa: E402

import sysid  # noqa: E402


def lateral_dfdx(t, x, u, p):
    """df/dx of the lateral ODE (its A matrix)."""
    return [[p.Yv, 0, -p.U0, p.g], [p.Lv, p.Lp, p.Lr, 0], [p.Nv, p.Np, p.Nr, 0], [0, 1, 0, 0]]


def lateral_dfdp(t, x, u, p):
    """df/dp of the lateral ODE, by parameter name (the others are zero)."""
    z = 0.0
    return {"Yv": [x[0], z, z, z], "Yd_ped": [u[1], z, z, z], "U0": [-x[2], z, z, z],
            "g": [x[3], z, z, z], "Lv": [z, x[0], z, z], "Lp": [z, x[1], z, z],
            "Lr": [z, x[2], z, z], "Ld_lat": [z, u[0], z, z], "Ld_ped": [z, u[1], z, z],
            "Nv": [z, z, x[0], z], "Np": [z, z, x[1], z], "Nr": [z, z, x[2], z],
            "Nd_lat": [z, z, u[0], z], "Nd_ped": [z, z, u[1], z]}


def states_dx(t, x, u, p):
    """dh/dx of the output (all four states)."""
    return np.eye(4)


def states_dp(t, x, u, p):
    """dh/dp: the outputs do not depend on the parameters."""
    return {}


def main() -> None:
    dt, n = 0.05, 1200
    u = _sweeps(n, dt)
    y0 = sysid.GreyBox(lateral, {**TRUE, **KNOWN}).model(dt=dt).simulate(u)
    y = y0 + 0.05 * y0.std(axis=0) * np.random.default_rng(0).standard_normal(y0.shape)
    data = sysid.IOData(u=u, y=y, dt=dt)
    start = {**{k: 1.3 * v for k, v in TRUE.items()}, **KNOWN}
    rows = []
    for _ in range(2):  # the first linear run includes imports
        t0, c0 = time.perf_counter(), time.process_time()
        lin = sysid.greyest(data, sysid.GreyBox(lateral, start), x0="zero")
        t_lin, c_lin = time.perf_counter() - t0, time.process_time() - c0
    rows.append(("linear GreyBox (ZOH, Fréchet chain rule)", t_lin, c_lin,
                 lin.info["iterations"], "-"))
    derivs = dict(dfdx=lateral_dfdx, dfdp=lateral_dfdp, dhdx=states_dx, dhdp=states_dp)
    cases = [("NonlinearGreyBox rk4, vectorised", dict(vectorized=True)),
             ("NonlinearGreyBox rk4, per column", dict(vectorized=False)),
             ("NonlinearGreyBox adaptive (DOPRI45), vectorised",
              dict(vectorized=True, integrator="adaptive")),
             ("NonlinearGreyBox rk4, sensitivity equations, user derivatives", derivs),
             ("NonlinearGreyBox rk4, sensitivity equations, central differences of f "
              "(vectorised)", dict(vectorized=True, jacobian="sensitivity"))]
    only = sys.argv[1:]
    for name, kw in cases:
        if only and not any(o in name for o in only):
            continue
        nl = sysid.NonlinearGreyBox(lateral_ode, states, start, nx=4, **kw)
        t0, c0 = time.perf_counter(), time.process_time()
        fit = sysid.greyest(data, nl)
        t, c = time.perf_counter() - t0, time.process_time() - c0
        worst = max(abs(fit.parameters[k]["value"] - lin.parameters[k]["value"])
                    / lin.parameters[k]["std"] for k in TRUE)
        rows.append((f"{name} (max diff/std {worst:.1e})", t, c, fit.info["iterations"],
                     f"{fit.info['rhs_calls']} ({c / fit.info['rhs_calls'] * 1e6:.0f} µs CPU "
                     "each)"))
    print("| case | wall | CPU | iterations | calls of f (or of its derivatives) |")
    print("|---|---|---|---|---|")
    for name, t, c, it, calls in rows:
        print(f"| {name} | {t:.2f} s | {c:.2f} s | {it} | {calls} |")


if __name__ == "__main__":
    main()
