"""A sweep of the LTI analysis and continuous-time tools (issue 26): each test failed before
its fix (the numbers in the comments are the old answers)."""

from __future__ import annotations

import numpy as np
import pytest

import sysid


@pytest.mark.parametrize(("num", "den", "dt", "gain"), [
    ([1.0, 0.0], [1.0, 1.0, 0.0], 0.0, 1.0),          # s / (s (s + 1)): was inf
    ([1.0, 0.0], [1.0, 0.0], 0.0, 1.0),               # s / s: was inf
    ([-1.0], [1.0, 0.0], 0.0, -np.inf),               # -1 / s: was +inf
    ([1.0, -1.0], [1.0, -1.5, 0.5], 1.0, 2.0),        # (z - 1) / ((z - 1)(z - 0.5)): was inf
    ([2.0], [1.0, -1.0], 1.0, np.inf),
    ([-3.0], [1.0, 0.0, 0.0], 0.0, -np.inf),          # a double integrator
])
def test_transfer_function_dcgain_cancels_and_signs_integrators(num, den, dt, gain):
    G = sysid.TransferFunction(num, den, dt=dt)
    assert G.dcgain()[0, 0] == pytest.approx(gain)


def test_statespace_dcgain_of_a_cancelled_integrator_is_finite():
    # the realisation of s / (s^2 + s) has an unobservable pole at s = 0; its DC gain is 1,
    # and dcgain() raised "the DC gain is infinite"
    cont = sysid.TransferFunction([1.0, 0.0], [1.0, 1.0, 0.0]).to_statespace()
    np.testing.assert_allclose(cont.dcgain(), [[1.0]])
    disc = sysid.TransferFunction([1.0, -1.0], [1.0, -1.5, 0.5], dt=0.1).to_statespace()
    np.testing.assert_allclose(disc.dcgain(), [[2.0]])
    with pytest.raises(sysid.NumericalError, match="at s = 0"):
        sysid.TransferFunction([1.0], [1.0, 0.0]).to_statespace().dcgain()


def test_continuous_dcgain_std_after_d2c():
    # ContinuousStateSpace.dcgain had no std argument (TypeError), though d2c carries the
    # uncertainty over; the gain b / (1 - a) = 2 has the same std as the discrete model's
    def build(t: np.ndarray) -> sysid.StateSpaceModel:
        return sysid.StateSpaceModel([[t[0]]], [[t[1]]], [[1.0]], dt=0.1)

    m = build(np.array([0.5, 1.0]))
    m.uncertainty = sysid.ParameterUncertainty([0.5, 1.0], np.diag([1e-4, 4e-4]), build)
    g, sd = sysid.d2c(m).dcgain(std=True)
    np.testing.assert_allclose(g, [[2.0]])
    theory = np.hypot(1 / 0.5 * 0.02, 1 / 0.5**2 * 0.01)
    np.testing.assert_allclose(sd, [[theory]], rtol=1e-6)
    np.testing.assert_allclose(sd, m.dcgain(std=True)[1], rtol=1e-6)


@pytest.mark.parametrize("method", ["zoh", "foh"])
def test_c2d_overflow_names_the_sample_time(method):
    # was NonFiniteError("A has non-finite entries"), about the user's finite A
    c = sysid.ContinuousStateSpace([[1000.0]], [[1.0]], [[1.0]])
    with pytest.raises(sysid.NumericalError, match="dt = 10 s overflows.*smaller dt"):
        sysid.c2d(c, 10.0, method)
    with pytest.raises(sysid.NumericalError, match="overflows"):
        c.simulate(np.ones(3), dt=10.0)


@pytest.mark.parametrize("n", [0, -3, 2.5])
def test_continuous_responses_check_n_samples(n):
    # -3 raised NumPy's "negative dimensions are not allowed", 0 "u has no samples",
    # 2.5 was truncated to 2 samples
    c = sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]])
    G = sysid.TransferFunction([1.0], [1.0, 1.0], iodelay=0.2)
    for call in (lambda: c.step(n, dt=0.1), lambda: c.impulse(n), lambda: G.step(n, dt=0.1),
                 lambda: sysid.step(c, n)):
        with pytest.raises(sysid.DataError, match="n_samples must be a positive integer"):
            call()


def test_controllability_of_a_transfer_function():
    # was AttributeError: 'TransferFunction' object has no attribute 'A'
    G = sysid.TransferFunction([1.0, 1.0], [1.0, 3.0, 2.0])  # (s + 1) / ((s + 1)(s + 2))
    ss = G.to_statespace()
    np.testing.assert_array_equal(sysid.ctrb(G), sysid.ctrb(ss))
    np.testing.assert_array_equal(sysid.obsv(G), sysid.obsv(ss))
    assert sysid.is_controllable(G) and not sysid.is_observable(G)
    with pytest.raises(sysid.DataError, match="ctrb needs a state-space form"):
        sysid.ctrb([[1.0]])


def test_c2d_and_d2c_take_transfer_functions_and_say_which_way():
    G = sysid.TransferFunction([2.0, 1.0], [1.0, 3.0, 2.0])
    for method in ("zoh", "foh", "tustin"):
        d = sysid.c2d(G, 0.1, method)
        ref = sysid.c2d(G.to_statespace(), 0.1, method)
        np.testing.assert_allclose(d.freqresp([0.3, 3.0]), ref.freqresp([0.3, 3.0]))
    Gd = sysid.TransferFunction([1.0], [1.0, -0.5], dt=0.1)
    np.testing.assert_allclose(sysid.d2c(Gd).A, [[np.log(0.5) / 0.1]])
    with pytest.raises(sysid.DataError, match="delays.*to_statespace\\(dt\\)"):
        sysid.c2d(sysid.TransferFunction([1.0], [1.0, 1.0], iodelay=0.2), 0.1)
    with pytest.raises(sysid.DataError, match="dt = 0.1; use d2c"):
        sysid.c2d(sysid.c2d(G, 0.1), 0.1)
    with pytest.raises(sysid.DataError, match="dt = 0; use c2d"):
        sysid.d2c(G)


@pytest.mark.parametrize("G", [
    sysid.TransferFunction([1.0, 0.0], [1.0, 1.0, 0.0]),             # = 1 / (s + 1)
    sysid.TransferFunction([1.0, 0.0], [1.0, 1.0, 0.0]).to_statespace(),
])
def test_stepinfo_of_a_cancelled_integrator_settles(G):
    # was steady_state inf and every time nan: any pole at s = 0 was taken as an integrator
    info = sysid.stepinfo(G)
    assert info.steady_state == pytest.approx(1.0)
    assert info.rise_time == pytest.approx(np.log(9), rel=1e-3)
    assert info.settling_time == pytest.approx(np.log(50), rel=1e-3)


def test_stepinfo_of_a_cancelled_discrete_integrator_settles():
    # (z - 1) / ((z - 1)(z - 0.5)): the gain at z = 1 was 0 / 0 = nan, and so was every entry
    info = sysid.stepinfo(sysid.TransferFunction([1.0, -1.0], [1.0, -1.5, 0.5], dt=0.1))
    assert info.steady_state == pytest.approx(2.0)
    assert np.isfinite(info.rise_time) and np.isfinite(info.settling_time)
    assert sysid.stepinfo(sysid.TransferFunction([-1.0], [1.0, 0.0])).steady_state == -np.inf
