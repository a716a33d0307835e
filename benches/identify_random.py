"""``sysid.identify`` on random plants with a slow pole, scored against the noise-free
response: a check of identify's choices on systems no choice was made on (records of the
kind where a subspace fit puts the slow pole just outside the unit circle).

Each seed draws a plant (2-6 states, 1-2 inputs and outputs; one real pole 1 - 10^-u with u
uniform in 1.5-3, the others real or complex pairs of modulus 0.5-0.97, in a random state
basis), a low-pass random input of 1500-4000 samples, a coloured output disturbance of 5-30 %
of each output's spread, and a fresh validation input of 2000 samples. Score: the simulation
fit (NRMSE %, :func:`sysid.compare`, initial state fitted) of identify's model on the
validation record's noise-free output. One JSON line per seed on stdout.

    .venv/bin/python benches/identify_random.py 0 40 > new.jsonl

To compare two versions, run the same seeds with the older package first on the path
(``PYTHONPATH=<checkout>/python``, its compiled module copied in) and compare the lines.
"""

from __future__ import annotations

import argparse
import json
import warnings

import numpy as np
from scipy import signal

import sysid


def plant(rng: np.random.Generator) -> sysid.StateSpaceModel:
    """A random stable plant with one slow real pole (see the module docstring)."""
    n, m, l = (int(rng.integers(2, 7)), int(rng.integers(1, 3)), int(rng.integers(1, 3)))
    blocks: list[np.ndarray] = [np.array([[1 - 10 ** rng.uniform(-3, -1.5)]])]
    size = 1
    while size < n:
        if n - size >= 2 and rng.random() < 0.5:
            r, th = rng.uniform(0.5, 0.97), rng.uniform(0.1, 2.5)
            blocks.append(r * np.array([[np.cos(th), np.sin(th)], [-np.sin(th), np.cos(th)]]))
            size += 2
        else:
            blocks.append(np.array([[rng.uniform(-0.5, 0.95)]]))
            size += 1
    A = np.zeros((n, n))
    k = 0
    for b in blocks:
        A[k:k + b.shape[0], k:k + b.shape[0]] = b
        k += b.shape[0]
    T = rng.standard_normal((n, n))
    A = T @ A @ np.linalg.inv(T)
    return sysid.StateSpaceModel(A, rng.standard_normal((n, m)), rng.standard_normal((l, n)),
                                 np.zeros((l, m)), dt=1.0)


def run(seed: int) -> dict[str, object]:
    rng = np.random.default_rng(1000 + seed)
    g = plant(rng)
    m, l = g.ninputs, g.noutputs
    N = int(rng.integers(1500, 4000))

    def low_pass(count: int) -> np.ndarray:
        return signal.lfilter([1], [1, -rng.uniform(0, 0.9)], rng.standard_normal((count, m)),
                              axis=0)
    u = low_pass(N)
    y0 = g.simulate(u)
    e = signal.lfilter([1], [1, -rng.uniform(0, 0.95)], rng.standard_normal((N, l)), axis=0)
    y = y0 + rng.uniform(0.05, 0.3) * np.std(y0, axis=0) * e / np.std(e, axis=0)
    uv = low_pass(2000)
    row: dict[str, object] = {"seed": seed, "n": g.nstates, "m": m, "l": l, "N": N}
    try:
        res = sysid.identify(sysid.IOData(u, y, 1.0), progress=False)
        row["fit"] = float(sysid.compare(res.model, sysid.IOData(uv, g.simulate(uv), 1.0))
                           .mean_fit)
        row["stable"] = bool(res.model.is_stable())
        row["choice"] = res.choice
    except Exception as ex:  # noqa: BLE001 - a failure is a result here
        row.update(fit=float("nan"), stable=None, choice=f"{type(ex).__name__}: {ex}"[:120])
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("first", type=int, nargs="?", default=0)
    ap.add_argument("stop", type=int, nargs="?", default=40)
    a = ap.parse_args()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for seed in range(a.first, a.stop):
            print(json.dumps(run(seed)), flush=True)


if __name__ == "__main__":
    main()
