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

The realisations from Markov parameters (:func:`sysid.era`, :func:`sysid.kung`,
:func:`sysid.ho_kalman`) and :func:`sysid.frd_subspace` have no record to take root mean
squares from: they divide each output row and multiply each input column of the response by
the scales that give every output row and every input column a unit root mean square over
lags (or frequencies) and the other channels, :func:`balanced_scales`. Those scales change
with the units exactly as the channels do, so the scaled response, and the model, do not
depend on them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import DataError
from ..models.statespace import StateSpaceModel

__all__ = ["SCALE_DEFAULT", "balanced_scales", "check_scale", "in_record_units", "record_rms",
           "rescaled", "safe_rms", "scaled_experiments"]

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


def in_record_units(model: StateSpaceModel, su: np.ndarray, sy: np.ndarray,
                    basis: str | None = None) -> StateSpaceModel:
    """A subspace model fitted on the scaled factor, :func:`rescaled` to the record's units,
    the scales recorded in ``info["channel_scaling"]``: ``input_rms`` and ``output_rms``, or
    for scales from a response (:func:`balanced_scales`) ``input_scale``, ``output_scale``
    and the ``basis`` they were taken from."""
    if np.all(su == 1.0) and np.all(sy == 1.0):
        return model
    out = rescaled(model, su, sy)
    out.info["channel_scaling"] = (
        {"input_rms": su.tolist(), "output_rms": sy.tolist()} if basis is None else
        {"input_scale": su.tolist(), "output_scale": sy.tolist(), "basis": basis})
    return out


def check_scale(scale: Any) -> bool:
    """``scale`` as a bool (``None``: :data:`SCALE_DEFAULT`); anything else is named."""
    value = SCALE_DEFAULT if scale is None else scale
    if not isinstance(value, (bool, np.bool_)):
        raise DataError(f"scale must be True or False, got {scale!r}")
    return bool(value)


def _channel(kind: str, k: int, names: Any) -> str:
    name = names[k] if names is not None and k < len(names) else None
    default = ("u" if kind == "input" else "y") + str(k)  # IOData's names when none given
    return f"{kind} {k}" + (f" ({name!r})" if name and name != default else "")


def record_rms(data: IOData) -> tuple[np.ndarray, np.ndarray]:
    """The record's input and output root mean squares over all its experiments (ones with a
    single input and output: nothing to weigh); a channel that is zero throughout is named."""
    if data.n_inputs * data.n_outputs == 1:
        return np.ones(1), np.ones(1)
    out = []
    for kind, k, names in (("input", 0, data.input_names), ("output", 1, data.output_names)):
        rms = safe_rms(np.concatenate([e[k] for e in data.experiments]), 0)
        dead = np.flatnonzero(~(rms > 0) | ~np.isfinite(rms))
        if dead.size:
            raise DataError(f"{_channel(kind, int(dead[0]), names)} has root mean square "
                            f"{rms[dead[0]]:g}: it cannot be scaled; leave the channel out, "
                            "or pass scale=False")
        out.append(rms)
    return out[0], out[1]


def safe_rms(x: np.ndarray, axis: Any) -> np.ndarray:
    """Root mean square over ``axis``, without overflow for entries beyond 1e154.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.subspace.scaling import safe_rms
    >>> safe_rms(np.array([[3e200, 0.0], [-3e200, 0.0]]), 0).tolist()
    [3e+200, 0.0]
    """
    big = np.max(np.abs(x), axis=axis, keepdims=True)
    safe = np.where(big > 0, big, 1.0)
    return np.squeeze(big, axis=axis) * np.sqrt(np.mean(np.abs(x / safe) ** 2, axis=axis))


def balanced_scales(response: np.ndarray, what: str, input_names: Any = None,
                    output_names: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """Input and output scales ``su``, ``sy`` of a response ``(count, noutputs, ninputs)``
    (Markov parameters, or a frequency response over frequency): ``response * su / sy``
    (each input column times its scale, each output row divided by its) has unit root mean
    square over the lags and inputs of every output row and over the lags and outputs of
    every input column.

    This balancing (Sinkhorn and Knopp's on the entries' mean squares) changes with the
    units as the channels do: outputs ``ky`` times larger give scales ``ky`` times larger,
    inputs ``ku`` times larger scales ``ku`` times larger, and the balanced response is the
    same. It starts from the least-squares fit of the log mean squares by output and input
    terms, which changes with the units in the same way, so every iterate does (exact
    invariance also when coupled channels make the balancing converge slowly). With one input
    and one output there is nothing to weigh: ones. A channel without response (all zero) is
    named.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.subspace.scaling import balanced_scales
    >>> h = np.array([[[1.0, 2.0], [300.0, 600.0]]])
    >>> su, sy = balanced_scales(h, "Markov parameters")
    >>> bool(np.allclose(h * su / sy[:, None], 1.0))
    True
    """
    _, l, m = response.shape
    if l * m == 1:
        return np.ones(1), np.ones(1)
    ms = safe_rms(response, 0) ** 2  # (l, m) mean squares over lags / frequencies
    for kind, axis, names in (("output", 1, output_names), ("input", 0, input_names)):
        dead = np.flatnonzero(np.all(ms == 0, axis=axis))
        if dead.size:
            raise DataError(
                f"{_channel(kind, int(dead[0]), names)} has no response (all its {what} are "
                f"zero): it cannot be scaled; leave the channel out, or pass scale=False")
    if not np.all(np.isfinite(ms)):
        raise DataError(f"the {what} are too large to scale in double precision")
    i, j = np.nonzero(ms)
    fit = np.zeros((i.size, l + m))
    fit[np.arange(i.size), i] = 1.0
    fit[np.arange(i.size), l + j] = -1.0
    z = np.linalg.lstsq(fit, np.log(ms[i, j]), rcond=None)[0]
    vy, xu = np.exp(z[:l]), np.exp(z[l:])  # squared scales
    for _ in range(500):
        vy_new = ms @ xu / m
        xu_new = l / (vy_new ** -1 @ ms)  # 1 / mean over the outputs of ms / vy
        done = (np.max(np.abs(vy_new / vy - 1.0)) < 1e-14
                and np.max(np.abs(xu_new / xu - 1.0)) < 1e-14)
        vy, xu = vy_new, xu_new
        if done:
            break
    g = np.exp(np.mean(np.log(xu)) / 2)  # the common factor: input scales of geometric mean 1
    return np.sqrt(xu) / g, np.sqrt(vy) / g


def scaled_experiments(data: IOData, su: np.ndarray, sy: np.ndarray
                       ) -> list[tuple[Any, Any]]:
    """The record's experiments with every channel divided by its scale (copies; the record
    itself unchanged)."""
    if np.all(su == 1.0) and np.all(sy == 1.0):
        return list(data.experiments)
    return [(u / su if u.shape[1] else u, y / sy) for u, y in data.experiments]
