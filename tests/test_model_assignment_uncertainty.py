"""Replacing a state-space model's matrix or sample time drops a parameter uncertainty that
belonged to the old values, with a warning that says why; the ``std=True`` results never
mix the old model's numbers with the new model's.

Before: after ``m.A = [[0.9]]`` on ``build([0.5])``, ``freqresp([0])`` gave 10 but with
``std=True`` 2 (the old model's), ``poles`` 0.9 against 0.5, ``dcgain`` 10 against 2, and
the same after ``m.dt = ...``: the ``std=True`` results evaluate ``uncertainty.build(theta)``.
"""

import copy
import pickle
import warnings

import numpy as np
import pytest

import sysid
from sysid.errors import DataError
from sysid.models.paramtable import ParameterTable
from sysid.models.uncertainty import UncertaintyWarning


def build(t):
    return sysid.StateSpaceModel([[t[0]]], [[1.0]], [[1.0]], dt=0.1)


def estimated():
    m = build([0.5])
    m.uncertainty = sysid.ParameterUncertainty([0.5], [[1e-4]], build)
    return m


def test_estimate_before_any_change():
    m = estimated()
    assert m.freqresp([0.0], std=True)[0][0, 0, 0] == pytest.approx(2.0)
    assert m.dcgain(std=True)[0][0, 0] == pytest.approx(2.0)
    assert "\nparameters:" in m.summary() and "uncertainty:" in m.summary()
    assert "std damping" in m.to_pandas().columns


@pytest.mark.parametrize("name, value", [("A", [[0.9]]), ("B", [[2.0]]), ("C", [[3.0]]),
                                         ("D", [[1.0]]), ("dt", 0.2)])
def test_replacing_a_value_drops_the_uncertainty_with_a_warning(name, value):
    m = estimated()
    with pytest.warns(UncertaintyWarning, match=f"{name}.*replaced.*uncertainty is dropped.*"
                      "belongs to the estimated parameters.*re-estimate.*set "
                      "model.uncertainty again"):
        setattr(m, name, value)
    assert m.uncertainty is None
    # every std=True result now says there is none (and why), not the old model's numbers
    for call in (lambda: m.freqresp([0.0], std=True), lambda: m.poles(std=True),
                 lambda: m.dcgain(std=True), lambda: m.step(5, std=True),
                 lambda: m.impulse(5, std=True), lambda: sysid.damp(m, std=True),
                 lambda: m.markov(3, std=True)):
        with pytest.raises(DataError, match=f"no parameter uncertainty \\(dropped when {name}"):
            call()
    # the model's own numbers are the new ones, and the tables show no stale std columns
    assert "std damping" not in m.to_pandas().columns
    assert "\nparameters:" not in m.summary() and "uncertainty:" not in m.summary()


def test_the_numbers_reported_by_the_audit():
    m = estimated()
    with pytest.warns(UncertaintyWarning):
        m.A = [[0.9]]
    assert m.freqresp([0.0])[0, 0, 0].real == pytest.approx(10.0)
    assert m.poles()[0] == pytest.approx(0.9)
    assert m.dcgain()[0, 0] == pytest.approx(10.0)
    # set again (its build at the new values): the std results are the new model's
    m.uncertainty = sysid.ParameterUncertainty([0.9], [[1e-4]], build)
    H, sd = m.freqresp([0.0], std=True)
    assert H[0, 0, 0].real == pytest.approx(10.0)
    assert sd[0, 0, 0].real == pytest.approx(0.01 / 0.1**2)
    assert m.poles(std=True)[0][0] == pytest.approx(0.9)
    assert m.dcgain(std=True)[0][0, 0] == pytest.approx(10.0)


def test_the_same_value_keeps_it_silently():
    m = estimated()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m.A = [[0.5]]
        m.dt = 0.1
        m.noise_cov = [[2.0]]          # no std result reads the innovation covariance
        m.x0 = [1.0]                   # nor the initial state
        m.K = [[0.3]]                  # an output-error model's parameters hold no K
    assert m.uncertainty is not None
    with pytest.warns(UncertaintyWarning, match="K was replaced"):
        m.K = [[0.4]]                  # but replacing a K the model had drops it
    assert m.uncertainty is None


def test_a_refused_value_keeps_model_and_uncertainty():
    m = estimated()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(sysid.NonFiniteError):
            m.A = [[np.nan]]
        with pytest.raises(DataError):
            m.dt = -0.1
    assert m.uncertainty is not None and m.A[0, 0] == 0.5 and m.dt == 0.1


def test_copies_and_pickles_keep_their_own():
    m = estimated()
    c = copy.deepcopy(m)
    with pytest.warns(UncertaintyWarning):
        c.A = [[0.8]]
    assert c.uncertainty is None and m.uncertainty is not None
    back = pickle.loads(pickle.dumps(m))
    assert back.dt == 0.1 and back.uncertainty is not None
    with pytest.warns(UncertaintyWarning):
        back.dt = 0.05
    assert back.dt == 0.05 and back.uncertainty is None


def test_continuous_model_drops_it_too():
    def cbuild(t):
        return sysid.ContinuousStateSpace([[-t[0]]], [[1.0]], [[1.0]])

    c = cbuild([1.0])
    c.uncertainty = sysid.ParameterUncertainty([1.0], [[0.01]], cbuild)
    with pytest.warns(UncertaintyWarning, match="ContinuousStateSpace.A was replaced"):
        c.A = [[-2.0]]
    assert c.uncertainty is None
    assert c.dcgain()[0, 0] == pytest.approx(0.5)


def tf_build(t):
    return sysid.TransferFunction([1.0], [1.0, t[0]])


def poly_build(t):
    return sysid.PolynomialModel(a=[[np.array([t[0]])]], b=[[np.array([1.0])]], nk=[[1]],
                                 dt=1.0)


@pytest.mark.parametrize("name, value", [("num", [[np.array([3.0])]]),
                                         ("den", [[np.array([1.0, 4.0])]]),
                                         ("iodelay", np.array([[0.2]])), ("dt", 0.1)])
def test_transfer_function_coefficients_drop_it(name, value):
    # before: G.den = (s + 4) kept the uncertainty, dcgain 0.25 but with std=True 0.5
    G = tf_build([2.0])
    G.uncertainty = sysid.ParameterUncertainty([2.0], [[1e-4]], tf_build)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        setattr(G, name, getattr(G, name))  # the same value keeps it
        G.hold = "foh"                      # no std result reads the hold
    assert G.uncertainty is not None
    with pytest.warns(UncertaintyWarning, match=f"TransferFunction.{name}.* was replaced"):
        setattr(G, name, value)
    assert G.uncertainty is None
    with pytest.raises(DataError, match=f"no parameter uncertainty \\(dropped when {name}"):
        G.dcgain(std=True)


def test_transfer_function_parameter_table_goes_with_it():
    G = tf_build([2.0])
    G.uncertainty = sysid.ParameterUncertainty([2.0], [[1e-4]], tf_build)
    G.parameters = ParameterTable(["a1"], [2.0], [0.01], [False])
    with pytest.warns(UncertaintyWarning):
        G.den = [[np.array([1.0, 4.0])]]
    assert G.parameters is None and "0.01" not in G.summary()


@pytest.mark.parametrize("name, value", [("a", [[np.array([-0.8])]]),
                                         ("b", [[np.array([2.0])]]),
                                         ("c", [np.array([0.3])]), ("d", [np.array([-1.0])]),
                                         ("f", [[np.array([-0.2])]]), ("nk", np.array([[2]])),
                                         ("dt", 0.5)])
def test_polynomial_coefficients_drop_it(name, value):
    # before: m.a = [[[-0.8]]] kept the uncertainty, dcgain 5 but with std=True 2
    m = poly_build([-0.5])
    m.uncertainty = sysid.ParameterUncertainty([-0.5], [[1e-4]], poly_build)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        setattr(m, name, getattr(m, name))
        m.noise_variance = np.array([4.0])  # no std result reads the innovation variance
    assert m.uncertainty is not None
    with pytest.warns(UncertaintyWarning, match=f"PolynomialModel.{name}.* was replaced"):
        setattr(m, name, value)
    assert m.uncertainty is None
    with pytest.raises(DataError, match=f"no parameter uncertainty \\(dropped when {name}"):
        m.dcgain(std=True)


def test_polynomial_sample_time_checked_when_written():
    m = poly_build([-0.5])
    with pytest.raises(DataError, match="dt must be a positive number"):
        m.dt = -1.0
    assert m.dt == 1.0


def test_estimators_keep_their_own_uncertainty():
    rng = np.random.default_rng(1)
    u = rng.standard_normal((400, 1))
    v = np.cumsum(0.1 * rng.standard_normal(400))  # integrated noise: D = 1 - q^-1
    y = np.zeros((400, 1))
    for t in range(1, 400):
        y[t] = 0.5 * y[t - 1] + u[t - 1] + v[t] - 0.5 * v[t - 1]
    data = sysid.IOData(u, y, 1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", UncertaintyWarning)
        m = sysid.arx(data, 1, 1, 1, integrate_noise=True)
    assert m.uncertainty is not None and m.d[0].tolist() == [-1.0]
