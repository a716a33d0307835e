"""MATLAB's simsd: the simulated output's standard deviation, calibrated by Monte Carlo."""

import warnings

import numpy as np
import pytest

import sysid

TRUE = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]])


def _record(rng, u, sd=0.5):
    return sysid.IOData(u, TRUE.simulate(u) + sd * rng.standard_normal(u.shape), 1.0)


def test_predicted_std_matches_the_spread_over_experiments():
    # 200 output-error fits on independent noise (same input): the sample standard deviation
    # of their step simulations against the mean first-order std simsd predicts from one fit
    # each. 200 runs: the sample std is within 5 % (one sigma) of its value, so 20 % is a
    # four-sigma bound
    rng = np.random.default_rng(0)
    u = rng.standard_normal((300, 1))
    ut = np.ones((25, 1))
    sims, preds = [], []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sysid.SysidWarning)
        for _ in range(200):
            m = sysid.oe(_record(rng, u), 1, 1, 1)
            sims.append(m.simulate(ut)[:, 0])
            preds.append(sysid.simsd(m, ut, n=0).std[:, 0])
    ratio = np.mean(preds, axis=0)[1:] / np.std(sims, axis=0, ddof=1)[1:]
    assert np.all(np.abs(ratio - 1) < 0.2), ratio
    assert np.all(np.array(preds)[:, 0] == 0)  # y(0) = D u(0) with D = 0 fixed: no spread


def test_monte_carlo_agrees_with_first_order_and_noise_adds_its_variance():
    rng = np.random.default_rng(1)
    u = rng.standard_normal((400, 1))
    m = sysid.oe(_record(rng, u), 1, 1, 1)
    ut = rng.standard_normal((60, 1))
    lin = sysid.simsd(m, ut, n=3, seed=2)
    mc = sysid.simsd(m, ut, n=3000, method="monte-carlo", seed=2)
    np.testing.assert_allclose(mc.std[5:], lin.std[5:], rtol=0.1)
    np.testing.assert_array_equal(lin.y, m.simulate(ut))
    assert lin.samples.shape == (3, 60, 1) and mc.samples.shape == (3000, 60, 1)
    # with the noise (white here: an output-error model): its variance is added, and the
    # drawn responses spread by that much about the estimate
    nz = sysid.simsd(m, ut, n=2000, noise=True, seed=3)
    sd_e = float(np.sqrt(m.noise_variance[0]))
    np.testing.assert_allclose(nz.std, np.sqrt(lin.std ** 2 + sd_e ** 2), rtol=1e-9)
    spread = (nz.samples - nz.y).std(axis=0)
    np.testing.assert_allclose(spread[5:], nz.std[5:], rtol=0.1)


def test_noise_through_a_noise_model_and_the_result_object():
    # an ARMAX-type innovations model: the noise goes through K; stationary std from it
    rng = np.random.default_rng(4)
    u = rng.standard_normal((2000, 1))
    e = 0.3 * rng.standard_normal((2000, 1))
    x, y = 0.0, np.empty((2000, 1))
    for t in range(2000):
        y[t] = x + e[t, 0]
        x = 0.8 * x + u[t, 0] + 0.5 * e[t, 0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sysid.SysidWarning)
        m = sysid.armax(sysid.IOData(u, y, 1.0), 1, 1, 1, 1)
    s = sysid.simsd(m, np.zeros((200, 1)), n=1500, noise=True, seed=5)
    # y = (1 + (c1 - a1) q^-1 / (1 - 0.8 q^-1)) e: variance sd^2 (1 + 0.5^2 / (1 - 0.64))
    want = 0.3 * np.sqrt(1 + 0.25 / 0.36)
    assert s.std[-1, 0] == pytest.approx(want, rel=0.08)
    assert float(np.std(s.samples[:, -1, 0])) == pytest.approx(want, rel=0.1)
    # each drawn noise path starts at rest: the std reported follows it from the innovation's
    # (0.3 at t = 0, where the stationary 0.37 was reported at every sample) to the
    # stationary one; 1500 draws: a sample std within 2 % (one sigma), 8 % is four sigmas
    assert s.std[0, 0] == pytest.approx(0.3, rel=0.08) and s.std[0, 0] < s.std[3, 0]
    spread = (s.samples - s.y).std(axis=0)[:, 0]
    for t in (0, 1, 2, 5, 199):
        assert spread[t] == pytest.approx(s.std[t, 0], rel=0.08), t
    df = s.to_pandas()
    assert list(df.columns) == ["t", "y0", "y0 std"] and len(df) == 200
    assert "std mean" in s.summary() and "with noise" in repr(s)


def test_plot(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    rng = np.random.default_rng(6)
    m = sysid.oe(_record(rng, rng.standard_normal((200, 1))), 1, 1, 1)
    ax = sysid.simsd(m, np.ones((20, 1)), n=4, seed=0).plot()
    assert len(ax[0].lines) == 5  # four drawn responses and the estimate
    ax[0].figure.savefig(tmp_path / "simsd.png")


def test_bad_requests_name_the_fix():
    rng = np.random.default_rng(7)
    m = sysid.oe(_record(rng, rng.standard_normal((200, 1))), 1, 1, 1)
    with pytest.raises(sysid.DataError, match="no parameter uncertainty"):
        sysid.simsd(TRUE, np.ones((10, 1)))
    with pytest.raises(sysid.DataError, match=r"\(samples, 1\)"):
        sysid.simsd(m, np.ones((10, 2)))
    with pytest.raises(sysid.DataError, match="n >= 2"):
        sysid.simsd(m, np.ones((10, 1)), n=1, method="monte-carlo")
    with pytest.raises(sysid.DataError, match="'linear' or 'monte-carlo'"):
        sysid.simsd(m, np.ones((10, 1)), method="exact")
    with pytest.raises(sysid.DataError, match="NaN"):
        sysid.simsd(m, np.full((10, 1), np.nan))


def test_continuous_time_models_take_the_records_sample_time():
    # simsd(tfest_model, data) raised "a continuous-time model needs the sample time of the
    # data: pass dt", and simsd had no dt (MATLAB's simsd takes idtf and idproc models)
    rng = np.random.default_rng(0)
    u = rng.standard_normal((400, 1))
    y = sysid.TransferFunction([1.0], [1.0, 1.0]).simulate(u, dt=0.1)
    data = sysid.IOData(u, y + 0.02 * rng.standard_normal((400, 1)), 0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        models = [sysid.tfest(data, 1, 0), sysid.procest(data, "P1")]
    for m in models:
        s = sysid.simsd(m, data, n=0)
        np.testing.assert_allclose(s.t[:3], [0.0, 0.1, 0.2])
        np.testing.assert_allclose(s.y, m.simulate(data.u, dt=0.1), rtol=1e-12)
        lin = sysid.simsd(m, np.ones((60, 1)), n=0, dt=0.1)
        mc = sysid.simsd(m, np.ones((60, 1)), n=1000, dt=0.1, method="monte-carlo", seed=1)
        # 1000 draws: the sample std within 10 % of the first-order one (a 4.5 sigma band)
        np.testing.assert_allclose(mc.std[-1], lin.std[-1], rtol=0.1)
    with pytest.raises(sysid.DataError, match="pass dt="):
        sysid.simsd(models[0], data.u)
    with pytest.raises(sysid.DataError, match="disagrees with the record's dt"):
        sysid.simsd(models[0], data, dt=0.2)
