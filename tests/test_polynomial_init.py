"""`armax` and `bj` start from a given model (MATLAB's `armax(data, init_sys)`,
`bj(data, init_sys)`), as `oe` does; polynomial and trended models say whether they are
stable (MATLAB's `isstable`)."""

import numpy as np
import pytest

import sysid
from sysid.errors import DataError


def _bj_record(seed: int = 0, n: int = 2000):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n)
    e = 0.1 * rng.standard_normal(n)
    g = sysid.TransferFunction([0.0, 1.0, 0.5], [1.0, -1.5, 0.7], dt=1.0)
    h = sysid.TransferFunction([1.0, 0.3], [1.0, -0.9], dt=1.0)
    return sysid.IOData(u, g.simulate(u)[:, 0] + h.simulate(e)[:, 0], 1.0)


def _start(model: sysid.PolynomialModel) -> list[np.ndarray]:
    return [model.b[0][0], model.c[0], model.d[0], model.f[0][0], model.a[0][0]]


def test_bj_takes_its_start_from_init():
    # bj had no init=: a user refining an earlier fit (or an oe model) could not
    data = _bj_record()
    start = sysid.PolynomialModel([[np.zeros(0)]], [[np.array([0.9, 0.4])]], [[1]], 1.0,
                                  c=[np.array([0.2])], d=[np.array([-0.8])],
                                  f=[[np.array([-1.4, 0.6])]])
    # no iteration: the parameters are the start's, exactly
    m0 = sysid.bj(data, 2, 1, 1, 2, 1, init=start, max_iter=0)
    for got, want in zip(_start(m0), _start(start)):
        np.testing.assert_array_equal(got, want)
    assert m0.info["start"] == "init" and m0.info["start_stabilized"] == [False]
    # the search from it reaches the true model
    m = sysid.bj(data, 2, 1, 1, 2, 1, init=start)
    np.testing.assert_allclose(m.f[0][0], [-1.5, 0.7], atol=0.02)
    np.testing.assert_allclose(m.d[0], [-0.9], atol=0.03)
    assert m.info["cost"][0][-1] <= m.info["cost"][0][0]


def test_bj_starts_from_an_oe_fit_and_reflects_unstable_roots():
    data = _bj_record(1)
    oe = sysid.oe(data, 2, 2, 1)
    m = sysid.bj(data, 2, 1, 1, 2, 1, init=oe, max_iter=0)
    np.testing.assert_array_equal(m.f[0][0], oe.f[0][0])
    np.testing.assert_array_equal(m.b[0][0], oe.b[0][0])
    np.testing.assert_array_equal(m.c[0], [0.0])  # oe has no noise model: C = D = 1
    unstable = sysid.PolynomialModel([[np.zeros(0)]], [[np.array([1.0, 0.5])]], [[1]], 1.0,
                                     c=[np.zeros(0)], d=[np.array([-1.2])],
                                     f=[[np.array([-1.5, 0.7])]])
    m = sysid.bj(data, 2, 1, 1, 2, 1, init=unstable, max_iter=0)
    assert m.info["start_stabilized"] == [True]
    assert abs(m.d[0][0]) < 1.0


def test_armax_takes_its_start_from_init():
    rng = np.random.default_rng(2)
    n = 2000
    u, e = rng.standard_normal(n), 0.1 * rng.standard_normal(n)
    y = np.zeros(n)
    for t in range(1, n):
        y[t] = 0.7 * y[t - 1] + u[t - 1] + e[t] + 0.5 * e[t - 1]
    data = sysid.IOData(u, y, 1.0)
    arx = sysid.arx(data, 1, 1, 1)
    m0 = sysid.armax(data, 1, 1, 1, init=arx, max_iter=0)
    np.testing.assert_array_equal(m0.a[0][0], arx.a[0][0])
    np.testing.assert_array_equal(m0.b[0][0], arx.b[0][0])
    np.testing.assert_array_equal(m0.c[0], [0.0])
    assert m0.info["start"] == "init"
    m = sysid.armax(data, 1, 1, 1, init=arx)
    np.testing.assert_allclose([m.a[0][0][0], m.c[0][0]], [-0.7, 0.5], atol=0.05)
    # the same minimum as from armax's own start
    own = sysid.armax(data, 1, 1, 1)
    assert m.info["cost"][0][-1] == pytest.approx(own.info["cost"][0][-1], rel=1e-6)


@pytest.mark.parametrize("fit", [
    lambda d, m: sysid.bj(d, 2, 1, 1, 2, 1, init=m),
    lambda d, m: sysid.armax(d, 1, 1, 1, init=m),
])
def test_init_with_other_channel_counts_is_refused(fit):
    data = _bj_record(3)
    two_inputs = sysid.PolynomialModel([[np.array([-0.5])]], [[np.ones(1), np.ones(1)]],
                                       [[1, 1]], 1.0)
    with pytest.raises(DataError, match="init has other input/output counts"):
        fit(data, two_inputs)


def test_polynomial_and_trended_models_say_whether_they_are_stable():
    # PolynomialModel had poles() but no is_stable() (StateSpaceModel and TransferFunction
    # have it): a user checking an oe or arx fit as MATLAB's isstable got an AttributeError
    stable = sysid.PolynomialModel([[np.array([-0.5])]], [[np.ones(1)]], [[1]], 1.0,
                                   f=[[np.array([-0.9])]])
    unstable_f = sysid.PolynomialModel([[np.zeros(0)]], [[np.ones(1)]], [[1]], 1.0,
                                       f=[[np.array([-1.1])]])
    integrator = sysid.PolynomialModel([[np.array([-1.0])]], [[np.ones(1)]], [[1]], 1.0)
    assert stable.is_stable()
    assert not unstable_f.is_stable() and not integrator.is_stable()
    # a noise model's poles (D of a Box-Jenkins model) are not the measured part's
    noisy = sysid.PolynomialModel([[np.zeros(0)]], [[np.ones(1)]], [[1]], 1.0,
                                  c=[np.zeros(0)], d=[np.array([-1.0])],
                                  f=[[np.array([-0.5])]])
    assert noisy.is_stable()
    rng = np.random.default_rng(4)
    u = rng.standard_normal(400)
    raw = sysid.IOData(u=20.0 + u, y=3.0 + stable.simulate(u), dt=1.0)
    d, tr = sysid.detrend(raw, "mean", return_trend=True)
    assert tr.attach(sysid.oe(d, 1, 1, 1)).is_stable() is True
    assert tr.attach(unstable_f).is_stable() is False
