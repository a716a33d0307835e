"""The residual independence test keeps its level on a coloured residual (a model without a
noise model, as an output-error fit leaves) and gains power there: the residual and the
inputs are filtered by the residual's own autoregressive whitening filter first."""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

import sysid

PLANT = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], dt=1.0)


def record(seed: int, u_pole: float, e_pole: float, N: int = 1000):
    """A first-order plant's input (AR(1) ``u_pole``) and output with an AR(1) ``e_pole``
    disturbance, no noise model: the true model's errors are the disturbance itself."""
    rng = np.random.default_rng([seed, 61])
    u = lfilter([1.0], [1.0, -u_pole], rng.standard_normal(N))[:, None]
    v = lfilter([1.0], [1.0, -e_pole], 0.5 * rng.standard_normal(N))[:, None]
    return u, PLANT.simulate(u) + v


def test_a_coloured_residual_of_the_true_model_is_rejected_at_the_tests_level():
    """200 records, coloured input and disturbance (AR(1) 0.9 each): the true model is
    rejected at alpha = 0.01 in 2 runs expected; at most 8 allowed (P(X >= 9) ~ 2e-4 at the
    level). Without the whitening the rate was about 25 % (51 of 200)."""
    runs = 200
    rejected = 0
    for s in range(runs):
        u, y = record(s, 0.9, 0.9)
        res = sysid.residuals(PLANT, (u, y), x0="zero")
        rejected += res.independence[0] is False
        assert res.whitening_order[0] >= 1  # the disturbance is coloured: it is whitened
    assert rejected <= 8, rejected


def test_a_slightly_wrong_model_is_still_rejected_under_a_coloured_disturbance():
    """A pole 0.785 against the true 0.8 (same static gain), white input, AR(1) 0.9
    disturbance: rejected in at least 48 of 60 records (59 measured; 17 without the
    whitening, whose correlated lags hid the error)."""
    wrong = sysid.StateSpaceModel([[0.785]], [[1.0]], [[0.215 / 0.2]], dt=1.0)
    rejected = sum(sysid.residuals(wrong, record(s, 0.0, 0.9), x0="zero").independence[0]
                   is False for s in range(60))
    assert rejected >= 48, rejected


def test_a_white_residual_is_left_unfiltered_in_most_records():
    """The true model of a plant with white output noise: AIC keeps the filter at order 0
    in most records (the test is then Ljung's regression test as before)."""
    orders = [int(sysid.residuals(PLANT, record(s, 0.5, 0.0), x0="zero").whitening_order[0])
              for s in range(40)]
    assert sum(q == 0 for q in orders) >= 24, orders


def test_whiteness_rejected_for_a_model_without_a_noise_model_says_what_it_means():
    """The true plant without a noise model under an AR(1) 0.9 disturbance: whiteness is
    rejected (its errors are the disturbance) and the summary says to judge it by the
    independence test; a model with a Kalman gain gets no such note."""
    u, y = record(3, 0.5, 0.9)
    res = sysid.residuals(PLANT, (u, y), x0="zero")
    assert not res.is_white and res.independence[0] is True
    assert "no noise model" in res.whiteness_note and res.whiteness_note in res.summary()
    with_k = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], K=[[0.5]], dt=1.0)
    res_k = sysid.residuals(with_k, (u, y), x0="zero")
    assert not res_k.is_white and res_k.whiteness_note == ""


def test_the_true_model_under_feedback_is_not_rejected_for_its_coloured_residual():
    """A proportional controller on the last output (``u(t) = r(t) - 0.5 y(t - 1)``), an
    AR(1) 0.9 disturbance: the inputs now carry the disturbance's past, so the raw residual
    of the true plant (no noise model) correlates with them (60 of 60 rejected before); the
    whitened residual is the disturbance's innovation, which the controller has not yet
    seen, and the test holds its level (0.6 expected in 60; at most 4 allowed)."""
    rejected = 0
    for s in range(60):
        rng = np.random.default_rng([s, 62])
        ref = rng.standard_normal(1000)
        v = lfilter([1.0], [1.0, -0.9], 0.5 * rng.standard_normal(1000))
        x, y, u = 0.0, np.zeros(1000), np.zeros(1000)
        for t in range(1000):
            y[t] = x + v[t]
            u[t] = ref[t] - 0.5 * (y[t - 1] if t else 0.0)
            x = 0.8 * x + u[t]
        res = sysid.residuals(PLANT, (u[:, None], y[:, None]), x0="zero")
        rejected += res.independence[0] is False
    assert rejected <= 4, rejected
