"""Simulation-error fits (``focus="simulation"``) with a coloured disturbance: the reported
standard deviations are the sandwich covariance's (``sysid.pem.sandwich``), calibrated by
Monte Carlo; with white errors they stay the Gauss-Newton ones."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid

A = np.diag([0.9, 0.6])
PLANT = sysid.StateSpaceModel(A, [[1.0], [1.0]], [[1.0, -0.5]])
DC = 1 / (1 - 0.9) - 0.5 / (1 - 0.6)  # the plant's static gain, 8.75


def _runs(K, runs=200):
    noise = sysid.StateSpaceModel(A, K, [[1.0, -0.5]], [[1.0]])  # H = 1 + C (qI - A)^-1 K
    gains, stds, poles, pole_stds, notes = [], [], [], [], set()
    for i in range(runs):
        rng = np.random.default_rng(1000 + i)
        u, e = rng.standard_normal(500), 0.2 * rng.standard_normal(500)
        y = PLANT.simulate(u)[:, 0] + noise.simulate(e)[:, 0]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            m = sysid.ssest(sysid.IOData(u=u, y=y), 2, focus="simulation")
            g, s = m.dcgain(std=True)
            p, ps = m.poles(std=True)
        gains.append(float(np.ravel(g)[0]))
        stds.append(float(np.ravel(s)[0]))
        j = int(np.argmax(np.abs(p)))
        poles.append(p[j].real)
        pole_stds.append(ps[j].real)
        notes.add(m.info["pem"]["covariance"].split(" (")[0])
    g, s = np.array(gains), np.array(stds)
    return (np.std(g, ddof=1), np.mean(s), np.mean(np.abs(g - DC) <= 1.96 * s),
            np.std(poles, ddof=1), np.mean(pole_stds), notes)


@pytest.mark.parametrize("K", [[[0.3], [0.2]], [[0.0], [0.0]]], ids=["coloured", "white"])
def test_simulation_focus_standard_deviations_match_monte_carlo(K):
    # 200 runs: a sample std within about 10 % of its value (sqrt(1/(2 * 199))), a coverage
    # of 95 % within 3 points (binomial): the Gauss-Newton std of the static gain was a third
    # of the sample one with the coloured disturbance (0.073 against 0.216)
    mc, reported, coverage, pole_mc, pole_reported, notes = _runs(K)
    assert notes == {"sandwich for coloured simulation errors"}
    assert 0.75 * mc < reported < 1.25 * mc
    assert 0.75 * pole_mc < pole_reported < 1.25 * pole_mc
    assert 0.86 <= coverage <= 0.99


def test_a_correction_that_overflows_keeps_the_gauss_newton_covariance():
    """A simulated Jacobian that is finite but beyond squaring (1e200: from a model one step
    from the estimate that runs away over the record) overflowed the correction, and
    ``np.linalg.eigh`` raised LinAlgError from every standard deviation and from saving the
    model. Now the Gauss-Newton covariance stays, and the fit's note says why."""
    from sysid.models.uncertainty import ParameterUncertainty
    from sysid.pem.sandwich import sandwich_covariance

    rng = np.random.default_rng(0)
    y = rng.standard_normal((400, 1))
    e = np.cumsum(y[:, 0]) * 0.05  # coloured errors: the correction is formed

    class Runaway(ParameterUncertainty):
        def scaled_jacobian(self, fn, *, step=1e-3):
            G = np.column_stack([y[:, 0], e, 1e200 * e])
            return y[:, 0] - e, G

    unc = Runaway([0.5, 1.0, 1.0], np.diag([1e-2, 2e-2, 3e-2]),
                  lambda t: sysid.StateSpaceModel([[t[0]]], [[t[1]]], [[t[2]]]))
    got, note = sandwich_covariance(unc, lambda m: None, y)  # no RuntimeWarning either
    assert got is None and "overflows" in note
