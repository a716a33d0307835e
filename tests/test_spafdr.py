"""MATLAB's spafdr: frequency-dependent resolution, calibrated bands, MIMO, bad input."""

import numpy as np
import pytest

import sysid

RES = sysid.StateSpaceModel([[1.6, -0.9], [1.0, 0.0]], [[1.0], [0.0]], [[0.1, 0.0]])


def test_noise_free_response_on_a_logarithmic_grid():
    rng = np.random.default_rng(0)
    u = rng.standard_normal((20000, 1))
    frd = sysid.spafdr(sysid.IOData(u=u, y=RES.simulate(u)))
    assert frd.omega.size == 128 and frd.method == "spafdr"
    assert np.allclose(np.diff(np.log(frd.omega)), np.log(frd.omega[1] / frd.omega[0]))
    assert frd.omega[-1] == pytest.approx(np.pi)
    err = frd.compare(RES).relative_error
    assert np.median(err) < 0.01 and err.max() < 0.1
    # resolution proportional to frequency above the record's line spacing
    r = frd.info["resolution"]
    assert r[-1] / r[len(r) // 2] == pytest.approx(frd.omega[-1] / frd.omega[len(r) // 2],
                                                   rel=0.05)
    # more lines higher up (at the Nyquist frequency the window has one side only)
    assert np.all(np.diff(frd.info["averages"][len(r) // 2:-1]) > 0)


def test_band_covers_at_its_level():
    # 60 records of a first-order system with output noise: the 95 % circle holds the
    # truth at 92-100 % of (record, frequency) pairs (the one number of degrees of freedom
    # is the smallest over the grid: conservative elsewhere)
    g = sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]])
    inside = []
    for seed in range(60):
        rng = np.random.default_rng(seed)
        u = rng.standard_normal((3000, 1))
        y = g.simulate(u) + 0.5 * rng.standard_normal((3000, 1))
        frd = sysid.spafdr(sysid.IOData(u=u, y=y), n_freq=40, confidence=0.95)
        inside.append(frd.within_band(g).ravel())
    rate = float(np.mean(np.concatenate(inside)))
    assert 0.92 <= rate <= 1.0, rate


def test_two_inputs_two_outputs_from_one_experiment():
    rng = np.random.default_rng(1)
    g = sysid.StateSpaceModel([[0.8, 0.1], [0.0, 0.5]], [[1.0, 0.0], [0.3, 1.0]],
                              [[1.0, 0.0], [0.5, 1.0]])
    u = rng.standard_normal((16000, 2))
    frd = sysid.spafdr(sysid.IOData(u=u, y=g.simulate(u) + 0.05 * rng.standard_normal(
        (16000, 2))), n_freq=30)
    assert frd.response.shape == (30, 2, 2)
    assert np.median(frd.compare(g).relative_error) < 0.05


def test_resolution_trades_bias_for_variance():
    # a smooth response (across a resonance a wide window's bias shows as noise instead)
    rng = np.random.default_rng(2)
    u = rng.standard_normal((8000, 1))
    g = sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]])
    d = sysid.IOData(u=u, y=g.simulate(u) + 0.1 * rng.standard_normal((8000, 1)))
    w = np.linspace(0.2, 2.0, 10)
    fine = sysid.spafdr(d, 0.01, w)
    coarse = sysid.spafdr(d, 0.1, w)
    np.testing.assert_allclose(fine.info["resolution"], 0.01)
    assert np.all(coarse.info["averages"] > 5 * fine.info["averages"])
    assert np.all(coarse.std < fine.std)


def test_bad_requests_name_the_fix():
    rng = np.random.default_rng(3)
    d = sysid.IOData(u=rng.standard_normal(500), y=rng.standard_normal(500), dt=0.1)
    with pytest.raises(sysid.DataError, match="Nyquist"):
        sysid.spafdr(d, omega=[1.0, 100.0])
    with pytest.raises(sysid.DataError, match="positive widths"):
        sysid.spafdr(d, resolution=-1.0)
    with pytest.raises(sysid.DataError, match="one per frequency"):
        sysid.spafdr(d, resolution=[0.1, 0.2], omega=[1.0, 2.0, 3.0])
    with pytest.raises(sysid.DataError, match="time series"):
        sysid.spafdr(sysid.IOData(y=rng.standard_normal(100)))


def test_the_window_at_the_nyquist_frequency_takes_the_mirrored_lines():
    # the grid ends at the Nyquist frequency, where the window held only the lines below it:
    # a pole at z = -0.5 (G = -2 there, real) came out -1.966 - 0.240j (12 % off, complex)
    rng = np.random.default_rng(0)
    g = sysid.StateSpaceModel([[-0.5]], [[1.0]], [[1.0]])
    u = rng.standard_normal((20000, 1))
    frd = sysid.spafdr(sysid.IOData(u=u, y=g.simulate(u)))
    assert frd.omega[-1] == pytest.approx(np.pi)
    top = frd.response[-1, 0, 0]
    assert abs(top.imag) < 1e-12                      # real, as every real system there
    assert abs(top - (-2.0)) < 0.03 * 2.0             # leakage and smoothing only
    # and the lines below zero: a window wider than its frequency mirrors them too
    low = sysid.spafdr(sysid.IOData(u=u, y=g.simulate(u)), resolution=0.05, omega=[0.02])
    assert abs(low.response[0, 0, 0] - g.freqresp([0.02])[0, 0, 0]) < 0.02
