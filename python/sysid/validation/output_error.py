"""The feedback check of the output-error fits: one helper, said in each estimator's words.

An output-error fit (``oe``, ``tfest`` on a time record, ``ssest``/``pem`` with
``focus="simulation"`` or ``noise="none"``, ``procest``, ``polyest`` with ``na = nc = nd = 0``,
``greyest`` without a noise model) minimises the simulation error ``y - G u`` with no noise
model: it takes the input as independent of the output noise. Under feedback (``u = r - F y``)
the input carries that noise, and the estimate of ``G`` is biased (Ljung 1999, section 13.4;
Forssell & Ljung 1999). The prediction-error fits with a noise model (``arx``, ``armax``,
``bj``, ``ssest`` with the default prediction focus, ``pbsid``, ``ssarx``) are consistent under
feedback when their noise model can describe the noise, and are not checked here.

:func:`output_error` wraps such an estimator: on a time record with inputs it runs
:func:`sysid.check_feedback` once (means removed, default lags: one compression pass of the
record, a few per cent of the fit's time; ``benches/results/warning_audit.md``) and, when the
combined p-value is below :data:`~sysid.validation.feedback.FEEDBACK_WARNING_LEVEL` (1e-6,
the level of the subspace estimators' warning), raises :class:`sysid.FeedbackWarning` after
the fit, naming the inputs, the effect size and the remedy in the estimator's terms
(:data:`REMEDY`). The fit runs inside :func:`feedback_checked`, so that the estimators it
calls (``tfest``'s discrete fit runs ``oe``; ``ssest`` runs ``pem``) neither run the test
again nor warn in their own words; :func:`sysid.identify`, which runs its own feedback check
and sets biased candidates aside, fits its candidates inside it too.

Not checked: frequency-domain data and fits on averaged periods (``periods=``; averaging a
periodic reference's periods removes the noise that biases the fit under feedback), time
series (no input), and the nonlinear estimators (``nlhw``, ``nlgreyest``): the test cannot
tell a nonlinear plant's distortions in open loop from feedback (module notes of
:mod:`sysid.validation.feedback`), and those estimators are used on nonlinear plants.
"""

from __future__ import annotations

import functools
import inspect
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any, TypeVar

from .._display import pvalue
from ..errors import FeedbackWarning, SysidError, is_frd
from .feedback import FEEDBACK_WARNING_LEVEL

__all__ = ["REMEDY", "feedback_checked", "feedback_test", "output_error", "say_fed_back"]

F = TypeVar("F", bound=Callable[..., Any])

#: what each output-error estimator's user can do under feedback, in its own terms
REMEDY = {
    "oe": "use a model with a noise model, consistent under feedback when that model fits "
          "the noise: sysid.bj or sysid.armax, or sysid.ssest(data, order) (prediction "
          "focus, the default)",
    "tfest": "fit a noise model with the plant: sysid.bj or sysid.armax, or "
             "sysid.ssest(data, order) (prediction focus, the default); with a periodic "
             "reference, tfest on the averaged periods (periods=) is not biased by the noise",
    "ssest": "use focus='prediction' (the default: the noise model K makes the fit "
             "consistent under feedback), with a closed-loop start (method='pbsid' or "
             "'ssarx')",
    "pem": "refine with focus='prediction' and noise='estimate' (a noise model K), from a "
           "closed-loop start (sysid.pbsid or sysid.ssarx)",
    "procest": "fit a noise model with the plant (sysid.bj, sysid.armax, or "
               "sysid.ssest(data, order) with the prediction focus), or run the test in open "
               "loop",
    "polyest": "give it a noise model (nc, nd: Box-Jenkins; na with nc: ARMAX), or use "
               "sysid.ssest(data, order) (prediction focus, the default)",
    "greyest": "use focus='prediction' with a noise model (noise='model' with the "
               "structure's K, or noise='estimate')",
}

_CHECKED: ContextVar[bool] = ContextVar("sysid_feedback_checked", default=False)


@contextmanager
def feedback_checked() -> Iterator[None]:
    """Within it, output-error fits neither run the feedback test nor warn: the caller ran it
    (or runs its own) and says it in its words. Usable as a decorator
    (``@feedback_checked()``); :func:`sysid._parallel.ordered` carries it into its threads.

    Examples
    --------
    >>> from sysid.validation.output_error import feedback_checked, _CHECKED
    >>> with feedback_checked():
    ...     inside = _CHECKED.get()
    >>> inside, _CHECKED.get()
    (True, False)
    """
    token = _CHECKED.set(True)
    try:
        yield
    finally:
        _CHECKED.reset(token)


def feedback_test(data: Any) -> Any:
    """:func:`sysid.check_feedback` on ``data`` when it is a time record with inputs (means
    removed, default lags), else None; None too for a record the test cannot read (too
    short, an input that never moves: no claim) and inside :func:`feedback_checked`.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.output_error import feedback_test
    >>> u = np.random.default_rng(0).standard_normal(500)
    >>> feedback_test(sysid.IOData(u=u, y=np.cumsum(u))).detected
    False
    >>> feedback_test(sysid.FRD([1.0], [1.0])) is None
    True
    """
    from ..data.iodata import IOData, as_record
    from .feedback import check_feedback

    if _CHECKED.get():
        return None
    data = as_record(data)
    if is_frd(data) or not isinstance(data, IOData) or data.n_inputs == 0:
        return None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the estimator's own checks speak
            return check_feedback(data)
    except SysidError:
        return None


def say_fed_back(test: Any, method: str) -> None:
    """The :class:`sysid.FeedbackWarning` of ``method`` (a key of :data:`REMEDY`) when
    ``test`` (:func:`feedback_test`'s) has its combined p-value below
    :data:`~sysid.validation.feedback.FEEDBACK_WARNING_LEVEL`: the inputs, the effect size
    and the remedy in the estimator's terms; nothing otherwise.

    Examples
    --------
    >>> import numpy as np, sysid, warnings
    >>> from sysid.validation.output_error import feedback_test, say_fed_back
    >>> rng = np.random.default_rng(0)
    >>> n = 3000; r = rng.standard_normal(n); e = 0.5 * rng.standard_normal(n)
    >>> u, y = np.zeros(n), np.zeros(n)
    >>> for t in range(1, n):
    ...     y[t] = 0.8 * y[t - 1] + u[t - 1] + e[t]
    ...     u[t] = r[t] - 0.5 * y[t - 1]
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     say_fed_back(feedback_test(sysid.IOData(u=u, y=y)), "oe")
    >>> [x.category.__name__ for x in w]
    ['FeedbackWarning']
    """
    from .._checks import user_stacklevel
    if test is None or not test.p_value < FEEDBACK_WARNING_LEVEL:
        return
    m = len(test.p_values)
    names = [n for n, p in zip(test.input_names, test.p_values)
             if m * p < FEEDBACK_WARNING_LEVEL]
    warnings.warn(
        f"{method}: the record shows feedback (past outputs predict "
        f"{'input ' if len(names) == 1 else 'inputs '}{', '.join(names)}, "
        f"{pvalue(test.p_value)}; {test.size_text()}). {method} fits the simulation "
        f"error with no noise model, taking the input as independent of the output noise, "
        f"which a loop feeds back into it: the estimate is biased, more so the larger those "
        f"shares. {REMEDY[method][0].upper()}{REMEDY[method][1:]} (see "
        f"sysid.check_feedback). A nonlinear plant in open loop can show the same (its "
        f"distortions, functions of past inputs, stay in a linear model's outputs): "
        f"sysid.advice(data) weighs both",
        FeedbackWarning, stacklevel=user_stacklevel())


def output_error(method: str, when: Callable[[dict[str, Any]], bool] | None = None
                 ) -> Callable[[F], F]:
    """Decorator of an output-error estimator ``method`` (its first argument ``data``): the
    feedback test on the record before the fit (unless ``periods`` or ``transient`` is given,
    or ``when``, called with the call's arguments and their defaults, says no), the fit inside
    :func:`feedback_checked`, then :func:`say_fed_back`'s warning and the test in the
    model's ``info["feedback_check"]``.

    Examples
    --------
    >>> from sysid.validation.output_error import output_error
    >>> @output_error("pem", when=lambda a: a["focus"] == "simulation")
    ... def fit(data, focus="prediction"):
    ...     return focus
    >>> fit(None, focus="simulation")
    'simulation'
    """
    def wrap(fn: F) -> F:
        sig = inspect.signature(fn)

        @functools.wraps(fn)
        def checked(*args: Any, **kwargs: Any) -> Any:
            if _CHECKED.get():
                return fn(*args, **kwargs)
            test = None
            try:
                bound = sig.bind(*args, **kwargs)
            except TypeError:
                bound = None  # the estimator's own error follows
            if bound is not None:
                bound.apply_defaults()
                a = bound.arguments
                if (a.get("periods") is None and a.get("transient") is None
                        and (when is None or when(a))):
                    test = feedback_test(a["data"])
            with feedback_checked():
                out = fn(*args, **kwargs)
            if test is not None:
                say_fed_back(test, method)
                info = getattr(out, "info", None)
                if isinstance(info, dict):
                    info["feedback_check"] = {
                        "p_value": float(test.p_value), "lags": int(test.lags),
                        "explained": [float(x) for x in test.explained],
                        "explained_new": [float(x) for x in test.explained_new],
                        "warned": bool(test.p_value < FEEDBACK_WARNING_LEVEL)}
            return out
        return checked  # type: ignore[return-value]
    return wrap
