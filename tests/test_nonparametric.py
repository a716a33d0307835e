"""Non-parametric estimates: FRF with coherence and confidence bands, spectra, correlation."""

from __future__ import annotations

import runpy
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import signal

import sysid
from sysid.errors import DataError, InsufficientDataError

matplotlib.use("Agg")


def true_system() -> sysid.StateSpaceModel:
    A = np.array([[0.6, 0.2, 0.0], [-0.2, 0.6, 0.0], [0.0, 0.0, -0.5]])
    B = np.array([[1.0, 0.0], [0.5, 1.0], [0.0, 1.0]])
    C = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 0.5]])
    D = np.array([[0.2, 0.0], [0.0, 0.1]])
    return sysid.StateSpaceModel(A, B, C, D, dt=0.1)


def mimo_record(noise: float, n: int = 8000, seed: int = 0) -> sysid.IOData:
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 2))
    y = true_system().simulate(u) + noise * rng.standard_normal((n, 2))
    return sysid.IOData(u=u, y=y, dt=0.1)


ESTIMATORS = {
    "spa": lambda d, **kw: sysid.spa(d, lags=60, **kw),
    "welch": lambda d, **kw: sysid.welch_frf(d, nperseg=128, **kw),
    "etfe": lambda d, **kw: sysid.etfe(d, smoothing=41, **kw),
}


@pytest.mark.parametrize("name", list(ESTIMATORS))
def test_frf_within_its_band_of_the_true_response(name: str) -> None:
    g = true_system()
    frd = ESTIMATORS[name](mimo_record(0.5))
    assert frd.response.shape[1:] == (2, 2)
    inside = frd.within_band(g)
    assert inside.mean() >= 0.95  # 99 % band
    # and the band is not vacuous: at 50 % it holds about half the points
    half = ESTIMATORS[name](mimo_record(0.5), confidence=0.5).within_band(g).mean()
    assert 0.35 < half < 0.65
    assert frd.compare(g).fraction_within_band == pytest.approx(inside.mean())


@pytest.mark.parametrize("name", ["spa", "welch"])
def test_coherence_near_one_without_noise_and_lower_with(name: str) -> None:
    clean = ESTIMATORS[name](mimo_record(0.0))
    noisy = ESTIMATORS[name](mimo_record(1.0))
    mc_clean = clean.info["multiple_coherence"]
    mc_noisy = noisy.info["multiple_coherence"]
    assert np.median(mc_clean) > 0.97
    assert np.median(mc_noisy) < np.median(mc_clean) - 0.1
    # pairwise coherences add up to the multiple coherence for independent inputs
    assert np.median(np.abs(clean.coherence.sum(axis=2) - mc_clean)) < 0.05


def test_coherence_function_matches_scipy() -> None:
    d = mimo_record(0.5)
    c = sysid.coherence(d, nperseg=256)
    for i in range(2):
        for j in range(2):
            f, ref = signal.coherence(d.u[:, j], d.y[:, i], fs=10.0, nperseg=256)
            np.testing.assert_allclose(c.values[:, i, j], ref, atol=1e-10)
            np.testing.assert_allclose(c.hz, f)
    assert c.pair("y1", "u0").shape == f.shape
    assert c.band(0.6).dtype == bool
    with pytest.raises(DataError, match="unknown pair"):
        c.pair("u0", "y0")


def test_etfe_equals_y_over_u_on_the_fft_grid() -> None:
    rng = np.random.default_rng(0)
    u = rng.standard_normal(256)
    y = np.convolve(u, [0.5, 1.0, -0.3])[:256] + 0.1 * rng.standard_normal(256)
    frd = sysid.etfe(sysid.IOData(u=u, y=y, dt=0.5))
    np.testing.assert_allclose(frd.response[:, 0, 0], np.fft.rfft(y) / np.fft.rfft(u),
                               rtol=1e-12)
    np.testing.assert_allclose(frd.omega, 2 * np.pi * np.fft.rfftfreq(256, 0.5))
    assert frd.std is None


def test_etfe_mimo_from_as_many_experiments_as_inputs() -> None:
    g = true_system()
    rng = np.random.default_rng(1)
    us = [rng.standard_normal((512, 2)) for _ in range(2)]
    d = sysid.IOData(u=us, y=[g.simulate(u) for u in us], dt=0.1)
    frd = sysid.etfe(d)
    # Y = G U exactly for the periodic part; transients make it approximate
    Ys = [np.fft.rfft(y, axis=0) for _, y in d.experiments]
    Us = [np.fft.rfft(u, axis=0) for u, _ in d.experiments]
    Y = np.stack(Ys, axis=2)  # (nf, l, experiments)
    U = np.stack(Us, axis=2)
    np.testing.assert_allclose(frd.response, Y @ np.linalg.inv(U), rtol=1e-8, atol=1e-8)
    with pytest.raises(DataError, match="needs at least 2 experiments"):
        sysid.etfe(d.experiment(0))
    with pytest.raises(DataError, match="equal length"):
        sysid.etfe(d.experiment(0).merge(d.experiment(1).slice(0, 300)))


def test_spectra_match_scipy_welch_and_csd() -> None:
    d = mimo_record(0.5, n=4096)
    s = sysid.spectra(d, nperseg=256)
    f, puu = signal.welch(d.u[:, 0], fs=10.0, nperseg=256)
    np.testing.assert_allclose(s.psd("u0"), puu, rtol=1e-10)
    _, pyu = signal.csd(d.u[:, 1], d.y[:, 0], fs=10.0, nperseg=256)
    np.testing.assert_allclose(s.csd("y0", "u1"), pyu, rtol=1e-10, atol=1e-14)
    p = sysid.periodogram(d)
    _, ref = signal.periodogram(d.y[:, 1], fs=10.0)
    np.testing.assert_allclose(p.psd("y1"), ref, rtol=1e-10, atol=1e-14)
    with pytest.raises(DataError, match="no channel"):
        s.psd("zz")


def test_spectra_average_experiments() -> None:
    d = mimo_record(0.5, n=4096)
    a, b = d.split(0.5)
    both = a.merge(b)
    s = sysid.spectra(both, nperseg=256)
    _, p1 = signal.welch(a.u[:, 0], fs=10.0, nperseg=256)
    _, p2 = signal.welch(b.u[:, 0], fs=10.0, nperseg=256)
    np.testing.assert_allclose(s.psd("u0"), 0.5 * (p1 + p2), rtol=1e-10)


def test_correlation_and_bounds() -> None:
    rng = np.random.default_rng(0)
    u = rng.standard_normal(3000)
    y = np.r_[np.zeros(4), 0.8 * u[:-4]] + 0.3 * rng.standard_normal(3000)
    c = sysid.correlation(sysid.IOData(u=u, y=y), 20, confidence=0.99)
    assert c.significant("y0", "u0").tolist() == [4]
    r = c.pair("y0", "u0")
    uc, yc = u - u.mean(), y - y.mean()
    ref = np.dot(yc[4:], uc[:-4]) / 3000 / np.sqrt(uc.var() * yc.var())
    assert r[c.lags.tolist().index(4)] == pytest.approx(ref)
    np.testing.assert_allclose(c.pair("u0", "y0")[::-1], r)  # r_uy(-tau) = r_yu(tau)
    assert c.pair("u0", "u0")[20] == pytest.approx(1.0)
    assert c.bound == pytest.approx(2.5758 / np.sqrt(3000), rel=1e-4)
    with pytest.raises(InsufficientDataError):
        sysid.correlation(sysid.IOData(u=u[:10], y=y[:10]), 20)


def test_frd_object() -> None:
    g = true_system()
    w = np.linspace(0.1, np.pi / 0.1, 50)
    f = sysid.FRD(w, g.freqresp(w), dt=0.1, input_names=["a", "b"])
    assert f.compare(g).max_error < 1e-12
    assert f.select(outputs="y1", inputs="b").response.shape == (50, 1, 1)
    np.testing.assert_allclose(f.hz, w / (2 * np.pi))
    with pytest.raises(DataError, match="no confidence band"):
        f.within_band(g)
    with pytest.raises(sysid.ShapeError, match="n_freq"):
        sysid.FRD(w, np.zeros((3, 1, 1)))
    with pytest.raises(DataError, match="finite"):
        sysid.FRD([1.0], [[[np.nan]]])


def test_unexcited_frequencies_are_dropped() -> None:
    n = 1024
    u = sysid.multisine(n, lines=np.arange(10, 60), periods=4)
    g = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    d = sysid.IOData(u=u[n:], y=g.simulate(u)[n:])
    frd = sysid.etfe(d)
    assert frd.omega.size == 50  # only the excited lines (every third bin of 3 periods)
    np.testing.assert_allclose(frd.omega, 2 * np.pi * np.arange(10, 60) / n)
    np.testing.assert_allclose(frd.response, g.freqresp(frd.omega), rtol=1e-6)
    assert frd.info["dropped"].size > 0


def test_bad_inputs_to_estimators() -> None:
    ts = sysid.IOData(u=None, y=np.ones(100))
    with pytest.raises(DataError, match="time series"):
        sysid.spa(ts)
    d = mimo_record(0.5, n=200)
    with pytest.raises(DataError, match="noverlap"):
        sysid.welch_frf(d, nperseg=64, noverlap=64)
    with pytest.raises(InsufficientDataError, match="lower nperseg"):
        sysid.welch_frf(d, nperseg=512)
    with pytest.raises(DataError, match="smoothing must exceed"):
        sysid.etfe(d, smoothing=2)
    with pytest.raises(InsufficientDataError, match="lags"):
        sysid.spa(d, lags=500)


def test_plots_draw() -> None:
    d = mimo_record(0.5, n=2000)
    frd = sysid.spa(d)
    fig = frd.plot(models={"true": true_system()})
    assert len(fig.axes) == 3 * 2 * 2
    assert len(d.plot().axes) == 4
    assert sysid.spectra(d).plot() is not None
    assert len(sysid.coherence(d).plot().axes) == 2
    assert sysid.correlation(d, 10).plot("y0", "u0") is not None
    # without the pair (a TypeError before): the last channel against the first
    ax = sysid.correlation(d, 10).plot()
    assert ax.get_ylabel() == f"r({d.output_names[-1]}, {d.input_names[0]})"
    import matplotlib.pyplot as plt

    plt.close("all")


def test_winding_workflow_example(capsys: pytest.CaptureFixture[str]) -> None:
    example = Path(__file__).resolve().parents[1] / "examples" / "winding_workflow.py"
    mod = runpy.run_path(str(example))
    res = mod["main"](sysid.datasets.path("winding"))  # plots are tested elsewhere (slow)
    assert res["dt"] == pytest.approx(0.1)
    est, val = res["estimation"], res["validation"]
    assert (est.n_inputs, est.n_outputs) == (5, 2)
    assert est.n_samples + val.n_samples == res["data"].n_samples
    assert res["spa"].response.shape[1:] == (2, 5)
    assert res["coherence"].values.shape[1:] == (2, 5)
    # all five inputs together explain most of each tension at low frequency
    low = res["coherence"].hz < 0.5
    assert res["coherence"].multiple[low].mean() > 0.6
    assert np.all(res["fit"] > 50)
    # the validation simulation maps back to the record's units
    raw = res["data"].slice(1500).y
    assert np.all(np.abs(np.mean(res["y_original"] - raw, axis=0)) < 0.5)
    assert "validation fit" in capsys.readouterr().out


@pytest.mark.parametrize(
    "fn, a, b",
    [
        (sysid.spa, {"lags": 20}, {"lags": 60}),
        (sysid.spa, {"remove_mean": True}, {"remove_mean": False}),
        (sysid.spa, {"n_freq": 64}, {"n_freq": 128}),
        (sysid.welch_frf, {"nperseg": 128}, {"nperseg": 128, "noverlap": 16}),
        (sysid.welch_frf, {"nperseg": 128}, {"nperseg": 128, "window": "hamming"}),
        (sysid.welch_frf, {"nperseg": 128}, {"nperseg": 128, "nfft": 256}),
        (sysid.etfe, {"smoothing": 21}, {"smoothing": 21, "window": "boxcar"}),
        (sysid.etfe, {"smoothing": 21}, {"smoothing": 41}),
    ],
)
def test_every_option_changes_the_estimate(fn, a, b) -> None:  # type: ignore[no-untyped-def]
    d = mimo_record(0.5, n=3000)
    y_off = sysid.IOData(u=d.u + 1.0, y=d.y + 2.0, dt=d.dt)  # offsets matter for remove_mean
    fa, fb = fn(y_off, **a), fn(y_off, **b)
    assert fa.omega.shape != fb.omega.shape or not np.allclose(fa.response, fb.response)


def test_confidence_level_widens_the_band() -> None:
    d = mimo_record(0.5, n=3000)
    narrow, wide = sysid.spa(d, confidence=0.5), sysid.spa(d, confidence=0.99)
    assert np.all(wide.radius > narrow.radius)
    np.testing.assert_allclose(wide.response, narrow.response)


def test_spectra_detrend_option() -> None:
    x = np.random.default_rng(0).standard_normal(1024) + 5.0
    d = sysid.IOData(u=None, y=x)
    on = sysid.spectra(d, nperseg=128).psd("y0")
    off = sysid.spectra(d, nperseg=128, detrend=False).psd("y0")
    assert off[0] > 100 * on[0]  # the mean shows at zero frequency only without detrending


def test_frd_from_model_and_to_pandas() -> None:
    g = true_system()
    w = np.linspace(0.1, 30.0, 7)
    f = sysid.FRD.from_model(g, w)
    np.testing.assert_allclose(f.response, g.freqresp(w))
    df = sysid.spa(mimo_record(0.5, n=2000), n_freq=16).to_pandas()
    assert len(df) == 16 * 2 * 2
    assert {"omega", "output", "input", "magnitude", "coherence", "std"} <= set(df.columns)
    row = df[(df.output == "y1") & (df.input == "u0")].iloc[3]
    assert row.magnitude == pytest.approx(np.hypot(row.real, row.imag))


@settings(max_examples=15, deadline=None)
@given(st.floats(0.1, 10.0), st.integers(0, 1000), st.sampled_from(["spa", "welch", "etfe"]))
def test_frf_scales_and_permutes_with_the_channels(c: float, seed: int, name: str) -> None:
    d = mimo_record(0.3, n=1500, seed=seed)
    base = ESTIMATORS[name](d)
    scaled = ESTIMATORS[name](sysid.IOData(u=c * d.u, y=d.y[:, ::-1], dt=d.dt))
    np.testing.assert_allclose(scaled.omega, base.omega)
    np.testing.assert_allclose(scaled.response, base.response[:, ::-1, :] / c, rtol=1e-8,
                               atol=1e-10)
    np.testing.assert_allclose(scaled.coherence, base.coherence[:, ::-1, :], atol=1e-10)


def test_band_is_calibrated_with_few_averages() -> None:
    # about 8 Welch segments and a 9-bin smoothing window for 2 inputs: the large-sample
    # circle would hold ~78 % at the 90 % level; the F-distribution band holds ~90 %
    g = true_system()
    cover = []
    for seed in range(8):
        d = mimo_record(0.5, n=1200, seed=seed)
        for frd in (sysid.welch_frf(d, nperseg=256, confidence=0.9),
                    sysid.etfe(d, smoothing=9, confidence=0.9)):
            assert frd.dof is not None and frd.dof < 20
            cover.append(frd.within_band(g).mean())
    assert 0.85 < np.mean(cover) < 0.95
    with pytest.raises(InsufficientDataError, match="increase smoothing"):
        sysid.etfe(mimo_record(0.5, n=400), smoothing=3)


def test_f16_multisine_etfe_over_periods() -> None:
    d = sysid.datasets.load_f16()
    P = 8192  # samples per period; the first period holds the transient
    periods = [d.slice(k * P, (k + 1) * P) for k in range(1, 9)]
    frd = sysid.etfe(periods[0].merge(*periods[1:]), min_power=1e-3)
    # only the multisine's lines are kept: 2..15 Hz on the 400/8192 Hz grid
    assert frd.hz.min() >= 2.0 - 1e-9 and frd.hz.max() <= 15.0 + 1e-9
    assert 250 < frd.omega.size <= round(13 / (400 / P)) + 1
    # averaged over 8 periods, the response is coherent on every kept line
    assert np.percentile(frd.coherence, 5) > 0.99
    assert frd.info["dropped"].size > 3000


def test_spa_refuses_frequencies_above_nyquist():
    # omega in Hz (or past pi/dt) gave aliased values without a word
    rng = np.random.default_rng(0)
    u = rng.standard_normal((600, 1))
    d = sysid.IOData(u, sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]).simulate(u), dt=0.1)
    ok = sysid.spa(d, lags=20, omega=[1.0, np.pi / 0.1])
    assert ok.omega.size == 2
    with pytest.raises(sysid.DataError, match="above the Nyquist frequency"):
        sysid.spa(d, lags=20, omega=[1.0, 40.0])


def test_etfe_removes_the_operating_point_like_spa():
    # smoothed etfe kept the means: near DC it returned the ratio of the means (10.0 for a
    # gain of 7.5) with coherence 1 and a band that excluded the truth
    rng = np.random.default_rng(1)
    g = sysid.StateSpaceModel([[1.5, -0.7], [1, 0]], [[1.0], [0]], [[1.0, 0.5]], dt=0.1)
    u = rng.standard_normal((4000, 1))
    y = g.simulate(u) + 0.1 * rng.standard_normal((4000, 1))
    d = sysid.IOData(u=u + 2.0, y=y + 20.0, dt=0.1)
    e = sysid.etfe(d, smoothing=20)
    k = np.searchsorted(e.omega, [0.016, 0.05])
    assert e.within_band(g)[k].all()
    np.testing.assert_allclose(np.abs(e.response[k, 0, 0]), 7.5, rtol=0.02)
    raw = sysid.etfe(d, smoothing=20, remove_mean=False)  # the old behaviour, on request
    assert abs(abs(raw.response[k[0], 0, 0]) - 7.5) > 1.0


def test_welch_segments_of_a_record_cut_into_experiments():
    """The default segment length was a quarter of the shortest experiment: the dryer cut
    at four gaps into 100-299 samples got 16-sample segments (9 frequencies), where each
    experiment's segments are averaged together: now the largest length every experiment
    holds with seven segments in all (64 samples, 33 frequencies), and a single record's
    default is unchanged (a quarter of it)."""
    a = np.loadtxt(sysid.datasets.path("dryer"))
    cuts = [0, 100, 299, 548, 697, 996]
    d = sysid.IOData([a[s:e, :1] for s, e in zip(cuts, cuts[1:])],
                     [a[s:e, 1:] for s, e in zip(cuts, cuts[1:])], 0.08)
    frd = sysid.welch_frf(sysid.detrend(d, "mean"))
    assert frd.omega.size == 32  # 33 bins less the zero-frequency one
    one = sysid.welch_frf(sysid.detrend(sysid.IOData(a[:, :1], a[:, 1:], 0.08), "mean"))
    assert one.omega.size == 64  # 1000 samples: 128-sample segments, as before
    # the two estimates agree where both are sure (the dryer's band: below 10 rad/s)
    low = frd.omega < 10.0
    g1 = frd.response[low, 0, 0]
    g2 = np.interp(frd.omega[low], one.omega, np.abs(one.response[:, 0, 0]))
    assert np.median(np.abs(np.abs(g1) - g2) / g2) < 0.1
