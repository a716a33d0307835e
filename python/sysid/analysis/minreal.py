"""Minimal realisation: cancel what does not reach the output (MATLAB's ``minreal``).

- :class:`~sysid.TransferFunction`: in each pair, a pole and a zero closer than ``tol``
  (relative to their magnitude) cancel, and the gain is kept.
- State-space models: the controllable and observable part, by two staircase
  (orthogonal Hessenberg) reductions: ``ctrb``/``obsv`` rank decisions from an SVD at ``tol``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_real
from ..errors import DataError
from ..models.checks import check_start
from ..models.linear import minimal_basis

__all__ = ["minreal"]


def minreal(sys: Any, tol: float | None = None) -> Any:
    """The model without its cancelling or unreachable parts.

    Parameters
    ----------
    sys : TransferFunction, StateSpaceModel or ContinuousStateSpace
    tol : float, optional
        Cancellation (transfer function) or rank (state space) tolerance; default
        ``sqrt(eps)``.

    An innovations-form model keeps the states its noise (``K``) reaches, and its ``K`` and
    noise covariance: its predictions are unchanged.

    Examples
    --------
    >>> import sysid
    >>> G = sysid.TransferFunction([1.0, 1.0], [1.0, 3.0, 2.0])     # (s + 1) / ((s + 1)(s + 2))
    >>> print(sysid.minreal(G))
    y0 <- u0:  1 / (s + 2)
    """
    tol = (float(np.sqrt(np.finfo(float).eps)) if tol is None
           else as_real(tol, "tol (or None for the default)", positive=True))
    from ..tf.model import TransferFunction

    if isinstance(sys, TransferFunction):
        return _tf(sys, tol)
    if hasattr(sys, "A") and hasattr(sys, "B") and hasattr(sys, "C"):
        check_start(sys, None, "minreal", role="model")
        return _ss(sys, tol)
    raise DataError(f"minreal needs a TransferFunction or a state-space model, got "
                    f"{type(sys).__name__}")


def _tf(G: Any, tol: float) -> Any:
    from ..tf.model import TransferFunction

    nums, dens = [], []
    for i in range(G.noutputs):
        rn, rd = [], []
        for j in range(G.ninputs):
            num, den = G.num[i][j], G.den[i][j]
            z, p = list(np.roots(num)), list(np.roots(den))
            keep_p = []
            for pk in p:
                d = [abs(pk - zk) for zk in z]
                k = int(np.argmin(d)) if d else -1
                if k >= 0 and d[k] <= tol * max(1.0, abs(pk)):
                    z.pop(k)
                else:
                    keep_p.append(pk)
            k0 = num[0] if num.size else 0.0
            rn.append(np.real(k0 * np.poly(z)) if z else np.array([k0]))
            rd.append(np.real(np.poly(keep_p)) if keep_p else np.ones(1))
        nums.append(rn)
        dens.append(rd)
    return TransferFunction(nums, dens, dt=G.dt, iodelay=G.iodelay, hold=G.hold,
                            input_names=G.input_names, output_names=G.output_names,
                            info={**G.info, "minreal": True})


def _ss(sys: Any, tol: float) -> Any:
    A, B, C, D = (np.asarray(x, float) for x in (sys.A, sys.B, sys.C, sys.D))
    K = getattr(sys, "K", None)
    # an innovations-form model: the noise enters through K, so the states it reaches are
    # kept too (the noise model and the predictor survive)
    BK = B if K is None else np.hstack([B, np.asarray(K, float)])
    T = minimal_basis(A, BK, C, tol)
    A2, B2, C2 = T.T @ A @ T, T.T @ B, C @ T
    kw = {"input_names": sys.input_names, "output_names": sys.output_names}
    from ..models.continuous import ContinuousStateSpace
    from ..models.statespace import StateSpaceModel

    if isinstance(sys, ContinuousStateSpace):
        return ContinuousStateSpace(A2, B2, C2, D, hold=sys.hold, **kw)
    if K is None:
        return StateSpaceModel(A2, B2, C2, D, dt=sys.dt, **kw)
    return StateSpaceModel(A2, B2, C2, D, T.T @ np.asarray(K, float), dt=sys.dt,
                           noise_cov=getattr(sys, "noise_cov", None), **kw)
