"""Zero-order-hold continuous equivalent of a discrete model with poles on the negative
real axis (MATLAB's ``d2c`` raises the model's order for them).

A real pole ``z = -r`` (``r > 0``) has no real logarithm: ``log(-r) = log r + i pi`` is
complex, so no real continuous model of the same order samples to it. Two copies of the
pole do have one: with ``J = [[0, 1], [-1, 0]]``, ``exp(log(r) I + pi J) = -r I``. So the
modes on the negative real axis are split off (ordered real Schur form, then a Sylvester
equation to decouple them), a copy of them is added that the input does not reach and the
output does not see (the sampled model is unchanged), and the pair takes the real logarithm
``[[L, pi I], [-pi I, L]]`` with ``L = log(-A2)``. Each such pole becomes a complex pair
``(log r +- i pi) / dt``, at the Nyquist frequency, as MATLAB's conversion has it.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from ..errors import NumericalError

__all__ = ["negative_real", "zoh_doubled"]


def negative_real(p: np.ndarray) -> np.ndarray:
    """Mask of the poles ``p`` on the negative real axis (not at zero)."""
    p = np.asarray(p, dtype=complex)
    return ((np.abs(p.imag) <= 1e-12 * np.maximum(1.0, np.abs(p))) & (p.real < 0)
            & (np.abs(p) > 1e-12))


def zoh_doubled(A: np.ndarray, B: np.ndarray, C: np.ndarray, dt: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Ac, Bc, Cc)`` of the ZOH continuous equivalent with each pole on the negative real
    axis doubled (``D`` is unchanged).

    Examples
    --------
    >>> import numpy as np
    >>> Ac, Bc, Cc = zoh_doubled(np.array([[-0.5]]), np.array([[1.0]]), np.array([[1.0]]), 0.1)
    >>> Ac.shape, bool(np.allclose(scipy.linalg.expm(0.1 * Ac), -0.5 * np.eye(2)))
    ((2, 2), True)
    """
    n, m = B.shape
    T, Z, keep = scipy.linalg.schur(A, output="real",
                                    sort=lambda x, y: not (y == 0 and x < 0))
    T11, T12, T22 = T[:keep, :keep], T[:keep, keep:], T[keep:, keep:]
    # decouple: [[I, X], [0, I]] maps blkdiag(T11, T22) to T when T11 X - X T22 = -T12
    X = scipy.linalg.solve_sylvester(T11, -T22, -T12) if keep else np.zeros((0, n))
    V = Z.copy()
    V[:, keep:] += Z[:, :keep] @ X
    Bz = np.linalg.solve(V, B)
    Cz = C @ V
    k = n - keep
    L1 = scipy.linalg.logm(T11) if keep else np.zeros((0, 0))
    L2 = scipy.linalg.logm(-T22)
    L1, L2 = np.real_if_close(L1, tol=1e6), np.real_if_close(L2, tol=1e6)
    if np.iscomplexobj(L1) or np.iscomplexobj(L2):
        raise NumericalError("the matrix logarithm is complex: no real continuous equivalent")
    N = keep + 2 * k
    Ac = np.zeros((N, N))
    Ac[:keep, :keep] = L1
    Ac[keep:n, keep:n] = Ac[n:, n:] = L2
    Ac[keep:n, n:] = np.pi * np.eye(k)
    Ac[n:, keep:n] = -np.pi * np.eye(k)
    Ac /= dt
    Bd = np.vstack([Bz, np.zeros((k, m))])
    Cc = np.hstack([Cz, np.zeros((C.shape[0], k))])
    # Bd = (integral_0^dt exp(Ac s) ds) Bc; the integral is the top-right block below
    big = np.zeros((2 * N, 2 * N))
    big[:N, :N], big[:N, N:] = Ac * dt, np.eye(N) * dt
    phi = scipy.linalg.expm(big)[:N, N:]
    Bc = np.linalg.solve(phi, Bd)
    return Ac, Bc, Cc
