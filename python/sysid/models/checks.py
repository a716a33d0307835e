"""Checks that a model satisfies :class:`sysid.Model`, and access to optional members.

Kept apart from :mod:`sysid.models.protocol` so that the plots can use them without
importing the result classes (which import the plots).
"""

from __future__ import annotations

from typing import Any

from ..errors import DataError

__all__ = ["REQUIRED", "FREQUENCY", "check_model", "as_statespace"]

#: Names a model must have to satisfy :class:`sysid.Model` (checked by :func:`check_model`).
REQUIRED = ("simulate", "predict", "freqresp", "dt", "ninputs", "noutputs", "input_names",
            "output_names", "n_parameters", "info")
#: The frequency-domain part, enough for Bode and sigma plots (e.g. :class:`sysid.FRD`).
FREQUENCY = ("freqresp", "ninputs", "noutputs", "input_names", "output_names")


def check_model(model: Any, what: str = "model", members: tuple[str, ...] = REQUIRED) -> Any:
    """Return ``model`` if it satisfies :class:`Model`, else raise a :class:`DataError`
    naming the missing members.

    Examples
    --------
    >>> from sysid.models.protocol import check_model
    >>> check_model(object())
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: model must satisfy sysid.Model (e.g. a sysid.StateSpaceModel); ...
    """
    missing = [name for name in members if not hasattr(model, name)]
    if missing:
        raise DataError(
            f"{what} must satisfy sysid.Model (e.g. a sysid.StateSpaceModel); "
            f"{type(model).__name__} lacks "
            f"{', '.join(missing)} (see sysid.models.protocol for the interface)"
        )
    return model


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
