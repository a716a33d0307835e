"""Polynomial models as state-space models in innovations form (MATLAB's ``idss(m)``).

``A_i(q) y_i = sum_j B_ij(q) / F_ij(q) u_j(t - nk_ij) + C_i(q) / D_i(q) e_i`` becomes
``x(t+1) = A x + B u + K e``, ``y = C x + D u + e`` with the same simulation and the same
predictions:

- **ARX and ARMAX** (no ``F``, no ``D``), coupled MIMO ARX included: the block observer
  form of ``y(t) = sum_l (-A_l y(t-l) + B_l u(t-l) + C_l e(t-l)) + B_0 u(t) + e(t)``:
  states ``x_l(t+1) = -A_l y(t) + x_{l+1}(t) + B_l u(t) + C_l e(t)`` with ``y = x_1 + B_0 u
  + e``, so ``B`` blocks are ``B_l - A_l B_0`` and ``K`` blocks ``C_l - A_l``
  (``max(na, nb + nk - 1, nc)`` blocks of one state per output).
- **Other structures** (``F`` or ``D``): one block per input channel, ``B_ij / (A_i F_ij)``,
  and one per output for the strictly proper part of the noise model ``C_i / (A_i D_i)``,
  whose input is the innovation (not minimal when ``A`` is shared; exact).
- **Output error** (noise model 1): the deterministic blocks, no ``K`` (the noise
  covariance kept: the innovations are the white output noise).
- **Time series**: the noise blocks alone (a coupled AR model: the block observer form).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError

__all__ = ["realize"]


def _tf2ss(num: Any, den: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Controller canonical form of ``num(z) / den(z)`` (coefficients in descending powers),
    the realisation and conventions of ``scipy.signal.tf2ss`` for one input and output:
    ``den`` made monic, the numerator's leading coefficients within 1e-14 of zero dropped, a
    constant ``den`` as one zero state. Written here because importing ``scipy.signal``
    costs about a second (``identify``'s first call spent it on this alone)."""
    den = np.trim_zeros(np.atleast_1d(np.asarray(den, float)), "f")
    num = np.atleast_1d(np.asarray(num, float)) / den[0]
    den = den / den[0]
    lead = 0
    while lead < num.size - 1 and np.allclose(num[lead], 0.0, atol=1e-14):
        lead += 1
    num = num[lead:]
    k = den.size
    if num.size > k:
        raise DataError("improper transfer function: the numerator is longer than the "
                        "denominator")
    num = np.concatenate([np.zeros(k - num.size), num])
    d = np.array([[num[0]]])
    if k == 1:
        return np.zeros((1, 1)), np.zeros((1, 1)), np.zeros((1, 1)), d
    a = np.vstack([-den[1:][None, :], np.eye(k - 2, k - 1)])
    b = np.eye(k - 1, 1)
    c = (num[1:] - num[0] * den[1:])[None, :]
    return a, b, c, d


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
    has_f = any(x.size for row in m.f for x in row)
    has_d = any(x.size for x in m.d)
    if m.coupled and (has_f or has_d):
        raise DataError("the state-space form of a coupled MIMO model with F or D "
                        "polynomials is not available; coupled models come from arx")
    if (m.n_inputs or m.coupled) and not has_f and not has_d:
        return _observer(m)
    return _blocks(m)


def _observer(m: Any) -> Any:
    """ARX and ARMAX, coupled or not, in block observer form: with matrix polynomials
    ``A(q) y = B(q) u + C(q) e`` (``A_l``, ``C_l`` diagonal unless coupled), block states
    ``x_l(t+1) = -A_l y(t) + x_{l+1}(t) + B_l u(t) + C_l e(t)`` and ``y = x_1 + B_0 u + e``,
    so the ``B`` blocks are ``B_l - A_l B_0`` and the ``K`` blocks ``C_l - A_l`` (an ARX
    predictor ``A - K C`` is a nilpotent shift, a FIR filter)."""
    from ..models.statespace import StateSpaceModel

    ny, nu = m.n_outputs, m.n_inputs
    na = max(x.size for row in m.a for x in row)
    nc = max([x.size for x in m.c] or [0])
    nb = max([int(m.nk[i, j]) + m.b[i][j].size - 1
              for i in range(ny) for j in range(nu) if m.b[i][j].size] or [0])
    n = max(na, nb, nc)
    Al = np.zeros((n + 1, ny, ny))
    Bl = np.zeros((n + 1, ny, nu))
    Cl = np.zeros((n + 1, ny, ny))
    for i in range(ny):
        for k in range(ny):
            Al[1:m.a[i][k].size + 1, i, k] = m.a[i][k]
        Cl[1:m.c[i].size + 1, i, i] = m.c[i]
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
        K[r] = Cl[lag] - Al[lag]
    C = np.zeros((ny, n * ny))
    C[:, :ny] = np.eye(ny)
    return StateSpaceModel(A, B, C, Bl[0], K, dt=m.dt, noise_cov=_noise_cov(m),
                           input_names=m.input_names if nu else None,
                           output_names=m.output_names)


def _noise_blocks(m: Any) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per output, ``(A, k, c)`` of the strictly proper part of ``C_i / (A_i D_i)`` (an empty
    block for a noise model of 1)."""
    out = []
    for i in range(m.n_outputs):
        num, den = _monic(m.c[i]), np.convolve(_monic(m.a[i][i]), _monic(m.d[i]))
        k = max(num.size, den.size)
        num, den = np.pad(num, (0, k - num.size)), np.pad(den, (0, k - den.size))
        a, b, c, _ = _tf2ss(num, den) if k > 1 else (np.zeros((0, 0)),) * 4
        out.append((np.atleast_2d(a).reshape(k - 1, k - 1), np.reshape(b, (-1,)),
                    np.reshape(c, (-1,))))
    return out


def _blocks(m: Any) -> Any:
    """Deterministic blocks per channel and noise blocks per output."""
    from ..models.statespace import StateSpaceModel

    ny, nu = m.n_outputs, m.n_inputs
    det = []
    for i in range(ny):
        for j in range(nu):
            num, den = m._channel_tf(i, j)
            num = np.trim_zeros(num, "f")
            det.append((i, j, *_tf2ss(num if num.size else np.zeros(1), den)))
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
    if nu and nn == 0:  # output error: the noise model is 1, no innovations gain; the
        # innovations are the output's white noise e (variance lambda): keep its covariance
        return StateSpaceModel(A, B, C, D, dt=m.dt, noise_cov=_noise_cov(m),
                               input_names=m.input_names, output_names=m.output_names)
    return StateSpaceModel(A, B, C, D, K, dt=m.dt, noise_cov=_noise_cov(m),
                           input_names=m.input_names if nu else None,
                           output_names=m.output_names)
