"""Checks that a model satisfies :class:`sysid.Model`, and access to optional members.

Kept apart from :mod:`sysid.models.protocol` so that the plots can use them without
importing the result classes (which import the plots).
"""

from __future__ import annotations

from typing import Any

from ..errors import DataError, NonFiniteError

__all__ = [
    "REQUIRED", "FREQUENCY", "check_model", "inner_model", "as_statespace", "discrete_statespace",
    "check_start", "warn_unstable",
]

#: Names a model must have to satisfy :class:`sysid.Model` (checked by :func:`check_model`).
REQUIRED = ("simulate", "predict", "freqresp", "dt", "ninputs", "noutputs", "input_names",
            "output_names", "n_parameters", "info")
#: The frequency-domain part, enough for Bode and sigma plots (e.g. :class:`sysid.FRD`).
FREQUENCY = ("freqresp", "ninputs", "noutputs", "input_names", "output_names")


def inner_model(obj: Any) -> Any:
    """The model a result holds (``sysid.identify``'s, ``greyest``'s, ...: its ``.model``)
    when ``obj`` is such a result and not a model itself; ``obj`` otherwise."""
    if callable(getattr(obj, "simulate", None)):
        return obj
    inner = getattr(obj, "model", None)
    return inner if callable(getattr(inner, "simulate", None)) else obj


def check_model(model: Any, what: str = "model", members: tuple[str, ...] = REQUIRED) -> Any:
    """Return ``model`` if it satisfies :class:`Model` (a result that holds one, such as
    ``sysid.identify``'s, gives its ``.model``), else raise a :class:`DataError` naming the
    missing members.

    Examples
    --------
    >>> from sysid.models.protocol import check_model
    >>> check_model(object())
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: model must satisfy sysid.Model (e.g. a sysid.StateSpaceModel); ...
    """
    missing = [name for name in members if not hasattr(model, name)]
    inner = inner_model(model)
    if missing and inner is not model:
        return check_model(inner, what, members)
    if missing:
        raise DataError(
            f"{what} must satisfy sysid.Model (e.g. a sysid.StateSpaceModel); "
            f"{type(model).__name__} lacks "
            f"{', '.join(missing)} (see sysid.models.protocol for the interface)"
        )
    return model


def require_freqresp(model: Any, name: str) -> None:
    """Refuse a ``model`` without ``freqresp(omega)``, naming the argument."""
    if not callable(getattr(model, "freqresp", None)):
        raise DataError(f"{name} must be a model with freqresp(omega) (a StateSpaceModel, "
                        f"TransferFunction, ...), got {type(model).__name__}")


def as_statespace(model: Any, purpose: str) -> Any:
    """``model.to_statespace()``, or a :class:`DataError` naming ``purpose`` and the
    missing method."""
    conv = getattr(model, "to_statespace", None)
    if conv is None:
        raise DataError(
            f"{purpose} needs a state-space form, but {type(model).__name__} has no "
            "to_statespace() method; add one (returning a sysid.StateSpaceModel)"
        )
    return conv()


def _optional(model: Any, name: str, purpose: str) -> Any:
    """Call ``model.name()`` or ``model.to_statespace().name()``, or raise naming both."""
    fn = getattr(model, name, None)
    if fn is not None:
        return fn()
    return getattr(as_statespace(model, f"{purpose} ({name}())"), name)()


def discrete_statespace(model: Any, purpose: str) -> Any:
    """The discrete state-space form of any model, for tools working on ``A, B, C, D``.

    A model with ``A``, ``B``, ``C``, ``D`` and ``dt > 0`` is returned as it is; others go
    through ``to_statespace()``; a continuous-time model is told to discretise first.
    """
    model = check_model(model)
    if all(hasattr(model, k) for k in ("A", "B", "C", "D")) and model.dt:
        return model
    if not model.dt:
        raise DataError(f"{purpose} works on discrete-time models; discretise first with "
                        "model.c2d(dt)")
    ss = as_statespace(model, purpose)
    if not all(hasattr(ss, k) for k in ("A", "B", "C", "D")):
        raise DataError(f"{type(model).__name__}.to_statespace() returned a "
                        f"{type(ss).__name__}, not a state-space model")
    return ss


def check_start(model: Any, data: Any, who: str, role: str = "start model") -> None:
    """Refuse a start model that ``who`` could only misuse: a matrix with a NaN or Inf (set
    after construction) raises a :class:`~sysid.errors.NonFiniteError` naming it; a sample
    time other than the record's (an :class:`~sysid.IOData`) a :class:`DataError`, worded as
    :func:`sysid.compare` words it (the refined model would be relabelled with the data's).
    ``role``: what the model is to ``who`` in the messages (``"model"`` for a function that
    analyses or scores it rather than starting from it; ``data=None``: no record).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.models.checks import check_start
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=1.0)
    >>> check_start(m, sysid.IOData(u=np.ones(5), y=np.arange(5.0), dt=0.1), "pem")
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: the data are sampled every 0.1 s but the start model every 1 s; ...
    """
    import numpy as np

    for name in ("A", "B", "C", "D", "K", "noise_cov"):
        mat = getattr(model, name, None)
        if mat is None:
            continue
        arr = np.asarray(mat)
        if arr.dtype.kind in "biufc" and not np.all(np.isfinite(arr)):
            raise NonFiniteError(
                f"the {role}'s {name} has non-finite entries (NaN or Inf): {who} cannot "
                + ("start from it; give a start whose matrices are finite (e.g. from "
                   "sysid.n4sid(data, order))" if role == "start model" else
                   f"use it; set {name} back to finite values (or rebuild the model)"))
    dt, data_dt = getattr(model, "dt", None), getattr(data, "dt", None)
    if (dt and data_dt and hasattr(data, "experiments")
            and not np.isclose(data_dt, dt, rtol=1e-9)):
        raise DataError(
            f"the data are sampled every {data_dt:.10g} s but the {role} every "
            f"{dt:.10g} s; {who} would "
            + ("relabel the model" if role == "start model" else "use the wrong time base")
            + f": resample the data or use a {role} of the same sample time "
            "(sysid.c2d(sysid.d2c(model), data.dt) resamples one)")


def warn_unstable(model: Any, method: str, closed_loop: bool = False,
                  advice: str | None = None) -> None:
    """:class:`~sysid.errors.StabilityWarning` when a fit returns an unstable model (a pole
    on or outside the unit circle; in the right half-plane for a continuous model), naming
    the pole and what to do (``advice``; by default the subspace estimators' options).

    Examples
    --------
    >>> import warnings, sysid
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     warn_unstable(sysid.StateSpaceModel([[1.2]], [[1.0]], [[1.0]]), "n4sid")
    >>> w[0].category.__name__
    'StabilityWarning'
    """
    import warnings

    import numpy as np

    from .._checks import user_stacklevel
    from .._display import modulus as display_modulus
    from ..errors import StabilityWarning

    if getattr(model, "nstates", None) == 0:
        return
    poles = np.asarray(model.poles(), dtype=complex).ravel()
    if poles.size == 0 or not np.all(np.isfinite(poles)):
        return
    if not getattr(model, "dt", 1.0):  # continuous time: the right half-plane
        k = int(np.argmax(poles.real))
        if poles[k].real < 0:
            return
        warnings.warn(StabilityWarning(
            f"{method} returned an unstable model: pole {poles[k]:.4g} has real part "
            f"{poles[k].real:.4g} >= 0, so its simulation diverges. " + (advice or "")),
            stacklevel=user_stacklevel())
        return
    k = int(np.argmax(np.abs(poles)))
    if abs(poles[k]) < 1.0:
        return
    if advice is not None:
        warnings.warn(StabilityWarning(
            f"{method} returned an unstable model: pole {poles[k]:.4g} has modulus "
            f"{display_modulus(abs(poles[k]))} >= 1, so its simulation diverges. {advice}"),
            stacklevel=user_stacklevel())
        return
    others = " or ".join(f"method={w!r}" for w in ("moesp", "n4sid", "cva") if w != method)
    warnings.warn(StabilityWarning(
        f"{method} returned an unstable model: pole {poles[k]:.4g} has modulus "
        f"{display_modulus(abs(poles[k]))} >= 1, so its simulation diverges. Unless the "
        "process itself is unstable, " + (
                        "refine it with sysid.pem(data, model, focus='simulation') (which "
                        "keeps the simulation stable), or try a lower order or another horizon"
                        if closed_loop else
                        "use stable=True (reflects the unstable poles inside the unit circle), "
                        f"another weighting ({others}), a lower order or a longer "
                        "horizon, or refine with sysid.ssest(data, order, focus='simulation')")),
        stacklevel=user_stacklevel())
