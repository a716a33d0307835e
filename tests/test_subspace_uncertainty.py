"""The uncertainty `n4sid`, `moesp` and `cva` attach by default (MATLAB's `n4sid` reports a
covariance): the simulation-error criterion's at the estimate; the closed-loop `pbsid` and
`ssarx`: the prediction-error criterion's. Calibrated by Monte Carlo against the
estimators' own spread."""

import warnings

import numpy as np
import pytest

import sysid

TRUE = sysid.StateSpaceModel([[1.5, -0.7], [1.0, 0.0]], [[1.0], [0.0]], [[0.5, 0.3]],
                             K=[[0.5], [0.2]])
POLE = np.sort_complex(TRUE.poles())[-1]  # 0.75 + 0.37i


# the innovations form driven by [u, e]: coloured output noise
NOISY = sysid.StateSpaceModel(TRUE.A, np.hstack([TRUE.B, TRUE.K]), TRUE.C, [[0.0, 1.0]])


def _record(rng, n=2000):
    u = rng.standard_normal((n, 1))
    e = 0.3 * rng.standard_normal((n, 1))
    return sysid.IOData(u=u, y=NOISY.simulate(np.hstack([u, e])))


def _assert_pole_calibrated(fit, runs=200, pole=POLE):
    """Over ``runs`` fits, the first-order std of the upper pole ``pole`` (real and imaginary
    parts) within 20 % of the estimates' sample std and its 95 % intervals covering the true
    pole 90-99 % of the time; returns the last model."""
    est, sd = [], []
    for _ in range(runs):
        m = fit()
        p, s = m.poles(std=True)
        k = int(np.argmin(np.abs(p - pole)))
        est.append(p[k])
        sd.append(s[k])
    est, sd = np.array(est), np.array(sd)
    for part in (np.real, np.imag):
        ratio = float(np.median(part(sd)) / np.std(part(est)))
        assert 0.8 < ratio < 1.2, ratio
        cover = float(np.mean(np.abs(part(est) - part(pole)) <= 1.96 * part(sd)))
        assert 0.90 <= cover <= 0.99, cover
    return m


@pytest.mark.parametrize("method", ["n4sid", "cva"])
def test_default_pole_std_matches_the_estimators_spread(method):
    # 200 records of 2000 samples: the first-order std of the upper pole (real and imaginary
    # parts) within 20 % of the sample std of the estimates (the sample std's own relative
    # error is ~5 % at 200 runs), and the 95 % intervals cover the true pole 90-99 % of the
    # time (binomial std 1.5 %). (At 600 samples the first-order std is 10-14 % short and
    # the intervals cover 88-90 %: an asymptotic result.)
    rng = np.random.default_rng(5)
    _assert_pole_calibrated(lambda: getattr(sysid, method)(_record(rng), 2))


# the same plant under the feedback u = r - 0.3 y, driven by [r, e], returning [y, u]
GAIN = 0.3
LOOP = sysid.StateSpaceModel(
    TRUE.A - GAIN * TRUE.B @ TRUE.C, np.hstack([TRUE.B, TRUE.K - GAIN * TRUE.B]),
    np.vstack([TRUE.C, -GAIN * TRUE.C]), [[0.0, 1.0], [1.0, -GAIN]])


def _closed_loop_record(rng, n=2000):
    r = rng.standard_normal((n, 1))
    e = 0.5 * rng.standard_normal((n, 1))
    yu = LOOP.simulate(np.hstack([r, e]))
    return sysid.IOData(u=yu[:, 1:], y=yu[:, :1])


@pytest.mark.parametrize("method", ["pbsid", "ssarx"])
def test_closed_loop_pole_std_matches_the_estimators_spread(method):
    # as above, under feedback: the input is correlated with the noise, so the
    # simulation-error criterion's covariance (its formula assumes an independent input)
    # overstates the spread by 1.4-1.9 times here; the prediction-error one with the
    # estimate's K is the one attached, and must match
    rng = np.random.default_rng(11)
    m = _assert_pole_calibrated(
        lambda: getattr(sysid, method)(_closed_loop_record(rng), 2, horizon=10))
    assert "prediction-error" in m.info["uncertainty"]["method"]


def test_closed_loop_uncertainty_none_and_a_bad_value():
    d = _closed_loop_record(np.random.default_rng(12), 500)
    a = sysid.pbsid(d, 2, horizon=10)
    b = sysid.pbsid(d, 2, horizon=10, uncertainty=None)
    for k in ("A", "B", "C", "D", "K"):
        np.testing.assert_array_equal(getattr(a, k), getattr(b, k))
    assert b.uncertainty is None and a.uncertainty is not None
    with pytest.raises(sysid.DataError, match="break the feedback loop"):
        sysid.ssarx(d, 2, uncertainty="bootstrap")


def test_the_model_is_unchanged_and_keeps_its_noise_model():
    d = _record(np.random.default_rng(6))
    a = sysid.n4sid(d, 2)
    b = sysid.n4sid(d, 2, uncertainty=None)
    for k in ("A", "B", "C", "D", "K"):
        np.testing.assert_array_equal(getattr(a, k), getattr(b, k))
    assert b.uncertainty is None and a.uncertainty is not None
    assert "criterion" in a.info["uncertainty"]["method"]
    draw = a.uncertainty.sample(1, np.random.default_rng(0))[0]
    np.testing.assert_array_equal(draw.K, a.K)   # draws are models like the estimate
    assert draw.x0 is None and a.x0 is None
    # what the uncertainty gives: damping, response bands, the parameter table
    assert np.all(np.isfinite(sysid.damp(a, std=True).wn_std))
    H, sH = a.freqresp([0.1, 1.0], std=True)
    assert np.all(np.isfinite(sH)) and np.all(np.abs(sH) > 0)


def test_bootstrap_and_none_and_a_bad_value():
    d = _record(np.random.default_rng(7), 300)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = sysid.moesp(d, 2, uncertainty="bootstrap")
    assert m.info["uncertainty"]["method"] == "bootstrap"
    with pytest.raises(sysid.DataError, match="'criterion', 'bootstrap' or None"):
        sysid.n4sid(d, 2, uncertainty="yes")


def test_an_unstable_estimate_without_a_stable_predictor_says_why_it_has_none():
    # an integrator's record: the criterion is undefined at an unstable model whose
    # predictor is unstable too; the model comes back as estimated, with the reason
    rng = np.random.default_rng(8)
    u = rng.standard_normal((400, 1))
    y = np.cumsum(u, axis=0) * 0.1 + 0.001 * rng.standard_normal((400, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = sysid.n4sid(sysid.IOData(u=u, y=y), 1, kalman=False)
    if m.is_stable():
        pytest.skip("the estimate came out stable here")
    assert m.uncertainty is None and m.info["uncertainty"]["method"] == "none"
    with pytest.raises(sysid.DataError, match="no stable predictor"):
        m.poles(std=True)
