"""Order and feedthrough of a refined state-space model chosen from the data (``ssest`` with
``order="auto"``, a range of orders, or ``feedthrough="auto"``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import DataError
from ..validation.crossval import TOL, choose, simulation_fit

__all__ = ["ssest_select", "split", "significant_feedthrough"]


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


def significant_feedthrough(model: Any, level: float = 2.0) -> tuple[bool, str]:
    """Whether some entry of ``D`` exceeds ``level`` times its standard deviation."""
    unc = getattr(model, "uncertainty", None)
    D = np.asarray(model.D)
    if unc is None or not D.size:
        return bool(np.any(D != 0)), "no uncertainty: kept as estimated"
    idx = [i for i, nm in enumerate(unc.names) if nm.startswith("D[")]
    if not idx:
        return False, "D not estimated"
    std = np.asarray(unc.std)[idx]
    val = np.asarray(unc.theta)[idx]
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.abs(val) / std
    z = np.where(np.isfinite(z), z, 0.0)
    k = int(np.argmax(z))
    keep = bool(z[k] > level)
    why = (f"largest |D| / std = {z[k]:.1f} ({unc.names[idx[k]]}): "
           + ("significant, D kept" if keep else f"below {level:g}, D = 0"))
    return keep, why


def ssest_select(data: IOData, order: Any, *, feedthrough: Any, **kw: Any) -> Any:
    """:func:`sysid.ssest` with the order and/or the feedthrough chosen from the data."""
    import sysid

    from ..subspace.estimator import SubspaceEstimator

    if isinstance(feedthrough, str):
        if feedthrough != "auto":
            raise DataError(f"feedthrough must be True, False or 'auto', got {feedthrough!r}")
        n = _order(data, order, True, kw)
        with_d = sysid.ssest(data, n["order"], feedthrough=True, **kw)
        keep, why = significant_feedthrough(with_d)
        model = with_d if keep else sysid.ssest(data, n["order"], feedthrough=False, **kw)
        model.info["feedthrough_selection"] = {"feedthrough": keep, "reason": why}
        model.info["order_selection"] = n
        return model
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
