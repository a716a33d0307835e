"""State-space to transfer function (MATLAB's ``tf(sys)`` / ``idtf(sys)``, python-control's
``ss2tf``).

Each output/input pair ``(i, j)`` of ``y = (C (zI - A)^-1 B + D) u`` (``s`` for a
continuous model) is the ratio of two polynomials: the characteristic polynomial
``det(zI - A)`` and, for the pair's row ``c_i`` and column ``b_j``, ``det(zI - A + b_j c_i) -
det(zI - A) + d_ij det(zI - A)`` (the determinant lemma for a rank-one change). Every pair
keeps the full order: a mode the pair does not see cancels against a zero, and
:func:`sysid.minreal` removes it. The parameter uncertainty of an estimated model goes through
the same map, so the coefficients, poles and responses of the transfer function carry their
standard deviations. The noise model (``K``) is not converted.

Examples
--------
>>> import sysid
>>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[2.0]], dt=0.1)
>>> print(sysid.ss2tf(m))
y0 <- u0:  2 / (z - 0.5)
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError
from ..models.carried import carry
from .model import TransferFunction, statespace_polynomials

__all__ = ["ss2tf"]


def ss2tf(model: Any) -> TransferFunction:
    """The transfer function of a state-space model, one entry per output and input.

    Parameters
    ----------
    model : StateSpaceModel, ContinuousStateSpace, or a model with ``to_statespace()``
        Discrete models give polynomials in ``z`` (``dt`` kept), continuous ones in ``s``.

    Returns
    -------
    TransferFunction
        Every entry over ``det(zI - A)`` (module docstring; :func:`sysid.minreal` cancels
        the modes a pair does not see); with the model's parameter uncertainty carried
        (``G.poles(std=True)``, ``G.freqresp(w, std=True)``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.9, 0.2], [0.0, 0.5]], [[1.0], [1.0]], [[1.0, 0.0]])
    >>> G = sysid.ss2tf(m)
    >>> np.round(G.num[0][0], 6).tolist(), np.round(G.den[0][0], 6).tolist()
    ([1.0, -0.3], [1.0, -1.4, 0.45])
    >>> bool(np.allclose(G.freqresp([0.3]), m.freqresp([0.3])))
    True
    """
    from ..models.continuous import ContinuousStateSpace
    from ..models.statespace import StateSpaceModel

    ss = model
    if not isinstance(ss, (StateSpaceModel, ContinuousStateSpace)):
        if not hasattr(ss, "to_statespace"):
            raise DataError(f"ss2tf needs a state-space model (or one with to_statespace()), "
                            f"got {type(model).__name__}")
        ss = ss.to_statespace()
    A, B, C, D = (np.asarray(x, dtype=float) for x in (ss.A, ss.B, ss.C, ss.D))
    if not all(np.all(np.isfinite(x)) for x in (A, B, C, D)):
        raise DataError("the model has non-finite matrices: no transfer function")
    nums, dens = statespace_polynomials(A, B, C, D)
    continuous = isinstance(ss, ContinuousStateSpace)
    G = TransferFunction(nums, dens, dt=0.0 if continuous else float(ss.dt),
                         hold=getattr(ss, "hold", "zoh"), input_names=ss.input_names,
                         output_names=ss.output_names,
                         info={"method": "ss2tf", "from": dict(getattr(ss, "info", {}) or {})
                               .get("method", type(model).__name__)})
    return carry(model if getattr(model, "uncertainty", None) is not None else ss, G, ss2tf)
