"""Grey-box estimation: :func:`greyest` (MATLAB's ``greyest`` and ``nlgreyest``).

A linear structure (:class:`sysid.GreyBox`) is fitted by the prediction-error method of
:func:`sysid.pem`: the Rust predictor accumulates, over the samples, the Gauss-Newton matrix
in the entries of the sampled ``(A, B, C, D, K, x0)``, and the one optimiser of the core
(``sysid_core::optim``) searches the physical parameters through the chain rule
``J_p = J_theta dtheta/dp``, with ``dtheta/dp`` formed here once per iteration (central
differences of the structure function, Fréchet derivative of the matrix exponential). A
nonlinear structure (:class:`sysid.NonlinearGreyBox`) is integrated in the Rust core with all
finite-difference perturbations at once. Both report the parameters with standard deviations
from the same Gauss-Newton covariance (the inverse-covariance-weighted criterion, maximum
likelihood for Gaussian errors).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_int
from .._progress import iteration_printer
from ..data.iodata import IOData
from ..errors import DataError, SysidError
from ..models.paramtable import ParameterTable
from ..models.uncertainty import ParameterUncertainty
from ..pem.pem import _experiments
from .delays import shift_taps, tap_states
from .greybox import GreyBox
from .results import GreyEstimate, _costs, _criterion, _warn_unidentifiable

__all__ = ["greyest", "GreyEstimate"]

_FOCUS = ("prediction", "simulation")


def _progress(progress: Any, criterion: str) -> Any:
    if progress is True:
        return iteration_printer("greyest", criterion)
    if progress is False or progress is None:
        return None
    if callable(progress):
        return progress
    raise DataError(f"progress must be True, False or a callable, got {progress!r}")


def _x0_modes(x0: Any, count: int, n: int, has_model_x0: bool) -> list[Any]:
    if isinstance(x0, str):
        if x0 not in ("estimate", "zero", "model"):
            raise DataError(f"x0 must be 'estimate', 'zero', 'model' or an array, got {x0!r}")
        if x0 == "model" and not has_model_x0:
            raise DataError("x0='model' needs a structure function that returns x0")
        return [x0] * count
    if isinstance(x0, (list, tuple)) and len(x0) == count and count > 1:
        return [m for it in x0 for m in _x0_modes(it, 1, n, has_model_x0)]
    arr = np.asarray(x0, dtype=float).ravel()
    if arr.size != n:
        raise DataError(f"x0 has {arr.size} entries but the structure has {n} states")
    return [arr] * count


def greyest(
    data: Any,
    structure: Any,
    *,
    focus: str = "prediction",
    x0: Any = None,
    noise: str = "model",
    weighting: str = "noise",
    multistart: int = 0,
    rng: Any = None,
    max_iter: int = 100,
    tol: float = 1e-10,
    progress: bool | Callable[..., Any] = False,
) -> GreyEstimate:
    """Estimate the free parameters of a grey-box structure by prediction-error minimisation.

    Parameters
    ----------
    data : IOData or (u, y)
        Estimation data; every experiment is used (with its own initial state).
    structure : GreyBox or NonlinearGreyBox
        The model structure with initial values, fixed parameters and bounds.
    focus : {"prediction", "simulation"}
        One-step prediction errors (with the structure's ``K``) or simulation errors (``K = 0``).
        A nonlinear structure always uses simulation errors.
    x0 : "estimate", "zero", "model", array, or a list per experiment
        Initial states: estimated, zero, the structure's own (a linear ``fn`` returning x0,
        possibly a function of the parameters; a nonlinear structure's ``x0`` and
        ``x0_free``), or given. Default: "estimate" for linear, "model" for nonlinear
        structures.
    noise : {"model", "none", "estimate"}
        ``K`` as the structure returns it (zero when it returns none), no ``K``, or every entry
        of ``K`` estimated freely (innovation gain of the sampled model). Prediction focus only.
    weighting : {"noise", "identity"}
        Weight the errors by the inverse of their covariance, re-estimated between iterations
        (maximum likelihood, default), or the plain sum of squares.
    multistart : int
        Extra searches from random initial values within the bounds (a fixed seed ``rng``);
        the lowest loss wins. Against local minima.
    rng : seed or numpy Generator, optional
    max_iter : int
    tol : float
        Relative cost decrease below which the search stops.
    progress : bool or callable
        ``True`` prints one line per iteration; a callable gets
        ``(iteration, cost, step_norm, gradient_norm, damping)`` and may return ``False``.

    Returns
    -------
    GreyEstimate
        ``.parameters`` (table with std and 95 % intervals), ``.correlation``, ``.model``
        (with ``uncertainty``), ``.info``. Warns with :class:`sysid.IdentifiabilityWarning`
        naming the parameters the data cannot determine separately.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> def motor(p, dt=None):
    ...     return [[-1 / p.tau]], [[p.K / p.tau]], [[1.0]], [[0.0]]
    >>> u = np.sign(np.sin(np.arange(400) * 0.05))
    >>> y = sysid.GreyBox(motor, {"K": 2.0, "tau": 0.3}).model(dt=0.05).simulate(u)
    >>> s = sysid.GreyBox(motor, params={"K": 1.0, "tau": sysid.param(1.0, bounds=(0.01, 10))})
    >>> fit = sysid.greyest(sysid.IOData(u=u, y=y, dt=0.05), s, x0="zero")
    >>> np.round(fit.parameters.value, 6)
    array([2. , 0.3])
    """
    from .nlgreybox import NonlinearGreyBox
    from .nlgreyest import nlgreyest

    data = _experiments(data)
    if focus not in _FOCUS:
        raise DataError(f"focus must be 'prediction' or 'simulation', got {focus!r}")
    if weighting not in ("noise", "identity"):
        raise DataError(f"weighting must be 'noise' or 'identity', got {weighting!r}")
    multistart = as_int(multistart, "multistart", 0)
    max_iter = as_int(max_iter, "max_iter", 0)
    cb = _progress(progress, _criterion(weighting))
    if isinstance(structure, NonlinearGreyBox):
        return nlgreyest(data, structure, x0=x0, weighting=weighting, multistart=multistart,
                         rng=rng, max_iter=max_iter, tol=float(tol), progress=cb)
    if not isinstance(structure, GreyBox):
        raise DataError("structure must be a sysid.GreyBox or sysid.NonlinearGreyBox, got "
                        f"{type(structure).__name__}")
    if noise not in ("model", "none", "estimate"):
        raise DataError(f"noise must be 'model', 'none' or 'estimate', got {noise!r}")
    if (data.n_inputs, data.n_outputs) != (structure.ninputs, structure.noutputs):
        raise DataError(f"the structure has {structure.ninputs} input(s) and "
                        f"{structure.noutputs} output(s), the data {data.n_inputs} and "
                        f"{data.n_outputs}")
    dt = float(data.dt)
    if structure.dt is not None and not structure.continuous and \
            abs(structure.dt - dt) > 1e-9 * dt:
        raise DataError(f"the structure's dt={structure.dt} differs from the data's dt={dt}: "
                        "resample the data or give the structure the data's sample time")
    fit = _LinearFit(data, structure, dt, focus, "estimate" if x0 is None else x0, noise,
                     weighting == "noise")
    best = fit.run(fit.z0, max_iter, float(tol), cb)
    starts: list[float | None] = []
    if multistart:
        gen = np.random.default_rng(rng)
        for _ in range(multistart):
            try:
                r = fit.run(fit.random_start(gen), max_iter, float(tol), None)
            except SysidError:
                starts.append(None)
                continue
            starts.append(r["loss"])
            if r["loss"] < best["loss"]:
                best = r
    return fit.result(best, starts)


class _LinearFit:
    """The bookkeeping of one linear grey-box estimation (outer vector z, map to theta)."""

    def __init__(self, data: IOData, s: GreyBox, dt: float, focus: str, x0: Any, noise: str,
                 reweight: bool) -> None:
        self.data, self.s, self.dt, self.focus, self.reweight = data, s, dt, focus, reweight
        self.taps = s.input_taps(dt)
        base = s.sampled_taps(None, dt)[0]
        self.n, self.m = base["B"].shape  # m: one input column per tap (delayed input)
        self.l = base["C"].shape[0]
        n, l = self.n, self.l
        self.free = s.free_names
        self.scale = np.array([s.params[k].typical for k in self.free])
        self.exps = [(shift_taps(np.asarray(u, dtype=float), self.taps),
                      np.ascontiguousarray(y))
                     for u, y in data.experiments]
        self.noise = noise if focus == "prediction" else "none"
        self.k_model = self.noise == "model" and base["K"] is not None
        self.k_free = self.noise == "estimate"
        self.with_k = self.k_model or self.k_free
        self.modes = _x0_modes(x0, len(self.exps), n, base["x0"] is not None)
        nf = len(self.free)
        z0 = [s.params[k].value / sc for k, sc in zip(self.free, self.scale)]
        lo = [s.params[k].bounds[0] / sc for k, sc in zip(self.free, self.scale)]
        hi = [s.params[k].bounds[1] / sc for k, sc in zip(self.free, self.scale)]
        self.names = list(self.free)
        if self.k_free:
            k0 = base["K"] if base["K"] is not None else np.zeros((n, l))
            z0 += list(k0.ravel())
            self.names += [f"K[{i},{j}]" for i in range(n) for j in range(l)]
        self.x0_params: list[int] = []
        for e, mode in enumerate(self.modes):
            if isinstance(mode, str) and mode == "estimate":
                self.x0_params += list(range(len(z0), len(z0) + n))
                self.names += [f"x0[{e}][{i}]" for i in range(n)]
                z0 += [0.0] * n
        extra = len(z0) - nf
        self.lower = np.array(lo + [-np.inf] * extra)
        self.upper = np.array(hi + [np.inf] * extra)
        self.z0 = np.array(z0, dtype=float)
        self.nf = nf

    def values(self, z: np.ndarray) -> dict[str, float]:
        vals = {k: v.value for k, v in self.s.params.items()}
        for k, zi, sc in zip(self.free, z[:self.nf], self.scale):
            vals[k] = float(zi * sc)
        return vals

    def theta(self, z: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
        n, l, nf = self.n, self.l, self.nf
        vals = self.values(z)
        base, ders = self.s.sampled_taps(vals, self.dt, self.free if jac else None)

        def pack(mats: dict[str, Any], xs: list[np.ndarray], with_k: Any) -> list[np.ndarray]:
            parts = [mats["A"].ravel(), mats["B"].ravel(), mats["C"].ravel(), mats["D"].ravel()]
            if self.with_k:
                parts.append(with_k)
            return parts + xs

        o = nf + (n * l if self.k_free else 0)
        k_now = (z[nf:o] if self.k_free else
                 (base["K"].ravel() if self.k_model else np.zeros(0)))
        xs = []
        for mode in self.modes:
            if isinstance(mode, str) and mode == "estimate":
                xs.append(z[o:o + n])
                o += n
            elif isinstance(mode, str) and mode == "model":
                xs.append(np.asarray(base["x0"]).ravel())
            elif isinstance(mode, str):
                xs.append(np.zeros(n))
            else:
                xs.append(mode)
        th = np.concatenate(pack(base, xs, k_now))
        if not jac:
            return th, None
        M = np.zeros((th.size, z.size))
        for j, d in enumerate(ders):
            dk = d["K"].ravel() if (self.k_model and d["K"] is not None) else \
                np.zeros(n * l if self.with_k else 0)
            dx = [np.asarray(d["x0"]).ravel() if (isinstance(md, str) and md == "model"
                                                   and d["x0"] is not None) else np.zeros(n)
                  for md in self.modes]
            M[:, j] = np.concatenate(pack(d, dx, dk)) * self.scale[j]
        # the freely estimated K entries and initial states enter theta directly
        off_k = n * n + n * self.m + l * n + l * self.m
        if self.k_free:
            M[off_k:off_k + n * l, nf:nf + n * l] = np.eye(n * l)
        o = nf + (n * l if self.k_free else 0)
        row = off_k + (n * l if self.with_k else 0)
        for mode in self.modes:
            if isinstance(mode, str) and mode == "estimate":
                M[row:row + n, o:o + n] = np.eye(n)
                o += n
            row += n
        return th, M

    def random_start(self, gen: np.random.Generator) -> np.ndarray:
        z = self.z0.copy()
        for i in range(self.nf):
            lo, hi = self.lower[i], self.upper[i]
            a = lo if np.isfinite(lo) else z[i] - 2.0 * max(1.0, abs(z[i]))
            b = hi if np.isfinite(hi) else z[i] + 2.0 * max(1.0, abs(z[i]))
            z[i] = gen.uniform(max(a, lo), min(b, hi))
        return z

    def run(self, z0: np.ndarray, max_iter: int, tol: float, cb: Any) -> dict[str, Any]:
        res = _sysid.greybox_linear(
            (self.n, self.m, self.l), self.exps, lambda z, jac: self.theta(z, jac),
            list(map(float, z0)), focus=self.focus, with_k=self.with_k,
            reweight=self.reweight, x0_params=self.x0_params,
            search={"lower": list(self.lower), "upper": list(self.upper), "max_iter": max_iter,
                    "tol_cost": tol}, progress=cb)
        res["loss"] = float(np.linalg.det(res["innovation_covariance"]))
        res["start"] = z0
        return res

    def result(self, res: dict[str, Any], starts: list[float | None]) -> GreyEstimate:
        s, nf, n = self.s, self.nf, self.n
        z = np.asarray(res["p"])
        vals = self.values(z)
        S = np.diag(self.scale)
        cov_z = np.asarray(res["covariance"])
        cov = S @ cov_z[:nf, :nf] @ S
        std = dict(zip(self.free, np.sqrt(np.clip(np.diag(cov), 0, None))))
        active = {int(i) for i in res["active_bounds"] if i < nf}
        bound = []
        for k in s.names:
            i = self.free.index(k) if k in self.free else -1
            if i in active:
                bound.append("lower" if z[i] <= self.lower[i] else "upper")
            else:
                bound.append("")
        table = ParameterTable(
            s.names, [vals[k] for k in s.names], [std.get(k, 0.0) for k in s.names],
            [s.params[k].fixed for k in s.names], bound,
            [s.params[k].unit for k in s.names], [s.params[k].description for k in s.names])
        _warn_unidentifiable(np.asarray(res["unidentifiable"]), self.names,
                             np.concatenate([self.scale, np.ones(z.size - nf)]))
        est = s.with_values(vals)
        th = np.asarray(res["theta"])
        off = n * n + n * self.m + self.l * n + self.l * self.m
        K = th[off:off + n * self.l].reshape(n, self.l) if self.with_k else None
        row = off + (n * self.l if self.with_k else 0)
        x0s = [th[row + e * n: row + (e + 1) * n] for e in range(len(self.exps))]
        lam = np.asarray(res["innovation_covariance"])
        d = self.data
        delayed = bool(np.any(s.input_delay > 0))

        def build(theta_free: np.ndarray) -> Any:
            v = dict(vals)
            v.update(zip(self.free, np.asarray(theta_free, dtype=float)))
            return _model(est, v, self.dt, K, delayed, d, lam, None)

        info = {
            "method": "greyest", "iterations": res["iterations"],
            "evaluations": res["evaluations"], **_costs(res, self.reweight),
            "stop": res["stop"],
            "condition": res["condition"], "rank": int(res["rank"]), "n_free": int(z.size),
            "n_samples": int(res["n_samples"]), "focus": self.focus, "noise": self.noise,
            "x0_values": x0s, "multistart": starts, "loss": res["loss"],
            "greybox": {"parameters": table.rows()},
        }
        model = _model(est, vals, self.dt, K, delayed, d, lam, info)
        if len(x0s) == 1 and not delayed and hasattr(model, "K"):
            model.x0 = x0s[0]
        model.uncertainty = ParameterUncertainty(
            [vals[k] for k in self.free], cov, build, names=list(self.free),
            dof=min(int(res["rank"]), nf), method="gauss-newton")
        return GreyEstimate(table, cov, list(self.free), model, est, x0s, info)


def _model(s: GreyBox, vals: dict[str, float], dt: float, K: Any, delayed: bool,
           data: IOData, lam: np.ndarray, info: dict[str, Any] | None) -> Any:
    from ..models.continuous import ContinuousStateSpace
    from ..models.statespace import StateSpaceModel

    names = {"input_names": data.input_names, "output_names": data.output_names}
    if s.continuous and K is None and not delayed:
        m = s.matrices(vals, dt)
        out: Any = ContinuousStateSpace(m["A"], m["B"], m["C"], m["D"], hold=s.hold,
                                        info=info, **names)
        return out
    mats = dict(s.sampled_taps(vals, dt)[0])
    mats["K"] = K
    A, B, C, D, Ka = tap_states(mats, s.input_taps(dt), s.ninputs)
    return StateSpaceModel(A, B, C, D, Ka, dt=dt, noise_cov=lam, info=info, **names)
