"""Stable/unstable additive decomposition ``G = G_stable + G_unstable`` (MATLAB's ``stabsep``),
which :func:`sysid.balanced_truncation`, :func:`sysid.balanced_realization` and
:func:`sysid.hankel_singular_values` use to keep the unstable part of a model unchanged.

An ordered real Schur form ``Q' A Q = [[A11, A12], [0, A22]]`` puts the stable poles in
``A11`` (``|z| < 1``, or ``Re s < 0``); the Sylvester equation ``A11 X - X A22 = -A12``
removes the coupling, so with ``T = Q [[I, X], [0, I]]`` the model splits into
``(A11, B1 - X B2, C1)`` and ``(A22, B2, C1 X + C2)``; the feedthrough goes with the stable
part. Poles within ``margin`` of the stability boundary count as unstable (they are kept).

Examples
--------
>>> import numpy as np
>>> from sysid.analysis.stable_split import split_stable
>>> s = split_stable(np.array([[1.5, 1.0], [0.0, 0.5]]), np.eye(2), np.eye(2), dt=1.0)
>>> s.n_stable, float(s.stable[0][0, 0]), float(s.unstable[0][0, 0])
(1, 0.5, 1.5)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from ..errors import NumericalError

__all__ = ["StableSplit", "split_stable"]

Triple = tuple[np.ndarray, np.ndarray, np.ndarray]


@dataclass(frozen=True)
class StableSplit:
    """The two parts of :func:`split_stable` and the state transformation between them.

    Attributes
    ----------
    stable, unstable : tuple of ndarray
        ``(A, B, C)`` of each part (the feedthrough stays with the model).
    T, T_inv : ndarray
        ``x = T [x_stable; x_unstable]`` and its inverse.
    """

    stable: Triple
    unstable: Triple
    T: np.ndarray
    T_inv: np.ndarray

    @property
    def n_stable(self) -> int:
        """Number of stable states."""
        return int(self.stable[0].shape[0])


def is_stable_pole(p: np.ndarray, dt: float, margin: float = 1e-8) -> np.ndarray:
    """Which poles lie inside the stability region by more than ``margin`` (relative)."""
    if dt:
        return np.abs(p) < 1.0 - margin
    return p.real < -margin * np.maximum(1.0, np.abs(p))


def split_stable(A: np.ndarray, B: np.ndarray, C: np.ndarray, dt: float,
                 radius: float | None = None) -> StableSplit:
    """Split ``(A, B, C)`` into decoupled stable and unstable parts (``dt = 0``: continuous).
    ``radius`` (discrete time): the poles of modulus below it form the first part, instead
    of the stable ones (a split of the fast modes from the slow ones).

    Raises :class:`~sysid.NumericalError` when a stable and an unstable pole are so close
    that the decoupling transformation is not computable to working precision.
    """
    n = A.shape[0]

    def stable_first(re: np.ndarray, im: np.ndarray | None = None) -> bool:
        p = np.asarray(re + 1j * (0.0 if im is None else im))
        return bool(is_stable_pole(p, dt) if radius is None else np.abs(p) < radius)

    T1, Q, ns = scipy.linalg.schur(A, output="real", sort=stable_first)
    A11, A12, A22 = T1[:ns, :ns], T1[:ns, ns:], T1[ns:, ns:]
    X = scipy.linalg.solve_sylvester(A11, -A22, -A12) if 0 < ns < n else np.zeros((ns, n - ns))
    big = float(np.max(np.abs(X), initial=0.0))
    if not np.isfinite(big) or big > 1e8 * max(1.0, float(np.abs(A).max())):
        raise NumericalError(
            "the stable and unstable parts of the model cannot be separated accurately: a "
            "stable pole lies too close to an unstable one (the decoupling grows to "
            f"{big:.3g}); move the poles apart or reduce a stabilised (feedback) model")
    W = np.eye(n)
    W[:ns, ns:] = X
    W_inv = np.eye(n)
    W_inv[:ns, ns:] = -X
    T, T_inv = Q @ W, W_inv @ Q.T
    Bt, Ct = T_inv @ B, C @ T
    return StableSplit((A11.copy(), Bt[:ns], Ct[:, :ns]), (A22.copy(), Bt[ns:], Ct[:, ns:]),
                       T, T_inv)
