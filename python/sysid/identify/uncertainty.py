"""The uncertainty :func:`sysid.identify` attaches to a chosen model that carries none (a
subspace one): the simulation-error criterion's at it."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..data.iodata import IOData

__all__ = ["with_uncertainty"]


def with_uncertainty(model: Any, data: IOData, checks: dict[str, Any],
                     subspace_methods: tuple[str, ...]) -> Any:
    """A chosen model that carries no parameter uncertainty (a subspace one) with the
    uncertainty of the simulation-error criterion at it (:func:`sysid.pem` with no iteration,
    the criterion identify's refinements use): poles, damping and responses then have
    standard deviations, as MATLAB reports them for ``n4sid`` models. First order, and the
    spread a prediction-error fit would have: a subspace estimate spreads at least as much
    (``checks["uncertainty"]`` says so). The model itself is unchanged; when the criterion
    cannot be evaluated at it, it is returned as it is (and the checks say why)."""
    import sysid

    focus = "simulation"
    if not model.is_stable():
        # the simulation-error criterion diverges at an unstable A; the prediction-error one
        # is defined wherever the predictor A - K C is stable (an integrating or unstable
        # plant under feedback: the data insist)
        K = getattr(model, "K", None)
        stable_predictor = K is not None and np.max(np.abs(np.linalg.eigvals(
            np.asarray(model.A) - np.asarray(K) @ np.asarray(model.C)))) < 1.0
        if not stable_predictor:
            checks["uncertainty"] = model.info["identify_uncertainty"] = (
                "none: the chosen model is unstable (the data insist) and has no stable "
                "predictor, so neither prediction-error criterion is defined at it; refine "
                "it with sysid.ssest(data, model) for a model with uncertainty")
            return model
        focus = "prediction"
    wt = "output" if data.n_outputs > 1 else None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            m = sysid.pem(data, model, focus=focus, weighting=wt, max_iter=0,
                          feedthrough=bool(np.any(np.asarray(model.D) != 0)), progress=False)
        if m.uncertainty is None:
            raise ValueError("no covariance")
        step = np.ones((20, data.n_inputs))  # the same model, in whatever state basis
        if not np.allclose(m.simulate(step), model.simulate(step), rtol=1e-8, atol=1e-12):
            raise ValueError("the criterion moved the model")
    except Exception as e:  # noqa: BLE001 - reported in the checks, never raised
        checks["uncertainty"] = model.info["identify_uncertainty"] = (
            f"none: the chosen model's parameter uncertainty could not be evaluated "
            f"({type(e).__name__}: {e})"[:300])
        return model
    m.info = dict(model.info)  # the subspace fit's record, not a search that did not run
    subspace = str((model.info or {}).get("method", "")) in subspace_methods
    m.info["identify_uncertainty"] = checks["uncertainty"] = (
        f"the chosen model's parameter uncertainty is the {focus}-error criterion's at it "
        "(first order, as for a prediction-error fit"
        + ("; the subspace estimate itself spreads at least as much: "
           "SubspaceEstimator(...).fit(..., uncertainty='bootstrap') for its own)"
           if subspace else ")")
        + ("; the prediction-error criterion because the model is unstable (the data insist)"
           if focus == "prediction" else ""))
    return m
