"""``sysid.findop`` and ``sysid.linearize`` (MATLAB's): exact for linear models, the
analytic operating point and linearisation of known NARX and Hammerstein-Wiener models, and,
for every fitted nonlinear family, the linear model predicts the small-signal response to a
signal other than the impulses it was built from (the deviation of a simulation about the
operating point, to second order in its size); clear errors."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid
from sysid.errors import DataError, NumericalError

W = np.array([0.05, 0.5, 2.0])


def test_linear_model_is_its_own_linearisation():
    m = sysid.StateSpaceModel([[0.9, 0.2, 0.0], [-0.2, 0.9, 0.0], [0.0, 0.0, 0.4]],
                              [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]],
                              [[1.0, 0.0, 1.0], [0.0, 1.0, 0.0]], [[0.1, 0.0], [0.0, 0.2]])
    lin = sysid.linearize(m, [1.0, -2.0])
    assert lin.nstates == 3
    assert np.allclose(lin.freqresp(W), m.freqresp(W), atol=1e-8)
    assert np.allclose(sysid.findop(m, [1.0, -2.0]).y0, m.dcgain() @ [1.0, -2.0])


def test_narx_operating_point_is_analytic():
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, 3000)
    y = np.zeros(3000)
    for t in range(1, 3000):
        y[t] = 0.5 * y[t - 1] + u[t - 1] + 0.2 * u[t - 1] ** 2
    m = sysid.nlarx(sysid.IOData(u=u, y=y), 1, 1, 1)
    for u0 in (-0.5, 0.0, 0.8):
        op = sysid.findop(m, u0)
        assert np.isclose(op.y0[0], (u0 + 0.2 * u0**2) / 0.5, atol=1e-8)
        lin = sysid.linearize(m, u0)  # dy(t) = 0.5 dy(t-1) + (1 + 0.4 u0) du(t-1)
        assert lin.nstates == 1 and np.isclose(lin.poles()[0], 0.5, atol=1e-7)
        assert np.isclose(lin.dcgain()[0, 0], (1 + 0.4 * u0) / 0.5, rtol=1e-6)


def test_hammerstein_operating_point_is_analytic():
    hw = sysid.HammersteinWienerModel(sysid.UserFunction(lambda v: v + v**3),
                                      sysid.Nonlinearity(), b=[1.0, 0.3], f=[-0.6], nk=1,
                                      dt=0.1)
    for u0 in (0.0, 0.7):
        lin = sysid.linearize(hw, u0)
        gain = 1 + 3 * u0**2
        expected = gain * sysid.ss2tf(hw.linear() if callable(hw.linear) else hw.linear)\
            .freqresp(W)
        assert np.allclose(lin.freqresp(W), expected, rtol=1e-6)
        assert np.isclose(sysid.findop(hw, u0).y0[0], (u0 + u0**3) * 1.3 / 0.4)


@pytest.mark.parametrize("family", ["nlarx", "nlhw", "pnlss"])
def test_small_signal_response_of_fitted_models(family):
    rng = np.random.default_rng(1)
    n = 1500
    u = rng.uniform(-1, 1, n)
    x = np.zeros(n)
    for t in range(1, n):  # a Wiener system with a mild saturation
        x[t] = 0.7 * x[t - 1] + 0.5 * u[t - 1]
    y = np.tanh(x) + 0.01 * rng.standard_normal(n)
    data = sysid.IOData(u=u, y=y)
    with warnings.catch_warnings():  # short fits of a small record: warnings not tested
        warnings.simplefilter("ignore")
        model = {"nlarx": lambda: sysid.nlarx(data, 2, 2, 1),
                 "nlhw": lambda: sysid.nlhw(data, 2, 2, 1, max_iter=20),
                 "pnlss": lambda: sysid.pnlss(data, 2, degree=3, max_iter=20)}[family]()
    u0 = 0.4
    lin = sysid.linearize(model, u0)
    op = lin.info["operating_point"]
    s = np.sin(0.3 * np.arange(400)) + 0.5 * np.sin(1.1 * np.arange(400))
    eps = 1e-3
    held = np.full(op.samples + 400, u0)
    held[op.samples:] += eps * s
    dev = (np.asarray(model.simulate(held)).ravel()[op.samples:] - op.y0[0]) / eps
    pred = lin.simulate(s).ravel()
    assert np.max(np.abs(dev - pred)) < 0.01 * max(1.0, np.max(np.abs(pred)))


def test_refusals():
    with pytest.raises(NumericalError, match="does not settle"):
        sysid.findop(sysid.StateSpaceModel([[1.1]], [[1.0]], [[1.0]]), 1.0)
    # at rest (u0 = 0) an unstable model stays there, but its impulse response runs away:
    # this said "numerical failure in simulate: the simulated output overflowed"
    with pytest.raises(NumericalError, match="grows without bound.*to_statespace"):
        sysid.linearize(sysid.StateSpaceModel([[1.1]], [[1.0]], [[1.0]]))
    m = sysid.StateSpaceModel([[0.5]], [[1.0, 1.0]], [[1.0]])
    with pytest.raises(DataError, match="one value per input"):
        sysid.linearize(m, [1.0, 2.0, 3.0])
    with pytest.raises(DataError, match="step"):
        sysid.linearize(m, 0.0, step=-1.0)


def test_bad_order_is_refused():
    m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    with pytest.raises(DataError, match="order"):
        sysid.linearize(m, 0.0, order=-1)
    with pytest.raises(DataError, match="max_samples"):
        sysid.linearize(m, 0.0, max_samples=10)


def test_continuous_linear_models_are_their_own_linearisation():
    # findop/linearize of a TransferFunction or ContinuousStateSpace raised "a continuous-time
    # model needs the sample time of the data: pass dt", which neither function takes
    g = sysid.TransferFunction([2.0], [1.0, 3.0, 2.0], iodelay=0.2)
    c = sysid.ContinuousStateSpace([[-1.0, 0.5], [0.0, -2.0]], [[1.0], [1.0]], [[1.0, 1.0]])
    p = sysid.ProcessModel("P1D", Kp=2.0, Tp1=1.0, Td=0.2)
    for m in (g, c, p):
        op = sysid.findop(m, 3.0)
        np.testing.assert_allclose(op.y0, 3.0 * np.asarray(m.dcgain()).ravel(), rtol=1e-12)
        lin = sysid.linearize(m, 3.0)
        assert lin is not m and lin.info["operating_point"].samples == 0
        w = np.array([0.1, 1.0, 5.0])
        np.testing.assert_allclose(lin.freqresp(w), m.freqresp(w), rtol=1e-12)
    with pytest.raises(sysid.NumericalError, match="integrates its input"):
        sysid.findop(sysid.TransferFunction([1.0], [1.0, 0.0]), 1.0)
