"""What the command line's default path needs from :func:`sysid.identify`: the chosen model
of the deviations, the records with its offsets removed, and a one-model order table."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..data.iodata import IOData

__all__ = ["prepare"]


def prepare(est_data: IOData, val_data: IOData | None, preprocessing: dict[str, Any] | None,
            bars: bool | None, say: Callable[[str], None]) -> dict[str, Any]:
    """Run :func:`sysid.identify` and return ``model``, ``selection``, ``est``, ``val`` and
    ``result`` for the command line's validation and report."""
    from ..validation.criteria import select_order
    from .core import identify

    say("sysid.identify: candidate families and orders, chosen on held-out parts of the "
        "estimation data")
    res = identify(est_data, val_data, progress=bars)
    say(f"chosen: {res.choice} ({res.seconds:.1f} s)")
    model = res.model.statespace
    model.info["preprocessing"] = {**model.info.get("preprocessing", {}),
                                   **dict(preprocessing or {}),
                                   "identify_offsets": {"u": res.model.u_offset.tolist(),
                                                        "y": res.model.y_offset.tolist()}}
    est = res.model.remove_offsets(est_data)
    val = res.model.remove_offsets(val_data) if val_data is not None else None
    sel = select_order(est, models=[model], validation=val)
    # the one-model table's own reason ("order n (models) chosen by validation") is not why:
    # identify chose it, on blocks held out of the estimation data
    sel.reason = (f"{res.choice}, chosen by sysid.identify on blocks held out of the "
                  "estimation data (its leaderboard: leaderboard.csv beside the report)")
    return {"model": model, "selection": sel, "est": est, "val": val, "result": res}
