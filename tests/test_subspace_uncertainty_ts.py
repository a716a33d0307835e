"""The uncertainty `n4sid` and `cva` attach to a time series (no input): the
prediction-error criterion's at the estimate (the simulation of a time series is zero
whatever A and C are, so the simulation-error criterion is flat in them and its covariance
was 8-70 times too wide). Calibrated by Monte Carlo against the estimators' own spread."""

import numpy as np
import pytest
from test_subspace_uncertainty import _assert_pole_calibrated

import sysid

# AR(2): y = e / (1 - 1.5 q^-1 + 0.7 q^-2), its innovations form driven by e
AR2 = sysid.StateSpaceModel([[1.5, -0.7], [1.0, 0.0]], [[1.0], [0.0]], [[1.5, -0.7]],
                            [[1.0]])
POLE = np.sort_complex(AR2.poles())[-1]  # 0.75 + 0.37i


def _series(rng, n=500):
    e = rng.standard_normal((n + 200, 1))
    return sysid.IOData(None, AR2.simulate(e)[200:], 1.0)


@pytest.mark.parametrize("method", ["n4sid", "cva"])
def test_time_series_pole_std_matches_the_estimators_spread(method):
    # 200 series of 500 samples at the default horizons: the first-order std of the upper
    # pole (real and imaginary parts) within 20 % of the estimates' sample std, 95 %
    # intervals covering the true pole 90-99 % of the time (the simulation-error
    # criterion's: 8-70 times too wide, covering always). The time-series default (past
    # from the AIC autoregression, future the order's) is near the criterion's efficiency;
    # at the input-output default (past = future = 20) the estimator's own spread was 1.5-4
    # times wider and the intervals covered 55-80 % of the time.
    rng = np.random.default_rng(5)

    def fit():
        m = getattr(sysid, method)(_series(rng), 2)
        assert m.info["future"] == 3 and "AIC" in m.info["horizon_selection"]["rule"]
        return m

    m = _assert_pole_calibrated(fit, pole=POLE)
    unc = m.info["uncertainty"]
    assert unc["criterion"] == "prediction" and "prediction-error" in unc["method"]
    assert "time series" in unc["why"]
    draw = m.uncertainty.sample(1, np.random.default_rng(0))[0]
    assert not np.allclose(draw.K, m.K)  # K is a parameter of that criterion


def test_a_time_series_without_a_stable_predictor_has_no_criterion():
    from sysid.pem.at_estimate import criterion_at

    d = _series(np.random.default_rng(1))
    m = sysid.n4sid(d, 2, uncertainty=None)
    m.K = None
    fitted, why = criterion_at(m, d)
    assert fitted is None and "time series" in why


def test_identify_says_which_criterion_for_a_time_series():
    from sysid.identify.uncertainty import with_uncertainty

    d = _series(np.random.default_rng(2))
    m = sysid.n4sid(d, 2, uncertainty=None)
    checks = {}
    out = with_uncertainty(m, d, checks, ("n4sid",))
    assert "prediction-error criterion because the record is a time series" in checks[
        "uncertainty"]
    assert out.poles(std=True)[1][0].real < 0.1
