"""User-supplied NARX regressors (``sysid.CustomRegressor``): FROLS picks the true custom term
among the polynomial candidates and recovers the coefficients exactly on noise-free data;
simulation and prediction evaluate the function per sample; bad callables fail clearly."""

from __future__ import annotations

import numpy as np
import pytest

import sysid


def _system(n, seed, noise=0.0):
    """y = 0.5 y(t-1) + 0.8 u(t-1) - 0.4 y(t-1) |u(t-1)| + 0.3 sin(2 u(t-2))."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.5, 1.5, (n, 1))
    e = noise * rng.standard_normal(n)
    y = np.zeros((n, 1))
    for t in range(2, n):
        y[t] = (0.5 * y[t - 1] + 0.8 * u[t - 1] - 0.4 * y[t - 1] * abs(u[t - 1])
                + 0.3 * np.sin(2 * u[t - 2]) + e[t])
    return sysid.IOData(u, y, 1.0)


def _regressors():
    return [
        sysid.CustomRegressor(lambda y, u: y * np.abs(u), ["y0(t-1)", "u0(t-1)"],
                              name="y0(t-1)*|u0(t-1)|"),
        sysid.CustomRegressor(lambda u: np.sin(2 * u), ["u0(t-2)"], name="sin(2 u0(t-2))"),
        sysid.CustomRegressor(lambda u: np.cos(u), ["u0(t-1)"], name="cos(u0(t-1))"),
        sysid.CustomRegressor(lambda u: np.exp(-u ** 2), ["u0(t-1)"], name="gauss(u0(t-1))"),
    ]


def _coefs(m):
    return dict(zip(m.term_names(0), m.coefs[0]))


def test_true_custom_terms_are_selected_exactly():
    m = sysid.nlarx(_system(600, 1), 1, 2, basis=sysid.PolynomialBasis(3), max_terms=6,
                    criterion="bic", custom=_regressors())
    got = _coefs(m)
    truth = {"y0(t-1)": 0.5, "u0(t-1)": 0.8, "y0(t-1)*|u0(t-1)|": -0.4,
             "sin(2 u0(t-2))": 0.3}
    assert set(got) == set(truth), m.terms_table()
    for k, v in truth.items():
        assert abs(got[k] - v) < 1e-8
    # without the custom regressors the polynomial model cannot be exact
    poly = sysid.nlarx(_system(600, 1), 1, 2, basis=sysid.PolynomialBasis(3), max_terms=6,
                       criterion=None)
    assert poly.noise_variance[0] > 1e-6 > m.noise_variance[0]
    assert "tanh(y0(t-1))" in repr(sysid.CustomRegressor(np.tanh, ["y0(t-1)"]))


def test_free_run_and_prediction_evaluate_the_functions():
    est, val = _system(600, 1), _system(300, 2)
    m = sysid.nlarx(est, 1, 2, max_terms=6, criterion="bic", custom=_regressors())
    ys = m.simulate(val.u, x0=val.y[:m.max_lag])
    np.testing.assert_allclose(ys, val.y, atol=1e-8)
    np.testing.assert_allclose(m.predict(val.u, val.y, 1), val.y, atol=1e-8)
    np.testing.assert_allclose(m.predict(val.u, val.y, 5), val.y, atol=1e-8)
    assert sysid.compare(m, val).fit[0] > 99.99
    assert "y0(t-1)*|u0(t-1)|" in m.terms_table() and "sin(2 u0(t-2))" in m.summary()
    with pytest.raises(sysid.DataError, match="cannot be saved"):
        m.to_dict()


def test_custom_terms_with_noise_and_rbf_and_mimo():
    est = _system(2000, 3, noise=0.01)
    m = sysid.nlarx(est, 1, 2, max_terms=8, criterion="bic", custom=_regressors())
    assert {"y0(t-1)*|u0(t-1)|", "sin(2 u0(t-2))"} <= set(_coefs(m))
    r = sysid.nlarx(est, 1, 2, basis=sysid.RBFBasis(n_centres=5), max_terms=8,
                    criterion="bic", custom=_regressors()[:2])
    assert {"y0(t-1)*|u0(t-1)|", "sin(2 u0(t-2))"} <= set(_coefs(r))
    # 2 outputs: a custom term of the second output's lag in the first equation
    rng = np.random.default_rng(4)
    u = rng.uniform(-1, 1, (500, 2))
    y = np.zeros((500, 2))
    for t in range(1, 500):
        y[t, 0] = 0.3 * y[t - 1, 0] + u[t - 1, 0] + 0.5 * np.sin(3 * y[t - 1, 1])
        y[t, 1] = 0.5 * y[t - 1, 1] + u[t - 1, 1] - 0.2 * u[t - 1, 0] ** 2
    reg = sysid.CustomRegressor(lambda v: np.sin(3 * v), ["y1(t-1)"], name="sin(3 y1(t-1))")
    mm = sysid.nlarx(sysid.IOData(u, y, 1.0), 1, 1, max_terms=5, criterion="bic",
                     custom=[reg])
    assert abs(_coefs(mm)["sin(3 y1(t-1))"] - 0.5) < 1e-8
    assert "sin(3 y1(t-1))" not in mm.term_names(1)
    np.testing.assert_allclose(mm.simulate(u, x0=y[:1]), y, atol=1e-8)


def test_narmax_with_custom_regressors():
    rng = np.random.default_rng(5)
    n = 3000
    u = rng.uniform(-1, 1, (n, 1))
    e = 0.05 * rng.standard_normal(n)
    y = np.zeros((n, 1))
    for t in range(1, n):
        y[t] = 0.5 * y[t - 1] + np.sin(2 * u[t - 1]) + e[t] + 0.7 * e[t - 1]
    reg = sysid.CustomRegressor(lambda v: np.sin(2 * v), ["u0(t-1)"], name="s")
    m = sysid.nlarx(sysid.IOData(u, y, 1.0), 1, 1, max_terms=4, criterion="bic",
                    noise_terms=1, custom=[reg])
    c = _coefs(m)
    assert abs(c["s"] - 1.0) < 0.02 and abs(c["e_y0(t-1)"] - 0.7) < 0.05


@pytest.mark.parametrize(
    ("fn", "match"),
    [
        (lambda u: np.ones(3), "returned shape"),
        (lambda u: np.log(u), "non-finite"),
        (lambda u: u[None, :], "returned shape"),
        (lambda u: 1 / 0, "raised ZeroDivisionError"),
    ],
)
def test_bad_callables_give_clear_errors(fn, match):
    d = _system(200, 6)
    reg = sysid.CustomRegressor(fn, ["u0(t-1)"], name="bad")
    with pytest.raises(sysid.DataError, match=f"'bad'.*{match}|{match}"):
        sysid.nlarx(d, 1, 1, custom=[reg])


def test_bad_definitions_and_simulation_failures():
    d = _system(200, 6)
    with pytest.raises(sysid.DataError, match="callable"):
        sysid.CustomRegressor(3.0, ["u0(t-1)"])
    with pytest.raises(sysid.DataError, match="form"):
        sysid.CustomRegressor(np.sin, ["u0[t-1]"])
    with pytest.raises(sysid.DataError, match="neither an output"):
        sysid.nlarx(d, 1, 1, custom=[sysid.CustomRegressor(np.sin, ["z(t-1)"])])
    with pytest.raises(sysid.DataError, match="lag of at least 1"):
        sysid.nlarx(d, 1, 1, custom=[sysid.CustomRegressor(np.sin, ["y0(t)"])])
    # finite on the estimation data, not in simulation: the error names the regressor
    reg = sysid.CustomRegressor(lambda y: np.sqrt(y + 10.0), ["y0(t-1)"], name="root")
    m = sysid.NARXModel([1], [1], [1], sysid.PolynomialBasis(1), [[[0], [-1, 0]]],
                        [[0.5, 1.0]], 1.0, custom=[reg])
    assert m.term_names(0) == ["y0(t-1)", "root"]
    with pytest.raises(sysid.DataError, match="'root'"):
        m.simulate(np.zeros(20), x0=[[-30.0]])
    with pytest.raises(sysid.DataError, match="custom must be"):
        sysid.nlarx(d, 1, 1, custom=[np.sin])
