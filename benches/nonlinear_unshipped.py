"""The nonlinear benchmark's models (benches/nonlinear.py) on public nonlinear benchmark
records the project does not ship: Silverbox, the Wiener-Hammerstein benchmark (2009),
the cascaded tanks and EMPS. A check that nothing was tuned to the shipped records.

    .venv/bin/python benches/nonlinear_unshipped.py DIR [--only silverbox,wh2009,tanks,emps]
        [--models PREFIXES] [--max-train 40000] [--out FILE]

``DIR`` holds the records as their authors distribute them (copies are kept in several public
repositories, for example forgi86/pytorch-ident and forgi86/sysid-neural-unc):
``silverbox/SNLS80mV.csv`` (columns V1 input, V2 output; fs = 1e7 / 2**14 Hz),
``wh2009/WienerHammerBenchmark.csv`` (uBenchMark, yBenchMark, fs), ``cascaded_tanks/
dataBenchmark.csv`` (uEst, uVal, yEst, yVal, Ts) and ``emps/DATA_EMPS.mat``,
``emps/DATA_EMPS_PULSES.mat`` (vir, qm, t). Splits: Silverbox as the nonlinearbenchmark.org
loader (the multisine part [40650, 127400), its first 75 % to train; tests: the arrow
[100, 40575), the arrow without extrapolation [100, 32100), the multisine's last 25 %); WH
the original one (samples 1-100 000 estimate, the rest test); tanks and EMPS their
estimation and test files. Training is cut to ``--max-train`` samples (Silverbox: the first
ones; WH: the last ones of the estimation part, which starts quiet). Orders from the physics,
not from test results: Silverbox 2, WH 6, tanks 2, EMPS 2; the other settings are
nonlinear.py's generic ones. Every model is simulated from rest over the whole test record.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import nonlinear as nl  # noqa: E402

import sysid  # noqa: E402

DIR = "."
MAX_TRAIN = 40000


def _col(a):
    return np.asarray(a, dtype=float).reshape(-1, 1)


def _settings(order):
    return dict(order=order, na=order, nb=order, hidden=16, lags=max(2 * order, 6),
                periods=None)


def silverbox():
    d = np.genfromtxt(os.path.join(DIR, "silverbox", "SNLS80mV.csv"), delimiter=",",
                      skip_header=1)[:, :2]
    u, y = _col(d[:, 0]), _col(d[:, 1])
    dt = 2 ** 14 / 1e7
    mu, my = u[40650:127400], y[40650:127400]
    s = int(len(mu) * 0.75)
    train = sysid.IOData(mu[:min(s, MAX_TRAIN)], my[:min(s, MAX_TRAIN)], dt)
    tests = {"arrow": (u[100:40575], y[100:40575]),
             "arrow, no extrapolation": (u[100:32100], y[100:32100]),
             "multisine test": (mu[s:], my[s:])}
    return train, tests, None, _settings(2)


def wh2009():
    d = np.genfromtxt(os.path.join(DIR, "wh2009", "WienerHammerBenchmark.csv"),
                      delimiter=",", skip_header=1)
    u, y = _col(d[:, 0]), _col(d[:, 1])
    n0 = max(0, 100000 - MAX_TRAIN)
    train = sysid.IOData(u[n0:100000], y[n0:100000], 1 / d[0, 2])
    return train, {"test": (u[100000:], y[100000:])}, None, _settings(6)


def tanks():
    d = np.genfromtxt(os.path.join(DIR, "cascaded_tanks", "dataBenchmark.csv"),
                      delimiter=",", skip_header=1)
    train = sysid.IOData(_col(d[:, 0]), _col(d[:, 2]), float(d[0, 4]))
    return train, {"validation": (_col(d[:, 1]), _col(d[:, 3]))}, None, _settings(2)


def emps():
    from scipy.io import loadmat

    def load(f):
        m = loadmat(os.path.join(DIR, "emps", f))
        return _col(m["vir"][:, 0]), _col(m["qm"][:, 0]), float(m["t"][1, 0] - m["t"][0, 0])
    u, y, dt = load("DATA_EMPS.mat")
    ut, yt, _ = load("DATA_EMPS_PULSES.mat")
    n = min(len(u), MAX_TRAIN)
    return sysid.IOData(u[:n], y[:n], dt), {"pulses": (ut, yt)}, None, _settings(2)


LOADERS = {"silverbox": silverbox, "wh2009": wh2009, "tanks": tanks, "emps": emps}


def main():
    global DIR, MAX_TRAIN
    ap = argparse.ArgumentParser()
    ap.add_argument("dir")
    ap.add_argument("--only", default=",".join(LOADERS))
    ap.add_argument("--models", default=None)
    ap.add_argument("--max-train", type=int, default=MAX_TRAIN)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    DIR, MAX_TRAIN = a.dir, a.max_train
    nl.MODELS[:] = [] if a.models is None else a.models.split(",")
    lines = [f"sysid {sysid.__version__}; command: .venv/bin/python "
             f"benches/nonlinear_unshipped.py DIR --only {a.only} --max-train {MAX_TRAIN}"
             + (f" --models {a.models}" if a.models else "")
             + f"; {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}"]
    for name in a.only.split(","):
        nl.run(name, LOADERS[name], lines)
    if a.out:
        with open(a.out, "a") as f:
            f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
