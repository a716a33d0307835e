"""identify on a record sampled far faster than its input changes.

A throttle valve logged at 1 kHz while a chirp sweeps it from 0.26 to 2.8 Hz: every window of
the subspace sweep (20 samples, 20 ms) sees the input as a smooth curve, the rows of future
inputs have numerical rank 6 of 20, and every subspace estimator refuses the record
(``ExcitationError``), so identify had nothing to start from. MATLAB's advice for such data
is to resample them so that the sampling frequency is about ten times the band of interest
(``idresamp``); identify now does so itself when, and only when, the record is refused for
it: the band that holds 99.9 % of each input's power (Welch's periodogram) is put at
:data:`~sysid.data.oversampling.BAND_SHARE` of the decimated record's Nyquist frequency
(:func:`sysid.decimate`: a zero-phase anti-alias filter, levels kept), the record is
identified there, and the chosen model is converted back to the record's sample time
(:func:`sysid.d2d` with a first-order hold: every pole mapped exactly, ``z ** (1 / q)``,
and the input taken as varying linearly between the decimated samples, as a band-limited
input does; Tustin's map where a pole lies on the negative real axis, which has no such
equivalent). On a synthetic chirp record the hold gives 99.0 %, Tustin 97.1 % (its map moves
lightly damped modes), a zero-order hold 85.8 % (it takes the smooth input as held over
each decimated sample: half a sample late).
Its noise model is not converted (``K`` dropped); the coarse model stays in
``info["decimated"]``, and ``checks["sampling"]`` says what was done. A refused record
whose inputs fill the band (a few tones across it, white noise on collinear channels), or
whose decimated copy is refused too, raises the first error as before.
"""

from __future__ import annotations

import functools
import time
from contextvars import ContextVar
from typing import Any

from ..data.iodata import IOData
from ..data.oversampling import decimation_factor, input_band
from ..errors import ExcitationError, InsufficientDataError, NumericalError

__all__ = ["record_feedback", "retry_decimated"]

#: the feedback test of the record as sampled, while its decimated copy is identified
_FEEDBACK: ContextVar[Any] = ContextVar("sysid_record_feedback", default=None)


def record_feedback() -> Any:
    """The feedback test (:func:`sysid.check_feedback`) of the record as it was sampled
    while :func:`retry_decimated` identifies its decimated copy, else ``None``: the
    anti-alias filter smooths input and output alike, and past outputs of the filtered
    record then predict a smooth input a little beyond its own past (a throttle valve's
    chirp: 5e-7 of its variance, p = 6e-6) where the record shows no feedback (p = 1).

    Examples
    --------
    >>> from sysid.identify.oversampled import record_feedback
    >>> record_feedback() is None
    True
    """
    return _FEEDBACK.get()


def retry_decimated(identify: Any) -> Any:
    """``identify`` that, on a record whose inputs the subspace sweep refuses
    (``ExcitationError``) and that is sampled far faster than its inputs change
    (:func:`~sysid.data.oversampling.decimation_factor`), identifies the decimated record
    and returns the chosen model at the record's sample time (module docstring); the first
    error otherwise."""

    @functools.wraps(identify)
    def wrapper(data: Any, validation: Any = None, **kw: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return identify(data, validation, **kw)
        except ExcitationError as err:
            from ..data.filtering import decimate
            from ..data.offsets import remove_means
            from ..validation.feedback import check_feedback
            from ..validation.records import validation_record

            rec = data if isinstance(data, IOData) else IOData(u=data[0], y=data[1])
            band = input_band(rec)
            q = decimation_factor(rec, band)
            if q is None:
                raise
            try:
                fb = check_feedback(remove_means(rec)[0])
            except Exception:  # noqa: BLE001 - a record it cannot read: the copy's own test
                fb = None
            token = _FEEDBACK.set(fb)
            try:
                res = identify(decimate(rec, q), None, **kw)
            except (ExcitationError, InsufficientDataError):  # the copy is refused too
                raise err from None
            finally:
                _FEEDBACK.reset(token)
            return _at_record_rate(res, rec, validation_record(validation, rec), q, band,
                                   time.perf_counter() - t0)

    return wrapper


def _at_record_rate(res: Any, rec: IOData, validation: IOData | None, q: int, band: float,
                    seconds: float) -> Any:
    """``res`` (identified on ``rec`` decimated by ``q``; ``band``, the inputs' band) with
    its model at ``rec``'s sample time and its validation fit there."""
    from ..models.continuous import d2d
    from ..validation.coverage import coverage_note
    from .result import IdentifiedModel, IdentifyResult, reported_fit

    coarse = res.model.statespace  # (d2d leaves its noise model, carries its uncertainty)
    method = "first-order hold"
    try:
        fine = d2d(coarse, rec.dt, "foh")
    except NumericalError:  # a pole on the negative real axis: no hold equivalent
        method = "Tustin (a pole on the negative real axis has no first-order-hold equivalent)"
        fine = d2d(coarse, rec.dt, "tustin")
    fine.info = {"identify": coarse.info.get("identify"),
                 "decimated": {"q": q, "dt": coarse.dt, "model": coarse}}
    model = IdentifiedModel(fine, res.model.u_offset, res.model.y_offset)
    checks = dict(res.checks)
    checks["sampling"] = (
        f"the record is sampled far faster than its inputs change (99.9 % of their power "
        f"below {100 * band:.2g} % of the Nyquist frequency) and the subspace "
        f"windows refuse it: identified on it decimated by {q} (sysid.decimate, dt = "
        f"{coarse.dt:g}), the model converted back to dt = {rec.dt:g} (sysid.d2d, {method}; "
        "no noise model); held-out fits are at the decimated rate, the feedback test is "
        f"the record's as sampled (the filter's smoothing fakes a little feedback)")
    if validation is not None and (note := coverage_note(rec, validation)) is not None:
        checks["validation"] = note
    out = IdentifyResult(model, res.leaderboard, res.choice, checks,
                         reported_fit(model, validation), seconds, res.interrupted, res.score)
    out.out_of_time = res.out_of_time
    return out
