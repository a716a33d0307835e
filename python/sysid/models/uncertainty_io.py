"""Saving a model's parameter uncertainty with it.

A :class:`~sysid.models.uncertainty.ParameterUncertainty` holds ``build(theta)``, a function
of the estimator that cannot be written to a file. What is written is what the
uncertainty is used for: the parameters, their covariance, and how the model's stored
numbers move with them, ``d(stored numbers) / d theta`` by central differences of
``build``. Loading rebuilds ``build`` as the affine map ``numbers(theta) = numbers(theta0)
+ J (theta - theta0)``, which is ``build`` itself when the stored numbers are linear in the
parameters (free entries of ``A, B, C, D, K``, polynomial and transfer-function
coefficients, delays) and its first-order expansion otherwise (a grey-box model's physical
parameters): first-order standard deviations are the same either way; a Monte Carlo
propagation of a nonlinear parameterisation then samples the expansion, and the restored
uncertainty's ``method`` says so.

Examples
--------
>>> import numpy as np, sysid
>>> rng = np.random.default_rng(0)
>>> u = rng.standard_normal((300, 1))
>>> y = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]]).simulate(u)
>>> m = sysid.arx(sysid.IOData(u, y + 0.1 * rng.standard_normal((300, 1))), 1, 1)
>>> back = sysid.model_from_dict(sysid.model_to_dict(m))
>>> bool(np.allclose(back.poles(std=True)[1], m.poles(std=True)[1]))
True
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from .uncertainty import ParameterUncertainty

__all__ = ["body_with_uncertainty", "model_from_body", "uncertainty_from_dict",
           "uncertainty_to_dict"]

#: parameters beyond which the map is not written (2 p model builds on saving)
MAX_PARAMETERS = 4000


def _leaves(body: Any, path: tuple[Any, ...] = ()) -> dict[tuple[Any, ...], np.ndarray]:
    """Every real numeric array or number of a ``to_dict()`` body, by its path."""
    out: dict[tuple[Any, ...], np.ndarray] = {}
    if isinstance(body, dict):
        for k, v in body.items():
            if k != "info":
                out.update(_leaves(v, (*path, k)))
    elif isinstance(body, (list, tuple)):
        for i, v in enumerate(body):
            out.update(_leaves(v, (*path, i)))
    elif isinstance(body, np.ndarray) and body.dtype.kind == "f":
        out[path] = body
    elif isinstance(body, float):
        out[path] = np.asarray(body)
    return out


def uncertainty_to_dict(model: Any) -> dict[str, Any] | None:
    """The saved form of ``model.uncertainty`` (``None`` without one), or a dict
    ``{"omitted": reason}`` when it cannot be written."""
    unc = getattr(model, "uncertainty", None)
    if not isinstance(unc, ParameterUncertainty):
        return None
    p = unc.n_parameters
    if isinstance(getattr(type(model), "uncertainty", None), property):
        return None  # a wrapper (offsets, trend): its inner model carries the uncertainty
    nominal = unc.build(unc.theta)
    other = None  # the family build() makes, when not the model's own (a discrete TF's
    if type(nominal) is not type(model):  # build makes PolynomialModels): saved whole
        if not callable(getattr(nominal, "to_dict", None)):
            return {"omitted": f"build() makes a {type(nominal).__name__}, which cannot be "
                               "saved"}
        other = {"family": type(nominal).__name__, "body": nominal.to_dict()}
    if p > MAX_PARAMETERS:
        return {"omitted": f"{p} parameters (more than {MAX_PARAMETERS})"}
    base = _leaves(nominal.to_dict())
    scale = max(1.0, float(np.max(np.abs(unc.theta)))) if p else 1.0
    rows, cols, vals, linear = [], [], [], True
    keys = list(base)
    offsets = np.cumsum([0] + [base[k].size for k in keys])
    for i in range(p):
        h = 1e-6 * max(abs(float(unc.theta[i])), 1e-3 * scale)
        e = np.zeros(p)
        e[i] = h
        plus, minus = (_leaves(unc.build(unc.theta + s * e).to_dict()) for s in (1, -1))
        for n, k in enumerate(keys):
            if k not in plus or k not in minus or plus[k].shape != base[k].shape \
                    or minus[k].shape != base[k].shape:
                return {"omitted": f"the model's stored numbers change shape with parameter "
                                   f"{unc.names[i]}"}
            d = (plus[k] - minus[k]).ravel() / (2 * h)
            curv = (plus[k] + minus[k] - 2 * base[k]).ravel()
            if np.any(np.abs(curv) > 1e-9 * (1.0 + np.abs(base[k].ravel()))):
                linear = False
            nz = np.flatnonzero(d)
            rows.extend(offsets[n] + nz)
            cols.extend([i] * nz.size)
            vals.extend(d[nz])
    return {"theta": unc.theta, "covariance": unc.covariance, "names": list(unc.names),
            "dof": int(unc.dof), "method": unc.method, "linear": linear,
            **({} if other is None else {"built": other}),
            "paths": [list(k) for k in keys],
            "map": {"rows": np.asarray(rows, dtype=float), "cols": np.asarray(cols, dtype=float),
                    "values": np.asarray(vals, dtype=float)}}


def _set(body: Any, path: list[Any], value: Any) -> None:
    for k in path[:-1]:
        body = body[k]
    body[path[-1]] = value


def uncertainty_from_dict(saved: dict[str, Any], body: dict[str, Any], cls: type,
                          registry: dict[str, type] | None = None
                          ) -> ParameterUncertainty | None:
    """The :class:`ParameterUncertainty` written by :func:`uncertainty_to_dict`, its
    ``build`` the affine map on the model's stored numbers (``body``: the loaded
    ``to_dict()`` content; ``cls.from_dict`` makes the model)."""
    if "omitted" in saved:
        return None
    built = saved.get("built")
    if isinstance(built, dict):  # build() makes another family than the model's
        found = (registry or {}).get(built["family"])  # the loader's registered families
        if found is None:
            return None
        cls, body = found, built["body"]
    theta = np.asarray(saved["theta"], dtype=float).ravel()
    paths = [list(p) for p in saved["paths"]]
    leaves = _leaves(body)
    base = [np.asarray(leaves[tuple(p)], dtype=float) for p in paths]
    offsets = np.cumsum([0] + [b.size for b in base])
    mp = saved["map"]
    rows = np.asarray(mp["rows"], dtype=int)
    cols = np.asarray(mp["cols"], dtype=int)
    vals = np.asarray(mp["values"], dtype=float)
    flat0 = np.concatenate([b.ravel() for b in base]) if base else np.zeros(0)

    def build(t: Any) -> Any:
        dt = np.asarray(t, dtype=float).ravel() - theta
        flat = flat0.copy()
        np.add.at(flat, rows, vals * dt[cols])
        new = copy.deepcopy(body)
        for n, (p, b) in enumerate(zip(paths, base)):
            v = flat[offsets[n]:offsets[n + 1]].reshape(b.shape)
            _set(new, p, float(v) if b.ndim == 0 and not isinstance(
                _get(body, p), np.ndarray) else v)
        return cls.from_dict(new)  # type: ignore[attr-defined]

    method = str(saved.get("method", "gauss-newton"))
    if not saved.get("linear", True):
        method += " (restored: first-order map of a nonlinear parameterisation)"
    return ParameterUncertainty(theta, saved["covariance"], build, names=saved.get("names"),
                                dof=saved.get("dof"), method=method)


def _get(body: Any, path: list[Any]) -> Any:
    for k in path:
        body = body[k]
    return body


def body_with_uncertainty(model: Any) -> dict[str, Any]:
    """``model.to_dict()`` with its saved uncertainty under ``"uncertainty"`` (for a model
    class that stores another model inside its own ``to_dict``)."""
    body = model.to_dict()
    saved = None if "uncertainty" in body else uncertainty_to_dict(model)
    return body if saved is None else {**body, "uncertainty": saved}


def model_from_body(cls: type, body: dict[str, Any],
                    registry: dict[str, type] | None = None) -> Any:
    """Inverse of :func:`body_with_uncertainty`: ``cls.from_dict`` and the uncertainty
    (``registry``: the model families by name, for an uncertainty whose ``build`` makes
    another family than the model's)."""
    body = dict(body)
    own = body.get("uncertainty")  # a class may store its uncertainty itself: left to it
    ours = isinstance(own, dict) and ("map" in own or "omitted" in own)
    saved = body.pop("uncertainty") if ours else None
    model = cls.from_dict(body)  # type: ignore[attr-defined]
    unc = uncertainty_from_dict(saved, body, cls, registry) if saved is not None else None
    if unc is not None:
        model.uncertainty = unc
    return model
