"""Refined instrumental variables for continuous-time models (SRIVC; Young & Jakeman 1980),
the start of :func:`sysid.tfest` on sampled data.

For ``y = B(s) / A(s) u(t - tau) + e`` with monic ``A`` of degree ``n`` and ``B`` of degree
``m``, filtering both sides by ``1 / A(s)`` gives the linear regression

.. math::

    y_f^{(n)} = -a_1 y_f^{(n-1)} - \\dots - a_n y_f + b_0 u_f^{(m)} + \\dots + b_m u_f,
    \\qquad x_f^{(k)} = \\frac{s^k}{A(s)} x,

solved with the instruments ``[-\\hat x_f^{(n-1)}, ..., -\\hat x_f, u_f^{(m)}, ..., u_f]``,
``\\hat x = B/A u`` the noise-free output of the current model; the filter is then rebuilt
from the new ``A`` and the step repeated. The filtered signals are states of the filters
``1/A`` (output) and ``1/A^2`` (input: ``u_f^{(k)} = s^k A / A^2 u`` and
``\\hat x_f^{(k)} = s^k B / A^2 u``), sampled exactly under the input's hold (the delayed
input included, :mod:`sysid.tf.sampling`); the measured output is interpolated linearly.
One pass in the Rust core accumulates the normal equations
(:func:`sysid._sysid.tf_filtered_gram`).
"""

from __future__ import annotations

import numpy as np

from .. import _sysid
from ..greybox.delays import shift_taps
from .sampling import sample_pair, split_delay

__all__ = ["srivc"]


def _companion(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(A, e_n)``: states ``s^{i-1} / a(s)`` of the monic ``a`` (descending, a[0] = 1)."""
    n = a.size - 1
    A = np.zeros((n, n))
    b = np.zeros(n)
    if n == 0:  # a static gain: no states
        return A, b
    A[:-1, 1:] = np.eye(n - 1)
    A[-1, :] = -a[::-1][:n]
    b[-1] = 1.0
    return A, b


def _sampled_filter(a: np.ndarray, dt: float, tau: float, hold: str
                    ) -> tuple[np.ndarray, list[tuple[int, np.ndarray, np.ndarray]]]:
    """Sampled ``1/a(s)`` filter whose outputs are its states and the (delayed) input."""
    A, b = _companion(a)
    k = A.shape[0]
    C = np.vstack([np.eye(k), np.zeros((1, k))])
    D = np.zeros(k + 1)
    D[-1] = 1.0
    whole, r = split_delay(tau, dt)
    Ad, cols, _ = sample_pair(A, b, C, D, dt, whole, r, hold)
    return Ad, cols


def _rows(a: np.ndarray, bnum: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Maps from the filter outputs ``s_y`` (n + 1) and ``s_u`` (2n + 1) to ``w = [target,
    phi, zeta]``."""
    n = a.size - 1
    p = n + m + 1
    a2 = np.convolve(a, a)
    # P_q = s^q / A^2 u for q = 0..2n, from s_u (P_{2n} = u - sum alpha_j P_{2n-j})
    P = np.eye(2 * n + 1)
    P[2 * n, :2 * n] = -a2[1:][::-1]
    Ly, Lu = np.zeros((1 + 2 * p, n + 1)), np.zeros((1 + 2 * p, 2 * n + 1))
    Ly[0, n] = 1.0
    Ly[0, :n] -= a[1:][::-1]           # y^{(n)}_f = y - sum a_i y^{(n-i)}_f
    for k in range(n):                 # -y^{(n-1-k)}_f in phi; -xhat^{(n-1-k)}_f in zeta
        Ly[1 + k, n - 1 - k] = -1.0
        for i, bi in enumerate(bnum):
            Lu[1 + p + k] -= bi * P[n - 1 - k + m - i]
    for k in range(m + 1):             # u^{(m-k)}_f = sum_i a_i P_{m-k+n-i}
        row = sum(ai * P[m - k + n - i] for i, ai in enumerate(a))
        Lu[1 + n + k] = row
        Lu[1 + p + n + k] = row
    return Ly, Lu


def _step(u: np.ndarray, y: np.ndarray, dt: float, tau: float, hold: str, a: np.ndarray,
          bnum: np.ndarray, m: int, iv: bool) -> tuple[np.ndarray, np.ndarray] | None:
    n = a.size - 1
    Ady, cy = _sampled_filter(a, dt, 0.0, "foh")
    Adu, cu = _sampled_filter(np.convolve(a, a), dt, tau, hold)
    Ly, Lu = _rows(a, bnum, m)
    ny, nu = Ady.shape[0], Adu.shape[0]
    ty = [(0, s) for s, _, _ in cy]
    tu = [(0, s) for s, _, _ in cu]
    q = len(ty) + len(tu)
    Ad = np.zeros((ny + nu, ny + nu))
    Ad[:ny, :ny], Ad[ny:, ny:] = Ady, Adu
    Bd, Cs, Ds = np.zeros((ny + nu, q)), np.zeros((ny + 1 + nu + 1, ny + nu)), \
        np.zeros((ny + 1 + nu + 1, q))
    Cs[:ny, :ny], Cs[ny + 1:ny + 1 + nu, ny:] = np.eye(ny), np.eye(nu)
    for c, (_, bc, dc) in enumerate(cy):
        Bd[:ny, c], Ds[:ny + 1, c] = bc, dc
    for c, (_, bc, dc) in enumerate(cu):
        Bd[ny:, len(ty) + c], Ds[ny + 1:, len(ty) + c] = bc, dc
    L = np.hstack([Ly, Lu])
    V = np.hstack([shift_taps(y[:, None], ty), shift_taps(u[:, None], tu)])
    G = _sysid.tf_filtered_gram(Ad, Bd, np.ascontiguousarray(L @ Cs),
                                np.ascontiguousarray(L @ Ds), V)
    p = n + m + 1
    z = slice(1 + p, 1 + 2 * p) if iv else slice(1, 1 + p)
    if not np.all(np.isfinite(G[z, :1 + p])):
        # a filter whose sampling lost its stability in rounding (coefficients of 1e10 and
        # more: six poles at 63 rad/s) ran its states to overflow: no estimate from it
        return None
    theta = np.linalg.lstsq(G[z, 1:1 + p], G[z, 0], rcond=None)[0]
    return np.concatenate([[1.0], theta[:n]]), theta[n:]


def _stabilised(a: np.ndarray) -> np.ndarray:
    r = np.roots(a)
    if np.all(r.real < 0):
        return a
    r = np.where(r.real >= 0, -np.abs(r.real) - 1e-6 * (1 + np.abs(r)) + 1j * r.imag, r)
    return np.real(np.poly(r))


def srivc(u: np.ndarray, y: np.ndarray, dt: float, n: int, m: int, tau: float, hold: str,
          a0: np.ndarray, max_iter: int = 30, tol: float = 1e-10
          ) -> tuple[np.ndarray, np.ndarray, int]:
    """``(a, b, iterations)`` of ``B/A`` (descending, ``a[0] = 1``) from one input ``u`` and
    output ``y`` (1-D), delay ``tau`` seconds, starting from the filter ``a0``.

    The first step is the least-squares (state-variable filter) estimate; the following ones
    use the instruments of the previous model. A step whose filtered signals overflow ends
    the iteration at the last estimate (NaN coefficients when the first one does: the
    caller tries another filter).

    The estimate is computed in time scaled by the start filter's frequency ``c`` (the
    geometric mean of its poles' magnitudes: ``s' = s / c``, sample time ``c dt``), where
    the filter ``(s' + 1)^n`` has coefficients of order one, and mapped back (``a_k c^k``);
    unscaled, the filter ``1 / A^2`` of eight poles at 250 rad/s has coefficients up to
    1e38 and its sampled states overflow (the CONTSID toolbox scales time likewise).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.tf.srivc import srivc
    >>> u = np.random.default_rng(0).standard_normal(400)
    >>> y = sysid.TransferFunction([2.0], [1.0, 3.0]).simulate(u, dt=0.05)[:, 0]
    >>> a, b, _ = srivc(u, y, 0.05, 1, 0, 0.0, "zoh", np.array([1.0, 1.0]))
    >>> np.round(a, 3), np.round(b, 3)
    (array([1., 3.]), array([2.]))
    """
    a0 = np.asarray(a0, dtype=float)
    c = abs(a0[-1]) ** (1.0 / n) if n and a0[-1] != 0 else 1.0  # the filter's frequency
    if not (np.isfinite(c) and c > 0):
        c = 1.0
    a, b, it = _srivc_scaled(u, y, dt * c, n, m, tau * c, hold,
                             a0 / c ** np.arange(n + 1), max_iter, tol)
    # back to unscaled time: a_k = a'_k c^k, b_i = b'_i c^(n - m + i) (descending b)
    return a * c ** np.arange(n + 1), b * c ** (n - m + np.arange(m + 1)), it


def _srivc_scaled(u: np.ndarray, y: np.ndarray, dt: float, n: int, m: int, tau: float,
                  hold: str, a0: np.ndarray, max_iter: int, tol: float
                  ) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`srivc`'s iteration (in whatever time units ``dt`` and ``tau`` are given)."""
    a = _stabilised(np.asarray(a0, dtype=float))
    b = np.zeros(m + 1)
    it = 0
    for it in range(1, max_iter + 1):
        step = _step(u, y, dt, tau, hold, a, b, m, iv=it > 1)
        if step is None:
            if it == 1:
                return np.full(n + 1, np.nan), np.full(m + 1, np.nan), it
            break
        a_new, b_new = step
        a_new = _stabilised(a_new)
        change = np.linalg.norm(np.concatenate([a_new - a, b_new - b])) / max(
            np.linalg.norm(np.concatenate([a_new, b_new])), 1e-300)
        a, b = a_new, b_new
        if it > 1 and change < tol:
            break
    return a, b, it
