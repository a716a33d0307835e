"""Getting a record into shape before identification.

Every function takes an :class:`~sysid.IOData` and returns a new one (nothing is changed in
place). Steps that remove something a model should later give back (trends, offsets,
scaling) record it in :attr:`IOData.trend`, so that ``data.retrend()`` or
``data.trend.add_outputs(y_model)`` maps results back to engineering units.

Typical order (flight-test practice): segment selection (:func:`select_mode`,
:func:`select_mask`, :func:`drop_quiet`), spike and drop-out repair (:func:`despike`,
:meth:`IOData.from_raw`), :func:`detrend`, zero-phase filtering (:func:`lowpass`,
:func:`highpass`, :func:`bandpass`), :func:`resample` or :func:`decimate`, :func:`scale`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .._checks import as_nonnegative
from ..errors import DataError, InsufficientDataError
from .iodata import IOData, require_record
from .raw import _fill, _runs
from .segments import _Exp, channel_index, unknown_names

__all__ = [
    "find_spikes",
    "line_share",
    "despike",
    "detrend",
    "scale",
    "select_mode",
    "select_mask",
    "drop_quiet",
]


# --------------------------------------------------------------------------------------------
# spikes
# --------------------------------------------------------------------------------------------


def find_spikes(x: Any, window: int = 7, n_sigmas: float = 3.0) -> np.ndarray:
    """Hampel identifier: samples further than ``n_sigmas`` robust standard deviations
    (``1.4826 * MAD``) from the median of the ``window`` samples centred on them.

    Parameters
    ----------
    x : array_like
        ``(samples, channels)`` or 1-D.
    window : int
        Odd window length (samples).
    n_sigmas : float
        Threshold.

    Returns
    -------
    ndarray of bool
        Same shape as ``x`` (2-D), True at spikes.

    Notes
    -----
    The spread of a short window is a noisy estimate: with it alone (MATLAB's ``hampel``),
    4.7 % of the samples of white noise are flagged at 3 sigmas and window 7, and
    :func:`despike` replaced them. The local scale is floored at the channel's noise level
    from the median of its second differences (``|x[k+1] - 2 x[k] + x[k-1]|``, which a
    smooth signal leaves small): 0.26 % of white noise is then flagged (a normal's 0.27 %
    beyond 3 sigmas), 0.5 % of a slow AR(1) noise, and spikes of 5 sigmas and more are
    found as often as before. On piecewise-constant signals (binary inputs) step edges may
    be flagged: apply it to measured channels.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.data.preprocessing import find_spikes
    >>> rng = np.random.default_rng(0)
    >>> x = np.sin(np.arange(50) / 5.0) + 0.05 * rng.standard_normal(50); x[20] += 5.0
    >>> np.flatnonzero(find_spikes(x))
    array([20])
    """
    if isinstance(x, IOData):
        raise DataError("find_spikes takes one array (samples, channels), not a record: pass "
                        "data.y (or data.u) of one experiment, or repair the record with "
                        "sysid.despike(data)")
    arr = np.asarray(x, dtype=float)
    arr = arr[:, None] if arr.ndim == 1 else arr
    if arr.ndim != 2 or arr.shape[0] == 0:
        raise DataError(f"x must be 1-D or 2-D with samples, got shape {arr.shape}")
    if not isinstance(window, (int, np.integer)) or window < 3 or window % 2 == 0:
        raise DataError(f"window must be an odd integer >= 3, got {window!r}")
    if not n_sigmas > 0:
        raise DataError(f"n_sigmas must be positive, got {n_sigmas}")
    h = window // 2
    padded = np.pad(arr, ((h, h), (0, 0)), mode="edge")
    win = np.lib.stride_tricks.sliding_window_view(padded, window, axis=0)  # (n, ch, window)
    med = np.median(win, axis=2)
    mad = np.median(np.abs(win - med[:, :, None]), axis=2)
    # the first and last h samples: their windows cut at the record's ends (edge padding
    # repeated a spike at sample 0 until it was its own median)
    ends = np.r_[0:min(h, arr.shape[0]), max(arr.shape[0] - h, h):arr.shape[0]]
    if ends.size:
        cut = np.lib.stride_tricks.sliding_window_view(
            np.pad(arr, ((h, h), (0, 0)), constant_values=np.nan), window, axis=0)[ends]
        med[ends] = np.nanmedian(cut, axis=2)
        mad[ends] = np.nanmedian(np.abs(cut - med[ends][:, :, None]), axis=2)
    dev = np.abs(arr - med)
    # floor: round-off in constant stretches
    floor = 1e-9 * (np.max(np.abs(arr), axis=0) + 1e-300)
    sigma = 1.4826 * np.maximum(mad, floor)
    if arr.shape[0] >= 3:  # and the channel's noise level, from its second differences
        d2 = np.abs(arr[2:] - 2.0 * arr[1:-1] + arr[:-2])
        sigma = np.maximum(sigma, np.median(d2, axis=0) / (0.6745 * np.sqrt(6.0)))
    return dev > n_sigmas * sigma


#: an output sample is an isolated spike when its departure from the line through its two
#: neighbours exceeds this many robust standard deviations (1.4826 MAD) both of such
#: departures and of the output itself: far from its neighbours and far out in the record.
#: Conservative: on the shipped real records the largest clean value is about 6 (steep pH
#: titration jumps); a glitch of 20 standard deviations scores 10-40
SPIKE_SIGMAS = 10.0


def _spikes(x: np.ndarray) -> np.ndarray:
    """Samples of ``x`` that depart from the line through their neighbours by more than
    ``SPIKE_SIGMAS`` scales of such departures and of ``x`` itself, the largest of each run
    (a spike's neighbours depart by half as much). Scales from the central 98 % (a normal's
    2.33 sigma each side), so that neither a few spikes nor a signal that stands still most
    of the time (saturated, quantised: a median absolute deviation of 0) sets them."""
    dev = np.abs(x[1:-1] - (x[2:] + x[:-2]) / 2)
    lo, hi = np.quantile(x, [0.01, 0.99])
    s_x = (hi - lo) / 4.65
    s_dev = np.quantile(dev, 0.98) / 2.33
    bad = (dev > SPIKE_SIGMAS * s_dev) & (dev > SPIKE_SIGMAS * s_x)
    left = np.r_[0.0, dev[:-1]]
    right = np.r_[dev[1:], 0.0]
    return 1 + np.flatnonzero(bad & (dev >= left) & (dev >= right))


def spike_report(data: IOData) -> str | None:
    """Isolated spikes in the outputs (a logger glitch, a dropped sample written as a huge
    value), in words, or None: :func:`sysid.identify`'s check, far more conservative than
    :func:`find_spikes` (a global scale, not a local window: it flags a record, not samples
    to repair). Least squares bends every candidate to them (a few spikes of
    20 standard deviations take a 90 % record to 20 %), and nothing else in the search
    says why.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.data.preprocessing import spike_report
    >>> y = np.sin(np.arange(400) / 9.0); y[[50, 300]] += 30.0
    >>> print(spike_report(sysid.IOData(u=np.ones(400), y=y)))
    output y0: 2 isolated spike(s) (first at sample 50)
    """
    found = []
    for j, name in enumerate(data.output_names):
        hits: list[int] = []
        start = 0
        for _, y in data.experiments:
            x = y[:, j]
            if x.size >= 5:
                hits.extend((start + _spikes(x)).tolist())
            start += x.size
        if hits:
            found.append(f"output {name}: {len(hits)} isolated spike(s) (first at sample "
                         f"{hits[0]})")
    return "; ".join(found) or None


def repair_isolated_spikes(data: IOData) -> tuple[IOData, dict[str, list[int]]]:
    """``data`` with the outputs' isolated spikes (:func:`spike_report`'s conservative test)
    replaced by the mean of their two neighbours, and the samples repaired per output
    (counted over the experiments laid end to end, as :func:`spike_report` counts them).

    :func:`sysid.identify`'s repair: a single sample far from both neighbours and far out
    in the record is a logger glitch that every least-squares fit bends to (one such sample
    of 170 standard deviations takes a 99.9 % record to 79 %). Only a single sample is
    repaired: where the test still finds a spike within three samples once it is replaced
    (a glitch of several samples, a run of drop-out values), nothing there is changed (the
    mean of a glitch's neighbours would spread it), and neither is a spike within two
    samples of one in an input (an impulse the output answers through a direct term).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.data.preprocessing import repair_isolated_spikes
    >>> u = np.random.default_rng(0).standard_normal(400)
    >>> y = np.convolve(u, [0.5, 0.3, 0.2])[:400]; y[50] += 30.0
    >>> fixed, where = repair_isolated_spikes(sysid.IOData(u=u, y=y))
    >>> where, bool(abs(fixed.y[50, 0] - (y[49] + y[51]) / 2) < 1e-12)
    ({'y0': [50]}, True)
    >>> y[200:203] = -9999.0  # a run of drop-out values: left alone
    >>> repair_isolated_spikes(sysid.IOData(u=u, y=y))[1]
    {'y0': [50]}
    """
    where: dict[str, list[int]] = {}
    exps, start = [], 0
    for e in data._exps:
        u, y = e.u.copy(), e.y.copy()
        near: set[int] | None = None  # samples within two of an input's spike, when needed
        for j, name in enumerate(data.output_names):
            x = y[:, j]
            hits = _spikes(x) if len(x) >= 5 else []
            if len(hits) and near is None:
                near = {int(t) + d for k in range(u.shape[1]) for t in _spikes(u[:, k])
                        for d in range(-2, 3)} if u.shape[0] >= 5 else set()
            hits = [int(t) for t in hits if int(t) not in (near or set())]
            if not hits:
                continue
            mask = np.zeros((len(x), 1), dtype=bool)
            mask[hits] = True
            trial = _fill(x[:, None], mask)[:, 0]  # a lone sample: its neighbours' mean
            left = _spikes(trial)  # a spike still near one: not a single sample
            done = [t for t in hits if not np.any(np.abs(left - t) <= 3)]
            y[done, j] = trial[done]
            if done:
                where.setdefault(name, []).extend(start + t for t in done)
        exps.append(_Exp(u, y, e.t0, e.tu, e.ty))
        start += y.shape[0]
    if not where:
        return data, where
    return data._derive(exps), where


def despike(
    data: IOData,
    *,
    window: int = 7,
    n_sigmas: float = 3.0,
    channels: Sequence[str] | None = None,
    dropout: float | None = None,
) -> IOData:
    """Replace spikes (and drop-out values) by linear interpolation between good samples.

    Parameters
    ----------
    data : IOData
    window, n_sigmas :
        Hampel identifier settings (:func:`find_spikes`).
    channels : list of str, optional
        Channel names to repair; default every output.
    dropout : float, optional
        A sentinel value the logger writes when a sample is lost (e.g. ``0.0`` or
        ``-9999``); such samples are repaired too.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> y = np.sin(np.arange(50) / 5.0); y[20] = 9.0
    >>> d = sysid.despike(sysid.IOData(u=None, y=y))
    >>> bool(abs(d.y[20, 0] - np.sin(4.0)) < 0.02)
    True
    """
    require_record(data, "despike", pairs=False)
    if dropout is not None and not (
            isinstance(dropout, (int, float, np.integer, np.floating))
            and not isinstance(dropout, (bool, np.bool_)) and np.isfinite(dropout)):
        raise DataError(f"dropout must be the finite sentinel value the logger writes for a "
                        f"lost sample (e.g. 0.0 or -9999), or None, got {dropout!r}")
    names = data.output_names if channels is None else list(channels)
    iu = channel_index([n for n in names if n in data.input_names], data.input_names, "input")
    unknown = [n for n in names if n not in data.input_names and n not in data.output_names]
    if unknown:
        raise DataError(unknown_names(data, unknown))
    iy = [data.output_names.index(n) for n in names if n in data.output_names]
    exps = []
    for e in data._exps:
        u, y = e.u.copy(), e.y.copy()
        for arr, idx in ((u, iu), (y, iy)):
            if not idx:
                continue
            sub = arr[:, idx]
            bad = find_spikes(sub, window, n_sigmas)
            if dropout is not None:
                bad |= sub == dropout
            arr[:, idx] = _fill(sub, bad)
        exps.append(_Exp(u, y, e.t0, e.tu, e.ty))
    return data._derive(exps)


# --------------------------------------------------------------------------------------------
# trends and scaling
# --------------------------------------------------------------------------------------------


def line_share(x: Any) -> np.ndarray:
    """Per column of ``x`` (samples x channels; 1-D: one channel), the share of its variation
    that a straight line in time takes out (its R^2); 0 for a constant column or fewer than
    three samples.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.data.preprocessing import line_share
    >>> np.round(line_share(np.c_[np.arange(10.0), np.ones(10)]), 12).tolist()
    [1.0, 0.0]
    """
    x = np.asarray(x, dtype=float)
    x = x.reshape(x.shape[0], -1)
    if x.shape[0] < 3:
        return np.zeros(x.shape[1])
    t = np.linspace(-1.0, 1.0, x.shape[0])
    c = x - x.mean(axis=0)
    var = np.sum(c ** 2, axis=0)
    line = (t @ c) ** 2 / (t @ t)  # the variation the least-squares line takes out
    return np.where(var > 0, line / np.where(var > 0, var, 1.0), 0.0)


def _basis(n: int, kind: str, breakpoints: Sequence[int]) -> np.ndarray:
    k = np.arange(n, dtype=float)
    if kind in ("mean", "constant"):
        return np.ones((n, 1))
    # scaled time keeps the least-squares problem well conditioned
    s = k / max(n - 1, 1)
    cols = [np.ones(n), s]
    if kind == "piecewise":
        for b in breakpoints:
            cols.append(np.maximum(s - b / max(n - 1, 1), 0.0))
    return np.column_stack(cols)


def detrend(
    data: IOData,
    kind: str = "linear",
    *,
    breakpoints: Sequence[int] | Sequence[Sequence[int]] | None = None,
    inputs: bool = True,
    outputs: bool = True,
    return_trend: bool = False,
) -> Any:
    """Remove a mean, a line or a continuous piecewise line from every channel.

    The removed trend is recorded per sample (see :attr:`IOData.trend`), so
    ``detrend(d).retrend()`` gives ``d`` back and model outputs can be mapped back with
    ``data.trend.add_outputs(y_model, experiment)``.

    Parameters
    ----------
    data : IOData
    kind : {"mean", "linear", "piecewise"}
        Offset only; offset and slope; or a continuous piecewise-linear trend with knots at
        ``breakpoints``. Fitted per experiment and channel by least squares.
    breakpoints : sequence of int, optional
        Sample indices of the knots of a piecewise-linear trend (``"piecewise"``, or
        ``"linear"`` with breakpoints, as MATLAB's ``detrend(data, 1, breakpoints)``); a list
        of such sequences gives one per experiment.
    inputs, outputs : bool
        Which channels to detrend.
    return_trend : bool
        Also return the removed trend as a :class:`~sysid.Trend` that applies to other
        records (MATLAB's ``getTrend``): ``d, tr = detrend(data, return_trend=True)``, then
        ``tr.apply(validation)`` removes the same offsets and slopes from validation data,
        ``tr.restore(y)`` adds them back to model outputs and ``tr.attach(model)`` predicts
        raw data. Offsets and slopes (per second) are averaged over experiments, weighted by
        their samples; ``"piecewise"`` trends do not apply to other records.

    Returns
    -------
    IOData, or (IOData, Trend) with ``return_trend=True``

    Examples
    --------
    >>> import numpy as np, sysid
    >>> t = np.arange(100.0)
    >>> d = sysid.IOData(u=None, y=np.where(t < 50, t, 100 - t))
    >>> p = sysid.detrend(d, "piecewise", breakpoints=[50])
    >>> bool(np.abs(p.y).max() < 1e-9)
    True
    >>> est = sysid.IOData(u=np.arange(4.0), y=5.0 + 2.0 * np.arange(4.0), dt=0.5)
    >>> d2, tr = sysid.detrend(est, "linear", return_trend=True)
    >>> np.round(tr.y_offset, 9).tolist(), np.round(tr.y_slope, 9).tolist()   # per second
    ([5.0], [4.0])
    """
    require_record(data, "detrend", pairs=False)
    if kind not in ("mean", "constant", "linear", "piecewise"):
        raise DataError(f"kind must be 'mean', 'linear' or 'piecewise', got {kind!r}")
    if kind == "linear" and breakpoints is not None:
        kind = "piecewise"  # MATLAB's detrend(data, 1, breakpoints)
    n_exp = data.n_experiments
    if kind == "piecewise":
        if breakpoints is None:
            raise DataError("kind='piecewise' needs breakpoints=[sample, ...]")
        bl: list[Any] = list(breakpoints)
        per_exp = bl and all(isinstance(b, (list, tuple, np.ndarray)) for b in bl)
        bps: list[list[int]] = [list(b) for b in bl] if per_exp else [bl] * n_exp
        if len(bps) != n_exp:
            raise DataError(f"{len(bps)} breakpoint lists for {n_exp} experiments")
    elif breakpoints is not None:
        raise DataError("breakpoints make a piecewise-linear trend (kind='linear' or "
                        "'piecewise'); a mean has none: leave breakpoints out, or detrend the "
                        "segments one by one")
    else:
        bps = [[]] * n_exp
    exps, coefs = [], []
    for k, e in enumerate(data._exps):
        n = e.y.shape[0]
        for b in bps[k]:
            if not (isinstance(b, (int, np.integer)) and 0 < b < n - 1):
                raise DataError(
                    f"breakpoint {b!r} is not a sample index inside experiment {k} (1..{n - 2})"
                )
        basis = _basis(n, kind, sorted(bps[k]))
        if basis.shape[1] > n:
            raise InsufficientDataError(
                f"experiment {k} has {n} samples, too few for a {kind} trend"
            )
        pinv = np.linalg.pinv(basis)
        parts, coef = {}, {}
        for name, x, tr, sc, on in (
            ("u", e.u, e.tu, data._u_scale, inputs),
            ("y", e.y, e.ty, data._y_scale, outputs),
        ):
            c = pinv @ x if on and x.shape[1] else np.zeros((basis.shape[1], x.shape[1]))
            coef[name] = c
            fitted = basis @ c
            old = np.zeros_like(x) if tr is None else tr
            parts[name] = (x - fitted, old + sc * fitted)
        exps.append(_Exp(parts["u"][0], parts["y"][0], e.t0, parts["u"][1], parts["y"][1]))
        coefs.append((n, coef))
    out = data._derive(exps)
    if not return_trend:
        return out
    return out, _trend_of(out, kind, coefs)


def _trend_of(data: IOData, kind: str, coefs: list[tuple[int, dict[str, np.ndarray]]]) -> Any:
    """The :class:`Trend` of one detrend call: per-sample values, and for a mean or a line
    the sample-weighted average offsets and slopes (per second) that apply to other data."""
    from .trend import Trend

    exps = data._exps
    u_tr = [np.zeros_like(e.u) if e.tu is None else e.tu for e in exps]
    y_tr = [np.zeros_like(e.y) if e.ty is None else e.ty for e in exps]
    scales = (np.asarray(data._u_scale, float), np.asarray(data._y_scale, float))
    if kind == "piecewise":
        return Trend(u_tr, y_tr, *scales, dt=data.dt)
    # everything removed from the raw record so far (earlier detrends too, in raw units,
    # and through any scaling): a line per experiment when every step was a mean or a line
    w = np.array([n for n, _ in coefs], float)
    w = w / w.sum()
    offs, slopes, affine = [], [], True
    for trs in (u_tr, y_tr):
        off, slope = 0.0, 0.0
        for wk, tr in zip(w, trs):
            n = tr.shape[0]
            t = np.arange(n) * data.dt
            basis = np.column_stack([np.ones(n), t])
            c = np.linalg.lstsq(basis, tr, rcond=None)[0] if tr.size else np.zeros((2, 0))
            affine &= bool(np.allclose(basis @ c, tr, rtol=1e-9,
                                       atol=1e-9 * (1.0 + float(np.max(np.abs(tr), initial=0)))))
            off, slope = off + wk * c[0], slope + wk * c[1]
        offs.append(np.atleast_1d(np.asarray(off, float)))
        slopes.append(np.atleast_1d(np.asarray(slope, float)))
    if not affine:  # an earlier piecewise detrend: values of this record only
        return Trend(u_tr, y_tr, *scales, dt=data.dt)
    line = kind == "linear" or not all(
        np.allclose(tr, tr[:1], rtol=1e-12, atol=1e-12 * (1.0 + float(np.max(np.abs(tr)))))
        for trs in (u_tr, y_tr) for tr in trs if tr.size)
    if not line:
        slopes = [np.zeros_like(o) for o in offs]
    return Trend(u_tr, y_tr, *scales, kind="linear" if line else "mean",
                 offsets=(np.asarray(offs[0], float), np.asarray(offs[1], float)),
                 slopes=(np.asarray(slopes[0], float), np.asarray(slopes[1], float)),
                 dt=data.dt, t0=exps[0].t0 if len(exps) == 1 else None)


def scale(data: IOData, by: str | Any = "std") -> IOData:
    """Divide every channel by a factor, recorded in :attr:`IOData.trend`.

    Parameters
    ----------
    by : {"std", "max"} or (u_scale, y_scale)
        The standard deviation or the largest absolute value of each channel (over all
        experiments), or explicit factors per input and output.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.scale(sysid.IOData(u=np.array([0.0, 2.0, 4.0]), y=np.ones(3)), "max")
    >>> d.u.ravel(), d.trend.u_scale
    (array([0. , 0.5, 1. ]), array([4.]))
    """
    require_record(data, "scale", pairs=False)
    if isinstance(by, str):
        if by not in ("std", "max"):
            raise DataError(f"by must be 'std', 'max' or (u_scale, y_scale), got {by!r}")
        f = np.std if by == "std" else (lambda x, axis: np.max(np.abs(x), axis=axis))
        su = f(np.vstack([e.u for e in data._exps]), axis=0) if data.n_inputs else np.ones(0)
        sy = f(np.vstack([e.y for e in data._exps]), axis=0)
    else:
        try:
            su, sy = (np.asarray(v, dtype=float).ravel() for v in by)
        except (TypeError, ValueError):
            raise DataError("by must be 'std', 'max' or a pair (u_scale, y_scale)") from None
        if su.size != data.n_inputs or sy.size != data.n_outputs:
            raise DataError(
                f"scales have {su.size} and {sy.size} entries for {data.n_inputs} inputs and "
                f"{data.n_outputs} outputs"
            )
    for kind, s, names in (("input", su, data.input_names), ("output", sy, data.output_names)):
        bad = ~(np.isfinite(s) & (s > 0))
        if bad.any():
            raise DataError(
                f"{kind} {names[int(np.flatnonzero(bad)[0])]} has scale "
                f"{s[bad][0]:g} (a constant channel?); remove it or give explicit scales"
            )
    return data._scaled(su, sy)


# --------------------------------------------------------------------------------------------
# segment selection
# --------------------------------------------------------------------------------------------


def select_mask(data: IOData, mask: Any, *, min_length: int = 2) -> IOData:
    """Keep the samples where ``mask`` is True; each contiguous run becomes an experiment.

    Parameters
    ----------
    mask : array_like of bool, or list of them (one per experiment)
    min_length : int
        Runs shorter than this are dropped.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.arange(8.0), y=np.arange(8.0))
    >>> sysid.select_mask(d, [1, 1, 1, 0, 0, 1, 1, 0]).lengths
    [3, 2]
    """
    require_record(data, "select_mask", pairs=False)
    masks = mask if isinstance(mask, list) and data.n_experiments > 1 else [mask]
    if len(masks) != data.n_experiments:
        raise DataError(
            f"give one mask per experiment ({data.n_experiments}), got {len(masks)}"
        )
    if not isinstance(min_length, (int, np.integer)) or min_length < 1:
        raise DataError(f"min_length must be a positive integer, got {min_length!r}")
    exps = []
    for k, (e, m) in enumerate(zip(data._exps, masks)):
        m = np.asarray(m).ravel()
        if m.size != e.y.shape[0]:
            raise DataError(
                f"mask of experiment {k} has {m.size} samples but the data have {e.y.shape[0]}"
            )
        if m.dtype.kind not in "biu":
            raise DataError(f"mask must be boolean, got dtype {m.dtype}")
        for a, b in _runs(m.astype(bool)):
            if b - a >= min_length:
                exps.append(e.rows(slice(a, b), data.dt))
    if not exps:
        raise InsufficientDataError(
            f"no run of at least {min_length} selected samples; check the mask or min_length"
        )
    return data._derive(exps)


def select_mode(
    data: IOData, mode: Any, keep: Any, *, min_length: int = 2
) -> IOData:
    """Keep the samples whose ``mode`` (a flag or switch signal) is in ``keep``; each
    contiguous run becomes its own experiment.

    Parameters
    ----------
    mode : array_like, or list of them (one per experiment)
        A value per sample (e.g. 1, 2 autopilot, 3 manual).
    keep : scalar or collection
        Mode values to keep.
    min_length : int
        Shorter runs are dropped (manoeuvres too short to identify from).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.arange(9.0), y=np.arange(9.0))
    >>> sysid.select_mode(d, [3, 1, 1, 2, 3, 3, 1, 2, 2], keep={1, 2}).lengths
    [3, 3]
    """
    require_record(data, "select_mode", pairs=False)
    ks = np.atleast_1d(np.asarray(list(keep) if isinstance(keep, (set, frozenset)) else keep))
    modes = mode if isinstance(mode, list) and data.n_experiments > 1 else [mode]
    masks = [np.isin(np.asarray(m).ravel(), ks) for m in modes]
    if not any(m.any() for m in masks):
        seen = np.unique(np.concatenate([np.asarray(m).ravel() for m in modes]))
        raise InsufficientDataError(f"no sample has a mode in {ks.tolist()}; modes seen: "
                                    f"{seen.tolist()[:20]}")
    return select_mask(data, masks if data.n_experiments > 1 else masks[0],
                       min_length=min_length)


def drop_quiet(
    data: IOData,
    *,
    window: int = 50,
    threshold: float = 0.05,
    channels: Sequence[str] | None = None,
    min_length: int | None = None,
) -> IOData:
    """Cut out stretches where the inputs hardly move (nothing to identify from).

    A sample is quiet when the moving standard deviation over ``window`` samples of every
    chosen channel is below ``threshold`` times that channel's overall standard deviation;
    quiet runs of at least ``window`` samples are removed and the record is split there.

    Parameters
    ----------
    channels : list of str, optional
        Channels that must move; default every input (outputs for time series).
    min_length : int, optional
        Shortest kept segment (default ``window``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = np.random.default_rng(0).standard_normal(300); u[100:200] = 0.0
    >>> sysid.drop_quiet(sysid.IOData(u=u, y=u), window=20).n_experiments
    2
    """
    require_record(data, "drop_quiet", pairs=False)
    if not isinstance(window, (int, np.integer)) or window < 2:
        raise DataError(f"window must be an integer >= 2, got {window!r}")
    if window > max(data.lengths):
        raise DataError(f"window = {window} is longer than the longest experiment "
                        f"({max(data.lengths)} samples): choose a window of a few dozen "
                        "samples, far shorter than the record")
    threshold = as_nonnegative(threshold, "threshold")
    if channels is None:
        names = data.input_names if data.n_inputs else data.output_names
    else:
        names = list(channels)
    unknown = [n for n in names if n not in data.input_names + data.output_names]
    if unknown:
        raise DataError(unknown_names(data, unknown))
    allx = [
        np.column_stack(
            [e.u[:, data.input_names.index(n)] if n in data.input_names
             else e.y[:, data.output_names.index(n)] for n in names]
        )
        for e in data._exps
    ]
    ref = np.vstack(allx).std(axis=0)
    from scipy import ndimage  # here: `import sysid` would spend 0.3 s importing it

    masks = []
    for x in allx:
        mean = ndimage.uniform_filter1d(x, window, axis=0, mode="nearest")
        msq = ndimage.uniform_filter1d(x * x, window, axis=0, mode="nearest")
        sd = np.sqrt(np.maximum(msq - mean * mean, 0.0))
        quiet = (sd <= threshold * ref).all(axis=1)
        keep = np.ones(len(x), dtype=bool)
        for a, b in _runs(quiet):
            if b - a >= window:
                keep[a:b] = False
        masks.append(keep)
    return select_mask(
        data,
        masks if data.n_experiments > 1 else masks[0],
        min_length=window if min_length is None else min_length,
    )
