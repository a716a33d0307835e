"""nlarx network nonlinearities (sigmoid network, wavelet network, tree partition) against
sysidentpy's neural NARX (NARXNN, a PyTorch multilayer perceptron trained by Adam) on the
same lagged regressors: fit time and free-run validation fit.

    .venv/bin/python benches/nlarx_networks.py           # N = 2000 and 10000
    .venv/bin/python benches/nlarx_networks.py --quick   # N = 2000 only

Data: a Wiener system (second-order linear block x(t) = 1.3 x(t-1) - 0.5 x(t-2) + 0.6 u(t-1)
+ 0.2 u(t-2), then y = tanh(x) + e, u uniform on [-0.6, 0.6], e ~ N(0, 0.01^2)); estimation
and validation records from different seeds. Every tool gets lags na = nb = 2, nk = 1 and 10
hidden units (sysidentpy: ylag = xlag = 2, Polynomial(degree=1) regressors, one hidden layer
of 10 sigmoid units, its defaults otherwise (Adam, learning rate 0.01, batches of 100,
200 epochs, one-step-ahead training), random_state=0; sysid:
``nlarx(..., basis=SigmoidNetwork(10))`` etc., prediction focus, separable least squares on
the shared Gauss-Newton optimiser). Fit: 100 (1 - |y - ysim| / |y - mean y|) of the free-run
simulation from the measured first two outputs (sysidentpy: ``predict`` with
``steps_ahead=None``, its free run). Every (case, tool) runs in its own subprocess with a
timeout. sysidentpy and torch live in benches/.venv-peers only (``benches/.venv-peers/bin/python
-m pip install sysidentpy torch``: PyPI's torch with its nvidia-* dependency wheels, run on the
CPU), never in sysid's environment. Results: benches/results/nlarx_networks.md.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
PEERS = HERE / ".venv-peers" / "bin" / "python"
DATA = HERE / ".data"
UNITS = 10
TOOLS = ("sysid-arx", "sysid-sigmoidnet", "sysid-wavenet", "sysid-treepartition",
         "sysidentpy-narxnn", "sysidentpy-frols")


def make(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    u = rng.uniform(-0.6, 0.6, n)
    x = np.zeros(n)
    for t in range(2, n):
        x[t] = 1.3 * x[t - 1] - 0.5 * x[t - 2] + 0.6 * u[t - 1] + 0.2 * u[t - 2]
    return u, np.tanh(x) + 0.01 * rng.standard_normal(n)


def data_file(n: int) -> Path:
    from data import estimation_validation_file

    return estimation_validation_file(DATA / f"nlarx_networks_{n}.npz", make, n, 2000)


def fit_percent(y: np.ndarray, ys: np.ndarray) -> float:
    y, ys = y[2:], ys[2:]
    return float(100 * (1 - np.linalg.norm(y - ys) / np.linalg.norm(y - y.mean())))


def sysid_worker(tool: str, u, y, uv, yv) -> tuple[float, float]:
    import sysid

    basis = {"sysid-sigmoidnet": sysid.SigmoidNetwork(UNITS),
             "sysid-wavenet": sysid.WaveletNetwork(UNITS),
             "sysid-treepartition": sysid.TreePartition(UNITS)}.get(tool)
    est = sysid.IOData(u[:, None], y[:, None], 1.0)
    sysid.arx(sysid.IOData(u[:200, None], y[:200, None], 1.0), 2, 2, 1)  # warm-up
    t = time.perf_counter()
    if basis is None:
        m = sysid.arx(est, 2, 2, 1)
    else:
        m = sysid.nlarx(est, 2, 2, 1, basis=basis, progress=False)
    elapsed = time.perf_counter() - t
    ys = (m.simulate(uv[:, None]) if basis is None
          else m.simulate(uv[:, None], x0=yv[:2, None]))[:, 0]
    return elapsed, fit_percent(yv, ys)


def peer_worker(u, y, uv, yv) -> tuple[float, float]:
    import torch
    from sysidentpy.basis_function import Polynomial
    from sysidentpy.neural_network import NARXNN
    from torch import nn

    torch.manual_seed(0)
    torch.set_num_threads(1)

    class Net(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.hidden = nn.Linear(4, UNITS)
            self.out = nn.Linear(UNITS, 1)

        def forward(self, xb):
            return self.out(torch.sigmoid(self.hidden(xb)))

    model = NARXNN(net=Net(), ylag=2, xlag=2, basis_function=Polynomial(degree=1),
                   model_type="NARMAX", loss_func="mse_loss", optimizer="Adam", epochs=200,
                   verbose=False, optim_params={"betas": (0.9, 0.999), "eps": 1e-05},
                   random_state=0)
    t = time.perf_counter()
    model.fit(X=u[:, None], y=y[:, None])
    elapsed = time.perf_counter() - t
    ys = np.asarray(model.predict(X=uv[:, None], y=yv[:, None]))
    return elapsed, fit_percent(yv, ys.ravel()[: yv.size])


def frols_worker(u, y, uv, yv) -> tuple[float, float]:
    from sysidentpy.basis_function import Polynomial
    from sysidentpy.model_structure_selection import FROLS
    from sysidentpy.parameter_estimation import LeastSquares

    t = time.perf_counter()
    m = FROLS(order_selection=True, info_criteria="aic", n_info_values=15, ylag=2, xlag=2,
              estimator=LeastSquares(), basis_function=Polynomial(degree=3))
    m.fit(X=u[:, None], y=y[:, None])
    elapsed = time.perf_counter() - t
    ys = np.asarray(m.predict(X=uv[:, None], y=yv[:, None])).ravel()[: yv.size]
    return elapsed, fit_percent(yv, ys)


def worker(tool: str, path: str) -> dict:
    d = np.load(path)
    u, y, uv, yv = d["u"], d["y"], d["uv"], d["yv"]
    if tool.startswith("sysid-"):
        elapsed, fit = sysid_worker(tool, u, y, uv, yv)
    elif tool == "sysidentpy-frols":
        elapsed, fit = frols_worker(u, y, uv, yv)
    else:
        elapsed, fit = peer_worker(u, y, uv, yv)
    return {"time": elapsed, "fit": fit}


def run(tool: str, n: int, timeout: float) -> dict:
    py = sys.executable if tool.startswith("sysid-") else str(PEERS)
    if not Path(py).exists():
        return {"error": "benches/.venv-peers missing (pip install sysidentpy torch)"}
    env_path = str(ROOT / "python") if tool.startswith("sysid-") else ""
    cmd = [py, __file__, "--worker", tool, str(data_file(n))]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                           env={"PYTHONPATH": env_path, "OMP_NUM_THREADS": "1",
                                "RAYON_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"})
    except subprocess.TimeoutExpired:
        return {"error": f"timeout {timeout:.0f} s"}
    if r.returncode != 0:
        last = (r.stderr.strip().splitlines() or ["failed"])[-1]
        if "libcublas" in last or "libcud" in last:
            return {"error": "torch does not import (no CUDA libraries; see notes)"}
        return {"error": last[:120]}
    return json.loads(r.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--worker", nargs=2)
    ap.add_argument("--timeout", type=float, default=900)
    a = ap.parse_args()
    if a.worker:
        print(json.dumps(worker(*a.worker)))
        return
    sizes = [2000] if a.quick else [2000, 10000]
    lines = ["# nlarx network nonlinearities against sysidentpy's neural NARX", "",
             "Command: `.venv/bin/python benches/nlarx_networks.py" + (" --quick" if a.quick
                                                                       else "") + "`", "",
             "Wiener system (see the script's docstring), lags na = nb = 2, nk = 1, 10 units; "
             "one thread per tool. Fit: free-run validation fit (%) on 2000 fresh samples. "
             "Ratios: sysid's time / the peer's time (below 1: sysid faster) and sysid's fit "
             "minus the peer's fit (points); the peer is sysidentpy's NARXNN when it runs, else "
             "its polynomial FROLS NARX (degree 3, terms by AIC).", "",
             "| N | tool | time (s) | fit (%) | time ratio | fit difference |",
             "|---|---|---|---|---|---|"]
    for n in sizes:
        res = {t: run(t, n, a.timeout) for t in TOOLS}
        peer = res["sysidentpy-narxnn"]
        if "error" in peer:  # the neural peer could not run: ratios against FROLS
            peer = res["sysidentpy-frols"]
        for t in TOOLS:
            r = res[t]
            if "error" in r:
                lines.append(f"| {n} | {t} | - | - | - | {r['error']} |")
                print(n, t, r, file=sys.stderr)
                continue
            ratio = diff = "-"
            if "error" not in peer:
                ratio = f"{r['time'] / peer['time']:.3g}"
                diff = f"{r['fit'] - peer['fit']:+.1f}"
            lines.append(f"| {n} | {t} | {r['time']:.3g} | {r['fit']:.1f} | {ratio} | {diff} |")
            print(n, t, r, file=sys.stderr)
    out = HERE / "results" / ("nlarx_networks_quick.md" if a.quick else "nlarx_networks.md")
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
