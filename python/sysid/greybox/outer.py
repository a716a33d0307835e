"""The searched ("outer") parameters of a linear grey-box fit and the estimate built from
them, shared by :func:`sysid.greyest`'s time-domain and frequency-domain paths: the free
parameters scaled by their typical size, their bounds, random starts for ``multistart``, and
the parameter table, covariance and model with uncertainty at the solution.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..models.paramtable import ParameterTable
from ..models.uncertainty import ParameterUncertainty
from .delays import tap_states
from .greybox import GreyBox
from .results import _warn_unidentifiable

__all__: list[str] = []


class OuterParameters:
    """The free parameters of ``s`` as the search sees them (``z = value / typical``)."""

    def __init__(self, s: GreyBox) -> None:
        self.s = s
        self.free = s.free_names
        self.nf = len(self.free)
        self.scale = np.array([s.params[k].typical for k in self.free])
        self.names = list(self.free)
        self.z0 = np.array([s.params[k].value / sc for k, sc in zip(self.free, self.scale)],
                           dtype=float)
        self.lower = np.array([s.params[k].bounds[0] / sc
                               for k, sc in zip(self.free, self.scale)], dtype=float)
        self.upper = np.array([s.params[k].bounds[1] / sc
                               for k, sc in zip(self.free, self.scale)], dtype=float)

    def values(self, z: np.ndarray) -> dict[str, float]:
        vals = {k: v.value for k, v in self.s.params.items()}
        for k, zi, sc in zip(self.free, z[:self.nf], self.scale):
            vals[k] = float(zi * sc)
        return vals

    def random_start(self, gen: np.random.Generator) -> np.ndarray:
        z = self.z0.copy()
        for i in range(self.nf):
            lo, hi = self.lower[i], self.upper[i]
            a = lo if np.isfinite(lo) else z[i] - 2.0 * max(1.0, abs(z[i]))
            b = hi if np.isfinite(hi) else z[i] + 2.0 * max(1.0, abs(z[i]))
            z[i] = gen.uniform(max(a, lo), min(b, hi))
        return z

    def run(self, z0: np.ndarray, max_iter: int, tol: float, cb: Any) -> dict[str, Any]:
        """One search from ``z0`` (each path's core call)."""
        raise NotImplementedError

    def best_of_starts(self, max_iter: int, tol: float, cb: Any, multistart: int, rng: Any,
                       key: str) -> tuple[dict[str, Any], list[float | None]]:
        """The search from the structure's values and from ``multistart`` random starts
        (:meth:`random_start`, seeded by ``rng``; the bar ``cb`` only on the first): the one
        with the lowest ``res[key]``, and each random start's ``key`` (``None``: it failed)."""
        from ..errors import SysidError

        best = self.run(self.z0, max_iter, tol, cb)
        starts: list[float | None] = []
        gen = np.random.default_rng(rng) if multistart else None
        for _ in range(multistart):
            try:
                r = self.run(self.random_start(gen), max_iter, tol, None)  # type: ignore[arg-type]
            except SysidError:
                starts.append(None)
                continue
            starts.append(float(r[key]))
            if r[key] < best[key]:
                best = r
        return best, starts

    def estimate(self, res: dict[str, Any], make: Callable[[GreyBox, dict[str, float],
                                                                 dict[str, Any] | None], Any],
                 info: dict[str, Any]) -> tuple[ParameterTable, np.ndarray, GreyBox, Any]:
        """The parameter table, the covariance of the free parameters, the structure at the
        estimate and its model (``make(structure, values, info)``, with ``uncertainty``)
        from the core's result ``res`` (``p``, ``covariance``, ``active_bounds``,
        ``unidentifiable``, ``rank``)."""
        s, nf = self.s, self.nf
        z = np.asarray(res["p"])
        vals = self.values(z)
        S = np.diag(self.scale)
        cov = S @ np.asarray(res["covariance"])[:nf, :nf] @ S
        std = dict(zip(self.free, np.sqrt(np.clip(np.diag(cov), 0, None))))
        active = {int(i) for i in res["active_bounds"] if i < nf}
        bound = []
        for k in s.names:
            i = self.free.index(k) if k in self.free else -1
            if i in active:
                bound.append("lower" if z[i] <= self.lower[i] else "upper")
            else:
                bound.append("")
        full_scale = np.concatenate([self.scale, np.ones(z.size - nf)])
        weak = _warn_unidentifiable(np.asarray(res["unidentifiable"]), self.names, full_scale,
                                    z * full_scale)
        for i in weak:  # a direction the data do not determine: no finite std
            if i < nf:
                std[self.free[i]] = float("inf")
        table = ParameterTable(
            s.names, [vals[k] for k in s.names], [std.get(k, 0.0) for k in s.names],
            [s.params[k].fixed for k in s.names], bound,
            [s.params[k].unit for k in s.names], [s.params[k].description for k in s.names]
        ).cut_at_bounds(*np.array([s.params[k].bounds for k in s.names], float).T)
        est = s.with_values(vals)

        def build(theta_free: np.ndarray) -> Any:
            v = dict(vals)
            v.update(zip(self.free, np.asarray(theta_free, dtype=float)))
            return make(est, v, None)

        info["greybox"] = {"parameters": table.rows()}
        model = make(est, vals, info)
        model.uncertainty = ParameterUncertainty(
            [vals[k] for k in self.free], cov, build, names=list(self.free),
            dof=min(int(res["rank"]), nf), method="gauss-newton",
            undetermined=[i for i in weak if i < nf])
        return table, cov, est, model


def model_of(s: GreyBox, vals: dict[str, float], dt: float, K: Any, names: dict[str, Any],
             lam: Any, info: dict[str, Any] | None) -> Any:
    """The estimated model: continuous-time when the structure is (no noise model, no input
    delay), else the sampled one with the delays as shift-register states."""
    from ..models.continuous import ContinuousStateSpace
    from ..models.statespace import StateSpaceModel

    delayed = bool(np.any(s.input_delay > 0))
    if s.continuous and K is None and not delayed:
        m = s.matrices(vals, dt)
        out: Any = ContinuousStateSpace(m["A"], m["B"], m["C"], m["D"], hold=s.hold,
                                        info=info, **names)
        return out
    mats = dict(s.sampled_taps(vals, dt)[0])
    mats["K"] = K
    A, B, C, D, Ka = tap_states(mats, s.input_taps(dt), s.ninputs)
    return StateSpaceModel(A, B, C, D, Ka, dt=dt, noise_cov=lam, info=info, **names)
