"""sysid's time-series estimators against statsmodels (the peer), in one run.

    .venv/bin/python benches/timeseries.py       # writes benches/results/timeseries.md

statsmodels lives in benches/.venv-peers only (never a dependency of sysid; ``python
benches/run.py`` creates that environment, or ``benches/.venv-peers/bin/pip install
statsmodels``). The same records (AR(4) and ARMA(2, 2), 10^4 and 10^5 samples, seeded) are
fitted by

* sysid.ar with "yw", "burg", "ls" against statsmodels' ``yule_walker(method="mle")``,
  ``burg`` and ``AutoReg(trend="n")`` (the same estimators: the estimates must agree to
  round-off);
* sysid.arma (prediction error from rest, the shared Gauss-Newton search) against
  statsmodels' ``ARIMA(order=(2, 0, 2), trend="n")`` (exact Gaussian likelihood by the Kalman
  filter): a different criterion, so the estimates differ by a fraction of their std; the
  table reports the largest difference in units of sysid's reported std.

Times are wall-clock, best of three, each tool on the same machine in the same run; the ratio
is statsmodels / sysid (above 1: sysid is faster).
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy import signal

import sysid

HERE = Path(__file__).resolve().parent
PEER = HERE / ".venv-peers" / "bin" / "python"
OUT = HERE / "results" / "timeseries.md"

AR4 = np.poly([0.9, 0.7 * np.exp(0.6j), 0.7 * np.exp(-0.6j), -0.5]).real
ARMA_A, ARMA_C = [1.0, -1.2, 0.5], [1.0, 0.5, -0.2]

NOTE = """\
Where sysid loses (yw, burg): statsmodels returns the coefficients only; sysid also checks
the record (finite, not constant), computes the innovation variance and the asymptotic
covariance (residual filter and Gram matrix of the regressors, O(N n^2)) and builds a model
with its uncertainty. ARMA: statsmodels' exact likelihood (state-space Kalman filter in
Python/Cython, numerical derivatives) against the Rust prediction-error search; the estimates
agree to a hundredth of their std. The machine was heavily loaded (see the load average):
absolute times are several times the unloaded ones, the ratios compare tools in the same run.
"""

PEER_SCRIPT = r"""
import json, sys, time, warnings
import numpy as np
from statsmodels.regression.linear_model import yule_walker, burg
from statsmodels.tsa.ar_model import AutoReg
from statsmodels.tsa.arima.model import ARIMA

def best(f):
    out, ts = None, []
    for _ in range(3):
        t0 = time.perf_counter(); out = f(); ts.append(time.perf_counter() - t0)
    return min(ts), out

res = {}
for name, path in json.loads(sys.argv[1]).items():
    y = np.load(path)
    if not name.startswith("arma"):
        t, rho = best(lambda: yule_walker(y, order=4, method="mle", demean=False)[0])
        res[name + ":yw"] = [t, (-rho).tolist()]
        t, rho = best(lambda: burg(y, order=4, demean=False)[0])
        res[name + ":burg"] = [t, (-rho).tolist()]
        t, p = best(lambda: AutoReg(y, lags=4, trend="n").fit().params)
        res[name + ":ls"] = [t, (-p).tolist()]
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            t, p = best(lambda: ARIMA(y, order=(2, 0, 2), trend="n").fit().params)
        res[name + ":arma"] = [t, [-p[0], -p[1], p[2], p[3]]]
print(json.dumps(res))
"""


def best(f, reps: int = 3):  # type: ignore[no-untyped-def]
    out, ts = None, []
    for _ in range(reps):
        t0 = time.perf_counter()
        out = f()
        ts.append(time.perf_counter() - t0)
    return min(ts), out


def records() -> dict[str, np.ndarray]:
    out = {}
    for n in (10_000, 100_000):
        e = np.random.default_rng(n).standard_normal(n)
        out[f"ar-{n}"] = signal.lfilter([1.0], AR4, e)
        out[f"arma-{n}"] = signal.lfilter(ARMA_C, ARMA_A, e)
    return out


def ours(name: str, y: np.ndarray) -> dict[str, list]:
    res: dict[str, list] = {}
    if not name.startswith("arma"):
        for method in ("yw", "burg", "ls"):
            t, m = best(lambda method=method: sysid.ar(y, 4, method))
            res[f"{name}:{method}"] = [t, m.a[0][0].tolist(), m.std["a"][0][0].tolist()]
    else:
        t, m = best(lambda: sysid.arma(y, 2, 2))
        res[f"{name}:arma"] = [t, [*m.a[0][0], *m.c[0]],
                               [*m.std["a"][0][0], *m.std["c"][0]]]
    return res


def main() -> None:
    if not PEER.exists():
        sys.exit("benches/.venv-peers is missing: run `python benches/run.py --quick` once or "
                 "create it and `pip install statsmodels` there")
    recs = records()
    mine: dict[str, list] = {}
    for name, y in recs.items():
        mine.update(ours(name, y))
    with tempfile.TemporaryDirectory() as tmp:
        paths = {}
        for name, y in recs.items():
            paths[name] = str(Path(tmp) / f"{name}.npy")
            np.save(paths[name], y)
        run = subprocess.run([str(PEER), "-c", PEER_SCRIPT, json.dumps(paths)],
                             capture_output=True, text=True, check=True)
    peer = json.loads(run.stdout.strip().splitlines()[-1])
    peer_version = subprocess.run([str(PEER), "-c", "import statsmodels; "
                                   "print(statsmodels.__version__)"], capture_output=True,
                                  text=True).stdout.strip()
    rows = []
    for key, (t, est, sd) in mine.items():
        tp, ep = peer[key]
        diff = np.abs(np.asarray(est) - np.asarray(ep))
        agree = (f"{diff.max():.1e}" if not key.endswith("arma")
                 else f"{diff.max():.1e} ({(diff / np.asarray(sd)).max():.2f} std)")
        n = key.split(":")[0].split("-")[1]
        rows.append(f"| {key.split(':')[1]} | {int(n):,} | {t * 1e3:,.1f} ms | "
                    f"{tp * 1e3:,.1f} ms | {tp / t:,.1f}x | {agree} |")
    text = "\n".join([
        "# Time series: sysid against statsmodels",
        "",
        "`.venv/bin/python benches/timeseries.py` "
        f"({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
        f"{platform.machine()}, shared 2-core machine, load average {os.getloadavg()[0]:.1f}; "
        f"wall time, best of 3; statsmodels {peer_version} in benches/.venv-peers).",
        "",
        "AR(4) (`yw`: statsmodels `yule_walker(method=\"mle\")`, `burg`: `burg`, `ls`: "
        "`AutoReg(trend=\"n\")`; the same estimators) and ARMA(2, 2) (sysid: prediction error "
        "from rest; statsmodels: `ARIMA(order=(2, 0, 2), trend=\"n\")`, exact likelihood by the "
        "Kalman filter, a different criterion). Agreement: the largest absolute difference of "
        "the coefficients (for ARMA also in units of sysid's reported std).",
        "",
        "| estimator | N | sysid | statsmodels | ratio (statsmodels / sysid) | agreement |",
        "|---|---|---|---|---|---|",
        *rows,
        "",
        *NOTE.splitlines(),
        "",
    ])
    OUT.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
