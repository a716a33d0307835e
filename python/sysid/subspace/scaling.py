"""Channel scaling of the subspace methods: every input and output divided by its root mean
square (read from the record's factor, which is then scaled and triangularised again:
``HankelFactor.scaled``, no pass over the data), and the model returned in the record's
units.

The subspace weightings (MOESP's, N4SID's) and the least-squares steps for ``B`` and ``D``
weigh every output's errors in its own units, so the estimate changes with them: a
displacement recorded in millimetres rather than metres takes over the fit. Computing on
channels of unit root mean square makes the model the same whatever the units (up to
rounding): an output recorded 1000 times larger gives an output matrix 1000 times larger and
nothing else changes. SLICOT's ``IB01AD`` computes in the record's
units; ``SubspaceEstimator(data, scale=False)`` reproduces it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..models.statespace import StateSpaceModel

__all__ = ["SCALE_DEFAULT", "in_record_units", "rescaled", "scaled_experiments"]

#: scale the channels to unit root mean square by default (unit-invariant estimates)
SCALE_DEFAULT = True


def rescaled(model: StateSpaceModel, su: np.ndarray, sy: np.ndarray) -> StateSpaceModel:
    """A model fitted to inputs divided by ``su`` and outputs by ``sy``, in the record's
    units: ``B / su``, ``sy C``, ``sy D / su``, ``K / sy``, the innovation covariance and a
    subspace fit's noise covariances ``R``, ``S`` in ``info`` with the output scales (``A``,
    ``Q`` and the initial state are unchanged). Shared with :func:`sysid.pem`'s output
    scaling.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.subspace.scaling import rescaled
    >>> m = rescaled(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), np.array([2.0]),
    ...              np.array([10.0]))
    >>> float(m.B[0, 0]), float(m.C[0, 0])
    (0.5, 10.0)
    """
    if np.all(su == 1.0) and np.all(sy == 1.0):
        return model
    s = sy[:, None]
    info = dict(model.info)
    if info.get("R") is not None:
        info["R"] = s * np.asarray(info["R"]) * sy[None, :]
    if info.get("S") is not None:
        info["S"] = np.asarray(info["S"]) * sy[None, :]
    return StateSpaceModel(
        model.A, model.B / su[None, :], s * model.C, s * model.D / su[None, :],
        None if model.K is None else model.K / sy[None, :], dt=model.dt,
        noise_cov=None if model.noise_cov is None else s * model.noise_cov * sy[None, :],
        x0=model.x0, input_names=model.input_names, output_names=model.output_names,
        info=info)


def in_record_units(model: StateSpaceModel, su: np.ndarray, sy: np.ndarray) -> StateSpaceModel:
    """A subspace model fitted on the scaled factor, :func:`rescaled` to the record's units,
    the scales recorded in ``info["channel_scaling"]``."""
    if np.all(su == 1.0) and np.all(sy == 1.0):
        return model
    out = rescaled(model, su, sy)
    out.info["channel_scaling"] = {"input_rms": su.tolist(), "output_rms": sy.tolist()}
    return out


def scaled_experiments(data: IOData, su: np.ndarray, sy: np.ndarray
                       ) -> list[tuple[Any, Any]]:
    """The record's experiments with every channel divided by its scale (copies; the record
    itself unchanged)."""
    if np.all(su == 1.0) and np.all(sy == 1.0):
        return list(data.experiments)
    return [(u / su if u.shape[1] else u, y / sy) for u, y in data.experiments]
