"""Frequency-domain subspace identification (McKelvey, Akçay & Ljung 1996)."""

from __future__ import annotations

import numpy as np
import pytest

import sysid

TRUE = sysid.StateSpaceModel(
    [[0.7, 0.3, 0.0], [-0.3, 0.7, 0.0], [0.0, 0.0, -0.5]],
    [[1.0, 0.0], [0.0, 1.0], [0.5, 0.2]],
    [[1.0, 0.0, 1.0], [0.0, 1.0, 0.2]],
    [[0.1, 0.0], [0.0, 0.0]],
    dt=0.1,
)
CT = sysid.ContinuousStateSpace([[0.0, 1.0, 0.0], [-4.0, -0.4, 1.0], [0.0, 0.0, -2.0]],
                                [[0.0], [1.0], [1.0]], [[1.0, 0.0, 0.0]])


def _poles(m):
    return np.sort_complex(m.poles())


def test_exact_discrete_frd_gives_the_system():
    w = np.linspace(0.0, np.pi / 0.1, 60)
    model = sysid.frd_subspace(sysid.FRD(w, TRUE.freqresp(w), dt=0.1), feedthrough=True)
    assert model.nstates == 3 and model.dt == 0.1
    np.testing.assert_allclose(_poles(model), _poles(TRUE), atol=1e-8)
    np.testing.assert_allclose(model.freqresp(w), TRUE.freqresp(w), atol=1e-8)


def test_exact_continuous_frd_gives_the_system():
    w = np.logspace(-1, 2, 80)
    model = sysid.frd_subspace(sysid.FRD(w, CT.freqresp(w)), continuous=True)
    assert isinstance(model, sysid.ContinuousStateSpace) and model.nstates == 3
    np.testing.assert_allclose(_poles(model), _poles(CT), atol=1e-8)
    np.testing.assert_allclose(model.freqresp(w), CT.freqresp(w), atol=1e-8)


def test_noisy_frd_converges_as_frequencies_grow():
    errs = []
    for nf in (50, 400, 3200):
        e = []
        for seed in range(4):
            rng = np.random.default_rng(seed)
            w = np.linspace(0.01, np.pi / 0.1, nf)
            g = TRUE.freqresp(w)
            g = g + 0.05 * (rng.standard_normal(g.shape) + 1j * rng.standard_normal(g.shape))
            model = sysid.frd_subspace(sysid.FRD(w, g, dt=0.1), 3, horizon=6,
                                       feedthrough=True)  # TRUE has a D
            e.append(np.max(np.abs(_poles(model) - _poles(TRUE))))
        errs.append(np.mean(e))
    # about 1/sqrt(n_freq): measured 0.0088, 0.0047, 0.0013
    assert errs[0] > errs[1] > errs[2] and errs[2] < errs[0] / 4, errs
    assert errs[2] < 0.003, errs


def test_weights_and_errors():
    w = np.linspace(0.0, np.pi / 0.1, 40)
    g = TRUE.freqresp(w)
    g[5] += 10.0  # an outlier, removed by a zero weight
    weights = np.ones(40)
    weights[5] = 0.0
    model = sysid.frd_subspace(sysid.FRD(w, g, dt=0.1), 3, weights=weights, feedthrough=True)
    np.testing.assert_allclose(_poles(model), _poles(TRUE), atol=1e-8)
    with pytest.raises(sysid.DataError, match="dt"):
        sysid.frd_subspace(sysid.FRD(w, g), 3)
    with pytest.raises(sysid.DataError, match="Nyquist"):
        sysid.frd_subspace(sysid.FRD(w * 2, g, dt=0.1), 3)
    with pytest.raises(sysid.OrderError):
        sysid.frd_subspace(sysid.FRD(w, g, dt=0.1), 30, horizon=4)


def test_continuous_model_from_sampled_data():
    # a known CT system sampled with a zero-order hold: a DT subspace model, then d2c (ZOH),
    # or the smoothed FRD of the record through frd_subspace, both give the CT poles
    # (measured over 4 seeds: at most 0.0015 and 0.016)
    ct_true = sysid.ContinuousStateSpace([[0.0, 1.0, 0.0], [-4.0, -0.4, 1.0], [0.0, 0.0, -1.0]],
                                         [[0.0], [0.0], [1.0]], [[4.0, 0.0, 0.0]])
    rng = np.random.default_rng(5)
    dt = 0.2
    u = rng.standard_normal(6000)
    y = sysid.c2d(ct_true, dt).simulate(u) + 0.01 * rng.standard_normal((6000, 1))
    data = sysid.IOData(u=u, y=y, dt=dt)
    ct = sysid.d2c(sysid.moesp(data, 3, horizon=10), "zoh")
    assert np.max(np.abs(_poles(ct) - _poles(ct_true))) < 0.005
    ct2 = sysid.frd_subspace(data, 3, horizon=10, lags=300, continuous=True)  # time data in
    assert isinstance(ct2, sysid.ContinuousStateSpace)
    assert np.max(np.abs(_poles(ct2) - _poles(ct_true))) < 0.04


def test_input_output_spectra_of_a_record():
    # McKelvey's spectra form with the transient term: exact for a noise-free record that is
    # not periodic (zero initial state, non-zero final state)
    rng = np.random.default_rng(2)
    u = rng.standard_normal((1024, 2))
    data = sysid.IOData(u=u, y=TRUE.simulate(u), dt=0.1)
    model = sysid.frd_subspace(data, 3, method="dft", feedthrough=True)  # TRUE has a D
    np.testing.assert_allclose(_poles(model), _poles(TRUE), atol=1e-8)
    np.testing.assert_allclose(model.D, TRUE.D, atol=1e-8)
    w = np.linspace(0.0, np.pi / 0.1, 9)
    np.testing.assert_allclose(model.freqresp(w), TRUE.freqresp(w), atol=1e-8)
    with pytest.raises(sysid.DataError, match="method"):
        sysid.frd_subspace(data, 3, method="fft")


def test_weights_of_another_length_are_a_shape_error():
    """weights=np.ones(5) with 60 frequencies raised numpy's "operands could not be
    broadcast together with remapped shapes"; a single number is still every line's."""
    w = np.linspace(0.0, np.pi / 0.1, 60)
    frd = sysid.FRD(w, TRUE.freqresp(w), dt=0.1)
    with pytest.raises(sysid.ShapeError, match=r"weights has shape \(5,\) but should be "
                       r"\(60,\): one weight per frequency of the FRD, or a single number"):
        sysid.frd_subspace(frd, 3, weights=np.ones(5), feedthrough=True)
    one = sysid.frd_subspace(frd, 3, weights=2.0, feedthrough=True)
    np.testing.assert_allclose(_poles(one), _poles(TRUE), atol=1e-8)
    u = np.random.default_rng(0).standard_normal((200, 2))
    data = sysid.IOData(u, TRUE.simulate(u), dt=0.1)
    with pytest.raises(sysid.ShapeError, match=r"should be \(101,\): one weight per DFT "
                       r"frequency of the 200-sample record"):
        sysid.frd_subspace(data, 3, method="dft", weights=np.ones(7))


def _lightly_damped(freqs, damping, seed=0, d=0.0):
    """Modes at ``freqs`` (rad/sample) of relative damping ``damping``, two outputs."""
    rng = np.random.default_rng(seed)
    n = 2 * len(freqs)
    A = np.zeros((n, n))
    for i, w in enumerate(freqs):
        r = np.exp(-damping * w)
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = r * np.array([[np.cos(w), -np.sin(w)],
                                                            [np.sin(w), np.cos(w)]])
    T = np.eye(n) + 0.3 * rng.standard_normal((n, n))
    return sysid.StateSpaceModel(T @ A @ np.linalg.inv(T), rng.standard_normal((n, 1)),
                                 rng.standard_normal((2, n)), np.full((2, 1), d), dt=1.0)


@pytest.mark.parametrize("feedthrough", [False, True])
def test_lines_crowded_on_a_small_arc_are_fitted_at_warped_frequencies(feedthrough):
    # three lightly damped modes excited on 0.03-0.12 rad/sample (the F-16 shaker's 2-15 Hz
    # at 400 Hz is 0.03-0.24): unwarped, the powers z_k^i are nearly collinear and the fit
    # found one state of six; warped, the system to round-off, with or without D
    true = _lightly_damped([0.05, 0.06, 0.09], 0.02, d=0.3 if feedthrough else 0.0)
    w = np.linspace(0.03, 0.12, 200)
    f = sysid.FRD(w, true.freqresp(w), dt=1.0)
    m = sysid.frd_subspace(f, 6, feedthrough=feedthrough)
    assert m.info["warped"] and m.dt == 1.0 and m.nstates == 6
    np.testing.assert_allclose(_poles(m), _poles(true), atol=1e-9)
    np.testing.assert_allclose(m.freqresp(w), true.freqresp(w), atol=1e-10)
    np.testing.assert_allclose(m.D, true.D, atol=1e-9)
    with pytest.raises(sysid.OrderError):
        sysid.frd_subspace(f, 6, warp=False, feedthrough=feedthrough)


def test_warped_fit_of_noisy_lines_and_when_it_applies():
    true = _lightly_damped([0.05, 0.06, 0.09], 0.02, seed=1)
    w = np.linspace(0.03, 0.12, 200)
    g = true.freqresp(w)
    rng = np.random.default_rng(2)
    noisy = g + 1e-2 * np.abs(g).mean() * (rng.standard_normal(g.shape)
                                            + 1j * rng.standard_normal(g.shape))
    f = sysid.FRD(w, noisy, dt=1.0)
    for horizon in (7, 10, None):  # unwarped: 8.4e-2, 8.9e-2, no model (0.97)
        err = {}
        for warp in ("auto", False):
            m = sysid.frd_subspace(f, 6, warp=warp, horizon=horizon)
            err[warp] = np.linalg.norm(m.freqresp(w) - g) / np.linalg.norm(g)
        assert err["auto"] < 5e-3 and err["auto"] < err[False] / 10
    # lines spread over the circle gain nothing: no warp; a line at Nyquist cannot be warped
    full = np.linspace(0.01, np.pi, 60)
    assert not sysid.frd_subspace(sysid.FRD(full, true.freqresp(full), dt=1.0),
                                  6).info["warped"]
    with pytest.raises(sysid.DataError, match="Nyquist"):
        sysid.frd_subspace(sysid.FRD(full, true.freqresp(full), dt=1.0), 6, warp=True)
    with pytest.raises(sysid.DataError, match="warp must be"):
        sysid.frd_subspace(f, 6, warp="yes")
    with pytest.raises(sysid.DataError, match="continuous=True always"):
        sysid.frd_subspace(f, 6, warp=True, continuous=True)
