"""ssest and n4sid on frequency-response data (MATLAB's ``ssest(idfrd, n)``,
``n4sid(idfrd, n)``): the frequency-domain subspace fit, refined on the lines by pem,
weighted by the FRD's std or uniformly without one (python/sysid/pem/ssest.py,
python/sysid/pem/periodic.py)."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.errors import DataError


def _mimo4() -> sysid.StateSpaceModel:
    A = np.array([[0.6, 0.5, 0.0, 0.0], [-0.5, 0.6, 0.0, 0.0], [0.0, 0.0, -0.2, 0.8],
                  [0.0, 0.0, -0.8, -0.2]])
    return sysid.StateSpaceModel(A, [[1.0, 0.0], [0.2, 0.5], [0.5, 0.1], [-0.3, 1.0]],
                                 [[1.0, 0.0, 0.3, 0.1], [0.0, 0.7, -0.4, 0.5]])


def test_noise_free_response_gives_the_system_to_machine_precision():
    true = _mimo4()
    w = np.linspace(0.02, 3.1, 150)
    frd = sysid.FRD(w, true.freqresp(w), dt=1.0)
    for m in (sysid.n4sid(frd, 4), sysid.ssest(frd, 4)):
        np.testing.assert_allclose(np.sort_complex(m.poles()), np.sort_complex(true.poles()),
                                   atol=1e-9)
        np.testing.assert_allclose(m.freqresp(w), true.freqresp(w), atol=1e-9)
    # n4sid on an FRD is the frequency-domain subspace fit
    np.testing.assert_allclose(sysid.n4sid(frd, 4).freqresp(w),
                               sysid.frd_subspace(frd, 4).freqresp(w), atol=1e-12)
    m = sysid.ssest(frd, 4)
    assert m.info["pem"]["weighting"] == "uniform"  # no std: MATLAB's default
    assert m.info["start"]["method"] == "frd_subspace"
    assert sysid.ssest(frd, "auto").nstates == 4


def test_uniform_weighting_gives_calibrated_pole_uncertainty():
    # Monte Carlo, 300 draws of complex white noise on 60 lines: the predicted standard
    # deviation of the pole (from the residual variance, one level for every line) within
    # 20 % of the sample one, and 95 % intervals covering 90-99 %; a 300-draw sample std is
    # within about 8 % of the true one (2 sigma), so 20 % leaves room for the first-order
    # approximation
    true = sysid.StateSpaceModel([[0.7, 0.4], [-0.4, 0.7]], [[1.0], [0.3]], [[1.0, 0.0]])
    w = np.linspace(0.05, 3.0, 60)
    G = true.freqresp(w)
    rng = np.random.default_rng(5)
    tp = np.linalg.eigvals(true.A)
    tp = tp[np.argmax(tp.imag)]
    P, S = [], []
    for _ in range(300):
        noise = 0.05 / np.sqrt(2) * (rng.standard_normal(G.shape)
                                     + 1j * rng.standard_normal(G.shape))
        m = sysid.ssest(sysid.FRD(w, G + noise, dt=1.0), 2)
        p, s = m.poles(std=True)
        i = int(np.argmax(p.imag))
        P.append(p[i])
        S.append(s[i])
    P, S = np.array(P), np.array(S)
    for part in (np.real, np.imag):
        ratio = float(np.mean(part(S)) / np.std(part(P)))
        assert 0.8 < ratio < 1.2, ratio
        cover = float(np.mean(np.abs(part(P) - part(tp)) < 1.96 * part(S)))
        assert 0.90 <= cover <= 0.99, cover


def test_an_frd_with_std_is_weighted_by_it():
    rng = np.random.default_rng(2)
    true = sysid.StateSpaceModel([[0.8, 0.3], [-0.3, 0.8]], [[1.0], [0.0]], [[1.0, 0.5]])
    u = rng.standard_normal(4000)
    y = true.simulate(u) + 0.05 * rng.standard_normal((4000, 1))
    frd = sysid.welch_frf(sysid.IOData(u=u, y=y))
    m = sysid.ssest(frd, 2)
    assert m.info["pem"]["weighting"] == "noise"
    assert set(m.info["start"]["losses"]) == {"frd_subspace weighted", "frd_subspace"}
    assert m.is_stable()
    np.testing.assert_allclose(np.sort_complex(m.poles()), np.sort_complex(true.poles()),
                               atol=0.03)
    # pem on an FRD without std: the uniform weighting, said in info
    bare = sysid.FRD(frd.omega, frd.response, dt=frd.dt)
    assert sysid.pem(bare, sysid.n4sid(bare, 2)).info["pem"]["weighting"] == "uniform"


def test_bad_frequency_response_calls_say_what_to_do():
    true = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    w = np.linspace(0.1, 3.0, 40)
    frd = sysid.FRD(w, true.freqresp(w), dt=1.0)
    with pytest.raises(DataError, match="integer or 'auto'"):
        sysid.ssest(frd, range(1, 4))
    # feedthrough="auto" decides on held-out lines (it was refused): exact data of a system
    # without D need none
    for fit in (sysid.ssest, sysid.n4sid):
        assert fit(frd, 1, feedthrough="auto").info["feedthrough_selection"][
            "feedthrough"] is False
    with pytest.raises(DataError, match="do not apply"):
        sysid.ssest(frd, 1, periods=2)
    with pytest.raises(DataError, match="stable= and x0="):
        sysid.n4sid(frd, 1, stable=True)
    with pytest.raises(DataError, match="sample time"):
        sysid.ssest(sysid.FRD(w, true.freqresp(w)), 1)
    with pytest.raises(DataError, match=r"frequency-response data.*sysid\.ssest\(frd"):
        sysid.moesp(frd, 1)


def test_oe_fits_frequency_response_data_as_matlab_oe_of_idfrd():
    g = sysid.TransferFunction([0.5, 0.2], [1.0, -1.2, 0.5], dt=1.0)
    w = np.linspace(0.02, 3.1, 100)
    frd = sysid.FRD(w, g.freqresp(w), dt=1.0)
    m = sysid.oe(frd, [2, 2, 1])  # MATLAB's vector form
    np.testing.assert_allclose(m.b[0][0], [0.5, 0.2], atol=1e-10)
    np.testing.assert_allclose(m.f[0][0], [-1.2, 0.5], atol=1e-10)
    assert m.info["weighting"] == "uniform" and m.info["domain"] == "frequency"
    assert np.all(m.noise_variance == 0) and "not estimated" in m.info["noise_variance"]
    # periodic data: oe on the record's lines is oe on their FRD (sysid.bla)
    u = sysid.multisine(128, band=(0, 0.5), periods=5, seed=0)
    rng = np.random.default_rng(1)
    y = g.simulate(np.vstack([u[-128:], u]))[128:] + 0.01 * rng.standard_normal((640, 1))
    d = sysid.IOData(u, y, 1.0)
    on_lines = sysid.oe(d, 2, 2, 1, periods=5)
    on_frd = sysid.oe(sysid.bla(d, 5), 2, 2, 1)
    assert on_frd.info["weighting"] == "noise"
    np.testing.assert_allclose(on_frd.b[0][0], on_lines.b[0][0], rtol=1e-10)
    np.testing.assert_allclose(on_frd.f[0][0], on_lines.f[0][0], rtol=1e-10)
    with pytest.raises(DataError, match="leave init out"):
        sysid.oe(frd, 2, 2, 1, init=m)
    with pytest.raises(DataError, match="sample time"):
        sysid.oe(sysid.FRD(w, g.freqresp(w)), 2, 2, 1)
    with pytest.raises(DataError, match="leave periods"):
        sysid.oe(frd, 2, 2, 1, periods=2)


def _rel(model, g):
    return float(np.sum(np.abs(model.freqresp(g.omega) - g.response) ** 2)
                 / np.sum(np.abs(g.response) ** 2))


def test_feedthrough_auto_on_frequency_data_decides_from_held_out_lines():
    # feedthrough="auto" was refused for an FRD ("decides from a time record"), and the
    # default (no D) fits a force-to-acceleration response badly in silence
    import warnings

    rng = np.random.default_rng(7)
    w = np.linspace(0.02, 3.0, 120)
    A, B, C = [[0.9, 0.3], [-0.3, 0.9]], [[1.0], [0.0]], [[1.0, 0.0]]
    for D, expect in ((0.8, True), (0.0, False)):
        true = sysid.StateSpaceModel(A, B, C, [[D]], dt=1.0)
        g0 = true.freqresp(w)
        noise = 0.01 * (rng.standard_normal(g0.shape) + 1j * rng.standard_normal(g0.shape))
        g = sysid.FRD(w, g0 + noise, dt=1.0)
        m = sysid.frd_subspace(g, 2, feedthrough="auto")
        why = m.info["feedthrough_selection"]
        assert why["feedthrough"] is expect and bool(np.any(m.D != 0)) is expect
        assert (m.D[0, 0] == pytest.approx(D, abs=0.02)) if expect else m.D[0, 0] == 0
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            s = sysid.ssest(g, 2, feedthrough="auto")
            p = sysid.pem(g, m, feedthrough="auto")
        assert s.info["feedthrough_selection"]["feedthrough"] is expect
        assert bool(np.any(s.D != 0)) is expect and bool(np.any(p.D != 0)) is expect


def test_the_f16_ground_vibration_response_needs_its_direct_term():
    # the BLA of the F-16 (shaker force to acceleration, 2-15 Hz): without D the frequency
    # subspace fit misses the band (relative squared error 0.52 at order 8); "auto" sees it
    z = sysid.datasets.load_f16()
    g = sysid.bla(z[8192:].select(outputs=[0]), periods=8)
    with pytest.warns(sysid.FeedthroughWarning, match="the response shows one"):
        plain = sysid.frd_subspace(g, 8)  # the default, without D: said
    assert plain.info["feedthrough_check"]["ratio"] > 2
    auto = sysid.frd_subspace(g, 8, feedthrough="auto")
    assert auto.info["feedthrough_selection"]["feedthrough"] is True
    assert _rel(auto, g) < 0.2 < 0.4 < _rel(plain, g)
