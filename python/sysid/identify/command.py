"""What the command line's default path needs from :func:`sysid.identify`: the chosen model
of the deviations, the records with its offsets removed, and a one-model order table."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import DataError

__all__ = ["prepare", "refuse_still_part", "write_leaderboard", "uniform_time", "RESAMPLE_HINT"]

#: what the command says of a time column with gaps or jitter
RESAMPLE_HINT = ("pass --resample median (the stamps' median spacing) or --resample SECONDS "
                 "to interpolate the record onto a uniform grid")


def uniform_time(u: np.ndarray, y: np.ndarray, t: np.ndarray, column: str,
                 resample: str | None, resample_gap: float, say: Callable[[str], None],
                 pre: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """``u``, ``y``, the time column ``t`` (seconds) and the sample time of a file's record:
    its stamps' own when they are uniform (:func:`sysid.sample_time`; gaps and jitter are
    refused, naming ``--resample``), else, with ``resample`` (``--resample``: ``"median"``
    or seconds), the record interpolated onto a uniform grid as
    ``IOData.from_csv(resample=...)`` does it (:func:`sysid.data.raw.resample_stamps`; a gap
    over ``resample_gap`` sample times refused), said and noted in ``pre["resampled"]``.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.array([0.0, 0.11, 0.19, 0.3, 0.42, 0.5])
    >>> pre = {}
    >>> u, y, tt, dt = uniform_time(t[:, None], 2 * t[:, None], t, "time", "0.1", 5.0,
    ...                             lambda s: None, pre)
    >>> dt, y.ravel(), pre["resampled"]["n_stamps"]
    (0.1, array([0. , 0.2, 0.4, 0.6, 0.8, 1. ]), 6)
    """
    from ..data.units import sample_time

    if resample is None:
        try:
            return u, y, t, sample_time(t, remedy=RESAMPLE_HINT)
        except DataError as e:
            raise DataError(f"time column {column!r}: {e}") from None
    from dataclasses import asdict

    from ..data.raw import resample_stamps

    try:
        step: float | str = float(resample)
    except ValueError:
        step = resample
    try:
        rec = resample_stamps(IOData, [(t, u if u.shape[1] else None, y)], step,
                              resample_gap, {}, option="--resample-gap ")
    except DataError as e:
        raise DataError(f"time column {column!r}: {e}") from None
    say(str(rec.resampling))
    pre["resampled"] = asdict(rec.resampling)
    return rec.u, rec.y, rec.time, rec.dt


def refuse_still_part(u: np.ndarray, y: np.ndarray, k: int, split: str,
                      inputs: list[str], outputs: list[str], centred: bool = True) -> None:
    """Refuse a channel constant in the estimation part (the first ``k`` samples) of a file
    in which it changes later, naming the split: the estimators' own refusal said "input
    torque is 0.05 in every sample" of a motor step test whose torque steps at sample 10 000,
    where the default ``--split 0.5`` ends the estimation part. With ``centred`` (the means
    are removed before the fit), inputs on one line about their means there and apart later
    are refused the same way.

    Examples
    --------
    >>> import numpy as np
    >>> u = np.r_[np.zeros(6), np.ones(4)][:, None]
    >>> refuse_still_part(u, np.arange(10.0)[:, None], 5, "0.5", ["u"], ["y"])
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: input u is 0 in every sample of the estimation part (samples 0-4 \
of 10, --split 0.5) and first changes at sample 6: nothing to identify its effect from; pass \
a --split past that sample (a larger fraction, or a sample count above 6)
    """
    for kind, x, names in (("input", u, inputs), ("output", y, outputs)):
        for j, name in enumerate(names):
            part, rest = x[:k, j], x[k:, j]
            if part.size and rest.size and np.all(part == part[0]) and np.any(rest != part[0]):
                first = k + int(np.flatnonzero(rest != part[0])[0])
                raise DataError(
                    f"{kind} {name} is {part[0]:g} in every sample of the estimation part "
                    f"(samples 0-{k - 1} of {x.shape[0]}, --split {split}) and first changes at "
                    f"sample {first}: nothing to identify its effect from; pass a --split past "
                    f"that sample (a larger fraction, or a sample count above {first})")
    if centred and u.shape[1] > 1 and 0 < k < u.shape[0]:
        _refuse_dependent_part(u, k, split, inputs)


def _refuse_dependent_part(u: np.ndarray, k: int, split: str, inputs: list[str]) -> None:
    """Refuse inputs dependent about their means (their values on one line or plane) in the
    estimation part only: the estimators, fitted after the means are removed, said "linearly
    dependent in every sample ... a channel recorded twice?" of two heaters' controller
    outputs that moved along one line for the first 1012 of 1936 samples only."""
    from .._dependence import input_dependence

    c = u[:k] - u[:k].mean(axis=0)
    found = input_dependence([c])  # the estimators' test, on the centred estimation part
    if found is None:
        return  # independent there (constant and non-finite channels: their own refusals)
    _, v0, d = found
    v = v0 / d
    r = np.abs((u - u[:k].mean(axis=0)) @ v)
    off = np.flatnonzero(r > 1e-6 * float(np.max(np.abs(c) @ np.abs(v))))
    off = off[off >= k]
    if off.size == 0:
        return  # dependent in the whole file too: the estimators' own refusal says so
    names = [inputs[j] for j in range(len(inputs)) if abs(v0[j]) > 1e-3 * np.abs(v0).max()]
    first = int(off[0])
    raise DataError(
        f"inputs {', '.join(names)} lie on one line about their means in every sample of the "
        f"estimation part (samples 0-{k - 1} of {u.shape[0]}, --split {split}): one is a "
        f"constant plus a combination of the others there, so their effects cannot be told "
        f"apart; they part at sample {first}: pass a --split past that sample (a larger "
        f"fraction, or a sample count above {first})")


def prepare(est_data: IOData, val_data: IOData | None, preprocessing: dict[str, Any] | None,
            bars: bool | None, say: Callable[[str], None]) -> dict[str, Any]:
    """Run :func:`sysid.identify` and return ``model``, ``selection``, ``est``, ``val`` and
    ``result`` for the command line's validation and report."""
    from ..validation.criteria import select_order
    from .core import identify
    from .steptest import input_changes

    say("sysid.identify: " + ("candidate families and orders, chosen on held-out parts of the "
                              "estimation data" if input_changes(est_data) is None else
                              "a step test: process models fitted from rest, chosen by BIC"))
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
    how = ("on blocks held out of the estimation data" if res.score == "held-out" else
           "by BIC on the whole estimation data (a step test: no part can be held out)")
    sel.reason = (f"{res.choice}, chosen by sysid.identify {how} (its leaderboard: "
                  "leaderboard.csv beside the report)")
    return {"model": model, "selection": sel, "est": est, "val": val, "result": res}


def write_leaderboard(result: Any, path: Path) -> Path:
    """identify's leaderboard as a CSV beside the command line's report (no pandas needed)."""
    import csv

    from .._atomic import atomic_path
    from .result import COLUMNS

    with atomic_path(path) as tmp, open(tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS)
        for row in result.leaderboard:
            w.writerow(["" if row.get(c) is None else row.get(c) for c in COLUMNS])
    return path
