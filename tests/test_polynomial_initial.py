"""The initial conditions of oe, armax, bj and polyest (MATLAB's ``InitialCondition``):
records that start mid-response, several experiments, the marginal covariance, the
keyword's checks (:mod:`sysid.polynomial.initial`)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

import sysid
from sysid.errors import DataError

B, F = [0.5, 0.2], [-1.2, 0.5]


def _mid_response(n: int = 500, skip: int = 100, seed: int = 0, a: list[float] = F
                  ) -> tuple[np.ndarray, np.ndarray]:
    """``y = B/F u(t-1)`` from rest over ``skip + n`` samples, the first ``skip`` dropped."""
    u = np.random.default_rng(seed).standard_normal(n + skip)
    y = lfilter([0.0, *B], [1.0, *a], u)
    return u[skip:], y[skip:]


@pytest.mark.parametrize("ic", ["estimate", "auto"])
def test_oe_recovers_a_record_starting_mid_response(ic: str) -> None:
    u, y = _mid_response()
    d = sysid.IOData(u, y, 1.0)
    zero = sysid.oe(d, 2, 2, 1, initial_condition="zero")
    assert np.max(np.abs(zero.f[0][0] - F)) > 1e-6  # from rest the transient biases it
    m = sysid.oe(d, 2, 2, 1, initial_condition=ic)
    np.testing.assert_allclose(m.b[0][0], B, atol=1e-8)
    np.testing.assert_allclose(m.f[0][0], F, atol=1e-8)
    assert m.info["initial_condition"] == "estimate"
    # the state is SciPy's lfilter zi of [0, b], [1, f]: with it the model reproduces y
    zi = m.info["initial_state"][0]["input"][0]
    sim = lfilter([0.0, *B], [1.0, *F], u, zi=zi)[0]
    np.testing.assert_allclose(sim, y, atol=1e-7)


@pytest.mark.parametrize("ic", ["estimate", "auto"])
def test_armax_recovers_a_record_starting_mid_response_with_c_exact(ic: str) -> None:
    a = [-0.9, 0.2]
    u, y = _mid_response(a=a, seed=1)
    d = sysid.IOData(u, y, 1.0)
    zero = sysid.armax(d, 2, 2, 1, 1, initial_condition="zero")
    assert abs(zero.c[0][0]) > 1e-3  # from rest, C soaks up the transient
    m = sysid.armax(d, 2, 2, 1, 1, initial_condition=ic)
    np.testing.assert_allclose(m.a[0][0], a, atol=1e-8)
    np.testing.assert_allclose(m.b[0][0], B, atol=1e-8)
    np.testing.assert_allclose(m.c[0], [0.0], atol=1e-8)
    assert m.info["initial_condition"] == "estimate"


@pytest.mark.parametrize("ic", ["estimate", "auto"])
def test_bj_recovers_a_record_starting_mid_response(ic: str) -> None:
    u, y = _mid_response(seed=2)
    d = sysid.IOData(u, y, 1.0)
    zero = sysid.bj(d, 2, 1, 1, 2, 1, initial_condition="zero")
    assert np.max(np.abs(zero.f[0][0] - F)) > 1e-6
    m = sysid.bj(d, 2, 1, 1, 2, 1, initial_condition=ic)
    np.testing.assert_allclose(m.b[0][0], B, atol=1e-8)
    np.testing.assert_allclose(m.f[0][0], F, atol=1e-8)


def test_polyest_takes_the_keyword() -> None:
    u, y = _mid_response(seed=3)
    m = sysid.polyest(sysid.IOData(u, y, 1.0), [0, 2, 0, 0, 2, 1], initial_condition="estimate")
    np.testing.assert_allclose(m.f[0][0], F, atol=1e-8)
    assert m.info["initial_condition"] == "estimate"


def _noisy_record() -> sysid.IOData:
    rng = np.random.default_rng(7)
    u = rng.standard_normal(700)
    e = 0.05 * rng.standard_normal(700)
    y = lfilter([0, 0.5, 0.2], [1, -1.2, 0.5], u) + lfilter([1, 0.3], [1, -0.5], e)
    return sysid.IOData(u[100:], y[100:], 1.0)


def test_zero_reproduces_the_fit_from_rest() -> None:
    """The numbers of the code before ``initial_condition`` existed (computed with it)."""
    d = _noisy_record()
    m = sysid.oe(d, 2, 2, 1, initial_condition="zero")
    np.testing.assert_allclose(m.b[0][0], [0.5049672087954437, 0.19128480360424255], rtol=1e-12)
    np.testing.assert_allclose(m.f[0][0], [-1.206377609959414, 0.5045492841386499], rtol=1e-12)
    m = sysid.armax(d, 2, 2, 1, 1, initial_condition="zero")
    np.testing.assert_allclose(m.a[0][0], [-1.2052571386435846, 0.5034334371360318],
                               rtol=1e-12)
    np.testing.assert_allclose(m.c[0], [-0.1525440376145442], rtol=1e-12)
    m = sysid.bj(d, 2, 1, 1, 2, 1, initial_condition="zero")
    np.testing.assert_allclose(m.f[0][0], [-1.2052547114510346, 0.5041976951248766],
                               rtol=1e-12)
    np.testing.assert_allclose(m.d[0], [-0.634201389274113], rtol=1e-12)
    assert m.info["initial_condition"] == "zero"
    assert not np.any(m.info["initial_state"][0]["input"][0])


def test_auto_is_zero_or_estimate_exactly() -> None:
    """``auto`` gives one of the two fits, and says which and why."""
    d = _noisy_record()  # starts mid-response: the state matters
    auto = sysid.oe(d, 2, 2, 1)
    est = sysid.oe(d, 2, 2, 1, initial_condition="estimate")
    assert auto.info["initial_condition"] == "estimate"
    np.testing.assert_array_equal(auto.f[0][0], est.f[0][0])
    costs = auto.info["initial_condition_costs"]
    assert costs["estimate"] < 0.5 * costs["zero"]
    # at rest, with noise: the estimated state lowers the criterion no more than noise would
    rng = np.random.default_rng(4)
    u = rng.standard_normal(600)
    y = lfilter([0, 0.5, 0.2], [1, -1.2, 0.5], u) + 0.1 * rng.standard_normal(600)
    d = sysid.IOData(u, y, 1.0)
    auto, zero = sysid.oe(d, 2, 2, 1), sysid.oe(d, 2, 2, 1, initial_condition="zero")
    assert auto.info["initial_condition"] == "zero"
    np.testing.assert_array_equal(auto.f[0][0], zero.f[0][0])


def test_each_experiment_has_its_own_initial_state() -> None:
    records = [_mid_response(n=n, skip=skip, seed=s)
               for n, skip, s in ((300, 40, 5), (200, 77, 6), (250, 13, 7))]
    d = sysid.IOData([u[:, None] for u, _ in records], [y[:, None] for _, y in records], 1.0)
    zero = sysid.oe(d, 2, 2, 1, initial_condition="zero")
    assert np.max(np.abs(zero.f[0][0] - F)) > 1e-6
    m = sysid.oe(d, 2, 2, 1)
    np.testing.assert_allclose(m.f[0][0], F, atol=1e-8)
    np.testing.assert_allclose(m.b[0][0], B, atol=1e-8)
    states = m.info["initial_state"]
    assert len(states) == 3
    for (u, y), s in zip(records, states):
        sim = lfilter([0.0, *B], [1.0, *F], u, zi=s["input"][0])[0]
        np.testing.assert_allclose(sim, y, atol=1e-7)
    # the states differ: one per experiment
    assert np.ptp([s["input"][0][0] for s in states]) > 0.1


def test_predicted_std_matches_monte_carlo_with_the_state_estimated() -> None:
    """A second-order OE plant on short records (80 samples) that start mid-response (its
    poles of radius 0.84 keep the transient for some 25 samples): the marginal standard
    deviation (the initial state a nuisance) predicts the spread of the estimates, which are
    unbiased (from rest they are not)."""
    runs, n, sigma = 150, 80, 0.05
    truth = np.r_[B, -1.5, 0.7]
    rng = np.random.default_rng(11)
    est, pred = [], []
    for _ in range(runs):
        u = rng.standard_normal(n + 60)
        y = lfilter([0.0, *B], [1.0, -1.5, 0.7], u)[60:] + sigma * rng.standard_normal(n)
        m = sysid.oe(sysid.IOData(u[60:], y, 1.0), 2, 2, 1, initial_condition="estimate")
        est.append(np.r_[m.b[0][0], m.f[0][0]])
        pred.append(m.uncertainty.std)
    sample = np.std(est, axis=0, ddof=1)
    predicted = np.sqrt(np.mean(np.square(pred), axis=0))
    np.testing.assert_allclose(predicted, sample, rtol=0.2)
    bias = np.abs(np.mean(est, axis=0) - truth)
    assert np.all(bias < 3 * sample / np.sqrt(runs)), bias / sample


@pytest.mark.parametrize("bad", ["Estimate", "backcast", "", None, 1])
@pytest.mark.parametrize("fit", ["oe", "armax", "bj", "polyest"])
def test_a_bad_value_names_the_allowed_ones(fit: str, bad: object) -> None:
    u, y = _mid_response(n=100)
    d = sysid.IOData(u, y, 1.0)
    call = {"oe": lambda **k: sysid.oe(d, 2, 2, 1, **k),
            "armax": lambda **k: sysid.armax(d, 2, 2, 1, 1, **k),
            "bj": lambda **k: sysid.bj(d, 2, 1, 1, 2, 1, **k),
            "polyest": lambda **k: sysid.polyest(d, [0, 2, 0, 0, 2, 1], **k)}[fit]
    with pytest.raises(DataError, match="'auto', 'zero' or 'estimate'"):
        call(initial_condition=bad)


def test_backcast_is_not_offered_and_lines_have_no_transient() -> None:
    u, y = _mid_response(n=100)
    with pytest.raises(DataError, match="'backcast' is not offered"):
        sysid.oe(sysid.IOData(u, y, 1.0), 2, 2, 1, initial_condition="backcast")
    g = sysid.TransferFunction([0.5, 0.2], [1.0, -1.2, 0.5], dt=1.0)
    up = sysid.multisine(64, band=(0, 0.5), periods=4, seed=0)
    yp = g.simulate(np.vstack([np.tile(up, (5, 1)), up]))[-256:]
    with pytest.raises(DataError, match="no transient"):
        sysid.oe(sysid.IOData(up, yp, 1.0), 2, 2, 1, periods=4, initial_condition="estimate")
