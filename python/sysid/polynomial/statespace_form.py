"""Polynomial models as state-space models in innovations form (MATLAB's ``idss(m)``).

``A_i(q) y_i = sum_j B_ij(q) / F_ij(q) u_j(t - nk_ij) + C_i(q) / D_i(q) e_i`` becomes
``x(t+1) = A x + B u + K e``, ``y = C x + D u + e`` with the same simulation and the same
predictions:

- **ARX and ARMAX** (no ``F``, no ``D``): per output, the observer form of
  ``y(t) = sum_l (-a_l y(t-l) + b_l u(t-l) + c_l e(t-l)) + b_0 u(t) + e(t)``: states
  ``x_l(t+1) = -a_l y(t) + x_{l+1}(t) + b_l u(t) + c_l e(t)`` with ``y = x_1 + b_0 u + e``,
  so ``B`` rows are ``b_l - a_l b_0`` and ``K`` rows ``c_l - a_l`` (minimal: ``max(na, nb +
  nk - 1, nc)`` states per output).
- **Other structures** (``F`` or ``D``): one block per input channel, ``B_ij / (A_i F_ij)``,
  and one per output for the strictly proper part of the noise model ``C_i / (A_i D_i)``,
  whose input is the innovation (not minimal when ``A`` is shared; exact).
- **Output error** (noise model 1): the deterministic blocks, no ``K``.
- **Time series**: the noise blocks alone; **coupled MIMO ARX** (matrix ``A``): its block
  observer form, ``K`` stacking ``-A_l``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError

__all__ = ["realize"]


def _monic(c: Any) -> np.ndarray:
    return np.concatenate([[1.0], np.asarray(c, dtype=float).ravel()])


def _noise_cov(m: Any) -> np.ndarray:
    nv = np.asarray(m.noise_variance, dtype=float)
    return nv if nv.ndim == 2 else np.diag(nv.ravel())


def realize(m: Any) -> Any:
    """The innovations-form :class:`~sysid.StateSpaceModel` of the polynomial model ``m``
    (see the module).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.PolynomialModel([[[-0.5]]], [[[1.0]]], [[1]], 1.0, c=[[0.3]])  # ARMAX
    >>> ss = realize(m)
    >>> ss.A.tolist(), ss.B.tolist(), ss.K.tolist()
    ([[0.5]], [[1.0]], [[0.8]])
    """
    if m.coupled:
        return _coupled(m)
    has_f = any(x.size for row in m.f for x in row)
    if m.n_inputs and not has_f and not any(x.size for x in m.d):
        return _observer(m)
    return _blocks(m)


def _observer(m: Any) -> Any:
    """ARX / ARMAX: one observer-form block per output."""
    from ..models.statespace import StateSpaceModel

    ny, nu = m.n_outputs, m.n_inputs
    parts = []
    for i in range(ny):
        a, c = m.a[i][i], m.c[i]
        nb = [int(m.nk[i, j]) + m.b[i][j].size - 1 for j in range(nu) if m.b[i][j].size]
        n = max([a.size, c.size, *nb, 0])
        al, cl = np.zeros(n + 1), np.zeros(n + 1)
        al[1:a.size + 1], cl[1:c.size + 1] = a, c
        bl = np.zeros((n + 1, nu))
        for j in range(nu):
            k0 = int(m.nk[i, j])
            bl[k0:k0 + m.b[i][j].size, j] = m.b[i][j]
        A = np.zeros((n, n))
        if n:
            A[:, 0] = -al[1:]
            A[:-1, 1:] = np.eye(n - 1)
        B = bl[1:] - np.outer(al[1:], bl[0])
        K = (cl[1:] - al[1:])[:, None]
        parts.append((A, B, K, bl[0]))
    n = sum(p[0].shape[0] for p in parts)
    A, B, K = np.zeros((n, n)), np.zeros((n, nu)), np.zeros((n, ny))
    C, D = np.zeros((ny, n)), np.zeros((ny, nu))
    o = 0
    for i, (a, b, k, d0) in enumerate(parts):
        r = a.shape[0]
        A[o:o + r, o:o + r], B[o:o + r], K[o:o + r, i] = a, b, k[:, 0]
        if r:
            C[i, o] = 1.0
        D[i] = d0
        o += r
    return StateSpaceModel(A, B, C, D, K, dt=m.dt, noise_cov=_noise_cov(m),
                           input_names=m.input_names, output_names=m.output_names)


def _noise_blocks(m: Any) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per output, ``(A, k, c)`` of the strictly proper part of ``C_i / (A_i D_i)`` (an empty
    block for a noise model of 1)."""
    from scipy import signal

    out = []
    for i in range(m.n_outputs):
        num, den = _monic(m.c[i]), np.convolve(_monic(m.a[i][i]), _monic(m.d[i]))
        k = max(num.size, den.size)
        num, den = np.pad(num, (0, k - num.size)), np.pad(den, (0, k - den.size))
        a, b, c, _ = signal.tf2ss(num, den) if k > 1 else (np.zeros((0, 0)),) * 4
        out.append((np.atleast_2d(a).reshape(k - 1, k - 1), np.reshape(b, (-1,)),
                    np.reshape(c, (-1,))))
    return out


def _blocks(m: Any) -> Any:
    """Deterministic blocks per channel and noise blocks per output."""
    from scipy import signal

    from ..models.statespace import StateSpaceModel

    ny, nu = m.n_outputs, m.n_inputs
    det = []
    for i in range(ny):
        for j in range(nu):
            num, den = m._channel_tf(i, j)
            num = np.trim_zeros(num, "f")
            det.append((i, j, *signal.tf2ss(num if num.size else np.zeros(1), den)))
    noise = _noise_blocks(m)
    nd = sum(b[2].shape[0] for b in det)
    nn = sum(b[0].shape[0] for b in noise)
    n = nd + nn
    A, B, C, D = np.zeros((n, n)), np.zeros((n, nu)), np.zeros((ny, n)), np.zeros((ny, nu))
    K = np.zeros((n, ny))
    o = 0
    for i, j, a, b, c, d in det:
        r = a.shape[0]
        A[o:o + r, o:o + r], B[o:o + r, j], C[i, o:o + r] = a, b[:, 0], c[0]
        D[i, j] = d[0, 0]
        o += r
    for i, (a, k, c) in enumerate(noise):
        r = a.shape[0]
        A[o:o + r, o:o + r], K[o:o + r, i], C[i, o:o + r] = a, k, c
        o += r
    if nu and nn == 0:  # output error: the noise model is 1, no innovations gain
        return StateSpaceModel(A, B, C, D, dt=m.dt, input_names=m.input_names,
                               output_names=m.output_names)
    return StateSpaceModel(A, B, C, D, K, dt=m.dt, noise_cov=_noise_cov(m),
                           input_names=m.input_names if nu else None,
                           output_names=m.output_names)


def _coupled(m: Any) -> Any:
    """A coupled MIMO ARX model ``y(t) = sum_l (-A_l y(t - l) + B_l u(t - l)) + B_0 u(t)
    + e(t)`` in observer form: block states ``x_l`` with ``x_l(t + 1) = -A_l y(t) +
    x_{l+1}(t) + B_l u(t)`` and ``y = x_1 + B_0 u + e``, so ``K`` stacks ``-A_l`` (the
    predictor ``A - K C`` is a nilpotent shift, as an ARX predictor is a FIR filter)."""
    from ..models.statespace import StateSpaceModel

    ny, nu = m.n_outputs, m.n_inputs
    if any(x.size for row in m.f for x in row) or any(x.size for x in (*m.c, *m.d)):
        raise DataError("the state-space form of a coupled MIMO model with F, C or D "
                        "polynomials is not available; coupled models come from arx")
    na = max(x.size for row in m.a for x in row)
    nb = max([int(m.nk[i, j]) + m.b[i][j].size - 1
              for i in range(ny) for j in range(nu) if m.b[i][j].size] or [0])
    n = max(na, nb)
    Al = np.zeros((n + 1, ny, ny))
    Bl = np.zeros((n + 1, ny, nu))
    for i in range(ny):
        for k in range(ny):
            Al[1:m.a[i][k].size + 1, i, k] = m.a[i][k]
        for j in range(nu):
            k0 = int(m.nk[i, j])
            Bl[k0:k0 + m.b[i][j].size, i, j] = m.b[i][j]
    A = np.zeros((n * ny, n * ny))
    B = np.zeros((n * ny, nu))
    K = np.zeros((n * ny, ny))
    for lag in range(1, n + 1):
        r = slice((lag - 1) * ny, lag * ny)
        A[r, :ny] = -Al[lag]
        if lag < n:
            A[r, lag * ny:(lag + 1) * ny] = np.eye(ny)
        B[r] = Bl[lag] - Al[lag] @ Bl[0]
        K[r] = -Al[lag]
    C = np.zeros((ny, n * ny))
    C[:, :ny] = np.eye(ny)
    return StateSpaceModel(A, B, C, Bl[0], K, dt=m.dt, noise_cov=_noise_cov(m),
                           input_names=m.input_names if nu else None,
                           output_names=m.output_names)
