"""Zero-phase Butterworth filtering and changes of sample rate (with anti-alias filtering).

Every function takes an :class:`~sysid.IOData` and returns a new one; a removed trend
recorded in :attr:`IOData.trend` is carried along (filtered trends are not: see
:func:`filtfilt`).
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from typing import Any

import numpy as np
from scipy import signal

from .._checks import as_dt, as_int, check_elements
from ..errors import DataError, InsufficientDataError
from .iodata import IOData, require_record
from .segments import _Exp

__all__ = ["butter_sos", "filtfilt", "lowpass", "highpass", "bandpass", "resample", "decimate"]


# --------------------------------------------------------------------------------------------
# filtering
# --------------------------------------------------------------------------------------------


#: the steepest Butterworth filter :func:`butter_sos` designs
MAX_FILTER_ORDER = 50


def butter_sos(kind: str, cutoff: float | Sequence[float], dt: float, order: int = 4) -> np.ndarray:
    """Second-order sections of a digital Butterworth filter (``scipy.signal.butter``).

    Parameters
    ----------
    kind : {"lowpass", "highpass", "bandpass", "bandstop"}
    cutoff : float or (float, float)
        Corner frequency(ies) in Hz, below the Nyquist frequency ``1 / (2 dt)``.
    dt : float
        Sample time in seconds.
    order : int
        Filter order (applied twice by :func:`filtfilt`, so the magnitude is squared).
    """
    if kind not in ("lowpass", "highpass", "bandpass", "bandstop"):
        raise DataError(f"unknown filter kind {kind!r}")
    if not isinstance(order, (int, np.integer)) or isinstance(order, bool) or order < 1:
        raise DataError(f"order must be a positive integer, got {order!r}")
    if order > MAX_FILTER_ORDER:
        raise DataError(f"order {order} is beyond {MAX_FILTER_ORDER}: a Butterworth filter "
                        "that steep has no numerical meaning (its sections' poles crowd the "
                        "unit circle); use order 2-10, or a band edge further away")
    fc = np.atleast_1d(np.asarray(cutoff, dtype=float))
    need = 2 if kind in ("bandpass", "bandstop") else 1
    if fc.size != need:
        raise DataError(f"a {kind} filter needs {need} cutoff frequency(ies) in Hz, got {cutoff}")
    nyq = 0.5 / dt
    if not (np.all(fc > 0) and np.all(fc < nyq)):
        raise DataError(
            f"cutoff {cutoff} Hz must lie strictly between 0 and the Nyquist frequency "
            f"{nyq:g} Hz (dt = {dt:g} s)"
        )
    if need == 2 and not fc[0] < fc[1]:
        raise DataError(f"band edges must be increasing, got {cutoff}")
    if fc.min() < 1e-8 * nyq:
        raise DataError(f"cutoff {fc.min():g} Hz is below 1e-8 of the Nyquist frequency "
                        f"{nyq:g} Hz: the filter's poles lie within round-off of 1 and its "
                        "initial conditions cannot be solved; remove a mean or drift instead "
                        "(sysid.detrend), or decimate first (sysid.decimate)")
    return signal.butter(int(order), fc if need == 2 else fc[0], btype=kind, output="sos",
                         fs=1.0 / dt)


def filtfilt(
    data: IOData, sos: Any, *, inputs: bool = True, outputs: bool = True
) -> IOData:
    """Zero-phase filtering (forward and backward, ``scipy.signal.sosfiltfilt``) of every
    experiment. Experiments too short for the filter's padding raise an error."""
    require_record(data, "filtfilt", pairs=False)
    sos = np.asarray(sos, dtype=float)
    if sos.ndim != 2 or sos.shape[1] != 6:
        raise DataError(f"sos must have shape (n_sections, 6), got {sos.shape}")
    padlen = 3 * (2 * sos.shape[0] + 1 - min((sos[:, 2] == 0).sum(), (sos[:, 5] == 0).sum()))
    exps = []
    for k, e in enumerate(data._exps):
        if e.y.shape[0] <= padlen:
            raise InsufficientDataError(
                f"experiment {k} has {e.y.shape[0]} samples; the zero-phase filter needs more "
                f"than {padlen} (lower the order or drop short segments)"
            )
        try:
            u = signal.sosfiltfilt(sos, e.u, axis=0) if inputs and e.u.shape[1] else e.u
            y = signal.sosfiltfilt(sos, e.y, axis=0) if outputs else e.y
        except (ValueError, np.linalg.LinAlgError) as err:  # SciPy's words about the sections
            raise DataError(f"the filter sections cannot filter this record ({err}): give "
                            "sections of a stable filter, each [b0, b1, b2, 1, a1, a2], with "
                            "poles not at 1 (sysid.data.filtering.butter_sos designs them)"
                            ) from None
        exps.append(_Exp(u, y, e.t0, e.tu, e.ty))
    return data._derive(exps)


def lowpass(
    data: IOData, cutoff: float, order: int = 4, *, inputs: bool = True, outputs: bool = True
) -> IOData:
    """Zero-phase Butterworth low-pass filter (cutoff in Hz) of inputs and/or outputs.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> t = np.arange(1000) * 0.01
    >>> d = sysid.IOData(u=None, y=np.sin(2 * np.pi * 0.5 * t) + np.sin(2 * np.pi * 20 * t),
    ...                  dt=0.01)
    >>> f = sysid.lowpass(d, 5.0)
    >>> bool(np.abs(f.y[100:-100, 0] - np.sin(2 * np.pi * 0.5 * t[100:-100])).max() < 1e-2)
    True
    """
    require_record(data, "lowpass", pairs=False)
    return filtfilt(data, butter_sos("lowpass", cutoff, data.dt, order),
                    inputs=inputs, outputs=outputs)


def highpass(
    data: IOData, cutoff: float, order: int = 4, *, inputs: bool = True, outputs: bool = True
) -> IOData:
    """Zero-phase Butterworth high-pass filter (cutoff in Hz); see :func:`lowpass`."""
    require_record(data, "highpass", pairs=False)
    return filtfilt(data, butter_sos("highpass", cutoff, data.dt, order),
                    inputs=inputs, outputs=outputs)


def bandpass(
    data: IOData,
    low: float,
    high: float,
    order: int = 4,
    *,
    inputs: bool = True,
    outputs: bool = True,
) -> IOData:
    """Zero-phase Butterworth band-pass filter between ``low`` and ``high`` Hz."""
    require_record(data, "bandpass", pairs=False)
    return filtfilt(data, butter_sos("bandpass", (low, high), data.dt, order),
                    inputs=inputs, outputs=outputs)


# --------------------------------------------------------------------------------------------
# resampling
# --------------------------------------------------------------------------------------------


def _trend_on(tr: np.ndarray | None, n_new: int, factor: float) -> np.ndarray | None:
    """A recorded trend (one value per old sample) at the new samples ``k * factor`` (in
    old samples): linear between old samples, and past the last one its last segment
    extended (a trend removed by :func:`~sysid.detrend` is linear there; holding its last
    value made ``retrend()`` wrong at the end of an upsampled record)."""
    if tr is None:
        return None
    n = tr.shape[0]
    k_old = np.arange(n, dtype=float)
    k_new = np.arange(n_new) * factor
    out = np.empty((n_new, tr.shape[1]))  # no columns: a time series' input trend
    for j in range(tr.shape[1]):
        out[:, j] = np.interp(k_new, k_old, tr[:, j])
    past = k_new > n - 1
    if n >= 2 and past.any():
        out[past] = tr[-1] + (k_new[past] - (n - 1))[:, None] * (tr[-1] - tr[-2])
    return out


def resample(data: IOData, dt: float, *, max_denominator: int = 1000) -> IOData:
    """Change the sample time with polyphase anti-alias filtering
    (``scipy.signal.resample_poly``, ends padded with a line).

    The ratio ``data.dt / dt`` must be a fraction ``up / down`` with ``down`` at most
    ``max_denominator`` (to 1e-9): the result has exactly the sample time asked for, or a
    :class:`~sysid.DataError` names the nearest one that can be had (resampling to another
    rate than asked, silently, moved every frequency of a model fitted to the result).

    A trend recorded by :func:`~sysid.detrend` is evaluated at the new instants, its last
    segment extended past the last old sample, so that ``retrend()`` restores it there.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.ones(300), y=np.ones(300), dt=0.01)
    >>> r = sysid.resample(d, 0.025)
    >>> r.dt, r.n_samples
    (0.025, 120)
    """
    require_record(data, "resample", pairs=False)
    short = [k for k, n in enumerate(data.lengths) if n < 2]
    if short:
        raise InsufficientDataError(f"experiment(s) {short} have one sample: resampling "
                                    "interpolates between samples and needs at least 2; drop "
                                    "them first")
    new_dt = as_dt(dt)
    target = data.dt / new_dt
    ratio = Fraction(target).limit_denominator(int(max_denominator))  # up / down
    up, down = ratio.numerator, ratio.denominator
    if up == 0 or abs(up / down - target) > 1e-9 * target:
        near = (f"the nearest is {data.dt * down / up:.10g} s" if up else
                f"the longest is {data.dt * max_denominator:.6g} s")
        raise DataError(
            f"dt = {new_dt:g} s is not the record's {data.dt:g} s times a fraction down/up "
            f"with down <= max_denominator = {max_denominator} ({near}); ask for such a "
            "sample time, or raise max_denominator (longer anti-alias filters)")
    # the resampled channels (and trends) of every experiment, and the polyphase filter of
    # 20 max(up, down) taps
    nc = data.n_inputs + data.n_outputs
    check_elements(sum(2 * nc * -(-e.y.shape[0] * up // down) for e in data._exps)
                   + 20 * max(up, down) + 1,
                   f"resampling dt = {data.dt:g} s to dt = {new_dt:g} s ({up}/{down} as many "
                   "samples)", "choose a longer dt (or cut the record to the part you need "
                   "first)")
    exps = []
    for e in data._exps:
        n_new = int(np.ceil(e.y.shape[0] * up / down))
        u = (signal.resample_poly(e.u, up, down, axis=0, padtype="line")
             if e.u.shape[1] else np.zeros((n_new, 0)))
        y = signal.resample_poly(e.y, up, down, axis=0, padtype="line")
        f = down / up
        exps.append(_Exp(u, y, e.t0, _trend_on(e.tu, n_new, f), _trend_on(e.ty, n_new, f)))
    return data._derive(exps, dt=new_dt)


#: Fewest samples an experiment may keep after :func:`decimate`.
MIN_DECIMATED = 10
#: Highest anti-alias filter order of :func:`decimate` (beyond, the Chebyshev filter's
#: coefficients are meaningless in double precision).
MAX_DECIMATE_ORDER = 30


def decimate(data: IOData, q: int, *, order: int = 8) -> IOData:
    """Keep every ``q``-th sample after a zero-phase Chebyshev anti-alias filter
    (as ``scipy.signal.decimate`` with ``zero_phase=True``; the filter is MATLAB's and
    SciPy's order-``order`` type I with 0.05 dB ripple and cut-off ``0.8 / q``, scaled to
    unit gain at DC so that levels and offsets are kept, applied forward and back in
    second-order sections, which keep it well conditioned for large ``q``).

    ``q`` must leave every experiment at least ``MIN_DECIMATED`` (10) samples and ``order``
    lie in 1..30; otherwise a :class:`~sysid.DataError` is raised.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> sysid.decimate(sysid.IOData(u=np.ones(100), y=np.ones(100), dt=0.01), 4).dt
    0.04
    """
    require_record(data, "decimate", pairs=False)
    if not isinstance(q, (int, np.integer)) or isinstance(q, (bool, np.bool_)) or q < 2:
        raise DataError(f"q must be an integer >= 2, got {q!r}")
    order = as_int(order, "order", 1, MAX_DECIMATE_ORDER)
    for k, e in enumerate(data._exps):
        n = e.y.shape[0]
        kept = -(-n // int(q))
        if kept < MIN_DECIMATED:
            top = (n - 1) // (MIN_DECIMATED - 1)  # the largest q that keeps enough
            fix = f"pass q <= {top}" if top >= 2 else "the experiment is too short to decimate"
            raise InsufficientDataError(
                f"decimating experiment {k} ({n} samples) by q = {q} would leave {kept} "
                f"sample(s), fewer than {MIN_DECIMATED}: nothing could be identified from "
                f"them; {fix}")
    # SciPy's default Chebyshev filter has a DC gain of 10^(-0.05/20) (the passband ripple's
    # trough), 0.9886 forward and back: a 300 degree level became 296.6. Scaled to unit DC
    # gain, levels and offsets survive decimation. In second-order sections: as one
    # polynomial (SciPy's decimate) the filter of cut-off 0.8 / q is ill-conditioned for large
    # q (q = 34: a 5 V offset moved the decimated chirp by 2e-5 of its amplitude, and the
    # record's means then changed the model identified from it)
    sos = signal.cheby1(order, 0.05, 0.8 / int(q), output="sos")
    sos[0, :3] /= np.prod(np.sum(sos[:, :3], axis=1) / np.sum(sos[:, 3:], axis=1))
    exps = []
    for k, e in enumerate(data._exps):
        if e.y.shape[0] <= 3 * (order + 1):
            raise InsufficientDataError(f"experiment {k} is too short to decimate")

        def dec(x: np.ndarray) -> np.ndarray:
            if not x.shape[1]:
                return np.zeros((len(range(0, x.shape[0], q)), 0))
            return signal.sosfiltfilt(sos, x, axis=0, padlen=3 * (order + 1))[::q]

        def take(tr: np.ndarray | None) -> np.ndarray | None:
            return None if tr is None else tr[::q]

        exps.append(_Exp(dec(e.u), dec(e.y), e.t0, take(e.tu), take(e.ty)))
    return data._derive(exps, dt=data.dt * q)
