"""Candidate data-driven default horizons for the subspace fits, measured on the real records
of ``benches/realdata.py`` (results in ``results/subspace_defaults.md``; no default changed).

    .venv/bin/python benches/horizon_rules.py RULE [realdata.py arguments]
    .venv/bin/python benches/horizon_rules.py --compare BASE.json RULE.json [...]

``RULE`` replaces the default horizon (``available_horizon``: the largest ``i <= 20`` whose
data matrix has ten times as many columns as rows) of every ``SubspaceEstimator`` made without
a horizon (``n4sid``, ``moesp``, ``cva``, ``ssest``'s start) on an input-output record:

- ``aic``: ``k + 1``, ``k`` the order of the vector ARX model (``y(t)`` on ``k`` past outputs
  and inputs, channels scaled) that minimises Akaike's criterion (as MATLAB's ``N4Horizon``
  "auto" takes its horizons from an ARX order chosen by AIC), within today's data allowance
  raised from 20 to 50 blocks;
- ``aic_longer``: the larger of today's and ``aic``'s (only longer, where the data allow);
- ``memory``: the length over which that ARX model's impulse responses hold 99 % of their
  energy, with the allowance relaxed to four times as many columns as rows (so a slow
  process such as the DaISy heating system gets 33 blocks rather than 13).

The horizon is then given to the estimator as ``horizon=`` (the order choice of
``order="auto"`` runs at it). ``--compare`` prints, per record and tool, the validation fits of
two result files of ``realdata.py`` and how many moved by more than 0.5 points.
"""

from __future__ import annotations

import functools
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))


def _scaled(x: np.ndarray) -> np.ndarray:
    x = x - x.mean(0)
    s = x.std(0)
    return x / np.where(s > 0, s, 1.0)


def arx_aic(data, kmax: int):
    """``(k, theta)``: the vector ARX order by AIC (``N log det S + 2 k l (l + m)``) and its
    coefficients (rows: ``k`` lags of the outputs, then ``k`` of the inputs)."""
    l, m = data.n_outputs, data.n_inputs
    P = l + kmax * (l + m)
    G, n = np.zeros((P, P)), 0
    for u, y in data.experiments:
        u, y = _scaled(np.asarray(u, float)), _scaled(np.asarray(y, float))
        N = y.shape[0]
        if N <= kmax + 1:
            continue
        Z = np.hstack([y[kmax - j:N - j] for j in range(kmax + 1)]
                      + [u[kmax - j:N - j] for j in range(1, kmax + 1)])
        G += Z.T @ Z
        n += N - kmax
    best, crit, theta = 1, np.inf, None
    for k in range(1, kmax + 1):
        idx = list(range(l, l + k * l)) + list(range(l + kmax * l, l + kmax * l + k * m))
        gxy = G[np.ix_(idx, range(l))]
        th = np.linalg.lstsq(G[np.ix_(idx, idx)], gxy, rcond=None)[0]
        sign, logdet = np.linalg.slogdet((G[:l, :l] - gxy.T @ th) / max(n, 1))
        if sign <= 0:
            break
        c = n * logdet + 2 * k * l * (l + m)
        if c < crit:
            best, crit, theta = k, c, th
    return best, theta


def memory(data, k: int, theta: np.ndarray, top: int) -> int:
    """Samples until the ARX model's impulse responses hold 99 % of their energy."""
    l, m = data.n_outputs, data.n_inputs
    A = [theta[j * l:(j + 1) * l].T for j in range(k)]
    B = [theta[k * l + j * m:k * l + (j + 1) * m].T for j in range(k)]
    h = np.zeros((4 * top, l, m))
    for t in range(4 * top):
        acc = B[t].copy() if t < k else np.zeros((l, m))
        for j in range(min(k, t)):
            acc += A[j] @ h[t - j - 1]
        h[t] = acc
        if not np.all(np.isfinite(h[t])) or np.abs(h[t]).max() > 1e12:
            return top
    e = np.cumsum((h ** 2).sum(axis=(1, 2)))
    return 2 if e[-1] <= 0 else int(np.searchsorted(e, 0.99 * e[-1]) + 1)


def allowance(lengths, m: int, l: int, factor: int, top: int = 50) -> int:
    """The largest ``i <= top`` with ``factor * i * (m + l)`` samples in the experiments of
    at least ``4 i`` (today's rule: ``factor = 20``, ``top = 20``)."""
    for i in range(top, 1, -1):
        if sum(n for n in lengths if n >= 4 * i) >= factor * i * (m + l):
            return i
    return 2


def horizon(data, rule: str) -> int:
    from sysid.subspace.data_horizon import available_horizon

    lengths, m, l = list(data.lengths), data.n_inputs, data.n_outputs
    i0 = available_horizon(lengths, m, l)
    if rule == "default":
        return i0
    kmax = max(2, min(50, allowance(lengths, m, l, 8)))
    k, theta = arx_aic(data, kmax)
    if rule in ("aic", "aic_longer"):
        i = max(2, min(allowance(lengths, m, l, 20), k + 1))
        return max(i, i0) if rule == "aic_longer" else i
    if rule == "memory":
        mem = memory(data, k, theta, kmax) if theta is not None else i0
        return max(2, min(allowance(lengths, m, l, 8), mem))
    raise SystemExit(f"unknown rule {rule!r}: aic, aic_longer, memory")


def compare(base: str, other: str) -> None:
    b = {(r["record"], r["tool"]): r for r in json.loads(Path(base).read_text())}
    o = {(r["record"], r["tool"]): r for r in json.loads(Path(other).read_text())}
    moved = {"up": 0, "down": 0, "same": 0}
    worst = (0.0, "")
    for rec in dict.fromkeys(k[0] for k in o):
        cells = []
        for tool in ("n4sid", "moesp", "ssest", "cva"):
            if (rec, tool) not in o or (rec, tool) not in b:
                continue
            x, y = float(b[(rec, tool)]["fit"]), float(o[(rec, tool)]["fit"])
            moved["up" if y - x > 0.5 else "down" if y - x < -0.5 else "same"] += 1
            worst = min(worst, (y - x, f"{rec} {tool}"))
            cells.append(f"{tool} {x:.1f} -> {y:.1f}")
        print(f"{rec:18s} " + " | ".join(cells))
    print(f"up {moved['up']}, down {moved['down']}, within 0.5: {moved['same']}; "
          f"largest drop {worst[0]:.1f} ({worst[1]})")


def main() -> None:
    if sys.argv[1] == "--compare":
        for other in sys.argv[3:]:
            compare(sys.argv[2], other)
        return
    rule = sys.argv[1]
    from sysid.data.iodata import require_record
    from sysid.subspace import estimator as est

    original = est.SubspaceEstimator.__init__

    @functools.wraps(original)
    def patched(self, data, *args, **kw):
        given = args[0] if args else kw.get("horizon")
        if given is None and kw.get("past") is None and kw.get("future") is None:
            d = require_record(data, "SubspaceEstimator")
            if d.n_inputs > 0:
                h = horizon(d, rule)
                args = (h, *args[1:]) if args else args
                if not args:
                    kw["horizon"] = h
        return original(self, data, *args, **kw)

    est.SubspaceEstimator.__init__ = patched
    import realdata

    sys.argv = ["realdata.py", *sys.argv[2:]]
    realdata.main()


if __name__ == "__main__":
    main()
