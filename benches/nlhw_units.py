"""Does the Hammerstein-Wiener row of benches/nonlinear.py depend on the channels' units?

nlhw (one input and output) or nlhw_ss (otherwise), sigmoid networks of 3 units in and out,
fitted as the nonlinear bench fits them (each channel centred on its training mean) and on
standardised channels (also divided by its training standard deviation); test RMSE in the
record's units. A model whose fit depends on the units has a search (start, damping, stop)
that does: the criterion's minimiser does not move for one output.

    SYSID_SHARED_DATA=/work/shared/data .venv/bin/python benches/nlhw_units.py \
        ph f16 boucwen [tanks emps silverbox wh2009, with SYSID_NLREC=DIR]

``DIR`` for the unshipped records as in benches/nonlinear_unshipped.py.
"""
import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import nonlinear as nl  # noqa: E402
import nonlinear_unshipped as nu  # noqa: E402

import sysid  # noqa: E402

nu.DIR = os.environ.get("SYSID_NLREC", ".")
nu.MAX_TRAIN = 40000
RECORDS = {"ph": nl.ph, "f16": nl.f16, "boucwen": nl.boucwen, "tanks": nu.tanks,
           "emps": nu.emps, "silverbox": nu.silverbox, "wh2009": nu.wh2009}


def fit(d, s):
    """The bench's Hammerstein-Wiener fit of ``d`` (nlhw for one input and output)."""
    kw = dict(input_nl=sysid.SigmoidNetwork(3), output_nl=sysid.SigmoidNetwork(3),
              progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if d.n_inputs == 1 and d.n_outputs == 1:
            return sysid.nlhw(d, s["nb"], s["na"], **kw)
        return sysid.nlhw_ss(d, s["order"], **kw)


def main(names):
    for name in names:
        train, tests, P, s = RECORDS[name]()
        U = np.vstack([e[0] for e in train.experiments])
        Y = np.vstack([e[1] for e in train.experiments])
        mu, my = U.mean(0), Y.mean(0)
        for mode in ("centred", "standardised"):
            su, sy = (U.std(0), Y.std(0)) if mode == "standardised" else (1.0, 1.0)
            d = sysid.IOData([(e[0] - mu) / su for e in train.experiments],
                             [(e[1] - my) / sy for e in train.experiments], train.dt)
            t = time.perf_counter()
            m = fit(d, s)
            el = time.perf_counter() - t
            out = {}
            for tn, (u, y) in tests.items():
                yh = np.asarray(nl.sim(m, (u - mu) / su, P)).reshape(len(u), -1) * sy + my
                out[tn] = round(float(np.sqrt(np.mean((y - yh) ** 2))), 6)
            print(name, mode, f"{el:.1f} s", m.info.get("iterations"), m.info.get("stop"), out,
                  flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
