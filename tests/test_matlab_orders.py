"""MATLAB's order vectors (``arx(data, [na nb nk])`` and the like): a MATLAB user's first
call. Before, every one of them failed with Python's bare ``TypeError: arx() missing 1
required positional argument: 'nb'``. The vector form gives the same model as the orders
given one by one; a vector of the wrong length or with a fraction says what it should hold.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sysid

from conftest import quiet


def _coefficients(m):
    """Every polynomial coefficient of a model, flattened (empty polynomials included)."""
    out = []
    for name in ("a", "b", "c", "d", "f"):
        for row in getattr(m, name, None) or []:
            for p in (row if isinstance(row, list) else [row]):
                out.append(np.ravel(np.asarray(p, float)))
    return np.concatenate(out) if out else np.zeros(0)


@pytest.fixture(scope="module")
def dryer():
    d = sysid.datasets.load_dryer()
    return sysid.detrend(d, "mean")


@pytest.mark.parametrize("fn, orders", [
    ("arx", (2, 2, 1)), ("iv4", (2, 2, 1)), ("armax", (2, 2, 2, 1)), ("oe", (2, 2, 3)),
    ("bj", (2, 1, 1, 2, 1)),
])
def test_the_vector_form_is_the_same_model_as_the_orders_one_by_one(dryer, fn, orders):
    f = getattr(sysid, fn)
    one_by_one = quiet(f, dryer, *orders)
    vector = quiet(f, dryer, list(orders))
    assert np.array_equal(_coefficients(vector), _coefficients(one_by_one))
    assert np.array_equal(vector.nk, one_by_one.nk)


def test_nk_defaults_to_one_when_the_orders_are_given_one_by_one(dryer):
    assert np.array_equal(quiet(sysid.oe, dryer, 2, 2).nk, [[1]])
    assert np.array_equal(quiet(sysid.oe, dryer, [2, 2, 1]).nk, [[1]])


def test_nonlinear_estimators_and_arxregul_take_the_vector_too(dryer):
    basis = sysid.PolynomialBasis(2)
    a = quiet(sysid.nlarx, dryer, [2, 2, 1], basis=basis)
    b = quiet(sysid.nlarx, dryer, 2, 2, 1, basis=basis)
    assert np.allclose(a.simulate(dryer.u), b.simulate(dryer.u), rtol=0, atol=0)
    hw = quiet(sysid.nlhw, dryer, [2, 2, 1], input_nl=sysid.SigmoidNetwork(2), output_nl=None,
               max_iter=5)
    hw2 = quiet(sysid.nlhw, dryer, 2, 2, 1, input_nl=sysid.SigmoidNetwork(2), output_nl=None,
                max_iter=5)
    assert np.array_equal(hw.simulate(dryer.u), hw2.simulate(dryer.u))
    # MATLAB's arxRegul(data, orders, kernel): the kernel follows the vector
    r1 = sysid.arxregul(dryer, [0, 20, 1], "ss")
    r2 = sysid.arxregul(dryer, 0, 20, 1, "ss")
    assert r1.kernel == "ss" and r1.hyperparameters == r2.hyperparameters


def test_several_inputs_and_outputs_take_one_row_per_output():
    # MATLAB's [NA NB NK] for the shipped winding record (5 inputs, 2 outputs): NA 2 x 2,
    # NB and NK 2 x 5 side by side; armax and oe one row [na nb nc nk] / [nb nf nk] each
    w = np.loadtxt(sysid.datasets.path("winding"))[:800]
    d = sysid.IOData(u=w[:, :5] - w[:, :5].mean(0), y=w[:, 5:7] - w[:, 5:7].mean(0))
    NA, NB, NK = [[2, 1], [0, 2]], [[2] * 5, [1] * 5], [[1] * 5, [1, 1, 2, 1, 1]]
    m = quiet(sysid.arx, d, np.hstack([NA, NB, NK]))
    assert np.array_equal(_coefficients(m), _coefficients(quiet(sysid.arx, d, NA, NB, NK)))
    assert np.array_equal(m.nk, NK)
    rows = np.hstack([[[1], [2]], np.full((2, 5), 1), [[1], [0]], np.ones((2, 5), int)])
    m = quiet(sysid.armax, d, rows, max_iter=3)
    same = quiet(sysid.armax, d, [1, 2], 1, [1, 0], 1, max_iter=3)
    assert np.array_equal(_coefficients(m), _coefficients(same))


def test_a_vector_that_does_not_fit_the_channels_says_what_it_should_hold(dryer):
    with pytest.raises(sysid.ShapeError, match=r"\[nb \(one per input\), nf \(one per input"
                       r"\), nk \(one per input\)\]: for 1 input\(s\) and 1 output\(s\) a "
                       r"vector of 3 numbers, got shape \(2,\)"):
        sysid.oe(dryer, [2, 2])
    with pytest.raises(sysid.DataError, match="whole numbers"):
        sysid.arx(dryer, [2, 1.5, 1])
    with pytest.raises(sysid.DataError, match=r"arx needs nb: .*arx\(data, \[na, nb, nk\]\)"):
        sysid.arx(dryer, 2)
    with pytest.raises(sysid.DataError, match=r"bj needs nd, nf"):
        sysid.bj(dryer, 2, 1)
    with pytest.raises(sysid.DataError, match="the vector comes alone"):
        sysid.arx(dryer, [2, 2, 1], nk=1)
    w = np.loadtxt(sysid.datasets.path("winding"))[:300]
    mimo = sysid.IOData(u=w[:, :5], y=w[:, 5:7])
    with pytest.raises(sysid.ShapeError, match=r"2 rows \(one per output\) of 12 numbers"):
        sysid.arx(mimo, [2, 2, 1])


@settings(deadline=None)  # two fits (and arx's feedthrough check) on a loaded machine
@given(na=st.integers(0, 3), nb=st.lists(st.integers(0, 3), min_size=2, max_size=2),
       nk=st.lists(st.integers(0, 2), min_size=2, max_size=2))
def test_arx_vector_and_separate_orders_agree_for_any_orders(na, nb, nk):
    # two inputs: MATLAB's [na nb1 nb2 nk1 nk2]
    rng = np.random.default_rng(0)
    u = rng.standard_normal((200, 2))
    y = np.convolve(u[:, 0], [0, 1, 0.5])[:200] + 0.3 * u[:, 1] + 0.1 * rng.standard_normal(200)
    d = sysid.IOData(u=u, y=y[:, None])
    if na == 0 and sum(nb) == 0:
        return
    a = quiet(sysid.arx, d, [na, *nb, *nk])
    b = quiet(sysid.arx, d, na, [nb], [nk])
    assert np.array_equal(_coefficients(a), _coefficients(b))


def test_arxstruc_with_validation_data_as_matlab_s(dryer):
    # MATLAB's V = arxstruc(ze, zv, struc(1:5, 1:5, 1:4)); selstruc(V, 0): every row fitted
    # on ze, scored by its one-step prediction errors on zv. Before: TypeError (arxstruc
    # took the ranges only, and sysid.struc did not exist)
    ze, zv = dryer[:500], dryer[500:]
    nn = sysid.struc(range(1, 6), range(1, 6), range(1, 5))
    assert nn.shape == (100, 3) and nn[0].tolist() == [1, 1, 1]
    v = sysid.arxstruc(ze, zv, nn)
    assert v.shape == (100, 5)
    for a, b, k, loss, p in v[[0, 37, 99]]:
        m = sysid.arx(ze, int(a), int(b), int(k))
        e = zv.y - m.predict(zv.u, zv.y, 1)
        assert loss == pytest.approx(float(np.mean(e ** 2)), rel=1e-12) and p == a + b
    best = sysid.selstruc(v, 0)
    assert list(best) == v[int(np.argmin(v[:, 3])), :3].astype(int).tolist()
    with pytest.raises(sysid.DataError, match=r"rows \[na, nb, nk\]"):
        sysid.arxstruc(ze, zv, [[1, 2]])
    with pytest.raises(sysid.DataError, match="nothing after it"):
        sysid.arxstruc(ze, zv, nn, [1])
    with pytest.raises(sysid.DataError, match="needs the ranges"):
        sysid.arxstruc(ze, [1, 2])



def test_arxstruc_with_validation_data_says_nothing_of_candidates_that_diverge():
    # arxstruc(ze, zv, struc(1:5, 1:5, 0:4)) on the robot arm gave one StabilityWarning per
    # row whose ARX model's simulation diverges (ten), though the table scores their stable
    # one-step predictors; under warnings-as-errors it raised. An offset warning of the data
    # comes once, not once per row; arx still warns for the structure chosen
    d = sysid.datasets.load_robot_arm()
    d = sysid.IOData(d.u - d.u[:800].mean(0), d.y - d.y[:800].mean(0), d.dt)
    ze, zv = d[:800], d[800:]
    nn = sysid.struc(range(1, 6), range(1, 6), range(0, 5))
    unstable = [row for row in nn
                if not quiet(sysid.arx, ze, *map(int, row)).is_stable()]
    assert unstable  # the table holds candidates whose simulation diverges
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        v = sysid.arxstruc(ze, zv, nn)
    assert v.shape == (125, 5)
    with pytest.warns(sysid.StabilityWarning):
        sysid.arx(ze, *map(int, unstable[0]))
    raw = sysid.IOData(ze.u + 5.0, ze.y + 5.0, ze.dt)
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        sysid.arxstruc(raw, zv, nn[:4])
    offsets = [w for w in said if "offset" in str(w.message)]
    assert len(offsets) == 1, [str(w.message)[:80] for w in said]

def test_ar_orders_of_a_time_series_compared_as_matlab_s():
    # V = arxstruc(ze, zv, struc(1:10)) on a time series, selstruc(V): arxstruc gave a table
    # [na, loss, parameters] that selstruc refused ("shape (10, 3)"), and struc needed nb, nk
    from scipy import signal

    rng = np.random.default_rng(2)
    y = signal.lfilter([1.0], [1.0, -1.2, 0.5, -0.1], rng.standard_normal(3000))
    ts = sysid.IOData(None, y[:, None], 1.0)
    ze, zv = ts[:2000], ts[2000:]
    nn = sysid.struc(range(1, 9))
    assert nn.tolist() == [[k] for k in range(1, 9)]
    v = sysid.arxstruc(ze, zv, nn)
    assert v.shape == (8, 3)
    for na, loss, p in v[[0, 2, 7]]:
        m = sysid.arx(ze, int(na))  # MATLAB's arx(y, na): no input orders for a series
        r = zv.y - m.predict(zv, horizon=1)
        assert p == na and loss == pytest.approx(float(np.mean(r ** 2)), rel=1e-12)
    assert sysid.selstruc(v, 0) == (int(v[int(np.argmin(v[:, 1])), 0]),)
    assert sysid.selstruc(v, "bic") == (3,)  # the true order
    # the time series' own orders alone (arx(y, na) asked for nb before); input orders for
    # a record without inputs are refused with the call to make
    np.testing.assert_allclose(sysid.armax(ze, 2, nc=1).c[0], sysid.armax(ze, [2, 1]).c[0])
    with pytest.raises(sysid.DataError, match=r"no inputs \(a time series\), so armax takes "
                       r"no nb: armax\(data, na, nc=\.\.\.\), or \[na, nc\]"):
        sysid.armax(ze, 2, 1)
    with pytest.raises(sysid.DataError, match=r"oe models the response to inputs.*sysid\.ar"):
        sysid.oe(ze, 2, 2)


def test_arxstruc_validation_form_with_several_inputs():
    # MATLAB's NN rows for m inputs are [na, nb1..nbm, nk1..nkm]; before, arxstruc(ze, zv, NN)
    # took one input, and selstruc read columns 3 and 4 as loss and parameter count
    from scipy import signal

    rng = np.random.default_rng(1)
    n = 2000
    u = rng.standard_normal((n, 2))
    e = 0.05 * rng.standard_normal(n)
    y = (signal.lfilter([0, 1.0, 0.5], [1, -0.6], u[:, 0])
         + signal.lfilter([0, 0, 0.8], [1, -0.6], u[:, 1]) + signal.lfilter([1], [1, -0.6], e))
    d = sysid.IOData(u, y[:, None], 1.0)
    ze, zv = d[:1000], d[1000:]
    nn = [[1, 2, 1, 1, 2], [1, 1, 1, 1, 2], [1, 2, 1, 1, 1], [1, 2, 1, 2, 2], [1, 2, 0, 1, 0]]
    v = sysid.arxstruc(ze, zv, nn)
    assert v.shape == (5, 7)
    for row in v:
        a, b, k = int(row[0]), row[1:3].astype(int).tolist(), row[3:5].astype(int).tolist()
        m = sysid.arx(ze, a, [b], [k])
        r = zv.y - m.predict(zv.u, zv.y, 1)
        assert row[5] == pytest.approx(float(np.mean(r ** 2)), rel=1e-12)
        assert row[6] == a + sum(b)
    # the true structure: lowest validation loss, and AIC/BIC agree on the table
    assert sysid.selstruc(v, 0) == (1, 2, 1, 1, 2)
    assert sysid.selstruc(v, "aic") == sysid.selstruc(v, "bic") == (1, 2, 1, 1, 2)
    # struc's rows [na, nb, nk] give every input the same nb and nk (as the ranges do)
    shared = sysid.arxstruc(ze, zv, [[1, 2, 1]])
    assert shared[0, :5].tolist() == [1, 2, 2, 1, 1]
    with pytest.raises(sysid.DataError, match=r"\[na, nb1..nb2, nk1..nk2\]"):
        sysid.arxstruc(ze, zv, [[1, 2, 1, 1]])
    with pytest.raises(sysid.DataError, match="same channels"):
        sysid.arxstruc(ze, zv.select(inputs=0), nn)


def test_order_auto_of_a_polynomial_estimator_points_to_the_structure_choice(dryer):
    """``arx(data, "auto")`` (a state-space habit) said "arx needs nb", as if "auto" were a
    number of A coefficients; it now says the polynomial estimators take whole numbers and
    where the automatic choices are, and the structure choice it names runs."""
    for fit in (sysid.arx, sysid.oe, sysid.bj, sysid.nlarx):
        with pytest.raises(sysid.DataError, match=r"takes its orders as whole numbers, got "
                           r"'auto' .*sysid.selstruc\(sysid.arxstruc\(est, val, .*sysid."
                           r"identify\(data\)"):
            fit(dryer, "auto")
    with pytest.raises(sysid.DataError, match=r"oe takes its orders as whole numbers"):
        sysid.oe(dryer, 2, "auto", 1)
    est, val = dryer.slice(0, 500), dryer.slice(500, 1000)
    nk = 1
    na, nb, k = sysid.selstruc(sysid.arxstruc(est, val, sysid.struc(range(1, 11),
                                                                     range(1, 11), nk)))
    assert 1 <= na <= 10 and 1 <= nb <= 10 and k == nk
