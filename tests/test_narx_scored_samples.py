"""A NARX model's first ``max_lag`` outputs are its initial condition (copies of the
measured ones), not predictions: compare's fit numbers, residuals' tests and nlarx's own
free-run checks score only the samples after them, by one rule (``given_start``)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid
from sysid.nonlinear.narx import _free_run
from sysid.validation.compare import given_start


def narx_sys(n, seed, noise):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, n)
    e = noise * rng.standard_normal(n)
    y = np.zeros(n)
    for t in range(1, n):
        y[t] = 0.5 * y[t - 1] + u[t - 1] + 0.2 * u[t - 1] ** 2 + e[t]
    return u, y


def nrmse_fit(y, yh):
    return 100 * (1 - np.linalg.norm(y - yh) / np.linalg.norm(y - y.mean()))


@pytest.fixture(scope="module")
def fitted():
    u, y = narx_sys(2000, 3, 0.2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = sysid.nlarx(sysid.IOData(u, y, 1.0), 8, 8, 1, basis=sysid.PolynomialBasis(2),
                        criterion="bic", max_terms=20)
    uv, yv = narx_sys(60, 8, 0.2)
    return m, uv, yv


def test_compare_scores_only_the_samples_the_model_predicts(fitted):
    # compare scored the first max_lag = 8 samples, copies of the measured outputs (zero
    # error): 66.02 % where the 52 samples the model simulates give 61.08 % (nlarx's own
    # free run said 61.08); one step ahead 69.51 against 65.08
    m, uv, yv = fitted
    L = m.max_lag
    assert L == given_start(m) == 8
    r = sysid.compare(sysid.IOData(uv, yv, 1.0), m)
    s = m.simulate(uv, x0=yv[:L]).ravel()
    assert r.start == L and np.array_equal(r.yhat[0][:L, 0], yv[:L])  # kept in yhat
    assert r.fit[0, 0] == pytest.approx(nrmse_fit(yv[L:], s[L:]), abs=1e-9)
    assert r.fit[0, 0] == pytest.approx(61.076, abs=5e-3)
    sse, var, count = _free_run(m, [(uv[:, None], yv[:, None])])  # nlarx's own rule
    assert count == 60 - L
    assert 100 * (1 - np.sqrt(sse[0] / var[0])) == pytest.approx(r.fit[0, 0], abs=1e-9)
    p = m.predict(uv, yv, 1).ravel()
    r1 = sysid.compare(sysid.IOData(uv, yv, 1.0), m, horizon=1)
    assert r1.fit[0, 0] == pytest.approx(nrmse_fit(yv[L:], p[L:]), abs=1e-9)
    assert r1.fit[0, 0] == pytest.approx(65.076, abs=5e-3)


def test_residuals_leave_out_the_copied_start(fitted):
    m, uv, yv = fitted
    L = m.max_lag
    res = sysid.residuals(m, (uv, yv), max_lag=10)
    e = yv - m.predict(uv, yv, 1).ravel()
    assert res.n_samples == 60 - L and res.e[0].shape == (60 - L, 1)
    np.testing.assert_allclose(res.e[0][:, 0], e[L:], atol=1e-12)
    assert not np.any(res.e[0] == 0.0)  # the eight zeros of the copied start are gone


def test_a_record_no_longer_than_max_lag_is_refused(fitted):
    m, uv, yv = fitted
    with pytest.raises(sysid.DataError, match="first 8 outputs"):
        sysid.compare(m, (uv[:8], yv[:8]))
    with pytest.raises(sysid.DataError, match="after the first 8"):
        sysid.residuals(m, (uv[:20], yv[:20]), max_lag=12)


def test_error_spectrum_leaves_out_the_copied_start():
    """``error_spectrum`` took a NARX model's first ``max_lag`` samples (copies of the
    measured outputs, zero error) into its Welch estimate: the same rule as ``compare``."""
    import scipy.signal

    rng = np.random.default_rng(3)
    u = rng.standard_normal(400)
    y = np.zeros(400)
    for t in range(1, 400):
        y[t] = 0.5 * y[t - 1] + u[t - 1] + 0.2 * u[t - 1] ** 2
    y = y + 0.1 * rng.standard_normal(400)
    d = sysid.IOData(u, y[:, None], 1.0)
    m = sysid.nlarx(d, 4, 4, 1, basis=sysid.PolynomialBasis(2))
    spec = sysid.error_spectrum(m, d, nperseg=64)
    cmp = sysid.compare(d, m)
    s = m.max_lag
    assert cmp.start == s
    _, want = scipy.signal.welch((cmp.y[0] - cmp.yhat[0])[s:], fs=1.0, nperseg=64, axis=0)
    np.testing.assert_allclose(spec.error_psd, want, rtol=1e-12)
