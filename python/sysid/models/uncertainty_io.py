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

from typing import Any

import numpy as np

from .affine_map import MAX_PARAMETERS, affine_build, stored_map
from .uncertainty import ParameterUncertainty, form_deferred

__all__ = ["body_with_uncertainty", "model_from_body", "uncertainty_from_dict",
           "uncertainty_to_dict"]

def uncertainty_to_dict(model: Any) -> dict[str, Any] | None:
    """The saved form of ``model.uncertainty`` (``None`` without one), or a dict
    ``{"omitted": reason}`` when it cannot be written."""
    unc = getattr(model, "uncertainty", None)
    if not isinstance(unc, ParameterUncertainty):
        return None
    if isinstance(getattr(type(model), "uncertainty", None), property):
        return None  # a wrapper (offsets, trend): its inner model carries the uncertainty
    saved = stored_map(unc, type(model), MAX_PARAMETERS)
    if "omitted" in saved:
        return saved
    return {"theta": unc.theta, "covariance": unc.covariance, "names": list(unc.names),
            "dof": int(unc.dof), "method": unc.method,
            "undetermined": list(getattr(unc, "undetermined", [])), **saved}


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
    build = affine_build(saved, body, cls)
    method = str(saved.get("method", "gauss-newton"))
    if not saved.get("linear", True):
        method += " (restored: first-order map of a nonlinear parameterisation)"
    return ParameterUncertainty(theta, saved["covariance"], build, names=saved.get("names"),
                                dof=saved.get("dof"), method=method,
                                undetermined=saved.get("undetermined", ()))


def body_with_uncertainty(model: Any) -> dict[str, Any]:
    """``model.to_dict()`` with its saved uncertainty under ``"uncertainty"`` (for a model
    class that stores another model inside its own ``to_dict``)."""
    form_deferred(model)  # a deferred covariance formed before the info naming it is written
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
