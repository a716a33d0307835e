"""Time series: sysid.ar (four methods) against independent oracles, calibrated standard
deviations, output-only n4sid/ssest, and sysid.forecast with calibrated bands."""

import numpy as np
import pytest
from scipy import signal

import sysid

A2 = [1.0, -1.5, 0.7]  # AR(2), poles 0.75 +- 0.37i


def _ar2(n, seed):
    return signal.lfilter([1.0], A2, np.random.default_rng(seed).standard_normal(n))


def _yule_walker_oracle(y, n):
    """Plain Yule-Walker: the full Toeplitz matrix of biased autocovariances, solved densely."""
    N = y.size
    r = np.array([y[: N - k] @ y[k:] / N for k in range(n + 1)])
    R = np.array([[r[abs(i - j)] for j in range(n)] for i in range(n)])
    return np.linalg.solve(R, -r[1:])


def _burg_oracle(y, n):
    """Burg written as a loop over samples (a second, independent implementation)."""
    f, b, a = list(y), list(y), [1.0]
    for m in range(1, n + 1):
        num = den = 0.0
        for t in range(m, len(y)):
            num += f[t] * b[t - 1]
            den += f[t] ** 2 + b[t - 1] ** 2
        k = -2 * num / den
        a = [(a[i] if i < len(a) else 0.0) + k * (a[m - i] if m - i < len(a) else 0.0)
             for i in range(m + 1)]
        f, b = ([0.0] * m + [f[t] + k * b[t - 1] for t in range(m, len(y))],
                [0.0] * m + [b[t - 1] + k * f[t] for t in range(m, len(y))])
    return np.array(a[1:])


def test_ar_methods_match_independent_oracles():
    y = _ar2(3000, 0)
    np.testing.assert_allclose(sysid.ar(y, 2, "yw").a[0][0], _yule_walker_oracle(y, 2),
                               rtol=1e-12)
    np.testing.assert_allclose(sysid.ar(y, 3, "burg").a[0][0], _burg_oracle(y, 3), rtol=1e-10)
    Phi = -np.column_stack([y[1:-1], y[:-2]])
    ls = np.linalg.lstsq(Phi, y[2:], rcond=None)[0]
    np.testing.assert_allclose(sysid.ar(y, 2, "ls").a[0][0], ls, rtol=1e-10)
    yr = y[::-1]
    Pb = -np.column_stack([yr[1:-1], yr[:-2]])
    fb = np.linalg.lstsq(np.vstack([Phi, Pb]), np.r_[y[2:], yr[2:]], rcond=None)[0]
    np.testing.assert_allclose(sysid.ar(y, 2).a[0][0], fb, rtol=1e-10)


@pytest.mark.parametrize("method", ["fb", "burg", "yw", "ls"])
def test_ar_is_consistent(method):
    errs = [np.abs(sysid.ar(_ar2(n, 2), 2, method).a[0][0] - A2[1:]).max()
            for n in (500, 50000)]
    assert errs[1] < 0.02 and errs[1] < errs[0]


@pytest.mark.parametrize("method", ["burg", "ls"])
def test_ar_std_is_calibrated_by_monte_carlo(method):
    # 300 runs: the sample std of a1 is within ~8 % of the truth (chi distribution, 2 sigma)
    # and the 95 % interval coverage within 0.92..0.98 has probability > 0.99 if calibrated
    est, sd = [], []
    for s in range(300):
        m = sysid.ar(_ar2(400, 100 + s), 2, method)
        est.append(m.a[0][0])
        sd.append(m.std["a"][0][0])
    est, sd = np.array(est), np.array(sd)
    ratio = est.std(axis=0) / sd.mean(axis=0)
    assert np.all((ratio > 0.85) & (ratio < 1.15)), ratio
    cover = (np.abs(est - A2[1:]) < 1.96 * sd).mean(axis=0)
    assert np.all((cover > 0.90) & (cover < 0.99)), cover


def test_ar_pools_experiments_and_ar_arma_keep_working_on_iodata():
    ys = [_ar2(2000, 3), _ar2(1500, 4)]
    both = sysid.ar(sysid.IOData(None, [y[:, None] for y in ys], 1.0), 2, "ls").a[0][0]
    Phi = np.vstack([-np.column_stack([y[1:-1], y[:-2]]) for y in ys])
    ref = np.linalg.lstsq(Phi, np.concatenate([y[2:] for y in ys]), rcond=None)[0]
    np.testing.assert_allclose(both, ref, rtol=1e-10)
    y = signal.lfilter([1, 0.5], [1, -0.7], np.random.default_rng(5).standard_normal(4000))
    m = sysid.arma(sysid.IOData(None, y[:, None], 0.1), 1, 1)
    assert abs(m.a[0][0][0] + 0.7) < 0.05 and abs(m.c[0][0] - 0.5) < 0.05 and m.dt == 0.1


def test_output_only_n4sid_and_ssest():
    y = _ar2(4000, 6)[:, None]
    d = sysid.IOData(None, y, 1.0)
    true = np.roots(A2)
    for m in (sysid.n4sid(d, 2), sysid.ssest(d, 2)):
        assert m.ninputs == 0
        p = np.sort_complex(m.poles())
        assert np.abs(p - np.sort_complex(true)).max() < 0.05


def test_forecast_of_an_ar1_is_analytic():
    m = sysid.ar(signal.lfilter([1], [1, -0.8], np.random.default_rng(7).standard_normal(5000)),
                 1)
    a, lam = -m.a[0][0][0], float(m.noise_variance[0])
    f = sysid.forecast(m, [0.3, -0.2, 1.5], 4)
    np.testing.assert_allclose(f.mean[:, 0], 1.5 * a ** np.arange(1, 5), rtol=1e-12)
    np.testing.assert_allclose(f.std[:, 0] ** 2,
                               lam * np.cumsum(a ** (2 * np.arange(4))), rtol=1e-12)
    assert f.t.tolist() == [3.0, 4.0, 5.0, 6.0]
    assert np.all(f.lower < f.mean) and np.all(f.upper > f.mean)
    assert "4 steps" in repr(f)


def test_forecast_equals_the_models_own_k_step_predictor():
    y = _ar2(3000, 8)[:, None]
    d = sysid.IOData(None, y, 1.0)
    for m in (sysid.n4sid(d, 2), sysid.arma(d, 2, 1)):
        N = 2000
        for k in (1, 3, 7):
            pred = m.predict(np.zeros((N + k, 0)), y[: N + k], k)[N + k - 1]
            fc = sysid.forecast(m, y[:N], k).mean[k - 1]
            np.testing.assert_allclose(fc, pred, rtol=1e-8, atol=1e-10)


def test_forecast_bands_cover_at_their_level():
    # 400 independent realisations of the true AR(2): 95 % bands at 1 and 10 steps cover
    # 0.92..0.98 (binomial 2.5 sigma at p = 0.95)
    m = sysid.polynomial.model.PolynomialModel([[A2[1:]]], [[]], np.zeros((1, 0)), 1.0)
    hits = np.zeros((400, 2))
    for s in range(400):
        y = _ar2(220, 1000 + s)
        f = sysid.forecast(m, y[:200], 10)
        for i, k in enumerate((1, 10)):
            hits[s, i] = f.lower[k - 1, 0] <= y[200 + k - 1] <= f.upper[k - 1, 0]
    cover = hits.mean(axis=0)
    assert np.all((cover > 0.92) & (cover < 0.98)), cover


def test_bad_input_names_the_fix():
    y = _ar2(100, 9)
    with pytest.raises(sysid.DataError, match="method must be"):
        sysid.ar(y, 2, "mle")
    with pytest.raises(sysid.DataError, match="without inputs"):
        sysid.ar(sysid.IOData(np.ones((100, 1)), y[:, None], 1.0), 2)
    with pytest.raises(sysid.DataError, match="n4sid"):
        sysid.ar(sysid.IOData(None, np.ones((100, 2)), 1.0), 2)
    with pytest.raises(sysid.InsufficientDataError, match="lower order"):
        sysid.ar(y[:5], 3)
    with pytest.raises(sysid.DataError, match="y0 is 0 in every sample"):
        sysid.ar(np.zeros(50), 2, "burg")
    with pytest.raises(sysid.DataError, match="na must be"):
        sysid.ar(y, 0)
    m = sysid.ar(y, 2)
    with pytest.raises(sysid.DataError, match="horizon"):
        sysid.forecast(m, y, 0)
    with pytest.raises(sysid.DataError, match="level"):
        sysid.forecast(m, y, 3, level=95)
    with pytest.raises(sysid.ShapeError):
        sysid.forecast(m, np.ones((10, 2)), 3)
    with pytest.raises(sysid.DataError, match="future_inputs"):
        sysid.forecast(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), y, 3)
    with pytest.raises(sysid.DataError, match="to_statespace"):
        sysid.forecast(object(), y, 3)


def _arma_oracle(y, na, nc):
    """Prediction-error ARMA written directly: e = A(q)/C(q) y from rest, sum e^2 minimised
    by SciPy's least_squares from the long-AR two-stage start (an independent
    implementation of the same criterion)."""
    from scipy.optimize import least_squares

    def resid(th):
        return signal.lfilter(np.r_[1.0, th[:na]], np.r_[1.0, th[na:]], y)

    return least_squares(resid, np.zeros(na + nc), xtol=1e-14, ftol=1e-14, gtol=1e-14).x


def test_arma_matches_an_independent_prediction_error_fit():
    y = signal.lfilter([1, 0.5, -0.2], [1, -1.2, 0.5],
                       np.random.default_rng(11).standard_normal(3000))
    m = sysid.arma(y, 2, 2)
    ref = _arma_oracle(y, 2, 2)
    th = np.r_[m.a[0][0], m.c[0]]

    def cost(t):
        return float(np.sum(signal.lfilter(np.r_[1.0, t[:2]], np.r_[1.0, t[2:]], y) ** 2))

    # the same minimum: the criterion to 1e-8 (sysid stops on its gradient tolerance, a few
    # 1e-5 from the oracle's point: a hundredth of the parameters' std)
    assert cost(th) <= cost(ref) * (1 + 1e-8)
    sd = np.r_[m.std["a"][0][0], m.std["c"][0]]
    assert np.all(np.abs(th - ref) < 0.01 * sd), (th - ref) / sd


def test_arma_std_is_calibrated_by_monte_carlo():
    # 200 ARMA(1, 1) records of 500 samples: 95 % intervals cover 0.90..0.99 (binomial sd
    # of the coverage 1.5 % at 200 runs: 0.95 +- 3 sd) and the reported std is within 20 %
    # of the sample std (whose own sampling error is 5 % at 200 runs)
    est, sd = np.empty((200, 2)), np.empty((200, 2))
    for s in range(200):
        y = signal.lfilter([1, 0.5], [1, -0.7], np.random.default_rng(500 + s).standard_normal(500))
        m = sysid.arma(y, 1, 1)
        est[s] = m.a[0][0][0], m.c[0][0]
        sd[s] = m.std["a"][0][0][0], m.std["c"][0][0]
    ratio = est.std(axis=0) / sd.mean(axis=0)
    assert np.all((ratio > 0.8) & (ratio < 1.2)), ratio
    cover = (np.abs(est - [-0.7, 0.5]) < 1.96 * sd).mean(axis=0)
    assert np.all((cover > 0.90) & (cover < 0.99)), cover


def test_forecast_continues_the_records_clock():
    # the times started at t = 0 whatever the record's start: 3 steps after
    # d.slice(200, 300) at dt = 0.5 were [50, 50.5, 51], and plot() drew the past from 0
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    d = sysid.IOData(None, _ar2(400, 31), 0.5)
    m = sysid.ar(d, 2)
    past = d.slice(200, 300)
    f = sysid.forecast(m, past, 3)
    np.testing.assert_allclose(f.t, [150.0, 150.5, 151.0], atol=1e-12)
    assert f.to_pandas().index.tolist() == pytest.approx([150.0, 150.5, 151.0])
    np.testing.assert_allclose(f.mean, sysid.forecast(m, past.y, 3).mean, rtol=1e-12)
    fig = f.plot(n_past=50)
    np.testing.assert_allclose(fig.axes[0].lines[0].get_xdata(), past.time[-50:])
    plt.close(fig)


def test_forecast_with_inputs_takes_a_u_y_pair_and_says_what_is_missing():
    # the k-step forecast equals the model's own k-step predictor (which sees the inputs up
    # to the predicted sample and the outputs k samples earlier)
    rng = np.random.default_rng(32)
    m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]], K=[[0.5]], dt=1.0)
    N, k = 200, 4
    u, e = rng.standard_normal((2, N + k, 1))
    x, y = 0.0, np.empty((N + k, 1))
    for t in range(N + k):
        y[t] = x + e[t]
        x = 0.9 * x + u[t, 0] + 0.5 * e[t, 0]
    f = sysid.forecast(m, (u[:N], y[:N]), k, future_inputs=u[N:])
    pred = np.vstack([m.predict(u[: N + j], y[: N + j], j)[-1] for j in range(1, k + 1)])
    np.testing.assert_allclose(f.mean, pred, rtol=1e-10, atol=1e-12)
    f_io = sysid.forecast(m, sysid.IOData(u[:N], y[:N], 1.0), k, future_inputs=u[N:])
    np.testing.assert_allclose(f.mean, f_io.mean, rtol=1e-12)
    # outputs alone: the core's "u has shape (100, 1) but should have shape (samples, 2)"
    with pytest.raises(sysid.DataError, match=r"past inputs.*IOData or a pair \(u, y\)"):
        sysid.forecast(m, y[:N], k, future_inputs=u[N:])
    with pytest.raises(sysid.ShapeError, match="200 samples but the past outputs 199"):
        sysid.forecast(m, (u[:N], y[:N - 1]), k, future_inputs=u[N:])


def test_forecast_refuses_a_past_shorter_than_the_order():
    # an AR(2) forecast from one past sample silently took the sample before it as zero
    y = np.sin(0.3 * np.arange(200)) + 0.1 * np.random.default_rng(0).standard_normal(200)
    m = sysid.ar(y, 2)
    with pytest.raises(sysid.InsufficientDataError, match="fewer than the model's order 2"):
        sysid.forecast(m, y[:1], 3)
    assert sysid.forecast(m, y[:2], 3).mean.shape == (3, 1)


def test_forecast_estimates_the_predictor_start_by_default():
    # MATLAB's forecast fits the initial condition ('e'); from rest, an ARMA(1,1) with
    # c = 0.95 forecast 1.972 from 30 samples where the fitted start gives 1.718 (the
    # conditional mean given the infinite past: 1.661)
    from scipy.signal import lfilter

    arma = sysid.PolynomialModel([[[-0.5]]], [[]], np.zeros((1, 0)), 1.0, c=[[0.95]],
                                 noise_variance=[1.0])
    e = np.random.default_rng(3).standard_normal(2030)
    y = lfilter([1, 0.95], [1, -0.5], e)[-30:]
    zero = sysid.forecast(arma, y, 3, initial_condition="zero")
    est = sysid.forecast(arma, y, 3)
    np.testing.assert_allclose(zero.mean[:, 0], 1.9717613897862776 * 0.5 ** np.arange(3))
    np.testing.assert_allclose(est.mean[:, 0], 1.7178926614084151 * 0.5 ** np.arange(3))
    assert np.all(est.std > zero.std)  # the fitted start's uncertainty in the bands
    with pytest.raises(sysid.DataError, match="initial_condition must be"):
        sysid.forecast(arma, y, 3, initial_condition="e")
    # seeded, 400 records of 30 samples: the fitted start's one-step error has the variance
    # its band says (mean of z^2 within 3 sigmas, sqrt(2/400), of 1; coverage of the 95 %
    # band within 3 binomial sigmas) and is smaller than from rest (MSE 1.07 against 1.22)
    rng = np.random.default_rng(11)
    z2, inside, sq = [], 0, {"zero": 0.0, "estimate": 0.0}
    for _ in range(400):
        yy = lfilter([1, 0.95], [1, -0.5], rng.standard_normal(231))[-31:]
        for ic in sq:
            f = sysid.forecast(arma, yy[:30], 1, initial_condition=ic)
            err = yy[30] - f.mean[0, 0]
            sq[ic] += err**2 / 400
            if ic == "estimate":
                z2.append((err / f.std[0, 0]) ** 2)
                inside += int(f.lower[0, 0] <= yy[30] <= f.upper[0, 0])
    assert abs(np.mean(z2) - 1) < 3 * np.sqrt(2 / 400)
    assert 0.917 < inside / 400 < 0.983
    assert sq["estimate"] < sq["zero"]
