"""Regularised ARX (``sysid.arxregul``, ``arx(..., regularization=...)``) and the Rust MIMO
ARX simulation / k-step prediction kernel."""

import numpy as np
import pytest
from scipy import signal

import sysid
from sysid import _sysid
from sysid.errors import DataError, ShapeError
from sysid.polynomial import arxregul as ar


def _data(u, y):
    return sysid.IOData(np.reshape(u, (len(u), -1)), np.reshape(y, (len(y), -1)), 1.0)


def _dense_regression(u, y, na, nb, nk):
    """Phi and y of the SISO ARX regression, rows from the compressor's first lag on."""
    L = max(na, nb + nk - 1, 1)
    rows = range(L, len(y))
    phi = [[y[t - lag] for lag in range(1, na + 1)] + [u[t - lag] for lag in range(nk, nk + nb)]
           for t in rows]
    return np.array(phi), y[L:]


def _dense_value(Phi, y, P, s2):
    Sigma = Phi @ P @ Phi.T + s2 * np.eye(len(y))
    return y @ np.linalg.solve(Sigma, y) + np.linalg.slogdet(Sigma)[1]


@pytest.mark.parametrize("name", ["tc", "ss", "dc", "ridge"])
def test_marginal_likelihood_value_and_gradient_match_dense(name):
    rng = np.random.default_rng(5)
    n, na, nb, nk = 60, 2, 3, 1
    u = rng.standard_normal(n)
    y = signal.lfilter([0, 1.0, 0.5], [1, -1.2, 0.5], u) + 0.3 * rng.standard_normal(n)
    sums, _ = ar.summaries(_data(u, y), na, nb, nk)
    s, rows = sums[0]
    Phi, yy = _dense_regression(u, y, na, nb, nk)
    assert rows == len(yy)
    prior = ar._Prior(name, [na, nb])
    x = rng.uniform(-1.0, 1.0, prior.nh * len(prior.sizes))
    P, dP = prior(x)
    s2 = 0.2
    v, g, ds = ar.marginal_likelihood(s, rows, P, s2, dP)
    np.testing.assert_allclose(v, _dense_value(Phi, yy, P, s2), rtol=1e-10)
    # gradient: the dense trace formula and central differences in the coordinates x
    Si = np.linalg.inv(Phi @ P @ Phi.T + s2 * np.eye(len(yy)))
    al = Si @ yy
    dense = [np.trace(Si @ Phi @ d @ Phi.T) - al @ Phi @ d @ Phi.T @ al for d in dP]
    np.testing.assert_allclose(g, dense, rtol=1e-8, atol=1e-10)
    h = 1e-6
    fd = []
    for k in range(x.size):
        e = np.zeros(x.size)
        e[k] = h
        fd.append((_dense_value(Phi, yy, prior(x + e)[0], s2)
                   - _dense_value(Phi, yy, prior(x - e)[0], s2)) / (2 * h))
    np.testing.assert_allclose(g, fd, rtol=1e-5, atol=1e-7)
    fd_s = (_dense_value(Phi, yy, P, s2 + h) - _dense_value(Phi, yy, P, s2 - h)) / (2 * h)
    np.testing.assert_allclose(ds, fd_s, rtol=1e-6)


def _fir_case(rng, n=200, taps=50):
    """A lightly damped system (poles at radius 0.9), short record, 50-tap FIR fits."""
    u = rng.standard_normal(n)
    num, den = [0, 1.0, 0.5], [1, -1.5, 0.81]
    y0 = signal.lfilter(num, den, u)
    y = y0 + 0.3 * np.std(y0) * rng.standard_normal(n)
    h = signal.lfilter(num, den, np.r_[1.0, np.zeros(taps)])[1:taps + 1]
    return _data(u, y), h


def test_tc_dc_regularisation_beats_least_squares_monte_carlo():
    """Chen, Ohlsson & Ljung (2012): with a 50-tap FIR on 200 samples of a lightly damped
    system, the tuned TC and DC priors cut the impulse-response error of least squares
    (30 seeded records: the margins below are wide, TC 0.30 against LS 0.84 on 50)."""
    err = {"ls": [], "tc": [], "dc": []}
    for run in range(30):
        d, h = _fir_case(np.random.default_rng(100 + run))
        err["ls"].append(np.sum((sysid.arx(d, 0, 50, 1).b[0][0] - h) ** 2))
        for k in ("tc", "dc"):
            err[k].append(np.sum((sysid.arx(d, 0, 50, 1, regularization=k).b[0][0] - h) ** 2))
    ls, tc, dc = (np.mean(err[k]) for k in ("ls", "tc", "dc"))
    assert tc < 0.5 * ls and dc < 0.5 * ls, (ls, tc, dc)
    # and in most single runs, not only on average
    assert np.mean(np.array(err["tc"]) < np.array(err["ls"])) > 0.8


def test_regularised_high_order_arx_impulse_response():
    """ARX(10, 10) on 150 samples of an ARX(2, 2) system: the TC-regularised model's impulse
    response (from B/A) is closer to the truth than least squares' on average."""
    num, den = [0, 1.0, 0.5], [1, -1.5, 0.81]
    pulse = np.r_[1.0, np.zeros(59)]
    h = signal.lfilter(num, den, pulse)
    e_ls, e_tc = [], []
    for run in range(20):
        rng = np.random.default_rng(300 + run)
        u = rng.standard_normal(150)
        y = signal.lfilter(num, den, u) + signal.lfilter([1], den, 0.5 * rng.standard_normal(150))
        d = _data(u, y)

        def ir(m):
            return signal.lfilter(np.r_[0, m.b[0][0]], np.r_[1, m.a[0][0]], pulse)

        e_ls.append(np.sum((ir(sysid.arx(d, 10, 10, 1)) - h) ** 2))
        e_tc.append(np.sum((ir(sysid.arx(d, 10, 10, 1, regularization="tc")) - h) ** 2))
    assert np.mean(e_tc) < 0.7 * np.mean(e_ls), (np.mean(e_ls), np.mean(e_tc))


def test_band_limited_input_with_many_lags_is_tuned():
    """A multisine over part of the band, many lags, a large input and a small, nearly noise-free
    output (as the Bouc-Wen benchmark: u ~ 50, y ~ 7e-4): least squares' own coefficients
    blow up along the unexcited directions, the formed S = sigma^2 I + R1 P R1^T turns
    indefinite by round-off at every start point, and arxregul raised "not finite at any start
    point" (ssregest at its default 30 lags too). Now tuned, and the model simulates the
    record as a plain ARX model of low order does."""
    u = 50.0 * sysid.multisine(1024, band=(0.02, 0.3), periods=4, phases="random", seed=3)[:, 0]
    y = 1e-3 * signal.lfilter([0, 0.2, 0.1], [1, -1.2, 0.5], u / 50.0)
    y = y + 1e-3 * y.std() * np.random.default_rng(0).standard_normal(y.size)
    d = _data(u, y)
    reg = sysid.arxregul(d, 25, 25, 1, "tc")
    m = sysid.arx(d, 25, 25, 1, regularization=reg)
    assert float(sysid.compare(d, m).fit[0, 0]) > 99.0
    assert sysid.ssregest(d, 2, feedthrough=False).nstates == 2  # its default 30 lags


def test_lambda_to_zero_gives_plain_arx():
    d, _ = _fir_case(np.random.default_rng(1), n=300, taps=10)
    base = sysid.arx(d, 2, 6, 1)
    R = np.diag(np.arange(1.0, 9.0))
    exact = sysid.arx(d, 2, 6, 1, regularization=(0.0, R))
    np.testing.assert_array_equal(exact.a[0][0], base.a[0][0])
    np.testing.assert_array_equal(exact.b[0][0], base.b[0][0])
    near = sysid.arx(d, 2, 6, 1, regularization=(1e-10, R))
    np.testing.assert_allclose(near.b[0][0], base.b[0][0], atol=1e-8)
    # the posterior route with the tuned prior and lam -> 0
    reg = sysid.arxregul(d, 2, 6, 1, "tc")
    reg.lam = np.array([1e-12])
    post = sysid.arx(d, 2, 6, 1, regularization=reg)
    np.testing.assert_allclose(post.a[0][0], base.a[0][0], atol=1e-7)
    np.testing.assert_allclose(post.b[0][0], base.b[0][0], atol=1e-7)


def test_posterior_route_equals_matlab_pair_route():
    d, _ = _fir_case(np.random.default_rng(2), n=300, taps=10)
    reg = sysid.arxregul(d, 2, 4, 1, "dc")
    a = sysid.arx(d, 2, 4, 1, regularization=reg)
    b = sysid.arx(d, 2, 4, 1, regularization=(reg.lam[0], reg.R[0]))
    np.testing.assert_allclose(a.b[0][0], b.b[0][0], rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(a.a[0][0], b.a[0][0], rtol=1e-6, atol=1e-9)
    # the posterior covariance is the pair route's sigma^2 (Phi^T Phi + lam R)^-1 rescaled
    assert a.uncertainty.method == "posterior"
    assert np.all(np.diag(a.covariance[0]) > 0)
    assert a.info["regularization"] is reg and "lam=" in repr(reg)
    df = reg.to_pandas()
    assert list(df["block"]) == ["a[0]", "b[0]"] and {"c", "lambda", "rho"} <= set(df.columns)


def test_mimo_tunes_per_output_and_is_consistent():
    rng = np.random.default_rng(7)
    n = 3000
    u = rng.standard_normal((n, 2))
    y = np.zeros((n, 2))
    e = 0.05 * rng.standard_normal((n, 2))
    for t in range(2, n):
        y[t, 0] = 0.6 * y[t - 1, 0] - 0.2 * y[t - 1, 1] + u[t - 1, 0] + 0.3 * u[t - 2, 1] + e[t, 0]
        y[t, 1] = 0.1 * y[t - 1, 0] + 0.5 * y[t - 1, 1] + 0.7 * u[t - 1, 1] - 0.4 * u[t - 1, 0] \
            + e[t, 1]
    d = sysid.IOData(u, y, 1.0)
    reg = sysid.arxregul(d, [[1, 1], [1, 1]], 2, 1, "tc")
    assert reg.lam.shape == (2,) and len(reg.prior) == 2 and len(reg.hyperparameters[0]) == 4
    m = sysid.arx(d, [[1, 1], [1, 1]], 2, 1, regularization=reg)
    np.testing.assert_allclose(m.a[0][1], [0.2], atol=0.02)
    np.testing.assert_allclose(m.b[1][0], [-0.4, 0.0], atol=0.02)
    np.testing.assert_allclose(reg.lam, [0.0025, 0.0025], rtol=0.1)
    ml = sysid.arxregul(d, [[1, 1], [1, 1]], 2, 1, "ss", noise_variance="ml")
    np.testing.assert_allclose(ml.lam, [0.0025, 0.0025], rtol=0.1)


def test_bad_kernels_and_options():
    d, _ = _fir_case(np.random.default_rng(3), n=100, taps=5)
    with pytest.raises(DataError, match="unknown regularization kernel 'xyz'"):
        sysid.arx(d, 1, 2, 1, regularization="xyz")
    with pytest.raises(DataError, match="unknown regularization kernel"):
        sysid.arxregul(d, 1, 2, 1, "SE")
    with pytest.raises(DataError, match="noise_variance"):
        sysid.arxregul(d, 1, 2, 1, "tc", noise_variance="em")
    with pytest.raises(DataError, match="kernel= goes with a numeric"):
        sysid.arx(d, 1, 2, 1, regularization="tc", kernel=np.eye(3))
    with pytest.raises(DataError, match="positive semi-definite"):
        sysid.arx(d, 1, 2, 1, regularization=(1.0, -np.eye(3)))
    with pytest.raises(DataError, match="one pair, or 1 pairs"):
        sysid.arx(d, 1, 2, 1, regularization=(1.0, np.eye(3), 2))
    with pytest.raises(DataError, match="regularization must be a number"):
        sysid.arx(d, 1, 2, 1, regularization=True)
    with pytest.raises(DataError, match="tuned for orders"):
        sysid.arx(d, 1, 3, 1, regularization=sysid.arxregul(d, 1, 2, 1))
    with pytest.raises(DataError, match="decay lambda"):
        ar.kernel("tc", 3, (1.0, 1.5))
    with pytest.raises(DataError, match="takes 3 hyper"):
        ar.kernel("dc", 3, (1.0, 0.5))
    with pytest.raises(DataError, match="no parameters"):
        sysid.arxregul(d, 0, 0, 1)


# -- the Rust MIMO ARX kernel -----------------------------------------------------------------
def _reference_simulate(a, w):
    """The former per-sample Python loop of PolynomialModel.simulate (coupled A)."""
    n, ny = w.shape
    y = np.zeros((n, ny))
    for t in range(n):
        for i in range(ny):
            s = w[t, i]
            for k in range(ny):
                ak = np.asarray(a[i][k])
                for lag in range(1, min(ak.size, t) + 1):
                    s -= ak[lag - 1] * y[t - lag, k]
            y[t, i] = s
    return y


def _reference_predict(a, w, y, k):
    """The former numpy recursion of PolynomialModel._coupled_predict."""
    n, ny = y.shape
    na = max(len(a[i][q]) for i in range(ny) for q in range(ny))
    lags = np.zeros((na + 1, ny, ny))
    for i in range(ny):
        for q in range(ny):
            lags[1:len(a[i][q]) + 1, i, q] = a[i][q]
    preds = [y]
    for j in range(1, k + 1):
        p = w.copy()
        for lag in range(1, na + 1):
            if lag < n:
                p[lag:] -= preds[max(j - lag, 0)][: n - lag] @ lags[lag].T
        preds.append(p)
    return preds[k]


def _coupled_model():
    a = [[[-0.6, 0.1], [0.2]], [[-0.1], [-0.5, 0.05, 0.02]]]
    b = [[[1.0], [0.3, 0.1]], [[-0.4], [0.7]]]
    return sysid.PolynomialModel(a, b, [[1, 2], [1, 1]], 1.0)


def test_mimo_simulate_and_predict_match_former_python_loops():
    m = _coupled_model()
    rng = np.random.default_rng(4)
    u = rng.standard_normal((300, 2))
    y = m.simulate(u) + 0.1 * rng.standard_normal((300, 2))
    w = np.column_stack([m._deterministic(u, i) for i in range(2)])
    np.testing.assert_array_equal(m.simulate(u), _reference_simulate(m.a, w))
    for k in (1, 2, 3, 7, 400):
        np.testing.assert_allclose(m.predict(u, y, horizon=k), _reference_predict(m.a, w, y, k),
                                   rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(m.predict(u, y, horizon=400), m.simulate(u), atol=1e-12)
    np.testing.assert_allclose(m.residuals(u, y), y - m.predict(u, y, 1), atol=0)


def test_matrix_filter_siso_equals_lfilter_and_rejects_bad_shapes():
    rng = np.random.default_rng(6)
    w = rng.standard_normal((200, 1))
    a = [[[-1.5, 0.7]]]
    sim = _sysid.arx_matrix_filter(a, w)
    np.testing.assert_allclose(sim[:, 0], signal.lfilter([1.0], [1, -1.5, 0.7], w[:, 0]),
                               rtol=1e-12, atol=1e-12)
    with pytest.raises(ShapeError, match="A coefficients"):
        _sysid.arx_matrix_filter([[[0.5], [0.1]]], w)
    with pytest.raises(ShapeError, match="y"):
        _sysid.arx_matrix_filter(a, w, np.zeros((199, 1)), 1)
    with pytest.raises(DataError, match="horizon"):
        _sysid.arx_matrix_filter(a, w, w, 0)
    with pytest.raises(DataError, match="NaN"):
        _sysid.arx_matrix_filter([[[np.nan]]], w)
    with pytest.raises(DataError):
        _coupled_model().simulate(np.zeros((10, 3)))
