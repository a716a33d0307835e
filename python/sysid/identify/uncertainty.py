"""The uncertainty :func:`sysid.identify` attaches to a chosen model that carries none (a
subspace one): the simulation-error criterion's at it (the prediction-error one for a time
series or an unstable model)."""

from __future__ import annotations

from typing import Any

from ..data.iodata import IOData
from ..pem.at_estimate import criterion_at
from ..pem.sandwich import through_deferred

__all__ = ["with_uncertainty"]


def with_uncertainty(model: Any, data: IOData, checks: dict[str, Any],
                     subspace_methods: tuple[str, ...]) -> Any:
    """A chosen model that carries no parameter uncertainty (a subspace one) with the
    uncertainty of the simulation-error criterion at it (:func:`sysid.pem` with no iteration,
    the criterion identify's refinements use; :func:`~sysid.pem.at_estimate.criterion_at`):
    poles, damping and responses then have standard deviations, as MATLAB reports them for
    ``n4sid`` models. The model itself is unchanged: its ``A, B, C, D`` and its noise model
    (the Kalman gain ``K`` and innovation covariance ``noise_cov`` a subspace fit estimates,
    which the simulation-error criterion leaves out: without them its one-step predictions
    were its simulation), carried by the uncertainty's draws too; when the criterion cannot
    be evaluated at it, it is returned as it is (and the checks say why).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.uncertainty import with_uncertainty
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((400, 1))
    >>> y = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]]).simulate(u)
    >>> d = sysid.IOData(u=u, y=y + 0.1 * rng.standard_normal((400, 1)))
    >>> m = sysid.SubspaceEstimator(d, 5).fit(1)
    >>> out = with_uncertainty(m, d, {}, ("moesp",))
    >>> bool(np.array_equal(out.K, m.K)), out.poles(std=True)[1].shape
    (True, (1,))
    """
    m, focus = criterion_at(model, data)
    if m is None:
        checks["uncertainty"] = model.info["identify_uncertainty"] = (
            f"none: {focus}")
        return model
    K, noise = getattr(model, "K", None), getattr(model, "noise_cov", None)
    if K is not None and getattr(m, "K", None) is None:
        # the simulation-error criterion left K out (it plays no part in simulation); the
        # candidate's noise model is the model's, and its draws' (same A, B, C, D basis)
        def with_noise(draw: Any) -> Any:
            draw.K, draw.noise_cov = K, noise
            return draw

        m.K, m.noise_cov = K, noise
        m.uncertainty = through_deferred(m.uncertainty, with_noise)
    m.info = dict(model.info)  # the subspace fit's record, not a search that did not run
    subspace = str((model.info or {}).get("method", "")) in subspace_methods
    m.info["identify_uncertainty"] = checks["uncertainty"] = (
        f"the chosen model's parameter uncertainty is the {focus}-error criterion's at it "
        "(first order, as for a prediction-error fit"
        + ("; on long records it matches a subspace estimator's own spread, as sysid.n4sid "
           "attaches it; SubspaceEstimator(...).fit(..., uncertainty='bootstrap') for the "
           "estimator's own)" if subspace else ")")
        + ("" if focus != "prediction" else
           "; the prediction-error criterion because the record is a time series (without an "
           "input the simulation-error criterion is flat in A, C)" if data.n_inputs == 0 else
           "; the prediction-error criterion because the model is unstable (the data insist)"))
    return m
