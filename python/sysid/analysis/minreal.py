"""Minimal realisation: cancel what does not reach the output (MATLAB's ``minreal``).

- :class:`~sysid.TransferFunction`: in each pair, a pole and a zero closer than ``tol``
  (relative to their magnitude) cancel, and the gain is kept; a repeated root (which
  ``np.roots`` splits by about ``eps^(1/k)`` for ``k`` copies) is compared by its centre and
  cancels as many times as it occurs in both.
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
            z, p = _cancel(np.roots(num), np.roots(den), tol)
            k0 = num[0] if num.size else 0.0
            rn.append(np.real(k0 * np.poly(z)) if z.size else np.array([k0]))
            rd.append(np.real(np.poly(p)) if p.size else np.ones(1))
        nums.append(rn)
        dens.append(rd)
    return TransferFunction(nums, dens, dt=G.dt, iodelay=G.iodelay, hold=G.hold,
                            input_names=G.input_names, output_names=G.output_names,
                            info={**G.info, "minreal": True})


def _spread(k: int, tol: float) -> float:
    """How far (relative) ``np.roots`` may scatter the ``k`` copies of a ``k``-fold root about
    it: ``eps^(1/k)`` times the root's conditioning (``2.8e-8`` for the double root of
    ``(s + 1)^2``, ``1.4e-3`` for ``(s + 1)^5`` beside ``s + 3``); ``tol`` stands for
    ``sqrt(eps)``."""
    return float((1e4 * tol * tol) ** (1.0 / k))


def _clusters(r: np.ndarray, tol: float) -> list[list[Any]]:
    """``r`` as ``[centre, count, members]`` groups, one per multiple root: the ``k`` roots
    nearest one of them, all within :func:`_spread` of their mean (the largest such ``k``),
    are one root at that mean (accurate to about ``eps^(2/k)``: the scatter cancels in the
    sum)."""
    left = list(range(r.size))
    out = []
    while left:
        order = np.argsort(np.abs(r[left] - r[left[0]]), kind="stable")
        members, centre = [left[0]], complex(r[left[0]])
        for k in range(len(left), 1, -1):
            group = [left[o] for o in order[:k]]
            c = complex(np.mean(r[group]))
            if np.max(np.abs(r[group] - c)) <= _spread(k, tol) * max(1.0, abs(c)):
                members, centre = group, c
                break
        out.append([centre, len(members), members])
        left = [x for x in left if x not in members]
    return out


def _cancel(z: np.ndarray, p: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Zeros and poles left when each (multiple) pole cancels the (multiple) zeros whose
    centre is within ``tol`` (relative) of its own, as often as both occur (a multiple root
    some of whose copies cancel keeps the others at its centre); then, root by root, a pole
    and a zero within ``tol`` of each other."""
    zc, pc = _clusters(z, tol), _clusters(p, tol)
    for c in pc:
        while c[1] > 0:
            near = [(abs(c[0] - q[0]), n) for n, q in enumerate(zc) if q[1] > 0]
            if not near:
                break
            dist, n = min(near)
            # a k-fold root's centre is found to about eps^(2/k), looser than tol for k > 3
            k = max(c[1], zc[n][1])
            if dist > max(tol, _spread(k, tol) ** 2) * max(1.0, abs(c[0])):
                break
            gone = min(c[1], zc[n][1])
            for x in (c, zc[n]):
                x[1] -= gone
                x[2] = None            # cancelled in part: what is left sits at the centre

    def left(cs: list[list[Any]], r: np.ndarray) -> list[complex]:
        return [complex(v) for c in cs
                for v in (r[c[2]] if c[2] is not None else np.full(c[1], c[0]))]

    zs, keep = left(zc, z), []
    for pk in left(pc, p):
        d = [abs(pk - zk) for zk in zs]
        k = int(np.argmin(d)) if d else -1
        if k >= 0 and d[k] <= tol * max(1.0, abs(pk)):
            zs.pop(k)
        else:
            keep.append(pk)
    return np.array(zs, dtype=complex), np.array(keep, dtype=complex)


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
