"""Controllability and observability: the Kalman matrices and the staircase rank tests.

Moved out of :mod:`sysid.analysis.lti` (which re-exports them) to keep modules short.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.linalg

__all__ = ["ctrb", "obsv", "is_controllable", "is_observable"]


def _statespace(model: Any, purpose: str) -> Any:
    """``model`` when it has ``A, B, C``, else its ``to_statespace()`` (a transfer function's
    realisation), else a :class:`~sysid.DataError` naming ``purpose``."""
    if all(hasattr(model, k) for k in ("A", "B", "C")):
        return model
    from ..models.checks import as_statespace

    return as_statespace(model, purpose)


def ctrb(model: Any) -> np.ndarray:
    """Controllability matrix ``[B, AB, ..., A^{n-1} B]``, shape ``(n, n m)``.

    Parameters
    ----------
    model : state-space model or TransferFunction
        Anything with ``A`` and ``B``, or a ``to_statespace()`` (its realisation).

    Returns
    -------
    ndarray
        ``(n, n m)``; ``(0, 0)`` for a static gain.
    """
    model = _statespace(model, "ctrb")
    A, B = model.A, model.B
    blocks, ab = [], B
    for _ in range(A.shape[0]):
        blocks.append(ab)
        ab = A @ ab
    return np.hstack(blocks) if blocks else np.zeros((0, 0))


def obsv(model: Any) -> np.ndarray:
    """Observability matrix ``[C; CA; ...; C A^{n-1}]``, shape ``(n l, n)``.

    Parameters
    ----------
    model : state-space model or TransferFunction
        Anything with ``A`` and ``C``, or a ``to_statespace()`` (its realisation).

    Returns
    -------
    ndarray
        ``(n l, n)``; ``(0, 0)`` for a static gain.
    """
    return ctrb(_Transposed(_statespace(model, "obsv"))).T


class _Transposed:
    def __init__(self, model: Any) -> None:
        self.A, self.B, self.C = model.A.T, model.C.T, model.B.T


def _balanced(A: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(A, B)`` after a diagonal state similarity (powers of 2, exact) that balances the
    rows and columns of ``[[A, B], [0, 0]]`` (LAPACK ``gebal`` without permutation, as SLICOT
    TB01ID does for ``A`` and ``B``): a badly scaled state basis is undone before any rank is
    judged. The input coordinates are left alone (their rows are zero)."""
    n, m = B.shape
    S = np.zeros((n + m, n + m))
    S[:n, :n], S[:n, n:] = A, B
    _, (scale, _) = scipy.linalg.matrix_balance(S, permute=False, separate=True)
    t = scale[:n]
    return A * (t[None, :] / t[:, None]), B / t[:, None]


def _staircase_ok(A: np.ndarray, B: np.ndarray, tol: float | None) -> bool:
    """Controllability by the orthogonal staircase (block Hessenberg) form of SLICOT AB01ND.

    The pair is balanced (:func:`_balanced`), ``A`` shifted by ``trace(A)/n`` and scaled to
    unit norm, ``B`` scaled to unit norm (none of which changes controllability), so the rank
    decisions, singular values ``> tol``, do not depend on the scale of ``B``, of ``A`` or of
    the states. Each step rotates the reachable directions of the current input block to the
    top; the coupling of the rest to them is the next block. A zero-rank block leaves states
    that no input reaches.
    """
    n = A.shape[0]
    if n == 0:
        return True
    if not B.size or not np.any(B):
        return False
    tol = n * np.finfo(float).eps * 1e3 if tol is None else float(tol)
    A, B = _balanced(A, B)
    A = A - (np.trace(A) / n) * np.eye(n)
    norm_a = float(np.linalg.norm(A, 2))
    if norm_a > 0:
        A = A / norm_a
    Z, rest = B / float(np.linalg.norm(B, 2)), A
    while True:
        U, sv, _ = np.linalg.svd(Z, full_matrices=True)
        r = int(np.sum(sv > tol))
        if r == rest.shape[0]:
            return True
        if r == 0:
            return False
        rest = U.T @ rest @ U
        Z, rest = rest[r:, :r], rest[r:, r:]


def is_controllable(model: Any, tol: float | None = None) -> bool:
    """Whether every state can be reached from the inputs (the rank of :func:`ctrb` is n).

    Decided on the orthogonal staircase form of ``(A, B)`` (SLICOT AB01ND), not on the powers
    of ``A`` in :func:`ctrb`, whose columns lose precision as they grow. The answer does not
    change when ``B`` is multiplied by a nonzero scalar, nor ``A`` (or shifted by a multiple
    of the identity), nor under a diagonal change of the state scaling (undone by balancing,
    as SLICOT TB01ID): ``A`` and ``B`` are each brought to unit norm first, and each rank is
    judged by singular values above ``tol`` (default ``1000 n eps``) relative to that.

    Parameters
    ----------
    model : state-space model or TransferFunction
        Anything with ``A`` and ``B``, or a ``to_statespace()`` (its realisation).
    tol : float, optional
        Relative rank tolerance; larger values call weakly coupled states uncontrollable.

    Returns
    -------
    bool

    Examples
    --------
    >>> import sysid
    >>> sysid.is_controllable(sysid.StateSpaceModel([[0.5, 0], [0, 0.2]], [[1], [0]], [[1, 1]]))
    False
    """
    model = _statespace(model, "is_controllable")
    return _staircase_ok(np.asarray(model.A, float), np.asarray(model.B, float), tol)


def is_observable(model: Any, tol: float | None = None) -> bool:
    """Whether the outputs see every state: the dual of :func:`is_controllable` (on
    ``(A', C')``), with the same invariance to scaling ``C`` and the states.

    Parameters
    ----------
    model : state-space model or TransferFunction
        Anything with ``A`` and ``C``, or a ``to_statespace()`` (its realisation).
    tol : float, optional
        Relative rank tolerance, as for :func:`is_controllable`.

    Returns
    -------
    bool

    Examples
    --------
    >>> import sysid
    >>> sysid.is_observable(sysid.StateSpaceModel([[0.5, 0], [0, 0.2]], [[1], [0]], [[1, 1]]))
    True
    """
    model = _statespace(model, "is_observable")
    return _staircase_ok(np.asarray(model.A, float).T, np.asarray(model.C, float).T, tol)
