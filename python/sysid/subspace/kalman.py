"""The Kalman gain of a subspace fit where the core's Riccati solvers give up.

The core (``riccati::kalman_gain``: structure-preserving doubling, then Newton's iteration in
scaled coordinates) refuses rather than return an inaccurate gain. On some over-ordered fits
(a spurious mode far outside the unit circle that the noise hardly drives) it fails where
SciPy's generalised-Schur solver of the same equation still finds the stabilising solution;
that solution is used when it is as accurate as the core's last resort (relative residual
below ``1e-6``) and makes ``A - K C`` stable.
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
    from scipy import linalg

    A, C, Q, R, S = (np.asarray(res[k], float) for k in ("A", "C", "Q", "R", "S"))
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
    if np.any(np.linalg.eigvalsh((innov + innov.T) / 2) <= 0):
        return None
    return {**res, "K": K, "noise_cov": (innov + innov.T) / 2, "kalman_regularization": 0.0,
            "kalman_residual": rel, "kalman_solver": "scipy.linalg.solve_discrete_are"}
