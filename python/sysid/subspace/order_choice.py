"""The automatic order of a subspace fit (``order="auto"``), chosen by simulation fit
cross-validated inside the record (:mod:`sysid.validation.crossval`; for a time series, which
has no simulation, one-step prediction fit), among the orders whose model on the whole record
is stable unless the data insist on an unstable one
(:func:`sysid.validation.stable_orders.stable_first`); the singular-value gap where the record
cannot be split or the estimator holds no data (built from a factor).
(``feedthrough="auto"``, which ``order="auto"`` uses unless ``feedthrough``
is given: :mod:`sysid.subspace.feedthrough`.)"""

from __future__ import annotations

from functools import partial
from typing import Any

__all__ = ["order_selection"]


def _svd_rule(sub: Any, why: str, failure: str = "") -> dict[str, Any]:
    """The singular-value rule's choice; ``failure``: why the record could not be
    cross-validated (also in the reason)."""
    return {"order": int(sub.auto_order()), "criterion": "singular-value gap",
            "reason": "largest gap of the log singular values" + why, "table": {},
            "failure": failure}


def order_selection(est: Any, key: str, feedthrough: bool,
                    orders: list[int] | None = None) -> dict[str, Any]:
    """See :meth:`sysid.SubspaceEstimator.order_selection` (cached on the estimator);
    ``orders``: only these (the singular-value rule then takes the one nearest its gap)."""
    from ..validation.crossval import cross_validated_order

    cache_key = ("cv", key, feedthrough, None if orders is None else tuple(orders))
    if cache_key in est._svd:
        return dict(est._svd[cache_key])
    sub = est._subspace(key)
    out: dict[str, Any]
    if not est._from_factor:
        focus = "simulation" if est.factor.n_inputs else "prediction"
        try:
            make = partial(type(est), scale=est.scale, matrices=est.matrices)
            out = cross_validated_order(est.data, make,
                                        method=key, past=est.past,
                                        future=est.future, feedthrough=feedthrough,
                                        orders=orders, whole=est, focus=focus).as_dict()
            out["order"] = min(out["order"], sub.max_order)
        except Exception as e:  # noqa: BLE001 - too short to split: the SVD rule
            out = _svd_rule(sub, f" (the record could not be cross-validated: {e})", str(e))
    else:
        out = _svd_rule(sub, "")
    if orders is not None and out["order"] not in orders:
        gap = out["order"]
        out["order"] = min(orders, key=lambda n: (abs(n - gap), n))
        out["reason"] += f"; the nearest of the orders given ({gap} is not among them)"
    est._svd[cache_key] = out
    return dict(out)
