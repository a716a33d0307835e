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
"""

from __future__ import annotations

from functools import partial
from typing import Any

import numpy as np

from .._checks import as_orders
from ..errors import DataError
from .methods import CLOSED_LOOP, _method

__all__ = ["FEEDTHROUGH_DEFAULT", "check_feedthrough", "choose_feedthrough",
           "default_feedthrough"]

#: the default of every sysid state-space estimator at a given order: no ``D`` (MATLAB's)
FEEDTHROUGH_DEFAULT = False


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
    from ..validation.crossval import TOL, cross_validated_order

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
                c = cross_validated_order(est.data, partial(type(est), scale=est.scale),
                                          method=key, past=est.past,
                                          future=est.future, feedthrough=ft, orders=orders,
                                          whole=est).as_dict()
            best[ft] = c["table"].get(c["order"], -np.inf)
    except Exception as e:  # noqa: BLE001 - a record too short to split
        return _undecided(f"the record could not be cross-validated: {e}")
    use = bool(best[True] > best[False] + TOL)
    return use, {"feedthrough": use, "criterion": "held-out simulation fit",
                 "held_out_fit": {"with D": best[True], "without D": best[False]},
                 "reason": f"held-out simulation fit {best[True]:.1f} % with D, "
                           f"{best[False]:.1f} % without: "
                           + ("D estimated" if use else f"D = 0 (gain not above {TOL:g})")}
