"""A validation record given beside estimation data, checked before any fit: the one rule
``identify``, ``pnlss`` and ``nlssest`` share."""

from __future__ import annotations

from typing import Any

from ..data.iodata import IOData
from ..errors import DataError, InsufficientDataError, several_records_hint
from .fit import require_outputs_vary

__all__ = ["validation_record"]


def validation_record(validation: Any, data: IOData) -> IOData | None:
    """``validation`` as an :class:`IOData` (a ``(u, y)`` pair takes ``data``'s sample
    time), refused with a :class:`~sysid.DataError` naming the mismatch when its channels or
    sample time differ from ``data``'s, an experiment has fewer than two samples or an
    output stands still (a fit against it is undefined): said before the fit, not as a
    failure after it. ``None`` stays ``None``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.records import validation_record
    >>> d = sysid.IOData(u=np.ones((10, 2)), y=np.arange(10.0))
    >>> validation_record((np.ones((5, 2)), np.arange(5.0)), d).lengths
    [5]
    """
    if validation is None:
        return None
    if isinstance(validation, tuple) and len(validation) == 2:
        validation = IOData(u=validation[0], y=validation[1], dt=data.dt)
    if not isinstance(validation, IOData):
        raise DataError(f"validation must be a sysid.IOData or a (u, y) pair, got "
                        f"{type(validation).__name__}" + several_records_hint(validation))
    if (validation.n_inputs, validation.n_outputs) != (data.n_inputs, data.n_outputs):
        raise DataError(f"validation has {validation.n_inputs} input(s) and "
                        f"{validation.n_outputs} output(s), the estimation data "
                        f"{data.n_inputs} and {data.n_outputs}: give the same channels")
    if abs(float(validation.dt) - float(data.dt)) > 1e-9 * float(data.dt):
        raise DataError(f"validation is sampled every {validation.dt:.10g} s, the estimation "
                        f"data every {data.dt:.10g} s: resample one of them (sysid.resample)")
    if min(validation.lengths) < 2:  # one sample is "constant": say what is wrong
        raise InsufficientDataError(
            f"the validation record is too short ({min(validation.lengths)} sample in an "
            "experiment): a fit against it needs an output that can vary; pass a longer one")
    require_outputs_vary([y for _, y in validation.experiments], validation.output_names)
    return validation
