"""The automatic order and feedthrough of a subspace fit (``order="auto"``,
``feedthrough="auto"``), chosen by simulation fit cross-validated inside the record
(:mod:`sysid.validation.crossval`); the singular-value gap where the record cannot be split."""

from __future__ import annotations

from typing import Any

from .._checks import as_int

__all__ = ["order_selection", "feedthrough_selection"]


def _svd_rule(sub: Any, why: str) -> dict[str, Any]:
    return {"order": int(sub.auto_order()), "criterion": "singular-value gap",
            "reason": "largest gap of the log singular values" + why, "table": {}}


def order_selection(est: Any, key: str, feedthrough: bool) -> dict[str, Any]:
    """See :meth:`sysid.SubspaceEstimator.order_selection` (cached on the estimator)."""
    from ..validation.crossval import cross_validated_order

    cache_key = ("cv", key, feedthrough)
    if cache_key in est._svd:
        return dict(est._svd[cache_key])
    sub = est._subspace(key)
    out: dict[str, Any]
    if est.factor.n_inputs and not est._from_factor:
        try:
            out = cross_validated_order(est.data, type(est), method=key, past=est.past,
                                        future=est.future, feedthrough=feedthrough).as_dict()
            out["order"] = min(out["order"], sub.max_order)
        except Exception as e:  # noqa: BLE001 - too short to split: the SVD rule
            out = _svd_rule(sub, f" (the record could not be cross-validated: {e})")
    else:
        out = _svd_rule(sub, "")
    est._svd[cache_key] = out
    return dict(out)


def feedthrough_selection(est: Any, key: str, order: Any, closed_loop: bool
                          ) -> tuple[bool, dict[str, Any]]:
    """See :meth:`sysid.SubspaceEstimator.feedthrough_selection`."""
    from ..validation.crossval import TOL, cross_validated_order

    if closed_loop or not est.factor.n_inputs or est._from_factor:
        return False, {"feedthrough": False, "reason": "not decided from data (closed-loop "
                       "method, no inputs or no data): no feedthrough"}
    orders = None if isinstance(order, str) else [as_int(order, "order", 1)]
    best = {}
    try:
        for ft in (False, True):
            c = cross_validated_order(est.data, type(est), method=key, past=est.past,
                                      future=est.future, feedthrough=ft, orders=orders)
            best[ft] = c.table[c.order]
            if orders is None:
                est._svd[("cv", key, ft)] = c.as_dict()
    except Exception as e:  # noqa: BLE001 - too short to split
        return False, {"feedthrough": False, "reason": f"could not be cross-validated ({e}): "
                       "no feedthrough"}
    use = bool(best[True] > best[False] + TOL)
    return use, {"feedthrough": use,
                 "held_out_fit": {"with D": best[True], "without D": best[False]},
                 "reason": f"held-out simulation fit {best[True]:.1f} % with D, "
                           f"{best[False]:.1f} % without: "
                           + ("D estimated" if use else f"D = 0 (gain below {TOL:g})")}
