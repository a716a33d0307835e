"""Continuous-time models are first-class (issue 9 item 2): exact ZOH/FOH simulation of
sampled data, c2d/d2c round trips, step/impulse, compare/residuals at the data's rate."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal
from hypothesis import given, settings
from hypothesis import strategies as st

import sysid

SETTINGS = settings(max_examples=30, deadline=None)


def _system(seed: int, n: int, m: int, l: int, dt: float) -> sysid.ContinuousStateSpace:
    """A random stable system whose poles satisfy |s| dt < 2 (principal logarithm exists)."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    ev = np.linalg.eigvals(A)
    A = A - (np.max(ev.real) + 0.2 + rng.random()) * np.eye(n)
    A *= min(1.0, 1.5 / (dt * np.max(np.abs(np.linalg.eigvals(A)))))
    return sysid.ContinuousStateSpace(A, rng.standard_normal((n, m)), rng.standard_normal((l, n)),
                                      rng.standard_normal((l, m)))


systems = st.builds(
    lambda seed, n, m, l, dt: (_system(seed, n, m, l, dt), dt),
    st.integers(0, 2**31), st.integers(1, 4), st.integers(1, 2), st.integers(1, 2),
    st.floats(0.01, 0.5),
)


def _close(a, b, tol=1e-10):
    scale = max(1.0, float(np.max(np.abs(b))) if np.size(b) else 1.0)
    np.testing.assert_allclose(a, b, rtol=0, atol=tol * scale)


@SETTINGS
@given(systems, st.sampled_from(["zoh", "foh", "tustin"]))
def test_c2d_then_d2c_returns_the_system(case, method):
    sys, dt = case
    back = sysid.d2c(sysid.c2d(sys, dt, method), method)
    for k in "ABCD":
        _close(getattr(back, k), getattr(sys, k))


@SETTINGS
@given(systems, st.sampled_from(["zoh", "foh", "tustin"]))
def test_d2c_then_c2d_returns_the_discrete_model(case, method):
    sys, dt = case
    d = sysid.c2d(sys, dt, method)
    again = sysid.c2d(sysid.d2c(d, method), dt, method)
    for k in "ABCD":
        _close(getattr(again, k), getattr(d, k))


@SETTINGS
@given(systems, st.sampled_from(["zoh", "foh", "bilinear"]))
def test_c2d_matches_scipy_cont2discrete(case, method):
    sys, dt = case
    ref = scipy.signal.cont2discrete((sys.A, sys.B, sys.C, sys.D), dt, method=method)
    d = sysid.c2d(sys, dt, method)
    for got, want in zip((d.A, d.B, d.C, d.D), ref[:4]):
        _close(got, want, 1e-11)


def test_zoh_simulation_matches_lsim():
    sys = _system(1, 3, 2, 2, 0.05)
    rng = np.random.default_rng(0)
    u = rng.standard_normal((200, 2))
    t = 0.05 * np.arange(200)
    x0 = rng.standard_normal(3)
    # lsim without interpolation holds the input: a zero-order hold
    _, y_ref, _ = scipy.signal.lsim((sys.A, sys.B, sys.C, sys.D), u, t, X0=x0, interp=False)
    _close(sys.simulate(u, t, method="zoh", x0=x0), y_ref, 1e-9)
    # with interpolation lsim is a first-order hold; the state at t = 0 is x0 in both
    _, y_lin, _ = scipy.signal.lsim((sys.A, sys.B, sys.C, sys.D), u, t, X0=x0, interp=True)
    _close(sys.simulate(u, dt=0.05, method="foh", x0=x0), y_lin, 1e-9)
    assert np.max(np.abs(y_lin - y_ref)) > 1e-2  # the hold option changes the result
    # from rest with u(0) != 0 (the FOH state shift xi(0) = -G2 u(0) matters here)
    for method, interp in (("zoh", False), ("foh", True)):
        _, ref, _ = scipy.signal.lsim((sys.A, sys.B, sys.C, sys.D), u, t, interp=interp)
        _close(sys.simulate(u, t, method=method), ref, 1e-9)


def test_foh_simulation_of_a_ramp_is_exact():
    """dx/dt = -a x + b u, y = x, u(t) = t from rest: x(t) = (b/a)(t - 1/a + e^{-a t}/a)."""
    a, b, dt = 2.0, 3.0, 0.25
    sys = sysid.ContinuousStateSpace([[-a]], [[b]], [[1.0]])
    t = dt * np.arange(80)
    exact = (b / a) * (t - 1 / a + np.exp(-a * t) / a)
    y = sys.simulate(t, t, method="foh")[:, 0]
    np.testing.assert_allclose(y, exact, rtol=0, atol=1e-12 * np.max(exact))
    zoh = sys.simulate(t, t, method="zoh")[:, 0]
    assert np.max(np.abs(zoh - exact)) > 0.1  # a held ramp lags by half a sample


def test_step_and_impulse_are_the_analytic_responses():
    wn, zeta = 3.0, 0.2
    sys = sysid.ContinuousStateSpace([[0.0, 1.0], [-wn**2, -2 * zeta * wn]], [[0.0], [wn**2]],
                                     [[1.0, 0.0]])
    r = sysid.step(sys)
    wd = wn * np.sqrt(1 - zeta**2)
    phi = np.arccos(zeta)
    exact = 1 - np.exp(-zeta * wn * r.t) * np.sin(wd * r.t + phi) / np.sqrt(1 - zeta**2)
    np.testing.assert_allclose(r.y[:, 0, 0], exact, atol=1e-12)
    assert r.t[-1] == pytest.approx(5 / (zeta * wn))  # five time constants by default
    imp = sys.impulse(50, dt=0.1)
    exact_h = wn / np.sqrt(1 - zeta**2) * np.exp(-zeta * wn * imp.t) * np.sin(wd * imp.t)
    np.testing.assert_allclose(imp.y[:, 0, 0], exact_h, atol=1e-12)
    assert sys.step(7, dt=0.5).t[-1] == pytest.approx(3.0)


def test_sampled_data_with_either_hold_are_fitted_exactly():
    sys = _system(4, 2, 1, 1, 0.1)
    rng = np.random.default_rng(2)
    u = rng.standard_normal((300, 1))
    for hold in ("zoh", "foh"):
        data = sysid.IOData(u, sys.simulate(u, dt=0.1, method=hold), 0.1)
        model = sysid.ContinuousStateSpace(sys.A, sys.B, sys.C, sys.D, hold=hold)
        np.testing.assert_allclose(sysid.compare(model, data).fit, 100.0, atol=1e-7)
        other = "foh" if hold == "zoh" else "zoh"
        wrong = sysid.ContinuousStateSpace(sys.A, sys.B, sys.C, sys.D, hold=other)
        assert sysid.compare(wrong, data).fit[0, 0] < 99.9
        noisy = sysid.IOData(u, data.experiments[0][1] + 0.01 * rng.standard_normal((300, 1)),
                             0.1)
        res = sysid.residuals(model, noisy, max_lag=10)
        assert res.is_white and res.n_samples == 300


def test_sample_time_arguments_are_checked():
    sys = _system(0, 1, 1, 1, 0.1)
    u = np.ones((5, 1))
    t = 0.1 * np.arange(5)
    np.testing.assert_array_equal(sys.simulate(u, t), sys.simulate(u, dt=0.1))
    with pytest.raises(sysid.DataError, match="sample time"):
        sys.simulate(u)
    with pytest.raises(sysid.DataError, match="not both"):
        sys.simulate(u, t, dt=0.1)
    with pytest.raises(sysid.DataError, match="uniformly"):
        sys.simulate(u, t**2)
    with pytest.raises(sysid.DataError, match="method"):
        sys.simulate(u, dt=0.1, method="cubic")
    with pytest.raises(sysid.DataError, match="hold"):
        sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]], hold="tustin")
    with pytest.raises(sysid.NumericalError, match="negative real axis"):
        sysid.d2c(sysid.StateSpaceModel([[-0.5]], [[1.0]], [[1.0]]), "foh")
    with pytest.raises(sysid.NumericalError, match="pole at z = 0"):
        sysid.d2c(sysid.StateSpaceModel([[0.0]], [[1.0]], [[1.0]]))


def test_public_names_and_protocol():
    from sysid.models.continuous import ContinuousStateSpace, c2d, d2c

    assert sysid.ContinuousStateSpace is ContinuousStateSpace
    assert sysid.c2d is c2d and sysid.d2c is d2c
    sys = _system(0, 2, 1, 1, 0.1)
    assert isinstance(sys, sysid.Model) and sys.dt == 0.0
    assert sys.n_parameters == 2 * (1 + 1) + 1  # n (l + m) + l m (D is non-zero)
    np.testing.assert_allclose(sysid.damp(sys).s, np.sort_complex(sys.poles()), atol=1e-12)


def test_compare_uses_the_continuous_state_and_rest():
    """At the data's rate the initial state is the continuous one: from-rest FOH data are
    fitted exactly with x0="zero" (u(0) != 0), and x0="estimate" recovers a true x(0)."""
    sys = sysid.ContinuousStateSpace([[-0.5, 2.0], [-2.0, -0.5]], [[1.0], [0.3]],
                                     [[1.0, 0.0]], hold="foh")
    rng = np.random.default_rng(6)
    u = 1.0 + rng.standard_normal((250, 1))
    rest = sysid.IOData(u, sys.simulate(u, dt=0.1), 0.1)
    np.testing.assert_allclose(sysid.compare(sys, rest, x0="zero").fit, 100.0, atol=1e-8)
    x_true = np.array([1.5, -0.7])
    moved = sysid.IOData(u, sys.simulate(u, dt=0.1, x0=x_true), 0.1)
    r = sysid.compare(sys, moved)
    np.testing.assert_allclose(r.x0[0], x_true, atol=1e-9)
    np.testing.assert_allclose(r.fit, 100.0, atol=1e-8)
    assert sysid.compare(sys, moved, x0="zero").fit[0, 0] < 99
    assert "SampledContinuous" in r.summary() and r.dt == 0.1


@pytest.mark.parametrize("method", ["zoh", "foh", "tustin"])
def test_d2c_of_a_transfer_function_with_delays_keeps_them_as_seconds(method):
    # d2c of a discrete transfer function with a delay realised the delay as poles at z = 0
    # and raised "a pole at z = 0 at zero ... use method='tustin'" (which turns each delay
    # sample into a pole at -2/dt); as MATLAB's d2c the delay is kept: k samples, k dt s
    G = sysid.TransferFunction([[[0.2, 0.1], [0.5]], [[0.3], [1.0, -0.5]]],
                               [[[1.0, -1.2, 0.5], [1.0, -0.8]], [[1.0, -0.6], [1.0, -0.1]]],
                               dt=0.1, iodelay=[[2, 0], [1, 3]])
    c = sysid.d2c(G, method)
    assert isinstance(c, sysid.TransferFunction) and c.dt == 0.0
    np.testing.assert_allclose(c.iodelay, [[0.2, 0.0], [0.1, 0.3]])
    back = c.to_statespace(0.1) if method != "tustin" else None
    w = np.linspace(0.1, 30.0, 25)
    if back is not None:  # sampled again with the same hold: the discrete model itself
        np.testing.assert_allclose(back.freqresp(w), G.freqresp(w), atol=1e-10)
    for i, j in G.pairs():  # each pair's delay-free part as d2c of it alone
        part = sysid.TransferFunction(G.num[i][j], G.den[i][j], dt=0.1)
        ref = sysid.d2c(part, method).freqresp(w)[:, 0, 0] * np.exp(-1j * w * c.iodelay[i, j])
        np.testing.assert_allclose(c.freqresp(w)[:, i, j], ref, rtol=1e-9, atol=1e-12)
    # a pole at z = 0 that is not a declared delay says what it is and the way out
    with pytest.raises(sysid.NumericalError, match="iodelay"):
        sysid.d2c(sysid.StateSpaceModel([[0.0, 0.0], [1.0, 0.9]], [[1.0], [0.0]],
                                        [[0.0, 1.0]], dt=0.1))
