"""Exceptions raised by sysid.

Every error of the Rust core arrives as one of these classes (the mapping lives in the
binding crate). Bad input raises a subclass of :class:`ValueError`, numerical failure a
subclass of :class:`ArithmeticError`; all derive from :class:`SysidError`.

Examples
--------
>>> import numpy as np, sysid
>>> try:
...     sysid.IOData(u=np.zeros((5, 1)), y=np.zeros((4, 1)))
... except sysid.DataError as e:
...     print(type(e).__name__)
ShapeError
"""

from __future__ import annotations

__all__ = [
    "SysidError",
    "DataError",
    "NonFiniteError",
    "ShapeError",
    "InsufficientDataError",
    "ExcitationError",
    "OrderError",
    "NumericalError",
    "RiccatiError",
    "ExcitationWarning",
    "FeedbackWarning",
    # issue 26 (branch pem): iterative estimators' warnings
    "StabilityWarning",
    "IterationLimitWarning",
]


class SysidError(Exception):
    """Base class of every sysid exception."""


class DataError(SysidError, ValueError):
    """The data or an argument is unusable as given; the message says how to fix it."""


class NonFiniteError(DataError):
    """A NaN or Inf in the data."""


class ShapeError(DataError):
    """Arrays with the wrong number of dimensions, samples or channels."""


class InsufficientDataError(DataError):
    """Too few samples for the requested horizon or model."""


class ExcitationError(DataError):
    """The input is not persistently exciting enough for the requested horizon or order."""


class OrderError(DataError):
    """The requested model order is larger than the data or horizon allow."""


class NumericalError(SysidError, ArithmeticError):
    """A numerical step failed (rank loss, non-convergence)."""


class RiccatiError(NumericalError):
    """The Riccati equation of the Kalman gain has no stabilising solution."""


class ExcitationWarning(UserWarning):
    """The input may not excite the system enough for the requested model order."""


class FeedbackWarning(UserWarning):
    """The input depends on past outputs (feedback): open-loop subspace methods are biased;
    use ``method="pbsid"`` or ``"ssarx"`` (see :func:`sysid.check_feedback`)."""


# issue 26 (branch pem): what an iterative estimator says about the model it returns


class StabilityWarning(UserWarning):
    """The returned model is unstable (a pole on or outside the unit circle); the message
    names the largest pole modulus and the option that keeps the model stable
    (``enforce_stability=True``, or ``focus="simulation"``)."""


class IterationLimitWarning(UserWarning):
    """An iterative search stopped at its iteration cap before a convergence test was met;
    the model is the best iterate found. The message says how far from converged it was and
    what to do (raise ``max_iter``, or refine again from the returned model)."""
