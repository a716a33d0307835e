"""Hammerstein-Wiener fit speed on the nonlinear benchmarks (issues 28/29): process CPU and
wall seconds, iterations, final cost and test RMSE of one fit.

    .venv/bin/python benches/hw_speed.py f16 [--iter 30 --scaled]   # nlssest's _hw_fit settings
    .venv/bin/python benches/hw_speed.py f16|ph|boucwen             # the nlhw row of nonlinear.py

``f16|ph|boucwen`` runs the same call as the ``nlhw`` row of ``benches/nonlinear.py`` (its
loaders and settings: ``nlhw_ss`` for several channels, means removed, 540 s budget; SISO
``nlhw`` otherwise). ``--scaled`` also divides the channels by their standard deviations and
``--iter`` caps the iterations, as ``nlssest``'s Hammerstein-Wiener start does (it fits on
nlssest's training parts, so its own numbers differ slightly).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import nonlinear as nb  # noqa: E402

import sysid  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("case", choices=["f16", "ph", "boucwen"])
    ap.add_argument("--iter", type=int, default=None)
    ap.add_argument("--scaled", action="store_true")
    a = ap.parse_args()
    train, tests, warm, s = {"ph": nb.ph, "boucwen": nb.boucwen, "f16": nb.f16}[a.case]()
    exps = train.experiments
    u = np.vstack([e[0] for e in exps])
    y = np.vstack([e[1] for e in exps])
    us, ys = (u.std(axis=0), y.std(axis=0)) if a.scaled else (1.0, 1.0)
    kw = {} if a.iter is None else {"max_iter": a.iter}
    c0, t0 = time.process_time(), time.perf_counter()
    if train.n_inputs == 1 and train.n_outputs == 1 and not a.scaled:
        mod = sysid.nlhw(train, s["nb"], s["na"], input_nl=sysid.SigmoidNetwork(3),
                         output_nl=sysid.SigmoidNetwork(3), progress=False, **kw)
        info, sim = mod.info, mod
    else:
        d = sysid.IOData([e[0] / us for e in exps], [e[1] / ys for e in exps], train.dt)
        mod = nb.Offset(d, lambda d: sysid.nlhw_ss(
            d, s["order"], input_nl=sysid.SigmoidNetwork(3), output_nl=sysid.SigmoidNetwork(3),
            progress=nb.Budget(), **kw))
        info = mod.model.info

        class sim:  # noqa: N801 - the model in the record's units
            @staticmethod
            def simulate(uu):
                return mod.simulate(uu / us) * ys
    cpu, wall = time.process_time() - c0, time.perf_counter() - t0
    cost = info["cost"][-1]
    cells = []
    for k, (uu, yy) in tests.items():
        r, f = nb.metrics(yy, nb.sim(sim, uu, warm))
        cells.append(f"{k}: RMSE {r:.4g} fit {f:.1f}")
    print(f"{a.case}: cpu {cpu:.2f} s, wall {wall:.1f} s, iterations {info.get('iterations')} "
          f"({info.get('stop')}), final cost {cost!r}; " + "; ".join(cells), flush=True)


if __name__ == "__main__":
    main()
