"""How sure tfest/oe on periodic data are (issues 26/28): the std of the lines comes from a
few periods and is itself uncertain, so the covariance is scaled by the residual scale
``2 V / (n_residuals - rank)`` (the rule of pem's and greyest's frequency paths). Monte Carlo
over noise realisations: the predicted std within 20 % of the sample std, the 95 % intervals
covering 90-99 % of the runs, from 8 periods on. With 4 periods the std of the lines is so
uncertain that the estimate itself is noisier by about (P - 2) / (P - 3) than any residual
scale can see (predicted / sample std 0.84-0.87 with 16 lines, tending to 0.71 with many):
the docstrings say so, and that case is not claimed here."""

from __future__ import annotations

import numpy as np
import pytest
from test_tfest_periodic import DEN, NUM

import sysid

TRUE = np.array(DEN[1:] + NUM)      # a1, a2, b0, b1


def monte_carlo(periods, runs, n_per=64, seed=1):
    """Estimates and predicted std of ``[a1, a2, b0, b1]`` over ``runs`` noise draws."""
    g = sysid.TransferFunction([0.0] + NUM, DEN, dt=1.0)
    u = sysid.multisine(n_per, band=(0, 0.5), periods=periods, seed=0)
    y0 = g.simulate(np.vstack([np.tile(u[:n_per], (20, 1)), u]))[20 * n_per:]
    rng = np.random.default_rng(seed)
    sd = 0.1 * float(np.std(y0))
    est, std = [], []
    for _ in range(runs):
        G = sysid.tfest(sysid.IOData(u, y0 + sd * rng.standard_normal(y0.shape), dt=1.0),
                        2, 1, dt=1.0, periods=periods)
        free = ~G.parameters.fixed
        est.append(G.parameters.value[free])
        std.append(G.parameters.std[free])
    return np.array(est), np.array(std)


@pytest.mark.parametrize("periods", [8, 16])
def test_predicted_std_and_coverage_match_monte_carlo(periods):
    est, std = monte_carlo(periods, 300)
    assert np.allclose(est.mean(0), TRUE, atol=0.2 * est.std(0).max())   # unbiased
    ratio = std.mean(0) / est.std(0, ddof=1)
    assert np.all((ratio > 0.8) & (ratio < 1.2)), ratio
    cover = np.mean(np.abs(est - TRUE) <= 1.96 * std)
    assert 0.90 <= cover <= 0.99, cover


def test_std_does_not_depend_on_the_scale_of_the_frd_std():
    """The residual scale makes the covariance follow the spread of the residuals: an FRD
    whose std is ten times too large (or small) reports the same parameter std."""
    g = sysid.TransferFunction([0.0] + NUM, DEN, dt=1.0)
    w = np.linspace(0.05, 3.0, 40)
    h = g.freqresp(w)
    rng = np.random.default_rng(3)   # complex noise of std 0.01: 0.01/sqrt(2) per part
    noise = 0.01 / np.sqrt(2) * (rng.standard_normal(h.shape)
                                 + 1j * rng.standard_normal(h.shape))
    s = [sysid.tfest(sysid.FRD(w, h + noise, std=np.full(h.shape, k), dt=1.0), 2, 1, dt=1.0)
         for k in (0.01, 0.1)]
    np.testing.assert_allclose(s[0].parameters.std, s[1].parameters.std, rtol=1e-6)
    assert s[0].info["residual_scale"][0, 0] == pytest.approx(
        100 * s[1].info["residual_scale"][0, 0])
    assert 0.5 < s[0].info["residual_scale"][0, 0] < 2.0   # right std, right model: about 1


def test_oe_reports_the_same_covariance_as_tfest():
    g = sysid.TransferFunction([0.0] + NUM, DEN, dt=1.0)
    u = sysid.multisine(64, band=(0, 0.5), periods=4, seed=0)
    y0 = g.simulate(np.vstack([np.tile(u[:64], (20, 1)), u]))[20 * 64:]
    d = sysid.IOData(u, y0 + 0.05 * np.random.default_rng(5).standard_normal(y0.shape),
                     dt=1.0)
    G = sysid.tfest(d, 2, 1, dt=1.0, periods=4)
    m = sysid.oe(d, 2, 2, 1, periods=4)
    sg = G.parameters.std[~G.parameters.fixed]            # a1 a2 b0 b1
    np.testing.assert_allclose(np.sqrt(np.diag(m.covariance[0])), np.r_[sg[2:], sg[:2]],
                               rtol=1e-8)
    np.testing.assert_allclose(m.info["residual_scale"], G.info["residual_scale"])
