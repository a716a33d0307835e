"""The frequency-weighted PNLSS fit on periodic data (weighting="bla")."""

import numpy as np
import pytest

import sysid
from sysid.errors import DataError
from sysid.nlss import freqweight


def _truth():
    return sysid.PNLSSModel([[0.8, 0.2], [-0.2, 0.7]], [[0.5], [0.3]], [[1.0, 0.0]], [[0.0]],
                            [[0.05, 0.0], [0.0, -0.03]], np.zeros((1, 0)),
                            zeta=[[0, 0], [0, 1]], eta=[])


def _record(noise=0.0, periods=4, P=256, seed=1):
    u = 0.5 * sysid.multisine(P, band=(0, 0.5), phases="random", seed=seed, periods=periods)
    y = _truth().simulate(u)
    rng = np.random.default_rng(seed)
    return u, y, y + noise * rng.standard_normal(y.shape)


def test_weights_are_the_inverse_noise_variance_of_the_averaged_spectrum(monkeypatch):
    monkeypatch.setattr(freqweight, "SMOOTH", 0)
    u, _, yn = _record(noise=0.05, periods=5)
    P = 256
    (per, lines, w), = freqweight.line_weights(sysid.IOData(u, yn, 1.0), [5], [P])
    Y = np.fft.fft(yn[P:, 0].reshape(4, P), axis=1)
    assert per == P
    assert lines == list(range(P // 2 + 1))
    k = np.asarray(lines)
    want = 1.0 / (np.var(Y[:, k], axis=0, ddof=1) / 4)
    np.testing.assert_allclose(w, want, rtol=1e-10)


def test_needs_two_steady_periods():
    u, y, _ = _record(periods=2)
    d = sysid.IOData(u, y, 1.0)
    assert freqweight.line_weights(d, [2], [256]) is None
    with pytest.raises(DataError, match="two whole periods"):
        sysid.pnlss(d, 2, degree=[2], terms="states", periods=2, weighting="bla",
                    progress=False)


def test_weighted_fit_recovers_a_known_system_from_noise_free_data():
    u, y, _ = _record()
    m = sysid.pnlss(sysid.IOData(u, y, 1.0), 2, degree=[2], terms="states",
                    output_terms="none", periods=4, weighting="bla", progress=False)
    assert m.info["weighting"] == "bla"
    assert np.max(np.abs(m.simulate(u)[256:] - y[256:])) < 1e-6


@pytest.mark.filterwarnings("ignore:pnlss stopped at max_iter")
def test_weighting_changes_the_noisy_fit():
    u, _, yn = _record(noise=0.02)
    d = sysid.IOData(u, yn, 1.0)
    kw = dict(degree=[2], terms="states", output_terms="none", periods=4, max_iter=20,
              progress=False)
    bla = sysid.pnlss(d, 2, weighting="bla", **kw)
    none = sysid.pnlss(d, 2, **kw)
    assert bla.info["weighting"] == "bla" and none.info["weighting"] == "none"
    assert not np.allclose(bla.theta, none.theta)


def test_bad_weighting_is_rejected():
    u, y, _ = _record()
    d = sysid.IOData(u, y, 1.0)
    with pytest.raises(DataError, match="weighting must be"):
        sysid.pnlss(d, 2, degree=[2], periods=4, weighting="freq", progress=False)
    with pytest.raises(DataError, match="needs periods="):
        sysid.pnlss(d, 2, degree=[2], weighting="bla", progress=False)
    with pytest.raises(DataError, match="not average=True"):
        sysid.pnlss(d, 2, degree=[2], periods=4, average=True, weighting="bla",
                    progress=False)


@pytest.mark.filterwarnings("ignore:pnlss stopped at max_iter")
def test_the_decoupled_model_fits_on_the_weighted_cost_too():
    # the truth's two monomials x1^2, x1 x2 are sums of squares of three linear forms: the
    # decoupled model with three quadratic branches holds it; both costs approach it (the
    # branch directions converge slowly), by different paths
    u, y, _ = _record()
    d = sysid.IOData(u, y, 1.0)
    kw = dict(degree=[2], branches=3, periods=4, max_iter=60, progress=False)
    bla = sysid.pnlss(d, 2, weighting="bla", **kw)
    none = sysid.pnlss(d, 2, **kw)
    assert bla.info["weighting"] == "bla" and none.info["weighting"] == "none"
    assert bla.info["method"] == "pnlss (decoupled)"
    assert not np.allclose(bla.theta, none.theta)
    start = sysid.pnlss(d, 2, weighting="bla", **{**kw, "max_iter": 0})
    for m in (bla, none):
        err = np.max(np.abs(m.simulate(u)[256:] - y[256:]))
        assert err < 1e-2 * np.max(np.abs(start.simulate(u)[256:] - y[256:])), err
