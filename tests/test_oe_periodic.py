"""oe on periodic data: B/F fitted on the excited lines by tfest's frequency-response fit
(issue 28): exactness, the model class and its uncertainty, agreement with the time-domain
oe within the predicted std, "auto"'s fallback, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from test_tfest_periodic import DEN, NUM, record

import sysid
from sysid.errors import DataError


def test_noise_free_recovered_exactly_in_oe_form():
    g = sysid.TransferFunction(NUM, DEN, dt=1.0)
    m = sysid.oe(record(g), 2, 2, 1, periods=4)
    assert isinstance(m, sysid.PolynomialModel) and m.info["domain"] == "frequency"
    np.testing.assert_allclose(m.b[0][0], NUM, rtol=1e-8)
    np.testing.assert_allclose(m.f[0][0], DEN[1:], rtol=1e-8)
    assert m.nk[0, 0] == 1 and m.info["periods"] == 4
    assert m.noise_variance[0] < 1e-20


@pytest.mark.parametrize("nb, nf, nk", [(1, 1, 0), (3, 1, 2)])
def test_feedthrough_and_long_numerator(nb, nf, nk):
    num = [0.4, -0.3, 0.25][:nb]
    den = [1.0, -0.6]
    # B(q) q^-nk / F(q) as a TransferFunction in z: numerator and denominator in z^-1
    b = np.concatenate([np.zeros(nk), num])
    k = max(b.size, len(den))
    g = sysid.TransferFunction(np.pad(b, (0, k - b.size)), np.pad(den, (0, k - len(den))),
                               dt=1.0)
    m = sysid.oe(record(g), nb, nf, nk, periods=4)
    np.testing.assert_allclose(m.b[0][0], num, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(m.f[0][0], den[1:], rtol=1e-8)


def test_two_inputs():
    g = sysid.TransferFunction([[NUM, [0.3]]], [[DEN, [1.0, -0.7]]], dt=1.0)
    m = sysid.oe(record(g, n_in=2), [[2, 1]], [[2, 1]], [[1, 1]], periods=4)
    np.testing.assert_allclose(m.b[0][0], NUM, rtol=1e-8)
    np.testing.assert_allclose(m.b[0][1], [0.3], rtol=1e-8)
    np.testing.assert_allclose(m.f[0][1], [-0.7], rtol=1e-8)


def test_noisy_agrees_with_time_domain_within_predicted_std():
    g = sysid.TransferFunction(NUM, DEN, dt=1.0)
    data = record(g, periods=8, noise=0.05, seed=3)
    mf = sysid.oe(data, 2, 2, 1, periods=8)
    mt = sysid.oe(data, 2, 2, 1)
    sf = mf.uncertainty.std
    assert mf.uncertainty.names == mt.uncertainty.names
    assert np.all(sf > 0) and np.all(sf < 0.02)
    diff = mf.uncertainty.theta - mt.uncertainty.theta
    assert np.all(np.abs(diff) < 4 * sf), diff / sf
    truth = np.concatenate([NUM, DEN[1:]])
    assert np.all(np.abs(mf.uncertainty.theta - truth) < 4 * sf)
    # the output noise variance from the periods' average (0.05^2)
    assert 0.7 < mf.noise_variance[0] / 0.05 ** 2 < 1.3


def test_auto_falls_back_on_non_periodic_data():
    g = sysid.TransferFunction(NUM, DEN, dt=1.0)
    u = np.random.default_rng(0).standard_normal(1000)
    m = sysid.oe(sysid.IOData(u, g.simulate(u), dt=1.0), 2, 2, 1, periods="auto")
    assert "domain" not in m.info
    assert m.info["periodicity"]["reason"].startswith("time domain")
    np.testing.assert_allclose(m.f[0][0], DEN[1:], atol=1e-6)


def test_bad_input():
    g = sysid.TransferFunction(NUM, DEN, dt=1.0)
    data = record(g, periods=4)
    with pytest.raises(DataError, match="does not divide"):
        sysid.oe(data, 2, 2, 1, periods=3)
    with pytest.raises(DataError, match="at least 2"):
        sysid.oe(data, 2, 2, 1, periods=4, transient=3)
    with pytest.raises(DataError, match="nb >= 1"):
        sysid.oe(data, 0, 2, 1, periods=4)
    with pytest.raises(DataError, match="leave init out"):
        sysid.oe(data, 2, 2, 1, periods=4, init=sysid.arx(data, 2, 2, 1))
