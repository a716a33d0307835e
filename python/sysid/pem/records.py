"""The record a time-domain estimator takes: an :class:`~sysid.IOData` or a ``(u, y)`` pair;
an FRD is refused with the estimators that take one named (shared by :func:`sysid.pem`,
:func:`sysid.ssest` and :func:`sysid.greyest`).

Examples
--------
>>> import numpy as np
>>> _experiments((np.zeros(4), np.ones(4))).n_samples
4
"""

from __future__ import annotations

from typing import Any

from ..data.iodata import IOData
from ..errors import DataError, is_frd, several_records_hint

__all__ = ["_experiments"]


def _experiments(data: Any) -> IOData:
    if isinstance(data, IOData):
        return data
    if isinstance(data, tuple) and len(data) == 2:
        return IOData(u=data[0], y=data[1])
    if is_frd(data):  # MATLAB's idfrd
        raise DataError("this takes a time record; for a frequency response fit "
                        "sysid.ssest(frd, order) or sysid.frd_subspace(frd, order) (a "
                        "state-space model; refine it with sysid.pem(frd, model)) or "
                        "sysid.tfest(frd, n_poles), or pass the record itself (with periods= "
                        "for periodic data: the fit is then on its excited lines)")
    raise DataError(f"data must be a sysid.IOData or a (u, y) pair, got {type(data).__name__}"
                    + several_records_hint(data))
