"""d2d: resampling a discrete model (MATLAB's d2d), python/sysid/models/continuous.py."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.errors import DataError


def _model() -> sysid.StateSpaceModel:
    return sysid.StateSpaceModel([[0.6, 0.3, 0.0], [-0.3, 0.6, 0.0], [0.0, 0.0, -0.4]],
                                 [[1.0, 0.0], [0.5, 1.0], [0.2, -0.3]],
                                 [[1.0, 0.0, 0.5], [0.0, 1.0, 1.0]], [[0.1, 0.0], [0.0, 0.2]],
                                 dt=0.1)


def test_a_whole_multiple_with_zoh_is_exact_for_any_poles():
    # a pole on the negative real axis (no continuous equivalent): the input held over
    # k old samples, sampled every k, is the resampled model's simulation
    m = _model()
    k = 3
    r = sysid.d2d(m, k * 0.1)
    assert r.dt == pytest.approx(0.3) and r.K is None
    u = np.random.default_rng(0).standard_normal((200, 2))
    fine = m.simulate(np.repeat(u, k, axis=0))[::k]
    np.testing.assert_allclose(r.simulate(u), fine, atol=1e-12)
    # another ratio goes through the ZOH continuous equivalent, whose negative real pole is
    # doubled (as MATLAB's d2c); halving the sample time and holding two samples is exact
    with pytest.warns(sysid.SysidWarning, match="negative real axis"):
        half = sysid.d2d(m, 0.05)
    assert half.nstates == m.nstates + 1
    back = sysid.d2d(half, 0.1)
    np.testing.assert_allclose(back.simulate(u), m.simulate(u), atol=1e-9)


def test_other_ratios_go_through_the_continuous_equivalent_and_round_trip():
    m = sysid.StateSpaceModel([[0.9, 0.1], [0.0, 0.8]], [[1.0], [0.5]], [[1.0, 1.0]],
                              [[0.0]], dt=0.2)
    for method in ("zoh", "foh", "tustin"):
        r = sysid.d2d(m, 0.05, method)
        ref = sysid.c2d(sysid.d2c(m, method), 0.05, method)
        w = np.linspace(0.1, 15.0, 30)
        np.testing.assert_allclose(r.freqresp(w), ref.freqresp(w), atol=1e-12)
        back = sysid.d2d(r, 0.2, method)
        np.testing.assert_allclose(back.freqresp(w), m.freqresp(w), atol=1e-9)
    # the poles map as z^(dt_new / dt)
    np.testing.assert_allclose(np.sort(sysid.d2d(m, 0.05).poles().real),
                               np.sort(np.array([0.8, 0.9]) ** 0.25), atol=1e-12)


def test_uncertainty_goes_through_the_resampling():
    rng = np.random.default_rng(1)
    true = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], dt=0.1)
    u = rng.standard_normal(500)
    y = true.simulate(u) + 0.05 * rng.standard_normal((500, 1))
    est = sysid.ssest(sysid.IOData(u, y, 0.1), 1)
    p, s = est.poles(std=True)
    r = sysid.d2d(est, 0.2)
    pr, sr = r.poles(std=True)
    assert pr[0].real == pytest.approx(p[0].real ** 2, rel=1e-9)
    # d(p^2) = 2 p dp, first order
    assert sr[0].real == pytest.approx(2 * abs(p[0].real) * s[0].real, rel=1e-3)


def test_bad_calls_say_what_to_do():
    m = _model()
    with pytest.raises(DataError, match="method must be"):
        sysid.d2d(m, 0.2, "matched")
    with pytest.raises(DataError):
        sysid.d2d(m, -1.0)
    with pytest.raises(DataError, match="discrete"):
        sysid.d2d(sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]]), 0.1)
