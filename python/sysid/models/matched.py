"""Matched pole-zero sampling (MATLAB's ``c2d(sys, Ts, 'matched')`` and its ``d2c`` inverse).

Every finite pole and zero of a single-input single-output model is mapped by ``z = e^{s dt}``
(and back by ``s = log(z) / dt``). Of the ``r`` zeros at infinity (``r`` the relative degree),
``r - 1`` are put at ``z = -1``, the Nyquist frequency, and one stays at infinity, so the
discrete model keeps one sample of delay and rolls off towards the Nyquist frequency as the
continuous one does at high frequency; this is what MATLAB's ``c2d(sys, Ts, 'matched')``
returns (``11 / (s^2 + s)`` at ``Ts = 0.1``: ``0.052339 (z + 1) / ((z - 1)(z - 0.9048))``).
python-control's ``sample_system(method='matched')`` adds no zeros at ``z = -1``; the two agree
up to the factor ``((z + 1) / 2)^(r - 1)``. ``d2c`` maps zeros at ``z = -1`` back to infinity.
The gain matches the DC gain; with poles or zeros at ``s = 0`` (``z = 1``) it matches the
low-frequency asymptote instead: ``s`` corresponds to ``(z - 1) / dt``, so an integrator
``1/s`` becomes ``dt / (z - 1)``.

Called by :func:`sysid.c2d` and :func:`sysid.d2c` with ``method="matched"``.

Examples
--------
>>> import numpy as np
>>> from sysid.models.matched import matched_c2d
>>> Ad, Bd, Cd, Dd = matched_c2d(np.array([[-1.0]]), np.array([[1.0]]), np.array([[1.0]]),
...                              np.array([[0.0]]), 0.1)
>>> bool(np.isclose(Ad[0, 0], np.exp(-0.1)))
True
>>> bool(np.isclose((Cd @ Bd)[0, 0] / (1 - Ad[0, 0]), 1.0))   # DC gain 1 kept
True
"""

from __future__ import annotations

import numpy as np

from ..errors import DataError, NumericalError
from .linear import transmission_zeros

__all__ = ["matched_c2d", "matched_d2c"]

Matrices = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]

#: How close to ``z = -1`` a discrete zero is taken as a zero at infinity by ``d2c``.
_NYQUIST_TOL = 1e-4


def _siso(B: np.ndarray, C: np.ndarray, direction: str) -> None:
    if B.shape[1] != 1 or C.shape[0] != 1:
        raise DataError(
            f"{direction} with method='matched' maps the poles and zeros of one input-output "
            f"channel, but this model has {B.shape[1]} inputs and {C.shape[0]} outputs; "
            "convert each channel on its own (one column of B, one row of C) or use "
            "method='zoh' or 'tustin'")


def _gain(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray, poles: np.ndarray,
          zeros: np.ndarray) -> float:
    """``K`` in ``G(x) = K prod(x - zeros) / prod(x - poles)``, from one evaluation of ``G``
    at a point well away from every pole and zero."""
    n = A.shape[0]
    radius = 1.0 + float(np.max(np.abs(np.r_[poles, zeros]), initial=0.0))
    x0 = radius * (0.6 + 1.7j)
    g = (C @ np.linalg.solve(x0 * np.eye(n) - A, B) + D)[0, 0] if n else D[0, 0]
    ratio = np.prod(x0 - poles) / np.prod(x0 - zeros)
    return float((g * ratio).real)


def _at_origin(roots: np.ndarray, origin: float, dt: float) -> np.ndarray:
    """Which roots sit at the origin of the low-frequency asymptote (``s = 0`` or ``z = 1``)."""
    return np.abs(roots - origin) <= 1e-9 * max(1.0, 1.0 / dt if origin == 0.0 else 1.0)


def _realise(zeros: np.ndarray, poles: np.ndarray, k: float, n: int) -> Matrices:
    if n == 0:
        return np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.array([[k]])
    # the roots come in conjugate pairs up to rounding: the polynomials are real
    den = np.poly(poles).real
    num = k * np.poly(zeros).real if zeros.size else np.array([k])
    # the controllable companion form of num / den (no polynomial normalisation: SciPy's
    # tf2ss trims tiny leading numerator terms and warns about them)
    den = den / den[0]
    num = np.r_[np.zeros(n + 1 - num.size), num] / 1.0
    d = num[0]
    rest = num[1:] - d * den[1:]
    A = np.zeros((n, n))
    A[0] = -den[1:]
    A[1:, :-1] = np.eye(n - 1)
    B = np.zeros((n, 1))
    B[0, 0] = 1.0
    C = rest[None, :]
    D = np.array([[d]])
    return (np.asarray(A, float), np.asarray(B, float).reshape(n, 1),
            np.asarray(C, float).reshape(1, n), np.asarray(D, float).reshape(1, 1))


def matched_c2d(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
                dt: float) -> Matrices:
    """Discrete ``(Ad, Bd, Cd, Dd)`` with poles and zeros ``e^{s dt}`` and the same DC gain
    (the same low-frequency asymptote with integrators or differentiators)."""
    _siso(B, C, "c2d")
    n = A.shape[0]
    poles = np.linalg.eigvals(A).astype(complex) if n else np.zeros(0, complex)
    zeros = transmission_zeros(A, B, C, D).astype(complex) if n else np.zeros(0, complex)
    K = _gain(A, B, C, D, poles, zeros)
    p0, z0 = _at_origin(poles, 0.0, dt), _at_origin(zeros, 0.0, dt)
    zp, zz = np.exp(poles * dt), np.exp(zeros * dt)
    zp[p0], zz[z0] = 1.0, 1.0
    # low-frequency asymptote: (s - q) <-> (1 - e^{q dt}) / (-q) (z - e^{q dt}), s <-> (z - 1) / dt
    k = K * np.prod(-zeros[~z0]) / np.prod(-poles[~p0])
    k *= np.prod(1.0 - zp[~p0]) / np.prod(1.0 - zz[~z0]) * dt ** (int(p0.sum()) - int(z0.sum()))
    # all but one of the zeros at infinity to the Nyquist frequency (each is 2 at z = 1)
    nyquist = max(n - zeros.size - 1, 0)
    zz = np.r_[zz, -np.ones(nyquist)]
    return _realise(zz, zp, float(np.real(k)) / 2.0 ** nyquist, n)


def _log(roots: np.ndarray, what: str, dt: float) -> np.ndarray:
    bad = (np.abs(roots.imag) <= 1e-12 * np.maximum(1, np.abs(roots))) & (roots.real <= 0)
    if bad.any():
        raise NumericalError(
            f"d2c with method='matched': the model has a {what} at z = {roots[bad][0].real:g} "
            "(on the negative real axis or at zero), which e^{s dt} reaches from no real s; "
            "use method='tustin'")
    out = np.log(roots) / dt
    real = np.abs(roots.imag) <= 1e-12 * np.abs(roots)
    out[real] = out[real].real
    return out


def matched_d2c(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
                dt: float) -> Matrices:
    """Inverse of :func:`matched_c2d`: poles and zeros ``log(z) / dt`` (zeros at ``z = -1`` to
    infinity), the same DC gain."""
    _siso(B, C, "d2c")
    n = A.shape[0]
    zp = np.linalg.eigvals(A).astype(complex) if n else np.zeros(0, complex)
    zz = transmission_zeros(A, B, C, D).astype(complex) if n else np.zeros(0, complex)
    k = _gain(A, B, C, D, zp, zz)
    # zeros at the Nyquist frequency are zeros at infinity (each is 2 at z = 1); a multiple
    # one is computed to about eps^(1/multiplicity), hence the tolerance
    nyquist = np.abs(zz + 1.0) <= _NYQUIST_TOL
    k, zz = k * 2.0 ** int(nyquist.sum()), zz[~nyquist]
    p0, z0 = _at_origin(zp, 1.0, dt), _at_origin(zz, 1.0, dt)
    poles, zeros = np.zeros(n, complex), np.zeros(zz.size, complex)
    poles[~p0], zeros[~z0] = _log(zp[~p0], "pole", dt), _log(zz[~z0], "zero", dt)
    K = k * np.prod(-poles[~p0]) / np.prod(-zeros[~z0])
    K *= np.prod(1.0 - zz[~z0]) / np.prod(1.0 - zp[~p0]) / dt ** (int(p0.sum()) - int(z0.sum()))
    return _realise(zeros, poles, float(np.real(K)), n)
