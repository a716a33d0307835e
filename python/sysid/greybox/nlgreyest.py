"""Nonlinear grey-box estimation (the ``sysid.NonlinearGreyBox`` branch of ``sysid.greyest``).

The free parameters and the free initial-state entries of every experiment are found by
minimising the simulation errors (weighted by the inverse of their covariance, re-estimated
between iterations) with the one optimiser of the Rust core. The Rust core integrates the
state equation with all forward-difference perturbations at once (one call of a vectorised
``f`` per integrator stage for the whole Jacobian) and accumulates ``J^T W J`` over the
samples.

The simulation errors are the output disturbance itself, coloured on nearly every real
record, where the search's Gauss-Newton covariance is too small (a first-order plant with a
cubic term and an AR(1) disturbance, pole 0.9, 200 runs: 0.31-0.47 of the sample std, 95 %
intervals covering 47-65 %). The estimate carries the sandwich of :mod:`sysid.pem.sandwich`
instead, formed when first used (:func:`sysid.greybox.coloured.defer_nonlinear`): 0.89-0.94,
covering 89-93 % (``tests/test_nlgreyest_coloured.py``).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from .. import _sysid
from ..data.iodata import IOData
from ..errors import DataError, SysidError
from ..models.paramtable import ParameterTable
from ..models.uncertainty import ParameterUncertainty
from .coloured import defer_nonlinear
from .nlgreybox import NonlinearGreyBox
from .results import GreyEstimate, _costs, _warn_unidentifiable

__all__ = ["nlgreyest"]


def _initial_states(s: NonlinearGreyBox, x0: Any, count: int) -> tuple[np.ndarray, np.ndarray]:
    nx = s.nx
    if x0 is None or (isinstance(x0, str) and x0 == "model"):
        X = s.x0 if s.x0.shape[0] == count else np.repeat(s.x0[:1], count, axis=0)
        F = s.x0_free if s.x0_free.shape[0] == count else np.repeat(s.x0_free[:1], count, 0)
        if X.shape[0] != count:
            raise DataError(f"the structure has {s.x0.shape[0]} initial states for {count} "
                            "experiments")
        return X.astype(float), F.astype(bool)
    if isinstance(x0, str):
        if x0 == "estimate":
            X = s.x0 if s.x0.shape[0] == count else np.repeat(s.x0[:1], count, axis=0)
            return X.astype(float), np.ones((count, nx), bool)
        if x0 == "zero":
            return np.zeros((count, nx)), np.zeros((count, nx), bool)
        raise DataError(f"x0 must be 'model', 'estimate', 'zero' or an array, got {x0!r}")
    X = np.atleast_2d(np.asarray(x0, dtype=float))
    if X.shape[1] != nx:
        raise DataError(f"x0 has {X.shape[1]} entries per experiment, the structure {nx}")
    if X.shape[0] == 1:
        X = np.repeat(X, count, axis=0)
    if X.shape[0] != count:
        raise DataError(f"x0 has {X.shape[0]} rows for {count} experiments")
    return X, np.zeros((count, nx), bool)


def nlgreyest(data: IOData, s: NonlinearGreyBox, *, x0: Any, weighting: str, multistart: int,
              rng: Any, max_iter: int, tol: float, progress: Any) -> Any:
    """See :func:`sysid.greyest` (the nonlinear branch)."""
    exps = [(np.ascontiguousarray(u), np.ascontiguousarray(y)) for u, y in data.experiments]
    dt = float(data.dt)
    if s.dt and abs(s.dt - dt) > 1e-9 * dt:
        raise DataError(f"the structure's dt={s.dt} differs from the data's dt={dt}: "
                        "resample the data or give the structure the data's sample time")
    for what, given, have in (("input", s._ninputs, data.n_inputs),
                              ("output", s._noutputs, data.n_outputs)):
        if given is not None and given != have:
            raise DataError(f"the structure has {given} {what}(s) (n{what}s={given}), the "
                            f"data {have}: select the data's channels or fix n{what}s")
    s = s.with_values({}, dt=dt)
    s._ninputs, s._noutputs = data.n_inputs, data.n_outputs
    s._input_names, s._output_names = data.input_names, data.output_names
    X0, F0 = _initial_states(s, x0, len(exps))
    names = s.names
    free = s.free_names
    free_idx = [names.index(k) for k in free]
    free_x0 = [(e, i) for e in range(len(exps)) for i in range(s.nx) if F0[e, i]]
    typical = [s.params[k].typical for k in free] + [1.0] * len(free_x0)
    lower = [s.params[k].bounds[0] for k in free] + [-np.inf] * len(free_x0)
    upper = [s.params[k].bounds[1] for k in free] + [np.inf] * len(free_x0)

    def run(p: np.ndarray, cb: Any) -> dict[str, Any]:
        t0 = time.perf_counter()
        structure = (s.nx, list(map(float, p)), free_idx, [list(map(float, r)) for r in X0],
                     free_x0, typical)
        res = _sysid.greybox_ode(
            s.rhs(), s.out(), exps, structure, dt, reweight=weighting == "noise",
            integration=s.core_options(), jacobian=s.jacobian_options(free),
            search={"lower": lower, "upper": upper, "max_iter": max_iter, "tol_cost": tol},
            progress=cb)
        res["seconds"] = time.perf_counter() - t0
        res["loss"] = float(np.linalg.det(np.atleast_2d(res["innovation_covariance"])))
        return res

    best = run(s.values, progress)
    starts: list[float | None] = []
    if multistart:
        gen = np.random.default_rng(rng)
        for _ in range(multistart):
            p = s.values.copy()
            for k, i in zip(free, free_idx):
                lo, hi = s.params[k].bounds
                t = s.params[k].typical
                a = lo if np.isfinite(lo) else p[i] - 2 * t
                b = hi if np.isfinite(hi) else p[i] + 2 * t
                p[i] = gen.uniform(max(a, lo), min(b, hi))
            try:
                r = run(p, None)
            except SysidError:
                starts.append(None)
                continue
            starts.append(r["loss"])
            if r["loss"] < best["loss"]:
                best = r
    theta = np.asarray(best["theta"])
    nf = len(free)
    vals = dict(zip(names, s.values.tolist()))
    vals.update(zip(free, theta[:nf].tolist()))
    X = X0.copy()
    for k, (e, i) in enumerate(free_x0):
        X[e, i] = theta[nf + k]
    cov_all = np.asarray(best["covariance"])
    cov = cov_all[:nf, :nf]
    std = dict(zip(free, np.sqrt(np.clip(np.diag(cov), 0, None))))
    qnames = free + [f"x0[{e}][{i}]" for e, i in free_x0]
    for i in _warn_unidentifiable(np.asarray(best["unidentifiable"]), qnames,
                                  np.ones(len(qnames)), theta):
        if i < nf:  # a direction the data do not determine: no finite std
            std[free[i]] = float("inf")
    active = {int(i) for i in best["active_bounds"] if i < nf}
    bound = []
    for k in names:
        i = free.index(k) if k in free else -1
        bound.append(("lower" if theta[i] <= lower[i] else "upper") if i in active else "")
    table = ParameterTable(names, [vals[k] for k in names], [std.get(k, 0.0) for k in names],
                           [s.params[k].fixed for k in names], bound,
                           [s.params[k].unit for k in names],
                           [s.params[k].description for k in names]
                           ).cut_at_bounds(*np.array([s.params[k].bounds for k in names],
                                                     float).T)
    est = s.with_values(vals, x0=X, dt=dt)
    info = {
        "method": "greyest (nonlinear)", "iterations": best["iterations"],
        "evaluations": best["evaluations"], **_costs(best, weighting == "noise"),
        "stop": best["stop"],
        "condition": best["condition"], "rank": int(best["rank"]), "n_free": len(qnames),
        "n_samples": int(best["n_samples"]), "focus": "simulation", "x0_values": list(X),
        "multistart": starts, "loss": best["loss"], "seconds": best["seconds"],
        "rhs_calls": int(best["rhs_calls"]), "integrator": s.integrator,
        "jacobian": s.jacobian_method,
        "greybox": {"parameters": table.rows()},
    }
    est.info = info

    def build(theta_free: np.ndarray) -> NonlinearGreyBox:
        v = dict(vals)
        v.update(zip(free, np.asarray(theta_free, dtype=float)))
        return est.with_values(v)

    est.uncertainty = ParameterUncertainty(theta[:nf], cov, build, names=free,
                                           dof=min(int(best["rank"]), nf))
    out = GreyEstimate(table, cov, free, est, est, list(X), info)
    defer_nonlinear(out, best, exps, X, free_x0, weighting == "noise",
                    tuple(np.array([s.params[k].bounds for k in names], float).T))
    return out
