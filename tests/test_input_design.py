"""Input design: PRBS, random signals, multisines, chirps, persistent excitation."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid
from sysid.errors import DataError


def test_prbs_is_a_maximum_length_sequence() -> None:
    for bits in (5, 7, 9):
        period = 2**bits - 1
        u = sysid.prbs(period, n_bits=bits)[:, 0]
        assert set(np.unique(u)) == {-1.0, 1.0}
        assert u.sum() == 1.0  # one more "1" than "0" per period
        # circular autocorrelation: period at lag 0, -1 elsewhere
        r = np.array([np.dot(u, np.roll(u, k)) for k in range(period)])
        assert r[0] == period and np.all(r[1:] == -1)


def test_prbs_options() -> None:
    u = sysid.prbs(100, n_bits=5, hold=4, levels=(0.0, 2.0), n_channels=3)
    assert u.shape == (100, 3) and set(np.unique(u)) == {0.0, 2.0}
    assert np.all(u[0:4] == u[0]) and np.all(u[4:8] == u[4])  # held bits
    p = sysid.prbs(2**7 - 1, n_bits=7, n_channels=2)
    c = np.corrcoef(p.T)[0, 1]
    assert abs(c) < 0.05
    with pytest.raises(DataError, match="low < high"):
        sysid.prbs(10, levels=(1, 1))
    with pytest.raises(DataError, match="n_bits"):
        sysid.prbs(10, n_bits=1)


def test_random_signals_are_seeded_and_band_limited() -> None:
    a = sysid.random_gaussian(4096, band=(0.0, 0.25), std=2.0, seed=3)
    b = sysid.random_gaussian(4096, band=(0.0, 0.25), std=2.0, seed=3)
    np.testing.assert_array_equal(a, b)
    assert a.std() == pytest.approx(2.0)
    P = np.abs(np.fft.rfft(a[:, 0])) ** 2
    cut = int(0.25 * 2048)
    assert P[cut + 5 :].max() < 1e-20 * P.max()
    r = sysid.random_binary(2000, band=(0.0, 0.3), seed=1, n_channels=2)
    assert r.shape == (2000, 2) and set(np.unique(r)) == {-1.0, 1.0}
    with pytest.raises(DataError, match="band"):
        sysid.random_gaussian(10, band=(0.5, 0.2))


def test_multisine_spectrum_and_crest_factor() -> None:
    n = 1024
    u = sysid.multisine(n, band=(0.0, 0.5), rms=0.5, periods=2)
    assert u.shape == (2 * n, 1)
    np.testing.assert_allclose(u[:n], u[n:])
    assert np.sqrt(np.mean(u**2)) == pytest.approx(0.5)
    U = np.abs(np.fft.rfft(u[:n, 0]))
    lines = np.flatnonzero(U > 1e-8 * U.max())
    assert lines[0] == 1 and lines[-1] == 256
    np.testing.assert_allclose(U[lines], U[lines][0], rtol=1e-9)  # flat amplitude spectrum
    random_cf = sysid.crest_factor(sysid.multisine(n, band=(0, 0.5), phases="random", seed=0))
    assert sysid.crest_factor(u)[0] < 1.8 < random_cf[0] + 0.5  # Schroeder is low
    assert sysid.crest_factor(u)[0] < random_cf[0]


def test_mimo_multisine_interleaves_lines() -> None:
    n = 256
    u = sysid.multisine(n, band=(0.0, 1.0), n_channels=2)
    U = np.abs(np.fft.rfft(u, axis=0))
    on = U > 1e-8 * U.max()
    assert not np.any(on[:, 0] & on[:, 1])
    assert abs(int(on[:, 0].sum()) - int(on[:, 1].sum())) <= 1
    with pytest.raises(DataError, match="FFT line"):
        sysid.multisine(8, band=(0.9, 1.0), n_channels=3)


def test_chirp_sweeps() -> None:
    u = sysid.chirp(2000, 0.001, 1.0, 50.0, method="linear")[:, 0]
    # instantaneous frequency rises: count zero crossings in the two halves
    z = np.flatnonzero(np.diff(np.sign(u)) != 0)
    assert (z >= 1000).sum() > 2 * (z < 1000).sum()
    with pytest.raises(DataError, match="Nyquist"):
        sysid.chirp(100, 0.01, 1.0, 80.0)


def test_persistent_excitation_orders() -> None:
    t = np.arange(1000)
    rng = np.random.default_rng(0)
    assert sysid.persistent_excitation_order(np.sin(0.4 * t), 10) == 2
    assert sysid.persistent_excitation_order(np.sin(0.4 * t) + np.sin(1.3 * t), 10) == 4
    assert sysid.persistent_excitation_order(np.ones(100), 10) == 1
    assert sysid.persistent_excitation_order(rng.standard_normal(1000), 30) == 30
    assert sysid.persistent_excitation_order(sysid.prbs(1000), 12) == 12
    # two inputs where the second copies the first: not even order 1
    x = rng.standard_normal(500)
    assert sysid.persistent_excitation_order(np.column_stack([x, 2 * x]), 5) == 0
    # a list of experiments
    assert sysid.persistent_excitation_order([rng.standard_normal(50)] * 3, 8) == 8
    with pytest.raises(DataError, match="no inputs"):
        sysid.persistent_excitation_order(np.zeros((10, 0)), 3)
    # a record (MATLAB's pexcit(data)): its inputs, every experiment; it was refused
    sine = np.sin(0.4 * t)[:, None]
    rec = sysid.IOData([sine[:500], sine[500:]], [sine[:500], sine[500:]], 0.1)
    assert sysid.persistent_excitation_order(rec, 10) == 2
    with pytest.warns(sysid.ExcitationWarning, match="order 2 only"):
        assert sysid.check_excitation(rec, order=2) == 2
    with pytest.raises(DataError, match="no inputs"):
        sysid.persistent_excitation_order(sysid.IOData(y=sine), 3)


def test_check_excitation_warns() -> None:
    t = np.arange(600)
    with pytest.warns(sysid.ExcitationWarning, match="order 2 only"):
        got = sysid.check_excitation(np.sin(0.3 * t), order=4)
    assert got == 2
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sysid.check_excitation(np.random.default_rng(1).standard_normal(600), order=4)


def _fourth_order() -> sysid.StateSpaceModel:
    A = np.diag([0.7, 0.5, -0.4, 0.2])
    C = np.array([[1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 0.0, 1.0]])
    return sysid.StateSpaceModel(A, np.ones((4, 1)), C)


def _record(u: np.ndarray) -> sysid.IOData:
    noise = 1e-3 * np.random.default_rng(0).standard_normal((u.shape[0], 2))
    return sysid.IOData(u=u, y=_fourth_order().simulate(u) + noise)


def test_subspace_fit_warns_on_a_sinusoidal_input() -> None:
    t = np.arange(800)
    # two sinusoids: persistently exciting of order 4, enough for the engine's rank check on
    # the 4 future input rows, not for a 4th-order model (needs order 8)
    u = (np.sin(0.3 * t) + np.sin(1.1 * t))[:, None]
    est = sysid.SubspaceEstimator(_record(u), horizon=4)
    with pytest.warns(sysid.ExcitationWarning, match="order 4 only.*order 4 needs order 8"):
        est.fit(order=4)


def test_single_sinusoid_is_refused_by_the_engine() -> None:
    u = np.sin(0.3 * np.arange(800))[:, None]
    with pytest.raises(sysid.ExcitationError, match="not persistently exciting"):
        sysid.SubspaceEstimator(_record(u), horizon=4).fit(order=4)


def test_subspace_fit_is_quiet_on_white_noise() -> None:
    u = np.random.default_rng(0).standard_normal((800, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = sysid.SubspaceEstimator(_record(u), horizon=4).fit(order=4)
    assert model.nstates == 4


def test_lagged_gram_equals_hankel_product() -> None:
    from sysid.data.input_design import _lag_gram

    rng = np.random.default_rng(4)
    us = [rng.standard_normal((40, 2)), rng.standard_normal((25, 2)), rng.standard_normal((3, 2))]
    mo = 6
    ref = np.zeros((mo * 2, mo * 2))
    cols = 0
    for x in us:
        k = x.shape[0] - mo + 1
        if k < 1:
            continue
        H = np.hstack([x[i : i + k] for i in range(mo)])
        ref += H.T @ H
        cols += k
    G, c = _lag_gram(us, mo)
    assert c == cols
    np.testing.assert_allclose(G, ref, rtol=1e-12, atol=1e-12)


# ------------------------------------------ issue 26: the data layer's sweep (input design)
def test_multisine_refuses_non_integer_lines() -> None:
    # lines=[3.7, 5.2] excited bins 3 and 5 without a word
    with pytest.raises(DataError, match=r"integers.*\[3.7, 5.2\]"):
        sysid.multisine(64, lines=[3.7, 5.2])
    u = sysid.multisine(64, lines=[3.0, 5])  # integer-valued floats are bins
    k = np.flatnonzero(np.abs(np.fft.rfft(u[:, 0])) > 1e-8)
    np.testing.assert_array_equal(k, [3, 5])


def test_crest_factor_and_chirp_refuse_degenerate_input() -> None:
    with pytest.raises(DataError, match=r"channel\(s\) \[1\] are all zero"):
        sysid.crest_factor(np.column_stack([np.ones(4), np.zeros(4)]))
    np.testing.assert_allclose(sysid.crest_factor(np.array([1.0, -1, 1, -3])),
                               3 / np.sqrt(3.0))
    with pytest.raises(DataError, match="at least 2 samples"):
        sysid.chirp(1, 0.01, 0.1, 10)
    with pytest.raises(DataError, match="dt must be a positive number"):
        sysid.chirp(100, -0.01, 0.1, 10)


def test_covariance_order_never_falls_as_max_order_grows():
    # the lag covariance of n lags was formed from N - max_order + 1 columns for every n:
    # white noise of 100 samples gave 50 at max_order=50 and 1 at max_order=100
    u = np.random.default_rng(0).standard_normal(100)
    got = [sysid.persistent_excitation_order(u, mo, method="covariance")
           for mo in (10, 30, 50, 60, 100)]
    assert got == sorted(got) and got[0] == 10 and got[-1] == 50


def test_a_linear_chirp_may_start_at_zero_hertz():
    # chirp(..., f0=0) was refused ("f0, f1 must lie in (0, nyq]") for every method, though a
    # linear or quadratic sweep from DC is what scipy.signal.chirp and MATLAB's chirp give
    from scipy import signal

    t = np.arange(1000) * 0.01
    for method in ("linear", "quadratic"):
        u = sysid.chirp(1000, 0.01, 0.0, 20.0, method=method)
        np.testing.assert_allclose(u[:, 0], signal.chirp(t, 0.0, t[-1], 20.0, method=method))
    for method in ("logarithmic", "hyperbolic"):
        with pytest.raises(sysid.DataError, match="cannot start or end at 0 Hz.*'linear'"):
            sysid.chirp(1000, 0.01, 0.0, 20.0, method=method)
    with pytest.raises(sysid.DataError, match="two different frequencies in \\[0, 50\\] Hz"):
        sysid.chirp(1000, 0.01, 1.0, 60.0)
