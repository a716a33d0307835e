"""The feedthrough ``D`` of every state-space estimator: one default and one automatic rule.

Default, as MATLAB's toolbox: no direct term, ``D = 0``, for a model of a given order. Sampled
physical systems rarely respond within the sample they are excited in (a zero-order hold and
anti-aliasing filters add at least a fraction of a sample of delay), and a free ``D`` fitted to
noise or to the fast tail of the response hurts simulation on new data more than it helps.
``feedthrough=True`` estimates ``D``. Where the estimator chooses the structure itself
(``order="auto"``, or ``ssest`` with a sequence of orders) and ``feedthrough`` is not given,
``D`` is chosen with the order (``feedthrough="auto"``, :func:`default_feedthrough`): the
records where a sensor sees the input within the sample (accelerometers against a force,
heat flux against a temperature, a winding's tension) lose 10-60 fit points on new data
without it, the others lose nothing by the check (``benches/results/realdata.md``).

``feedthrough="auto"`` decides from the data, once, here, for every estimator: models with and
without ``D`` (subspace fits at the order asked for, or at each automatic order) are fitted on
part of the record and simulated on the part held out
(:func:`sysid.validation.crossval.cross_validated_order`: five contiguous blocks, or the
experiments); ``D`` is estimated only when it raises the held-out simulation fit by more than
``TOL`` (0.5) fit points. A direct term the data need (a sensor seeing the input, an actuator
measured after a fast stage) raises it by many points; a spurious one does not raise it at
all. Closed-loop methods, time series and estimators built from a factor alone cannot be
decided this way and take ``D = 0``; the decision and its reason are recorded in
``model.info["feedthrough_selection"]``.

Where the default leaves ``D`` out of a model of a given order, the one-call estimators
(``n4sid``, ``moesp``, ``cva``, ``ssest``) check that the record does not show a direct term
(:func:`warn_if_left_out`): the subspace fit at that order with ``D`` estimated, against the
one without, by their one-step prediction errors on the record. When ``D`` at least halves them
(``LEFT_OUT_RATIO``), a :class:`~sysid.errors.FeedthroughWarning` says so (the model is the
one asked for). Over 25 real records (8 shipped, 17 not) at orders 2, 4 and 8, all 22
fits where ``D`` halved the errors simulated the validation data better with it (by 0.4
to 860 fit points); below that ratio 33 of 49 did and 16 did worse
(``benches/feedthrough_check.py``, ``benches/results/feedthrough_check.md``). The one case
it cannot tell apart is feedback within the sample (an input computed from the same
sample's output, as an analogue loop sampled): the lag-0 dependence is then the
controller's, and a plant in such a loop has no ``D`` (the loop would be algebraic); the
warning says so.
"""

from __future__ import annotations

from functools import partial
from typing import Any

import numpy as np

from .._checks import as_orders
from ..errors import DataError
from .methods import CLOSED_LOOP, _method

__all__ = ["FEEDTHROUGH_DEFAULT", "LEFT_OUT_RATIO", "check_feedthrough", "choose_feedthrough",
           "default_feedthrough", "held_out_decision", "record_left_out", "warn_if_left_out"]

#: the default of every sysid state-space estimator at a given order: no ``D`` (MATLAB's)
FEEDTHROUGH_DEFAULT = False

#: ``D`` that divides the one-step prediction errors (sum of squares relative to each output's
#: variation) of the subspace fit at least by this is a direct term the record shows
LEFT_OUT_RATIO = 2.0

#: the samples of each experiment that check reads at most
CHECK_SAMPLES = 50_000


def default_feedthrough(value: Any, order: Any) -> Any:
    """``feedthrough`` as given; left out (``None``): ``"auto"`` when the order is chosen from
    the data too (``order="auto"`` or a sequence of orders), else ``FEEDTHROUGH_DEFAULT``
    (no ``D``).

    Examples
    --------
    >>> from sysid.subspace.feedthrough import default_feedthrough
    >>> default_feedthrough(None, "auto"), default_feedthrough(None, 4), default_feedthrough(
    ...     False, "auto")
    ('auto', False, False)
    """
    if value is not None:
        return value
    chosen = isinstance(order, str) or np.ndim(order) > 0
    return "auto" if chosen else FEEDTHROUGH_DEFAULT


def check_feedthrough(value: Any, *, auto: bool = True) -> bool | str:
    """``value`` as ``True``, ``False`` or ``"auto"`` (the only accepted values).

    Examples
    --------
    >>> from sysid.subspace.feedthrough import check_feedthrough
    >>> check_feedthrough("auto"), check_feedthrough(False)
    ('auto', False)
    """
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if auto and isinstance(value, str) and value == "auto":
        return "auto"
    allowed = "True, False or 'auto'" if auto else "True or False"
    raise DataError(f"feedthrough must be {allowed}, got {value!r}")


def _undecided(why: str) -> tuple[bool, dict[str, Any]]:
    return False, {"feedthrough": False, "criterion": "none",
                   "reason": f"not decided from the data ({why}): no feedthrough"}


def choose_feedthrough(est: Any, order: Any = "auto", *, method: str | None = None
                       ) -> tuple[bool, dict[str, Any]]:
    """Whether ``feedthrough="auto"`` estimates ``D`` for this record, and why.

    Parameters
    ----------
    est : SubspaceEstimator
        An estimator on the estimation record (its horizons and cached order choices are
        reused; the held-out fits use its class).
    order : int, "auto" or sequence of int
        The order(s) the held-out fits compare at; ``"auto"``: each side at its own
        automatic order.
    method : str, optional
        Subspace weighting of the held-out fits (default: the estimator's).

    Returns
    -------
    (bool, dict)
        The decision and ``{"feedthrough", "criterion", "held_out_fit", "reason"}``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.subspace.feedthrough import choose_feedthrough
    >>> rng = np.random.default_rng(0)
    >>> true = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], [[0.7]])
    >>> u = rng.standard_normal((600, 1))
    >>> y = true.simulate(u) + 0.02 * rng.standard_normal((600, 1))
    >>> choose_feedthrough(sysid.SubspaceEstimator(sysid.IOData(u=u, y=y)), 1)[0]
    True
    """
    from ..validation.crossval import cross_validated_order

    key = est.method if method is None else _method(method)
    if key in CLOSED_LOOP:
        return _undecided(f"closed-loop method {key!r}")
    if not est.factor.n_inputs:
        return _undecided("no inputs")
    if est._from_factor:
        return _undecided("an estimator built from a factor, without the data")
    if isinstance(order, str):
        if order != "auto":
            raise DataError(f"order must be an integer, a sequence of integers or 'auto', "
                            f"got {order!r}")
        orders = None
    else:
        orders = as_orders(order)
    best: dict[bool, float] = {}
    try:
        for ft in (False, True):
            if orders is None:  # each side at its automatic order (cached for fit)
                c = est.order_selection(key, ft)
                if c["criterion"] != "cross-validated simulation fit":
                    return _undecided("the record could not be cross-validated")
            else:
                make = partial(type(est), scale=est.scale, matrices=est.matrices)
                c = cross_validated_order(est.data, make,
                                          method=key, past=est.past,
                                          future=est.future, feedthrough=ft, orders=orders,
                                          whole=est).as_dict()
            best[ft] = c["table"].get(c["order"], -np.inf)
    except Exception as e:  # noqa: BLE001 - a record too short to split
        return _undecided(f"the record could not be cross-validated: {e}")
    return held_out_decision(best[True], best[False])


def held_out_decision(with_d: float, without: float) -> tuple[bool, dict[str, Any]]:
    """The ``feedthrough="auto"`` rule on the best held-out simulation fits with and without
    ``D``: ``D`` when it gains more than ``TOL`` points; the decision and its record
    (``info["feedthrough_selection"]``), shared by every estimator that decides ``D``.

    Examples
    --------
    >>> from sysid.subspace.feedthrough import held_out_decision
    >>> held_out_decision(81.5, 47.6)[0], held_out_decision(92.4, 92.2)[0]
    (True, False)
    """
    from ..validation.crossval import TOL

    use = bool(with_d > without + TOL)
    return use, {"feedthrough": use, "criterion": "held-out simulation fit",
                 "held_out_fit": {"with D": with_d, "without D": without},
                 "reason": f"held-out simulation fit {with_d:.1f} % with D, "
                           f"{without:.1f} % without: "
                           + ("D estimated" if use else f"D = 0 (gain not above {TOL:g})")}


def _prediction_error(model: Any, data: Any) -> float:
    """Sum over outputs of the one-step prediction errors' energy relative to the output's
    variation: the model's predictor (its simulation without ``K``) run from a zero state over
    the first ``CHECK_SAMPLES`` samples of every experiment (a ratio of two such sums is
    settled long before; a long record is not read again in full for a check)."""
    from .. import _sysid

    A, B, C, D = (np.asarray(x, float) for x in (model.A, model.B, model.C, model.D))
    K = np.zeros((A.shape[0], C.shape[0])) if model.K is None else np.asarray(model.K, float)
    err = np.zeros(C.shape[0])
    var = np.zeros(C.shape[0])
    for u, y in data.experiments:
        u = np.ascontiguousarray(u[:CHECK_SAMPLES], float)
        y = np.ascontiguousarray(y[:CHECK_SAMPLES], float)
        yh = _sysid.predict(A, B, C, D, K, u, y, None, 1)
        err += np.sum((y - yh) ** 2, axis=0)
        var += np.sum((y - y.mean(axis=0)) ** 2, axis=0)
    return float(np.sum(err / np.where(var > 0, var, 1.0)))


def record_left_out(ratio: float, fit: str, order: Any, who: str) -> dict[str, Any]:
    """The left-out check's record for ``model.info["feedthrough_check"]``, and the
    :class:`~sysid.errors.FeedthroughWarning` when ``ratio`` (one-step prediction errors of
    the ``fit`` without ``D`` over those with it) reaches ``LEFT_OUT_RATIO``; shared by the
    subspace estimators and ``ssregest``.

    Examples
    --------
    >>> import warnings
    >>> from sysid.subspace.feedthrough import record_left_out
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     check = record_left_out(5.0, "ARX model", 4, "ssregest")
    >>> [type(x.message).__name__ for x in w], check["threshold"]
    (['FeedthroughWarning'], 2.0)
    """
    import warnings

    from .._checks import user_stacklevel
    from ..errors import FeedthroughWarning

    check = {
        "ratio": float(ratio), "threshold": LEFT_OUT_RATIO,
        "what": f"one-step prediction errors of the {fit} at this order without D over "
                "those with D (sum over outputs, each relative to its variation; predictors "
                f"from a zero state over at most {CHECK_SAMPLES} samples per experiment)"}
    if ratio >= LEFT_OUT_RATIO:
        warnings.warn(
            f"{who} fitted no direct term (D = 0, the default at a given order), but the record "
            f"shows one: with D estimated, the one-step prediction errors of the {fit} "
            f"at order {order} are {ratio:.3g} times smaller (the output answers the input "
            f"within the sample). Pass feedthrough=True, or feedthrough='auto' to decide from "
            f"held-out data; unless the input is a controller's answer to the same sample's "
            f"output (feedback within the sample), where D = 0 is right and the closed-loop "
            f"methods (sysid.pbsid or sysid.ssarx) apply", FeedthroughWarning,
            stacklevel=user_stacklevel())
    return check


def warn_if_left_out(est: Any, order: int, method: str, model: Any, who: str,
                     kalman: bool = True, x0: bool = False, stable: bool = False
                     ) -> dict[str, Any] | None:
    """Warn (:class:`~sysid.errors.FeedthroughWarning`) when the record shows a direct term that
    ``model`` (fitted by ``est`` at ``order`` with ``method``, without ``D`` by default) leaves
    out: the subspace fit with ``D`` has one-step prediction errors at least
    ``LEFT_OUT_RATIO`` times smaller (``kalman``, ``x0``, ``stable``: as ``model`` was
    fitted). The check is kept in ``model.info["feedthrough_check"]`` and returned; records
    without inputs or data (an estimator built from a factor) and closed-loop methods are not
    checked (None).

    Examples
    --------
    >>> import numpy as np, sysid, warnings
    >>> from sysid.subspace.feedthrough import warn_if_left_out
    >>> rng = np.random.default_rng(0)
    >>> true = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], [[0.7]])
    >>> u = rng.standard_normal(600)
    >>> y = true.simulate(u) + 0.02 * rng.standard_normal((600, 1))
    >>> est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y))
    >>> m = est.fit(1, method="moesp")
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     check = warn_if_left_out(est, 1, "moesp", m, "moesp")
    >>> [type(x.message).__name__ for x in w], check["ratio"] > 2
    (['FeedthroughWarning'], True)
    """
    import warnings

    if (est._from_factor or not est.factor.n_inputs or _method(method) in CLOSED_LOOP
            or np.any(np.asarray(model.D) != 0)):
        return None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with_d = est._quiet_fit(order, method=method, feedthrough=True, kalman=kalman,
                                    x0=x0, stable=stable)
            without, with_ = (_prediction_error(m, est.data) for m in (model, with_d))
    except Exception:  # noqa: BLE001 - a check that cannot be made says nothing
        return None
    ratio = without / with_ if with_ > 0 else np.inf
    check = model.info["feedthrough_check"] = record_left_out(ratio, "subspace fit", order, who)
    return check
