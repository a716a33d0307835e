"""Prediction-error estimation of a :class:`~sysid.pem.ssform.StateSpaceStructure` (MATLAB's
``ssest(data, init_sys)`` / ``pem(data, init_sys)`` with fixed entries or a canonical form).

The structure's free parameters are those of a discrete :class:`sysid.GreyBox` whose
matrices are affine in them (constant derivatives, given exactly), fitted by
:func:`sysid.greyest`: the shared search, its covariance and its identifiability check. A
structure with nothing fixed (``form="free"``) is refined by :func:`sysid.pem` instead, in
its identifiable local coordinates. The errors (one-step prediction errors, or simulation
errors with no ``K`` under ``focus="simulation"``) are weighted by the inverse of their
covariance (the determinant criterion: maximum likelihood for prediction errors, and for
several outputs a fit that does not depend on their units; for one output the plain sum of
squares).

Examples
--------
>>> import numpy as np, sysid
>>> true = sysid.StateSpaceModel([[0.8, 0.1], [0.0, 0.5]], [[1.0], [1.0]], [[1.0, 0.0]])
>>> u = np.random.default_rng(1).standard_normal(300)
>>> data = sysid.IOData(u=u, y=true.simulate(u))
>>> start = sysid.StateSpaceModel([[0.6, 0.0], [0.0, 0.3]], [[1.0], [1.0]], [[1.0, 0.0]])
>>> s = sysid.ssform(start, free={"A": [[True, True], [False, True]], "B": False, "C": False})
>>> m = sysid.ssest(data, s, x0="zero")
>>> np.round(m.A, 6).tolist(), m.info["structure"].n_free
([[0.8, 0.1], [0.0, 0.5]], 3)
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..errors import DataError
from ..models.checks import warn_unstable
from ..models.statespace import StateSpaceModel
from .records import _experiments
from .ssform import StateSpaceStructure

__all__ = ["pem_structured"]


def _all_free(s: StateSpaceStructure) -> bool:
    """Nothing fixed but what ``pem``'s own options fix (``D``, ``K`` wholly free or zero)."""
    f, m = s.free, s.model
    zero = {"D": not np.any(m.D), "K": m.K is None or not np.any(m.K)}
    return (s.form == "free" and all(f[k].all() for k in "ABC")
            and all(f[k].all() or (not f[k].any() and zero[k]) for k in ("D", "K")))


def pem_structured(data: Any, structure: StateSpaceStructure, *, focus: str = "prediction",
                   x0: Any = "estimate", max_iter: int = 50, tol: float = 1e-6,
                   progress: Any = None, caller: str = "pem", given: list[str] | None = None,
                   refine: Callable[..., StateSpaceModel] | None = None) -> StateSpaceModel:
    """Fit the free parameters of ``structure`` to ``data`` (module docstring); the model
    returned carries ``info["structure"]`` (the structure at the estimate) and
    ``info["greyest"]`` (iterations, cost, stop). ``given``: the caller's options set that
    a structure does not take (an error names them); ``refine``: :func:`sysid.pem`, for a
    structure with nothing fixed."""
    from ..greybox.greybox import GreyBox, param
    from ..greybox.greyest import greyest

    other = [k for k in (given or []) if k not in ("focus", "x0", "tol")]
    if other:
        raise DataError(f"{caller} estimates a structure's free parameters and takes focus, "
                        f"x0, max_iter, tol and progress only, got {', '.join(other)}: the "
                        "structure itself says which entries of D and K are free "
                        "(sysid.ssform(model, feedthrough=..., noise=..., free=...)); for "
                        "regularization use a sysid.GreyBox")
    data = _experiments(data)
    if not isinstance(focus, str) or focus not in ("prediction", "simulation"):
        raise DataError(f"focus must be 'prediction' or 'simulation', got {focus!r}")
    s, mdl = structure, structure.model
    if data.n_inputs != mdl.ninputs or data.n_outputs != mdl.noutputs:
        raise DataError(f"the structure has {mdl.ninputs} input(s) and {mdl.noutputs} "
                        f"output(s) but the data have {data.n_inputs} and {data.n_outputs}")
    if _all_free(s) and not s.bounds and refine is not None:
        f = s.free
        noise = "estimate" if f["K"].any() else "none"
        out = refine(data, mdl, focus=focus, feedthrough=bool(f["D"].any()), x0=x0,
                     noise=noise, max_iter=max_iter, tol=tol, progress=progress)
        out.info["structure"] = s.read(out)
        return out
    if focus == "simulation":  # no noise model: K's entries would be undetermined
        s = s.without_noise()
        if not s.n_free:
            raise DataError("with focus='simulation' the structure has no free parameter "
                            "outside K: free some entries of A, B, C or D")
    names, ders = s.names, s.derivatives()

    def fn(p: Any, dt: Any = None) -> tuple[np.ndarray, ...]:
        m = s.matrices([p[k] for k in names])
        return m["A"], m["B"], m["C"], m["D"], m["K"]

    def jac(p: Any, dt: Any = None) -> dict[str, tuple[np.ndarray, ...]]:
        return {k: (d["A"], d["B"], d["C"], d["D"], d["K"]) for k, d in zip(names, ders)}

    start = {k: (param(v, bounds=s.bounds[k]) if k in s.bounds else v)
             for k, v in zip(names, s.values)}
    gb = GreyBox(fn, start, continuous=False, dt=mdl.dt, jacobian=jac,
                 input_names=data.input_names, output_names=data.output_names)
    # greyest's x0 is "estimate" | "zero" | array (its "model" needs an x0 from fn)
    est = greyest(data, gb, focus=focus, x0=x0, noise="model", weighting="noise",
                  max_iter=max_iter, tol=tol, progress=False if progress is None else progress)
    model = est.model
    theta = np.array([est.parameters.value[est.parameters.names.index(k)] for k in names])
    model.info.update({"method": caller, "structure": s.with_values(theta, model),
                       "greyest": est.info, "parameters": est.parameters})
    warn_unstable(model, caller, advice=(
        "The structure's free entries allow unstable models; fix or bound them "
        "(structure.with_bounds(...)), or start from a stable model closer to the data."))
    return model
