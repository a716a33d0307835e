"""Controllability and observability: the Kalman matrices and the PBH rank tests.

Moved out of :mod:`sysid.analysis.lti` (which re-exports them) to keep modules short.
"""

from __future__ import annotations

from typing import Any

import numpy as np

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


def _pbh_rank_ok(A: np.ndarray, B: np.ndarray, tol: float | None) -> bool:
    n = A.shape[0]
    if n == 0:
        return True
    scale = max(float(np.linalg.norm(A, 2)), float(np.linalg.norm(B, 2)) if B.size else 0.0,
                1e-300)
    tol = n * np.finfo(float).eps * 1e3 if tol is None else float(tol)
    for lam in np.linalg.eigvals(A):
        sv = np.linalg.svd(np.hstack([A - lam * np.eye(n), B]), compute_uv=False)
        if sv[n - 1] <= tol * scale:
            return False
    return True


def is_controllable(model: Any, tol: float | None = None) -> bool:
    """Popov-Belevitch-Hautus test: ``[A - lambda I, B]`` has full row rank at every pole.

    The rank is judged on the smallest singular value relative to ``max(||A||, ||B||)``;
    ``tol`` defaults to ``1000 n eps``. More reliable than the rank of :func:`ctrb`, whose
    columns lose precision as powers of A grow.

    Examples
    --------
    >>> import sysid
    >>> sysid.is_controllable(sysid.StateSpaceModel([[0.5, 0], [0, 0.2]], [[1], [0]], [[1, 1]]))
    False
    """
    model = _statespace(model, "is_controllable")
    return _pbh_rank_ok(model.A, model.B, tol)


def is_observable(model: Any, tol: float | None = None) -> bool:
    """PBH observability test (the dual of :func:`is_controllable`).

    Examples
    --------
    >>> import sysid
    >>> sysid.is_observable(sysid.StateSpaceModel([[0.5, 0], [0, 0.2]], [[1], [0]], [[1, 1]]))
    True
    """
    model = _statespace(model, "is_observable")
    return _pbh_rank_ok(model.A.T, model.C.T, tol)
