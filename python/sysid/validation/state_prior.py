"""The prior of a held-out block's initial state: where the model's input can put its state.

A model scored on a block of data it was not fitted to starts the block from an unknown
state, fitted by least squares (:func:`sysid.validation.crossval.simulation_errors`). Fitted
freely, that state is ``n`` more numbers fitted to the block's outputs: a model with modes
its input does not drive (a lightly damped pair with no input gain) then fits the block's
noise with them, and the more such modes, the better the score, although the model
simulates no better (twelve random plants at 30 % output noise: orders 6 to 10 chosen for
true orders 2 to 4, poles at ``|z|`` 0.97-1.0).

The state the block starts from was put there by earlier inputs. Its covariance under the
block's own input is that of the model's periodic steady-state response to it,
``P = (1/N) sum_t x(t) x(t)^T`` (:func:`input_state_covariance`), computed on the block's DFT
lines from the model's complex Schur form. The fit then takes ``x0 ~ N(0, P)`` a priori
(plus a small floor in every direction, relative to what the block's outputs tell about it,
so that noise-free data are still fitted exactly: ``sysid_core::model::initial_state``): a
direction the input drives is free, one it does not drive costs what it explains.
"""

from __future__ import annotations

import numpy as np


def input_state_covariance(A: np.ndarray, B: np.ndarray, u: np.ndarray) -> np.ndarray | None:
    """``(1/N) sum_t x(t) x(t)^T`` of the periodic steady-state response of
    ``x(t+1) = A x(t) + B u(t)`` to one period ``u`` (``N x m``); ``None`` when there is no
    state, input or sample, or when the result is not finite.

    Per DFT line ``k``, ``X_k = (z_k I - A)^-1 B U_k`` (``z_k = exp(2 pi i k / N)``), solved on
    the complex Schur form ``A = Z T Z^H`` by back-substitution for all lines at once; the
    covariance is ``sum_k X_k X_k^H / N^2`` (Parseval). A pole on the unit circle at a line
    makes its direction's variance huge (the distance is floored at ``1e-12``): a state the
    input integrates is free.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.validation.state_prior import input_state_covariance
    >>> u = np.random.default_rng(0).standard_normal((4096, 1))
    >>> P = input_state_covariance(np.array([[0.9]]), np.array([[1.0]]), u)
    >>> round(float(P[0, 0]), 1)  # 1 / (1 - 0.81) for a white input
    5.3
    """
    from scipy.linalg import schur

    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    u = np.asarray(u, dtype=float)
    n, N = A.shape[0], u.shape[0]
    if n == 0 or N == 0 or B.size == 0 or u.ndim != 2 or u.shape[1] != B.shape[1]:
        return None
    T, Z = schur(A, output="complex")
    C = (Z.conj().T @ B) @ np.fft.fft(u, axis=0).T  # n x N: Z^H B U_k per line
    z = np.exp(2j * np.pi * np.arange(N) / N)
    X = np.empty_like(C)
    for i in range(n - 1, -1, -1):
        d = z - T[i, i]
        d = np.where(np.abs(d) < 1e-12, 1e-12, d)
        X[i] = (C[i] + T[i, i + 1:] @ X[i + 1:]) / d
    P = (Z @ ((X @ X.conj().T) / float(N) ** 2) @ Z.conj().T).real
    P = 0.5 * (P + P.T)
    return P if np.all(np.isfinite(P)) else None
