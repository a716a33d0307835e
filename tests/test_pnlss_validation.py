"""PNLSS: the returned model chosen on validation data (``pnlss(validation=)``)."""

import warnings

import numpy as np
import pytest

import sysid
from sysid.errors import DataError


def _truth():
    # a second-order system with a cubic state term (stable, bounded for |u| <= 3)
    return sysid.PNLSSModel([[0.8, 0.2], [-0.2, 0.7]], [[0.5], [0.2]], [[1.0, 0.0]], [[0.0]],
                            np.array([[-0.1], [0.0]]), [[0.0]], zeta=[[0, 0, 0]], eta=[[0]])


def _record(seed, n, noise):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 1))
    return sysid.IOData(u, _truth().simulate(u) + noise * rng.standard_normal((n, 1)), 1.0)


def _fit(d, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the capped and short searches warn
        return sysid.pnlss(d, 2, degree=3, max_iter=60, progress=False, **kw)


def _mse(m, d, start):
    e = (d.y - m.simulate(d.u))[start:] / m.scaling.y_scale
    return float(np.mean(e ** 2))


def test_the_returned_iterate_has_the_lowest_validation_error():
    # a short noisy record and all degree-2-3 monomials: the later iterates fit the noise
    d, v, test = _record(0, 600, 0.3), _record(1, 400, 0.3), _record(2, 2000, 0.0)
    last = _fit(d)
    m = _fit(d, validation=v)
    rep = m.info["fit"]["validation"]
    errs, k = rep["errors"], rep["returned"]
    # one error per iterate (the linear start first), the minimum returned
    assert len(errs) == m.info["fit"]["iterations"] + 1
    assert k == int(np.argmin(errs)) and errs[k] <= errs[0]
    # the error reported is the returned model's own, on the validation record after the
    # linear start's settling time (at most a quarter of it)
    start = rep["scored_from"][0]
    assert 0 < start <= v.n_samples // 4
    assert abs(_mse(m, v, start) - errs[k]) < 1e-9 * errs[k]
    # here the search overfits: an earlier iterate is returned, and it simulates noise-free
    # data from the same system better than the last iterate does
    assert k < len(errs) - 1
    assert m.info["fit"]["returned"]["iteration"] == k
    assert _mse(m, test, 50) < _mse(last, test, 50)
    # the search is the same: its costs are those of the fit without validation
    np.testing.assert_allclose(m.info["fit"]["cost"], last.info["fit"]["cost"], rtol=1e-12)


def test_a_held_out_fraction_fits_the_rest():
    d = _record(3, 1000, 0.3)
    m = _fit(d, validation=0.25)
    rep = m.info["fit"]["validation"]
    # fitted on the first 750 samples: the same search as a fit on them alone
    part = sysid.IOData(d.u[:750], d.y[:750], 1.0)
    np.testing.assert_allclose(m.info["fit"]["cost"], _fit(part).info["fit"]["cost"],
                               rtol=1e-12)
    # scored on the held-out end of the whole experiment's simulation
    assert rep["scored_from"] == [750]
    assert abs(_mse(m, d, 750) - rep["errors"][rep["returned"]]) < 1e-9 * _mse(m, d, 750)


def test_the_decoupled_variant_is_chosen_alike():
    d, v = _record(4, 600, 0.3), _record(5, 400, 0.3)
    m = _fit(d, branches=2, validation=(v.u, v.y))
    rep = m.info["fit"]["validation"]
    assert isinstance(m, sysid.DecoupledPNLSSModel)
    assert rep["returned"] == int(np.argmin(rep["errors"]))


def test_validation_is_checked_before_the_fit():
    d = _record(6, 300, 0.1)
    with pytest.raises(DataError, match="fraction in"):
        _fit(d, validation=1.5)
    with pytest.raises(DataError, match="fraction in"):
        _fit(d, validation="last")
    with pytest.raises(DataError, match="same channels"):
        _fit(d, validation=sysid.IOData(np.zeros((50, 2)), np.zeros((50, 1)), 1.0))
    with pytest.raises(DataError, match="none left after transient=60"):
        _fit(d, validation=_record(7, 50, 0.0), transient=60)
    with pytest.raises(DataError, match="cut the periods"):
        _fit(d, validation=0.2, periods=3)
