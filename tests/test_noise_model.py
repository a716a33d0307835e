"""``sysid.noise2meas`` and ``sysid.spectrum`` (MATLAB's): the noise part as a model that
reproduces the disturbance, the analytic spectrum of an AR(1) process, a fitted model's
spectrum against the Welch estimate of the same record (the convention of
``sysid.spectra``), the uncertainty carried, and clear errors."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.errors import DataError


def _innovation_model() -> sysid.StateSpaceModel:
    return sysid.StateSpaceModel([[0.8, 0.1], [0.0, 0.5]], [[1.0], [0.5]],
                                 [[1.0, 0.0], [0.0, 1.0]], K=[[0.4, 0.0], [0.1, 0.3]],
                                 noise_cov=[[0.04, 0.01], [0.01, 0.09]], dt=0.5)


def test_noise_model_reproduces_the_disturbance():
    m = _innovation_model()
    e = np.random.default_rng(0).standard_normal((300, 2)) @ np.linalg.cholesky(
        m.noise_cov).T
    # the innovations form driven by e alone (u = 0): x+ = A x + K e, y = C x + e
    aug = sysid.StateSpaceModel(m.A, np.hstack([m.B, m.K]), m.C,
                                np.hstack([np.zeros((2, 1)), np.eye(2)]), dt=0.5)
    v = aug.simulate(np.hstack([np.zeros((300, 1)), e]))
    assert np.allclose(sysid.noise2meas(m).simulate(e), v, atol=1e-12)
    h = sysid.noise2meas(m, "normalize")
    assert np.allclose(h.D @ h.D.T, m.noise_cov) and np.allclose(h.B, m.K @ h.D)


def test_ar1_spectrum_is_analytic():
    a, lam, dt = 0.7, 0.25, 0.2
    m = sysid.StateSpaceModel([[a]], np.zeros((1, 0)), [[a]], K=[[1.0]], noise_cov=[[lam]],
                              dt=dt)  # y(t) = e(t) / (1 - a q^-1)
    w = np.linspace(0, np.pi / dt, 7)
    expected = 2 * dt * lam / np.abs(1 - a * np.exp(-1j * w * dt)) ** 2
    assert np.allclose(sysid.spectrum(m, omega=w).psd("y0").real, expected, rtol=1e-12)


def test_fitted_spectrum_matches_welch():
    rng = np.random.default_rng(3)
    n = 2 ** 15
    e = rng.standard_normal(n)
    y = np.zeros(n)
    for t in range(2, n):  # ARMA(2, 1)
        y[t] = 1.5 * y[t - 1] - 0.7 * y[t - 2] + e[t] + 0.5 * e[t - 1]
    data = sysid.IOData(u=np.zeros((n, 0)), y=y[:, None], dt=0.01)
    m = sysid.arma(data, 2, 1)
    welch = sysid.spectra(data, nperseg=512)
    model = sysid.spectrum(m, omega=welch.omega[1:-1])
    ratio = model.psd("y0").real / welch.psd("y0").real[1:-1]
    assert np.median(np.abs(np.log(ratio))) < 0.1  # Welch's own scatter at 64 segments


def test_uncertainty_carried():
    rng = np.random.default_rng(1)
    true = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], K=[[0.5]])
    u, e = rng.standard_normal(800), 0.2 * rng.standard_normal(800)
    aug = sysid.StateSpaceModel(true.A, [[1.0, 0.5]], true.C, [[0.0, 1.0]])
    y = aug.simulate(np.column_stack([u, e]))
    m = sysid.ssest(sysid.IOData(u=u, y=y), 1)
    p, sd = m.poles(std=True)
    ph, sdh = sysid.noise2meas(m).poles(std=True)
    assert np.allclose(p, ph) and np.allclose(sd, sdh)


def test_refusals():
    with pytest.raises(DataError, match="no noise covariance"):
        sysid.spectrum(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]))
    m = _innovation_model()
    with pytest.raises(DataError, match="'innovations' or 'normalize'"):
        sysid.noise2meas(m, "white")
    with pytest.raises(DataError, match="non-negative"):
        sysid.spectrum(m, omega=[-1.0])
    with pytest.raises(DataError, match="discrete model"):
        sysid.spectrum(np.eye(2))
