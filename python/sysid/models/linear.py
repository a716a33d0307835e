"""Small dense computations on linear models: transmission zeros and pole damping.

They work on matrices and pole arrays only, so every model family (and
:mod:`sysid.analysis.lti`, which exposes them as :func:`sysid.zeros` and :func:`sysid.damp`)
calls them without importing anything above ``models/``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._display import HTMLResult
from .pole_map import continuous_equivalent, damping_ratio

__all__ = ["transmission_zeros", "DampingTable", "damping_table"]


def _pencil_zeros(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray) -> np.ndarray:
    import scipy.linalg  # on first use: `import sysid` stays light

    n = A.shape[0]
    M = np.block([[A, B], [C, D]])
    N = np.zeros_like(M)
    N[:n, :n] = np.eye(n)
    w = scipy.linalg.eigvals(M, N, homogeneous_eigvals=True)
    alpha, beta = w
    scale = max(float(np.abs(M).max()), 1.0)
    # infinite eigenvalues come out with beta at round-off level
    finite = np.abs(alpha) < 1e8 * scale * np.abs(beta)
    z = alpha[finite] / beta[finite]
    return z.astype(complex)


def transmission_zeros(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
                       tol: float = 1e-6) -> np.ndarray:
    """Transmission zeros: finite generalised eigenvalues of the Rosenbrock pencil.

    ``[[A - z I, B], [C, D]]`` loses rank at a zero. For a square system the pencil's
    generalised eigenvalues are the zeros (``scipy.linalg.eigvals``). A non-square system is
    squared down twice with random (seeded) combinations of its outputs or inputs; zeros
    common to both, within ``tol`` relative, are kept (the spurious zeros of a squaring-down
    move with the combination, the true ones do not).

    Parameters
    ----------
    A, B, C, D : ndarray
        State-space matrices (discrete or continuous).
    tol : float
        Relative tolerance for matching zeros of the two squared-down systems.

    Returns
    -------
    ndarray
        Complex zeros (discrete ``z`` or continuous ``s``), sorted by modulus.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.models.linear import transmission_zeros
    >>> A, B, C = np.diag([0.5, 0.2]), np.ones((2, 1)), np.ones((1, 2))
    >>> transmission_zeros(A, B, C, np.zeros((1, 1)))
    array([0.35+0.j])
    """
    l, m = D.shape
    if l == m:
        z = _pencil_zeros(A, B, C, D)
    else:
        rng = np.random.default_rng(12345)
        k = min(l, m)
        cands = []
        for _ in range(2):
            if l > m:
                W = rng.standard_normal((k, l))
                cands.append(_pencil_zeros(A, B, W @ C, W @ D))
            else:
                W = rng.standard_normal((m, k))
                cands.append(_pencil_zeros(A, B @ W, C, D @ W))
        z1, z2 = cands
        keep = [a for a in z1 if z2.size and np.min(np.abs(z2 - a)) <= tol * max(1.0, abs(a))]
        z = np.array(keep, dtype=complex)
    return z[np.argsort(np.abs(z), kind="stable")]


class DampingTable(HTMLResult):
    """Poles with their natural frequency, damping ratio and time constant.

    Attributes
    ----------
    poles : ndarray
        Poles of the model (discrete ``z`` or continuous ``s``), sorted by frequency.
    s : ndarray
        Continuous-time equivalents ``log(z) / dt`` (equal to ``poles`` for continuous models).
    wn, wn_hz : ndarray
        Natural frequency ``|s|`` in rad/s and Hz.
    wd, wd_hz : ndarray
        Damped frequency ``|Im s|`` in rad/s and Hz (``|angle(z)| / (2 pi dt)`` in Hz).
    zeta : ndarray
        Damping ratio ``-Re(s) / |s|``.
    tau : ndarray
        Time constant ``-1 / Re(s)`` in seconds (``inf`` on the stability boundary).
    pole_std, wn_std, wn_hz_std, zeta_std : ndarray or None
        Standard deviations (``damp(model, std=True)``, from the model's parameter
        uncertainty); ``pole_std`` is complex (std of the real and imaginary parts).
    std_method : ndarray of str or None
        Per pole, how its std was obtained: ``"linear"`` (first order) or ``"monte-carlo"``
        (a pole that coincides with another, where first order does not hold).
    """

    def __init__(self, poles: np.ndarray, s: np.ndarray, dt: float | None,
                 std: dict[str, np.ndarray] | None = None) -> None:
        order = np.lexsort((s.imag, np.abs(s)))
        self.poles, self.s, self.dt = poles[order], s[order], dt
        self.pole_std = self.wn_std = self.wn_hz_std = self.zeta_std = None
        self.std_method: np.ndarray | None = None
        if std is not None:
            self.pole_std = std["pole_std"][order]
            if "std_method" in std:
                self.std_method = np.asarray(std["std_method"])[order]
            self.wn_std, self.wn_hz_std = std["wn_std"][order], std["wn_hz_std"][order]
            self.zeta_std = std["zeta_std"][order]
        with np.errstate(divide="ignore", invalid="ignore"):
            self.wn = np.abs(self.s)
            self.zeta = damping_ratio(self.s)
            self.wd = np.abs(self.s.imag)
            self.tau = np.where(self.s.real != 0, -1.0 / self.s.real, np.inf)
        self.wn_hz = self.wn / (2 * np.pi)
        self.wd_hz = self.wd / (2 * np.pi)

    def to_pandas(self) -> Any:
        """The table as a :class:`pandas.DataFrame`."""
        import pandas as pd

        cols = {
            "pole": self.poles, "magnitude": np.abs(self.poles), "wn [rad/s]": self.wn,
            "wn [Hz]": self.wn_hz, "damping": self.zeta, "wd [Hz]": self.wd_hz,
            "tau [s]": self.tau,
        }
        if self.pole_std is not None:
            cols.update({"std Re(pole)": self.pole_std.real, "std Im(pole)": self.pole_std.imag,
                         "std wn [Hz]": self.wn_hz_std, "std damping": self.zeta_std})
            if self.std_method is not None:
                cols["std method"] = self.std_method
        return pd.DataFrame(cols)

    def __len__(self) -> int:
        return len(self.poles)

    def __repr__(self) -> str:
        head = (f"{'pole':>24} {'|pole|':>8} {'wn rad/s':>10} {'wn Hz':>9} {'damping':>8} "
                f"{'wd Hz':>9}")
        if self.pole_std is not None:
            head += f" {'std Hz':>9} {'std damp':>9}"
        rows = [head]
        for k, (p, wn, fz, z, fd) in enumerate(
                zip(self.poles, self.wn, self.wn_hz, self.zeta, self.wd_hz)):
            rows.append(
                f"{p.real:>11.5g}{p.imag:>+11.5g}j {abs(p):8.4f} {wn:10.4g} {fz:9.4g} "
                f"{z:8.4f} {fd:9.4g}"
                + ("" if self.wn_hz_std is None or self.zeta_std is None else
                   f" {self.wn_hz_std[k]:9.3g} {self.zeta_std[k]:9.3g}")
            )
        where = f"dt = {self.dt:g} s" if self.dt is not None else "continuous time"
        return f"DampingTable ({where})\n" + "\n".join(rows)


def damping(model: Any, std: bool = False) -> DampingTable:
    """The :class:`DampingTable` of a model's poles (:func:`sysid.damp`, which checks the
    model first), with their standard deviations (``std=True``: from its uncertainty).

    Examples
    --------
    >>> import sysid
    >>> from sysid.models.linear import damping
    >>> round(float(damping(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])).zeta[0]), 3)
    1.0
    """
    if std:
        from .pole_uncertainty import damping_std

        d = damping_std(model, float(model.dt))  # dt = 0: a continuous model's own poles
        return DampingTable(d["poles"], d["s"].astype(complex), float(model.dt) or None, std=d)
    from .checks import _optional

    return damping_table(np.asarray(_optional(model, "poles", "damp")), float(model.dt))


def damping_table(poles: np.ndarray, dt: float) -> DampingTable:
    """The :class:`DampingTable` of ``poles``: discrete (``dt > 0``, mapped through
    ``s = log(z) / dt``; ``z = 0`` gives ``s = -inf``) or continuous (``dt == 0``).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.models.linear import damping_table
    >>> np.round(damping_table(np.array([-1.0 + 2.0j, -1.0 - 2.0j]), 0.0).zeta, 4)
    array([0.4472, 0.4472])
    """
    p = np.asarray(poles, dtype=complex)
    return DampingTable(p, continuous_equivalent(p, dt), dt or None)


def reachable_basis(A: np.ndarray, B: np.ndarray, tol: float) -> np.ndarray:
    """Orthonormal basis of the subspace ``B`` reaches through ``A`` (staircase with SVD rank
    decisions at ``tol``). The subspace does not depend on the units: not on the scale of
    ``B`` or of ``A``, nor on the state's (a diagonal similarity), so the rank tests run on
    ``D^-1 A D`` balanced (:func:`scipy.linalg.matrix_balance`) and ``D^-1 B``, each of unit
    norm, and the basis is mapped back (a stiff oscillator in SI units, ``|B|`` 1e-9, lost
    every state to a test against ``tol`` times ``max(|A|, |B|, 1)``)."""
    from scipy.linalg import matrix_balance

    n = A.shape[0]
    if n == 0 or not np.any(B):
        return np.zeros((n, 0))
    d = np.ones(n)
    if np.any(A):
        _, (d, _) = matrix_balance(A, permute=False, separate=True)
    A = A * (1.0 / d)[:, None] * d[None, :]
    B = B / d[:, None]
    A = A / max(float(np.linalg.norm(A)), 1e-300)
    B = B / float(np.linalg.norm(B))
    basis = np.zeros((n, 0))
    block = B
    for _ in range(n):
        if basis.shape[1]:
            block = block - basis @ (basis.T @ block)
        if block.size == 0:
            break
        U, s, _ = np.linalg.svd(block, full_matrices=False)
        r = int(np.sum(s > tol))
        if r == 0:
            break
        basis = np.hstack([basis, U[:, :r]])
        if basis.shape[1] >= n:
            break
        block = A @ U[:, :r]
    q, _ = np.linalg.qr(d[:, None] * basis) if basis.shape[1] else (basis, None)
    return q


def minimal_basis(A: np.ndarray, B: np.ndarray, C: np.ndarray, tol: float) -> np.ndarray:
    """Orthonormal basis ``T`` of the part of the state ``B`` reaches and ``C`` sees: ``(T^T A
    T, T^T B, C T)`` is the minimal realisation (:func:`sysid.minreal`).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.models.linear import minimal_basis
    >>> A = np.diag([0.5, 0.9]); B = np.array([[1.0], [0.0]]); C = np.array([[1.0, 1.0]])
    >>> minimal_basis(A, B, C, 1e-8).shape                   # the 0.9 mode is not reached
    (2, 1)
    """
    Vc = reachable_basis(A, B, tol)
    A1, C1 = Vc.T @ A @ Vc, C @ Vc
    return Vc @ reachable_basis(A1.T, C1.T, tol)
