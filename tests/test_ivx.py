"""``sysid.ivx`` (MATLAB's IV with given instruments): exact from noise-free data, unbiased
where coloured noise biases least squares, a calibrated standard deviation (Monte Carlo),
several experiments, and clear errors. The Rust kernel is checked by its doc test too."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.errors import DataError

from conftest import assert_std_calibrated

G = sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]])  # y = q^-1 / (1 - 0.7 q^-1) u


def test_noise_free_exact_and_several_experiments():
    rng = np.random.default_rng(0)
    u1, u2 = rng.standard_normal(300), rng.standard_normal(200)
    y1, y2 = G.simulate(u1), G.simulate(u2)
    m = sysid.ivx(sysid.IOData(u=[u1, u2], y=[y1, y2]), 1, 1, 1, x=[y1, y2])
    assert np.allclose(m.a[0][0], [-0.7], atol=1e-12) and np.allclose(m.b[0][0], [1.0])
    assert m.info["method"] == "ivx"


def test_unbiased_under_coloured_noise():
    rng = np.random.default_rng(1)
    u = rng.standard_normal(20000)
    x = G.simulate(u)
    e = rng.standard_normal(20001)
    y = x + 1.0 * (e[1:] + 0.9 * e[:-1])[:, None]  # output noise: ARX is biased
    data = sysid.IOData(u=u, y=y)
    ls = sysid.arx(data, 1, 1, 1)
    iv = sysid.ivx(data, 1, 1, 1, x=x)
    assert abs(ls.a[0][0][0] + 0.7) > 0.05
    assert abs(iv.a[0][0][0] + 0.7) < 4 * iv.uncertainty.std[0]


def test_standard_deviation_is_calibrated_monte_carlo():
    """200 records with white equation error: the predicted std of a and b within 20 % of
    the sample std, 95 % intervals covering 90-99 %."""
    rng = np.random.default_rng(2)
    est, sd = [], []
    for _ in range(200):
        u = rng.standard_normal(500)
        e = 0.5 * rng.standard_normal(500)
        y = np.zeros(500)
        for t in range(1, 500):
            y[t] = 0.7 * y[t - 1] + u[t - 1] + e[t]
        m = sysid.ivx(sysid.IOData(u=u, y=y), 1, 1, 1, x=G.simulate(u))
        est.append([m.a[0][0][0], m.b[0][0][0]])
        sd.append(m.uncertainty.std[:2])
    assert_std_calibrated(est, sd, [-0.7, 1.0])


def test_refusals():
    u = np.random.default_rng(3).standard_normal(100)
    y = G.simulate(u)
    with pytest.raises(DataError, match="shaped as the outputs"):
        sysid.ivx((u, y), 1, 1, 1, x=y[:50])
    with pytest.raises(DataError, match="non-finite"):
        sysid.ivx((u, y), 1, 1, 1, x=np.full_like(y, np.nan))
    with pytest.raises(DataError, match="one instrument array per experiment"):
        sysid.ivx(sysid.IOData(u=[u, u], y=[y, y]), 1, 1, 1, x=[y])
