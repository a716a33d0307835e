"""The one-call closed-loop estimators :func:`sysid.pbsid` and :func:`sysid.ssarx`
(``SubspaceEstimator(data, ..., method=...).fit(order)`` in one call; the methods themselves
are in :mod:`sysid.subspace.closed_loop`)."""

from __future__ import annotations

from typing import Any

from ..data.iodata import IOData, require_record
from ..errors import DataError
from ..models.statespace import StateSpaceModel
from ..pem.at_estimate import attach_criterion_uncertainty
from .estimator import Order, SubspaceEstimator, horizon_for_order
from .feedthrough import check_feedthrough, choose_feedthrough, default_feedthrough

__all__ = ["pbsid", "ssarx"]


def _one_call(method: str) -> Any:
    def fit(
        data: IOData | tuple[Any, Any],
        order: Order = "auto",
        *,
        horizon: int | None = None,
        past: int | None = None,
        future: int | None = None,
        feedthrough: bool | str | None = None,
        regularization: str = "none",
        ridge: float = 1e-3,
        scale: bool | None = None,
        uncertainty: str | None = "criterion",
    ) -> StateSpaceModel:
        from .closed_loop import closed_loop_fit

        if uncertainty not in ("criterion", None):
            raise DataError(f"uncertainty must be 'criterion' or None, got {uncertainty!r} "
                            "(a residual bootstrap that keeps the input would break the "
                            "feedback loop)")
        data = require_record(data, method)
        if past is None and future is None:  # one that allows a given order, as n4sid's
            horizon = horizon_for_order(data, order, horizon)
        est = SubspaceEstimator(data, horizon, past=past, future=future, method=method,
                                scale=scale)
        ft, why = check_feedthrough(default_feedthrough(feedthrough, order)), None
        if ft == "auto":
            ft, why = choose_feedthrough(est, order, method=method)
        model = closed_loop_fit(est, method, order, feedthrough=bool(ft),
                                regularization=regularization, ridge=ridge)
        if why is not None:
            model.info["feedthrough_selection"] = why
        if uncertainty == "criterion":  # the prediction error: its covariance holds in
            model = attach_criterion_uncertainty(model, data, "prediction")  # closed loop
        return model

    fit.__name__ = method
    fit.__qualname__ = method
    return fit


pbsid = _one_call("pbsid")
pbsid.__doc__ = """Identify a state-space model from closed-loop data with PBSID-opt.

    Equivalent to ``SubspaceEstimator(data, horizon, method="pbsid").fit(order, ...)``;
    consistent under feedback when the loop has a delay (see
    :mod:`sysid.subspace.closed_loop`).

    Parameters
    ----------
    data : IOData or (u, y)
    order : int or "auto"
    horizon, past, future : int, optional
        VARX order (past) and observability horizon (future <= past + 1). Without them at a
        given order, the horizon of :func:`~sysid.subspace.estimator.horizon_for_order` (the
        default, or the smallest that allows the order when the data do), as :func:`n4sid`.
    feedthrough : bool or "auto", optional
        Estimate ``D`` (only with a controller without direct feedthrough). Default
        ``D = 0``, as every sysid state-space estimator (with ``order="auto"`` as
        ``"auto"``, which keeps ``D = 0`` under feedback, with the reason in
        ``info["feedthrough_selection"]``).
    regularization : {"none", "ridge", "tc"}
        Of the VARX.
    ridge : float
        Ridge weight (``regularization="ridge"``).
    scale : bool, optional
        Fit on channels of unit root mean square (default; :mod:`sysid.subspace.scaling`),
        or in the record's units (``False``).
    uncertainty : {"criterion", None}
        ``"criterion"`` (default): the first-order uncertainty of the prediction-error
        criterion with the model's ``K`` at the estimate (:mod:`sysid.pem.at_estimate`; it
        holds under feedback, and matches the estimator's spread in a Monte Carlo test), so
        ``model.poles(std=True)``, ``damp`` and the response bands work; ``None``: none.

    Returns
    -------
    StateSpaceModel

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> n = 4000; r = rng.standard_normal(n); e = 0.5 * rng.standard_normal(n)
    >>> u, y = np.zeros(n), np.zeros(n)
    >>> for t in range(1, n):
    ...     y[t] = 0.8 * y[t - 1] + u[t - 1] + e[t]
    ...     u[t] = r[t] - 0.3 * y[t]
    >>> m = sysid.pbsid(sysid.IOData(u=u, y=y), order=1, horizon=10)
    >>> bool(abs(m.poles()[0] - 0.8) < 0.02)
    True
    """

ssarx = _one_call("ssarx")
ssarx.__doc__ = """Identify a state-space model from closed-loop data with SSARX (Jansson).

    Equivalent to ``SubspaceEstimator(data, horizon, method="ssarx").fit(order, ...)``; same
    parameters as :func:`pbsid`.

    Returns
    -------
    StateSpaceModel

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> n = 4000; r = rng.standard_normal(n); e = 0.5 * rng.standard_normal(n)
    >>> u, y = np.zeros(n), np.zeros(n)
    >>> for t in range(1, n):
    ...     y[t] = 0.8 * y[t - 1] + u[t - 1] + e[t]
    ...     u[t] = r[t] - 0.3 * y[t]
    >>> m = sysid.ssarx(sysid.IOData(u=u, y=y), order=1, horizon=10)
    >>> bool(abs(m.poles()[0] - 0.8) < 0.02)
    True
    """
