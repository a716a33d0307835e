"""One offset check for every linear estimator: a mean much larger than the variation.

A linear model ``y = G(q) u + H(q) e`` has no constant term, so a record whose channels sit
on offsets (a temperature in kelvin, a flow around its operating point) makes the estimator
spend its parameters on the offset instead of the dynamics: a pole near 1, a wrong static
gain, validation fits far below zero. Every linear estimator (subspace, ``ssest``/``pem``,
ARX, ARMAX, OE, BJ, IV) asks :func:`check_offsets` first (which also refuses channels of
magnitudes out of double precision's range), and one
:class:`~sysid.errors.OffsetWarning` says what to do: ``sysid.detrend(data,
return_trend=True)`` (then ``trend.apply(validation)`` for the validation data), or
:func:`sysid.identify`, which removes the offsets and restores them in its predictions.

A channel is flagged when ``|mean| > 10 std`` (the offset dwarfs the variation), unless the
record was detrended (:attr:`IOData.has_trend`), the channel is constant
(:func:`sysid._checks.constant_channels`: the estimators refuse it as such), or its values
reach zero (``min <= 0 <= max``): a step test from rest (an input switched on from 0, an
output measured from its initial value) has a mean far above its standard deviation, made by
the step itself; removing that mean, as the warning said, moved the record's start off rest.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import check_magnitudes, constant_channels, record_stats, user_stacklevel
from ..errors import OffsetWarning

__all__ = ["check_offsets", "remove_means", "OFFSET_RATIO"]

#: A channel whose mean exceeds this many standard deviations is flagged.
OFFSET_RATIO = 10.0


def offsets(data: Any, stats: dict[int, Any] | None = None) -> list[tuple[str, str, float, float]]:
    """``(kind, name, mean, std)`` of every channel with ``|mean| > OFFSET_RATIO std > 0``
    (empty for a detrended record); ``stats``: the record's :func:`~sysid._checks.record_stats`
    when the caller has them."""
    exps = list(data.experiments)
    if getattr(data, "has_trend", False):
        stats = None  # only some experiments count: their own statistics below
        # a detrended record: only experiments merged in raw (their trend all zero: nothing
        # was removed from them) can still sit on an offset
        kept = getattr(data, "_exps", None)
        exps = [] if kept is None else [
            (e.u, e.y) for e in kept
            if not (np.any(e.tu) or np.any(e.ty))]
        if not exps:
            return []
    out = []
    for kind, idx, names in (("input", 0, data.input_names), ("output", 1, data.output_names)):
        if not names:
            continue
        if stats is not None:
            if idx not in stats:
                continue
            _, mean, std = stats[idx]
        else:  # one pass in Rust (NumPy's column reductions of (samples, channels) are slow)
            _, mean, std = _sysid.channel_stats(
                [np.ascontiguousarray(e[idx], float) for e in exps])
        flagged = [j for j in range(len(names)) if abs(mean[j]) > OFFSET_RATIO * std[j] > 0]
        if flagged:  # a constant channel is the estimators' constancy check's to refuse
            flat = constant_channels([np.asarray(e[idx]) for e in exps], "all")
            out += [(kind, str(names[j]), float(mean[j]), float(std[j])) for j in flagged
                    if not flat[j] and not _reaches_zero(exps, idx, j)]
    return out


def _reaches_zero(exps: list[Any], idx: int, j: int) -> bool:
    """Whether channel ``j`` of side ``idx`` takes zero within its range (``min <= 0 <=
    max`` over every experiment): then its mean is made by its excursions from zero (a step
    test from rest: a heater switched from 0 to 50 %, a temperature measured from its start),
    a level the data visit, not an offset they never leave; removing the mean would move the
    start off rest instead."""
    lo, hi = np.inf, -np.inf
    for e in exps:
        x = np.asarray(e[idx])
        if x.shape[0]:
            col = x[:, j]
            lo, hi = min(lo, float(np.min(col))), max(hi, float(np.max(col)))
    return bool(lo <= 0.0 <= hi)


def check_offsets(data: Any, *, stacklevel: int | None = None, who: str = "identification",
                  stats: dict[int, Any] | None = None) -> bool:
    """Warn (:class:`~sysid.errors.OffsetWarning`) when a channel of ``data`` sits on an offset
    much larger than its variation and the record was not detrended; True if it warned. The
    warning points at the first caller outside sysid (or ``stacklevel`` frames up).

    First the range check of every estimator (:func:`sysid._checks.check_magnitudes`, its
    message naming ``who``): a channel whose values overflow or underflow products of
    samples raises a :class:`~sysid.errors.DataError` that says to rescale it. Both read the
    record's :func:`~sysid._checks.record_stats` (``stats``, when the caller has them).

    Examples
    --------
    >>> import numpy as np, sysid, warnings
    >>> u = np.random.default_rng(0).standard_normal(200)
    >>> raw = sysid.IOData(u=u, y=300.0 + np.cumsum(u) * 0.01, dt=1.0)
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     check_offsets(raw)
    True
    >>> w[0].category.__name__
    'OffsetWarning'
    >>> check_offsets(sysid.detrend(raw, "mean"))
    False
    """
    from .iodata import require_record

    require_record(data, "check_offsets", pairs=False)
    stats = record_stats(data) if stats is None else stats
    check_magnitudes(data, who, stats)
    found = offsets(data, stats)
    if not found:
        return False
    what = "; ".join(f"{kind} {name} has an offset ({mean:.4g}) much larger than its variation "
                     f"(std {std:.3g})" for kind, name, mean, std in found[:4])
    more = f" (and {len(found) - 4} more channels)" if len(found) > 4 else ""
    warnings.warn(OffsetWarning(
        f"{what}{more}, and the data were not detrended: a linear model has no constant term "
        "and spends its parameters on the offset (a pole near 1, a wrong static gain, "
        "validation fits far below zero). Remove it first: d, trend = sysid.detrend(data, "
        "'mean', return_trend=True), then trend.apply(validation) for other records (command "
        "line: --detrend mean); or use sysid.identify(data), which removes it and restores it "
        "in its predictions"), stacklevel=user_stacklevel() if stacklevel is None else stacklevel)
    return True


def remove_means(data: Any) -> tuple[Any, np.ndarray, np.ndarray]:
    """The record with every channel's mean over all experiments removed, and those means
    (inputs, outputs): the centring :func:`sysid.identify` records and
    :func:`sysid.advice`'s model-based checks use.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d, mu, my = remove_means(sysid.IOData(u=np.arange(4.0), y=np.ones(4) * 3))
    >>> mu.tolist(), my.tolist(), d.y.ravel().tolist()
    ([1.5], [3.0], [0.0, 0.0, 0.0, 0.0])
    """
    from .iodata import IOData

    u = np.vstack([e[0] for e in data.experiments])
    y = np.vstack([e[1] for e in data.experiments])
    mu, my = u.mean(0), y.mean(0)
    kw = {"dt": data.dt, "input_names": data.input_names, "output_names": data.output_names}
    us = [e[0] - mu for e in data.experiments]
    ys = [e[1] - my for e in data.experiments]
    out = IOData(u=us[0], y=ys[0], **kw) if len(us) == 1 else IOData(u=us, y=ys, **kw)
    return out, mu, my
