"""Faults of the audit 46 (second round) in the estimators' Python layer: the recursive
estimators' sample time, the output-error model's forecast band, greyest's initial state under
a first-order hold, nlarx on a record shorter than its term budget, and integer-valued floats
as orders."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy import signal

import sysid
from sysid import DataError, InsufficientDataError


# -- 1. Recursive*.run(IOData) keeps the record's dt -----------------------------------------
def _first_order(n: int = 500, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n)
    y = np.zeros(n)
    for t in range(1, n):
        y[t] = 0.5 * y[t - 1] + u[t - 1]
    return u, y


@pytest.mark.parametrize("make", [lambda **kw: sysid.RecursiveARX(1, 1, **kw),
                                  lambda **kw: sysid.RecursiveARMAX(1, 1, 1, **kw),
                                  lambda **kw: sysid.RecursiveOE(1, 1, **kw),
                                  lambda **kw: sysid.RecursiveBJ(1, 1, 1, 1, **kw)])
def test_recursive_run_takes_the_record_dt(make):
    u, y = _first_order()
    est = make()
    res = est.run(sysid.IOData(u[:, None], y[:, None], 0.01))
    assert res.dt == 0.01 and est.dt == 0.01  # was 1.0
    assert res.to_pandas().index[-1] == pytest.approx(4.99)  # was 499 (samples)
    assert est.to_model().dt == 0.01
    # the next piece of the same record carries on; arrays take the estimator's dt
    assert est.run(u[:10], y[:10]).dt == 0.01


def test_recursive_arx_pole_matches_batch_rate():
    u, y = _first_order()
    data = sysid.IOData(u[:, None], y[:, None], 0.01)
    est = sysid.RecursiveARX(1, 1)
    est.run(data)
    m = est.to_model()
    rate = np.log(np.abs(m.poles())) / m.dt
    np.testing.assert_allclose(rate, np.log(0.5) / 0.01, rtol=1e-6)  # was -0.69 1/s


def test_recursive_dt_given_and_record_dt_differ():
    u, y = _first_order()
    data = sysid.IOData(u[:, None], y[:, None], 0.01)
    est = sysid.RecursiveARX(1, 1, dt=0.1)
    with pytest.raises(DataError, match=r"dt=0\.01 differs from the estimator's dt=0\.1 "
                                        r"\(the constructor's dt\)"):
        est.run(data)
    assert est.samples == 0  # nothing was processed
    same = sysid.RecursiveARX(1, 1, dt=0.01)
    assert same.run(data).dt == 0.01
    # a second record of another dt than the first one's
    first = sysid.RecursiveARX(1, 1)
    first.run(data)
    with pytest.raises(DataError, match=r"dt=0\.02 differs .*first record"):
        first.run(sysid.IOData(u[:, None], y[:, None], 0.02))
    # arrays alone: dt 1 as before
    assert sysid.RecursiveARX(1, 1).run(u, y).dt == 1.0


# -- 2. forecast of an output-error model uses its noise variance ----------------------------
def test_oe_statespace_keeps_noise_variance():
    mo = sysid.PolynomialModel([[[]]], [[[0, 0.5]]], [[0]], 1.0, f=[[[-0.7]]],
                               noise_variance=[0.09])
    ss = mo.to_statespace()
    assert ss.noise_cov is not None  # was None
    np.testing.assert_allclose(ss.noise_cov, [[0.09]])


def test_oe_forecast_band_is_the_noise_std():
    rng = np.random.default_rng(0)
    n = 2000
    u = rng.standard_normal(n)
    y = signal.lfilter([0, 0.5], [1, -0.7], u) + 0.3 * rng.standard_normal(n)
    m = sysid.oe(sysid.IOData(u[:, None], y[:, None], 1.0), 1, 1, 1)
    lam = float(m.noise_variance[0])
    uf = np.zeros((3, 1))
    for past in (2000, 20, 3):  # a 3-sample past gave std 0.57 (its own residuals)
        rec = (u[-past:, None], y[-past:, None])
        f = sysid.forecast(m, rec, 3, future_inputs=uf, initial_condition="zero")
        np.testing.assert_allclose(f.std[:, 0], np.sqrt(lam), rtol=1e-12)
        # the fitted start (the default) adds its own uncertainty, gone on a long past
        g = sysid.forecast(m, rec, 3, future_inputs=uf)
        assert np.all(g.std[:, 0] >= np.sqrt(lam) * (1 - 1e-12))
        assert np.allclose(g.std[:, 0], np.sqrt(lam), rtol={2000: 1e-12, 20: 1e-5, 3: 0.05}[past])


# -- 3. greyest with hold="foh" reports the physical initial state ---------------------------
def _dc_motor(p, dt=None):
    return [[0, 1], [0, -1 / p.tau]], [[0], [p.G / p.tau]], np.eye(2), np.zeros((2, 1))


_A, _B, _C, _D = _dc_motor(type("P", (), {"tau": 0.5, "G": 3.0})())


def _foh_record(x0, delay=0.0, n=300, dt=0.1, fine=10):
    """Noise-free outputs of the DC motor driven by the linear interpolation of the samples
    (the input before the record is zero), delayed by ``delay`` s: scipy's lsim."""
    rng = np.random.default_rng(3)
    u = rng.standard_normal(n)
    u[0] = 1.0
    tf = np.arange(n * fine) * dt / fine
    uf = np.interp(tf - delay, np.arange(-1, n) * dt, np.r_[0.0, u], left=0.0)
    _, yf, _ = signal.lsim((_A, _B, _C, _D), uf, tf, X0=x0, interp=True)
    return sysid.IOData(u=u, y=yf[::fine], dt=dt)


def test_greyest_foh_initial_state_is_physical():
    data = _foh_record([0.5, -1.0])
    fit = sysid.greyest(data, sysid.GreyBox(_dc_motor, {"tau": 1.0, "G": 1.0}, hold="foh"))
    np.testing.assert_allclose(fit.parameters.value, [0.5, 3.0], rtol=1e-6)
    # was [0.490, -1.281], the sampled model's x - G2 u(0)
    np.testing.assert_allclose(fit.initial_states[0], [0.5, -1.0], atol=1e-6)
    ys = fit.model.simulate(data.u, dt=data.dt, x0=fit.initial_states[0])
    assert np.abs(ys - data.y).max() < 1e-8  # was 0.28
    # the sampled model's own state stays in info
    assert np.abs(fit.info["x0_values"][0] - [0.5, -1.0]).max() > 0.1


@pytest.mark.parametrize("delay", [0.03, 0.1, 0.13])
def test_greyest_foh_initial_state_with_input_delay(delay):
    data = _foh_record([0.5, -1.0], delay)
    s = sysid.GreyBox(_dc_motor, {"tau": 1.0, "G": 1.0}, hold="foh", input_delay=delay)
    fit = sysid.greyest(data, s)
    np.testing.assert_allclose(fit.parameters.value, [0.5, 3.0], rtol=1e-6)
    np.testing.assert_allclose(fit.initial_states[0], [0.5, -1.0], atol=1e-6)


def test_greyest_foh_given_and_zero_initial_states_are_physical():
    s = sysid.GreyBox(_dc_motor, {"tau": 1.0, "G": 1.0}, hold="foh")
    given = sysid.greyest(_foh_record([0.5, -1.0]), s, x0=[0.5, -1.0])
    np.testing.assert_allclose(given.parameters.value, [0.5, 3.0], rtol=1e-8)  # was 0.509
    np.testing.assert_allclose(given.initial_states[0], [0.5, -1.0], atol=1e-12)
    rest = sysid.greyest(_foh_record([0.0, 0.0]), s, x0="zero")
    np.testing.assert_allclose(rest.parameters.value, [0.5, 3.0], rtol=1e-8)
    np.testing.assert_allclose(rest.initial_states[0], [0.0, 0.0], atol=1e-12)


def test_greyest_foh_two_experiments():
    a, b = _foh_record([0.5, -1.0]), _foh_record([-0.2, 0.4])
    data = sysid.IOData(u=[a.u, b.u], y=[a.y, b.y], dt=0.1)
    fit = sysid.greyest(data, sysid.GreyBox(_dc_motor, {"tau": 1.0, "G": 1.0}, hold="foh"))
    np.testing.assert_allclose(fit.initial_states[0], [0.5, -1.0], atol=1e-6)
    np.testing.assert_allclose(fit.initial_states[1], [-0.2, 0.4], atol=1e-6)


# -- 4. nlarx on a record with fewer rows than the terms FROLS may select ---------------------
def test_nlarx_fewer_rows_than_terms_raises():
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, 5)
    y = np.zeros(5)
    for t in range(2, 5):
        y[t] = 0.5 * y[t - 1] + 0.8 * u[t - 1]
    data = sysid.IOData(u[:, None], y[:, None], 1.0)
    with pytest.raises(InsufficientDataError,
                       match=r"3 regression rows for 35 candidate terms, of which FROLS may "
                             r"select 10 \(max_terms=10\).*longer record.*lower degree"):
        sysid.nlarx(data, 2, 2, basis=sysid.PolynomialBasis(3))


def test_nlarx_enough_rows_still_fits():
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, 60)
    y = np.zeros(60)
    for t in range(2, 60):
        y[t] = 0.5 * y[t - 1] + 0.8 * u[t - 1] - 0.2 * u[t - 2] ** 2
    m = sysid.nlarx(sysid.IOData(u[:, None], y[:, None], 1.0), 2, 2,
                    basis=sysid.PolynomialBasis(2))
    assert m.info["n_rows"] == 58 and m.info["n_candidates"] == 15


# -- 5. integer-valued floats as orders ---------------------------------------------------------
_RNG = np.random.default_rng(0)
_Y = signal.lfilter([1], [1, -0.5], _RNG.standard_normal(200))
_U = _RNG.standard_normal(200)


def _quiet(f, *args, **kw):
    """``f`` with the iteration-limit warning of a deliberately short search silenced."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sysid.IterationLimitWarning)
        return f(*args, **kw)


_REC = sysid.IOData(_U[:, None], (np.convolve(_U, [0, 1, 0.5])[:200]
                                + 0.1 * _RNG.standard_normal(200))[:, None], 1.0)


@pytest.mark.parametrize("call", [
    lambda: sysid.ar(_Y, 2.0),
    lambda: sysid.ar(_Y, np.float64(2)),
    lambda: sysid.arma(_Y, 1.0, 1.0),
    lambda: sysid.RecursiveARX(2.0, 2.0, 1.0),
    lambda: sysid.RecursiveARX(np.array([2.0, 2.0, 1.0])),
    lambda: sysid.RecursiveARMAX(np.float64(1), 1.0, 1.0, 1.0),
    lambda: sysid.RecursiveOE(2.0, 1.0, 1.0),
    lambda: sysid.RecursiveBJ(1.0, 1.0, 1.0, 1.0, 1.0),
    lambda: _quiet(sysid.pnlss, _REC, 2.0, degree=2, max_iter=2, progress=False),
    lambda: sysid.forecast(sysid.ar(_Y, 2), _Y, 3.0),
], ids=["ar", "ar np", "arma", "rarx", "rarx vector", "rarmax", "roe", "rbj", "pnlss",
        "forecast"])
def test_integer_valued_floats_accepted(call):
    call()


def test_integer_valued_floats_give_the_same_model():
    np.testing.assert_array_equal(sysid.ar(_Y, 2.0).a[0][0], sysid.ar(_Y, 2).a[0][0])
    assert sysid.RecursiveARX(np.array([2.0, 2.0, 1.0])).names == \
        sysid.RecursiveARX(2, 2, 1).names
    f1, f2 = (sysid.forecast(sysid.ar(_Y, 2), _Y, h) for h in (3.0, 3))
    np.testing.assert_array_equal(f1.mean, f2.mean)


@pytest.mark.parametrize("call, message", [
    (lambda: sysid.ar(_Y, 2.5), "na must be a positive integer, got 2.5"),
    (lambda: sysid.ar(_Y, np.nan), "na must be a positive integer, got nan"),
    (lambda: sysid.ar(_Y, True), "na must be a positive integer, got True"),
    (lambda: sysid.ar(_Y, -1.0), "na must be a positive integer, got -1.0"),
    (lambda: sysid.arma(_Y, 1, -1.0), "nc must be an integer >= 0, got -1.0"),
    (lambda: sysid.RecursiveARX(2.5, 2, 1), "na must be an integer >= 0, got 2.5"),
    (lambda: sysid.RecursiveARX(2, 2.5, 1), "nb must be an integer >= 0, got 2.5"),
    (lambda: sysid.RecursiveARX(2, 2, 1.5), "nk must be an integer >= 0, got 1.5"),
    (lambda: sysid.RecursiveARX(np.array([2.0, 2.5, 1.0])), "nb must be an integer >= 0"),
    (lambda: sysid.RecursiveARX(2, True), "nb must be an integer >= 0, got True"),
    (lambda: sysid.pnlss(_REC, 2.5, progress=False), "order must be a positive integer, got 2.5"),
    (lambda: sysid.forecast(sysid.ar(_Y, 2), _Y, 2.5),
     "horizon must be a positive integer, got 2.5"),
    (lambda: sysid.forecast(sysid.ar(_Y, 2), _Y, np.inf),
     "horizon must be a positive integer, got inf"),
])
def test_non_integers_still_refused(call, message):
    with pytest.raises(DataError, match=message.replace("(", r"\(")):
        call()


def test_integer_valued_floats_everywhere_a_count_is_taken():
    # n4sid(d, 2.0), ssest(..., max_iter=5.0), era(h, 2.0), impulse_response(d, 50.0) and
    # delayest refused what arx took: the one integer check now takes whole floats
    import warnings

    d = sysid.datasets.load_dryer()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert sysid.n4sid(d, 2.0).nstates == sysid.n4sid(d, 2).nstates == 2
        assert sysid.ssest(d, 2, max_iter=5.0).info["pem"]["iterations"] <= 5
        h = sysid.impulse_response(d, 50.0)
        assert h.markov.shape[0] == sysid.impulse_response(d, 50).markov.shape[0]
        assert sysid.era(h, 2.0).model.nstates == 2
    with pytest.raises(sysid.DataError, match="got 2.5"):
        sysid.n4sid(d, 2.5)
