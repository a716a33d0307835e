"""Peer oracles for the polynomial estimators (asserting script; peers live only in the
benchmark environment benches/.venv-peers, see benches/run.py).

    .venv/bin/python benches/oracles_polynomial.py

1. SIPPY's ``ARX_id`` (sippy-unipi) equals ``sysid.arx`` to 1e-10 on the same regression:
   SIPPY's delay ``theta`` is our ``nk - 1`` and both start at row ``max(na, nb + theta)``.
2. statsmodels' SARIMAX with exogenous regressors ``[y(t-1), u(t-1)]`` and an MA(1) error is
   the ARMAX model ``(1 + a q^-1) y = b u(t-1) + (1 + c q^-1) e``; its estimates agree with
   ``sysid.armax`` within our standard deviations.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from scipy import signal

import sysid

sys.path.insert(0, str(Path(__file__).parent))
from run import ensure_peers  # noqa: E402

PEER_CODE = r"""
import json, sys, numpy as np
d = np.load(sys.argv[1])
from sippy_unipi.arx import ARX_id
num, den, _, _, _ = ARX_id(d["y_arx"], d["u_arx"], 2, 3, 1)
import statsmodels.api as sm
y, u = d["y_armax"], d["u_armax"]
exog = np.column_stack([y[:-1], u[:-1]])
res = sm.tsa.SARIMAX(y[1:], exog=exog, order=(0, 0, 1), trend="n").fit(disp=False)
p = res.params
print(json.dumps({"den": den.tolist(), "num": num.tolist(),
                  "armax": [-p[0], p[1], p[2]], "armax_se": res.bse[:3].tolist()}))
"""


def main() -> None:
    py = ensure_peers()
    if py is None:
        sys.exit("peers not installed")
    rng = np.random.default_rng(2024)
    n = 2000
    u = rng.standard_normal(n)
    y = signal.lfilter([0, 0, 0.5, 0.2, -0.1], [1, -1.2, 0.5], u) + 0.1 * rng.standard_normal(n)
    u2 = rng.standard_normal(n)
    e = 0.3 * rng.standard_normal(n)
    y2 = signal.lfilter([0.0, 0.8], [1, -0.7], u2) + signal.lfilter([1, 0.5], [1, -0.7], e)
    with tempfile.TemporaryDirectory() as tmp:
        f = Path(tmp) / "d.npz"
        np.savez(f, y_arx=y, u_arx=u, y_armax=y2, u_armax=u2)
        out = subprocess.run([str(py), "-c", PEER_CODE, str(f)], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(out.stderr)
    peer = json.loads(out.stdout.strip().splitlines()[-1])
    m = sysid.arx(sysid.IOData(u[:, None], y[:, None], 1.0), 2, 3, 2)
    ours_den = np.r_[1.0, m.a[0][0]]
    ours_num = m.b[0][0]
    err_a = np.max(np.abs(ours_den - np.asarray(peer["den"])[:3]))
    err_b = np.max(np.abs(ours_num - np.asarray(peer["num"])[1:4]))
    print(f"ARX(2,3,nk=2) vs SIPPY ARX_id: max |dA| = {err_a:.2e}, max |dB| = {err_b:.2e}")
    assert err_a < 1e-10 and err_b < 1e-10
    a = sysid.armax(sysid.IOData(u2[:, None], y2[:, None], 1.0), 1, 1, 1, 1)
    ours = np.array([a.a[0][0][0], a.b[0][0][0], a.c[0][0]])
    sd = np.sqrt(np.diag(a.covariance[0]))
    theirs = np.asarray(peer["armax"])
    print("ARMAX (a, b, c): sysid", np.round(ours, 4), "std", np.round(sd, 4))
    print("            statsmodels", np.round(theirs, 4), "se", np.round(peer["armax_se"], 4))
    z = np.abs(ours - theirs) / sd
    print("difference in our standard deviations:", np.round(z, 3))
    assert np.all(z < 1.0)
    print("oracles agree")


if __name__ == "__main__":
    main()
