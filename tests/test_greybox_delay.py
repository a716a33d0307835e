"""Grey-box input delays that are not whole multiples of the sample time (ZOH, exact)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

import sysid
from sysid.errors import DataError
from sysid.greybox.delays import split_delays
from sysid.greybox.greybox import Parameters

A0 = np.array([[-0.7, 1.3], [-2.0, -0.4]])
B0 = np.array([[0.0, 1.0, 0.3], [1.0, -0.5, 0.2]])
C0 = np.array([[1.0, 0.0], [0.3, 1.0]])
D0 = np.array([[0.2, 0.0, 0.1], [0.0, -0.4, 0.0]])


def plant(p, dt=None):
    A = A0 * [[p.a, 1.0], [1.0, p.c]]
    return A, B0 * [[1.0], [p.b]], C0, D0


VALS = {"a": 1.1, "b": 0.9, "c": 1.2}


def _fine_simulation(u: np.ndarray, dt: float, delays: np.ndarray, k: int) -> np.ndarray:
    """The continuous delayed system on a grid k times finer, where every delay is a whole
    number of fine steps: the delayed ZOH input is constant over each fine step, so this is
    exact (to round-off) and independent of sysid (scipy's expm, a plain loop)."""
    A, B, C, D = (np.asarray(x, float) for x in plant(Parameters(VALS)))
    n, m = B.shape
    h = dt / k
    E = expm(np.block([[A, B], [np.zeros((m, n + m))]]) * h)
    Phi, Gam = E[:n, :n], E[:n, n:]
    steps = np.round(delays / h).astype(int)
    assert np.allclose(steps * h, delays, atol=1e-15)
    uf = np.repeat(u, k, axis=0)
    ud = np.zeros_like(uf)
    for j, s in enumerate(steps):
        ud[s:, j] = uf[:uf.shape[0] - s, j]
    x = np.zeros(n)
    y = np.zeros((u.shape[0], C.shape[0]))
    for i in range(uf.shape[0]):
        if i % k == 0:
            y[i // k] = C @ x + D @ ud[i]
        x = Phi @ x + Gam @ ud[i]
    return y


@pytest.mark.parametrize("delays", [[0.13, 0.02, 0.1], [0.0, 0.049, 0.151]])
def test_fractional_delay_matches_a_fine_step_simulation(delays):
    dt, k = 0.05, 1000
    delays = np.array(delays)
    u = np.random.default_rng(0).standard_normal((60, 3))
    s = sysid.GreyBox(plant, VALS, input_delay=delays)
    m = s.model(dt=dt)
    y = m.simulate(u)
    ref = _fine_simulation(u, dt, delays, k)
    assert np.max(np.abs(y - ref)) < 1e-12 * np.max(np.abs(ref)), np.max(np.abs(y - ref))
    # the realisation: one shift-register state per whole sample of delay, one more for a
    # fraction (0.13 = 2 dt + 0.03: 3, 0.02: 1, 0.1 = 2 dt: 2)
    lo, r = split_delays(delays, dt)
    assert m.nstates == 2 + int(np.sum(lo + (r > 0)))


def test_fractional_delay_matches_scipy_solve_ivp():
    """The same against SciPy's adaptive Runge-Kutta (DOP853) on the continuous delayed
    system, integrated piecewise between the instants where a delayed input switches."""
    from scipy.integrate import solve_ivp

    dt = 0.05
    delays = np.array([0.13, 0.02, 0.1])
    u = np.random.default_rng(2).standard_normal((30, 3))
    A, B, C, D = (np.asarray(x, float) for x in plant(Parameters(VALS)))

    def u_delayed(t: float) -> np.ndarray:   # ZOH input, delayed, zero before it arrives
        k = np.floor((t - delays) / dt + 1e-9).astype(int)
        return np.where(k >= 0, u[np.clip(k, 0, len(u) - 1), [0, 1, 2]], 0.0)

    switches = np.unique(np.concatenate([np.arange(len(u)) * dt + d for d in delays]))
    x = np.zeros(2)
    y = np.zeros((len(u), 2))
    for k in range(len(u)):
        t0 = k * dt
        y[k] = C @ x + D @ u_delayed(t0)
        cuts = [t0] + [c for c in switches if t0 < c < t0 + dt - 1e-12] + [t0 + dt]
        for a, b in zip(cuts[:-1], cuts[1:]):
            ud = u_delayed(0.5 * (a + b))
            x = solve_ivp(lambda t, z, ud=ud: A @ z + B @ ud, (a, b), x, method="DOP853",
                          rtol=1e-13, atol=1e-15).y[:, -1]
    got = sysid.GreyBox(plant, VALS, input_delay=delays).model(dt=dt).simulate(u)
    np.testing.assert_allclose(got, y, atol=1e-10 * np.max(np.abs(y)))


@pytest.mark.parametrize("delays", [[0.13, 0.02, 0.1], [0.05, 0.049, 0.151]])
def test_fractional_delay_with_first_order_hold(delays):
    """FOH: the delayed input is linear between the instants k dt + tau. On a grid 1000
    times finer those instants are grid points, so SciPy's FOH sampling of the fine step
    (cont2discrete) with the interpolated input is exact. The first input sample is zero, so
    that the FOH state convention (z = x - G u[k], MATLAB's and SciPy's) starts at x = 0."""
    from scipy.signal import cont2discrete

    dt, k = 0.05, 1000
    delays = np.array(delays)
    u = np.random.default_rng(4).standard_normal((40, 3))
    u[0] = 0.0
    A, B, C, D = (np.asarray(x, float) for x in plant(Parameters(VALS)))
    Af, Bf, Cf, Df, _ = cont2discrete((A, B, C, D), dt / k, method="foh")
    tf = np.arange(len(u) * k) * (dt / k)
    grid = np.concatenate([[-dt], np.arange(len(u)) * dt])
    w = np.column_stack([np.interp(tf - d, grid, np.concatenate([[0.0], u[:, j]]), left=0.0)
                         for j, d in enumerate(delays)])
    z = np.zeros(2)
    ref = np.zeros((len(u), 2))
    for i in range(len(tf)):
        if i % k == 0:
            ref[i // k] = Cf @ z + Df @ w[i]
        z = Af @ z + Bf @ w[i]
    s = sysid.GreyBox(plant, VALS, input_delay=delays, hold="foh")
    got = s.model(dt=dt).simulate(u)
    assert np.max(np.abs(got - ref)) < 1e-11 * np.max(np.abs(ref)), np.max(np.abs(got - ref))
    # derivatives of the taps against central differences
    base, ders = s.sampled_taps(None, dt, ["a", "b", "c"])
    for name, d in zip("abc", ders):
        up = s.sampled_taps({**VALS, name: VALS[name] + 1e-5}, dt)[0]
        dn = s.sampled_taps({**VALS, name: VALS[name] - 1e-5}, dt)[0]
        for key in ("A", "B", "D"):
            np.testing.assert_allclose(d[key], (up[key] - dn[key]) / 2e-5, atol=1e-9, rtol=1e-7)


def test_fraction_tends_to_the_whole_sample_shift():
    """tau -> l dt: the model is continuous in tau (the fractional taps merge). Without
    feedthrough only: with D the output at the sampling instant jumps when the delayed
    input's step crosses it (tau slightly above l dt sees the previous input sample)."""
    dt = 0.05

    def strictly_proper(p, dt=None):
        A, B, C, _ = plant(p)
        return A, B, C, np.zeros_like(D0)
    u = np.random.default_rng(1).standard_normal((40, 3))
    y0 = sysid.GreyBox(strictly_proper, VALS, input_delay=[0.1, 0.05, 0.0]
                       ).model(dt=dt).simulate(u)
    for eps in (1e-4, -1e-4, 1e-7, -1e-7):
        y = sysid.GreyBox(strictly_proper, VALS, input_delay=[0.1 + eps, 0.05 + eps, abs(eps)]
                          ).model(dt=dt).simulate(u)
        assert np.max(np.abs(y - y0)) < 20 * abs(eps) * np.max(np.abs(y0))
    # with feedthrough: tau = l dt + 1e-9 s reads D u_{k-l-1} at the sampling instant
    a = sysid.GreyBox(plant, VALS, input_delay=[0.1, 0, 0]).model(dt=dt).simulate(u)
    b = sysid.GreyBox(plant, VALS, input_delay=[0.1 + 1e-7, 0, 0]).model(dt=dt).simulate(u)
    jump = np.zeros_like(a)   # D (u_{k-3} - u_{k-2}), u_{-1} = 0
    jump[2:, 0] = D0[0, 0] * (np.concatenate([[0.0], u[:-3, 0]]) - u[:-2, 0])
    np.testing.assert_allclose(b - a, jump, atol=1e-6)


def test_fractional_delay_derivatives_are_exact():
    dt = 0.05
    s = sysid.GreyBox(plant, VALS, input_delay=[0.13, 0.02, 0.1])
    base, ders = s.sampled_taps(None, dt, ["a", "b", "c"])
    assert base["B"].shape == (2, 5) and base["D"].shape == (2, 5)
    assert s.input_taps(dt) == [(0, 2), (0, 3), (1, 0), (1, 1), (2, 2)]
    for k, d in zip("abc", ders):
        h = 1e-5
        up = s.sampled_taps({**VALS, k: VALS[k] + h}, dt)[0]
        dn = s.sampled_taps({**VALS, k: VALS[k] - h}, dt)[0]
        for key in ("A", "B", "D"):
            fd = (up[key] - dn[key]) / (2 * h)
            np.testing.assert_allclose(d[key], fd, atol=1e-9, rtol=1e-7)


def _motor(p, dt=None):
    return [[-1.0 / p.tau]], [[p.K / p.tau]], [[1.0]], [[0.0]]


def test_estimation_with_a_fixed_fractional_delay():
    dt, delay = 0.05, 0.13
    rng = np.random.default_rng(3)
    u = np.repeat(rng.standard_normal(40), 10)
    y = sysid.GreyBox(_motor, {"K": 2.0, "tau": 0.3}, input_delay=delay).model(dt=dt).simulate(u)
    data = sysid.IOData(u=u, y=y, dt=dt)
    s = sysid.GreyBox(_motor, {"K": 1.0, "tau": sysid.param(1.0, bounds=(0.01, 10))},
                      input_delay=delay)
    fit = sysid.greyest(data, s, x0="zero")
    np.testing.assert_allclose(fit.parameters.value, [2.0, 0.3], atol=1e-9)
    assert fit.model.nstates == 1 + 3
    np.testing.assert_allclose(fit.model.simulate(u), y, atol=1e-9)
    # the nearest whole-sample delays fit clearly worse
    for wrong in (0.1, 0.15):
        w = sysid.greyest(data, sysid.GreyBox(_motor, {"K": 1.0, "tau": 1.0},
                                              input_delay=wrong), x0="zero")
        assert w.info["loss"] > 1e6 * max(fit.info["loss"], 1e-30)
    # the same under first-order hold (inputs interpolated between samples)
    yf = sysid.GreyBox(_motor, {"K": 2.0, "tau": 0.3}, input_delay=delay, hold="foh"
                       ).model(dt=dt).simulate(u)
    sf = sysid.GreyBox(_motor, {"K": 1.0, "tau": sysid.param(1.0, bounds=(0.01, 10))},
                       input_delay=delay, hold="foh")
    ffit = sysid.greyest(sysid.IOData(u=u, y=yf, dt=dt), sf, x0="zero")
    np.testing.assert_allclose(ffit.parameters.value, [2.0, 0.3], atol=1e-9)
    assert np.max(np.abs(yf - y)) > 1e-3          # FOH and ZOH data differ
    # with noise: within the predicted std (x0 estimated, prediction focus)
    yn = y + 0.02 * rng.standard_normal(y.shape)
    noisy = sysid.greyest(sysid.IOData(u=u, y=yn, dt=dt), s)
    z = (noisy.parameters.value - [2.0, 0.3]) / noisy.parameters.std
    assert np.all(np.abs(z) < 4), z


def test_fractional_delay_errors_name_the_fix():
    with pytest.raises(DataError, match="continuous=True"):
        sysid.GreyBox(lambda p: ([[p.a]], [[1.0]], [[1.0]], [[0.0]]), {"a": 0.5},
                      continuous=False, input_delay=0.13).model(dt=0.05)
    # FOH: whole samples, and a fraction (one more state than under ZOH's l + 1: none here)
    m = sysid.GreyBox(_motor, {"K": 1.0, "tau": 1.0}, input_delay=0.1, hold="foh").model(dt=0.05)
    assert m.nstates == 3
    m = sysid.GreyBox(_motor, {"K": 1.0, "tau": 1.0}, input_delay=0.13, hold="foh"
                      ).model(dt=0.05)
    assert m.nstates == 1 + 3
