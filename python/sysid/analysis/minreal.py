"""Minimal realisation: cancel what does not reach the output (MATLAB's ``minreal``).

- :class:`~sysid.TransferFunction`: in each pair, a pole and a zero closer than ``tol``
  (relative to their magnitude) cancel, and the gain is kept; a repeated root (which
  ``np.roots`` splits by about ``eps^(1/k)`` for ``k`` copies) is compared by its centre and
  cancels as many times as it occurs in both.
- State-space models: the controllable and observable part, by two staircase
  (orthogonal Hessenberg) reductions: ``ctrb``/``obsv`` rank decisions from an SVD at ``tol``.

A model with a parameter uncertainty keeps it: each draw is reduced the way the estimate
was (the same projection of the states; the roots nearest the ones the estimate cancelled
removed), so its structure does not change from draw to draw.
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
    from ..models.carried import carry
    from ..tf.model import TransferFunction

    if isinstance(sys, TransferFunction):
        plan = _tf_plan(sys, tol)
        return carry(sys, _tf(sys, plan), lambda d: _tf(d, plan))
    if hasattr(sys, "A") and hasattr(sys, "B") and hasattr(sys, "C"):
        check_start(sys, None, "minreal", role="model")
        K = getattr(sys, "K", None)
        # an innovations-form model: the noise enters through K, so the states it reaches
        # are kept too (the noise model and the predictor survive)
        BK = sys.B if K is None else np.hstack([np.asarray(sys.B, float), np.asarray(K, float)])
        T = minimal_basis(np.asarray(sys.A, float), np.asarray(BK, float),
                          np.asarray(sys.C, float), tol)
        return carry(sys, _ss(sys, T), lambda d: _ss(d, T))
    raise DataError(f"minreal needs a TransferFunction or a state-space model, got "
                    f"{type(sys).__name__}")


def _tf_plan(G: Any, tol: float) -> list[list[tuple[np.ndarray, np.ndarray]]]:
    """Per channel, the zeros and the poles that cancel (their values)."""
    plan = []
    for i in range(G.noutputs):
        row = []
        for j in range(G.ninputs):
            z, p = np.roots(G.num[i][j]), np.roots(G.den[i][j])
            zk, pk = _cancel(z, p, tol)
            row.append((_drop(z, zk), _drop(p, pk)))
        plan.append(row)
    return plan


def _drop(r: np.ndarray, gone: np.ndarray) -> np.ndarray:
    """``r`` without the root nearest each of ``gone`` (one each)."""
    left = list(np.asarray(r, complex))
    for g in np.asarray(gone, complex):
        if left:
            left.pop(int(np.argmin([abs(x - g) for x in left])))
    return np.array(left, dtype=complex)


def _tf(G: Any, plan: list[list[tuple[np.ndarray, np.ndarray]]]) -> Any:
    """``G`` with, in each channel, the roots nearest the planned cancelling ones removed."""
    from ..tf.model import TransferFunction

    nums, dens = [], []
    for i in range(G.noutputs):
        rn, rd = [], []
        for j in range(G.ninputs):
            num, den = np.asarray(G.num[i][j], float), np.asarray(G.den[i][j], float)
            zc, pc = plan[i][j]
            z, p = _drop(np.roots(num), zc), _drop(np.roots(den), pc)
            k0 = num[0] if num.size else 0.0
            rn.append(np.real(k0 * np.poly(z)) if z.size else np.array([k0]))
            rd.append(np.real(den[0] * np.poly(p)) if p.size else den[:1].copy())
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


def _ss(sys: Any, T: np.ndarray) -> Any:
    """``sys`` projected on the states ``T`` (orthonormal columns) keeps."""
    A, B, C, D = (np.asarray(x, float) for x in (sys.A, sys.B, sys.C, sys.D))
    K = getattr(sys, "K", None)
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
