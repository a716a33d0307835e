"""How a model's stored numbers move with its parameters: the affine map that stands for an
estimator's ``build(theta)`` where the function itself cannot travel (a saved file, a
pickle). ``stored_map`` measures ``d(stored numbers) / d theta`` by central differences of
``build``; ``affine_build`` turns the measured map back into a ``build``: the model whose
numbers are ``numbers(theta0) + J (theta - theta0)`` (``build`` itself when they are linear
in the parameters, its first-order expansion otherwise). No dependency on the uncertainty
class: :mod:`sysid.models.uncertainty` and :mod:`sysid.models.uncertainty_io` both use it.

Examples
--------
>>> import numpy as np, sysid
>>> from sysid.models.uncertainty import ParameterUncertainty
>>> build = lambda t: sysid.StateSpaceModel([[t[0]]], [[1.0]], [[1.0]])
>>> unc = ParameterUncertainty([0.5], [[1e-4]], build)
>>> saved = stored_map(unc, sysid.StateSpaceModel, 100)
>>> again = affine_build(saved, build([0.5]).to_dict(), sysid.StateSpaceModel, [0.5])
>>> round(float(again([0.7]).A[0, 0]), 9)
0.7
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

__all__ = ["MAX_PARAMETERS", "AffineBuild", "affine_build", "stored_map"]

#: parameters beyond which the map is not measured (2 p model builds)
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


def _set(body: Any, path: list[Any], value: Any) -> None:
    for k in path[:-1]:
        body = body[k]
    body[path[-1]] = value


def _get(body: Any, path: list[Any]) -> Any:
    for k in path:
        body = body[k]
    return body


def stored_map(unc: Any, cls: type, max_parameters: int = MAX_PARAMETERS) -> dict[str, Any]:
    """``{"linear", "paths", "map"[, "built"]}``: the map of the stored numbers of the
    model ``unc.build`` makes (``"built"``: that model's family and body when it is not
    ``cls``), or ``{"omitted": reason}``."""
    p = int(np.size(unc.theta))
    nominal = unc.build(unc.theta)
    other = None  # the family build() makes, when not the model's own (a discrete TF's
    if type(nominal) is not cls:  # build makes PolynomialModels): saved whole
        if not callable(getattr(nominal, "to_dict", None)):
            return {"omitted": f"build() makes a {type(nominal).__name__}, which cannot be "
                               "saved"}
        other = {"family": type(nominal).__name__, "body": nominal.to_dict()}
    if p > max_parameters:
        return {"omitted": f"{p} parameters (more than {max_parameters})"}
    base = _leaves(nominal.to_dict())
    scale = max(1.0, float(np.max(np.abs(unc.theta)))) if p else 1.0
    rows: list[int] = []
    cols: list[int] = []
    vals: list[float] = []
    linear = True
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
            # numbers the parameter does not move (an infinite bound among them) move by 0
            same = (plus[k] == base[k]) & (minus[k] == base[k])
            with np.errstate(invalid="ignore"):
                d = np.where(same, 0.0, plus[k] - minus[k]).ravel() / (2 * h)
                curv = np.where(same, 0.0, plus[k] + minus[k] - 2 * base[k]).ravel()
            if np.any(np.abs(curv) > 1e-9 * (1.0 + np.abs(base[k].ravel()))):
                linear = False
            nz = np.flatnonzero(d)
            rows.extend(offsets[n] + nz)
            cols.extend([i] * nz.size)
            vals.extend(d[nz])
    return {"linear": linear, **({} if other is None else {"built": other}),
            "paths": [list(k) for k in keys],
            "map": {"rows": np.asarray(rows, dtype=float), "cols": np.asarray(cols, dtype=float),
                    "values": np.asarray(vals, dtype=float)}}


class AffineBuild:
    """``build(theta)`` from a measured map: the model whose stored numbers are
    ``numbers(theta0) + J (theta - theta0)`` (a class, not a closure: it pickles)."""

    def __init__(self, theta: Any, saved: dict[str, Any], body: dict[str, Any],
                 cls: type) -> None:
        self.theta = np.asarray(theta, dtype=float).ravel()
        self.paths = [list(p) for p in saved["paths"]]
        leaves = _leaves(body)
        self.base = [np.asarray(leaves[tuple(p)], dtype=float) for p in self.paths]
        self.offsets = np.cumsum([0] + [b.size for b in self.base])
        mp = saved["map"]
        self.rows = np.asarray(mp["rows"], dtype=int)
        self.cols = np.asarray(mp["cols"], dtype=int)
        self.vals = np.asarray(mp["values"], dtype=float)
        self.flat0 = np.concatenate([b.ravel() for b in self.base]) if self.base \
            else np.zeros(0)
        self.body, self.cls = body, cls

    def __call__(self, t: Any) -> Any:
        dt = np.asarray(t, dtype=float).ravel() - self.theta
        flat = self.flat0.copy()
        np.add.at(flat, self.rows, self.vals * dt[self.cols])
        new = copy.deepcopy(self.body)
        for n, (p, b) in enumerate(zip(self.paths, self.base)):
            v = flat[self.offsets[n]:self.offsets[n + 1]].reshape(b.shape)
            _set(new, p, float(v) if b.ndim == 0 and not isinstance(
                _get(self.body, p), np.ndarray) else v)
        return self.cls.from_dict(new)  # type: ignore[attr-defined]


def affine_build(saved: dict[str, Any], body: dict[str, Any], cls: type,
                 theta: Any = None) -> AffineBuild:
    """The ``build`` of a map measured by :func:`stored_map` (``theta``: the parameters it
    was measured at, default ``saved["theta"]``; ``body``, ``cls``: the model it makes)."""
    return AffineBuild(saved["theta"] if theta is None else theta, saved, body, cls)
