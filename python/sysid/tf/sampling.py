"""Realisations of rational transfer functions and their exact sampling with input delays.

A continuous pair ``G(s) = B(s) / A(s) e^{-s tau}`` with monic
``A(s) = s^n + a_1 s^{n-1} + ... + a_n`` and ``B(s) = b_0 s^m + ... + b_m`` (``m <= n``) is
realised in controllable canonical form, whose states are ``x_i = s^{i-1} / A(s) u``:

.. math::

    \\dot x = A_c x + e_n u, \\qquad y = c x + d u, \\qquad
    d = b_0 [m = n], \\quad c_{i} = \\beta_{i} - d\\,\\alpha_{i},

with ``alpha``, ``beta`` the coefficients of ``A`` and ``B`` in ascending powers. A delay
``tau = l h + r`` (``0 <= r <= h``, ``h`` the sample time) is sampled exactly under a zero-order
hold (two input taps, shifts ``l`` and ``l + 1``) or a first-order hold (three taps,
``l - 1, l, l + 1``; two when ``l = 0``), see :mod:`sysid.greybox.delays`. The interval ``l``
is kept fixed while ``r`` runs over ``[0, h]``, so the sampled model is a continuous function of
the delay (what the output-error search needs to estimate it).

Examples
--------
>>> import numpy as np
>>> from sysid.tf.sampling import canonical, sample_pair
>>> A, b, c, d = canonical([1.0, 3.0], [2.0])        # 2 / (s + 3)
>>> A.tolist(), c.tolist()
([[-3.0]], [[2.0]])
>>> Ad, cols, x0 = sample_pair(A, b, c, d, 0.1, 0, 0.0, "zoh")
>>> [s for s, _, _ in cols], bool(np.isclose(Ad[0, 0], np.exp(-0.3)))
([0, 1], True)
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import _sysid
from ..errors import DataError

__all__ = ["canonical", "canonical_form", "natural_frequency", "sample_pair", "split_delay"]

_SNAP = 1e-9


def natural_frequency(den: Any) -> float:
    """The power of two nearest the geometric mean of the magnitudes of the roots of ``den``
    (``|a_n / a_0|^(1/n)``; 1 without a nonzero constant term): the frequency that
    :func:`canonical` scales time by, exactly (a power of two).

    Examples
    --------
    >>> from sysid.tf.sampling import natural_frequency
    >>> natural_frequency([1.0, 3.0]), natural_frequency([1.0, 500.0, 250.0 ** 2])
    (4.0, 256.0)
    """
    den = np.atleast_1d(np.asarray(den, dtype=float))
    n = den.size - 1
    if n < 1 or den[0] == 0 or den[-1] == 0:
        return 1.0
    w = abs(den[-1] / den[0]) ** (1.0 / n)
    return float(2.0 ** np.round(np.log2(w))) if np.isfinite(w) and w > 0 else 1.0


def canonical(den: Any, num: Any, freq: float = 1.0
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(A, b, c, d)`` of ``num(s) / den(s)`` (descending powers, ``den`` monic after scaling),
    with ``c`` of shape ``(1, n)`` and ``d`` of shape ``(1,)``: the controllable canonical
    form in time scaled by ``freq`` (``s = freq s'``: the companion matrix of ``den(freq
    s')`` made monic, times ``freq``; ``b = freq e_n``). With ``freq`` near the poles'
    magnitudes (:func:`natural_frequency`) its entries are of the order of the poles
    themselves, where the plain form's last row holds ``a_n ~ |pole|^n`` (1e19 for eight
    poles at 250 rad/s: its sampled exponential then lost the poles to rounding).

    Examples
    --------
    >>> from sysid.tf.sampling import canonical
    >>> A, b, c, d = canonical([1.0, 1.0], [2.0, 3.0])   # (2 s + 3) / (s + 1) = 2 + 1 / (s + 1)
    >>> A.tolist(), c.tolist(), d.tolist()
    ([[-1.0]], [[1.0]], [2.0])
    >>> A, b, c, d = canonical([1.0, 1.0], [2.0, 3.0], 2.0)   # the same transfer function
    >>> A.tolist(), b.tolist(), c.tolist(), d.tolist()
    ([[-1.0]], [2.0], [[0.5]], [2.0])
    """
    den = np.atleast_1d(np.asarray(den, dtype=float))
    num = np.atleast_1d(np.asarray(num, dtype=float))
    if den.size == 0 or den[0] == 0:
        raise DataError("the denominator's leading coefficient must be nonzero")
    n = den.size - 1
    if num.size > n + 1:
        raise DataError(f"the numerator has degree {num.size - 1} above the denominator's {n}: "
                        "the transfer function is improper; give at most as many zeros as poles")
    A, c, d = canonical_form(den, num, freq)
    b = np.zeros(n)
    if n:
        b[-1] = freq
    return A, b, c, d


def canonical_form(den: np.ndarray, num: np.ndarray, freq: float = 1.0
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(A, c, d)`` of :func:`canonical` (``b = freq e_n``) for real or complex coefficients
    (the complex step of :mod:`sysid.tf.sensitivity` goes through it)."""
    num, den = num / den[0], den / den[0]
    n = den.size - 1
    k = np.arange(n + 1)
    den = den / float(freq) ** k               # a'_k = a_k / freq^k: den(freq s') / freq^n
    beta = np.zeros(n + 1, dtype=np.result_type(num, den))
    beta[:num.size] = num[::-1]                # ascending powers: beta'_j = beta_j freq^(j-n)
    beta = beta * float(freq) ** (k - n)
    A = np.zeros((n, n), dtype=den.dtype)
    if n:
        A[:-1, 1:] = np.eye(n - 1)
        A[-1, :] = -den[::-1][:n]
    d = beta[n] if n else beta[0]
    c = (beta[:n] - d * den[::-1][:n]).reshape(1, n)
    return A * float(freq), c, np.array([d])


def split_delay(tau: float, dt: float) -> tuple[int, float]:
    """``(l, r)`` with ``tau = l dt + r``, ``0 <= r < dt`` (snapped to whole samples within
    ``1e-9``).

    Examples
    --------
    >>> from sysid.tf.sampling import split_delay
    >>> split_delay(0.25, 0.1)
    (2, 0.05)
    """
    x = tau / dt
    near = round(x)
    if abs(x - near) <= _SNAP * max(1.0, x):
        return int(near), 0.0
    lo = int(np.floor(x))
    return lo, round((x - lo) * dt, 15)


def _expm(M: np.ndarray) -> np.ndarray:
    """``exp(M)`` in the Rust core (no LAPACK threads for these small matrices)."""
    return np.asarray(_sysid.expm_frechet(np.ascontiguousarray(M, dtype=float), [])[0])


def _foh_shift(A: np.ndarray, b: np.ndarray, dt: float, r: float) -> np.ndarray:
    """The state shift ``G`` of a first-order hold with ``l = 0`` (rest: ``z(0) = -G u(0)``)."""
    n = A.shape[0]
    M = np.zeros((n + 2, n + 2))
    M[:n, :n], M[:n, n], M[n, n + 1] = A * (dt - r), b * (dt - r), dt - r
    return _expm(M)[:n, n + 1] / dt


def sample_pair(A: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray, dt: float,
                whole: int, r: float, hold: str
                ) -> tuple[np.ndarray, list[tuple[int, np.ndarray, np.ndarray]], np.ndarray]:
    """``(Ad, [(shift, B column, D column)], G)`` of one input column ``b`` delayed by
    ``whole dt + r`` (``0 <= r <= dt``), the taps fixed by ``whole`` and the hold; ``G`` is the
    state at rest per unit ``u(0)`` (nonzero only for the first-order hold without whole delay).

    The caller sums ``B col * u(t - shift)``; output ``y = c x + sum D col u(t - shift)``.
    """
    from ..greybox import delays as greydelay

    n = A.shape[0]
    Ad = _expm(A * dt) if n else np.zeros((0, 0))
    if hold == "zoh":
        if n:
            g0, g1, _ = greydelay.fractional_columns(A, b, dt, r, [])
        else:
            g0 = g1 = np.zeros(0)
        if r > 0:
            return Ad, [(whole, g0, np.zeros_like(d)), (whole + 1, g1, d.copy())], np.zeros(n)
        return Ad, [(whole, g0, d.copy()), (whole + 1, g1, np.zeros_like(d))], np.zeros(n)
    if n == 0:
        w = r / dt
        cols = [(whole, np.zeros(0), d * (1 - w)), (whole + 1, np.zeros(0), d * w)]
        if whole >= 1:
            cols.insert(0, (whole - 1, np.zeros(0), np.zeros(1)))
        return Ad, cols, np.zeros(0)
    cols, _ = greydelay.foh_columns(A, b, c, d, Ad, dt, r, whole, [])
    G = _foh_shift(A, b, dt, r) if whole == 0 else np.zeros(n)
    return Ad, [(int(s), np.asarray(bc), np.asarray(dc)) for s, bc, dc in cols], G

