"""The Kalman gain of a subspace fit where the core's Riccati solvers give up.

The core (``riccati::kalman_gain``: structure-preserving doubling, then Newton's iteration in
scaled coordinates) refuses rather than return an inaccurate gain. On some over-ordered fits
(a spurious mode far outside the unit circle that the noise hardly drives) it fails where
SciPy's generalised-Schur solver of the same equation still finds the stabilising solution;
that solution is used when it is as accurate as the core's last resort (relative residual
below ``1e-6``) and makes ``A - K C`` stable. :func:`kalman_gain` is the one call for Python
code that needs a stabilising gain (core first, then the Schur solver); the subspace
estimators, whose core fit already tried the core's solvers, call :func:`schur_gain`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: the largest relative residual accepted (the core's ``riccati::LAST_RESORT_TOL``)
RESIDUAL_TOL = 1e-6


def schur_gain(res: dict[str, Any]) -> dict[str, Any] | None:
    """``res`` (a core fit with ``kalman=False``) with the gain ``K``, the innovation
    covariance and the equation's residual set from SciPy's Schur solver, or None when that
    gives no accurate stabilising solution.

    Examples
    --------
    >>> import numpy as np
    >>> res = {"A": np.array([[1.0]]), "C": np.array([[1.0]]), "Q": np.array([[1.0]]),
    ...        "R": np.array([[1.0]]), "S": np.array([[0.0]])}
    >>> out = schur_gain(res)
    >>> round(float(out["K"][0, 0]), 6)  # P = (1 + sqrt 5) / 2, K = P / (P + 1)
    0.618034
    """
    sol = _schur(*(np.asarray(res[k], float) for k in ("A", "C", "Q", "R", "S")))
    if sol is None:
        return None
    K, innov, rel = sol
    return {**res, "K": K, "noise_cov": innov, "kalman_regularization": 0.0,
            "kalman_residual": rel, "kalman_solver": "scipy.linalg.solve_discrete_are"}


def kalman_gain(A: Any, C: Any, Q: Any, R: Any, S: Any) -> tuple[np.ndarray, np.ndarray]:
    """The stabilising predictor gain ``K`` and innovation covariance of ``(A, C, Q, R, S)``:
    the core's solvers (``sysid._sysid.kalman_gain``), then SciPy's Schur solver where they
    refuse; :class:`~sysid.RiccatiError` (the core's) when neither finds an accurate one.

    Examples
    --------
    >>> import numpy as np
    >>> K, innov = kalman_gain(*(np.eye(1) for _ in range(4)), np.zeros((1, 1)))
    >>> round(float(K[0, 0]), 6), round(float(innov[0, 0]), 6)
    (0.618034, 2.618034)
    """
    from .. import _sysid
    from ..errors import RiccatiError

    try:
        K, _, innov = _sysid.kalman_gain(A, C, Q, R, S)
        return np.asarray(K), np.asarray(innov)
    except RiccatiError:
        sol = _schur(*(np.asarray(m, float) for m in (A, C, Q, R, S)))
        if sol is None:
            raise
        return sol[0], sol[1]


def _schur(A: np.ndarray, C: np.ndarray, Q: np.ndarray, R: np.ndarray, S: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray, float] | None:
    """``(K, innovation covariance, relative residual)`` from SciPy's Schur solver, or None
    when it gives no stabilising solution within ``RESIDUAL_TOL``."""
    from scipy import linalg

    try:
        with np.errstate(all="ignore"):
            P = linalg.solve_discrete_are(A.T, C.T, Q, R, s=S)
            innov = C @ P @ C.T + R
            G = A @ P @ C.T + S
            K = np.linalg.solve(innov.T, G.T).T
            resid = A @ P @ A.T + Q - K @ G.T - P
            rel = float(np.abs(resid).max() / max(np.abs(P).max(), np.abs(Q).max()))
            rho = float(np.max(np.abs(np.linalg.eigvals(A - K @ C)))) if len(A) else 0.0
    except (ValueError, np.linalg.LinAlgError):
        return None
    if not (np.isfinite(rel) and rel <= RESIDUAL_TOL and rho < 1.0):
        return None
    innov = (innov + innov.T) / 2
    if np.any(np.linalg.eigvalsh(innov) <= 0):
        return None
    return K, innov, rel
