"""Gramians, Hankel singular values and balanced truncation of stable discrete-time models.

The gramians solve ``Wc = A Wc A' + B B'`` and ``Wo = A' Wo A + C' C`` (Smith doubling in the
Rust core); the Hankel singular values are ``sqrt(eig(Wc Wo))``. Balancing uses the square-root
method, and truncation to r states keeps the r largest Hankel singular values with the
H-infinity error bound ``2 * sum(discarded)``. Unstable models raise :class:`sysid.DataError`.

Examples
--------
>>> import numpy as np, sysid
>>> m = sysid.StateSpaceModel([[0.9, 0.0], [0.0, 0.2]], [[1.0], [0.01]], [[1.0, 0.01]])
>>> np.round(sysid.hankel_singular_values(m), 3)
array([5.263, 0.   ])
>>> sysid.balanced_truncation(m, 1).nstates
1
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_int
from ..errors import DataError
from ..models.checks import discrete_statespace
from ..models.statespace import StateSpaceModel

__all__ = [
    "Gramians",
    "gramians",
    "hankel_singular_values",
    "balanced_realization",
    "balanced_truncation",
]


def _check(model: Any) -> StateSpaceModel:
    """The model's discrete state-space form (any :class:`sysid.Model` with one)."""
    if isinstance(model, StateSpaceModel):
        return model
    ss = discrete_statespace(model, "balanced realisation")
    if not isinstance(ss, StateSpaceModel):
        ss = StateSpaceModel(ss.A, ss.B, ss.C, ss.D, dt=ss.dt, input_names=model.input_names,
                             output_names=model.output_names)
    return ss


@dataclass(frozen=True)
class Gramians:
    """Controllability and observability gramians of a stable model.

    Attributes
    ----------
    controllability : ndarray
        ``Wc = A Wc A' + B B'``, ``(n, n)``.
    observability : ndarray
        ``Wo = A' Wo A + C' C``, ``(n, n)``.
    """

    controllability: np.ndarray
    observability: np.ndarray

    def __repr__(self) -> str:
        n = self.controllability.shape[0]
        return (f"Gramians(n={n}, trace Wc={np.trace(self.controllability):.4g}, "
                f"trace Wo={np.trace(self.observability):.4g})")


def gramians(model: StateSpaceModel) -> Gramians:
    """Controllability and observability gramians.

    Examples
    --------
    >>> import sysid
    >>> g = sysid.gramians(sysid.StateSpaceModel([[0.5]], [[1.0]], [[2.0]]))
    >>> round(float(g.controllability[0, 0]), 12), round(float(g.observability[0, 0]), 12)
    (1.333333333333, 5.333333333333)
    """
    m = _check(model)
    wc, wo = _sysid.gramians(m.A, m.B, m.C, m.D)
    return Gramians(wc, wo)


def hankel_singular_values(model: StateSpaceModel) -> np.ndarray:
    """Hankel singular values, decreasing.

    Examples
    --------
    >>> import sysid
    >>> sysid.hankel_singular_values(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.5]]))
    array([2.])
    """
    m = _check(model)
    return np.asarray(_sysid.hankel_singular_values(m.A, m.B, m.C, m.D))


def _reduce(model: StateSpaceModel, order: int | None, method: str) -> StateSpaceModel:
    m = _check(model)
    if order is not None:
        order = as_int(order, "order")
    out = _sysid.balanced_truncation(m.A, m.B, m.C, m.D, None if order is None else int(order))
    t_inv = np.asarray(out["t_inv"])
    info = dict(m.info)
    info.update(
        method=method,
        reduced_from=m.nstates,
        hankel_singular_values=np.asarray(out["hankel_singular_values"]),
        error_bound=float(out["error_bound"]) + 0.0,  # never -0.0 (nothing discarded)
        T=np.asarray(out["t"]),
        T_inv=t_inv,
    )
    return StateSpaceModel(
        out["a"], out["b"], out["c"], out["d"],
        None if m.K is None else t_inv @ m.K,
        dt=m.dt, noise_cov=m.noise_cov, x0=None if m.x0 is None else t_inv @ m.x0,
        input_names=m.input_names, output_names=m.output_names, info=info,
    )


def balanced_realization(model: StateSpaceModel) -> StateSpaceModel:
    """Balanced realisation: both gramians equal ``diag(hankel_singular_values)``.

    The model must be stable and minimal (use :func:`balanced_truncation` otherwise). A
    Kalman gain and initial state are transformed with the states.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.5, 0.2], [0.0, 0.3]], [[1.0], [1.0]], [[1.0, -0.5]])
    >>> g = sysid.gramians(sysid.balanced_realization(m))
    >>> bool(np.allclose(g.controllability, g.observability))
    True
    """
    return _reduce(model, None, "balanced")


def balanced_truncation(model: StateSpaceModel, order: int) -> StateSpaceModel:
    """Balanced truncation to ``order`` states.

    ``info`` of the result holds ``hankel_singular_values`` (of the full model),
    ``error_bound`` (``2 * sum`` of the discarded ones, a bound on the H-infinity error) and
    the projections ``T`` and ``T_inv``. A Kalman gain and initial state are projected with
    the states.

    Examples
    --------
    >>> import sysid
    >>> m = sysid.StateSpaceModel([[0.9, 0.0], [0.0, 0.2]], [[1.0], [0.05]], [[1.0, 0.05]])
    >>> r = sysid.balanced_truncation(m, 1)
    >>> r.nstates, r.info["error_bound"] < 0.01
    (1, True)
    """
    if order is None:
        raise DataError("order is required; use balanced_realization to keep every state")
    return _reduce(model, order, "balanced_truncation")
