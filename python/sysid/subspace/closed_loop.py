"""Closed-loop subspace identification: PBSID-opt and SSARX (the fit on an estimator's
factor; the one-call :func:`sysid.pbsid` and :func:`sysid.ssarx` live in
:mod:`sysid.subspace.closed_loop_calls`).

Data taken under feedback (``u = r - F y``) make the future inputs depend on past noise,
and the open-loop subspace methods (MOESP, N4SID, CVA) then converge to a wrong model.
Both methods here first fit a VARX (high-order ARX) of the one-step *predictor*, whose
residuals are the innovations whatever the feedback, and build the state sequence from it:

``"pbsid"`` (PBSID-opt, Chiuso 2007)
    ``Γ_f K_p`` assembled from the VARX coefficients, SVD weighted by the covariance of the
    past, state ``x(t) = Γ_f^+ Γ_f K_p z_p(t)``.
``"ssarx"`` (Jansson 2003)
    the VARX removes the influence of future innovations from the future outputs, then a
    canonical correlation analysis between the corrected future and the past gives the
    state.

Then ``C, D`` and ``A, B, K`` by least squares on the state sequence. Both are consistent
under feedback when the loop has a delay: the plant strictly proper (``feedthrough=False``,
the default) or, with ``feedthrough=True``, a controller without direct feedthrough. The VARX
may be regularised (``"ridge"``, or ``"tc"``: a prior ``c α^k`` on lag k with tuned
hyperparameters), which helps short records and long horizons. Everything runs on the
compressed record (the same factor as the open-loop methods), so the cost after the one
pass over the data does not depend on the record length.
"""

from __future__ import annotations

from typing import Any, Protocol, Union

import numpy as np

from .. import _sysid
from .._checks import as_int, as_option
from ..errors import DataError
from ..models.checks import warn_unstable
from ..models.statespace import StateSpaceModel
from .scaling import in_record_units


class _Factorised(Protocol):
    """What the fit reads of a :class:`sysid.SubspaceEstimator` (named structurally, so that
    this module need not import the estimator that calls it)."""

    past: int
    future: int
    factor: Any
    scaled_factor: Any
    channel_scales: tuple[Any, Any]
    data: Any
    _svd: dict[Any, Any]

__all__ = ["closed_loop_fit", "REGULARIZATIONS"]

REGULARIZATIONS = ("none", "ridge", "tc")

Order = Union[int, str]


def closed_loop_fit(
    est: _Factorised,
    method: str,
    order: Order = "auto",
    *,
    feedthrough: bool = False,
    kalman: bool = True,
    regularization: str = "none",
    ridge: float = 1e-3,
) -> StateSpaceModel:
    """Fit PBSID-opt or SSARX on an estimator's factor (``SubspaceEstimator.fit`` calls this).

    Parameters
    ----------
    est : SubspaceEstimator
    method : {"pbsid", "ssarx"}
    order : int or "auto"
        ``"auto"``: chosen by simulation fit cross-validated inside the record, as for the
        open-loop methods (:meth:`SubspaceEstimator.order_selection`); with a
        ``regularization``, the largest gap of the singular values.
    feedthrough : bool
        Estimate ``D`` (consistent only if the controller has no direct feedthrough).
    kalman : bool
        Keep the estimated ``K`` (else the model has no noise model).
    regularization : {"none", "ridge", "tc"}
    ridge : float
        Ridge weight relative to the mean diagonal of the scaled Gram matrix.

    Returns
    -------
    StateSpaceModel
    """
    regularization = as_option(regularization, "regularization")
    if not (isinstance(ridge, (int, float)) and np.isfinite(ridge) and ridge >= 0):
        raise DataError(f"ridge must be a finite number >= 0, got {ridge!r}")
    for name, flag in (("feedthrough", feedthrough), ("kalman", kalman)):
        if not isinstance(flag, bool):
            raise DataError(f"{name} must be True or False, got {flag!r}")
    key = (method, bool(feedthrough), regularization, float(ridge))
    cache = est._svd
    if key not in cache:
        cache[key] = _sysid.ClosedLoopSubspace(est.scaled_factor, method, regularization,
                                               float(ridge), bool(feedthrough))
    sub = cache[key]
    selection = None
    if isinstance(order, str):
        if order != "auto":
            raise DataError(f"order must be an integer or 'auto', got {order!r}")
        if regularization == "none":
            # as the open-loop methods: simulation fit cross-validated inside the record (the
            # plant model simulated on the recorded input, valid in closed loop too); the
            # singular-value gap stopped at 1-2 states on real records (a steam generator:
            # order 1, validation fit 19 % against 75 %)
            selection = est.order_selection(method=method, feedthrough=bool(feedthrough))
            n = int(selection["order"])
        else:  # the held-out fits would ignore the regularisation: the singular-value gap
            n = sub.auto_order()
    else:
        n = as_int(order, "order", 1)
    res = sub.fit(n)
    info = {
        "method": method,
        "order": n,
        "past": est.past,
        "future": est.future,
        "singular_values": sub.singular_values,
        "n_columns": est.factor.n_columns,
        "regularization": regularization,
        "Q": res["Q"],
        "R": res["R"],
        "S": res["S"],
    }
    if selection is not None:
        info["order_selection"] = selection
    model = StateSpaceModel(
        res["A"], res["B"], res["C"], res["D"], res["K"] if kalman else None,
        dt=est.data.dt,
        noise_cov=res["noise_cov"] if kalman else None,
        input_names=est.data.input_names,
        output_names=est.data.output_names,
        info=info,
    )
    model = in_record_units(model, *est.channel_scales)  # fitted on the scaled factor
    warn_unstable(model, method, closed_loop=True)
    if kalman and res.get("predictor_stabilized"):
        _note_predictor(model, res)
    return model


def _note_predictor(model: StateSpaceModel, res: dict[str, Any]) -> None:
    """The least-squares ``K`` of a closed-loop fit left the one-step predictor ``A - K C``
    unstable (a noise model with zeros outside the unit circle: every prediction and residual
    would diverge); the core replaced it by the stabilising Kalman gain of the same noise
    spectrum, the minimum-phase innovation model (Re grows by the reflected zeros' squared
    moduli). ``info["predictor_stabilized"]`` records the predictor's largest pole modulus
    before and after."""
    A, C = np.asarray(res["A"]), np.asarray(res["C"])
    K_ls = np.asarray(res["S"]) @ np.linalg.inv(np.asarray(res["R"]))  # S = K Re
    model.info["predictor_stabilized"] = {
        "before": float(np.max(np.abs(np.linalg.eigvals(A - K_ls @ C)))),
        "after": float(np.max(np.abs(np.linalg.eigvals(A - np.asarray(model.K) @ model.C)))),
        "why": "the least-squares K gave an unstable one-step predictor; K is the "
               "stabilising Kalman gain of the same noise spectrum (its minimum-phase factor)"}
