"""compare(frd, m1, m2, ...): models against frequency-response data, MATLAB's compare with
idfrd data (python/sysid/validation/compare_frd.py)."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest

import sysid
from sysid.errors import DataError

matplotlib.use("Agg")


def _true() -> sysid.StateSpaceModel:
    return sysid.StateSpaceModel([[0.8, 0.3], [-0.3, 0.8]], [[1.0, 0.0], [0.5, 1.0]],
                                 [[1.0, 0.0], [0.2, 0.7]])


def test_fit_is_the_nrmse_of_the_complex_response_per_pair():
    true = _true()
    w = np.linspace(0.05, 3.0, 80)
    frd = sysid.FRD(w, true.freqresp(w), dt=1.0)
    other = sysid.StateSpaceModel(true.A * 0.95, true.B, true.C)
    c = sysid.compare(frd, true, other)
    assert c.fit.shape == (2, 2, 2)
    np.testing.assert_allclose(c.fit[0], 100.0, atol=1e-9)
    g, gm = frd.response, other.freqresp(w)
    for i in range(2):
        for j in range(2):
            ref = 100 * (1 - np.linalg.norm(g[:, i, j] - gm[:, i, j])
                         / np.linalg.norm(g[:, i, j] - g[:, i, j].mean()))
            assert c.fit[1, i, j] == pytest.approx(ref, rel=1e-12)
    assert c.best == 0 and len(c) == 2
    df = c.to_pandas()
    assert len(df) == 8 and set(df.columns) == {"model", "output", "input", "fit"}
    assert "u1->y0" in c.summary() and "FRDCompareSet" in repr(c)
    assert len(c.plot().axes) == 8
    # the model first, as compare(model, data)
    np.testing.assert_allclose(sysid.compare(other, frd).fit[0], c.fit[1])


def test_continuous_models_meet_sampled_data_sampled_and_bad_lines_score_minus_inf():
    ct = sysid.ContinuousStateSpace([[-0.5]], [[1.0]], [[1.0]])
    dt = 0.2
    w = np.linspace(0.1, np.pi / dt * 0.95, 60)
    frd = sysid.FRD(w, ct.sampled(dt).freqresp(w), dt=dt)
    assert sysid.compare(frd, ct).fit[0, 0, 0] == pytest.approx(100.0, abs=1e-8)
    # a pole on the unit circle at a measured line: the response is infinite there
    w1 = np.array([0.0, 0.5, 1.0])
    integ = sysid.StateSpaceModel([[1.0]], [[1.0]], [[1.0]])
    frd1 = sysid.FRD(w1, [2.0, 1.0, 0.5j], dt=1.0)
    assert sysid.compare(frd1, integ).fit[0, 0, 0] == -np.inf
    # a constant measured response: only an exact model fits
    flat = sysid.FRD(w1, np.ones(3), dt=1.0)
    def gain(k: float) -> sysid.StateSpaceModel:
        return sysid.StateSpaceModel(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)),
                                     [[k]])

    assert sysid.compare(flat, gain(1.0)).fit[0, 0, 0] == 100.0
    assert sysid.compare(flat, gain(0.5)).fit[0, 0, 0] == -np.inf


def test_with_std_the_share_inside_the_band_is_reported():
    rng = np.random.default_rng(0)
    true = sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]])
    u = rng.standard_normal(3000)
    y = true.simulate(u) + 0.05 * rng.standard_normal((3000, 1))
    frd = sysid.welch_frf(sysid.IOData(u=u, y=y))
    c = sysid.compare(frd, true, sysid.StateSpaceModel([[0.3]], [[1.0]], [[1.0]]))
    assert c.within_band[0] > 0.9 > c.within_band[1]
    assert "in band" in c.summary() and "within_band" in c.to_pandas()


def test_bad_frequency_comparisons_say_what_to_do():
    true = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    w = np.linspace(0.1, 3.0, 20)
    frd = sysid.FRD(w, true.freqresp(w), dt=1.0)
    with pytest.raises(DataError, match="leave horizon out"):
        sysid.compare(frd, true, horizon=1)
    with pytest.raises(DataError, match="leave x0 out"):
        sysid.compare(frd, true, x0="zero")
    with pytest.raises(DataError, match="has 2 input.*FRD has 1 and 1"):
        sysid.compare(frd, _true())
    with pytest.raises(DataError, match="sample time 0.5"):
        sysid.compare(frd, sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.5))
    with pytest.raises(DataError, match="freqresp"):
        sysid.compare(frd, object())
    # a nonlinear model's freqresp is its linear part's: refused, the part named
    rng = np.random.default_rng(0)
    u = rng.standard_normal(400)
    hw = sysid.nlhw(sysid.IOData(u, true.simulate(u), 1.0), 1, 1, 1, max_iter=5)
    with pytest.raises(DataError, match=r"nonlinear.*model\.linear\(\)"):
        sysid.compare(frd, hw)
    assert sysid.compare(frd, hw.linear()).fit.shape == (1, 1, 1)
