r"""Exact derivatives of a sampled rational pair with respect to its parameters and its delay
(the Jacobian of the output-error refinement in :mod:`sysid.tf.refine`).

A pair ``num(s; p) / den(s; p) e^{-s tau}`` is realised in controllable canonical form
``(A, b, c, d)`` (:func:`sysid.tf.sampling.canonical`) and sampled with the data's hold
(:func:`sysid.tf.sampling.sample_pair`). Its derivatives come in three steps:

1. ``p -> (A, c, d)`` is a rational map (polynomial products, then division by the leading
   denominator coefficient), differentiated exactly by the complex step
   ``d f / d p_k = Im f(p + i h e_k) / h`` with ``h = 1e-30`` (no subtraction, so no
   cancellation);
2. ``(A, c, d) -> (A_d, Gamma, D columns)``: the Fréchet derivatives of the matrix
   exponentials that sample the pair, in one call to the Rust core for all parameters
   (:func:`sysid.greybox.delays.fractional_columns` and ``foh_columns``);
3. the fraction ``r`` of the delay ``tau = l h + r`` enters only through the lengths of the
   two sub-intervals: ``d/dt exp(M t) = M exp(M t)``, so its derivative is a product with the
   augmented matrix ``M`` (closed forms below), again exact.

Zero-order hold, with ``F_1 = e^{A (h - r)}``:
``d Gamma_0 / dr = -F_1 b`` and ``d Gamma_1 / dr = F_1 b`` (the two columns sum to the
undelayed ``Gamma``). First-order hold: the same rule applied to the two segments of
:func:`~sysid.greybox.delays.foh_columns`, plus the explicit ``r/h`` weights of its ramps.

Examples
--------
>>> import numpy as np
>>> from sysid.tf.sensitivity import pair_derivatives
>>> coef = lambda p: (p[1:], np.concatenate([[1.0], p[:1]]))     # p = [a1, b0]: b0 / (s + a1)
>>> S = pair_derivatives(coef, np.array([2.0, 3.0]), 0.1, 0, 0.04, "zoh")
>>> [s for s, _, _ in S.cols], len(S.d_cols), S.d_Ad[0].shape
([0, 1], 3, (1, 1))
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..greybox import delays as greydelay
from ..models.discretisation import expm
from .sampling import _foh_shift, canonical_form

__all__ = ["PairDerivatives", "pair_derivatives"]

_STEP = 1e-30


@dataclass
class PairDerivatives:
    """A sampled pair and its derivatives along each parameter, then the delay fraction.

    ``cols`` and each entry of ``d_cols`` are ``[(shift, B column, D column)]`` with the same
    shifts; ``d_c`` are derivatives of the ``(1, n)`` output row; ``G`` is the state at rest
    per unit first input (first-order hold without whole delay).
    """

    Ad: np.ndarray
    cols: list[tuple[int, np.ndarray, np.ndarray]]
    c: np.ndarray
    G: np.ndarray
    d_Ad: list[np.ndarray]
    d_cols: list[list[tuple[int, np.ndarray, np.ndarray]]]
    d_c: list[np.ndarray]
    d_G: list[np.ndarray]


def _realisation_derivatives(coef: Callable[[np.ndarray], Any], p: np.ndarray, freq: float
                             ) -> tuple[tuple[np.ndarray, ...], list[tuple[np.ndarray, ...]]]:
    num, den = coef(p)
    A, c, d = canonical_form(np.asarray(den, float), np.asarray(num, float), freq)
    ders = []
    for k in range(p.size):
        q = p.astype(complex)
        q[k] += 1j * _STEP
        nq, dq = coef(q)
        Aq, cq, dq_ = canonical_form(np.asarray(dq, complex), np.asarray(nq, complex), freq)
        ders.append((Aq.imag / _STEP, cq.imag / _STEP, dq_.imag / _STEP))
    return (A, c, d), ders


def pair_derivatives(coef: Callable[[np.ndarray], Any], p: np.ndarray, dt: float, whole: int,
                     r: float, hold: str, freq: float = 1.0) -> PairDerivatives:
    """The sampled pair of ``coef(p)`` delayed by ``whole dt + r`` and its derivatives along
    each entry of ``p``, then along ``r`` (``len(p) + 1`` directions); realised in time
    scaled by ``freq`` (:func:`sysid.tf.sampling.canonical`), a constant of the search."""
    (A, c, d), ders = _realisation_derivatives(coef, np.asarray(p, float), freq)
    n = A.shape[0]
    b = np.zeros(n)
    if n:
        b[-1] = freq
    Ad, dAd = expm(A * dt, [dA * dt for dA, _, _ in ders]) if n else (np.zeros((0, 0)), [
        np.zeros((0, 0)) for _ in ders])
    if hold == "zoh":
        cols, dcols, dG, G = _zoh(A, b, d, dt, whole, r, ders)
    else:
        cols, dcols, G, dG = _foh(A, b, c, d, Ad, dAd, dt, whole, r, ders)
    zero = np.zeros((0, 0)) if not n else np.zeros((n, n))
    return PairDerivatives(Ad, cols, c, G, list(dAd) + [zero], dcols,
                           [dc for _, dc, _ in ders] + [np.zeros_like(c)], dG)


def _zoh(A: np.ndarray, b: np.ndarray, d: np.ndarray, dt: float, whole: int, r: float,
         ders: list[tuple[np.ndarray, ...]]) -> tuple[Any, ...]:
    n = A.shape[0]
    if n:
        g0, g1, dg = greydelay.fractional_columns(A, b, dt, r, [(dA, np.zeros(n))
                                                               for dA, _, _ in ders])
        F1 = expm(A * (dt - r))[0]
        fb = F1 @ b
    else:
        g0 = g1 = fb = np.zeros(0)
        dg = [(np.zeros(0), np.zeros(0)) for _ in ders]
    at = 1 if r > 0 else 0  # the feedthrough column follows the delay's fraction

    def place(x0: np.ndarray, x1: np.ndarray, dd: np.ndarray) -> list[Any]:
        dcol = [dd if at == 0 else np.zeros_like(dd), dd if at == 1 else np.zeros_like(dd)]
        return [(whole, x0, dcol[0]), (whole + 1, x1, dcol[1])]

    cols = place(g0, g1, d)
    dcols = [place(a, b_, dd) for (a, b_), (_, _, dd) in zip(dg, ders)]
    dcols.append(place(-fb, fb, np.zeros_like(d)))
    zeros = [np.zeros(n) for _ in range(len(ders) + 1)]
    return cols, dcols, zeros, np.zeros(n)


def _foh(A: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray, Ad: np.ndarray,
         dAd: list[np.ndarray], dt: float, whole: int, r: float,
         ders: list[tuple[np.ndarray, ...]]) -> tuple[Any, ...]:
    n = A.shape[0]
    dirs = [(dA, np.zeros(n), dc, dd, dA_d) for (dA, dc, dd), dA_d in zip(ders, dAd)]
    cols, dcols = greydelay.foh_columns(A, b, c, d, Ad, dt, r, whole, dirs)
    cols = [(int(s), np.asarray(bc), np.asarray(dc)) for s, bc, dc in cols]
    dcols = [[(s, np.asarray(x), np.asarray(y)) for (s, _, _), (x, y) in zip(cols, dc)]
             for dc in dcols]
    dcols.append([(s, x, y) for s, (x, y) in zip([s for s, _, _ in cols],
                                                 _foh_delay(A, b, c, d, Ad, dt, whole, r))])
    if whole == 0:
        G = _foh_shift(A, b, dt, r)
        dG = [_foh_shift_derivative(A, b, dt, r, dA) for dA, _, _ in ders]
        M = _ramp(A, b, dt - r)
        dG.append(-(_ramp(A, b, 1.0) @ expm(M)[0])[:n, n + 1] / dt)
    else:
        G = np.zeros(n)
        dG = [np.zeros(n) for _ in range(len(ders) + 1)]
    return cols, dcols, G, dG


def _ramp(A: np.ndarray, b: np.ndarray, t: float, ramp: float = 1.0) -> np.ndarray:
    """``[[A, b, 0], [0, 0, ramp], [0, 0, 0]] t``."""
    n = A.shape[0]
    M = np.zeros((n + 2, n + 2))
    M[:n, :n], M[:n, n], M[n, n + 1] = A * t, b * t, ramp * t
    return M


def _foh_shift_derivative(A: np.ndarray, b: np.ndarray, dt: float, r: float,
                          dA: np.ndarray) -> np.ndarray:
    n = A.shape[0]
    _, (L,) = expm(_ramp(A, b, dt - r), [_ramp(dA, np.zeros(n), dt - r, 0.0)])
    return L[:n, n + 1] / dt


def _foh_delay(A: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray, Ad: np.ndarray,
               dt: float, whole: int, r: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """Derivatives along ``r`` of the first-order-hold columns (in the order of
    :func:`~sysid.greybox.delays.foh_columns`)."""
    n, h = A.shape[0], dt
    N1 = _ramp(A, b, 1.0)
    E1, E2 = expm(N1 * r)[0], expm(N1 * (h - r))[0]
    dE1, dE2 = N1 @ E1, -(N1 @ E2)            # d/dr exp(N r), d/dr exp(N (h - r))
    e0, e1, de0, de1 = E1[:n, n], E1[:n, n + 1], dE1[:n, n], dE1[:n, n + 1]
    v1, w1 = e0 * r / h - e1 / h, e0 * (1 - r / h) + e1 / h
    dv1 = de0 * r / h + e0 / h - de1 / h
    dw1 = de0 * (1 - r / h) - e0 / h + de1 / h
    F2, dF2 = E2[:n, :n], dE2[:n, :n]
    dgm = dF2 @ v1 + F2 @ dv1
    dg0 = dF2 @ w1 + F2 @ dw1 + dE2[:n, n] - dE2[:n, n + 1] / h
    dgp = dE2[:n, n + 1] / h
    ddm, dd0 = d / h, -d / h
    if whole >= 1:
        return [(dgp, np.zeros_like(d)), (dg0, dd0), (dgm, ddm)]
    return [(dg0 + Ad @ dgp, dd0 + c @ dgp), (dgm, ddm)]
