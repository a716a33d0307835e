"""The uncertainty :func:`sysid.identify` attaches to a chosen model that carries none (a
subspace one): the simulation-error criterion's at it."""

from __future__ import annotations

from typing import Any

from ..data.iodata import IOData
from ..pem.at_estimate import criterion_at

__all__ = ["with_uncertainty"]


def with_uncertainty(model: Any, data: IOData, checks: dict[str, Any],
                     subspace_methods: tuple[str, ...]) -> Any:
    """A chosen model that carries no parameter uncertainty (a subspace one) with the
    uncertainty of the simulation-error criterion at it (:func:`sysid.pem` with no iteration,
    the criterion identify's refinements use; :func:`~sysid.pem.at_estimate.criterion_at`):
    poles, damping and responses then have standard deviations, as MATLAB reports them for
    ``n4sid`` models. The model itself is unchanged; when the criterion cannot be evaluated
    at it, it is returned as it is (and the checks say why)."""
    m, focus = criterion_at(model, data)
    if m is None:
        checks["uncertainty"] = model.info["identify_uncertainty"] = (
            f"none: {focus}")
        return model
    m.info = dict(model.info)  # the subspace fit's record, not a search that did not run
    subspace = str((model.info or {}).get("method", "")) in subspace_methods
    m.info["identify_uncertainty"] = checks["uncertainty"] = (
        f"the chosen model's parameter uncertainty is the {focus}-error criterion's at it "
        "(first order, as for a prediction-error fit"
        + ("; on long records it matches a subspace estimator's own spread, as sysid.n4sid "
           "attaches it; SubspaceEstimator(...).fit(..., uncertainty='bootstrap') for the "
           "estimator's own)" if subspace else ")")
        + ("; the prediction-error criterion because the model is unstable (the data insist)"
           if focus == "prediction" else ""))
    return m
