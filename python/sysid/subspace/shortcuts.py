"""The one-call subspace estimators :func:`moesp`, :func:`n4sid` and :func:`cva`: a
:class:`~sysid.subspace.estimator.SubspaceEstimator` built and fitted in one call, and
:func:`n4sid` on frequency-response data (:func:`~sysid.subspace.frd_subspace.frd_subspace`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_int
from .._threads import one_blas_thread
from ..data.iodata import IOData, require_record
from ..errors import DataError, is_frd
from ..models.statespace import StateSpaceModel
from ..pem.at_estimate import attach_criterion_uncertainty
from .estimator import Order, SubspaceEstimator, horizon_for_order
from .feedthrough import warn_if_left_out
from .frd_subspace import frd_subspace

__all__ = ["moesp", "n4sid", "cva"]


def n4sid_frd(frd: Any, order: Any, horizon: int | None, feedthrough: Any, stable: bool,
              x0: bool, scale: bool | None) -> StateSpaceModel:
    """:func:`sysid.n4sid` on frequency-response data (MATLAB's ``n4sid(idfrd, n)``):
    :func:`frd_subspace`, with the options of a time record that do not apply refused.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> g = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    >>> w = np.linspace(0.1, 3.0, 30)
    >>> m = sysid.n4sid(sysid.FRD(w, g.freqresp(w), dt=1.0), 1)
    >>> round(float(m.poles()[0].real), 8)
    0.5
    """
    if stable or x0:
        raise DataError("n4sid on frequency-response data fits the response on its lines: "
                        "stable= and x0= apply to time records; leave them out (refine with "
                        "sysid.ssest(frd, order), which keeps the model stable)")
    # the default (None): no D, with frd_subspace's check that the response shows none
    return frd_subspace(frd, order, horizon=horizon, feedthrough=feedthrough, scale=scale)


_FRD_NOTE = """

    Frequency-response data (an :class:`sysid.FRD`, MATLAB's ``n4sid(idfrd, n)``): the
    frequency-domain subspace fit :func:`sysid.frd_subspace` (``order`` an integer or
    ``"auto"``, ``feedthrough`` ``True`` or ``False``; ``stable`` and ``x0`` do not apply)."""


def _frd_note(method: str) -> str:
    return _FRD_NOTE if method == "n4sid" else ""


def _shortcut(method: str):  # type: ignore[no-untyped-def]
    @one_blas_thread
    def fit(
        data: IOData | tuple[Any, Any],
        order: Order = "auto",
        *,
        horizon: int | None = None,
        feedthrough: bool | str | None = None,
        kalman: bool = True,
        stable: bool = False,
        x0: bool = False,
        scale: bool | None = None,
        input_delay: Any = None,
        uncertainty: str | None = "criterion",
    ) -> StateSpaceModel:
        if uncertainty not in ("criterion", "bootstrap", None):
            raise DataError(f"uncertainty must be 'criterion', 'bootstrap' or None, got "
                            f"{uncertainty!r}")
        if method == "n4sid" and is_frd(data) and input_delay is None:
            return n4sid_frd(data, order, horizon, feedthrough, stable, x0, scale)
        data = require_record(data, method.replace("-", "_"))
        if input_delay is not None:  # MATLAB's InputDelay: fitted on the shifted inputs
            from ..models.input_delay import delayed_fit

            return delayed_fit(data, input_delay, feedthrough, lambda shifted: fit(
                shifted, order, horizon=horizon, feedthrough=feedthrough, kalman=kalman,
                stable=stable, x0=x0, scale=scale, uncertainty=uncertainty))
        if not isinstance(order, str) and np.ndim(order) == 0:
            order = as_int(order, "order", 1)  # inf, nan, 2.5: before the data are compressed
        horizon = horizon_for_order(data, order, horizon)  # one that allows a given order
        est = SubspaceEstimator(data, horizon, method=method, scale=scale)
        model = est.fit(order, feedthrough=feedthrough, kalman=kalman, stable=stable, x0=x0,
                        uncertainty="bootstrap" if uncertainty == "bootstrap" else None)
        if feedthrough is None and not isinstance(order, str) and np.ndim(order) == 0:
            # D left out by default: say so when the record shows a direct term
            warn_if_left_out(est, order, method, model, fit.__name__, kalman=kalman, x0=x0,
                             stable=stable)
        if uncertainty == "criterion":
            model = attach_criterion_uncertainty(model, data)
        return model

    fit.__name__ = method.replace("-", "_")
    fit.__doc__ = f"""Identify a state-space model with {method.upper()} in one call.

    Equivalent to ``SubspaceEstimator(data, horizon, method="{method}").fit(order, ...)``
    (at a given order without ``horizon``, the horizon of
    :func:`~sysid.subspace.estimator.horizon_for_order`: the default, or the smallest that
    allows the order when the default does not and the data do); no feedthrough (``D = 0``)
    at a given order unless ``feedthrough=True`` (or ``"auto"``: decided from the data), as
    every sysid state-space estimator (left out by default, a ``FeedthroughWarning`` says when
    the record shows a direct term); with ``order="auto"`` (the
    default) the order and ``D`` are chosen together by held-out simulation fit
    (``info["order_selection"]``, ``info["feedthrough_selection"]``). ``scale=False``
    computes in the record's units instead of on channels of unit root mean square
    (:mod:`sysid.subspace.scaling`), as SLICOT's IB01AD does. ``input_delay`` (samples, one
    for all inputs or one each, or ``"auto"``; MATLAB's ``InputDelay``): fitted to the
    shifted inputs, the delays returned as states
    (:mod:`sysid.models.input_delay`). ``uncertainty``: ``"criterion"`` (the default, as
    MATLAB's ``n4sid`` reports a covariance) attaches the first-order uncertainty of the
    simulation-error criterion at the estimate (the prediction-error one, with ``K``, for a
    time series; :mod:`sysid.pem.at_estimate`; its spread matches the estimator's own in a
    Monte Carlo test; ``info["uncertainty"]["criterion"]`` names it), so ``model.poles(std=True)``,
    ``damp`` and the response bands work; ``"bootstrap"`` the estimator's own spread by a
    residual bootstrap (slower); ``None`` none (the fastest).{_frd_note(method)}

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(1)
    >>> true = sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]])
    >>> u = rng.standard_normal(300)
    >>> m = sysid.{fit.__name__}(sysid.IOData(u=u, y=true.simulate(u)), order=1, horizon=4)
    >>> bool(abs(m.poles()[0] - 0.7) < 1e-8)
    True
    """
    return fit


moesp = _shortcut("moesp")
n4sid = _shortcut("n4sid")
cva = _shortcut("cva")
