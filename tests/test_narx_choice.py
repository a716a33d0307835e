"""nlarx with basis="auto" (the default): the degree-2 polynomial terms only where the
estimation record's held-out blocks insist on them over the linear ARX model of the same
lags (sysid.nonlinear.choice)."""

import numpy as np
import pytest

import sysid


def _polynomial(n=400, seed=0):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, n)
    y = np.zeros(n)
    for t in range(2, n):
        y[t] = -0.605 * y[t - 1] - 0.163 * y[t - 2] ** 2 + 0.588 * u[t - 1] - 0.24 * u[t - 2]
    return sysid.IOData(u, y, 1.0)


def _linear(n=400, seed=0):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, n)
    y = np.convolve(u, [0.0, 1.0, 0.5])[:n] + 0.05 * rng.standard_normal(n)
    return sysid.IOData(u, y, 1.0)


def test_a_polynomial_system_gets_its_terms():
    m = sysid.nlarx(_polynomial(), 2, 2)
    choice = m.info["basis_choice"]
    assert choice["kind"] == "polynomial" and len(choice["folds"]["linear"]) == 5
    assert choice["table"]["polynomial"] > 99.99 > choice["table"]["linear"] + 5
    assert m.terms_table() == ("y0 = -0.605 y0(t-1) + 0.588 u0(t-1) - 0.24 u0(t-2) "
                               "- 0.163 y0(t-2)^2")


def test_a_linear_system_gets_the_arx_model_of_the_same_lags():
    # the old default kept FROLS's quadratic terms, chosen for their one-step error
    m = sysid.nlarx(_linear(), 2, 2)
    assert m.info["basis_choice"]["kind"] == "linear" and m.basis.degree == 1
    assert "the linear ARX model of the same lags" in m.info["basis_choice"]["reason"]
    given = sysid.nlarx(_linear(), 2, 2, basis=sysid.PolynomialBasis(1), criterion=None)
    np.testing.assert_array_equal(np.concatenate(m.coefs), np.concatenate(given.coefs))
    assert "basis_choice" not in given.info  # a given basis is fitted once


def test_short_records_and_simulation_focus():
    short = sysid.nlarx(_linear(n=30), 1, 1)
    assert short.info["basis_choice"]["kind"] == "linear"
    assert "too short" in short.info["basis_choice"]["reason"]
    # the automatic basis with the simulation focus was refused ("needs a network"): it is
    # a sigmoid network trained on the simulation error, and the choice says why
    sim = sysid.nlarx(_linear(), 2, 2, focus="simulation")
    assert isinstance(sim, sysid.NetworkNARXModel)
    assert sim.info["focus"] == "simulation" and sim.info["refine"]["iterations"] > 0
    assert "focus='simulation'" in sim.info["basis_choice"]["reason"]
    assert sysid.compare(_linear(seed=5), sim).fit[0, 0] > 90.0
    with pytest.raises(sysid.DataError, match="focus='simulation' needs a network"):
        sysid.nlarx(_linear(), 2, 2, basis=sysid.PolynomialBasis(2), focus="simulation")
    with pytest.raises(sysid.DataError, match="no noise_terms"):
        sysid.nlarx(_linear(), 2, 2, focus="simulation", noise_terms=1)
