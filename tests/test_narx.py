"""NARX / NARMAX: FROLS recovers known polynomial systems (SISO and 2 x 2, several
experiments), noisy selection is reliable in Monte Carlo, simulation/prediction/saving work
through the model protocol."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from _guides import run_guide

import sysid
from sysid import _sysid


def _term_set(model, i=0):
    return {tuple(t): c for t, c in zip(model.terms[i], model.coefs[i])}


def billings(n, seed, noise=0.0):
    """y = -0.605 y1 - 0.163 y2^2 + 0.588 u1 - 0.24 u2 (+ equation noise)."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, (n, 1))
    e = noise * rng.standard_normal(n)
    y = np.zeros((n, 1))
    for t in range(2, n):
        y[t] = -0.605 * y[t - 1] - 0.163 * y[t - 2] ** 2 + 0.588 * u[t - 1] - 0.24 * u[t - 2] \
            + e[t]
    return u, y


# variables with na=2, nb=2, nk=1: 0 y(t-1), 1 y(t-2), 2 u(t-1), 3 u(t-2)
BILLINGS = {(0,): -0.605, (1, 1): -0.163, (2,): 0.588, (3,): -0.24}


def cubic(n, seed, noise=0.0):
    """Degree 3: y = 0.5 y1 + 0.8 u1 - 0.3 u1^3 + 0.2 y1 u1^2 - 0.1 u2."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, (n, 1))
    e = noise * rng.standard_normal(n)
    y = np.zeros((n, 1))
    for t in range(2, n):
        y[t] = (0.5 * y[t - 1] + 0.8 * u[t - 1] - 0.3 * u[t - 1] ** 3
                + 0.2 * y[t - 1] * u[t - 1] ** 2 - 0.1 * u[t - 2] + e[t])
    return u, y


CUBIC = {(0,): 0.5, (2,): 0.8, (2, 2, 2): -0.3, (0, 2, 2): 0.2, (3,): -0.1}


def mimo(n, seed, noise=0.0):
    """2 x 2, degree 2, coupled through outputs and inputs."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, (n, 2))
    e = noise * rng.standard_normal((n, 2))
    y = np.zeros((n, 2))
    for t in range(1, n):
        y0, y1, u0, u1 = y[t - 1, 0], y[t - 1, 1], u[t - 1, 0], u[t - 1, 1]
        y[t, 0] = 0.4 * y0 + 0.7 * u0 + 0.3 * u1 * y1 + e[t, 0]
        y[t, 1] = -0.3 * y1 + 0.6 * u1 - 0.25 * u0 ** 2 + 0.2 * y0 + e[t, 1]
    return u, y


# variables with na=1 (each output), nb=1, nk=1: 0 y0(t-1), 1 y1(t-1), 2 u0(t-1), 3 u1(t-1)
MIMO = [{(0,): 0.4, (2,): 0.7, (1, 3): 0.3}, {(1,): -0.3, (3,): 0.6, (2, 2): -0.25, (0,): 0.2}]


def _check_exact(model, truth, i=0):
    got = _term_set(model, i)
    assert set(got) == set(truth), (model.term_names(i), truth)
    for k, v in truth.items():
        assert abs(got[k] - v) < 1e-8


def test_siso_degree2_exact_terms_and_coefficients():
    u, y = billings(500, 1)
    m = sysid.nlarx(sysid.IOData(u, y, 1.0), 2, 2, basis=sysid.PolynomialBasis(2),
                    max_terms=10)
    _check_exact(m, BILLINGS)
    # degree 3 candidates contain the degree-2 system: still exactly its terms
    m3 = sysid.nlarx(sysid.IOData(u, y, 1.0), 2, 2, basis=sysid.PolynomialBasis(3),
                     max_terms=10)
    _check_exact(m3, BILLINGS)


def test_siso_degree3_exact_terms_and_coefficients():
    u, y = cubic(600, 2)
    m = sysid.nlarx(sysid.IOData(u, y, 1.0), 2, 2, basis=sysid.PolynomialBasis(3),
                    max_terms=12)
    _check_exact(m, CUBIC)


def test_mimo_2x2_several_experiments_exact():
    (u1, y1), (u2, y2) = mimo(300, 3), mimo(250, 4)
    data = sysid.IOData([u1, u2], [y1, y2], 1.0)
    m = sysid.nlarx(data, 1, 1, basis=sysid.PolynomialBasis(2), max_terms=10)
    for i in range(2):
        _check_exact(m, MIMO[i], i)
    # free run of the identified model reproduces a new record from its initial output
    u, y = mimo(200, 5)
    assert np.max(np.abs(m.simulate(u, x0=y[:1]) - y)) < 1e-8
    assert np.max(np.abs(m.predict(u, y, 3) - y)) < 1e-8


def test_one_experiment_equals_its_split_rows_are_not_mixed():
    """Two experiments are two records: no regression row spans their junction."""
    (u1, y1), (u2, y2) = billings(300, 6), billings(300, 7)
    two = sysid.nlarx(sysid.IOData([u1, u2], [y1, y2], 1.0), 2, 2)
    _check_exact(two, BILLINGS)
    glued = sysid.nlarx(sysid.IOData(np.vstack([u1, u2]), np.vstack([y1, y2]), 1.0), 2, 2,
                        criterion=None, max_terms=4)
    assert glued.noise_variance[0] > 1e-12  # the junction rows are not explained


def test_blocking_does_not_change_the_selection():
    u, y = cubic(700, 8, noise=0.05)
    structure = {"orders": ([2], [2], [1], [0]), "degree": 3}
    runs = [_sysid.narx_frols([(u, y, None)], structure, 8, [[]], 1e-10, b)
            for b in (0, 5, 64, 1000)]
    for sel, _ in runs[1:]:
        assert sel[0]["terms"] == runs[0][0][0]["terms"]
        np.testing.assert_allclose(sel[0]["err"], runs[0][0][0]["err"], rtol=1e-9, atol=1e-14)
        np.testing.assert_allclose(sel[0]["r"], runs[0][0][0]["r"], rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("system,truth,degree", [(billings, BILLINGS, 2), (cubic, CUBIC, 3)])
def test_monte_carlo_true_terms_selected(system, truth, degree):
    runs, hits = 20, 0
    for seed in range(runs):
        u, y = system(800, 100 + seed, noise=0.05)
        m = sysid.nlarx(sysid.IOData(u, y, 1.0), 2, 2, basis=sysid.PolynomialBasis(degree),
                        max_terms=10, criterion="bic")
        hits += set(truth) <= set(_term_set(m))
    assert hits / runs >= 0.95


def test_mimo_monte_carlo_true_terms_selected():
    runs, hits = 20, 0
    for seed in range(runs):
        u, y = mimo(600, 200 + seed, noise=0.03)
        m = sysid.nlarx(sysid.IOData(u, y, 1.0), 1, 1, max_terms=8, criterion="bic")
        hits += all(set(MIMO[i]) <= set(_term_set(m, i)) for i in range(2))
    assert hits / runs >= 0.95


def test_criterion_and_budget_change_the_model():
    u, y = billings(600, 9, noise=0.05)
    d = sysid.IOData(u, y, 1.0)
    poly = sysid.PolynomialBasis(2)  # the selection itself (basis="auto" may take the ARX)
    full = sysid.nlarx(d, 2, 2, max_terms=10, criterion=None, basis=poly)
    aic = sysid.nlarx(d, 2, 2, max_terms=10, criterion="aic", basis=poly)
    bic = sysid.nlarx(d, 2, 2, max_terms=10, criterion="bic", basis=poly)
    small = sysid.nlarx(d, 2, 2, max_terms=2, criterion=None, basis=poly)
    assert full.n_parameters == 10 and small.n_parameters == 2
    assert bic.n_parameters <= aic.n_parameters <= full.n_parameters
    uv, yv = billings(400, 10, noise=0.05)
    val = sysid.nlarx(d, 2, 2, max_terms=10, criterion="validation", basis=poly,
                      validation=sysid.IOData(uv, yv, 1.0))
    assert set(BILLINGS) <= set(_term_set(val))
    fpe = sysid.nlarx(d, 2, 2, max_terms=10, criterion="fpe", basis=poly)
    assert fpe.n_parameters >= 4


def test_prediction_horizons_and_protocol():
    u, y = billings(400, 11, noise=0.05)
    m = sysid.nlarx(sysid.IOData(u, y, 1.0), 2, 2)
    assert isinstance(m, sysid.Model)
    p1, p5 = m.predict(u, y, 1), m.predict(u, y, 5)
    s = m.simulate(u, x0=y[:2])
    e1, e5, es = (float(np.mean((y - p) ** 2)) for p in (p1, p5, s))
    assert e1 < e5 <= es * 1.5
    # a horizon longer than the record is a free run from the measured start
    np.testing.assert_allclose(m.predict(u, y, 10_000)[2:], s[2:], atol=1e-12)
    c = sysid.compare(m, sysid.IOData(u, y, 1.0))
    assert c.fit[0] > 80
    # the linearisation around zero: the linear terms' ARX model
    assert np.allclose(sorted(np.abs(m.poles())), sorted(np.abs(np.roots([1, 0.605, 0]))),
                       atol=0.05)
    assert m.freqresp(np.array([0.1, 1.0])).shape == (2, 1, 1)


def test_save_load_roundtrip(tmp_path):
    u, y = billings(400, 12)
    for basis in (sysid.PolynomialBasis(2), sysid.RBFBasis(6)):
        m = sysid.nlarx(sysid.IOData(u, y, 1.0), 2, 2, basis=basis, max_terms=8)
        for ext in ("json", "npz"):
            sysid.save_model(m, tmp_path / f"m.{ext}")
            m2 = sysid.load_model(tmp_path / f"m.{ext}")
            np.testing.assert_array_equal(m2.simulate(u), m.simulate(u))
            assert m2.term_names() == m.term_names()


def test_rbf_basis_fits_a_smooth_nonlinearity():
    rng = np.random.default_rng(13)
    u = rng.uniform(-2, 2, (1500, 1))
    y = np.zeros((1500, 1))
    for t in range(1, 1500):
        y[t] = 0.5 * y[t - 1] + np.tanh(2 * u[t - 1])
    d = sysid.IOData(u, y, 1.0)
    lin = sysid.nlarx(d, 1, 1, basis=sysid.PolynomialBasis(1), max_terms=3)
    rbf = sysid.nlarx(d, 1, 1, basis=sysid.RBFBasis(12), max_terms=15)
    assert rbf.noise_variance[0] < 0.2 * lin.noise_variance[0]
    assert "rbf" in " ".join(rbf.term_names())


def test_narmax_noise_terms_by_extended_least_squares():
    rng = np.random.default_rng(14)
    n = 3000
    u = rng.uniform(-1, 1, (n, 1))
    e = 0.1 * rng.standard_normal(n)
    y = np.zeros((n, 1))
    for t in range(1, n):
        y[t] = 0.5 * y[t - 1] + u[t - 1] - 0.3 * u[t - 1] ** 2 + e[t] + 0.8 * e[t - 1]
    d = sysid.IOData(u, y, 1.0)
    m = sysid.nlarx(d, 1, 1, max_terms=6, criterion="bic", noise_terms=1, n_iterations=8)
    got = _term_set(m)
    # variables: 0 y(t-1), 1 u(t-1), 2 e(t-1)
    assert (2,) in got and abs(got[(2,)] - 0.8) < 0.1
    assert abs(got[(0,)] - 0.5) < 0.05 and abs(got[(1,)] - 1.0) < 0.05
    assert "NARMAX" in repr(m)
    # NARX alone is biased on the y(t-1) coefficient by the coloured noise
    narx = _term_set(sysid.nlarx(d, 1, 1, max_terms=6, criterion="bic"))
    assert abs(narx[(0,)] - 0.5) > abs(got[(0,)] - 0.5)
    # one-step residuals of the NARMAX model are close to white e
    r = y[1:, 0] - m.predict(u, y, 1)[1:, 0]
    assert abs(np.std(r) - 0.1) < 0.01


def test_presentation():
    u, y = billings(300, 15)
    m = sysid.nlarx(sysid.IOData(u, y, 1.0), 2, 2)
    df = m.to_pandas()
    assert list(df.columns) == ["output", "term", "coefficient", "err"] and len(df) == 4
    assert "y0(t-2)^2" in m.summary()
    assert np.isclose(df["err"].sum(), 1.0, atol=1e-9)
    assert m.info["n_candidates"] == 15 and m.info["method"] == "nlarx"


def test_errors():
    u, y = billings(100, 16)
    d = sysid.IOData(u, y, 1.0)
    with pytest.raises(sysid.DataError, match="criterion"):
        sysid.nlarx(d, 2, 2, criterion="cv")
    with pytest.raises(sysid.DataError, match="validation"):
        sysid.nlarx(d, 2, 2, criterion="validation")
    with pytest.raises(sysid.DataError, match="PolynomialBasis"):
        sysid.nlarx(d, 2, 2, basis=sysid.RBFBasis(3), noise_terms=1)
    with pytest.raises(sysid.DataError, match="candidate monomials"):
        sysid.nlarx(d, 30, 30, basis=sysid.PolynomialBasis(6))
    with pytest.raises(sysid.InsufficientDataError):
        sysid.nlarx(sysid.IOData(u[:3], y[:3], 1.0), 5, 2)
    yb = y.copy()
    yb[10] = np.nan
    with pytest.raises(sysid.SysidError):
        sysid.nlarx(sysid.IOData(u, yb, 1.0), 2, 2)
    unstable = sysid.NARXModel([1], [1], [1], sysid.PolynomialBasis(2), [[[0, 0]]], [[2.0]],
                               1.0)
    with pytest.raises(sysid.NumericalError, match="diverged"):
        unstable.simulate(np.ones(50), x0=[[2.0]])


def test_docs_nonlinear_examples_and_their_claims(capsys):
    """Runs every ```python block of docs/nonlinear.md; the stated outcomes hold."""
    ns = run_guide("nonlinear.md")
    out = capsys.readouterr().out
    assert "y0(t-2)^2" in out and "e_y0(t-1)" in out
    assert set(BILLINGS) == set(_term_set(ns["m"]))
    assert ns["c"].fit[0] > 95
    np.testing.assert_allclose(ns["ham"].input_nl.params, [-0.4, 0.6], atol=1e-6)
    # the F-16 statements: NARX does not win, the Hammerstein model does (numbers in the doc)
    assert ns["narx_rmse"] > ns["best_linear"] >= ns["hw_rmse"] - 1e-4
    assert abs(ns["best_linear"] - 0.0711) < 5e-4 and abs(ns["hw_rmse"] - 0.0711) < 5e-4
    # custom regressors: the true terms, exact
    assert set(ns["cm"].term_names(0)) == {"y0(t-1)", "u0(t-1)", "y0(t-1)*|u0(t-1)|",
                                           "sin(2 u0(t-2))"}
    # F-16 level 3 -> level 2 (table in the doc): chosen by level 3, NARX wins on level 2.
    # The high-order OE fits end in one of several minima with the processor's rounding
    # (the doc's two columns): the linear choice is one of them, either way behind NARX
    lin, nx = ns["f16_linear"], ns["f16_narx"]
    best = ns["f16_best_lin"]
    assert ns["f16_best_narx"].startswith("nlarx(20,21,0)")
    seen = {"oe(17,16,0)": [0.1085, 0.2921], "oe(15,14,0)": [0.1302, 0.2967]}
    assert best in seen, lin
    np.testing.assert_allclose(lin[best], seen[best], atol=5e-4)
    np.testing.assert_allclose(lin["arx(18,19,0)"], [0.1769, 0.2984], atol=5e-4)
    np.testing.assert_allclose(nx[ns["f16_best_narx"]], [0.1328, 0.2232], atol=5e-4)
    assert lin[best][1] > 1.3 * nx[ns["f16_best_narx"]][1]
    assert nx[ns["f16_best_narx"]][1] < min(v[1] for v in lin.values())
    # pH: NARX chosen on samples 701-1000 beats the chosen linear model on 1001-2001
    pl, pn = ns["ph_linear"][ns["ph_best_lin"]], ns["ph_narx"][ns["ph_best_narx"]]
    assert ns["ph_best_lin"] == "arx(1,3,0)" and ns["ph_best_narx"].startswith("nlarx(1,1,1)")
    np.testing.assert_allclose([pl[1], pn[1]], [1.849, 1.364], atol=5e-3)
    assert sum(np.isinf(v[1]) for v in ns["ph_narx"].values()) == 3
    # the three that diverge on validation already did on their fitting data, and said so
    assert sorted(ns["ph_warned"]) == sorted(k for k, v in ns["ph_narx"].items()
                                             if np.isinf(v[1]))
    pw = ns["ph_wiener"][ns["ph_best_wiener"]]
    assert ns["ph_best_wiener"] == "nlhw_ss(2) sigmoid(2)"
    np.testing.assert_allclose(pw, [0.388, 0.736], atol=5e-3)
    # the MIMO Hammerstein example: poles and nonlinearities
    np.testing.assert_allclose(np.sort(ns["ham2"].poles().real), [0.5, 0.8], atol=1e-6)
    np.testing.assert_allclose(ns["ham2"].input_nls[0].params, [-0.5, 0.6], atol=1e-6)
    np.testing.assert_allclose(ns["ham2"].input_nls[1].params, [0.3], atol=1e-6)


def test_a_model_without_input_terms_warns():
    # A lightly damped plant sampled fast under a slow input (as a motor position at 1 kHz):
    # the output lags explain all but about 1e-11 of the output one step ahead, FROLS stops
    # before any input term, and the model's simulation is a constant. It said nothing.
    t = np.arange(3000)
    u = np.sin(2 * np.pi * t / 1500) + 0.5 * np.sin(2 * np.pi * t / 700)
    y = np.zeros(3000)
    for k in range(2, 3000):
        y[k] = 1.99 * y[k - 1] - 0.99 * y[k - 2] + 1e-5 * u[k - 1]
    d = sysid.IOData(u[:, None], y[:, None], 1.0)
    poly = sysid.PolynomialBasis(2)
    with pytest.warns(sysid.ExcitationWarning, match="no selected term involves an input"):
        m = sysid.nlarx(d, 2, 2, basis=poly)
    assert m.info["uses_input"] is False
    assert np.ptp(m.simulate(u[:, None])) == 0.0
    # with a smaller err_tol the input term is selected, and nothing is said
    m = sysid.nlarx(d, 2, 2, err_tol=1e-16, basis=poly)
    assert any("u0" in n for n in m.term_names()) and "uses_input" not in m.info
    # by default (basis="auto") the linear ARX model of these lags, every lag kept, is
    # taken: the held-out blocks insist on it over the input-free polynomial model
    m = sysid.nlarx(d, 2, 2)
    assert m.info["basis_choice"]["kind"] == "linear" and "uses_input" not in m.info
    assert any("u0" in n for n in m.term_names())


def test_compare_runs_a_narx_model_from_the_measured_first_outputs():
    # A NARX model's state is its past outputs. compare started it from zero outputs, so a
    # record far from zero read as a long transient (heat exchanger: "diverged", -inf,
    # where nlarx's own validation criterion, run from the measured outputs, gave 12.3 %),
    # and it refused an array x0 that simulate accepts.
    rng = np.random.default_rng(21)
    u = rng.uniform(-1, 1, 600)
    y = np.zeros(600)
    y[0] = 20.0
    for t in range(1, 600):
        y[t] = 0.99 * y[t - 1] + 0.5 * u[t - 1] - 0.1 * u[t - 1] ** 2 + 0.2
    d = sysid.IOData(u, y, 1.0)
    m = sysid.nlarx(d, 1, 1, 1, basis=sysid.PolynomialBasis(2))
    own = m.simulate(u, x0=y[:1])[1:, 0]  # sample 0 is the initial condition: not scored
    want = 100 * (1 - np.linalg.norm(own - y[1:]) / np.linalg.norm(y[1:] - y[1:].mean()))
    assert sysid.compare(m, d).fit[0, 0] == pytest.approx(want, abs=1e-9)
    assert want > 99.9
    assert sysid.compare(m, d, x0=y[:1]).fit[0, 0] == pytest.approx(want, abs=1e-9)
    assert sysid.compare(m, d, x0="zero").fit[0, 0] < want - 1


def test_non_integer_lags_are_refused_not_truncated():
    rng = np.random.default_rng(22)
    u = rng.uniform(-1, 1, 300)
    d = sysid.IOData(u, np.convolve(u, [0, 0.5, 0.2])[:300], 1.0)
    for bad in ((2.5, 1, 1), (2, 1.7, 1), (2, 1, 0.5)):
        with pytest.raises(sysid.DataError, match="must be a non-negative integer"):
            sysid.nlarx(d, *bad)
    sysid.nlarx(d, 2.0, 1, 1)  # an integral float is a lag


def test_a_short_record_does_not_keep_a_term_per_row():
    # 12 samples, 10 regression rows: AIC kept 10 terms (an exact interpolation of the
    # noise, residual variance 1e-31); now at most half the rows, and a record without two
    # rows is refused
    rng = np.random.default_rng(0)
    u = rng.standard_normal(12)
    y = np.convolve(u, [0, 0.5, 0.3])[:12] + 0.2 * np.tanh(u) + 0.05 * rng.standard_normal(12)
    m = sysid.nlarx(sysid.IOData(u, y, 1.0), 2, 2, 1)
    assert len(m.terms[0]) <= m.info["n_rows"] // 2 and m.noise_variance[0] > 1e-6
    with pytest.raises(sysid.DataError, match="too short"):
        sysid.nlarx(sysid.IOData(u[:3], y[:3], 1.0), 2, 2, 1)


def test_a_free_run_that_diverges_on_the_estimation_data_is_said():
    # issue 26 (no silent unstable model): a degree-3 NARX of the pH record (the nonlinear
    # bench's setting) is a fine one-step predictor whose free run blows up at sample 24 of
    # the very data it was fitted to; nlarx returned it without a word and compare said -inf
    d = sysid.datasets.load_ph()
    cut = int(0.6 * d.u.shape[0])
    train = sysid.IOData(d.u[:cut], d.y[:cut], d.dt)
    with pytest.warns(sysid.StabilityWarning, match="free-run simulation diverges"):
        m = sysid.nlarx(train, 3, 3, basis=sysid.PolynomialBasis(3), max_terms=20)
    with pytest.warns(sysid.StabilityWarning, match="NARXModel diverged"):  # compare too
        assert m.info["free_run"]["diverged"] and np.isinf(sysid.compare(train, m).fit[0, 0])
    # a model that simulates is silent, and its free-run fit on the record is recorded
    u, y = billings(400, 1)
    ok = sysid.nlarx(sysid.IOData(u, y, 1.0), 2, 2, basis=sysid.PolynomialBasis(2))
    ys = ok.simulate(u, x0=y[:ok.max_lag])
    ref = 100 * (1 - np.linalg.norm((ys - y)[2:]) / np.linalg.norm(y[2:] - y[2:].mean()))
    assert ok.info["free_run"] == {"diverged": False, "fit": [pytest.approx(ref)]}
    assert ref > 99.9


def test_a_free_run_that_grows_without_overflowing_is_a_divergence():
    # the F-16 record, nlarx(est, 2, 2, 1): the linear NARX model's pole at 1.0106 grew its
    # free run to 2e36 times the output, finite, so no warning was given; compare then
    # reported fit -inf
    d = sysid.datasets.load_f16()[8192:16384]
    est = sysid.IOData(d.u - d.u.mean(0), d.y - d.y.mean(0), d.dt)
    with pytest.warns(sysid.StabilityWarning, match="grows to .* times the measured one"):
        m = sysid.nlarx(est, 2, 2, 1)
    assert m.info["free_run"]["diverged"]


def test_compare_does_not_call_a_bounded_narx_simulation_unstable_by_its_linearisation():
    # y(t) = 1.2 y(t-1) - 0.2 y(t-1)^3 + u(t-1): the linearisation at zero has a pole at 1.2,
    # the simulation stays near the equilibria +-1. compare warned "the NARXModel is unstable
    # (a pole of modulus 1.2): its simulation grows without bound" on a 100 % fit (on the
    # DaISy CSTR record: "a pole of modulus 26.23" beside a 98.1 % validation fit)
    def record(seed):
        rng = np.random.default_rng(seed)
        u, y = 0.1 * rng.standard_normal(1500), np.zeros(1500)
        y[0] = 1.0
        for t in range(1, 1500):
            y[t] = 1.2 * y[t - 1] - 0.2 * y[t - 1] ** 3 + u[t - 1]
        return sysid.IOData(u=u, y=y)

    m = sysid.nlarx(record(0), 1, 1, 1, basis=sysid.PolynomialBasis(degree=3))
    assert np.max(np.abs(m.poles())) == pytest.approx(1.2, abs=1e-6)
    with warnings.catch_warnings():
        warnings.simplefilter("error", sysid.StabilityWarning)
        r = sysid.compare(record(1), m)
    assert r.mean_fit > 99.9


def test_predict_with_an_infinite_horizon_is_the_simulation():
    # predict(u, y, np.inf) raised a DataError for NARX models, where every other family
    # (and MATLAB's predict(sys, data, Inf)) gives the simulation: here from the measured
    # first max_lag outputs, as any horizon beyond the record does
    from test_narx_network import _truth_sigmoid

    u, y = billings(120, 31, noise=0.05)
    poly = sysid.NARXModel([2], [2], [1], sysid.PolynomialBasis(2), [list(BILLINGS)],
                           [list(BILLINGS.values())], dt=1.0)
    for m in (poly, _truth_sigmoid()):
        want = m.simulate(u, x0=y[:2])
        np.testing.assert_array_equal(m.predict(u, y, np.inf), want)
        np.testing.assert_array_equal(m.predict(sysid.IOData(u, y, 1.0), horizon=np.inf), want)
        np.testing.assert_allclose(m.predict(u, y, 200), want, atol=1e-12)
        np.testing.assert_array_equal(m.predict(u[:1], y[:1], np.inf), y[:1])  # all copied
        with pytest.raises(sysid.DataError, match="positive integer"):
            m.predict(u, y, 0)


def test_a_validation_record_of_another_sample_time_is_refused():
    # nlarx chose its terms on a validation record sampled every 0.5 s for data sampled
    # every 1 s without a word; pnlss and nlssest refuse it (one check, validation_record)
    u, y = billings(300, 41, noise=0.02)
    uv, yv = billings(200, 42, noise=0.02)
    d, poly = sysid.IOData(u, y, 1.0), sysid.PolynomialBasis(2)
    with pytest.raises(sysid.DataError, match=r"sampled every 0\.5 s, the estimation data "
                                              r"every 1 s"):
        sysid.nlarx(d, 2, 2, 1, basis=poly, criterion="validation",
                    validation=sysid.IOData(uv, yv, 0.5))
    with pytest.raises(sysid.DataError, match="validation has 2 input"):
        sysid.nlarx(d, 2, 2, 1, basis=poly, criterion="validation",
                    validation=sysid.IOData(np.c_[uv, uv], yv, 1.0))
    same = sysid.nlarx(d, 2, 2, 1, basis=poly, criterion="validation",
                       validation=sysid.IOData(uv, yv, 1.0))
    pair = sysid.nlarx(d, 2, 2, 1, basis=poly, criterion="validation", validation=(uv, yv))
    assert same.terms == pair.terms  # a (u, y) pair takes the data's sample time



def test_rbf_basis_does_not_depend_on_the_order_of_the_experiments():
    # the seeded k-means ran on the experiments' lag vectors stacked as given: the same
    # three experiments in three orders validated at 96.51, 94.92 and 95.52 %
    sets = [billings(n, seed, noise=0.02) for n, seed in ((200, 51), (150, 52), (250, 53))]
    val = sysid.IOData(*billings(400, 54), 1.0)
    u_test = np.random.default_rng(0).uniform(-1, 1, 100)
    sims, fits = [], []
    for order in ([0, 1, 2], [2, 0, 1], [1, 2, 0]):
        d = sysid.IOData([sets[i][0] for i in order], [sets[i][1] for i in order], 1.0)
        m = sysid.nlarx(d, 2, 2, 1, basis=sysid.RBFBasis(5), max_terms=6)
        sims.append(m.simulate(u_test))
        fits.append(sysid.compare(val, m).fit[0, 0])
    np.testing.assert_allclose(sims[1], sims[0], atol=1e-9)
    np.testing.assert_allclose(sims[2], sims[0], atol=1e-9)
    assert max(fits) - min(fits) < 1e-7
    # one experiment's rows are taken as they come: its basis is the one fitted before
    lags = np.random.default_rng(1).standard_normal((300, 4))
    np.testing.assert_array_equal(sysid.RBFBasis(5).fitted(lags).centres,
                                  sysid.RBFBasis(5).fitted([lags]).centres)
