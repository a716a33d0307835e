"""tfest on periodic data: the discrete model fitted on the excited lines (the FRD branch on
sysid.bla of the record, issue 28): exactness, agreement with the time-domain fit within the
predicted uncertainty, "auto"'s detection and fallback, bad input."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.errors import DataError
from sysid.models.uncertainty import UncertaintyWarning

NUM, DEN = [0.5, 0.2], [1.0, -1.2, 0.5]   # (0.5 z + 0.2) / (z^2 - 1.2 z + 0.5), one lag


def record(g, n_per=256, periods=4, noise=0.0, seed=0, transient=0, n_in=1):
    """``periods`` periods of a multisine through ``g``, in steady state after ``transient``
    periods (the record starts at rest), with white output noise."""
    u = sysid.multisine(n_per, band=(0, 0.5), periods=periods + transient, seed=seed)
    if n_in > 1:  # two experiments, the inputs' phases rotated between them (as bla needs)
        v = sysid.multisine(n_per, band=(0, 0.5), periods=periods + transient, seed=seed + 7)
        us = [np.column_stack([u[:, 0], v[:, 0]]), np.column_stack([u[:, 0], -v[:, 0]])]
    else:
        us = [u]
    ys = []
    for k, ue in enumerate(us):
        if transient:
            y = g.simulate(ue)
        else:  # 20 periods before the record: steady state from its first sample
            y = g.simulate(np.vstack([np.tile(ue[:n_per], (20, 1)), ue]))[20 * n_per:]
        ys.append(y + noise * np.random.default_rng(seed + 1 + k).standard_normal(y.shape))
    return sysid.IOData(us, ys, dt=1.0) if n_in > 1 else sysid.IOData(u, ys[0], dt=1.0)


def coefficients(G):
    """Denominator (after its leading 1) and numerator of the one pair, in powers of z^-1."""
    return np.concatenate([G.den[0][0][1:], G.num[0][0]])


def test_noise_free_recovered_exactly():
    g = sysid.TransferFunction(NUM, DEN, dt=1.0)
    G = sysid.tfest(record(g), 2, 1, dt=1.0, periods=4)
    np.testing.assert_allclose(coefficients(G), [-1.2, 0.5, 0.5, 0.2], rtol=1e-8, atol=1e-10)
    assert G.dt == 1.0 and G.info["domain"] == "frequency" and G.info["periods"] == 4
    assert G.info["lines"] > 0 and G.info["periodicity"]["periods"] == "declared"


def test_noise_free_with_transient_and_estimated_delay():
    """Record from rest: the first period dropped; the delay (2 samples) from the data. With 3
    steady-state periods the std cannot be calibrated: a warning says so."""
    g = sysid.TransferFunction(NUM, DEN + [0.0, 0.0], dt=1.0)   # z^-2 more
    with pytest.warns(UncertaintyWarning, match=r"3 steady-state periods \(periods=4, "
                      r"transient=1\): measure 4 or more"):
        G = sysid.tfest(record(g, periods=3, transient=1), 2, 1, dt=1.0, periods=4,
                        transient=1, iodelay="auto")
    assert G.info["n_delays_estimated"] == 1
    np.testing.assert_allclose(G.freqresp(np.linspace(0.1, 3.0, 9)),
                               g.freqresp(np.linspace(0.1, 3.0, 9)), rtol=1e-8, atol=1e-10)
    assert G.info["periodicity"]["transient"] == 1


def test_two_inputs_noise_free():
    g = sysid.TransferFunction([[NUM, [0.3]]], [[DEN, [1.0, -0.7]]], dt=1.0)
    G = sysid.tfest(record(g, n_in=2), [[2, 1]], [[1, 0]], dt=1.0, periods=4)
    assert G.info["domain"] == "frequency"
    w = np.linspace(0.1, 3.0, 9)
    np.testing.assert_allclose(G.freqresp(w), g.freqresp(w), rtol=1e-8, atol=1e-10)


def test_noisy_agrees_with_time_domain_within_predicted_std():
    g = sysid.TransferFunction(NUM, DEN, dt=1.0)
    data = record(g, periods=8, noise=0.05, seed=3)
    Gf = sysid.tfest(data, 2, 1, dt=1.0, periods=8)
    Gt = sysid.tfest(data, 2, 1, dt=1.0)
    sf = Gf.parameters.std[:4]
    assert np.all(sf > 0) and np.all(np.isfinite(sf))
    # the time-domain estimate carries the same noise: compare with the larger std, and
    # both with the truth
    diff = np.abs(coefficients(Gf) - coefficients(Gt))
    assert np.all(diff < 4 * sf), (diff / sf)
    assert np.all(np.abs(coefficients(Gf) - [-1.2, 0.5, 0.5, 0.2]) < 4 * sf)
    assert np.all(sf < 0.02)  # an estimate, not a vacuous band


def test_auto_detects_the_period():
    g = sysid.TransferFunction(NUM, DEN, dt=1.0)
    G = sysid.tfest(record(g, periods=4, transient=1), 2, 1, dt=1.0, periods="auto")
    assert G.info["domain"] == "frequency"
    assert G.info["periodicity"]["detected"] and G.info["periodicity"]["period"] == 256
    np.testing.assert_allclose(coefficients(G), [-1.2, 0.5, 0.5, 0.2], rtol=1e-8, atol=1e-10)


def test_auto_on_non_periodic_data_falls_back_with_reason():
    g = sysid.TransferFunction(NUM, DEN, dt=1.0)
    u = np.random.default_rng(0).standard_normal(1000)
    data = sysid.IOData(u, g.simulate(u), dt=1.0)
    G = sysid.tfest(data, 2, 1, dt=1.0, periods="auto")
    assert "domain" not in G.info and G.info["method"].startswith("tfest (discrete")
    assert G.info["periodicity"]["reason"].startswith("time domain")
    np.testing.assert_allclose(coefficients(G), [-1.2, 0.5, 0.5, 0.2], atol=1e-6)


def test_bad_periods_raise_clear_errors():
    g = sysid.TransferFunction(NUM, DEN, dt=1.0)
    data = record(g, periods=4)
    with pytest.raises(DataError, match="does not divide"):
        sysid.tfest(data, 2, 1, dt=1.0, periods=3)
    with pytest.raises(DataError, match="at least 2"):
        sysid.tfest(data, 2, 1, dt=1.0, periods=4, transient=3)
    with pytest.raises(DataError, match="int or 'auto'"):
        sysid.tfest(data, 2, 1, dt=1.0, periods="yes")
    with pytest.raises(DataError, match="dt=data.dt"):
        sysid.tfest(data, 2, 1, periods=4)
    with pytest.raises(DataError, match="give periods="):
        sysid.tfest(data, 2, 1, dt=1.0, transient=1)
    with pytest.raises(DataError, match="leave them out"):
        sysid.tfest(sysid.bla(data, 4), 2, 1, dt=1.0, periods=4)


def test_time_domain_auto_delay_counts_the_lag_once():
    """delayest's delay includes the discrete model's one-sample lag (was counted twice)."""
    g = sysid.TransferFunction(NUM, DEN + [0.0, 0.0], dt=1.0)   # lag plus 2 samples
    u = np.random.default_rng(0).standard_normal(1000)
    G = sysid.tfest(sysid.IOData(u, g.simulate(u), dt=1.0), 2, 1, dt=1.0, iodelay="auto")
    w = np.linspace(0.1, 3.0, 9)
    np.testing.assert_allclose(G.freqresp(w), g.freqresp(w), rtol=1e-6, atol=1e-8)


@pytest.mark.parametrize("kw", [{"init": "x"}, {"max_delay": 3.0},
                                {"initial_state": "estimate"}])
def test_time_domain_options_refused_with_periods(kw):
    up = np.ravel(sysid.multisine(64, band=(0, 0.5), periods=3, seed=1))
    d = sysid.IOData(up, np.convolve(up, [0.0, 1.0, 0.5])[:up.size], dt=1.0)
    with pytest.raises(sysid.DataError, match=r"cannot be used with periods="):
        sysid.tfest(d, 2, 1, dt=1.0, periods=3, **kw)
