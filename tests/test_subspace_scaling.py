"""Channel scaling of the subspace methods (``SubspaceEstimator(scale=True)``, the default):
the estimate does not depend on the channels' units.

Before, every weighting computed in the record's units: on a two-output record with one
output in units 1000 times smaller, the other output's validation fit of an ``n4sid`` model
fell from 58 % to -104 % (DaISy's CD player arm; here a synthetic 2 x 2 plant of the same
kind)."""

from __future__ import annotations

import pickle
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sysid
from sysid import _sysid

A = np.array([[0.9, 0.25, 0, 0], [-0.25, 0.9, 0, 0], [0, 0, 0.6, 0], [0, 0, 0, -0.4]])
B = np.array([[1.0, 0.0], [0.0, 0.5], [0.7, -0.3], [0.2, 1.0]])
C = np.array([[1.0, 0.0, 0.5, 0.0], [0.0, 0.8, 0.0, 1.0]])
PLANT = sysid.StateSpaceModel(A, B, C)


def record(n: int = 3000, noise: float = 0.3, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 2))
    e = rng.standard_normal((n, 2))
    # coloured output noise: the weighting then matters
    from scipy.signal import lfilter

    v = lfilter([1.0], [1.0, -0.95], e, axis=0)
    return u, PLANT.simulate(u) + noise * v


def quiet(fn, *a, **k):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*a, **k)


def in_units(u, y, ku, ky):
    return sysid.IOData(u=u * ku, y=y * ky)


@pytest.mark.parametrize("method", ["moesp", "n4sid", "cva", "pbsid", "ssarx"])
def test_the_estimate_does_not_depend_on_the_units(method):
    u, y = record()
    ku, ky = np.array([1.0, 1e-3]), np.array([1.0, 1e3])
    base = quiet(sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), 8, method=method).fit, 4,
                 feedthrough=True)
    other = quiet(sysid.SubspaceEstimator(in_units(u, y, ku, ky), 8, method=method).fit, 4,
                  feedthrough=True)
    np.testing.assert_allclose(np.sort_complex(other.poles()), np.sort_complex(base.poles()),
                               atol=1e-9)
    # the same model in the other units: its responses scaled by the units
    np.testing.assert_allclose(other.markov(20), base.markov(20) * ky[None, :, None]
                               / ku[None, None, :], rtol=1e-7, atol=1e-10)
    np.testing.assert_allclose(other.noise_cov, base.noise_cov * np.outer(ky, ky), rtol=1e-7)
    np.testing.assert_allclose(other.K @ np.diag(ky), base.K, rtol=1e-6, atol=1e-9)


def test_without_scaling_the_units_change_the_fit():
    """The failure the scaling removes (and ``scale=False`` still reproduces, as SLICOT and
    MATLAB compute): one output in units 1000 times smaller takes the other's fit down."""
    u, y = record()
    val_u, val_y = record(seed=1)
    ky = np.array([1.0, 1e-3])
    fits = {}
    for scale in (False, True):
        for k in (np.ones(2), ky):
            est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y * k), 8, method="n4sid",
                                          scale=scale)
            m = quiet(est.fit, 4)
            val = sysid.IOData(u=val_u, y=val_y * k)
            fits[scale, k[1]] = quiet(sysid.compare, m, val).fit.ravel()
    np.testing.assert_allclose(fits[True, 1e-3], fits[True, 1.0], atol=1e-6)
    assert np.max(np.abs(fits[False, 1e-3] - fits[False, 1.0])) > 1.0, fits


@pytest.mark.parametrize("method", ["moesp", "n4sid", "cva"])
def test_noise_free_data_give_the_plant_to_machine_precision(method):
    rng = np.random.default_rng(3)
    u = rng.standard_normal((600, 2)) * np.array([1e3, 1e-2])
    y = PLANT.simulate(u)
    m = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), 6, method=method).fit(4)
    np.testing.assert_allclose(np.sort_complex(m.poles()), np.sort_complex(PLANT.poles()),
                               atol=1e-9)
    np.testing.assert_allclose(m.markov(10), PLANT.markov(10), rtol=1e-8, atol=1e-12)
    assert m.info["settings"]["scale"] is True
    assert m.info["channel_scaling"]["input_rms"][0] > 100


@settings(max_examples=15, deadline=None)
@given(st.lists(st.floats(-3, 3), min_size=4, max_size=4))
def test_invariance_holds_for_any_units(logs):
    u, y = record(800, seed=5)
    k = 10.0 ** np.asarray(logs)
    base = quiet(sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), 6).fit, 3)
    other = quiet(sysid.SubspaceEstimator(in_units(u, y, k[:2], k[2:]), 6).fit, 3)
    np.testing.assert_allclose(np.sort_complex(other.poles()), np.sort_complex(base.poles()),
                               atol=1e-8)


def test_x0_and_the_bootstrap_are_in_the_record_units():
    u, y = record(1500)
    ky = np.array([1e3, 1.0])
    base = quiet(sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), 8).fit, 4, x0=True)
    other = quiet(sysid.SubspaceEstimator(sysid.IOData(u=u, y=y * ky), 8).fit, 4, x0=True)
    np.testing.assert_allclose(other.simulate(u, x0=other.x0),
                               base.simulate(u, x0=base.x0) * ky, rtol=1e-6, atol=1e-6)
    est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y * ky), 8)
    m = quiet(est.fit, 2, uncertainty="bootstrap", n_boot=20, rng=0)
    # the bootstrap refits are compared with the model in the same (record) units
    dc, std = m.dcgain(std=True)
    assert np.all(np.isfinite(std)) and np.all(std < 0.5 * np.abs(dc).max() * ky[:, None])


def test_an_estimator_rebuilt_from_its_factor_fits_the_same_model():
    u, y = record(1500)
    est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y * np.array([1.0, 50.0])), 8)
    again = sysid.SubspaceEstimator.from_factor(pickle.loads(pickle.dumps(est.factor)))
    a, b = quiet(est.fit, 4), quiet(again.fit, 4)
    np.testing.assert_allclose(b.markov(10), a.markov(10), rtol=1e-10, atol=1e-12)
    raw = sysid.SubspaceEstimator.from_factor(est.factor, scale=False)
    assert raw.scaled_factor is raw.factor


def test_the_factor_scaled_in_the_core_is_that_of_the_scaled_record():
    u, y = record(1000)
    su, sy = np.array([2.0, 0.5]), np.array([10.0, 3.0])
    f = _sysid.compress([(u, y)], 4, 4, None, "qr")
    g = _sysid.compress([(u / su, y / sy)], 4, 4, None, "qr")
    h = f.scaled(su.tolist(), sy.tolist())
    np.testing.assert_allclose(h.l @ h.l.T, g.l @ g.l.T, rtol=1e-10, atol=1e-8)
    # the channels' root mean squares, over the samples the windows cover
    ru, ry = f.channel_rms()
    np.testing.assert_allclose(ru, np.sqrt(np.mean(u ** 2, axis=0)), rtol=0.02)
    np.testing.assert_allclose(ry, np.sqrt(np.mean(y ** 2, axis=0)), rtol=0.02)


@pytest.mark.parametrize("scales, match", [
    (([1.0], [1.0, 1.0]), "input_scale"),
    (([1.0, 0.0], [1.0, 1.0]), "finite and positive"),
    (([1.0, 1.0], [np.nan, 1.0]), "finite and positive"),
])
def test_bad_scales_are_refused_by_name(scales, match):
    u, y = record(200)
    f = _sysid.compress([(u, y)], 3, 3)
    with pytest.raises(sysid.DataError, match=match):
        f.scaled(*scales)
    with pytest.raises(sysid.DataError, match="scale must be True or False"):
        sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), 3, scale="yes")


@pytest.mark.parametrize("fn", [sysid.n4sid, sysid.moesp, sysid.cva, sysid.pbsid, sysid.ssarx])
def test_the_one_call_functions_take_scale(fn):
    u, y = record(1500)
    d = sysid.IOData(u=u, y=y * np.array([1.0, 1e3]))
    raw = quiet(fn, d, 4, horizon=8, scale=False)
    est = sysid.SubspaceEstimator(d, 8, method=fn.__name__, scale=False)
    same = quiet(est.fit, 4)
    np.testing.assert_allclose(raw.markov(10), same.markov(10), rtol=1e-9, atol=1e-12)
    scaled = quiet(fn, d, 4, horizon=8)
    assert "channel_scaling" in scaled.info and "channel_scaling" not in raw.info


@pytest.mark.parametrize("method", ["cov", "data"])
def test_output_only_modes_do_not_depend_on_the_units(method):
    """SSI-cov computed on the record's units: one of two channels 1000 times larger moved a
    damping ratio from 5.7 % to 5.2 %."""
    rng = np.random.default_rng(0)
    a = np.array([[0.95, 0.25, 0, 0], [-0.25, 0.95, 0, 0], [0, 0, 0.7, 0.6], [0, 0, -0.6, 0.7]])
    c = np.array([[1.0, 0, 0.5, 0], [0, 1.0, 0, 0.8]])
    x, y = np.zeros(4), np.empty((4000, 2))
    for t in range(4000):
        y[t] = c @ x + 0.1 * rng.standard_normal(2)
        x = a @ x + rng.standard_normal(4)
    k = np.array([1.0, 1000.0])
    base = sysid.ssi(sysid.IOData(None, y, 1.0), [4], method=method).modes_at(4, std=False)
    other = sysid.ssi(sysid.IOData(None, y * k, 1.0), [4], method=method).modes_at(4, std=False)
    np.testing.assert_allclose(other.frequencies_hz, base.frequencies_hz, rtol=1e-9)
    np.testing.assert_allclose(other.damping, base.damping, rtol=1e-7)
    # the shapes in the record's units: the second channel's entries 1000 times larger
    assert sysid.mac(other.mode_shapes / k, base.mode_shapes).diagonal().min() > 1 - 1e-9
