"""The default horizons of a time series (sysid.subspace.series_horizon): past from the
autoregression AIC picks, future the order's; input-output records keep theirs."""

import warnings

import numpy as np
import pytest
from scipy import signal

import sysid
from sysid.subspace.estimator import available_horizon, horizon_for_order
from sysid.subspace.series_horizon import ar_order_aic, series_horizons


def _series(b, n=800, seed=0):
    e = np.random.default_rng(seed).standard_normal(n + 200)
    return sysid.IOData(None, signal.lfilter(b, [1, -1.5, 0.7], e)[200:, None], 1.0)


def _var1(n=600, seed=0):
    rng = np.random.default_rng(seed)
    phi = np.array([[0.6, 0.3], [-0.2, 0.7]])
    y = np.zeros((n + 100, 2))
    for t in range(1, n + 100):
        y[t] = phi @ y[t - 1] + rng.standard_normal(2)
    return sysid.IOData(None, y[100:], 1.0)


def test_the_aic_order_follows_the_dynamics():
    ar2, arma = _series([1.0]), _series([1.0, 0.5])
    assert ar_order_aic([ar2.experiments[0][1]], 19) == 2
    assert ar_order_aic([arma.experiments[0][1]], 19) > 2  # the MA part asks for more
    assert ar_order_aic([_var1().experiments[0][1]], 9) == 1
    white = np.random.default_rng(3).standard_normal((500, 1))
    assert ar_order_aic([white], 10) == 0
    # several experiments are summed, not joined
    halves = [ar2.experiments[0][1][:400], ar2.experiments[0][1][400:]]
    assert ar_order_aic(halves, 10) == 2


def test_time_series_defaults_and_info():
    d = _series([1.0, 0.5])
    sel = series_horizons(d, 2)
    assert sel["future"] == 3 and sel["past"] == sel["ar_order"] + 1 > 3
    est = sysid.SubspaceEstimator(d)
    assert est.past == est.future == sel["past"] and est.horizon_selection["ar_order"] > 2
    m = sysid.n4sid(d, 2)
    assert (m.info["past"], m.info["future"]) == (sel["past"], 3)
    assert m.info["horizon_selection"] == sel
    assert sysid.SubspaceEstimator(d).fit(2).info["future"] == sel["past"]
    # two outputs: the future for 2 states is 2 blocks
    assert sysid.cva(_var1(), 2).info["future"] == 2


def test_auto_order_is_refitted_at_its_future():
    d = _series([1.0])
    auto = sysid.moesp(d)
    n = auto.info["order"]
    given = sysid.moesp(d, n)
    assert auto.info["future"] == given.info["future"] == -(-n // 1) + 1
    np.testing.assert_allclose(np.sort_complex(auto.poles()), np.sort_complex(given.poles()))
    assert auto.info["order_selection"]["order"] == n
    assert auto.info["settings"]["order_rule"] == "auto"


def test_a_given_horizon_and_input_output_records_are_unchanged():
    d = _series([1.0])
    m = sysid.n4sid(d, 2, horizon=5)
    assert (m.info["past"], m.info["future"]) == (5, 5) and "horizon_selection" not in m.info
    rng = np.random.default_rng(1)
    u = rng.standard_normal((600, 1))
    io = sysid.IOData(u, sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]]).simulate(u))
    est = sysid.SubspaceEstimator(io)
    assert est.past == est.future == available_horizon([600], 1, 1)
    assert est.horizon_selection is None
    assert "horizon_selection" not in sysid.n4sid(io, 1).info


@pytest.mark.parametrize("order", [4, 6])
def test_orders_beyond_the_autoregression_keep_the_record_horizon(order):
    # an AR(2) over-fitted: its extra states on a short future are wild (poles of modulus
    # 2-13 in most records); at the record's horizon, as before, seldom (this one's n4sid
    # at order 4 is still just unstable there: not what is tested)
    d = _series([1.0])
    assert horizon_for_order(d, order, None) == available_horizon([800], 0, 1) == 20
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sysid.StabilityWarning)
        m = sysid.n4sid(d, order, uncertainty=None)
    assert m.info["past"] == m.info["future"] == 20 and "horizon_selection" not in m.info


def test_auto_keeps_its_horizons_where_the_short_future_is_unstable():
    # ARMA(2,1), this record: "auto" picks 4 states; at future 5 the spurious ones are
    # unstable, so the order choice's model (future = past) is kept, and said
    d = _series([1.0, 0.5], n=500, seed=0)
    m = sysid.n4sid(d, uncertainty=None)
    assert m.info["order"] == 4 and m.info["future"] == m.info["past"]
    assert "the order choice's horizons kept" in m.info["horizon_selection"]["rule"]
    assert np.max(np.abs(m.poles())) < 1
