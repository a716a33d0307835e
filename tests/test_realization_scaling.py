"""Channel scaling of the realisations (``era``, ``kung``, ``ho_kalman``) and of
``frd_subspace`` (``scale=True``, the default): the model does not depend on the units.

Before, the Hankel SVD and the least squares weighed every entry in its own units: on a noisy
2 x 2 plant with one output in units 1000 times smaller and one input in units 1000 times
larger, ERA's order-2 poles moved by 0.017 and the unchanged output's Markov parameters by
7 %; ``frd_subspace``'s poles by 0.017 and that output's response by 16 %; from a time record
(``frd_subspace(IOData)``, ``okid(...).era``) the order-4 poles by more than 1. The Markov
parameter estimators themselves (least squares per output) never depended on the units."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sysid

A = np.array([[0.9, 0.25, 0, 0], [-0.25, 0.9, 0, 0], [0, 0, 0.6, 0], [0, 0, 0, -0.4]])
B = np.array([[1.0, 0.0], [0.0, 0.5], [0.7, -0.3], [0.2, 1.0]])
C = np.array([[1.0, 0.0, 0.5, 0.0], [0.0, 0.8, 0.0, 1.0]])
PLANT = sysid.StateSpaceModel(A, B, C)
KU, KY = np.array([1e3, 1.0]), np.array([1.0, 1e-3])  # one input larger, one output smaller
W = np.linspace(0.01, np.pi, 200)


def quiet(fn, *a, **k):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*a, **k)


def in_units(h, ku, ky):
    """A response (``(count, l, m)``) in other units: outputs times ``ky``, inputs ``ku``."""
    return h * ky[None, :, None] / ku[None, None, :]


def noisy_markov(seed=0):
    return PLANT.markov(40) + 0.02 * np.random.default_rng(seed).standard_normal((40, 2, 2))


def noisy_frd(seed=0, ku=None, ky=None):
    ku = np.ones(2) if ku is None else ku
    ky = np.ones(2) if ky is None else ky
    rng = np.random.default_rng(seed)
    g = PLANT.freqresp(W) + 0.05 * (rng.standard_normal((200, 2, 2))
                                    + 1j * rng.standard_normal((200, 2, 2)))
    return sysid.FRD(W, in_units(g, ku, ky), dt=1.0)


def record(n=3000, seed=0):
    from scipy.signal import lfilter

    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 2))
    v = lfilter([1.0], [1.0, -0.95], rng.standard_normal((n, 2)), axis=0)
    return u, PLANT.simulate(u) + 0.3 * v


def assert_same_model(other, base, ku, ky, rtol=1e-9):
    """``other`` is ``base`` in the other units: the same poles, responses times the units."""
    np.testing.assert_allclose(np.sort_complex(other.poles()), np.sort_complex(base.poles()),
                               rtol=rtol, atol=rtol)
    h = base.markov(20)
    np.testing.assert_allclose(other.markov(20), in_units(h, ku, ky), rtol=rtol,
                               atol=rtol * np.abs(in_units(h, ku, ky)).max())


REALISE = {
    "era": lambda h, **k: sysid.era(h, 2, **k).model,
    "kung": lambda h, **k: sysid.kung(h, 2, **k),
    "ho_kalman": lambda h, **k: sysid.ho_kalman(h, 2, **k),
}


@pytest.mark.parametrize("name", sorted(REALISE))
def test_the_realisation_does_not_depend_on_the_units(name):
    h = noisy_markov()
    base = REALISE[name](h)
    other = REALISE[name](in_units(h, KU, KY))
    assert_same_model(other, base, KU, KY)


def test_the_frequency_subspace_fit_does_not_depend_on_the_units():
    base = sysid.frd_subspace(noisy_frd(), 2)
    other = sysid.frd_subspace(noisy_frd(ku=KU, ky=KY), 2)
    assert_same_model(other, base, KU, KY)
    ct = sysid.frd_subspace(noisy_frd(), 2, continuous=True, T=1.0)
    ct_other = sysid.frd_subspace(noisy_frd(ku=KU, ky=KY), 2, continuous=True, T=1.0)
    np.testing.assert_allclose(ct_other.freqresp(W), in_units(ct.freqresp(W), KU, KY),
                               rtol=1e-9, atol=1e-9 * 1e3)


@pytest.mark.parametrize("method", ["spa", "dft"])
def test_the_fit_of_a_time_record_does_not_depend_on_the_units(method):
    u, y = record()
    base = quiet(sysid.frd_subspace, sysid.IOData(u=u, y=y), 4, method=method)
    other = quiet(sysid.frd_subspace, sysid.IOData(u=u * KU, y=y * KY), 4, method=method)
    assert_same_model(other, base, KU, KY)
    assert other.info["channel_scaling"]["output_rms"][1] < 1e-2


@pytest.mark.parametrize("estimate", ["okid", "impulse_response"])
def test_markov_parameters_from_data_then_era(estimate):
    """The Markov parameters (least squares per output) were already unit-invariant; ERA on
    them was not."""
    u, y = record()
    fit = {"okid": lambda d: sysid.okid(d, 8, 40),
           "impulse_response": lambda d: sysid.impulse_response(d, 40, regularization=None)}
    base = quiet(fit[estimate], sysid.IOData(u=u, y=y))
    other = quiet(fit[estimate], sysid.IOData(u=u * KU, y=y * KY))
    np.testing.assert_allclose(other.markov, in_units(base.markov, KU, KY), rtol=1e-9,
                               atol=1e-12)
    assert_same_model(other.era(4).model, base.era(4).model, KU, KY)


def test_without_scaling_the_units_change_the_model():
    """The failure the scaling removes (``scale=False`` still computes in the given units)."""
    h = noisy_markov()
    base = sysid.era(h, 2, scale=False).model
    other = sysid.era(in_units(h, KU, KY), 2, scale=False).model
    moved = np.abs(np.sort_complex(other.poles()) - np.sort_complex(base.poles())).max()
    assert moved > 0.01
    back = in_units(other.markov(20), 1 / KU, 1 / KY)
    change = np.abs(back[:, 0] - base.markov(20)[:, 0]).max() / np.abs(base.markov(20)).max()
    assert change > 0.05
    f0 = sysid.frd_subspace(noisy_frd(), 2, scale=False)
    f1 = sysid.frd_subspace(noisy_frd(ku=KU, ky=KY), 2, scale=False)
    assert np.abs(np.sort_complex(f1.poles()) - np.sort_complex(f0.poles())).max() > 0.01


@settings(max_examples=20, deadline=None)
@given(st.lists(st.floats(-4, 4), min_size=4, max_size=4))
def test_invariance_holds_for_any_units(logs):
    k = 10.0 ** np.asarray(logs)
    ku, ky = k[:2], k[2:]
    h = noisy_markov(1)
    assert_same_model(sysid.era(in_units(h, ku, ky), 2).model, sysid.era(h, 2).model, ku, ky,
                      rtol=1e-8)
    assert_same_model(sysid.frd_subspace(noisy_frd(1, ku, ky), 2),
                      sysid.frd_subspace(noisy_frd(1), 2), ku, ky, rtol=1e-8)


@settings(max_examples=10, deadline=None)
@given(st.lists(st.floats(-3, 3), min_size=5, max_size=5))
def test_invariance_with_more_outputs_than_inputs(logs):
    """Three outputs, two inputs, the balancing over a rectangular response."""
    k = 10.0 ** np.asarray(logs)
    ku, ky = k[:2], k[2:]
    plant = sysid.StateSpaceModel(A, B, np.vstack([C, [0.3, 0.0, 0.0, -1.0]]))
    h = plant.markov(40) + 0.02 * np.random.default_rng(2).standard_normal((40, 3, 2))
    assert_same_model(sysid.kung(in_units(h, ku, ky), 3), sysid.kung(h, 3), ku, ky, rtol=1e-8)


@pytest.mark.parametrize("name", sorted(REALISE))
def test_noise_free_markov_parameters_give_the_plant(name):
    h = in_units(PLANT.markov(41), np.array([1e4, 1e-2]), np.array([1e-3, 1e2]))
    m = {"era": lambda: sysid.era(h, 4).model, "kung": lambda: sysid.kung(h, 4),
         "ho_kalman": lambda: sysid.ho_kalman(h)}[name]()
    np.testing.assert_allclose(np.sort_complex(m.poles()), np.sort_complex(PLANT.poles()),
                               atol=1e-8)
    np.testing.assert_allclose(m.markov(41), h, rtol=1e-8, atol=1e-10 * np.abs(h).max())
    scaling = m.info["channel_scaling"]
    assert scaling["basis"] == "markov parameters"
    assert scaling["input_scale"][0] / scaling["input_scale"][1] > 1e4


def test_a_noise_free_frd_gives_the_plant():
    g = in_units(PLANT.freqresp(W), np.array([1e4, 1e-2]), np.array([1e-3, 1e2]))
    m = sysid.frd_subspace(sysid.FRD(W, g, dt=1.0), 4)
    np.testing.assert_allclose(np.sort_complex(m.poles()), np.sort_complex(PLANT.poles()),
                               atol=1e-8)
    np.testing.assert_allclose(m.freqresp(W), g, rtol=1e-8, atol=1e-10 * np.abs(g).max())
    assert m.info["channel_scaling"]["basis"] == "frequency response"


def test_the_balanced_response_has_unit_rms_rows_and_columns():
    from sysid.subspace.scaling import balanced_scales

    h = in_units(noisy_markov(), KU, KY)
    su, sy = balanced_scales(h, "Markov parameters")
    hs = h * su / sy[:, None]
    np.testing.assert_allclose(np.sqrt(np.mean(hs ** 2, axis=(0, 2))), 1.0, rtol=1e-12)
    np.testing.assert_allclose(np.sqrt(np.mean(hs ** 2, axis=(0, 1))), 1.0, rtol=1e-12)


def test_one_input_and_one_output_are_not_scaled():
    h = noisy_markov()[:, :1, :1] * 1e3
    a, b = sysid.era(h, 2), sysid.era(h, 2, scale=False)
    np.testing.assert_array_equal(a.model.A, b.model.A)
    np.testing.assert_array_equal(a.singular_values, b.singular_values)
    assert "channel_scaling" not in a.model.info


def test_scale_false_realises_the_parameters_as_given():
    h = in_units(noisy_markov(), KU, KY)
    raw = sysid.era(h, 2, scale=False)
    assert "channel_scaling" not in raw.model.info
    # the Hankel singular values of the parameters as given
    hank = np.block([[h[i + j + 1] for j in range(raw.cols)] for i in range(raw.rows)])
    np.testing.assert_allclose(raw.singular_values[:4], np.linalg.svd(hank, compute_uv=False)[:4],
                               rtol=1e-10)
    est = sysid.MarkovEstimate(h, 1.0, "fir", {})
    np.testing.assert_array_equal(est.era(2, scale=False).model.A, raw.model.A)
    d = sysid.era_stabilization(h, [2, 4], scale=False)
    np.testing.assert_allclose(np.sort(d.modes[0].frequencies_hz),
                               np.sort(raw.modes().frequencies_hz))


def test_modal_indicators_are_those_of_the_scaled_parameters():
    h = noisy_markov()
    base, other = sysid.era(h, 2), sysid.era(in_units(h, KU, KY), 2)
    np.testing.assert_allclose(other.mac, base.mac, rtol=1e-9)
    np.testing.assert_allclose(other.mpc, base.mpc, rtol=1e-9)
    np.testing.assert_allclose(other.singular_values, base.singular_values, rtol=1e-9)


def test_a_channel_without_response_is_named():
    h = noisy_markov()
    h[:, 1, :] = 0.0
    with pytest.raises(sysid.DataError, match="output 1 has no response"):
        sysid.era(h, 2)
    assert sysid.era(h, 2, scale=False).model.nstates == 2  # as before, unscaled
    h = noisy_markov()
    h[:, :, 0] = 0.0
    with pytest.raises(sysid.DataError, match="input 0 has no response"):
        sysid.kung(h, 2)
    g = noisy_frd().response.copy()
    g[:, 0, :] = 0.0
    frd = sysid.FRD(W, g, dt=1.0, output_names=["force", "speed"])
    with pytest.raises(sysid.DataError, match="output 0 \\('force'\\) has no response"):
        sysid.frd_subspace(frd, 2)
    u, y = record(500)
    u[:, 1] = 0.0
    with pytest.raises(sysid.DataError, match="input 1 has root mean square 0"):
        quiet(sysid.frd_subspace, sysid.IOData(u=u, y=y), 2)


def test_non_finite_parameters_and_bad_scale_values_are_named():
    h = noisy_markov()
    h[3, 1, 0] = np.nan
    with pytest.raises(sysid.NonFiniteError, match="output 1, input 0"):
        sysid.era(h, 2)
    with pytest.raises(sysid.DataError, match="scale must be True or False"):
        sysid.era(noisy_markov(), 2, scale="yes")
    with pytest.raises(sysid.DataError, match="scale must be True or False"):
        sysid.frd_subspace(noisy_frd(), 2, scale=1)
