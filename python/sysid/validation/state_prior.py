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

import hashlib
import threading
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

import numpy as np


class _Kept:
    """The last few results of ``make(*arrays)`` (C-contiguous arrays), found by the arrays'
    shapes and a digest of their numbers (an array changed in place is another key: no
    block's numbers are held); thread-safe, read-only results (shared by every caller).
    Every candidate model is scored on the same few held-out blocks: a block's DFT lines are
    computed once."""

    def __init__(self, make: Callable[..., tuple[np.ndarray, ...]], size: int = 8) -> None:
        self._make, self._size = make, size
        self._kept: OrderedDict[tuple[Any, ...], tuple[np.ndarray, ...]] = OrderedDict()
        self._lock = threading.Lock()

    def __call__(self, *arrays: np.ndarray) -> tuple[np.ndarray, ...]:
        digest = hashlib.blake2b(digest_size=20)
        for a in arrays:
            digest.update(a)
        key = (*(a.shape for a in arrays), digest.digest())
        with self._lock:
            hit = self._kept.get(key)
            if hit is not None:
                self._kept.move_to_end(key)
                return hit
        out = self._make(*arrays)
        for a in out:
            a.flags.writeable = False
        with self._lock:
            self._kept[key] = out
            while len(self._kept) > self._size:
                self._kept.popitem(last=False)
        return out


def input_state_covariance(A: np.ndarray, B: np.ndarray, u: np.ndarray) -> np.ndarray | None:
    """``(1/N) sum_t x(t) x(t)^T`` of the periodic steady-state response of
    ``x(t+1) = A x(t) + B u(t)`` to one period ``u`` (``N x m``); ``None`` when there is no
    state, input or sample, or when the result is not finite.

    Per DFT line ``k``, ``X_k = (z_k I - A)^-1 B U_k`` (``z_k = exp(2 pi i k / N)``), solved on
    the complex Schur form ``A = Z T Z^H`` by back-substitution for all lines at once; the
    covariance is ``sum_k X_k X_k^H / N^2`` (Parseval). The input is real, so the lines above
    ``N/2`` are the conjugates of those below: the sum is that over ``k <= N/2``, the lines
    other than ``0`` and ``N/2`` counted twice, real part. A block's lines are computed once
    and kept for the next models scored on it. A pole on the unit circle at a line makes its
    direction's variance huge (the distance is floored at ``1e-12``): a state the input
    integrates is free.

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
    from scipy.linalg.blas import zherk

    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    u = np.ascontiguousarray(u, dtype=float)
    n, N = A.shape[0], u.shape[0]
    if n == 0 or N == 0 or B.size == 0 or u.ndim != 2 or u.shape[1] != B.shape[1]:
        return None
    T, Z = schur(A, output="complex")
    U, z = _lines(u)
    X = (Z.conj().T @ B) @ U  # n x (N//2 + 1): Z^H B U_k per line, weighed
    # only a pole within 1e-11 of the unit circle can come within 1e-12 of a line
    near = np.abs(np.abs(np.diag(T)) - 1.0) < 1e-11
    for i in range(n - 1, -1, -1):
        if i < n - 1:
            X[i] += T[i, i + 1:] @ X[i + 1:]
        d = z - T[i, i]
        if near[i]:
            d[np.abs(d) < 1e-12] = 1e-12
        X[i] /= d
    # sum_k X_k X_k^H: the upper triangle of its conjugate from the BLAS's Hermitian product
    S = np.triu(zherk(1.0, X.T, trans=2)).conj()
    S += np.triu(S, 1).conj().T
    P = (Z @ S @ Z.conj().T).real
    P = 0.5 * (P + P.T)
    return P if np.all(np.isfinite(P)) else None


def _block_lines(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The DFT lines ``k <= N/2`` of the block input ``u`` (``N x m``), ``m x (N//2 + 1)``,
    weighed by ``sqrt(2) / N`` (``1 / N`` at ``0`` and ``N/2``); and
    ``z_k = exp(2 pi i k / N)``."""
    N = u.shape[0]
    U = np.fft.rfft(u, axis=0).T
    w = np.full(U.shape[1], np.sqrt(2.0) / N)
    w[0] = 1.0 / N
    if N % 2 == 0:
        w[-1] = 1.0 / N
    return U * w, np.exp(2j * np.pi * np.arange(U.shape[1]) / N)


_lines = _Kept(_block_lines)
