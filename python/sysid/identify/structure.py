"""The order of a refined state-space model chosen from the data (``ssest`` with
``order="auto"`` or a range of orders)."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .._checks import as_orders, reissue
from ..data.iodata import IOData
from ..errors import DataError

__all__ = ["refined_order", "ssest_select", "split"]


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
    decided before, by :func:`sysid.subspace.feedthrough.choose_feedthrough`): ``"auto"``,
    the subspace models' held-out simulation fit; a sequence of orders, the BIC of the
    refined models (:func:`refined_order`)."""
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
    sel, model = refined_order(data, order, bool(feedthrough), kw)
    model.info["order_selection"] = sel
    return model


def refined_order(data: IOData, order: Any, feedthrough: bool, kw: dict[str, Any]
                  ) -> tuple[dict[str, Any], Any]:
    """The order of a sequence whose model, refined on the whole record, has the lowest BIC
    of its simulation errors (:func:`sysid.identify.board.bic`: ``N log det`` of the error
    covariance, initial state and output offsets fitted, plus ``log N`` per parameter), and
    that model.

    Refined models scored on one held-out part (the last third) ranked the orders by how
    that stretch differs from the rest, and each order's model was fitted on two thirds of
    the record (the winding record: order 1, 50 % on validation data, against 74 % for the
    lowest BIC's order 4); the BIC uses the whole record for every model and pays for each
    parameter, as MATLAB's ``ssest`` order comparison does with its information criteria.
    """
    import sysid

    from .board import bic

    orders = as_orders(order)
    table: dict[int, float] = {}
    best: tuple[float, int, Any, list[Any]] | None = None
    for n in orders:
        # each order's warnings are kept, and only the chosen model's are shown
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            try:
                m = sysid.ssest(data, n, feedthrough=feedthrough, **kw)
                table[n] = bic(m, data)
            except Exception:  # noqa: BLE001 - an order the record cannot support
                table[n] = np.inf
                continue
        if np.isfinite(table[n]) and (best is None or table[n] < best[0]):
            best = (table[n], n, m, list(said))
    if best is None:
        raise DataError(f"no order of {orders} gave a refined model that simulates the record")
    b, n, model, said = best
    reissue(said)
    return {"order": n, "criterion": "BIC of refined models",
            "reason": f"lowest BIC {b:.4g} at order {n} (every order refined on the whole "
                      "record; BIC of the simulation errors)", "table": table}, model
