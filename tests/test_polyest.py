"""polyest (MATLAB's general polynomial estimator A y = B/F u + C/D e) and pem given a
polynomial model (MATLAB's pem(data, idpoly)): python/sysid/polynomial/polyest.py."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

import sysid
from sysid.errors import DataError


def _general(u: np.ndarray, e: np.ndarray) -> np.ndarray:
    """A y = B/F u(t-1) + C/D e with A = 1 - 0.5 q^-1, B = 1 + 0.5 q^-1, F = 1 - 0.6 q^-1,
    C = 1 + 0.4 q^-1, D = 1 - 0.3 q^-1."""
    x = signal.lfilter([0.0, 1.0, 0.5], [1.0, -0.6], u)
    v = signal.lfilter([1.0, 0.4], [1.0, -0.3], e)
    return signal.lfilter([1.0], [1.0, -0.5], x + v)


def test_noise_free_general_structure_is_recovered_to_machine_precision():
    u = np.random.default_rng(0).standard_normal(800)
    # noise free: C and D are not determined, so A, B, F alone (nc = nd = 0)
    y = signal.lfilter([1.0], [1.0, -0.5], signal.lfilter([0.0, 1.0, 0.5], [1.0, -0.6], u))
    m = sysid.polyest(sysid.IOData(u, y, 1.0), 1, 2, 0, 0, 1, 1)
    np.testing.assert_allclose(np.sort(np.r_[m.a[0][0], m.f[0][0]]), [-0.6, -0.5], atol=1e-8)
    # A and F are interchangeable in the input path; their product is determined
    np.testing.assert_allclose(np.convolve(np.r_[1, m.a[0][0]], np.r_[1, m.f[0][0]]),
                               np.convolve([1, -0.5], [1, -0.6]), atol=1e-8)
    # MATLAB's order vector gives the same model
    v = sysid.polyest(sysid.IOData(u, y, 1.0), [1, 2, 0, 0, 1, 1])
    np.testing.assert_allclose(v.b[0][0], m.b[0][0], atol=1e-12)


def test_special_cases_equal_the_named_estimators():
    rng = np.random.default_rng(3)
    u, e = rng.standard_normal(1500), 0.1 * rng.standard_normal(1500)
    d = sysid.IOData(u, _general(u, e), 1.0)
    for ours, theirs in ((sysid.polyest(d, 2, 2, 1, 0, 0, 1), sysid.armax(d, 2, 2, 1, 1)),
                         (sysid.polyest(d, 0, 2, 0, 0, 2, 1), sysid.oe(d, 2, 2, 1)),
                         (sysid.polyest(d, 0, 2, 1, 1, 2, 1), sysid.bj(d, 2, 1, 1, 2, 1))):
        np.testing.assert_allclose(ours.uncertainty.theta, theirs.uncertainty.theta, atol=1e-6)


def test_general_structure_is_consistent_and_its_std_calibrated():
    # Monte Carlo (200 records): the mean estimate within 3 sample std of the truth of each
    # parameter of the general model, and the predicted std within 25 % of the sample one
    # (200 draws: the sample std itself is within about 10 % at 2 sigma)
    est, sds = [], []
    for run in range(200):
        rng = np.random.default_rng(700 + run)
        u, e = rng.standard_normal(1000), 0.3 * rng.standard_normal(1000)
        m = sysid.polyest(sysid.IOData(u, _general(u, e), 1.0), 1, 2, 1, 1, 1, 1)
        est.append(m.uncertainty.theta)
        sds.append(np.sqrt(np.diag(m.covariance[0])))
    est, sds = np.asarray(est), np.asarray(sds)
    truth = np.array([-0.5, 1.0, 0.5, 0.4, -0.3, -0.6])  # a, b, c, d, f in that order
    assert np.all(np.abs(est.mean(axis=0) - truth) < 3 * est.std(axis=0) / np.sqrt(200) + 0.01)
    ratio = sds.mean(axis=0) / est.std(axis=0)
    assert np.all(np.abs(ratio - 1) < 0.25), ratio


def test_pem_refines_a_polynomial_model_in_its_own_structure():
    rng = np.random.default_rng(4)
    u, e = rng.standard_normal(2000), 0.1 * rng.standard_normal(2000)
    d = sysid.IOData(u, _general(u, e), 1.0)
    with pytest.warns(sysid.IterationLimitWarning):
        start = sysid.polyest(d, 1, 2, 1, 1, 1, 1, max_iter=1)
    refined = sysid.pem(d, start)
    assert isinstance(refined, sysid.PolynomialModel)
    assert refined.info["start"] == "init"
    assert [len(refined.a[0][0]), len(refined.b[0][0]), len(refined.f[0][0])] == [1, 2, 1]
    assert refined.info["cost"][0][-1] <= start.info["cost"][0][-1]
    full = sysid.polyest(d, 1, 2, 1, 1, 1, 1)
    np.testing.assert_allclose(refined.uncertainty.theta, full.uncertainty.theta, atol=1e-4)
    # an ARX model refined by pem stays at the least-squares minimum (up to the first
    # samples, which the regression drops and the predictor runs through from rest)
    arx = sysid.arx(d, 2, 2, 1)
    np.testing.assert_allclose(sysid.pem(d, arx).uncertainty.theta, arx.uncertainty.theta,
                               atol=1e-3)


def test_bad_calls_say_what_to_do():
    rng = np.random.default_rng(5)
    u, y = rng.standard_normal((300, 2)), rng.standard_normal((300, 2))
    d = sysid.IOData(u, y, 1.0)
    coupled = sysid.arx(d, [[1, 1], [1, 1]], [[1, 1], [1, 1]], [[1, 1], [1, 1]])
    # ARX with a coupled A: least squares again, its prediction-error minimum
    again = sysid.pem(d, coupled)
    np.testing.assert_allclose(again.a[0][1], coupled.a[0][1])
    assert "least-squares" in again.info["note"]
    with_c = sysid.PolynomialModel(coupled.a, coupled.b, coupled.nk, 1.0,
                                   c=[np.array([0.1]), np.array([0.1])])
    with pytest.raises(DataError, match="couples output"):
        sysid.pem(d, with_c)
    with pytest.raises(DataError, match="polyest"):
        sysid.polyest(d, "auto")
    with pytest.raises(DataError, match="got focus, x0"):
        sysid.pem(d, coupled, focus="simulation", x0="zero")
    with pytest.raises(DataError, match="sampled every 0.5"):
        sysid.pem(sysid.IOData(u, y, 1.0), sysid.polyest(sysid.IOData(u, y, 0.5), 1, 1, 0, 0,
                                                         0, 1))


def test_an_output_error_structure_carries_oes_uncertainty():
    # polyest([0, nb, 0, 0, nf, nk]) and bj with C = D = 1 are oe: the same estimate, but
    # they carried the Gauss-Newton covariance (std 0.6-0.77 of the sample one, intervals
    # covering 76-89 % under a coloured disturbance) where oe carries the sandwich
    from scipy.signal import lfilter

    rng = np.random.default_rng(1)
    u = rng.standard_normal(800)
    v = lfilter([1.0], [1.0, -0.95], 0.1 * rng.standard_normal(800))
    d = sysid.IOData(u, lfilter([0.0, 1.0, 0.5], [1.0, -1.2, 0.5], u) + v, 1.0)
    ref = sysid.oe(d, 2, 2, 1)
    for m in (sysid.polyest(d, [0, 2, 0, 0, 2, 1]), sysid.bj(d, 2, 0, 0, 2, 1)):
        assert m.info["covariance"].startswith("gauss-newton until first used")
        np.testing.assert_allclose(m.uncertainty.covariance, ref.uncertainty.covariance,
                                   rtol=1e-6)
        assert m.info["covariance"].startswith("sandwich")
    # a structure with a noise model keeps its Gauss-Newton covariance
    assert "covariance" not in sysid.bj(d, 2, 1, 1, 2, 1).info
