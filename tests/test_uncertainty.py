"""Parameter uncertainty (sysid.models.uncertainty) and its propagation: unit checks,
invariances, and Monte Carlo calibration for PEM, the subspace bootstrap and polynomial models."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import signal

import sysid
from sysid import _sysid
from sysid.errors import DataError
from sysid.models.pole_uncertainty import coincident_poles, pole_std
from sysid.models.uncertainty import ParameterUncertainty, UncertaintyWarning


def _truth() -> sysid.StateSpaceModel:
    A = np.array([[0.8, 0.3, 0.0, 0.0], [-0.3, 0.8, 0.0, 0.0],
                  [0.0, 0.0, 0.5, 0.0], [0.0, 0.0, 0.0, -0.4]])
    B = np.array([[1.0, 0.0], [0.5, 1.0], [0.0, 1.0], [1.0, -0.5]])
    C = np.array([[1.0, 0.0, 1.0, 0.5], [0.0, 1.0, -0.5, 1.0]])
    K = np.array([[0.3, 0.0], [0.0, 0.2], [0.1, 0.1], [0.0, 0.2]])
    return sysid.StateSpaceModel(A, B, C, np.zeros((2, 2)), K)


def _simulate(true, u, e):
    """Innovation form x+ = A x + B u + K e, y = C x + D u + e: process and measurement noise."""
    Ba = np.hstack([true.B, true.K])
    Da = np.hstack([true.D, np.eye(true.noutputs)])
    return _sysid.simulate(true.A, Ba, true.C, Da, np.hstack([u, e]), None)


def _first_order(theta=(0.5, 1.0), var=(1e-4, 4e-4)):
    return ParameterUncertainty(
        list(theta), np.diag(var),
        lambda t: sysid.StateSpaceModel([[t[0]]], [[t[1]]], [[1.0]], dt=0.1),
        names=["a", "b"])


# -- the class ---------------------------------------------------------------------------
def test_std_correlation_summary_and_repr():
    P = np.array([[4e-4, 1e-4], [1e-4, 1e-4]])
    unc = ParameterUncertainty([0.5, 1.0], P, lambda t: None, names=["a", "b"], method="x")
    np.testing.assert_allclose(unc.std, [0.02, 0.01])
    np.testing.assert_allclose(unc.correlation, [[1, 0.5], [0.5, 1]])
    assert repr(unc) == "ParameterUncertainty(2 parameters, rank 2, x)"
    assert "a" in unc.summary() and "0.02" in unc.summary()
    df = unc.to_pandas()
    assert list(df.index) == ["a", "b"] and np.allclose(df["std"], [0.02, 0.01])


def test_bad_input_is_named():
    build = lambda t: None  # noqa: E731
    with pytest.raises(DataError, match="shape"):
        ParameterUncertainty([1.0, 2.0], np.eye(3), build)
    with pytest.raises(DataError, match="positive semi-definite"):
        ParameterUncertainty([1.0, 2.0], np.diag([1.0, -1.0]), build)
    with pytest.raises(DataError, match="finite"):
        ParameterUncertainty([np.nan], [[1.0]], build)
    with pytest.raises(DataError, match="names"):
        ParameterUncertainty([1.0], [[1.0]], build, names=["a", "b"])
    with pytest.raises(DataError, match="method"):
        _first_order().propagate(lambda m: m.dcgain(), method="exact")
    with pytest.raises(DataError, match="real"):
        _first_order().propagate(lambda m: m.poles())
    with pytest.raises(DataError, match="no parameter uncertainty"):
        sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]).poles(std=True)


def test_linear_and_monte_carlo_agree_on_a_smooth_function():
    unc = _first_order()
    f = lambda m: np.r_[m.dcgain().ravel(), np.abs(m.freqresp([1.0, 5.0])[:, 0, 0])]  # noqa
    lin = unc.propagate(f)
    mc = unc.propagate(f, "monte-carlo", n=4000, rng=3)
    np.testing.assert_allclose(mc.std, lin.std, rtol=0.05)
    # the analytic Jacobian of the gain b / (1 - a) gives the same first order
    J = lambda t: np.array([[t[1] / (1 - t[0]) ** 2, 1 / (1 - t[0])]])  # noqa: E731
    an = unc.propagate(lambda m: m.dcgain().ravel(), jacobian=J)
    np.testing.assert_allclose(an.std, lin.std[:1], rtol=1e-6)
    # the option changes the result: Monte Carlo is a sampling estimate, not the linearisation
    assert not np.allclose(mc.covariance, lin.covariance, rtol=1e-6)
    # a large difference step sees the curvature of b / (1 - a): another (worse) number
    wide = unc.propagate(f, step=3.0)
    assert not np.allclose(wide.std, lin.std, rtol=1e-4)
    np.testing.assert_allclose(unc.propagate(f, step=1e-4).std, lin.std, rtol=1e-6)


def test_sample_has_the_covariance():
    P = np.array([[4e-4, 1e-4], [1e-4, 1e-4]])
    unc = ParameterUncertainty([0.5, 1.0], P, lambda t: t)
    draws = np.array(unc.sample(20000, rng=0))
    np.testing.assert_allclose(np.cov(draws, rowvar=False), P, rtol=0.05, atol=5e-6)
    a, b = unc.sample(2, rng=5), unc.sample(2, rng=5)
    assert np.array_equal(a, b)


def test_singular_covariance_only_steps_identifiable_directions():
    # theta = (a1, a2) with A = a1 + a2: only the sum is identified
    v = np.array([1.0, 1.0]) / np.sqrt(2)
    P = 2e-4 * np.outer(v, v)
    unc = ParameterUncertainty([0.2, 0.3], P,
                               lambda t: sysid.StateSpaceModel([[t[0] + t[1]]], [[1.0]], [[1.0]]))
    assert unc.dof == 1
    m = unc.model
    m.uncertainty = unc
    p, sd = m.poles(std=True)
    np.testing.assert_allclose(sd.real, [0.02], rtol=1e-6)  # var(a1 + a2) = 2 * 2e-4
    J = unc.jacobian(lambda mm: mm.poles().real)
    np.testing.assert_allclose(J, [[1.0, 1.0]], atol=1e-6)
    # a function of theta0 alone: only its component along the identifiable sum is seen
    J0 = ParameterUncertainty([0.2, 0.3], P, lambda t: t).jacobian(lambda t: t[:1])
    np.testing.assert_allclose(J0, [[0.5, 0.5]], atol=1e-6)


# -- state-space quantities --------------------------------------------------------------
def _model_with_uncertainty(seed=0, scale=1e-5):
    true = _truth()
    rng = np.random.default_rng(seed)
    theta = np.concatenate([true.A.ravel(), true.B.ravel(), true.C.ravel()])
    L = rng.standard_normal((theta.size, theta.size))
    P = scale * (L @ L.T) / theta.size

    def build(t):
        return sysid.StateSpaceModel(t[:16].reshape(4, 4), t[16:24].reshape(4, 2),
                                     t[24:32].reshape(2, 4), np.zeros((2, 2)), dt=0.1)
    m = build(theta)
    m.uncertainty = ParameterUncertainty(theta, P, build)
    return m


def test_pole_std_analytic_matches_differenced_eigenvalues():
    m = _model_with_uncertainty()
    p, sd = m.poles(std=True)
    # the same quantity by central differences of matched eigenvalues (generic route)
    ref = np.sort_complex(p)

    def parts(mm):
        q = np.sort_complex(mm.poles())
        return np.r_[q.real, q.imag]
    prop = m.uncertainty.propagate(parts)
    order = [int(np.argmin(np.abs(ref - z))) for z in p]
    np.testing.assert_allclose(sd.real, prop.std[:4][order], rtol=1e-5)
    np.testing.assert_allclose(sd.imag, prop.std[4:][order], rtol=1e-5, atol=1e-12)
    mc_p, mc_sd = m.poles(std=True, method="monte-carlo")
    np.testing.assert_allclose(mc_sd.real, sd.real, rtol=0.1)


def test_markov_dcgain_freqresp_std_and_model_std():
    m = _model_with_uncertainty()
    unc = m.uncertainty
    val, sd = m.markov(4, std=True)
    assert val.shape == sd.shape == (4, 2, 2) and np.all(sd[0] == 0)  # D is not a parameter
    np.testing.assert_allclose(sd[1].ravel(),
                               unc.propagate(lambda mm: mm.markov(2)[1].ravel()).std, rtol=1e-6)
    g, gsd = m.dcgain(std=True)
    np.testing.assert_allclose(g, m.dcgain())
    assert np.all(gsd > 0)
    H, Hsd = m.freqresp([0.0, 3.0], std=True)
    # the analytic state-space derivative equals differencing the frequency response
    _, G = unc.scaled_jacobian(lambda mm: mm.freqresp([0.0, 3.0]))
    num = np.sqrt(np.sum(G.real**2, 1)) + 1j * np.sqrt(np.sum(G.imag**2, 1))
    np.testing.assert_allclose(Hsd.ravel(), num, rtol=1e-6, atol=1e-14)
    np.testing.assert_allclose(Hsd[0].real, gsd, rtol=1e-6)  # H(0) is the DC gain
    np.testing.assert_allclose(Hsd[0].imag, 0, atol=1e-12)
    std = m.std
    np.testing.assert_allclose(std["A"].ravel(), unc.std[:16], rtol=1e-6)
    np.testing.assert_allclose(std["C"].ravel(), unc.std[24:], rtol=1e-6)
    assert np.all(std["D"] == 0) and "K" not in std
    assert m.covariance is unc.covariance


def test_damping_table_std_columns_match_propagation():
    m = _model_with_uncertainty(scale=1e-6)
    table = sysid.damp(m, std=True)

    def zeta_wn(mm):
        t = sysid.damp(mm)
        return np.r_[t.zeta, t.wn_hz]
    prop = m.uncertainty.propagate(zeta_wn)
    np.testing.assert_allclose(table.zeta_std, prop.std[:4], rtol=1e-4, atol=1e-12)
    np.testing.assert_allclose(table.wn_hz_std, prop.std[4:], rtol=1e-4)
    df = table.to_pandas()
    assert {"std wn [Hz]", "std damping", "std Re(pole)"} <= set(df.columns)
    assert "std damp" in repr(table)
    assert sysid.damp(m).zeta_std is None


def test_a_well_determined_pole_keeps_its_first_order_std_beside_an_uncertain_one():
    """A slow pole known to 0.002 at 0.98, a neighbour at 0.90 known to 0.1: the neighbour's
    region reaches the slow pole, not the other way round. The slow pole's std stays first
    order (the Monte Carlo draws mixed the two in their matching: a heating record's
    bootstrap std of its 0.98 pole was three times the spread of its own refits)."""
    def build(t):
        return sysid.StateSpaceModel([[t[0], 0.0], [0.0, t[1]]], [[1.0], [1.0]], [[1.0, 1.0]])
    theta = [0.98, 0.90]
    m = build(theta)
    m.uncertainty = ParameterUncertainty(theta, np.diag([0.002, 0.1]) ** 2, build)
    with pytest.warns(UncertaintyWarning, match="1 pole"):
        p, sd = m.poles(std=True)
    slow = int(np.argmin(np.abs(p - 0.98)))
    assert sd.real[slow] == pytest.approx(0.002, rel=1e-6)
    assert list(coincident_poles(p, np.abs(sd))) == [i != slow for i in range(2)]


def test_coincident_poles_get_the_monte_carlo_std_and_say_so():
    """Poles closer than their uncertainty: first order does not exist there, so the std is
    the Monte Carlo value (said in an UncertaintyWarning), never NaN."""
    def build(t):
        return sysid.StateSpaceModel([[t[0], 0.0], [0.0, t[1]]], [[1.0], [1.0]], [[1.0, 1.0]])
    for theta in ([0.5, 0.5 + 1e-4], [0.5, 0.5]):   # near-repeated, and exactly repeated
        m = build(theta)
        m.uncertainty = ParameterUncertainty(theta, 1e-4 * np.eye(2), build)
        with pytest.warns(UncertaintyWarning, match="Monte Carlo"):
            p, sd = m.poles(std=True)
        _, mc = pole_std(m, "monte-carlo", n=2000, rng=1)
        assert np.all(np.isfinite(sd.real)) and np.all(sd.real > 0.003)
        np.testing.assert_allclose(sd.real, mc.real, rtol=0.15)
        with pytest.warns(UncertaintyWarning, match="Monte Carlo"):
            t = sysid.damp(m, std=True)
        assert np.all(np.isfinite(t.zeta_std)) and np.all(np.isfinite(t.wn_hz_std))
        assert list(t.std_method) == ["monte-carlo"] * 2
    # well separated: first order, no warning
    far = build([0.5, -0.5])
    far.uncertainty = ParameterUncertainty([0.5, -0.5], 1e-4 * np.eye(2), build)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        np.testing.assert_allclose(far.poles(std=True)[1].real, [0.01, 0.01])
        assert list(sysid.damp(far, std=True).std_method) == ["linear"] * 2


def test_distinct_poles_with_large_uncertainty_keep_their_first_order_std():
    """Issue 26: poles 0.4 apart with std ~0.1 got NaN ("near-repeated"); they are distinct,
    so they get the eigenvalue-derivative std, which matches sampling here."""
    def build(t):
        A = np.array([[t[0], t[2]], [0.0, t[1]]])
        return sysid.StateSpaceModel(A, [[1.0], [1.0]], [[1.0, 0.5]], dt=0.1)
    theta = np.array([0.3, 0.7, 0.2])
    m = build(theta)
    P = np.diag([0.07, 0.07, 0.05]) ** 2
    m.uncertainty = ParameterUncertainty(theta, P, build)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p, sd = m.poles(std=True)
        t = sysid.damp(m, std=True)
    np.testing.assert_allclose(sd.real[np.argsort(p.real)], [0.07, 0.07], rtol=1e-6)
    _, mc = pole_std(m, "monte-carlo", n=4000, rng=0)
    np.testing.assert_allclose(sd.real, mc.real, rtol=0.1)
    assert np.all(np.isfinite(t.wn_hz_std)) and np.all(t.wn_hz_std > 0)
    # the damping table's frequency std is the first-order image of the pole std:
    # wn = |log z| / dt for a real pole z, d wn = dz / (z dt)
    np.testing.assert_allclose(np.sort(t.wn_std), np.sort(0.07 / (p.real * 0.1)), rtol=1e-4)


def test_poles_of_different_polynomials_never_coincide():
    """A multi-input OE model on the winding record (5 inputs, 2 outputs) warned that 11 poles
    "coincide with another pole" and reported Monte Carlo values: poles of different ``F_ij``
    that are close in value. Roots of different polynomials are independent: each pole's std
    is its own polynomial's first-order value, as if that polynomial were fitted alone; only
    roots of one polynomial can coincide."""
    def build(t):
        return sysid.PolynomialModel(
            a=[[np.zeros(0)]], b=[[np.array([1.0]), np.array([0.5])]],
            f=[[np.array([t[0]]), np.array([t[1], t[2]])]], nk=[[1, 1]], dt=1.0)
    f2 = np.convolve([1.0, -0.6005], [1.0, 0.3])[1:]       # roots 0.6005 and -0.3
    theta = np.r_[-0.6, f2]                                 # F1's root 0.6
    P = np.diag([1e-4, 4e-4, 4e-4])
    m = build(theta)
    m.uncertainty = ParameterUncertainty(theta, P, build)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p, sd = m.poles(std=True)
        t = sysid.damp(m, std=True)
    assert list(t.std_method) == ["linear"] * 3
    np.testing.assert_allclose(p[0], 0.6)
    np.testing.assert_allclose(sd[0].real, 0.01)
    # F2 alone: the same std for its two roots
    def alone(t):
        return sysid.PolynomialModel(a=[[np.zeros(0)]], b=[[np.array([0.5])]],
                                     f=[[np.array(t)]], nk=[[1]], dt=1.0)
    m2 = alone(f2)
    m2.uncertainty = ParameterUncertainty(f2, P[1:, 1:], alone)
    p2, sd2 = m2.poles(std=True)
    np.testing.assert_allclose(p[1:], p2, atol=1e-12)
    np.testing.assert_allclose(sd[1:], sd2, rtol=1e-6)
    # roots of one polynomial still coincide: F2 with a double root at 0.6
    near = np.r_[-0.6, np.convolve([1.0, -0.6], [1.0, -0.6001])[1:]]
    m3 = build(near)
    m3.uncertainty = ParameterUncertainty(near, P, build)
    with pytest.warns(UncertaintyWarning, match="2 pole"):
        m3.poles(std=True)
    # the same for a transfer function's denominators, channel by channel
    def tf(t):
        return sysid.TransferFunction([[[1.0], [1.0]]], [[[1.0, t[0]], [1.0, t[1]]]], dt=1.0)
    g = tf([-0.6, -0.6005])
    g.uncertainty = ParameterUncertainty([-0.6, -0.6005], 1e-4 * np.eye(2), tf)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        np.testing.assert_allclose(g.poles(std=True)[1].real, [0.01, 0.01], rtol=1e-6)


def test_a_quantity_undefined_on_one_side_of_the_estimate_gets_a_one_sided_derivative():
    """procest on a real record (a pole at -2.7e8, its time constant's std far larger than
    itself) raised "A has non-finite entries" from step(std=True): a model 0.001 std away
    was unstable. The derivative is taken on the side where the quantity exists; with
    neither side, the std is inf and an UncertaintyWarning says why."""
    from sysid.errors import NumericalError

    unc = ParameterUncertainty([0.5], [[1e-4]],
                               lambda t: sysid.StateSpaceModel([[t[0]]], [[1.0]], [[1.0]]))

    def square_within(lo, hi):
        def fn(m):
            if not lo <= m.A[0, 0] <= hi:
                raise NumericalError("simulate", "the simulated output overflowed")
            return m.A[0, 0] ** 2
        return fn
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _, G = unc.scaled_jacobian(square_within(0.0, 0.5))   # only the lower side exists
    np.testing.assert_allclose(abs(G[0, 0]), 2 * 0.5 * 0.01, rtol=1e-3)
    with pytest.warns(UncertaintyWarning, match="both sides"):
        _, G = unc.scaled_jacobian(square_within(0.5, 0.5))   # neither side
    assert np.isinf(G[0, 0])


def test_a_large_parameter_does_not_stretch_the_steps_of_well_determined_directions():
    """identify's output-error model of an industrial robot record (an initial state in the
    millions beside a pole at 0.9993 known to 1e-3) raised LinAlgError from poles(std=True)
    and from saving: the difference step's floor was 1e-7 of the largest parameter, so the
    best-determined direction was stepped hundreds of its standard deviations, into an
    unstable model whose simulation reached 1e204. The floor now follows the parameters each
    direction moves: dcgain's std from the pole is its first-order value."""
    a, sd_a = 0.99, 1e-4
    unc = ParameterUncertainty(
        [a, 3e6], np.diag([sd_a**2, 1.0]),
        lambda t: sysid.StateSpaceModel([[t[0]]], [[1.0, t[1]]], [[1.0]]), names=["a", "b2"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        g = unc.propagate(lambda m: m.dcgain().ravel()[:1])
    np.testing.assert_allclose(g.std[0], sd_a / (1 - a) ** 2, rtol=1e-4)


def test_a_step_into_a_runaway_simulation_is_shortened():
    """A simulation that runs away on one side of a step (the perturbed model unstable over
    the record) is no derivative: the step is shortened until both sides agree, and the std
    of a simulated output is its first-order value, not the runaway's."""
    a, sd_a = 0.9999, 1.0  # a std far past the stability margin: 1e-3 std crosses it
    unc = ParameterUncertainty([a], [[sd_a**2]],
                               lambda t: sysid.StateSpaceModel([[t[0]]], [[1.0]], [[1.0]]))
    u = np.ones((20000, 1))
    g = unc.propagate(lambda m: m.simulate(u)[-1])
    t = np.arange(20000)  # y[N-1] = sum_{k<N-1} a^k: its derivative sum k a^(k-1)
    # (before: 3.6e13 from the runaway side; the shortened step's curvature error: 0.3 %)
    np.testing.assert_allclose(g.std[0], sd_a * np.sum(t[1:-1] * a ** (t[1:-1] - 1)),
                               rtol=1e-2)


def test_a_near_integrator_does_not_stretch_the_step_horizon_to_years():
    """tfest on a real record fitted a pole at -5.5e-12 beside dynamics at 1e-3 rad/s: the
    default step horizon (five time constants of the slowest pole) was 1e12 s, and
    step(std=True) overflowed on a model within the uncertainty. Such a pole acts as an
    integrator: the horizon follows the other poles."""
    den = np.convolve([1.0, 5e-12], [1.0, 0.01])
    g = sysid.TransferFunction([[[0.01]]], [[den]])
    r = g.step()
    assert 400.0 < r.t[-1] < 600.0                   # five time constants of the 0.01 pole
    assert r.y[-1, 0, 0] > r.y[len(r.t) // 2, 0, 0]  # still rising: the integrator shows

    def build(t):
        return sysid.TransferFunction([[[0.01]]], [[np.convolve([1.0, t[0]], [1.0, 0.01])]])
    g.uncertainty = ParameterUncertainty([5e-12], [[1e-8]], build)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rs = g.step(std=True)
    assert np.all(np.isfinite(rs.std)) and rs.std[-1, 0, 0] > 0


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 10_000))
def test_std_invariant_under_similarity_and_reparameterisation(seed):
    """The state basis of build() and a linear change of parameters theta = M phi change
    neither the pole nor the frequency-response std."""
    m = _model_with_uncertainty(seed=seed % 7)
    unc = m.uncertainty
    rng = np.random.default_rng(seed)
    T = np.eye(4) + 0.3 * rng.standard_normal((4, 4))
    Ti = np.linalg.inv(T)
    M = np.eye(unc.theta.size) + 0.2 * rng.standard_normal((unc.theta.size,) * 2)
    Mi = np.linalg.inv(M)

    def build2(phi):
        mm = unc.build(M @ phi)
        return sysid.StateSpaceModel(T @ mm.A @ Ti, T @ mm.B, mm.C @ Ti, mm.D, dt=mm.dt)
    m2 = build2(Mi @ unc.theta)
    m2.uncertainty = ParameterUncertainty(Mi @ unc.theta, Mi @ unc.covariance @ Mi.T, build2)
    p1, s1 = m.poles(std=True)
    p2, s2 = m2.poles(std=True)
    o = [int(np.argmin(np.abs(p2 - z))) for z in p1]
    np.testing.assert_allclose(s2[o].real, s1.real, rtol=1e-4)
    np.testing.assert_allclose(s2[o].imag, s1.imag, rtol=1e-4, atol=1e-10)
    w = [0.2, 5.0, 20.0]
    np.testing.assert_allclose(m2.freqresp(w, std=True)[1], m.freqresp(w, std=True)[1],
                               rtol=1e-4)


# -- plots and the report ----------------------------------------------------------------
def test_bode_and_step_bands():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from sysid.plot.model import plot_bode

    m = _model_with_uncertainty()
    fig = plot_bode(m, np.linspace(0.1, 30, 50), confidence=0.95)
    assert sum(len(ax.collections) for ax in fig.axes) == 8  # magnitude and phase, 2 x 2
    plt.close(fig)
    fig = plot_bode(m, np.linspace(0.1, 30, 50))
    assert sum(len(ax.collections) for ax in fig.axes) == 0
    plt.close(fig)
    resp = sysid.step(m, 30, std=True)
    assert resp.std.shape == resp.y.shape and resp.std[0].max() == 0 and resp.std[5].min() > 0
    fig = resp.plot()
    assert sum(len(ax.collections) for ax in fig.axes) == 4
    plt.close(fig)


# -- Monte Carlo calibration -------------------------------------------------------------
_REF = np.array([0.8 + 0.3j, 0.5, -0.4])
_W = np.array([0.1, 0.4, 0.9, 1.6, 2.5])


def _pole_parts(p, sd):
    """Real and |imag| parts of the poles nearest the reference, with their std."""
    v, s = [], []
    for r in _REF:
        i = int(np.argmin(np.abs(p - r)))
        if r.imag > 0:
            v += [p[i].real, abs(p[i].imag)]
            s += [sd[i].real, sd[i].imag]
        else:
            v += [p[i].real]
            s += [sd[i].real]
    return v, s


def _check(values, stds, covered, label=""):
    sample = np.std(values, axis=0, ddof=1)
    predicted = np.sqrt(np.mean(np.square(stds), axis=0))
    ratio = predicted / sample
    assert np.all(np.abs(ratio - 1) < 0.25), (label, ratio)
    coverage = np.mean(covered, axis=0)
    print(label, "std ratio", np.round(ratio, 3), "coverage", coverage)  # shown with pytest -s
    assert np.all((coverage >= 0.90) & (coverage <= 0.98)), (label, coverage)
    return ratio, coverage


def test_monte_carlo_pem_and_subspace_bootstrap():
    """200 records of a 2-input 2-output order-4 system with process and measurement noise:
    the std of each pole (real and imaginary parts) within 25 % of the sample std, and the
    95 % intervals of the frequency response (Re H11, Im H22 at 5 frequencies) cover the truth
    in 90-98 % of runs, for PEM (Gauss-Newton covariance) and the subspace bootstrap."""
    true = _truth()
    G0 = true.freqresp(_W)
    out: dict[str, tuple[list, list, list]] = {"pem": ([], [], []), "bootstrap": ([], [], [])}
    for seed in range(200):
        rng = np.random.default_rng(2000 + seed)
        u = rng.standard_normal((600, 2))
        data = sysid.IOData(u=u, y=_simulate(true, u, 0.2 * rng.standard_normal((600, 2))))
        boot = sysid.SubspaceEstimator(data, horizon=6).fit(
            4, feedthrough=False, uncertainty="bootstrap", n_boot=30, rng=seed)
        pem = sysid.pem(data, true, tol=1e-8)
        for key, m in (("pem", pem), ("bootstrap", boot)):
            v, s = _pole_parts(*m.poles(std=True))
            H, sd = m.freqresp(_W, std=True)
            out[key][0].append(v)
            out[key][1].append(s)
            out[key][2].append(np.r_[
                np.abs(H[:, 0, 0].real - G0[:, 0, 0].real) <= 1.96 * sd[:, 0, 0].real,
                np.abs(H[:, 1, 1].imag - G0[:, 1, 1].imag) <= 1.96 * sd[:, 1, 1].imag])
    for key, (v, s, c) in out.items():
        _check(v, s, c, key)


def test_monte_carlo_armax_and_oe_coefficients():
    """ARMAX(1,1,1) and OE(1,1): the coefficient std (``m.std``) within 25 % of the sample
    std over 200 records, and 95 % intervals covering the truth in 90-98 % of runs."""
    truth = {"armax": [-0.7, 0.8, 0.5], "oe": [0.8, -0.7]}
    out: dict[str, tuple[list, list, list]] = {k: ([], [], []) for k in truth}
    for run in range(200):
        rng = np.random.default_rng(7000 + run)
        u = rng.standard_normal(400)
        e = 0.3 * rng.standard_normal(400)
        y = signal.lfilter([0.0, 0.8], [1.0, -0.7], u) + signal.lfilter([1.0, 0.5], [1.0, -0.7], e)
        d = sysid.IOData(u[:, None], y[:, None], 1.0)
        ma = sysid.armax(d, 1, 1, 1, 1)
        sa = ma.std
        yo = signal.lfilter([0.0, 0.8], [1.0, -0.7], u) + e
        mo = sysid.oe(sysid.IOData(u[:, None], yo[:, None], 1.0), 1, 1, 1)
        so = mo.std
        for key, v, s in (
            ("armax", [ma.a[0][0][0], ma.b[0][0][0], ma.c[0][0]],
             [sa["a"][0][0][0], sa["b"][0][0][0], sa["c"][0][0]]),
            ("oe", [mo.b[0][0][0], mo.f[0][0][0]], [so["b"][0][0][0], so["f"][0][0][0]]),
        ):
            out[key][0].append(v)
            out[key][1].append(s)
            out[key][2].append(np.abs(np.subtract(v, truth[key])) <= 1.96 * np.asarray(s))
    for key, (v, s, c) in out.items():
        _check(v, s, c, key)


def test_monte_carlo_iv4():
    """IV4 with coloured equation noise, open loop and closed loop (reference as instrument):
    its asymptotic covariance is calibrated."""
    est, sds = [], []
    for run in range(200):
        rng = np.random.default_rng(9000 + run)
        u = rng.standard_normal(600)
        v = signal.lfilter([1.0], [1.0, -0.9], rng.standard_normal(600))
        y = signal.lfilter([0.0, 1.0], [1.0, -0.5], u) + 0.3 * v
        m = sysid.iv4(sysid.IOData(u[:, None], y[:, None], 1.0), 1, 1, 1)
        est.append([m.a[0][0][0], m.b[0][0][0]])
        sds.append([m.std["a"][0][0][0], m.std["b"][0][0][0]])
    covered = np.abs(np.subtract(est, [-0.5, 1.0])) <= 1.96 * np.asarray(sds)
    _check(est, sds, covered, "iv4")
    # closed loop u = r - 0.3 y, the reference as instrument
    est, sds = [], []
    for run in range(200):
        rng = np.random.default_rng(11000 + run)
        r = rng.standard_normal(800)
        v = 0.3 * signal.lfilter([1.0], [1.0, -0.9], rng.standard_normal(800))
        x, u, y = np.zeros(800), np.zeros(800), np.zeros(800)
        for k in range(800):
            x[k] = 0.5 * x[k - 1] + u[k - 1] if k else 0.0
            y[k] = x[k] + v[k]
            u[k] = r[k] - 0.3 * y[k]
        m = sysid.iv4(sysid.IOData(u[:, None], y[:, None], 1.0), 1, 1, 1, reference=r)
        est.append([m.a[0][0][0], m.b[0][0][0]])
        sds.append([m.std["a"][0][0][0], m.std["b"][0][0][0]])
    covered = np.abs(np.subtract(est, [-0.5, 1.0])) <= 1.96 * np.asarray(sds)
    _check(est, sds, covered, "iv4 closed loop")


# -- polynomial models through the same code ---------------------------------------------
def test_polynomial_poles_and_freqresp_std():
    rng = np.random.default_rng(4)
    u = rng.standard_normal(500)
    y = signal.lfilter([0.0, 0.8], [1.0, -0.7], u) + 0.3 * rng.standard_normal(500)
    m = sysid.oe(sysid.IOData(u[:, None], y[:, None], 1.0), 1, 1, 1)
    p, sd = m.poles(std=True)
    # the pole of OE(1,1) is -f1: its std is that of f1
    np.testing.assert_allclose(sd.real, m.std["f"][0][0], rtol=1e-6)
    H, Hsd = m.freqresp([0.0], std=True)
    g = m.uncertainty.propagate(lambda mm: mm.freqresp([0.0])[:, 0, 0].real)
    np.testing.assert_allclose(Hsd[0, 0, 0].real, g.std[0], rtol=1e-6)
    arx = sysid.arx(sysid.IOData(u[:, None], y[:, None], 1.0), 2, 2, 1)
    np.testing.assert_allclose(np.r_[arx.std["a"][0][0], arx.std["b"][0][0]],
                               np.sqrt(np.diag(arx.covariance[0])), rtol=1e-6)
    assert arx.uncertainty.method == "least-squares"


# -- the bootstrap option ----------------------------------------------------------------
def test_bootstrap_option_changes_the_result_and_checks_input():
    true = _truth()
    rng = np.random.default_rng(11)
    u = rng.standard_normal((500, 2))
    data = sysid.IOData(u=u, y=_simulate(true, u, 0.2 * rng.standard_normal((500, 2))))
    est = sysid.SubspaceEstimator(data, horizon=6)
    plain = est.fit(4, feedthrough=False)
    assert plain.uncertainty is None and plain.std is None
    a = est.fit(4, feedthrough=False, uncertainty="bootstrap", n_boot=40, rng=1)
    b = est.fit(4, feedthrough=False, uncertainty="bootstrap", n_boot=40, rng=1)
    c = est.fit(4, feedthrough=False, uncertainty="bootstrap", n_boot=80, rng=1)
    assert a.uncertainty.method == "bootstrap" and a.info["uncertainty"]["n_boot"] == 40
    np.testing.assert_array_equal(a.covariance, b.covariance)  # seeded: reproducible
    other = est.fit(4, feedthrough=False, uncertainty="bootstrap", n_boot=40, rng=2)
    assert not np.allclose(a.covariance, other.covariance)
    assert not np.allclose(a.covariance, c.covariance)
    np.testing.assert_array_equal(a.A, plain.A)  # the estimate itself is unchanged
    with pytest.raises(DataError, match="kalman"):
        est.fit(4, kalman=False, uncertainty="bootstrap")
    with pytest.raises(DataError, match="bootstrap"):
        est.fit(4, uncertainty="asymptotic")
    with pytest.raises(DataError, match="n_boot"):
        est.fit(4, uncertainty="bootstrap", n_boot=3)


def test_modal_table_std_and_html_report_pole_table(tmp_path):
    from sysid.cli import main

    m = _model_with_uncertainty(scale=1e-6)
    modes = sysid.modal_analysis(m, std=True)
    table = sysid.damp(m, std=True)
    for z, sd_hz, sd_d in zip(modes.eigenvalues, modes.extra["sd_hz"], modes.extra["sd_damping"]):
        k = int(np.argmin(np.abs(table.poles - z)))
        np.testing.assert_allclose([sd_hz, sd_d], [table.wn_hz_std[k], table.zeta_std[k]])
    assert "SD_HZ" in modes.table() and "sd_hz" not in sysid.modal_analysis(m).extra
    # the report: a pole table, with std columns when asked for the bootstrap
    d = np.loadtxt(sysid.datasets.path("dryer"))
    path = tmp_path / "dryer.csv"
    np.savetxt(path, d, delimiter=",", header="heater,temperature", comments="")
    rep = tmp_path / "rep"
    assert main(["identify", str(path), "--inputs", "heater", "--outputs", "temperature",
                 "--order", "4", "--horizon", "15", "--detrend", "mean", "--quiet",
                 "--uncertainty", "bootstrap", "--n-boot", "30", "--report", str(rep)]) == 0
    html = (rep / "index.html").read_text()
    assert 'id="poles"' in html and "std damping" in html
    assert sysid.load_model(rep / "model.json").info["uncertainty"]["n_boot"] == 30
    from sysid.analysis.report import _pole_section
    from sysid.analysis.report_page import Page

    plain = _pole_section(Page("t"), sysid.StateSpaceModel(m.A, m.B, m.C, dt=0.1), [])
    assert "pole" in plain and "std damping" not in plain


def test_bootstrap_uses_every_experiment():
    true = sysid.StateSpaceModel([[0.8, 0.2], [-0.2, 0.8]], [[1.0], [0.5]], [[1.0, 0.0]],
                                 K=[[0.5], [0.1]])
    rng = np.random.default_rng(0)
    us = [rng.standard_normal((400, 1)) for _ in range(3)]
    ys = [_simulate(true, u, 0.1 * rng.standard_normal((400, 1))) for u in us]
    one = sysid.SubspaceEstimator(sysid.IOData(u=us[0], y=ys[0]), horizon=5).fit(
        2, uncertainty="bootstrap", n_boot=60, rng=0)
    three = sysid.SubspaceEstimator(sysid.IOData(u=us, y=ys), horizon=5).fit(
        2, uncertainty="bootstrap", n_boot=60, rng=0)
    s1, s3 = np.abs(one.poles(std=True)[1]), np.abs(three.poles(std=True)[1])
    # three times the data: about 1/sqrt(3) of the spread
    assert np.all(s3 < 0.8 * s1) and np.all(s3 > 0.35 * s1), (s1, s3)


def test_frequency_response_std_of_a_continuous_model_is_taken_at_s_equal_j_omega():
    # the analytic Jacobian evaluated every continuous model at z = exp(j w 0) = 1: the std of
    # G(s) = 1 / (s - a) was 1/4 of the truth at DC and constant over frequency
    from sysid.models.uncertainty import ParameterUncertainty, freqresp_std

    def build(t):
        return sysid.ContinuousStateSpace([[t[0]]], [[1.0]], [[1.0]])

    m = build([-1.0])
    m.uncertainty = ParameterUncertainty([-1.0], [[1e-4]], build)
    w = np.array([0.0, 1.0, 10.0])
    H, sd = freqresp_std(m, w)
    d = 0.01 / (1j * w + 1) ** 2  # dG/da times the std of a
    np.testing.assert_allclose(H.ravel(), 1 / (1j * w + 1), atol=1e-12)
    np.testing.assert_allclose(sd.ravel().real, np.abs(d.real), rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(sd.ravel().imag, np.abs(d.imag), rtol=1e-6, atol=1e-12)


def test_continuous_models_carry_uncertainty_through_d2c_and_damp():
    # d2c dropped the uncertainty (and ContinuousStateSpace had no poles(std=True)); damp
    # refused std for continuous models although their poles(std=True) worked
    rng = np.random.default_rng(12)
    true = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0], [0.0]], [[1.0, 0.5]],
                                 dt=0.1)
    u = rng.standard_normal((800, 1))
    d = sysid.IOData(u, true.simulate(u) + 0.05 * rng.standard_normal((800, 1)), dt=0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = sysid.ssest(d, 2, focus="simulation")
    c = sysid.d2c(m)
    z, zsd = m.poles(std=True)
    s, ssd = c.poles(std=True)
    # s = log(z) / dt: first order, |ds| = |dz| / (|z| dt) for each pole
    order = [int(np.argmin(np.abs(np.exp(si * 0.1) - z))) for si in s]
    np.testing.assert_allclose(np.abs(ssd), np.abs(zsd[order]) / (np.abs(z[order]) * 0.1),
                               rtol=0.02)
    table = sysid.damp(c, std=True)
    assert np.all(np.isfinite(table.wn_std)) and np.all(np.isfinite(table.zeta_std))
    H, sd = c.freqresp([0.5, 2.0], std=True)
    assert sd.shape == H.shape and np.all(np.abs(sd) > 0)
    # and back: c2d dropped it (d2c carried it), so a round trip lost the uncertainty
    back = sysid.c2d(c, 0.1)
    np.testing.assert_allclose(back.poles(std=True)[1][np.argsort(back.poles().imag)],
                               zsd[np.argsort(z.imag)], rtol=1e-5)


def test_a_real_poles_damping_std_is_zero_not_round_off():
    # a distinct real pole keeps damping 1 under small changes: its std printed 1.97e-17
    def build(t):
        return sysid.StateSpaceModel([[t[0], 0.0], [0.0, t[1]]], [[1.0], [1.0]], [[1.0, 1.0]],
                                     dt=0.1)
    m = build([0.9, 0.5])
    m.uncertainty = ParameterUncertainty([0.9, 0.5], 1e-4 * np.eye(2), build)
    t = sysid.damp(m, std=True)
    assert np.all(t.zeta_std == 0.0) and np.all(t.wn_hz_std > 0)


def test_dcgain_and_step_with_std_for_polynomial_and_transfer_function_models():
    # PolynomialModel had no dcgain; step(std=True) and TransferFunction.dcgain(std=True)
    # raised TypeError. The static gain's std is the settled step response's and the
    # frequency response's at 0.
    rng = np.random.default_rng(71)
    u = rng.standard_normal(800)
    y = np.zeros(800)
    for t in range(1, 800):
        y[t] = 0.7 * y[t - 1] + 0.5 * u[t - 1]
    d = sysid.IOData(u, y + 0.05 * rng.standard_normal(800), 1.0)
    for m in (sysid.oe(d, 1, 1, 1), sysid.armax(d, 1, 1, 1, 1),
              sysid.tfest(d, 1, progress=False)):
        g, gs = m.dcgain(std=True)
        assert g[0, 0] == pytest.approx(5 / 3, rel=0.05) and 0 < gs[0, 0] < 0.1
        kw = {} if m.dt > 0 else {"dt": 1.0}
        r = m.step(200, std=True, **kw)
        assert r.std[-1, 0, 0] == pytest.approx(gs[0, 0], rel=1e-3)
        _, hs = m.freqresp(np.array([0.0]), std=True)
        assert abs(hs[0, 0, 0]) == pytest.approx(gs[0, 0], rel=1e-3)


def test_the_bootstrap_of_an_unstable_estimate_resamples_like_the_data():
    """The ball-and-beam record's order-4 subspace estimate is unstable (poles 1.023 and
    0.90 +- 0.37j, modulus 0.98-1.03 with the data's noise). Its residual bootstrap
    simulated records through it that grew 1e6 times beyond the data, and their refits gave
    pole standard deviations of 1e-10 and 6e-9. The records are now the measured record's
    one-step predictions plus resampled innovations (fixed design), and the method says so;
    the standard deviations are of the order of the poles' spread between the record's
    halves (0.02-0.03 for the pair)."""
    d = sysid.detrend(sysid.datasets.load_ballbeam(), "mean")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the estimate's own StabilityWarning
        m = sysid.SubspaceEstimator(d).fit(4, uncertainty="bootstrap", n_boot=40, rng=0)
    assert m.uncertainty.method.startswith("bootstrap (fixed design")
    p, sd = m.poles(std=True)
    pair = np.abs(p.imag) > 0.1
    assert np.max(np.abs(p)) > 1.0
    assert np.all(np.abs(sd[pair]) > 5e-3)  # was 1.3e-10


def test_impulse_with_std_matches_the_delta_method_for_every_model_kind():
    """``impulse(std=True)`` raised TypeError where ``step(std=True)`` worked (MATLAB's
    ``impulse`` shows a confidence region as ``step`` does). For ``h_k = b a^(k-1)`` the
    first-order std is ``sqrt(J P J')`` with ``J = [b (k-1) a^(k-2), a^(k-1)]``; the
    state-space, polynomial, transfer-function and identified models give it, and
    ``sysid.impulse`` too."""
    from sysid.identify.result import IdentifiedModel

    a, b, P = 0.8, 0.5, np.array([[4e-4, 1e-4], [1e-4, 9e-4]])

    def build(t):
        return sysid.StateSpaceModel([[t[0]]], [[t[1]]], [[1.0]], dt=1.0)
    m = build([a, b])
    m.uncertainty = ParameterUncertainty([a, b], P, build)
    k = np.arange(1, 30)
    J = np.column_stack([b * (k - 1) * a ** np.maximum(k - 2, 0), a ** (k - 1)])
    want = np.sqrt(np.einsum("ij,jk,ik->i", J, P, J))
    for model in (m, IdentifiedModel(m, [0.0], [3.0])):
        for r in (model.impulse(30, std=True), sysid.impulse(model, 30, std=True)):
            np.testing.assert_allclose(r.y[1:, 0, 0], b * a ** (k - 1), rtol=1e-12)
            np.testing.assert_allclose(r.std[1:, 0, 0], want, rtol=1e-5)
            assert r.std[0, 0, 0] == 0.0
    # the estimators' models: the impulse std follows the step std's differences
    rng = np.random.default_rng(72)
    u = rng.standard_normal(800)
    y = np.zeros(800)
    for t in range(1, 800):
        y[t] = 0.7 * y[t - 1] + 0.5 * u[t - 1]
    d = sysid.IOData(u, y + 0.05 * rng.standard_normal(800), 1.0)
    for est in (sysid.oe(d, 1, 1, 1), sysid.tfest(d, 1, progress=False)):
        kw = {} if est.dt > 0 else {"dt": 1.0}
        r = est.impulse(50, std=True, **kw)
        assert r.std.shape == r.y.shape and np.all(np.isfinite(r.std))
        assert 0 < np.max(r.std) < 0.05
