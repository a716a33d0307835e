"""Exceptions raised by sysid.

Every error of the Rust core arrives as one of these classes (the mapping lives in the
binding crate). Bad input raises a subclass of :class:`ValueError`, numerical failure a
subclass of :class:`ArithmeticError`; all derive from :class:`SysidError`. Every warning
sysid gives derives from :class:`SysidWarning` (a :class:`UserWarning`), so that
``warnings.simplefilter("ignore", sysid.SysidWarning)`` silences sysid alone.

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
    "SysidWarning",
    "ExcitationWarning",
    "FeedbackWarning",
    "OffsetWarning",
    "StabilityWarning",
    "IterationLimitWarning",
    "IdentifiabilityWarning",
    "FeedthroughWarning",
]


class SysidError(Exception):
    """Base class of every sysid exception.

    An error of the Rust core also carries its facts as data (set by the binding crate's
    one error mapping): ``kind``, the core variant's name (``"NotPersistentlyExciting"``);
    ``problem``, the message without its remedy; ``remedy``, what may help (``None`` when
    the message has no separate one). Errors raised in Python have ``kind = None``.
    """

    #: the core error's variant, e.g. ``"NotPersistentlyExciting"`` (None: raised in Python)
    kind: str | None = None
    #: the core's message without its remedy (None: raised in Python)
    problem: str | None = None
    #: what the core suggests, e.g. a richer input or a shorter horizon (None: nothing apart)
    remedy: str | None = None

    def with_remedy(self, remedy: str) -> SysidError:
        """The same error of the core, its remedy replaced by ``remedy`` (the core's advice in
        the record's terms: a step test's, an oversampled record's decimation); the error
        itself when it has no problem apart (raised in Python).

        Examples
        --------
        >>> import sysid
        >>> e = sysid.ExcitationError("not exciting; use a richer input")
        >>> e.problem, e.kind = "not exciting", "NotPersistentlyExciting"
        >>> said = e.with_remedy("decimate the record first")
        >>> str(said), said.kind
        ('not exciting: decimate the record first', 'NotPersistentlyExciting')
        """
        if not self.problem:
            return self
        said = type(self)(f"{self.problem}: {remedy}")
        said.kind, said.problem, said.remedy = self.kind, self.problem, remedy
        return said


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


class SysidWarning(UserWarning):
    """Base class of every sysid warning; the plain ones (a step left out, a budget spent,
    a test that could not run) are of this class itself."""


class ExcitationWarning(SysidWarning):
    """The input may not excite the system enough for the requested model order."""


class FeedbackWarning(SysidWarning):
    """The input depends on past outputs (feedback): open-loop subspace methods are biased;
    use :func:`sysid.pbsid` or :func:`sysid.ssarx` (``method="pbsid"`` in ``ssest`` and
    ``SubspaceEstimator``; see :func:`sysid.check_feedback`). The output-error fits (no noise
    model: ``oe``, ``tfest``, ``ssest``/``pem`` with ``focus="simulation"``, ``procest``) are
    biased too and say so with their own remedy (:mod:`sysid.validation.output_error`)."""


class OffsetWarning(SysidWarning):
    """A channel sits on an offset much larger than its variation and the data were not
    detrended: linear models (no constant term) fit the offset instead of the dynamics.
    Remove it with :func:`sysid.detrend` (``return_trend=True`` gives the trend to apply to
    validation data) or use :func:`sysid.identify`, which removes and restores it."""


class StabilityWarning(SysidWarning):
    """An estimator returned an unstable model (a pole on or outside the unit circle): its
    simulation diverges. The message names the largest pole modulus and what to do (for
    example ``ssest(..., focus="simulation")`` or ``stable=True`` / ``enforce_stability``)."""


class IterationLimitWarning(SysidWarning):
    """An iterative search stopped at its iteration cap before a convergence test was met;
    the model is the best iterate found. The message says how far from converged it was and
    what to do (raise ``max_iter``, or refine again from the returned model)."""


class FeedthroughWarning(SysidWarning):
    """A state-space model was fitted without a direct term (``D = 0``, the default at a given
    order) on a record that shows one: with ``D`` estimated, the one-step prediction errors of
    the subspace fit at that order are at least halved. Pass ``feedthrough=True``, or
    ``feedthrough="auto"`` to decide from held-out data (:mod:`sysid.subspace.feedthrough`);
    unless the input is a controller's answer to the same sample's output, where the lag-0
    dependence is the controller's and ``D = 0`` is right."""


class IdentifiabilityWarning(SysidWarning):
    """The data cannot determine some parameters separately (named in the message): a grey-box
    parameter pair, a pole and a zero that cancel, or directions of an over-parameterised
    model; its fit may be good, but those parameters and what depends on them are not
    determined."""


class BoundWarning(SysidWarning):
    """An estimate ended on a bound of its search (the message names the parameter and the
    option to change: a start, the bounds, another structure), or a time constant collapsed
    towards zero, so that its pole acts within one sample and the model is in effect a
    simpler one (the message gives it)."""


def is_frd(data: object) -> bool:
    """Whether ``data`` is frequency-response data (an :class:`sysid.FRD`, MATLAB's
    ``idfrd``), told by its ``omega`` and ``response`` (no import of the model module).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.errors import is_frd
    >>> is_frd(sysid.FRD([1.0], [1.0])), is_frd(sysid.IOData(np.ones(4), np.ones(4)))
    (True, False)
    """
    return hasattr(data, "omega") and hasattr(data, "response")


def is_record(data: object) -> bool:
    """Whether ``data`` is an input/output record (a :class:`sysid.IOData`), told by its
    ``experiments`` and ``input_names`` (no import of the data module).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.errors import is_record
    >>> is_record(sysid.IOData(np.ones(4), np.ones(4))), is_record(np.ones(4))
    (True, False)
    """
    return hasattr(data, "experiments") and hasattr(data, "input_names")


def several_records_hint(data: object) -> str:
    """A hint for a list of records passed where one record goes: MATLAB's ``merge``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.errors import several_records_hint
    >>> a = sysid.IOData(u=np.ones(5), y=np.ones(5))
    >>> several_records_hint([a, a])[:40]
    '; several records are several experiment'
    """
    if isinstance(data, (list, tuple)) and data and all(is_record(d) for d in data):
        return ("; several records are several experiments of one: pass "
                "records[0].merge(*records[1:]) (MATLAB's merge)")
    return ""


def not_a_record(data: object) -> DataError:
    """The error for ``data`` where an IOData record goes (with :func:`several_records_hint`).

    Examples
    --------
    >>> str(not_a_record(3))
    'data must be an IOData record (sysid.IOData(u, y, dt))'
    """
    return DataError("data must be an IOData record (sysid.IOData(u, y, dt))"
                     + several_records_hint(data))


def refuse_frd(data: object, who: str) -> None:
    """A :class:`DataError` naming the estimators that take frequency-response data when
    ``data`` is one (an :class:`sysid.FRD`, MATLAB's ``idfrd``) and ``who`` takes time
    records only.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.errors import refuse_frd
    >>> refuse_frd(sysid.IOData(np.ones(4), np.ones(4)), "arx")  # a record: nothing to say
    """
    if is_frd(data):
        raise DataError(
            f"{who} takes a time record (IOData), got frequency-response data "
            f"({type(data).__name__}): fit it with sysid.ssest(frd, order), "
            "sysid.n4sid(frd, order), sysid.frd_subspace(frd, order), "
            "sysid.oe(frd, nb, nf, nk) or sysid.tfest(frd, n_poles)")
