"""Training of the network nonlinearities of ``nlarx``: sigmoid networks, wavelet networks
(separable least squares on the shared optimiser, in Rust) and tree partitions (greedy
growth with exact affine leaves, in Rust); focus on prediction or on simulation.

The unit parameters start from the data: a sigmoid's hyperplane passes through a random
estimation sample with a random direction of unit-order slope in standardised units; a
wavelet sits on a random sample with the dilation of the spread of the samples around it.
For every value of the unit parameters the linear term, offset and output weights are
solved exactly (variable projection), so only the unit parameters are searched.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import user_stacklevel, warn_iteration_limit
from .._progress import iteration_callback, iteration_printer
from ..errors import (
    DataError,
    InsufficientDataError,
    NumericalError,
    StabilityWarning,
)
from ..validation.runner import given_start
from .hw_model import SigmoidNetwork
from .narx_model import lag_names
from .narx_network_model import NetworkNARXModel, from_rust_nl

__all__ = ["WaveletNetwork", "TreePartition", "is_network", "nlarx_network"]

FOCUS = ("prediction", "simulation")

#: Largest number of searched parameters per output (the Gauss-Newton matrix is p x p).
MAX_PARAMETERS = 4000


class WaveletNetwork:
    """Wavelet network nonlinearity for :func:`sysid.nlarx` (MATLAB's ``idWaveletNetwork``):
    a linear term plus radial wavelets ``(nz - r^2) exp(-r^2 / 2)`` and Gaussian scaling
    functions ``exp(-r^2 / 2)``, ``r = dilation * |z - centre|`` on the standardised
    regressors ``z``.

    Parameters
    ----------
    units : int
        Number of wavelets.
    scaling_units : int
        Number of scaling functions (coarse Gaussian bumps) besides the wavelets.
    seed : int
        Seed of the random initial placement.

    Examples
    --------
    >>> import sysid
    >>> sysid.WaveletNetwork(8)
    WaveletNetwork(units=8, scaling_units=0)
    """

    def __init__(self, units: int = 10, scaling_units: int = 0, seed: int = 0) -> None:
        if int(units) != units or units < 0 or int(scaling_units) != scaling_units \
                or scaling_units < 0 or units + scaling_units < 1:
            raise DataError(f"units and scaling_units must be non-negative integers, at least "
                            f"one unit in all, got {units!r}, {scaling_units!r}")
        self.units, self.scaling_units, self.seed = int(units), int(scaling_units), int(seed)

    def kinds(self) -> list[str]:
        """The unit kinds, in order."""
        return ["scaling"] * self.scaling_units + ["wavelet"] * self.units

    def __repr__(self) -> str:
        return f"WaveletNetwork(units={self.units}, scaling_units={self.scaling_units})"


class TreePartition:
    """Tree partition nonlinearity for :func:`sysid.nlarx` (MATLAB's ``idTreePartition``): a
    piecewise-affine function on a binary partition of the regressor space, each cell split
    on one regressor, grown while the Bayesian information criterion falls.

    Parameters
    ----------
    max_leaves : int
        Largest number of cells (leaves).
    min_leaf : int, optional
        Fewest samples in a cell (default ``max(10, 3 (nz + 1))``).

    Examples
    --------
    >>> import sysid
    >>> sysid.TreePartition(8)
    TreePartition(max_leaves=8)
    """

    def __init__(self, max_leaves: int = 16, min_leaf: int | None = None) -> None:
        if int(max_leaves) != max_leaves or max_leaves < 1:
            raise DataError(f"max_leaves must be a positive integer, got {max_leaves!r}")
        if min_leaf is not None and (int(min_leaf) != min_leaf or min_leaf < 1):
            raise DataError(f"min_leaf must be a positive integer or None, got {min_leaf!r}")
        self.max_leaves, self.min_leaf = int(max_leaves), min_leaf

    def __repr__(self) -> str:
        return f"TreePartition(max_leaves={self.max_leaves})"


def is_network(basis: Any) -> bool:
    """Whether ``basis`` is a network nonlinearity (or a network model to refine), not a
    FROLS candidate basis."""
    return isinstance(basis, (SigmoidNetwork, WaveletNetwork, TreePartition, NetworkNARXModel))


def _kinds(basis: Any) -> list[str]:
    if isinstance(basis, SigmoidNetwork):
        return ["sigmoid"] * basis.units
    return list(basis.kinds())


def _start(model: NetworkNARXModel, na: list[int], nb: list[int], nk: list[int]
           ) -> tuple[list[str], list[np.ndarray]]:
    """Unit kinds and per-output unit parameters of a network model to refine."""
    if (model.na, model.nb, model.nk) != (na, nb, nk):
        raise DataError(f"the initial model has orders na={model.na}, nb={model.nb}, "
                        f"nk={model.nk} but nlarx was given na={na}, nb={nb}, nk={nk}")
    nls = model.nonlinearities
    if any(d["type"] != "network" for d in nls) or len({tuple(d["kinds"]) for d in nls}) != 1:
        raise DataError("only a sigmoid or wavelet network model (the same units for every "
                        "output) can be refined; grow a tree with sysid.TreePartition(...)")
    return list(nls[0]["kinds"]), [np.asarray(d["theta"], float).ravel() for d in nls]


def _initial(kinds: list[str], z: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Unit parameters ``(n_units, nz + 1)`` placed on the standardised samples ``z``."""
    n, nz = z.shape
    theta = np.zeros((len(kinds), nz + 1))
    rows = z[rng.choice(n, size=len(kinds), replace=len(kinds) > n)]
    for k, (kind, c) in enumerate(zip(kinds, rows)):
        if kind == "sigmoid":
            w = rng.standard_normal(nz)
            w *= rng.uniform(0.5, 2.0) / max(float(np.linalg.norm(w)), 1e-12)
            theta[k] = [*w, -float(w @ c)]
        else:
            spread = float(np.sqrt(nz)) * (2.0 if kind == "scaling" else 1.0)
            theta[k] = [1.0 / spread * rng.uniform(0.7, 1.5), *c]
    return theta


#: Bounds of the unit parameters in standardised units: a sigmoid's slopes and bias within
#: +-BOUND (sharper than a step over 1/BOUND of a standard deviation is not asked for), a
#: wavelet's dilation within [1/BOUND, BOUND] and its centre within +-10 standard deviations.
#: Without them a unit that saturates over the data drifts to huge parameters (its gradient
#: vanishes, so the scaled step does not).
BOUND = 25.0


def _unit_bounds(kinds: list[str], nz: int) -> tuple[np.ndarray, np.ndarray]:
    lo, hi = np.empty((len(kinds), nz + 1)), np.empty((len(kinds), nz + 1))
    for k, kind in enumerate(kinds):
        if kind == "sigmoid":
            lo[k], hi[k] = -BOUND, BOUND
        else:
            lo[k], hi[k] = -10.0, 10.0
            lo[k, 0], hi[k, 0] = 1.0 / BOUND, BOUND
    return lo.ravel(), hi.ravel()


def _standardise(lags: np.ndarray, names: list[str]) -> tuple[np.ndarray, np.ndarray]:
    shift = lags.mean(axis=0)
    scale = lags.std(axis=0)
    flat = scale <= 1e-12 * np.maximum(np.abs(shift), 1.0)
    if np.any(flat):
        bad = ", ".join(n for n, f in zip(names, flat) if f)
        raise DataError(f"the regressor(s) {bad} are constant over the estimation data: a "
                        "network cannot be fitted on them; drop that channel or lower nb/na")
    return shift, scale


def nlarx_network(exps: list[tuple[np.ndarray, np.ndarray]], na: list[int], nb: list[int],
                  nk: list[int], lags: np.ndarray, basis: Any, *, dt: float,
                  names: dict[str, Any], focus: str, max_iter: int, tol: float,
                  progress: Any) -> NetworkNARXModel:
    """:func:`sysid.nlarx` with a network nonlinearity (``lags``: the lagged variables of
    every estimation row, ``(n_rows, nz)``)."""
    if focus not in FOCUS:
        raise DataError(f"focus must be one of {FOCUS}, got {focus!r}")
    if int(max_iter) != max_iter or max_iter < 0:
        raise DataError(f"max_iter must be a non-negative integer, got {max_iter!r}")
    ny, nu = len(na), len(nb)
    outs = names["output_names"] or [f"y{i}" for i in range(ny)]
    ins = names["input_names"] or [f"u{j}" for j in range(nu)]
    starts, kinds0 = None, None
    if isinstance(basis, NetworkNARXModel):  # refine: its standardisation and parameters
        kinds0, starts = _start(basis, na, nb, nk)
        shift, scale = basis.shift, basis.scale
        basis = (SigmoidNetwork(len(kinds0)) if set(kinds0) == {"sigmoid"}
                 else WaveletNetwork(kinds0.count("wavelet"), kinds0.count("scaling")))
    else:
        shift, scale = _standardise(lags, lag_names(na, nb, nk, [0] * ny, list(ins),
                                                    list(outs)))
    n_rows, nz = lags.shape
    struct = {"orders": (na, nb, nk), "shift": shift.tolist(), "scale": scale.tolist()}
    recs = [(np.ascontiguousarray(u, float), np.ascontiguousarray(y, float)) for u, y in exps]
    info: dict[str, Any] = {"method": "nlarx", "focus": focus, "n_rows": int(n_rows)}
    if isinstance(basis, TreePartition):
        name = "treepartition"
        if n_rows < 2 * (nz + 1):
            raise InsufficientDataError(f"a tree partition on {nz} regressors needs at least "
                                        f"{2 * (nz + 1)} rows, got {n_rows}; use a longer record")
        nls, trees = [], []
        for i in range(ny):
            t, rep = _sysid.narx_tree_fit(recs, struct, i, basis.max_leaves,
                                          int(basis.min_leaf or 0))
            nls.append(from_rust_nl(t, nz))
            trees.append({"rss": list(rep["rss"]), "stop": rep["stop"]})
        info["tree"] = trees
        var = [tr["rss"][-1] / n_rows for tr in trees]
    else:
        name = "sigmoidnet" if isinstance(basis, SigmoidNetwork) else "wavenet"
        kinds = _kinds(basis) if kinds0 is None else kinds0
        p, q = len(kinds) * (nz + 1), 1 + nz + len(kinds)
        if p > MAX_PARAMETERS:
            raise DataError(f"{len(kinds)} units on {nz} regressors are {p} parameters per "
                            f"output, more than {MAX_PARAMETERS}; use fewer units or lags")
        if n_rows < p + q:
            raise InsufficientDataError(f"{len(kinds)} units on {nz} regressors have {p + q} "
                                        f"parameters per output but the data give {n_rows} "
                                        "rows; use fewer units or a longer record")
        rng = np.random.default_rng(getattr(basis, "seed", 0))
        z = (lags - shift) / scale
        codes = [{"sigmoid": 0, "wavelet": 1, "scaling": 2}[k] for k in kinds]
        nls, searches = [], []
        for i in range(ny):
            th0 = _initial(kinds, z, rng).ravel() if starts is None else starts[i]
            lo, hi = _unit_bounds(kinds, nz)
            th0 = np.clip(th0, lo, hi)
            cb, close = iteration_callback(progress, f"nlarx {name} ({outs[i]})", max_iter,
                                           iteration_printer("nlarx", "sum of squares / 2"))
            try:
                t, rep = _sysid.narx_network_fit(recs, struct, i, codes, th0.tolist(),
                                                 max_iter=int(max_iter),
                                                 tol=float(tol), progress=cb,
                                                 bounds=(lo.tolist(), hi.tolist()))
            finally:
                close()
            nls.append(from_rust_nl(t, nz))
            searches.append(_report(rep))
            _warn(rep, f"the {name} search of output {outs[i]}", max_iter)
        info["search"] = searches
        var = [2 * s["cost"] / n_rows for s in searches]
    model = NetworkNARXModel(na, nb, nk, nls, shift, scale, dt, name=name, noise_variance=var,
                             info=info, **names)
    if focus == "simulation":
        model = _refine(model, recs, max_iter, tol, progress, info)
    model.info = info
    return model


def _report(rep: dict[str, Any]) -> dict[str, Any]:
    return {"iterations": int(rep["iterations"]), "evaluations": int(rep["evaluations"]),
            "cost": float(rep["cost"]), "history": [float(c) for c in rep["history"]],
            "stop": str(rep["stop"]),
            "remaining_decrease": float(rep["remaining_decrease"])}


def _warn(rep: dict[str, Any], what: str, max_iter: int) -> None:
    if rep["stop"] == "maximum iterations" and max_iter > 0:
        warn_iteration_limit(what, max_iter, rep["history"],
                             remaining=rep["remaining_decrease"])


def _refine(model: NetworkNARXModel, recs: list[tuple[np.ndarray, np.ndarray]], max_iter: int,
            tol: float, progress: Any, info: dict[str, Any]) -> NetworkNARXModel:
    """Every parameter refined for free-run simulation from the prediction fit."""
    nz = model.shift.size
    lo, hi = [], []
    for d in model.nonlinearities:
        if d["type"] == "network":
            ul, uh = _unit_bounds(list(d["kinds"]), nz)
            n_lin = np.asarray(d["linear"]).size
            lo += [*ul, *[-np.inf] * n_lin]
            hi += [*uh, *[np.inf] * n_lin]
        else:
            n = np.asarray(d["coefs"]).size
            lo += [-np.inf] * n
            hi += [np.inf] * n
    cb, close = iteration_callback(progress, f"nlarx {model.name} (simulation)", max_iter,
                                   iteration_printer("nlarx", "sum of squares / 2"))
    try:
        nls, rep = _sysid.narx_network_refine(recs, model._args(), max_iter=int(max_iter),
                                              tol=float(tol), progress=cb, bounds=(lo, hi))
    except NumericalError as e:
        warnings.warn(f"the simulation-focus refinement could not start: the prediction "
                      f"fit's free run diverges on the estimation data ({e}); the model is the "
                      "prediction fit: use fewer units or smaller lags", StabilityWarning,
                      stacklevel=user_stacklevel())
        info["refine"] = {"iterations": 0, "stop": "failed to start", "cost": float("nan")}
        return model
    finally:
        close()
    info["refine"] = _report(rep)
    _warn(rep, "the simulation-focus search", max_iter)
    n_rows = info["n_rows"]
    pooled = np.full(model.noutputs, 2 * rep["cost"] / (n_rows * model.noutputs))
    out = NetworkNARXModel(model.na, model.nb, model.nk, [from_rust_nl(t, nz) for t in nls],
                           model.shift, model.scale, model.dt, name=model.name,
                           noise_variance=pooled, input_names=model.input_names,
                           output_names=model.output_names)
    out.noise_variance = _free_run_variances(out, recs, pooled)
    return out


def _free_run_variances(model: NetworkNARXModel, recs: list[tuple[np.ndarray, np.ndarray]],
                        pooled: np.ndarray) -> np.ndarray:
    """Each output's mean squared free-run error (from the measured first outputs, as the
    refinement runs it), not their pool; ``pooled`` if the run fails. The samples scored are
    those :func:`~sysid.validation.runner.given_start` says the model predicts."""
    L, k = model.max_lag, given_start(model)
    sums, count = np.zeros(model.noutputs), 0
    try:
        for u, y in recs:
            e = (y - np.asarray(model.simulate(u, x0=y[:L])).reshape(y.shape))[k:]
            sums += np.sum(e ** 2, axis=0)
            count += e.shape[0]
    except NumericalError:
        return pooled
    return sums / count if count else pooled
