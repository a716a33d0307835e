"""Checked attributes of the models: state-space matrices and sample times.

A matrix (``A, B, C, D, K, noise_cov, x0``) or a sample time ``dt`` can be replaced whole
after construction, and is then checked as the constructor checks it: ``m.A =
np.full((2, 2), np.nan)`` or ``m.dt = -0.1`` is refused when it is written, not found as NaN
(or a file :func:`sysid.load_model` refuses) later. A :class:`~sysid.ContinuousStateSpace`
keeps ``dt = 0`` (:class:`ContinuousTime`); an :class:`~sysid.FRD`'s ``dt`` is a sample
time or ``None`` (``SampleTime(continuous=None)``).

A model carrying a parameter :attr:`~sysid.StateSpaceModel.uncertainty` is ``build(theta)``
of the estimated parameters, and every ``std=True`` result (poles, frequency response, DC
gain, damping, step and impulse bands) is computed from ``build(theta)``, not from the
model's current matrices. Replacing a value those parameters determine (``A, B, C, D``,
``K`` when the model has one, ``dt``) by another therefore drops the uncertainty, with an
:class:`~sysid.models.uncertainty.UncertaintyWarning` saying why: the numbers with a
standard deviation are never those of the old model mixed with the values of the new one.
Giving a model without a noise model a ``K`` (its parameters never held one), and replacing
``noise_cov`` or ``x0`` (which no standard deviation is computed from), keep it. The
coefficients of a :class:`~sysid.TransferFunction` (``num, den, iodelay``) and of a
:class:`~sysid.PolynomialModel` (``a, b, c, d, f, nk``) are :class:`Coefficients` and follow
the same rule; ``hold`` and ``noise_variance`` keep it.

Examples
--------
>>> import warnings, numpy as np, sysid
>>> def build(t):
...     return sysid.StateSpaceModel([[t[0]]], [[1.0]], [[1.0]], dt=0.1)
>>> m = build([0.5])
>>> m.uncertainty = sysid.ParameterUncertainty([0.5], [[1e-4]], build)
>>> with warnings.catch_warnings(record=True) as caught:
...     warnings.simplefilter("always")
...     m.A = [[0.9]]
>>> m.uncertainty is None, caught[0].category.__name__
(True, 'UncertaintyWarning')
>>> m.dt = 0.0
Traceback (most recent call last):
...
sysid.errors.DataError: dt must be a positive number of seconds, got 0.0; ...
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .._checks import as_dt, as_matrix, check_covariance, user_stacklevel
from ..errors import DataError, ShapeError
from .paramtable import ParameterTable

__all__ = ["Coefficients", "ContinuousTime", "Matrix", "SampleTime", "drop_uncertainty",
           "frozen"]


def frozen(arr: Any) -> np.ndarray | None:
    """A read-only copy of ``arr`` (``None`` stays ``None``): the model's own, which neither
    an in-place edit (NumPy's "assignment destination is read-only") nor a change to the
    caller's array reaches."""
    if arr is None:
        return None
    out = np.array(arr, dtype=float, copy=True)
    out.flags.writeable = False
    return out


def drop_uncertainty(obj: Any, what: str) -> None:
    """Drop ``obj``'s parameter uncertainty, if it has one, because ``what`` (``"A"``,
    ``"dt (0.1 s -> 0.2 s)"``) was replaced: its covariance belongs to the estimated
    parameters, which give the old value (see the module documentation)."""
    if obj.__dict__.get("uncertainty") is None:
        return
    from .uncertainty import UncertaintyWarning

    obj.__dict__["uncertainty"] = None
    if isinstance(obj.__dict__.get("parameters"), ParameterTable):  # its std are the old's
        obj.__dict__["parameters"] = None
    info = obj.__dict__.get("info")
    if isinstance(info, dict):  # what std=True's "carries no parameter uncertainty" says
        info["uncertainty"] = {
            "method": "none",
            "why": f"dropped when {what} was replaced: it belonged to the estimated "
                   "parameters, which give the old value; re-estimate the model or set "
                   "model.uncertainty again"}
    warnings.warn(
        f"{type(obj).__name__}.{what} was replaced on a model that carries a parameter "
        "uncertainty: the uncertainty is dropped (model.uncertainty is now None), because "
        "its covariance belongs to the estimated parameters, which give the old value, and "
        "every std=True result would describe that old model; re-estimate the model "
        "(sysid.pem(data, model, max_iter=0) gives the criterion's covariance at it) or set "
        "model.uncertainty again", UncertaintyWarning, stacklevel=user_stacklevel())


#: the matrices whose replacement drops a parameter uncertainty (``K`` only when the model
#: had one: an output-error model's parameters hold no ``K``)
_ESTIMATED = ("A", "B", "C", "D", "K")


class Matrix:
    """A state-space matrix attribute: read-only, replaced only whole and then checked as
    the constructor checks it (real, finite, the model's shape), so that neither ``m.A[0, 0]
    = np.nan`` nor ``m.A = np.full((2, 2), np.nan)`` makes a model that simulates to NaN
    without a word; a replacement of an estimated value drops the model's parameter
    uncertainty (:func:`drop_uncertainty`)."""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name, self.slot = name, "_matrix_" + name

    def __get__(self, obj: Any, owner: type | None = None) -> Any:
        if obj is None:
            return self
        try:
            arr = obj.__dict__[self.slot]
        except KeyError:
            raise AttributeError(self.name) from None
        if arr is not None and arr.flags.writeable:  # a copy's (deepcopy, pickle)
            arr.flags.writeable = False
        return arr

    def __set__(self, obj: Any, value: Any) -> None:
        if self.slot not in obj.__dict__:  # the constructor's own, already checked
            obj.__dict__[self.slot] = frozen(value)
            return
        old = obj.__dict__[self.slot]
        n, m, l = obj.nstates, obj.ninputs, obj.noutputs
        shape = {"A": (n, n), "B": (n, m), "C": (l, n), "D": (l, m), "K": (n, l),
                 "noise_cov": (l, l), "x0": (n, 1)}[self.name]
        if value is None and self.name in ("K", "noise_cov", "x0"):
            arr = None
        else:
            if self.name == "x0" and np.size(value) == n:
                value = np.reshape(value, (n, 1))
            try:
                arr = as_matrix(value, self.name, shape)
            except ShapeError as e:
                raise ShapeError(f"{e}; a matrix of another size is another model: build it "
                                 f"with sysid.{type(obj).__name__}(A, B, C, D, ...)") from None
            if self.name == "noise_cov":
                arr = check_covariance(arr, "noise_cov")
            arr = frozen(arr[:, 0] if self.name == "x0" else arr)
        same = (arr is None and old is None) or (
            arr is not None and old is not None and np.array_equal(arr, old))
        if self.name in _ESTIMATED and old is not None and not same:
            drop_uncertainty(obj, self.name)
        obj.__dict__[self.slot] = arr


class Coefficients:
    """Coefficient arrays a model keeps as given (a transfer function's ``num``, ``den``,
    ``iodelay``; a polynomial model's ``a``, ``b``, ``c``, ``d``, ``f``, ``nk``), kept in the
    instance's ``__dict__`` under their own name (pickles and copies as before): replacing
    one by a different value drops the model's parameter uncertainty
    (:func:`drop_uncertainty`), the same value keeps it silently."""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, obj: Any, owner: type | None = None) -> Any:
        if obj is None:
            return self
        try:
            return obj.__dict__[self.name]
        except KeyError:
            raise AttributeError(self.name) from None

    def __set__(self, obj: Any, value: Any) -> None:
        if (obj.__dict__.get("uncertainty") is not None and self.name in obj.__dict__
                and not _same(obj.__dict__[self.name], value)):
            drop_uncertainty(obj, self.name)
        obj.__dict__[self.name] = value


def _same(x: Any, y: Any) -> bool:
    """``x`` and ``y`` hold the same numbers in the same nesting (arrays or lists of them,
    ragged ones compared entry by entry)."""
    try:
        return bool(np.array_equal(np.asarray(x, dtype=float), np.asarray(y, dtype=float)))
    except (TypeError, ValueError):  # ragged: one array per entry
        pass
    if not (isinstance(x, (list, tuple, np.ndarray)) and isinstance(y, (list, tuple, np.ndarray))
            and len(x) == len(y)):
        return False
    return all(_same(a, b) for a, b in zip(x, y))


_DISCRETE = object()  # SampleTime(): no continuous-time value, dt must be positive


class SampleTime:
    """A model's sample time ``dt``, checked by :func:`sysid._checks.as_dt` (a finite
    positive number of seconds) whenever it is written, in the constructor and after; a
    change drops the model's parameter uncertainty (:func:`drop_uncertainty`). Kept in the
    instance's ``__dict__`` under ``"dt"`` (pickles and copies as before).

    Parameters
    ----------
    continuous : optional
        What ``0`` (or ``None``) is stored as for a family that may be continuous-time
        (``None`` for an :class:`~sysid.FRD`, ``0.0`` for a transfer function); left out,
        the model is discrete-time only and ``0`` is refused.
    """

    def __init__(self, continuous: Any = _DISCRETE) -> None:
        self.continuous = continuous

    def __get__(self, obj: Any, owner: type | None = None) -> Any:
        if obj is None:
            return self
        try:
            return obj.__dict__["dt"]
        except KeyError:
            raise AttributeError("dt") from None

    def __set__(self, obj: Any, value: Any) -> None:
        old = obj.__dict__.get("dt", _DISCRETE)
        if self.continuous is not _DISCRETE and _zero(value):
            new = self.continuous
        else:
            try:
                new = as_dt(value)
            except DataError as e:
                if _positive(value):  # out of the representable range: as_dt says so
                    raise
                fix = (f"; a {type(obj).__name__} is discrete-time: dt is its sample time in "
                       "seconds (a continuous-time model, dt = 0, is a "
                       "sysid.ContinuousStateSpace: sysid.d2c(model) converts one)"
                       if self.continuous is _DISCRETE else
                       f"; {type(obj).__name__}.dt is the sample time in seconds of the data "
                       "it describes, or 0 (None) for continuous time")
                raise DataError(f"{e}{fix}") from None
        if old is not _DISCRETE and new != old:
            drop_uncertainty(obj, f"dt ({old} s -> {new} s)")
        obj.__dict__["dt"] = new


def _positive(value: Any) -> bool:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return False
    return bool(np.isfinite(v) and v > 0) and not isinstance(value, (bool, np.bool_, str))


def _zero(value: Any) -> bool:
    """``value`` is ``None`` or the number 0 (not ``False``, not ``"0"``)."""
    if value is None:
        return True
    if isinstance(value, (bool, np.bool_, str, bytes)) or np.ndim(value) != 0:
        return False
    try:
        return float(value) == 0.0
    except (TypeError, ValueError):
        return False


class ContinuousTime:
    """The ``dt`` of a continuous-time model: always ``0.0`` (python-control's convention);
    writing ``0`` or ``None`` keeps it, any other value is refused with the conversion
    that gives a sampled model."""

    def __get__(self, obj: Any, owner: type | None = None) -> float:
        return 0.0

    def __set__(self, obj: Any, value: Any) -> None:
        if _zero(value):
            return
        raise DataError(
            f"a {type(obj).__name__} is continuous-time: its dt stays 0, got {value!r}; "
            "for the model sampled every dt seconds use sysid.c2d(model, dt) (or "
            "model.sampled(dt) to meet data sampled every dt)")
