"""Audit 46: margin at the ends of the frequency axis and below the poles, stepinfo of a
TimeResponse and of samples from rest, a TrendedModel's step in deviation variables, and
minreal of repeated pole-zero pairs."""

from __future__ import annotations

import numpy as np
import pytest

import sysid


# -- margin -------------------------------------------------------------------------------
def test_margin_negative_dc_gain_is_a_phase_crossover_at_zero():
    # L = -2 / (s + 1): the closed loop s + 1 - 2 k is unstable for k > 0.5 (python-control
    # and MATLAB: GM 0.5 at w = 0); margin reported no phase crossover (GM inf)
    m = sysid.margin(sysid.TransferFunction([-2.0], [1.0, 1.0]))
    assert m.gain_margin == pytest.approx(0.5, rel=1e-12)
    assert m.phase_crossover == 0.0
    assert m.phase_margin == pytest.approx(-60.0, abs=1e-9)
    assert m.gain_crossover == pytest.approx(np.sqrt(3.0), rel=1e-9)
    # a state-space form, and a type-0 loop with a negative DC gain crossing elsewhere too
    ss = sysid.TransferFunction([-2.0], [1.0, 1.0]).to_statespace()
    assert sysid.margin(ss).gain_margin == pytest.approx(0.5, rel=1e-12)
    m3 = sysid.margin(sysid.TransferFunction([-10.0], [1.0, 3.0, 3.0, 1.0]))
    assert m3.gain_margin == pytest.approx(0.1, rel=1e-12)        # 1 + k L(0) = 0 at k 0.1
    assert list(m3.phase_crossovers) == [0.0]


def test_margin_discrete_phase_crossover_at_the_nyquist_frequency():
    # 0.5 / (z - 0.5): the closed-loop pole 0.5 - 0.5 k leaves the unit circle at k = 3,
    # at z = -1 (omega = pi / dt)
    for dt in (1.0, 0.1):
        m = sysid.margin(sysid.TransferFunction([0.5], [1.0, -0.5], dt=dt))
        assert m.gain_margin == pytest.approx(3.0, rel=1e-12)
        assert m.phase_crossover == pytest.approx(np.pi / dt, rel=1e-12)
    # 2 / (z + 0.5): pole -0.5 - 2 k, |pole| = 1 at k = 0.25
    m = sysid.margin(sysid.TransferFunction([2.0], [1.0, 0.5], dt=1.0))
    assert m.gain_margin == pytest.approx(0.25, rel=1e-12)
    # a negative DC gain of a discrete loop: z = 1, omega = 0
    m = sysid.margin(sysid.TransferFunction([-0.5], [1.0, 0.5], dt=1.0))
    assert (m.gain_margin, m.phase_crossover) == (pytest.approx(3.0, rel=1e-12), 0.0)


def test_margin_finds_a_gain_crossover_below_or_above_the_poles():
    # 2e-5 / (s (10 s + 1)): |L| = 1 at 2e-5 rad/s, far below the pole at 0.1 rad/s
    m = sysid.margin(sysid.TransferFunction([2e-5], [10.0, 1.0, 0.0]))
    w = m.gain_crossover
    assert abs(2e-5 / (1j * w * (10j * w + 1))) == pytest.approx(1.0, abs=1e-12)
    assert w == pytest.approx(2e-5, rel=1e-6)
    assert m.phase_margin == pytest.approx(90.0 - np.degrees(np.arctan(10 * w)), abs=1e-9)
    # 1e6 / (s + 1): |L| = 1 near 1e6 rad/s, above the default grid
    m = sysid.margin(sysid.TransferFunction([1e6], [1.0, 1.0]))
    assert m.gain_crossover == pytest.approx(np.sqrt(1e12 - 1), rel=1e-9)
    # an integrator with delay whose |L| is 1 right at the old grid's end (1e-3 rad/s)
    m = sysid.margin(sysid.TransferFunction([1e-3], [1.0, 0.0], iodelay=1.0))
    assert m.gain_crossover == pytest.approx(1e-3, rel=1e-9)
    assert m.phase_margin == pytest.approx(90.0 - np.degrees(1e-3), abs=1e-9)
    # slow discrete integrator: 1e-6 / (z - 1), dt = 0.1
    m = sysid.margin(sysid.TransferFunction([1e-6], [1.0, -1.0], dt=0.1))
    assert m.gain_crossover == pytest.approx(1e-5, rel=1e-6)
    assert m.gain_margin == pytest.approx(2e6, rel=1e-9)           # pole 1 - 1e-6 k = -1


def test_margin_keeps_the_cases_it_had_right():
    m = sysid.margin(sysid.TransferFunction([4.0], [1.0, 3.0, 2.0, 0.0]))
    assert (m.gain_margin, m.phase_crossover) == (pytest.approx(1.5), pytest.approx(np.sqrt(2)))
    assert list(m.phase_crossovers) == [pytest.approx(np.sqrt(2))]
    assert m.gain_crossovers.size == 1
    # no crossover at either end for a positive DC gain, nor a touch of |L| = 1 at z = -1
    for G in (sysid.TransferFunction([0.5], [1.0, 0.5], dt=1.0),
              sysid.TransferFunction([-0.5], [1.0, 0.5], dt=1.0)):
        assert sysid.margin(G).gain_crossovers.size == 0
    # an explicit grid is searched as given
    m = sysid.margin(sysid.TransferFunction([-2.0], [1.0, 1.0]), omega=np.geomspace(0.1, 10))
    assert m.phase_crossovers.size == 0


# -- stepinfo -----------------------------------------------------------------------------
def test_stepinfo_of_a_time_response_starts_from_rest_and_ends_at_the_dc_gain():
    # (s + 3) / (s + 1): y(0+) = 1 (the direct term), y(inf) = 3; from rest the 10-90 %
    # rise is ln(2 / 0.3) = 1.897; stepinfo(step(G)) took y[0] = 1 as the start (2.139)
    G = sysid.TransferFunction([1.0, 3.0], [1.0, 1.0])
    a, b = sysid.stepinfo(G), sysid.stepinfo(sysid.step(G))
    assert b.rise_time == pytest.approx(np.log(2 / 0.3), abs=1e-3)
    assert b.steady_state == pytest.approx(3.0, rel=1e-12)          # not y[-1] = 2.9865
    assert b.peak == pytest.approx(np.max(sysid.step(G).y), rel=1e-12)
    for k in ("rise_time", "settling_time", "overshoot", "undershoot"):
        assert getattr(b, k) == pytest.approx(getattr(a, k), abs=2e-3), k
    # a discrete one: 0.5 + 0.5 / (z - 0.5) ends at 1.5
    D = sysid.TransferFunction([0.5, 0.25], [1.0, -0.5], dt=1.0)
    r = sysid.step(D, 8)
    assert sysid.stepinfo(r).steady_state == pytest.approx(1.5, rel=1e-12)
    assert sysid.stepinfo(r).rise_time == pytest.approx(sysid.stepinfo(D).rise_time)
    # an integrator's step response does not settle: no final value, as for the model
    info = sysid.stepinfo(sysid.step(sysid.TransferFunction([1.0], [1.0, 0.0]), 50))
    assert np.isnan(info.rise_time) and info.steady_state == np.inf


def test_stepinfo_of_samples_defaults_to_yinit_zero():
    # MATLAB's stepinfo(y, t): yinit 0 by default; a record jumping to 1 at t = 0 and rising
    # to 3 (the step of (s + 3) / (s + 1)) rises from 0, not from its first sample
    t = np.linspace(0.0, 30.0, 30001)
    y = 3.0 - 2.0 * np.exp(-t)
    info = sysid.stepinfo(y, t)
    assert info.rise_time == pytest.approx(np.log(2 / 0.3), abs=1e-3)
    assert info.peak == pytest.approx(3.0, abs=1e-9)
    # the explicit yinit is still honoured
    info0 = sysid.stepinfo(y, t, yinit=1.0)
    assert info0.rise_time == pytest.approx(np.log(9), abs=1e-3)


# -- TrendedModel -------------------------------------------------------------------------
def _trended() -> tuple[object, object]:
    inner = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], dt=1.0)
    raw = sysid.IOData(u=20.0 + np.array([1.0, -1.0, 0.5, -0.5]),
                       y=50.0 + np.array([0.0, 1.0, 0.0, 0.5]), dt=1.0)
    _, tr = sysid.detrend(raw, "mean", return_trend=True)
    return tr.attach(inner), inner


def test_trended_model_step_and_impulse_are_the_linear_models():
    # m.step(30) ran the step through the trend (49.8, 30.9, ... toward -45) and stepinfo
    # reported 897 % overshoot; a step response is the linear model's, from rest
    m, inner = _trended()
    for kind in ("step", "impulse"):
        np.testing.assert_allclose(getattr(m, kind)(30).y, getattr(inner, kind)(30).y)
        np.testing.assert_allclose(getattr(sysid, kind)(m, 30).y, getattr(inner, kind)(30).y)
    assert m.step(30).y[0, 0, 0] == 0.0
    a, b = sysid.stepinfo(m), sysid.stepinfo(inner)
    for k in ("rise_time", "settling_time", "overshoot", "peak", "steady_state"):
        assert getattr(a, k) == pytest.approx(getattr(b, k), rel=1e-12), k
    assert a.overshoot == 0.0 and a.steady_state == pytest.approx(5.0)
    # simulate still takes and returns raw data
    assert m.simulate(np.full(3, 20.0))[0, 0] == pytest.approx(m.trend.y_offset[0])


# -- minreal ------------------------------------------------------------------------------
def test_minreal_cancels_repeated_pole_zero_pairs():
    P = np.polymul
    # (s + 1)^2 / ((s + 1)^2 (s + 2)) = 1 / (s + 2): np.roots splits the double root by
    # 2.8e-8, beyond the default tolerance, and nothing cancelled
    num = P([1.0, 1.0], [1.0, 1.0])
    G = sysid.minreal(sysid.TransferFunction(num, P(num, [1.0, 2.0])))
    np.testing.assert_allclose(G.num[0][0], [1.0], atol=1e-12)
    np.testing.assert_allclose(G.den[0][0], [1.0, 2.0], atol=1e-12)
    # fivefold (s + 1)^5, a complex double pair, part of a double root, discrete
    c, d = np.ones(1), np.array([1.0, 3.0])
    for _ in range(5):
        c, d = P(c, [1.0, 1.0]), P(d, [1.0, 1.0])
    cases = [(c, d, [1.0], [1.0, 3.0], 0.0),
             (P([1.0, 2.0, 5.0], [1.0, 2.0, 5.0]), P(P([1.0, 2.0, 5.0], [1.0, 2.0, 5.0]),
                                                     [1.0, 3.0]), [1.0], [1.0, 3.0], 0.0),
             ([1.0, 1.0], P(num, [1.0, 2.0]), [1.0], [1.0, 3.0, 2.0], 0.0),
             (num, P([1.0, 1.0], [1.0, 2.0]), [1.0, 1.0], [1.0, 2.0], 0.0),
             (P([1.0, -0.5], [1.0, -0.5]), P(P([1.0, -0.5], [1.0, -0.5]), [1.0, -0.9]),
              [1.0], [1.0, -0.9], 1.0)]
    for n, dd, n_ref, d_ref, dt in cases:
        R = sysid.minreal(sysid.TransferFunction(n, dd, dt=dt))
        np.testing.assert_allclose(R.num[0][0], n_ref, atol=1e-9)
        np.testing.assert_allclose(R.den[0][0], d_ref, atol=1e-9)
    # near but distinct roots stay
    R = sysid.minreal(sysid.TransferFunction([1.0, 1.0001], P([1.0, 1.0], [1.0, 2.0])))
    assert R.den[0][0].size == 3
