"""``arx(..., integrate_noise=True)`` (MATLAB's ``IntegrateNoise``, ARIX): unbiased where a
drifting disturbance biases plain ARX, predictions that follow the drift, a calibrated
standard deviation (Monte Carlo), and exact recovery from noise-free data."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.errors import DataError

from conftest import assert_std_calibrated


def _record(rng: np.random.Generator, n: int, drift: float = 0.05) -> sysid.IOData:
    u = rng.standard_normal(n)
    y = np.zeros(n)
    e = drift * rng.standard_normal(n)
    v = 0.0
    for t in range(1, n):  # (1 - 0.7 q^-1) y = u(t-1) + e / (1 - q^-1)
        v += e[t]
        y[t] = 0.7 * y[t - 1] + u[t - 1] + v
    return sysid.IOData(u=u, y=y)


def test_noise_free_recovery_and_structure():
    rng = np.random.default_rng(0)
    d = _record(rng, 300, drift=0.0)
    m = sysid.arx(d, 1, 1, 1, integrate_noise=True)
    assert np.allclose(m.a[0][0], [-0.7], atol=1e-12) and np.allclose(m.b[0][0], [1.0])
    assert m.d[0].tolist() == [-1.0] and m.info["integrate_noise"] is True


def test_drift_biases_arx_not_arix_and_predictions_follow_it():
    rng = np.random.default_rng(1)
    d = _record(rng, 3000)
    est, val = sysid.IOData(u=d.u[:2000], y=d.y[:2000]), sysid.IOData(u=d.u[2000:],
                                                                        y=d.y[2000:])
    # the plain fit simulates its own record worse than the mean (the drift is most of the
    # output) and says so; the ARIX fit of the differenced record does not
    with pytest.warns(sysid.SysidWarning, match="worse than its mean.*a drift"):
        plain = sysid.arx(est, 1, 1, 1)
    arix = sysid.arx(est, 1, 1, 1, integrate_noise=True)
    assert abs(plain.a[0][0][0] + 0.7) > 0.05  # the drift pulls the pole toward 1
    assert abs(arix.a[0][0][0] + 0.7) < 4 * arix.uncertainty.std[0]
    p_plain = sysid.compare(val, plain, horizon=1).fit[0, 0]
    p_arix = sysid.compare(val, arix, horizon=1).fit[0, 0]
    assert p_arix > p_plain + 5


def test_standard_deviation_is_calibrated_monte_carlo():
    """200 records: the predicted std of a and b within 20 % of the sample std, 95 %
    intervals covering 90-99 %."""
    rng = np.random.default_rng(2)
    est, sd = [], []
    for _ in range(200):
        m = sysid.arx(_record(rng, 400, drift=0.2), 1, 1, 1, integrate_noise=True)
        est.append([m.a[0][0][0], m.b[0][0][0]])
        sd.append(m.uncertainty.std[:2])
    assert_std_calibrated(est, sd, [-0.7, 1.0])


def test_refusals():
    d = _record(np.random.default_rng(3), 50)
    with pytest.raises(DataError, match="True or False"):
        sysid.arx(d, 1, 1, 1, integrate_noise=[True])
    with pytest.raises(DataError, match="at least 3 samples"):
        sysid.arx(sysid.IOData(u=d.u[:2], y=d.y[:2]), 1, 1, 1, integrate_noise=True)


def test_armax_with_integrated_noise():
    """ARIMAX: (1 - 0.7 q^-1) y = u(t-1) + (1 + 0.5 q^-1) e / (1 - q^-1)."""
    rng = np.random.default_rng(4)
    n = 3000
    u, e = rng.standard_normal(n), 0.1 * rng.standard_normal(n)
    y, v, w = np.zeros(n), 0.0, np.zeros(n)
    for t in range(1, n):
        w[t] = e[t] + 0.5 * e[t - 1]
        v += w[t]
        y[t] = 0.7 * y[t - 1] + u[t - 1] + v
    m = sysid.armax(sysid.IOData(u=u, y=y), 1, 1, 1, 1, integrate_noise=True)
    sd = m.uncertainty.std
    assert m.d[0].tolist() == [-1.0] and m.info["integrate_noise"] is True
    assert abs(m.a[0][0][0] + 0.7) < 4 * sd[0] and abs(m.c[0][0] - 0.5) < 4 * sd[2]
