"""The penalty of a regularised ARX fit is MATLAB's ``lam theta^T R theta`` on ``theta = [a, b]``
(the polynomials' coefficients, ``model.parameters``), one ``(lam, R)`` per output.

The fits are checked against the normal equations written out by hand with the regressors
``-y(t - k)`` and ``u(t - nk - l)`` (MATLAB's), over the rows ``t >= max lag``."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

import sysid
from sysid.errors import DataError

# a penalty with A-B cross terms: on [-a, b] it is another penalty
R3 = np.array([[2.0, 0.9, 0.3], [0.9, 1.5, 0.2], [0.3, 0.2, 1.0]])


def _siso(n=100, seed=0):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n)
    y = lfilter([0, 1, 0.5], [1, -0.7], u) + 0.3 * rng.standard_normal(n)
    return u, y, sysid.IOData(u[:, None], y[:, None], 1.0)


def _penalised(Phi, y, lam, R):
    return np.linalg.solve(Phi.T @ Phi + lam * R, Phi.T @ y)


def test_lam_r_penalises_the_polynomial_coefficients():
    """arx(d, 1, 2, 1, regularization=(50, R)) gave [-0.542, 0.399, 0.376], the solution for
    S R S (S = diag(-1, 1, 1)); MATLAB's penalty gives [-0.648, 0.709, 0.383]."""
    u, y, d = _siso()
    lam = 50.0
    t = np.arange(2, u.size)
    Phi = np.column_stack([-y[t - 1], u[t - 1], u[t - 2]])
    want = _penalised(Phi, y[t], lam, R3)
    m = sysid.arx(d, 1, 2, 1, regularization=(lam, R3))
    np.testing.assert_allclose(m.parameters[0], want, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(want, [-0.64823, 0.70864, 0.38286], atol=1e-5)
    np.testing.assert_allclose(m.a[0][0], want[:1], rtol=1e-10)
    np.testing.assert_allclose(m.b[0][0], want[1:], rtol=1e-10)
    # the loss leaves the penalty out; the covariance is loss (Phi^T Phi + lam R)^-1
    e = y[t] - Phi @ want
    np.testing.assert_allclose(m.info["loss"][0], e @ e / t.size, rtol=1e-9)
    np.testing.assert_allclose(m.covariance[0],
                               e @ e / t.size * np.linalg.inv(Phi.T @ Phi + lam * R3),
                               rtol=1e-8)


def test_kernel_factor_penalises_the_polynomial_coefficients():
    u, y, d = _siso(seed=1)
    M = np.linalg.cholesky(R3).T  # M^T M = R3
    t = np.arange(2, u.size)
    Phi = np.column_stack([-y[t - 1], u[t - 1], u[t - 2]])
    m = sysid.arx(d, 1, 2, 1, regularization=20.0, kernel=M)
    np.testing.assert_allclose(m.parameters[0], _penalised(Phi, y[t], 20.0, R3), rtol=1e-10)
    same = sysid.arx(d, 1, 2, 1, regularization=(20.0, R3))
    np.testing.assert_allclose(m.parameters[0], same.parameters[0], rtol=1e-10)


def test_kernel_factor_of_outputs_with_different_a_orders():
    """The A columns differ per output (one A coefficient in output 0's equation, two in
    output 1's): each output's penalty is still on its own [a, b]."""
    rng = np.random.default_rng(2)
    n = 400
    u = rng.standard_normal((n, 2))
    y = np.zeros((n, 2))
    for k in range(1, n):
        y[k, 0] = 0.6 * y[k - 1, 0] + u[k - 1, 0] + 0.1 * rng.standard_normal()
        y[k, 1] = 0.3 * y[k - 1, 0] + 0.5 * y[k - 1, 1] + u[k - 1, 1] + 0.1 * rng.standard_normal()
    d = sysid.IOData(u, y, 1.0)
    na, nb = [[1, 0], [1, 1]], [[2, 1], [1, 1]]  # both equations have 4 parameters
    M = np.linalg.cholesky(np.array([[3.0, 1.0, 0.5, 0.2], [1.0, 2.0, 0.4, 0.1],
                                     [0.5, 0.4, 1.5, 0.3], [0.2, 0.1, 0.3, 1.0]])).T
    m = sysid.arx(d, na, nb, 1, regularization=30.0, kernel=M)
    t = np.arange(2, n)
    phis = [np.column_stack([-y[t - 1, 0], u[t - 1, 0], u[t - 2, 0], u[t - 1, 1]]),
            np.column_stack([-y[t - 1, 0], -y[t - 1, 1], u[t - 1, 0], u[t - 1, 1]])]
    for i, Phi in enumerate(phis):
        np.testing.assert_allclose(m.parameters[i], _penalised(Phi, y[t, i], 30.0, M.T @ M),
                                   rtol=1e-9)


def test_a_prior_with_cross_terms_is_the_prior_of_the_polynomial_coefficients():
    """An ArxRegularization whose prior couples A and B: the posterior mean is
    (Phi^T Phi + lam P^-1)^-1 Phi^T y with MATLAB's regressors; the tuned (block-diagonal)
    kernels are the same prior either way."""
    u, y, d = _siso(n=300, seed=3)
    reg = sysid.arxregul(d, 1, 2, 1, "tc")
    t = np.arange(2, u.size)
    Phi = np.column_stack([-y[t - 1], u[t - 1], u[t - 2]])
    lam = float(reg.lam[0])
    tuned = sysid.arx(d, 1, 2, 1, regularization=reg)
    np.testing.assert_allclose(tuned.parameters[0],
                               _penalised(Phi, y[t], lam, np.linalg.inv(reg.prior[0])),
                               rtol=1e-8)
    reg.prior = [np.linalg.inv(R3)]
    coupled = sysid.arx(d, 1, 2, 1, regularization=reg)
    np.testing.assert_allclose(coupled.parameters[0], _penalised(Phi, y[t], lam, R3),
                               rtol=1e-8)
    np.testing.assert_allclose(coupled.parameters[0],
                               sysid.arx(d, 1, 2, 1, regularization=(lam, R3)).parameters[0],
                               rtol=1e-8)


def _two_outputs():
    rng = np.random.default_rng(0)
    u = rng.standard_normal((300, 1))
    Y = rng.standard_normal((300, 2))
    return u, Y, sysid.IOData(u, Y, 1.0)


def test_one_pair_per_output():
    """[(1, I), (5, I)] for two outputs raised numpy's "inhomogeneous shape" ValueError."""
    u, Y, d = _two_outputs()
    m = sysid.arx(d, [[1, 0], [0, 1]], [[1], [1]], [[1], [1]],
                  regularization=[(1.0, np.eye(2)), (5.0, np.eye(2))])
    t = np.arange(1, 300)
    for i, lam in enumerate([1.0, 5.0]):
        Phi = np.column_stack([-Y[t - 1, i], u[t - 1, 0]])
        np.testing.assert_allclose(m.parameters[i], _penalised(Phi, Y[t, i], lam, np.eye(2)),
                                   rtol=1e-10)
    assert m.info["regularization"] == {"lam": [1.0, 5.0]}
    # a tuple of pairs, and one pair for both outputs
    again = sysid.arx(d, [[1, 0], [0, 1]], 1, 1, regularization=((1.0, np.eye(2)),
                                                                 (5.0, np.eye(2))))
    np.testing.assert_allclose(again.parameters[1], m.parameters[1], rtol=1e-12)
    both = sysid.arx(d, [[1, 0], [0, 1]], 1, 1, regularization=(5.0, np.eye(2)))
    np.testing.assert_allclose(both.parameters[1], m.parameters[1], rtol=1e-12)


def test_each_output_gets_its_own_r_sized_by_its_equation():
    """Output 0 has three parameters (A couples y1), output 1 two: each R is checked and used
    for its own output (one output's R was passed for every output and the error named
    the wrong one)."""
    u, Y, d = _two_outputs()
    na = [[1, 1], [0, 1]]
    R0 = np.array([[2.0, 0.5, 0.3], [0.5, 1.0, 0.1], [0.3, 0.1, 1.0]])
    R1 = np.array([[1.0, 0.4], [0.4, 3.0]])
    m = sysid.arx(d, na, 1, 1, regularization=[(4.0, R0), (2.0, R1)])
    t = np.arange(1, 300)
    Phi0 = np.column_stack([-Y[t - 1, 0], -Y[t - 1, 1], u[t - 1, 0]])
    Phi1 = np.column_stack([-Y[t - 1, 1], u[t - 1, 0]])
    np.testing.assert_allclose(m.parameters[0], _penalised(Phi0, Y[t, 0], 4.0, R0), rtol=1e-10)
    np.testing.assert_allclose(m.parameters[1], _penalised(Phi1, Y[t, 1], 2.0, R1), rtol=1e-10)
    with pytest.raises(DataError, match=r"R of output 1 has shape \(3, 3\) but should be "
                                        r"\(2, 2\)"):
        sysid.arx(d, na, 1, 1, regularization=[(4.0, R0), (2.0, R0)])
    with pytest.raises(DataError, match=r"R of output 0 has shape \(2, 2\) but should be "
                                        r"\(3, 3\)"):
        sysid.arx(d, na, 1, 1, regularization=(1.0, R1))
    with pytest.raises(DataError, match="kernel has shape .* output 1's equation has 2"):
        sysid.arx(d, na, 1, 1, regularization=1.0, kernel=np.eye(3))
    with pytest.raises(DataError, match="one pair, or 2 pairs"):
        sysid.arx(d, na, 1, 1, regularization=[(4.0, R0)])
    with pytest.raises(DataError, match="lam of output 1 must be a finite number >= 0"):
        sysid.arx(d, na, 1, 1, regularization=[(4.0, R0), (-1.0, R1)])


def test_zero_lam_is_plain_least_squares():
    u, Y, d = _two_outputs()
    base = sysid.arx(d, [[1, 0], [0, 1]], 1, 1)
    zero = sysid.arx(d, [[1, 0], [0, 1]], 1, 1, regularization=[(0.0, R3[:2, :2]),
                                                                (0.0, np.eye(2))])
    for i in range(2):
        np.testing.assert_array_equal(zero.parameters[i], base.parameters[i])
    mixed = sysid.arx(d, [[1, 0], [0, 1]], 1, 1, regularization=[(0.0, np.eye(2)),
                                                                 (3.0, np.eye(2))])
    np.testing.assert_allclose(mixed.parameters[0], base.parameters[0], rtol=1e-10)
    assert not np.allclose(mixed.parameters[1], base.parameters[1], rtol=1e-3)
