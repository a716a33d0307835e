"""Best linear approximation (robust method) and the random-odd multisine."""

import numpy as np
import pytest

import sysid
from sysid.errors import DataError

G = sysid.StateSpaceModel([[1.2, -0.5], [1.0, 0.0]], [[1.0], [0.0]], [[0.2, 0.1]], dt=1.0)


def _records(f, R, n=512, P=3, noise=0.0, seed=0):
    rng = np.random.default_rng(seed)
    us = [sysid.multisine(n, band=(0, 0.9), phases="random", seed=seed + r, periods=P)
          for r in range(R)]
    ys = [f(G.simulate(u)) + noise * rng.standard_normal((n * P, 1)) for u in us]
    return sysid.IOData(us, ys, 1.0)


def test_linear_noise_free_is_exact():
    d = _records(lambda x: x, 2)
    f = sysid.bla(d, periods=3, transient=1)
    assert np.max(np.abs(f.response - G.freqresp(f.omega))) < 1e-10
    assert np.max(f.info["distortion_std"]) < 1e-10


def test_wiener_bla_matches_bussgang():
    # Wiener system x = G u, y = x + 0.2 x^3 under a Gaussian-like input: the BLA is
    # G * E[f'(x)] = G (1 + 0.6 var(x)) (Bussgang); random-phase multisines of 230 lines are
    # asymptotically Gaussian, the difference O(1/lines) is far below the band used here.
    d = _records(lambda x: x + 0.2 * x**3, 16, seed=3)
    f = sysid.bla(d, periods=3, transient=1)
    var_x = np.mean([np.var(G.simulate(u)) for u, _ in d.experiments])
    theory = G.freqresp(f.omega) * (1 + 0.6 * var_x)
    z = np.abs(f.response - theory).ravel() / f.std.ravel()
    assert np.mean(z < 3.0) > 0.95
    rel = np.abs(np.mean(f.response / theory) - 1)
    assert rel < 0.01
    # the distortion std is what the spread over realisations says, and is not noise
    assert np.all(f.info["noise_std"] < 1e-10)
    assert np.all(f.info["distortion_std"] > 0)


def test_noise_std_is_calibrated():
    # linear system, white output noise: |G_bla - G|^2 / std^2 follows F(2, dof) with the
    # dof of the estimated variance, mean dof / (dof - 2). R = 8 realisations (dof 14, mean
    # 7/6, std of the mean over 230 lines 0.09: bound 0.35 is ~4 sigma); the noise part from
    # 8 x 2 period differences (dof 32, mean 16/15, std of the mean 0.05: bound 0.2).
    d = _records(lambda x: x, 8, P=4, noise=0.05, seed=7)
    f = sysid.bla(d, periods=4, transient=1)
    err2 = np.abs(f.response - G.freqresp(f.omega)) ** 2
    assert abs(np.mean(err2 / f.std ** 2) - 14 / 12) < 0.35
    assert abs(np.mean(err2 / f.info["noise_std"] ** 2) - 32 / 30) < 0.2


def test_bla_model_recovers_linear_block():
    d = _records(lambda x: x, 2)
    m = sysid.bla_model(sysid.bla(d, periods=3, transient=1), 2)
    assert np.allclose(np.sort_complex(m.poles()), np.sort_complex(G.poles()), atol=1e-6)


def test_random_odd_grid():
    u = sysid.multisine(256, band=(0, 1), phases="random", grid="random-odd", seed=2)
    k = np.flatnonzero(np.abs(np.fft.rfft(u[:, 0])) > 1e-8)
    assert np.all(k % 2 == 1)
    odd = np.arange(1, 128, 2)
    assert k.size == odd.size - odd.size // 4
    u2 = sysid.multisine(256, band=(0, 1), grid="odd")
    k2 = np.flatnonzero(np.abs(np.fft.rfft(u2[:, 0])) > 1e-8)
    assert np.array_equal(k2, odd)
    with pytest.raises(DataError, match="grid"):
        sysid.multisine(64, grid="even")


def test_bad_input():
    d = _records(lambda x: x, 1)
    with pytest.raises(DataError, match="periods"):
        sysid.bla(sysid.IOData(d.u[:1000], d.y[:1000], 1.0), periods=3)
    with pytest.raises(DataError, match="transient"):
        sysid.bla(d, periods=3, transient=3)
    with pytest.raises(DataError, match="bla"):
        sysid.bla_model(sysid.FRD([0.1], [1.0]), 1)


def test_bla_refuses_an_input_that_does_not_repeat():
    # on white noise cut into "periods" it returned a response 16 % off (median), 121 % at
    # worst, without a word
    rng = np.random.default_rng(3)
    u = rng.standard_normal((1024, 1))
    g = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]])
    with pytest.raises(sysid.DataError, match="does not repeat every 256 samples"):
        sysid.bla(sysid.IOData(u, g.simulate(u)), periods=4)


def test_periods_auto_detects_them_as_pem_does():
    # bla(data, "auto") was refused ("periods must be a positive integer") where pem, ssest,
    # tfest and oe take it; the F-16 records hold 9 periods, and bla(data, 8) is refused
    d = _records(lambda x: x + 0.2 * x**3, 2, P=4)
    cut = sysid.IOData([u[:-100] for u, _ in d.experiments],   # a trailing partial period
                       [y[:-100] for _, y in d.experiments], 1.0)
    auto = sysid.bla(cut, "auto")
    whole = sysid.IOData([u[:3 * 512] for u, _ in d.experiments],
                         [y[:3 * 512] for _, y in d.experiments], 1.0)
    want = sysid.bla(whole, periods=3, transient=1)
    np.testing.assert_allclose(auto.response, want.response, rtol=1e-12)
    assert auto.info["periods"] == 3 and auto.info["transient"] == 1
    assert auto.info["periodicity"]["period"] == 512
    assert auto.info["periodicity"]["unused_samples"] == [412, 412]
    both = sysid.bla(cut, "auto", transient=0)
    assert both.info["transient"] == 0
    rng = np.random.default_rng(4)
    u = rng.standard_normal((1024, 1))
    with pytest.raises(sysid.DataError, match="does not repeat.*spa"):
        sysid.bla(sysid.IOData(u, G.simulate(u), 1.0), "auto")
