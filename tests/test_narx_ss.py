"""The state-space form of NARX models (``NARXModel.to_nlss``): stepping the state equations
sample by sample reproduces the NARX free run exactly, from any measured state."""

from __future__ import annotations

import numpy as np
import pytest

import sysid


def _mimo(n=300, seed=1):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, (n, 2))
    y = np.zeros((n, 2))
    for t in range(2, n):
        y[t, 0] = 0.4 * y[t - 1, 0] + 0.7 * u[t - 1, 0] + 0.3 * u[t - 2, 1] * y[t - 1, 1]
        y[t, 1] = -0.3 * y[t - 2, 1] + 0.6 * u[t, 1] - 0.25 * u[t - 1, 0] ** 2
    return u, y


def test_state_steps_equal_the_free_run():
    u, y = _mimo()
    m = sysid.nlarx(sysid.IOData(u, y, 1.0), 2, [2, 3], [1, 0], max_terms=6, criterion="bic")
    np.testing.assert_allclose(m.simulate(u, x0=y[:m.max_lag]), y, atol=1e-10)
    ss = m.to_nlss()
    L = ss.lags
    assert ss.nstates == 4 * L and len(ss.state_names) == ss.nstates
    # step from the measured state at t = L: exactly the NARX free run
    free = m.simulate(u, x0=y[:L])
    x = ss.state(u, y)
    for t in range(L, 60):
        x, yt = ss.step(x, u[t])
        assert np.array_equal(yt, free[t])
    # simulate from a state: the free run's tail, bit for bit
    np.testing.assert_array_equal(ss.simulate(u[L:], x0=ss.state(u, y)), free[L:])
    # from a state in the middle of the record: the true outputs
    np.testing.assert_allclose(ss.simulate(u[100:], x0=ss.state(u, y, 100)), y[100:],
                               atol=1e-10)
    assert "h(x(t), u(t))" in ss.summary()


def test_zero_state_and_custom_regressors():
    rng = np.random.default_rng(2)
    u = rng.uniform(-1, 1, (200, 1))
    y = np.zeros((200, 1))
    for t in range(1, 200):
        y[t] = 0.5 * y[t - 1] + np.sin(2 * u[t - 1])
    reg = sysid.CustomRegressor(lambda v: np.sin(2 * v), ["u0(t-1)"], name="s")
    m = sysid.nlarx(sysid.IOData(u, y, 1.0), 1, 1, max_terms=3, criterion="bic", custom=[reg])
    ss = m.to_nlss()
    np.testing.assert_allclose(ss.simulate(u), y, atol=1e-10)  # zero state: the system's rest
    np.testing.assert_allclose(ss.poles(), m.poles())
    with pytest.raises(sysid.DataError, match="state has"):
        ss.step(np.zeros(5), [0.0])
    with pytest.raises(sysid.DataError, match="t must be"):
        ss.state(u, y, 0)
