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
from ..errors import DataError, SysidError, is_frd
from ..models.statespace import StateSpaceModel
from ..pem.at_estimate import attach_criterion_uncertainty
from .estimator import Order, SubspaceEstimator, horizon_for_order
from .feedthrough import warn_if_left_out
from .frd_subspace import frd_subspace
from .series_horizon import series_horizons

__all__ = ["moesp", "n4sid", "cva", "order_estimator"]


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


def _series_estimator(data: IOData, order: int, method: str, scale: Any,
                      past: int | None = None, compressor: str = "auto"
                      ) -> SubspaceEstimator | None:
    """The estimator of a time series at ``order`` states: past from its AIC autoregression
    (or ``past``), future the shortest that allows the order
    (:mod:`sysid.subspace.series_horizon`: the efficient one); None for an order above the
    autoregression's ``p l`` (its extra states, fitted on a short future, are wild: the
    record's horizon, :func:`~sysid.subspace.estimator.horizon_for_order`, instead)."""
    sel = series_horizons(data, order)
    if order > sel["ar_order"] * data.n_outputs and past is None:
        return None
    if past is not None:
        sel["past"] = max(past, sel["future"])
    est = SubspaceEstimator(data, past=sel["past"], future=sel["future"], method=method,
                            scale=scale, compressor=compressor)
    est.horizon_selection = sel
    return est


def order_estimator(data: IOData, order: Any, horizon: int | None, method: str,
                    scale: Any = None, compressor: str = "auto") -> SubspaceEstimator:
    """The estimator ``moesp``/``n4sid``/``cva(data, order, horizon=horizon)`` fit with: a
    time series without ``horizon`` at a given order, :func:`_series_estimator`'s; else
    :func:`~sysid.subspace.estimator.horizon_for_order`'s horizon (``horizon`` when given).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from scipy import signal
    >>> from sysid.subspace.shortcuts import order_estimator
    >>> e = np.random.default_rng(0).standard_normal(500)
    >>> d = sysid.IOData(None, signal.lfilter([1.0], [1, -1.5, 0.7], e)[:, None], 1.0)
    >>> est = order_estimator(d, 2, None, "moesp")
    >>> est.past, est.future
    (3, 3)
    """
    est = None
    if data.n_inputs == 0 and horizon is None and isinstance(order, int):
        est = _series_estimator(data, order, method, scale, compressor=compressor)
    if est is None:
        horizon = horizon_for_order(data, order, horizon)  # one that allows a given order
        est = SubspaceEstimator(data, horizon, method=method, scale=scale,
                                compressor=compressor)
    return est


def _at_order_future(est: SubspaceEstimator, model: StateSpaceModel, data: IOData,
                     method: str, scale: Any, compressor: str = "auto", **fit: Any
                     ) -> StateSpaceModel:
    """A time series' model of the order ``order="auto"`` chose (with the default horizons,
    future = past), fitted again with the future shortened to that order's, as
    ``fit(data, n)`` fits it, unless that fit fails or is unstable where the first was not
    (an order above the process's: its extra states on a short future are wild; the first
    fit is kept and ``info["horizon_selection"]`` says so). The choices made on the first
    fit are kept in ``info``."""
    n = int(model.info["order"])
    short = _series_estimator(data, n, method, scale, past=est.past, compressor=compressor)
    if short is None or short.future >= est.future:
        return model
    try:  # warnings were given by the first fit
        again = short._quiet_fit(n, feedthrough=bool(model.info["settings"]["feedthrough"]),
                                 **fit)
    except SysidError:
        again = None
    if again is None or _radius(again) >= 1.0 > _radius(model):
        model.info["horizon_selection"]["rule"] += (
            f"; future {short.future} (the order's) gave no stable model at order {n}: "
            "the order choice's horizons kept")
        return model
    for key in ("order_selection", "feedthrough_selection"):
        if key in model.info:
            again.info[key] = model.info[key]
    again.info["settings"]["order_rule"] = model.info["settings"]["order_rule"]
    return again


def _radius(model: StateSpaceModel) -> float:
    return float(np.max(np.abs(model.poles()), initial=0.0))


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
        boot = "bootstrap" if uncertainty == "bootstrap" else None
        est = order_estimator(data, order, horizon, method, scale)
        model = est.fit(order, feedthrough=feedthrough, kalman=kalman, stable=stable, x0=x0,
                        uncertainty=boot)
        if est.horizon_selection is not None and (isinstance(order, str) or np.ndim(order)):
            model = _at_order_future(est, model, data, method, scale, kalman=kalman,
                                     stable=stable, x0=x0, uncertainty=boot)
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
    allows the order when the default does not and the data do; a time series, no input:
    past from the autoregression AIC picks, future the shortest that allows the order, for an
    efficient estimate, :mod:`sysid.subspace.series_horizon`, ``info["horizon_selection"]``,
    and ``order="auto"`` refitted at its order's future); no feedthrough (``D = 0``)
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
