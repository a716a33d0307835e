"""``ssest`` / ``pem`` with ``focus="prediction"`` (the default) on a lightly damped plant:
the noise model ``I + C (qI - A)^-1 K`` has the plant's poles, so an AR(1) output
disturbance leaves the one-step errors coloured (a notch at the resonance, where the poles
are learnt). The Gauss-Newton standard deviations of the pole's radius and angle were 1.7
and 1.55 times the spread; the reported ones are the sandwich of
``sysid.pem.prediction_sandwich``, calibrated here by Monte Carlo (200 runs: a sample std
within about 10 %, the coverage of 95 % intervals within about 3 points). With an
innovations-form disturbance the errors are white and the Gauss-Newton covariance stays."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.signal import lfilter

import sysid

R, W = 0.95, 0.5  # the resonance: poles 0.95 exp(+-0.5 i)
A = np.array([[2 * R * np.cos(W), -R * R], [1.0, 0.0]])
PLANT = sysid.StateSpaceModel(A, [[1.0], [0.0]], [[0.5, 0.3]])
N, RUNS = 1000, 200


def _quantities(m):
    p = m.poles()
    j = int(np.argmax(p.imag))
    return np.array([float(np.ravel(m.dcgain())[0]), abs(p[j]), abs(np.angle(p[j]))])


def _monte_carlo(disturbance):
    innovations = sysid.StateSpaceModel(A, [[0.6], [0.3]], PLANT.C, [[1.0]])
    est, std, notes, pending = [], [], [], []
    for run in range(RUNS):
        rng = np.random.default_rng(5000 + run)
        u, e = rng.standard_normal(N), rng.standard_normal(N)
        if disturbance == "ar1":
            v = 0.3 * lfilter([1.0], [1.0, -0.9], e)
        else:
            v = 0.3 * innovations.simulate(e[:, None])[:, 0]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sysid.SysidWarning)
            m = sysid.ssest(sysid.IOData(u=u, y=PLANT.simulate(u)[:, 0] + v), 2)
        pending.append(m.info["pem"]["covariance"].startswith("gauss-newton until first used"))
        std.append(m.uncertainty.propagate(_quantities).std)
        est.append(_quantities(m))
        notes.append(m.info["pem"]["covariance"])
    return np.array(est), np.array(std), notes, pending


@pytest.mark.parametrize("disturbance", ["ar1", "innovations"])
def test_prediction_focus_standard_deviations_match_monte_carlo(disturbance):
    est, std, notes, pending = _monte_carlo(disturbance)
    assert all(pending)  # formed when first used, not by the fit
    for k, name in enumerate(["dcgain", "pole radius", "pole angle"]):
        mc = np.std(est[:, k], ddof=1)
        ratio = float(np.sqrt(np.mean(std[:, k] ** 2)) / mc)
        # the noise model that cannot take the disturbance's shape also biases the poles
        # (by about three of their std here): the intervals are judged about the
        # estimates' mean, the value the fit converges to
        coverage = float(np.mean(np.abs(est[:, k] - est[:, k].mean()) <= 1.96 * std[:, k]))
        assert 0.8 < ratio < 1.2, (name, ratio)
        assert 0.90 <= coverage <= 0.99, (name, coverage)
    if disturbance == "ar1":
        assert all(n.startswith("sandwich for coloured prediction errors") for n in notes)
    else:  # white innovations: the Gauss-Newton covariance stays
        assert np.mean([n.startswith("gauss-newton: the prediction errors are white")
                        for n in notes]) > 0.9, notes[:3]


def test_the_prediction_sandwich_waits_for_its_first_use():
    """The sandwich waits for its first use: a fit whose uncertainty is never read does
    not pay for the Jacobian over the record, and reading it says which covariance."""
    from sysid.pem.sandwich import gauss_newton

    rng = np.random.default_rng(0)
    u = rng.standard_normal(800)
    y = PLANT.simulate(u)[:, 0] + lfilter([1.0], [1.0, -0.9], 0.3 * rng.standard_normal(800))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sysid.SysidWarning)
        m = sysid.ssest(sysid.IOData(u=u, y=y), 2)
    gn = gauss_newton(m.uncertainty)
    assert m.uncertainty.__dict__["_pending"] is not None
    assert gn.method == "gauss-newton"
    sd = m.uncertainty.std
    assert m.uncertainty.method == "gauss-newton with coloured prediction errors (sandwich)"
    assert m.info["pem"]["covariance"].startswith("sandwich for coloured prediction errors")
    assert sd.shape == gn.std.shape and not np.allclose(sd, gn.std)
