"""Defects found by a sweep of the non-parametric and frequency-domain tools (issue 26)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

import sysid
from sysid.errors import DataError, ShapeError


def _white(n: int = 4096, seed: int = 0) -> sysid.IOData:
    return sysid.IOData(u=None, y=np.random.default_rng(seed).standard_normal(n))


def test_nfft_shorter_than_nperseg_is_refused() -> None:
    # np.fft.rfft(n=64) cut every 128-sample segment to its first 64 samples: the density
    # of unit white noise came out 0.96 instead of 2 (scipy refuses nfft < nperseg)
    d = _white()
    with pytest.raises(DataError, match=r"nfft \(64\) must be at least nperseg \(128\)"):
        sysid.spectra(d, nperseg=128, nfft=64)
    u = np.random.default_rng(1).standard_normal(4096)
    with pytest.raises(DataError, match="nfft"):
        sysid.welch_frf(sysid.IOData(u, np.convolve(u, [1.0, 0.5])[:4096]), nperseg=128, nfft=64)
    with pytest.raises(DataError, match="nfft"):
        sysid.spectra(d, nperseg=128, nfft=200.5)
    # zero padding is as scipy's
    s = sysid.spectra(d, nperseg=128, nfft=256)
    f, p = signal.welch(d.y[:, 0], nperseg=128, nfft=256)
    np.testing.assert_allclose(s.hz, f)
    np.testing.assert_allclose(s.psd("y0"), p, rtol=1e-10)


def test_etfe_smoothing_wider_than_the_spectrum_is_refused() -> None:
    # a frequency window wider than the n bins of the circular spectrum wrapped onto bins it
    # already held; 1 / sum(W^2) counted them again: for n = 256 and smoothing = 1000 the
    # sample spread of the estimate was 1.56 times its std (the band far too narrow)
    rng = np.random.default_rng(2)
    u = rng.standard_normal(256)
    d = sysid.IOData(u, u + rng.standard_normal(256))
    with pytest.raises(DataError, match="smoothing = 1000 bins is wider than the spectrum"):
        sysid.etfe(d, smoothing=1000)
    assert sysid.etfe(d, smoothing=256).std is not None


@pytest.mark.parametrize("call", [
    lambda d: sysid.welch_frf(d, window="nonsense"),
    lambda d: sysid.spectra(d, window="nonsense"),
    lambda d: sysid.coherence(d, window="nonsense"),
    lambda d: sysid.periodogram(d, window="nonsense"),
    lambda d: sysid.etfe(d, smoothing=9, window="nonsense"),
])
def test_an_unknown_window_is_a_data_error(call) -> None:
    # scipy's raw ValueError ('Invalid window name') came through
    u = np.random.default_rng(3).standard_normal(512)
    with pytest.raises(DataError, match="'nonsense' is not a window"):
        call(sysid.IOData(u, u))


def test_spa_refuses_an_empty_or_matrix_grid() -> None:
    # an empty omega was numpy's 'zero-size array to reduction operation maximum'; a 2-D one
    # was flattened without a word
    u = np.random.default_rng(4).standard_normal(600)
    d = sysid.IOData(u, u, dt=0.1)
    with pytest.raises(DataError, match="non-empty 1-D array"):
        sysid.spa(d, lags=20, omega=[])
    with pytest.raises(DataError, match=r"shape \(2, 2\)"):
        sysid.spa(d, lags=20, omega=[[1.0, 2.0], [3.0, 4.0]])
    assert sysid.spa(d, lags=20, omega=np.array([[1.0], [2.0]])).omega.size == 2


def test_frd_compare_refuses_another_grid() -> None:
    # FRD.compare(other FRD) interpolated the other one linearly onto this grid (the branch
    # that refused different grids was never reached: an FRD has freqresp too); across a
    # resonance the interpolated 'measurement' is made up
    g = sysid.StateSpaceModel([[1.8, -0.95], [1.0, 0.0]], [[1.0], [0.0]], [[0.0, 0.1]], dt=1.0)
    fine = sysid.FRD.from_model(g, np.linspace(0.05, 3.0, 400))
    coarse = sysid.FRD.from_model(g, np.linspace(0.05, 3.0, 9))
    with pytest.raises(DataError, match="different frequency grids"):
        fine.compare(coarse)
    banded = sysid.FRD(fine.omega, fine.response, std=np.full(fine.response.shape, 0.1))
    with pytest.raises(DataError, match="different frequency grids"):
        banded.within_band(coarse)
    assert fine.compare(fine).max_error == 0.0
    assert fine.compare(g).max_error < 1e-12


def test_frd_checks_std_coherence_and_dt() -> None:
    w = np.array([1.0, 2.0])
    # one pair: std and coherence as (n_freq,), as the response itself
    f = sysid.FRD(w, [1.0, 2.0], std=[0.1, 0.2], coherence=[0.5, 1.0])
    assert f.std.shape == (2, 1, 1) and f.coherence.shape == (2, 1, 1)
    assert f.within_band(np.array([1.05, 2.0])).all()
    with pytest.raises(DataError, match="std must be finite and >= 0"):
        sysid.FRD(w, [1.0, 2.0], std=[-0.1, 0.2])
    with pytest.raises(DataError, match="std must be finite"):
        sysid.FRD(w, [1.0, 2.0], std=[np.nan, 0.2])
    with pytest.raises(DataError, match=r"coherence must be in \[0, 1\]"):
        sysid.FRD(w, [1.0, 2.0], coherence=[0.5, 2.0])
    with pytest.raises(DataError, match="dt must be a positive number of seconds"):
        sysid.FRD(w, [1.0, 2.0], dt=-0.1)
    with pytest.raises(ShapeError):
        sysid.FRD(w, np.ones((2, 2, 1)), std=[0.1, 0.2])


def test_bla_leaves_out_lines_a_measured_input_does_not_excite() -> None:
    # a measured input carries periodic power between the multisine's lines (its own
    # distortion, 1e-4 and less of the excited lines'): bla returned Y / U there too, the
    # ratio of two distortions (on the F-16 record 1088 lines for 267 excited, up to 270
    # times the response)
    G = sysid.StateSpaceModel([[0.7]], [[1.0]], [[0.3]], dt=1.0)
    n, P = 512, 4
    lines = np.arange(10, 80, 2)
    rng = np.random.default_rng(5)
    us, ys = [], []
    for r in range(3):
        ref = sysid.multisine(n, lines=lines, phases="random", seed=r, periods=P + 1)
        force = ref + 0.01 * ref**2 - 0.01 * np.mean(ref**2)  # the actuator's distortion
        y = G.simulate(force) + 1e-3 * rng.standard_normal(force.shape)
        us.append(force[n:])
        ys.append(y[n:])
    f = sysid.bla(sysid.IOData(us, ys, 1.0), periods=P)
    np.testing.assert_array_equal(f.info["lines"], lines)
    assert f.info["unexcited_lines"].size > 30
    rel = np.abs(f.response - G.freqresp(f.omega)) / np.abs(G.freqresp(f.omega))
    assert rel.max() < 0.02
    # given lines are taken as they are
    assert sysid.bla(sysid.IOData(us, ys, 1.0), periods=P, lines=lines[:5]).omega.size == 5


def test_bla_keeps_a_shaped_multisine_whole() -> None:
    # amplitudes falling over two decades (power over four) leave no gap between lines
    n = 1024
    lines = np.arange(1, 200)
    amp = np.logspace(0, -2, lines.size)
    rng = np.random.default_rng(6)
    k = np.zeros(n // 2 + 1, dtype=complex)
    k[lines] = amp * np.exp(2j * np.pi * rng.random(lines.size))
    u = np.tile(np.fft.irfft(k, n), 3)
    f = sysid.bla(sysid.IOData(u, 0.5 * u, 1.0), periods=3)
    np.testing.assert_array_equal(f.info["lines"], lines)
    assert f.info["unexcited_lines"].size == 0


def test_bla_f16_keeps_the_excited_band() -> None:
    d = sysid.datasets.load_f16()
    f = sysid.bla(d, periods=9, transient=1)
    assert 2.0 - 1e-9 <= f.hz.min() and f.hz.max() <= 15.0 + 1e-9  # the 2-15 Hz multisine
    assert 250 < f.omega.size < 300
    assert np.median(f.info["noise_std"] / np.abs(f.response)) < 0.01


def test_spectra_coherence_correlation_have_to_pandas() -> None:
    # FRD had to_pandas; the other non-parametric results had none
    rng = np.random.default_rng(7)
    u = rng.standard_normal((2048, 2))
    y = u @ np.array([[1.0], [0.5]]) + 0.1 * rng.standard_normal((2048, 1))
    d = sysid.IOData(u, y, dt=0.5)
    s = sysid.spectra(d, nperseg=128)
    df = s.to_pandas()
    row = df[(df.a == "y0") & (df.b == "u1")]
    np.testing.assert_allclose(row.real + 1j * row.imag, s.csd("y0", "u1"))
    np.testing.assert_allclose(row.hz, s.hz)
    c = sysid.coherence(d, nperseg=128)
    df = c.to_pandas()
    np.testing.assert_allclose(df[df.input == "u1"].coherence, c.pair("y0", "u1"))
    np.testing.assert_allclose(df[df.input == "u0"].multiple, c.multiple[:, 0])
    r = sysid.correlation(d, 5)
    df = r.to_pandas()
    sel = df[(df.a == "y0") & (df.b == "u0")]
    np.testing.assert_allclose(sel.r, r.pair("y0", "u0"))
    np.testing.assert_allclose(sel.time, r.lags * 0.5)
    assert set(sel.lag[sel.significant]) == set(r.significant("y0", "u0"))


@pytest.mark.parametrize("estimate", [
    lambda d: sysid.welch_frf(d),
    lambda d: sysid.spa(d, lags=30),
    lambda d: sysid.etfe(d, smoothing=20),
])
def test_dependent_or_constant_inputs_are_named(estimate) -> None:
    # two inputs with power but a singular spectral matrix (u1 = 2 u0) were told "the input
    # has no power at any frequency (an all-zero or constant input?)"
    u = np.random.default_rng(8).standard_normal(2000)
    y = u + 0.1 * np.random.default_rng(9).standard_normal(2000)
    with pytest.raises(sysid.ExcitationError, match="linearly dependent at every frequency"):
        estimate(sysid.IOData(np.c_[u, 2 * u], y))
    with pytest.raises(sysid.ExcitationError, match=r"input\(s\) \['u1'\] are constant"):
        estimate(sysid.IOData(np.c_[u, np.full(2000, 3.0)], y))
    with pytest.raises(sysid.ExcitationError, match="no power at any frequency"):
        estimate(sysid.IOData(np.zeros((2000, 2)), y))


def test_frd_plot_phase_band_is_whole_where_the_circle_holds_the_origin() -> None:
    # a confidence circle around a response smaller than its radius allows any phase; the
    # band was drawn +-90 degrees there (arcsin clipped at 1)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    w = np.array([0.1, 0.2, 0.3])
    f = sysid.FRD(w, [1.0, 0.01, 1.0], std=[0.01, 0.1, 0.01], dt=1.0)
    fig = f.plot()
    band = fig.axes[1].collections[0].get_paths()[0].vertices[:, 1]
    assert band.max() - band.min() >= 360.0 - 1e-9
    plt.close(fig)


def test_an_frd_keeps_its_frequencies_in_order_and_once():
    """Unsorted frequencies were kept as given, and the phase unwrapped along them (a jump of
    2 pi where the order went back); a repeated frequency was kept twice."""
    g = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]], dt=1.0)
    w = np.linspace(0.01, 3.0, 50)
    resp = g.freqresp(w)
    perm = np.random.default_rng(0).permutation(50)
    std = np.abs(resp) * 0.1
    f = sysid.FRD(w[perm], resp[perm], std=std[perm], dt=1.0)
    ordered = sysid.FRD(w, resp, std=std, dt=1.0)
    np.testing.assert_array_equal(f.omega, w)
    np.testing.assert_allclose(f.response, resp)
    np.testing.assert_allclose(f.std, std)
    np.testing.assert_allclose(f.phase, ordered.phase)
    with pytest.raises(sysid.DataError, match="more than once"):
        sysid.FRD(np.r_[w, w[3]], np.r_[resp, resp[3:4]], dt=1.0)


def test_an_experiment_shorter_than_a_segment_is_said_not_dropped_silently():
    rng = np.random.default_rng(0)
    u = [rng.standard_normal(2000), rng.standard_normal(100)]
    y = [signal.lfilter([0.0, 1.0], [1.0, -0.5], x) for x in u]
    with pytest.warns(UserWarning, match=r"experiment\(s\) 1 \(100 samples\) shorter"):
        sysid.welch_frf(sysid.IOData(u=u, y=y), nperseg=256)
