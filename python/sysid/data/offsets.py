"""One offset check for every linear estimator: a mean that costs a linear model its fit.

A linear model ``y = G(q) u + H(q) e`` has no constant term, so a record whose channels sit
on offsets (a temperature in kelvin, a flow around its operating point) makes the estimator
spend its parameters on the offset instead of the dynamics: a pole near 1, a wrong static
gain, validation fits far below zero. Every linear estimator (subspace, ``ssest``/``pem``,
ARX, ARMAX, OE, BJ, IV) asks :func:`check_offsets` first (which also refuses channels of
magnitudes out of double precision's range), and one
:class:`~sysid.errors.OffsetWarning` says what to do: ``sysid.detrend(data,
return_trend=True)`` (then ``trend.apply(validation)`` for the validation data), or
:func:`sysid.identify`, which removes the offsets and restores them in its predictions.

A channel is flagged when ``|mean| > 10 std`` (the offset dwarfs the variation), or when
``|mean| > 1.5 std`` and the record's offsets cost a quick ARX fit more than 5 fit points
(:func:`offset_effect`: the simulation fit of ARX(2, 2, 1) on the raw record against the same
on the mean-removed one). Measured on the 36 real records of the benchmark tables
(``benches/offset_check.py``, ``benches/results/realdata_fresh2.md``): a TCLab log under PID
with means of 3-9 standard deviations lost 240-320 fit points in ``n4sid`` and ``oe`` on raw
data without a word; an offset the static gain carries (the output's mean is the gain times
the input's) costs nothing and is not flagged. A channel is not flagged when the
record was detrended (:attr:`IOData.has_trend`), the channel is constant
(:func:`sysid._checks.constant_channels`: the estimators refuse it as such), or its values
reach zero (``min <= 0 <= max``): a step test from rest (an input switched on from 0, an
output measured from its initial value) has a mean far above its standard deviation, made by
the step itself; removing that mean, as the warning said, moved the record's start off rest.
Such a channel is flagged only when the quick ARX fit loses more than ``EFFECT_LIMIT`` with the
offsets left in (whatever its ratio): a motor-generator record (generator voltage 4741 +- 1084,
one sample below zero at its start) lost 50-60 validation fit points in every estimator on
raw data without a word. When the quick fit does not describe even the mean-removed record
(its simulation fit below zero: a long delay, a dominant disturbance), it cannot judge, and
the ratio above ``SCREEN_RATIO`` decides alone (steps from rest still exempt): the CED
record (output mean 1.9 std) and a sine-driven car (2.2 std) lost 27-152 fit points raw
without a word. A time series (no inputs: ``ar``, ``arma``, subspace time-series fits) is
screened alike by a quick AR(2) fit's one-step prediction errors, raw against mean-removed.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import check_magnitudes, constant_channels, record_stats, user_stacklevel
from ..errors import OffsetWarning

__all__ = ["check_offsets", "remove_means", "offset_effect", "OFFSET_RATIO", "SCREEN_RATIO",
           "EFFECT_LIMIT"]

#: A channel whose mean exceeds this many standard deviations is flagged.
OFFSET_RATIO = 10.0
#: A channel whose mean exceeds this many standard deviations (but not OFFSET_RATIO) is
#: flagged when the offsets cost a quick fit more than EFFECT_LIMIT (:func:`offset_effect`).
SCREEN_RATIO = 1.5
#: The share of simulation fit (fit % / 100) a quick ARX fit of the raw record may lose
#: against the same fit of the mean-removed record before the offsets are flagged.
EFFECT_LIMIT = 0.05


def offset_effect(data: Any, *, from_rest: bool = False) -> float:
    """The simulation fit a quick ARX model (``na = 2, nb = 2, nk = 1``, least squares on every
    output and input) of ``data`` loses when the channels' means are left in, as a share (fit
    % / 100; the largest over the outputs): the fit of the ARX model of the raw record minus
    that of the same structure fitted on the mean-removed record (its means restored), both
    simulated on the record from its first two measured samples, or from rest with
    ``from_rest`` (for the estimators that simulate from rest: ``tfest`` and ``procest`` with
    ``initial_state="zero"``; on the dryer and heating-system records ``tfest(data, 2)`` lost
    9 and 33 fit points to offsets of 3-6 standard deviations that cost the polynomial
    estimators, which fit their initial conditions, nothing). A linear model has no
    constant term: an offset the dynamics cannot carry (an output mean that is not the static
    gain times the input mean) pulls its poles toward 1 and its gain off. For a time series
    (no inputs), the AR(2) screen of :func:`_ar_effect` instead. Zero for a record too short
    for the fit; ``inf`` when the raw fit diverges;
    NaN when the quick model does not describe even the mean-removed record (its fit below
    zero or diverging): then it cannot tell what the offsets cost.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(400)
    >>> y = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]]).simulate(u)[:, 0]
    >>> y = y + 0.3 * rng.standard_normal(400)
    >>> offset_effect(sysid.IOData(u=u, y=y)) < 0.01  # no offset: nothing lost
    True
    >>> offset_effect(sysid.IOData(u=u + 3.0, y=y + 40.0)) > 0.1  # y's 40 is not 5 * 3
    True
    """
    if not data.input_names:
        return _ar_effect([np.asarray(y, float) for _, y in data.experiments])
    exps = [(np.asarray(u, float), np.asarray(y, float)) for u, y in data.experiments]
    exps = [(u, y) for u, y in exps if u.shape[0] > 10]
    if sum(u.shape[0] for u, _ in exps) < 40:
        return 0.0
    mu = np.vstack([u for u, _ in exps]).mean(0)
    my = np.vstack([y for _, y in exps]).mean(0)
    with np.errstate(all="ignore"):
        raw = _arx_sim_fit(exps, from_rest)
        cen = _arx_sim_fit([(u - mu, y - my) for u, y in exps], from_rest)
    if not np.all(np.isfinite(cen)) or np.min(cen) < 0:
        return float("nan")  # the quick model does not describe the record even without the
        # offsets: what it loses with them says nothing
    loss = np.where(np.isfinite(raw), (cen - raw) / 100.0, np.inf)
    return float(max(0.0, np.max(loss)))


def _ar_effect(ys: list[np.ndarray]) -> float:
    """A time series' :func:`offset_effect`: how much larger (relative RMS, the largest over
    the outputs) the one-step prediction errors of the mean-removed series are under an AR(2)
    model fitted by least squares on the raw series than under the same fit of the
    mean-removed one. An AR model has no constant term either: an offset pulls a pole toward
    1 and bends the spectrum (``y = 1.5 y(-1) - 0.7 y(-2) + e`` 3.4 standard deviations off
    zero: poles 0.96 and 0.63 instead of 0.75 +- 0.37j, errors 13 % larger), while a series
    with a pole near 1 already loses almost nothing to it (AR(1) at 0.95: 1 %). Zero for a
    series too short for the fit; NaN when even the mean-removed series is not predicted."""
    ys = [y for y in ys if y.shape[0] > 10]
    if sum(y.shape[0] for y in ys) < 40:
        return 0.0
    my = sum(y.sum(axis=0) for y in ys) / sum(y.shape[0] for y in ys)
    worst = 0.0
    for j in range(ys[0].shape[1]):
        cols = [np.ascontiguousarray(y[:, j]) for y in ys]
        with np.errstate(all="ignore"):
            raw = _ar2(cols)
            cen = [c - my[j] for c in cols]
            mod = _ar2(cen)
            e_raw, e_cen = _ar2_error(cen, raw), _ar2_error(cen, mod)
        if not (np.isfinite(e_cen) and e_cen > 0):
            return float("nan")
        worst = max(worst, float(np.sqrt(e_raw / e_cen)) - 1.0 if np.isfinite(e_raw)
                    else np.inf)
    return worst


def _ar2(cols: list[np.ndarray]) -> np.ndarray:
    """``(a1, a2)`` of ``y_t = a1 y_{t-1} + a2 y_{t-2} + e_t`` fitted over the experiments
    ``cols`` by the core's least squares (``_sysid.arx_fit``, as :func:`sysid.ar`'s
    ``"ls"``); NaN when the fit fails."""
    try:
        fits = _sysid.arx_fit([(np.zeros((c.shape[0], 0)), c[:, None]) for c in cols],
                              [[2]], [[]], [[]], 0.0, None)
    except Exception:  # noqa: BLE001 - a fit that fails fits nothing
        return np.full(2, np.nan)
    return -np.asarray(fits[0]["a"][0], float)  # A(q) y = e: y_t = -a1 y_{t-1} - a2 y_{t-2}


def _ar2_error(cols: list[np.ndarray], a: np.ndarray) -> float:
    """The mean squared one-step prediction error of the AR(2) coefficients ``a`` on
    ``cols``."""
    err, n = 0.0, 0
    for c in cols:
        e = c[2:] - a[0] * c[1:-1] - a[1] * c[:-2]
        err, n = err + float(e @ e), n + e.shape[0]
    return err / max(n, 1)


def _arx_sim_fit(exps: list[tuple[np.ndarray, np.ndarray]], from_rest: bool = False
                 ) -> np.ndarray:
    """Per output, the NRMSE fit (%) of an ARX(2, 2, 1) model fitted by the core's least
    squares (``_sysid.arx_fit``, as :func:`sysid.arx`) on ``exps`` and simulated on them from
    their first two measured outputs, or from rest (-inf if it diverges or the fit fails)."""
    ny, nu = exps[0][1].shape[1], exps[0][0].shape[1]
    try:
        fits = _sysid.arx_fit([(np.ascontiguousarray(u), np.ascontiguousarray(y))
                               for u, y in exps], [[2] * ny] * ny, [[2] * nu] * ny,
                              [[1] * nu] * ny, 0.0, None)
    except Exception:  # noqa: BLE001 - a fit that fails fits nothing
        return np.full(ny, -np.inf)
    # A(q) y = B(q) u: y_t = -a1 y_{t-1} - a2 y_{t-2} + b1 u_{t-1} + b2 u_{t-2}
    a = np.array([np.asarray(f["a"], float) for f in fits])  # (ny, ny, 2)
    bb = np.array([np.asarray(f["b"], float) for f in fits])  # (ny, nu, 2)
    a1, a2, b1, b2 = -a[:, :, 0], -a[:, :, 1], bb[:, :, 0], bb[:, :, 1]
    # the state (y_t, y_{t-1}, u_{t-1}), simulated in Rust from the measured first samples
    n = 2 * ny + nu
    A = np.zeros((n, n))
    A[:ny, :ny], A[:ny, ny:2 * ny], A[:ny, 2 * ny:] = a1, a2, b2
    A[ny:2 * ny, :ny] = np.eye(ny)
    B = np.vstack([b1, np.zeros((ny, nu)), np.eye(nu)])
    C, D = np.hstack([np.eye(ny), np.zeros((ny, ny + nu))]), np.zeros((ny, nu))
    err = np.zeros(ny)
    yall = np.vstack([y[2:] for _, y in exps])
    for u, y in exps:
        try:
            x0 = np.zeros(n) if from_rest else np.concatenate([y[1], y[0], u[0]])
            sim = _sysid.simulate(A, B, C, D, np.ascontiguousarray(u[1:]), x0)
        except Exception:  # noqa: BLE001 - a simulation that fails fits nothing
            return np.full(ny, -np.inf)
        err += np.sum((y[2:] - np.asarray(sim)[1:]) ** 2, axis=0)
    dev = np.sum((yall - yall.mean(0)) ** 2, axis=0)
    fit = 100.0 * (1.0 - np.sqrt(err / np.where(dev > 0, dev, np.nan)))
    return np.where(np.isfinite(fit), fit, -np.inf)


def offsets(data: Any, stats: dict[int, Any] | None = None
            ) -> list[tuple[str, str, float, float]]:
    """``(kind, name, mean, std)`` of every channel flagged (empty for a detrended record):
    ``|mean| > OFFSET_RATIO std > 0``, or ``|mean| > SCREEN_RATIO std`` when the offsets cost
    a quick fit more than :data:`EFFECT_LIMIT` (:func:`offset_effect`; a record without such
    a channel is not fitted) or the quick fit cannot judge (and the channel does not reach
    zero); ``stats``: the record's :func:`~sysid._checks.record_stats`
    when the caller has them."""
    return _flagged(data, stats)[0]


def _flagged(data: Any, stats: dict[int, Any] | None = None, from_rest: bool = False
             ) -> tuple[list[tuple[str, str, float, float]], float | None]:
    """:func:`offsets` and the :func:`offset_effect` that flagged them (None: by the ratio;
    NaN: by the ratio above ``SCREEN_RATIO`` because the quick fit could not judge)."""
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
            return [], None
    big, screened, at_zero = [], [], set()
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
        flagged = [j for j in range(len(names)) if abs(mean[j]) > SCREEN_RATIO * std[j] > 0]
        if flagged:  # a constant channel is the estimators' constancy check's to refuse
            flat = constant_channels([np.asarray(e[idx]) for e in exps], "all")
            for j in flagged:
                if flat[j]:
                    continue
                row = (kind, str(names[j]), float(mean[j]), float(std[j]))
                # a channel that reaches zero (a step from rest) is flagged only when the
                # quick fit says its offset costs the fit, whatever its ratio
                zero = _reaches_zero(exps, idx, j)
                if zero:
                    at_zero.add(row)
                (screened if zero or abs(mean[j]) <= OFFSET_RATIO * std[j] else big).append(row)
    if big or not screened:
        return big, None
    raw = data
    if getattr(data, "has_trend", False):  # the raw experiments alone
        from .iodata import IOData

        us, ys = [e[0] for e in exps], [e[1] for e in exps]
        kw = {"dt": data.dt, "input_names": data.input_names, "output_names": data.output_names}
        raw = IOData(u=us[0], y=ys[0], **kw) if len(us) == 1 else IOData(u=us, y=ys, **kw)
    effect = offset_effect(raw, from_rest=from_rest)
    if np.isnan(effect):  # the quick fit cannot judge (it fails on the mean-removed record
        # too): the ratio alone decides, steps from rest still exempt; the CED record
        # (output mean 1.9 std) and a sine-driven car (2.2 std) lost 27-152 fit points raw
        kept = [r for r in screened if r not in at_zero]
        return (kept, effect) if kept else ([], None)
    return (screened, effect) if effect > EFFECT_LIMIT else ([], None)


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
                  stats: dict[int, Any] | None = None, from_rest: bool = False,
                  fix: str | None = None) -> bool:
    """Warn (:class:`~sysid.errors.OffsetWarning`) when a channel of ``data`` sits on an offset
    much larger than its variation and the record was not detrended; True if it warned. The
    warning points at the first caller outside sysid (or ``stacklevel`` frames up).

    First the range check of every estimator (:func:`sysid._checks.check_magnitudes`, its
    message naming ``who``): a channel whose values overflow or underflow products of
    samples raises a :class:`~sysid.errors.DataError` that says to rescale it. Both read the
    record's :func:`~sysid._checks.record_stats` (``stats``, when the caller has them).
    ``from_rest``: the caller's model has no initial state to carry an offset (a transfer
    function simulated from rest, an FIR): the quick fit that screens moderate offsets is
    simulated from rest too (:func:`offset_effect`). ``fix``: the caller's own remedy, added
    to the warning's advice (with ``from_rest`` and no ``fix``: fit the initial state).

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
    found, effect = _flagged(data, stats, from_rest)
    if not found:
        return False
    if effect is None:
        what = "; ".join(f"{kind} {name} has an offset ({mean:.4g}) much larger than its "
                         f"variation (std {std:.3g})" for kind, name, mean, std in found[:4])
    else:
        what = "; ".join(f"{kind} {name} has an offset ({mean:.4g}, {abs(mean) / std:.1f} "
                         f"times its std {std:.3g})" for kind, name, mean, std in found[:4])
    more = f" (and {len(found) - 4} more channels)" if len(found) > 4 else ""
    if effect is not None and np.isnan(effect):
        more += (f"; a quick {'ARX' if data.input_names else 'AR'} fit does not describe even "
                 "the mean-removed record, so what "
                 "the offset costs cannot be screened: a mean this size usually costs linear "
                 "models their fit")
    elif effect is not None and not data.input_names:
        more += (f"; a quick AR(2) fit of the raw series predicts the mean-removed series with "
                 f"{100 * effect:.0f} % larger one-step errors than the same fit of the "
                 "mean-removed series")
    elif effect is not None:
        lost = "all of its fit" if not np.isfinite(effect) else f"{100 * effect:.0f} fit points"
        rest = " simulated from rest" if from_rest else ""
        more += (f"; a quick ARX fit of the raw record{rest} loses {lost} against the same "
                 "fit of the mean-removed record")
    warnings.warn(OffsetWarning(
        f"{what}{more}, and the data were not detrended: a linear model has no constant term "
        "and spends its parameters on the offset (a pole near 1, a wrong static gain, "
        "validation fits far below zero). Remove it first: d, trend = sysid.detrend(data, "
        "'mean', return_trend=True), then trend.apply(validation) for other records (command "
        "line: --detrend mean); or use sysid.identify(data), which removes it and restores it "
        "in its predictions" + (f" ({fix})" if fix else
                                " (or fit the initial state: initial_state='estimate')"
                                if from_rest else "")),
        stacklevel=user_stacklevel() if stacklevel is None else stacklevel)
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
