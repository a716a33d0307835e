"""The order of a refined state-space model chosen from the data (``ssest`` with
``order="auto"`` or a range of orders)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import DataError
from ..validation.crossval import TOL, choose, simulation_fit

__all__ = ["ssest_select", "split"]


def split(data: IOData, fraction: float = 2 / 3) -> tuple[IOData, IOData]:
    """The first ``fraction`` of every experiment and the rest (a contiguous hold-out)."""
    kw = {"dt": data.dt, "input_names": data.input_names, "output_names": data.output_names}
    a, b = [], []
    for u, y in data.experiments:
        k = int(round(fraction * u.shape[0]))
        a.append((u[:k], y[:k]))
        b.append((u[k:], y[k:]))

    def io(exps: list[Any]) -> IOData:
        if len(exps) == 1:
            return IOData(u=exps[0][0], y=exps[0][1], **kw)
        return IOData(u=[e[0] for e in exps], y=[e[1] for e in exps], **kw)
    return io(a), io(b)


def ssest_select(data: IOData, order: Any, *, feedthrough: Any, **kw: Any) -> Any:
    """:func:`sysid.ssest` with the order chosen from the data (``feedthrough="auto"`` is
    decided before, by :func:`sysid.subspace.feedthrough.choose_feedthrough`)."""
    import sysid

    from ..subspace.estimator import SubspaceEstimator

    if isinstance(order, str):
        if order != "auto":
            raise DataError(f"order must be an integer, a sequence of integers or 'auto', "
                            f"got {order!r}")
        est = SubspaceEstimator(data, kw.get("horizon"))
        sel = est.order_selection(feedthrough=bool(feedthrough))
        model = sysid.ssest(data, sel["order"], feedthrough=feedthrough, **kw)
        model.info["order_selection"] = sel
        return model
    sel = _order(data, order, bool(feedthrough), kw)
    model = sysid.ssest(data, sel["order"], feedthrough=feedthrough, **kw)
    model.info["order_selection"] = sel
    return model


def _order(data: IOData, order: Any, feedthrough: bool, kw: dict[str, Any]) -> dict[str, Any]:
    """An order: given, "auto" (subspace cross-validation) or the best of a sequence."""
    import sysid

    from ..subspace.estimator import SubspaceEstimator

    if isinstance(order, (int, np.integer)):
        return {"order": int(order), "criterion": "given", "reason": "given", "table": {}}
    if isinstance(order, str):
        return SubspaceEstimator(data, kw.get("horizon")).order_selection(
            feedthrough=feedthrough)
    orders = sorted({int(o) for o in np.ravel(order)})
    if not orders or orders[0] < 1:
        raise DataError(f"orders must be positive integers, got {order!r}")
    fit_part, held = split(data)
    table: dict[int, float] = {}
    quiet = dict(kw, progress=False)
    for n in orders:
        try:
            m = sysid.ssest(fit_part, n, feedthrough=feedthrough, **quiet)
            table[n] = simulation_fit(m, held)
        except Exception:  # noqa: BLE001 - an order the part cannot support
            table[n] = -np.inf
    n, why = choose(table, TOL)
    return {"order": n, "criterion": "held-out simulation fit of refined models",
            "reason": why + " (refined on the first 2/3 of the record, scored on the last 1/3)",
            "table": table}
