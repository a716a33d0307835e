"""nlhw / nlhw_ss with nonlinearities "auto" (the default): the identity or sigmoid networks,
as the estimation record's held-out blocks insist (sysid.nonlinear.choice)."""

import warnings

import numpy as np
import pytest

import sysid


def _wiener(seed=0, n=600, noise=0.01):
    # a lightly nonlinear input map (tanh) before a second-order block: a linear model
    # misses the saturation
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, (n, 1))
    w = np.tanh(2 * u[:, 0])
    x, y = np.zeros(2), np.zeros((n, 1))
    for t in range(n):
        y[t] = x[0]
        x = np.array([[0.8, 0.2], [-0.2, 0.7]]) @ x + np.array([0.0, 1.0]) * w[t]
    return sysid.IOData(u, y + noise * rng.standard_normal(y.shape), 1.0)


def _linear(seed=1, n=600):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, (n, 1))
    y = np.convolve(u[:, 0], [0.0, 1.0, 0.5])[:n, None] + 0.05 * rng.standard_normal((n, 1))
    return sysid.IOData(u, y, 1.0)


@pytest.mark.parametrize("fit", [lambda d: sysid.nlhw_ss(d, 2, progress=False),
                                 lambda d: sysid.nlhw(d, 2, 2, 1, progress=False)],
                         ids=["nlhw_ss", "nlhw"])
def test_a_saturating_input_gets_the_networks_and_they_validate_better(fit):
    # the old default fitted the identity on both sides: a linear model under a
    # nonlinear name. (nlhw's search on this record stops at its cap while still leaving a
    # plateau, and says so: tests/test_pem_cap_distance.py; not what this test is about.)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=sysid.IterationLimitWarning)
        m = fit(_wiener())
    choice = m.info["nonlinearity_choice"]
    assert choice["kind"] == "sigmoid" and choice["sides"] == ["input", "output"]
    assert choice["table"]["sigmoid"] > choice["table"]["identity"] + 5
    assert "held-out simulation fit" in choice["reason"]
    fresh = _wiener(seed=5)
    fits = [float(np.ravel(sysid.compare(fresh, k).fit)[0]) for k in
            (m, sysid.nlhw_ss(_wiener(), 2, input_nl=None, output_nl=None, progress=False))]
    assert fits[0] > fits[1] + 5, fits


def test_a_linear_record_keeps_the_identity_and_the_same_model():
    d = _linear()
    auto = sysid.nlhw_ss(d, 2, progress=False)
    given = sysid.nlhw_ss(d, 2, input_nl=None, output_nl=None, progress=False)
    assert auto.info["nonlinearity_choice"]["kind"] == "identity"
    assert len(auto.info["nonlinearity_choice"]["folds"]["sigmoid"]) == 5
    np.testing.assert_array_equal(auto.theta, given.theta)
    assert "nonlinearity_choice" not in given.info  # given: fitted once


def test_only_the_auto_side_is_chosen_and_a_short_record_keeps_the_identity():
    m = sysid.nlhw(_wiener(), 2, 2, 1, input_nl=sysid.SigmoidNetwork(2), progress=False)
    assert m.info["nonlinearity_choice"]["sides"] == ["output"]
    assert m.input_nl.params.size == sysid.SigmoidNetwork(2).initial(np.zeros(3)).size
    short = sysid.nlhw(_linear(n=30), 1, 1, 1, progress=False)
    assert short.info["nonlinearity_choice"]["kind"] == "identity"
    assert "too short" in short.info["nonlinearity_choice"]["reason"]
    with pytest.raises(sysid.DataError, match="max_iter"):
        sysid.nlhw_ss(_linear(), 2, max_iter=-1, progress=False)  # the whole record's error
