"""Bad arguments of the nonlinear estimators and bad measured signals of the polynomial,
NARX and Hammerstein-Wiener predictors: a DataError naming the argument and the fix, never
a raw OverflowError of the Rust binding, a NumPy reshape error, a silently truncated value
or a NaN passed through to the result."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid

from conftest import first_order_record


@pytest.fixture(scope="module")
def record():
    _, u, y, d = first_order_record()
    return u, y, d


@pytest.fixture(scope="module")
def models(record):
    _, _, d = record
    return {"arx": sysid.arx(d, 2, 2, 1), "oe": sysid.oe(d, 1, 1, 1),
            "nlhw": sysid.nlhw(d, 1, 1, 1, progress=False), "nlarx": sysid.nlarx(d, 2, 2, 1)}


@pytest.mark.parametrize("kw", [{"max_iter": -5}, {"max_iter": 2.5}, {"tol": float("nan")}])
def test_nlhw_refuses_a_bad_max_iter_or_tol(record, kw):
    name = next(iter(kw))
    with pytest.raises(sysid.DataError, match=f"{name} must be"):
        sysid.nlhw(record[2], 2, 2, 1, **kw)


@pytest.mark.parametrize("kw", [{"max_iter": -1}, {"transient": -3}, {"tol": float("nan")},
                                {"degree": 2.5}, {"seed": -1}])
def test_pnlss_refuses_negative_counts_and_fractions(record, kw):
    name = next(iter(kw))
    with pytest.raises(sysid.DataError, match=f"{name} must be"):
        sysid.pnlss(record[2], 1, **{"degree": 2, **kw})


def test_nlssest_refuses_a_negative_seed(record):
    with pytest.raises(sysid.DataError, match="seed must be a non-negative integer"):
        sysid.nlssest(record[2], 1, hidden=4, epochs=2, seed=-1)


def test_nlhw_takes_the_orders_as_arx_and_oe_do(record):
    d = record[2]
    with pytest.raises(sysid.ShapeError, match=r"nf has shape \(1, 2\)"):
        sysid.nlhw(d, 2, [2, 2], 1)
    with pytest.raises(sysid.DataError, match="nf must hold non-negative integers"):
        sysid.nlhw(d, 2, float("nan"), 1)
    with pytest.raises(sysid.DataError, match="nb must be a positive integer"):
        sysid.nlhw(d, 0, 1, 1)
    # a (1, 1) array is one order, as arx and oe read it
    m = sysid.nlhw(d, np.array([[1]]), 1, 1, progress=False)
    assert m.b.size == 1 and m.f.size == 1


def test_a_constant_output_is_named_with_its_level_and_the_caller(record):
    d = sysid.IOData(u=record[0], y=np.full((400, 1), 3.0), dt=0.1)
    with pytest.raises(sysid.DataError, match="y0 is 3 in every sample: nlhw cannot"):
        sysid.nlhw(d, 2, 2, 1)
    with pytest.raises(sysid.DataError, match="y0 is 3 in every sample: identify cannot"):
        sysid.identify(d)


@pytest.mark.parametrize("kind", ["arx", "oe", "nlhw", "nlarx"])
def test_predict_refuses_a_bad_measured_output(record, models, kind):
    u, y, _ = record
    m = models[kind]
    bad = y.copy()
    bad[10] = np.nan
    with pytest.raises(sysid.NonFiniteError, match="y has a non-finite value"):
        m.predict(u, bad)
    with pytest.raises(sysid.ShapeError, match="u has 400 samples but y has 395"):
        m.predict(u, y[:-5])
    with pytest.raises(sysid.ShapeError, match=r"y has shape \(400, 2\)"):
        m.predict(u, np.c_[y, y])
    with pytest.raises(sysid.DataError, match="horizon must be a positive integer"):
        m.predict(u, y, horizon=-1)


@pytest.mark.parametrize("kind", ["arx", "oe", "nlhw", "nlarx"])
def test_simulate_refuses_complex_input(record, models, kind):
    with pytest.raises(sysid.DataError, match="u must be a real numeric array"):
        models[kind].simulate(record[0] + 1j)


def test_nlarx_simulate_names_a_bad_x0(record, models):
    with pytest.raises(sysid.DataError, match="x0 must be None, 'zero' or the first 2 outputs"):
        models["nlarx"].simulate(record[0], x0="foo")
    with pytest.raises(sysid.NonFiniteError, match="x0 has a non-finite value"):
        models["nlarx"].simulate(record[0], x0=[np.nan, 0.0])


def test_valid_predictions_are_unchanged(record, models):
    u, y, _ = record
    for m in models.values():
        np.testing.assert_array_equal(m.predict(u, y[:, 0]), m.predict(u, y))
    p = models["arx"].predict(u, y, horizon=np.inf)
    np.testing.assert_allclose(p, models["arx"].simulate(u))
    np.testing.assert_array_equal(models["nlhw"].predict(u, y, 3), models["nlhw"].simulate(u))


def test_nlhw_ss_and_augmented_models_check_their_arguments_too(record):
    u, y, d = record
    with pytest.raises(sysid.DataError, match="max_iter must be"):
        sysid.nlhw_ss(d, 1, max_iter=-1)
    with pytest.raises(sysid.DataError, match="tol must be"):
        sysid.nlhw_ss(d, 1, tol=float("nan"))
    with pytest.raises(sysid.DataError, match="y0 is 3 in every sample: nlhw_ss cannot"):
        sysid.nlhw_ss(sysid.IOData(u=u, y=np.full((400, 1), 3.0), dt=0.1), 1)
    hw = sysid.nlhw_ss(d, 1, progress=False)
    aug = sysid.augmented_fit(d, ["cube"], method="arx", na=1, nb=1)
    for m in (hw, aug):
        with pytest.raises(sysid.DataError, match="u must be a real numeric array"):
            m.simulate(u + 1j)
        with pytest.raises(sysid.ShapeError, match="u has 400 samples but y has 395"):
            m.predict(u, y[:-5])


def test_nlhw_says_its_linear_start_s_warnings_as_its_own(record):
    # orders above the first-order plant: the output-error start's pole and zero cancel;
    # the warning named oe, a function the user did not call
    with pytest.warns(sysid.IdentifiabilityWarning) as rec:
        sysid.nlhw(record[2], 2, 2, 1, progress=False, max_iter=5)
    said = [str(w.message) for w in rec if issubclass(w.category, sysid.IdentifiabilityWarning)]
    assert said and all(s.startswith("nlhw (its linear start") for s in said)
    assert not any(s.startswith("oe:") for s in said)


def test_a_record_too_short_for_the_linear_start_says_so_in_the_fits_terms():
    # pnlss/nlssest on 10 samples raised the subspace start's "a data matrix with 8 rows
    # (horizons p=2, f=2 ...)", settings a nonlinear-model user never gave
    rng = np.random.default_rng(0)
    u = rng.standard_normal(300)
    y = np.convolve(u, [0.0, 1.0, 0.5])[:300]
    for fit in (lambda d: sysid.pnlss(d, 2, degree=2, progress=False),
                lambda d: sysid.nlssest(d, 2, progress=False)):
        with pytest.raises(sysid.InsufficientDataError,
                           match=r"too short for the linear start of order 2.*init="):
            fit(sysid.IOData(u[:10], y[:10], 1.0))


@pytest.fixture(scope="module")
def nlss_models(record):
    d = record[2]
    with warnings.catch_warnings():  # short searches: what they say is not tested here
        warnings.simplefilter("ignore", sysid.IterationLimitWarning)
        return {"pnlss": sysid.pnlss(d, 1, degree=2, max_iter=3, progress=False),
                "decoupled": sysid.pnlss(d, 1, degree=3, branches=2, max_iter=2,
                                         progress=False),
                "neural": sysid.nlssest(d, 1, hidden=4, epochs=2, progress=False)}


@pytest.mark.parametrize("kind", ["pnlss", "decoupled", "neural"])
def test_nonlinear_state_space_models_check_their_arguments_as_every_family(record,
                                                                             nlss_models,
                                                                             kind):
    # predict took horizon 0 or 1.5, simulate dropped a complex input's imaginary part and
    # returned an empty output for an empty input, where the other families refuse them
    u, y, _ = record
    m = nlss_models[kind]
    for h in (0, 1.5, -1, "2"):
        with pytest.raises(sysid.DataError, match="horizon must be a positive integer"):
            m.predict(u, y, h)
    with pytest.raises(sysid.DataError, match="u must be a real numeric array"):
        m.simulate(u + 1j)
    with pytest.raises(sysid.DataError, match="u must be a real numeric array"):
        m.predict(u + 1j, y)
    with pytest.raises(sysid.ShapeError, match="u has no samples"):
        m.simulate(np.zeros(0))
    with pytest.raises(sysid.ShapeError, match="u has 400 samples but y has 395"):
        m.predict(u, y[:-5])
    np.testing.assert_array_equal(m.predict(u, y, np.inf), m.simulate(u))
    np.testing.assert_array_equal(m.predict(u, y, 3), m.simulate(u))
