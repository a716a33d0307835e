"""The feedback test on periodic, band-limited inputs: no false FeedbackWarning on an
open-loop multisine record, the loop still found in a closed-loop one and on the winding
record (real, under tension control)."""

from __future__ import annotations

import warnings

import numpy as np

import sysid

PLANT = sysid.StateSpaceModel([[0.9, 0.3], [-0.3, 0.9]], [[1.0], [0.5]], [[1.0, 0.0]])


def multisine() -> np.ndarray:
    # 4 periods of 512 samples, lines up to half the Nyquist frequency: its own 20 lags
    # predict it to 1e-6, not exactly (with the outputs as regressors the test said p < 1e-14)
    return sysid.multisine(512, band=(0.0, 0.5), periods=4, phases="random", seed=1)


def test_open_loop_multisine_record_shows_no_feedback_and_fits_do_not_warn():
    rng = np.random.default_rng(0)
    u = multisine()
    data = sysid.IOData(u=u, y=PLANT.simulate(u) + 0.05 * rng.standard_normal(u.shape))
    res = sysid.check_feedback(data)
    assert not res.detected and res.p_value > 0.05, res
    with warnings.catch_warnings():
        warnings.simplefilter("error", sysid.FeedbackWarning)
        sysid.n4sid(data, 2)


def test_open_loop_multisines_are_calibrated():
    # 20 records, 20 phase realisations: at alpha = 0.05, 1 rejection expected; more than 5
    # has probability < 0.3 % under a calibrated test (binomial(20, 0.05))
    rejections = 0
    for seed in range(20):
        rng = np.random.default_rng(100 + seed)
        u = sysid.multisine(512, band=(0.0, 0.5), periods=4, phases="random", seed=seed)
        y = PLANT.simulate(u) + 0.05 * rng.standard_normal(u.shape)
        rejections += sysid.check_feedback(sysid.IOData(u=u, y=y), alpha=0.05).detected
    assert rejections <= 5, rejections


def test_closed_loop_with_a_multisine_reference_is_detected():
    rng = np.random.default_rng(1)
    r = multisine()[:, 0]
    e = 0.3 * rng.standard_normal(r.size)
    for delay in (0, 2, 4):  # the controller reads y(t - delay)
        u, y = np.zeros(r.size), np.zeros(r.size)
        for t in range(5, r.size):
            y[t] = 0.8 * y[t - 1] + u[t - 1] + e[t]
            u[t] = r[t] - 0.3 * y[t - delay]
        res = sysid.check_feedback(sysid.IOData(u=u, y=y))
        assert res.p_value < 1e-6, (delay, res)


def test_the_winding_record_under_tension_control_shows_feedback():
    w = np.loadtxt(sysid.datasets.path("winding"))
    est = sysid.IOData(u=w[:1666, :5], y=w[:1666, 5:], dt=0.1)
    assert sysid.check_feedback(est, lags=10).p_value < 1e-6
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sysid.moesp(est, 4)
    said = [str(c.message) for c in caught if c.category is sysid.FeedbackWarning]
    # the warning names the other cause a linear test cannot tell from a loop
    assert said and "A nonlinear plant in open loop can show the same" in said[0]


def test_the_automatic_order_warns_of_feedback_as_a_given_order_does():
    # the order choice's own fits (warnings ignored) used to consume the estimator's
    # once-only feedback warning: n4sid(data) never warned, n4sid(data, 4) did
    w = np.loadtxt(sysid.datasets.path("winding"))
    est = sysid.IOData(u=w[:1666, :5], y=w[:1666, 5:], dt=0.1)
    est = sysid.IOData(u=est.u - est.u.mean(0), y=est.y - est.y.mean(0), dt=0.1)
    for fit in (sysid.n4sid, sysid.moesp, sysid.cva):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            fit(est)
        assert [c.category for c in caught].count(sysid.FeedbackWarning) == 1, fit
    se = sysid.SubspaceEstimator(est)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        se.fit("auto")
        se.fit(3)  # once per estimator
    assert [c.category for c in caught].count(sysid.FeedbackWarning) == 1
