"""Orthogonal decomposition into deterministic and stochastic submodels (Picci & Katayama).

The output is ``G(q) u + H(q) e`` with a second-order plant G (poles 0.85 e^{+-0.4j}) and a
fourth-order disturbance H (poles 0.9 e^{+-1.2j}, 0.7 e^{+-2.5j}; minimum phase): both
orders are found and the poles recovered within a tolerance proportional to 1/sqrt(N)
(constants a few times the Monte Carlo spread, measured over 12 records).
"""

from __future__ import annotations

import numpy as np
import pytest

import sysid

POLES_D = np.array([0.85 * np.exp(1j * 0.4), 0.85 * np.exp(-1j * 0.4)])
POLES_S = np.array([0.9 * np.exp(1j * 1.2), 0.9 * np.exp(-1j * 1.2),
                    0.7 * np.exp(1j * 2.5), 0.7 * np.exp(-1j * 2.5)])
ZEROS_S = np.array([0.5 * np.exp(1j * 0.5), 0.5 * np.exp(-1j * 0.5), 0.3, -0.4])


def companion(poles):
    a = np.real(np.poly(poles))
    n = len(poles)
    A = np.zeros((n, n))
    A[0] = -a[1:]
    A[1:, :-1] = np.eye(n - 1)
    B = np.zeros((n, 1))
    B[0] = 1.0
    return A, B


def record(n, seed):
    rng = np.random.default_rng(seed)
    ad, bd = companion(POLES_D)
    as_, ks = companion(POLES_S)
    cs = (np.real(np.poly(ZEROS_S)) - np.real(np.poly(POLES_S)))[1:].reshape(1, 4)
    u = rng.standard_normal(n)
    e = rng.standard_normal(n)
    y = (sysid.StateSpaceModel(ad, bd, [[1.0, 0.5]]).simulate(u)
         + sysid.StateSpaceModel(as_, ks, cs, [[1.0]]).simulate(e))
    return sysid.IOData(u=u, y=y)


def pole_error(model, true):
    assert model.nstates == len(true)
    return float(np.max(np.abs(np.sort_complex(model.poles()) - np.sort_complex(true))))


@pytest.mark.parametrize("n", [5_000, 20_000])
def test_orders_and_poles_of_both_submodels(n):
    for seed in range(3):
        od = sysid.orthogonal_decomposition(record(n, seed), horizon=10)
        assert (od.deterministic.nstates, od.stochastic.nstates) == (2, 4), (n, seed, od)
        assert pole_error(od.deterministic, POLES_D) < 1.0 / np.sqrt(n), (n, seed)
        assert pole_error(od.stochastic, POLES_S) < 8.0 / np.sqrt(n), (n, seed)
        # the innovation variance is that of e
        assert abs(od.stochastic.noise_cov[0, 0] - 1.0) < 5.0 / np.sqrt(n)


def test_combined_model_is_the_block_diagonal_innovation_model():
    data = record(5_000, 7)
    od = sysid.orthogonal_decomposition(data, 2, 4, horizon=10)
    comb = od.combined
    assert comb.nstates == 6 and comb.info["order_det"] == 2
    np.testing.assert_allclose(np.sort_complex(comb.poles()),
                               np.sort_complex(np.r_[od.deterministic.poles(),
                                                     od.stochastic.poles()]), atol=1e-10)
    w = np.linspace(0.1, 3.0, 7)
    np.testing.assert_allclose(comb.freqresp(w), od.deterministic.freqresp(w), atol=1e-10)
    # its one-step predictor is better than the deterministic simulation alone
    pred = comb.predict(data.u, data.y)
    sim = od.deterministic.simulate(data.u)
    assert np.var(data.y - pred) < 0.8 * np.var(data.y - sim)


def test_noise_free_deterministic_part_is_exact():
    rng = np.random.default_rng(3)
    ad, bd = companion(POLES_D)
    u = rng.standard_normal(1_000)
    y = sysid.StateSpaceModel(ad, bd, [[1.0, 0.5]]).simulate(u)
    y = y + 0.01 * sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], [[1.0]]).simulate(
        rng.standard_normal(1_000))
    od = sysid.orthogonal_decomposition(sysid.IOData(u=u, y=y), 2, 1, horizon=8)
    assert pole_error(od.deterministic, POLES_D) < 1e-3
    assert abs(od.stochastic.poles()[0] - 0.5) < 0.1


def test_presentation_and_spectrum():
    od = sysid.orthogonal_decomposition(record(4_000, 2), 2, 4, horizon=10)
    assert "deterministic order 2, stochastic order 4" in repr(od)
    assert "stochastic poles" in od.summary()
    df = od.to_pandas()
    assert sorted(df["submodel"].value_counts().to_dict().items()) == [
        ("deterministic", 2), ("stochastic", 4)]
    w, phi = od.disturbance_spectrum(np.array([0.0, 1.2, 3.0]))
    assert phi.shape == (3, 1, 1) and np.all(phi.real > 0)
    # the spectrum peaks near the lightly damped disturbance pole (1.2 rad/sample)
    w, phi = od.disturbance_spectrum()
    assert abs(w[np.argmax(phi[:, 0, 0].real)] - 1.2) < 0.15
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    assert od.plot_disturbance_spectrum() is not None


def test_bad_input():
    with pytest.raises(sysid.DataError, match="input"):
        sysid.orthogonal_decomposition(sysid.IOData(y=np.ones(100)))
