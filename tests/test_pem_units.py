"""``sysid.pem`` searches on channels of unit root mean square (:mod:`sysid.pem.units`): the
search path, and the model it returns in the record's units, do not depend on the units of
the inputs and outputs.

Before, the search ran in the record's units: its step and stopping tests are relative to
the norm of the parameter vector, whose ``B`` entries carry the inverse of the inputs' units
and ``C`` entries the outputs' units. Inputs 1000 and 0.01 times their size and outputs
10 000 and 0.03 times theirs took a 2 x 2 prediction search from 5 iterations to its cap of
50 (poles 1e-3 apart), and a simulation search from 3 to 8 iterations."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sysid

A2 = np.array([[0.9, 0.25, 0, 0], [-0.25, 0.9, 0, 0], [0, 0, 0.6, 0], [0, 0, 0, -0.4]])
B2 = np.array([[1.0, 0.0], [0.0, 0.5], [0.7, -0.3], [0.2, 1.0]])
C2 = np.array([[1.0, 0.0, 0.5, 0.0], [0.0, 0.8, 0.0, 1.0]])
A1 = np.array([[0.85, 0.3], [-0.3, 0.85]])
B1, C1 = np.array([[1.0], [0.3]]), np.array([[1.0, 0.4]])
W = np.linspace(0.05, 3.0, 7)


def _record(l: int, seed: int = 0, n: int = 800) -> tuple[np.ndarray, np.ndarray]:
    """A record of the SISO (``l == 1``) or 2 x 2 plant, its output noise coloured."""
    rng = np.random.default_rng(seed)
    A, B, C = (A1, B1, C1) if l == 1 else (A2, B2, C2)
    u = rng.standard_normal((n, B.shape[1]))
    e = 0.2 * rng.standard_normal((n, l))
    e[1:] += 0.5 * e[:-1]
    return u, sysid.StateSpaceModel(A, B, C).simulate(u) + e


def _in_units(m: sysid.StateSpaceModel, ku: np.ndarray, ky: np.ndarray
              ) -> sysid.StateSpaceModel:
    """``m`` for inputs ``ku`` and outputs ``ky`` times larger (the same state)."""
    return sysid.StateSpaceModel(m.A, m.B / ku, ky[:, None] * m.C,
                                 ky[:, None] * m.D / ku, None if m.K is None else m.K / ky,
                                 dt=m.dt)


def _quiet(fn, *a, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*a, **kw)


def _refit(u, y, start, ku, ky, **kw):
    return _quiet(sysid.pem, sysid.IOData(u=u * ku, y=y * ky), _in_units(start, ku, ky), **kw)


def _cost_ratio(weighting: str, ky: np.ndarray) -> float:
    """The record-units criterion in the new units over the old: the determinant changes by
    ``prod(ky^2)``, the plain sum of squares (common ``ky``) by ``ky^2``, the sum relative
    to each output's scale not at all."""
    return {"noise": float(np.prod(ky ** 2)), "identity": float(ky[0] ** 2),
            "output": 1.0}[weighting]


def _check_same(m1, m2, ku, ky, weighting, rtol=1e-8):
    i1, i2 = m1.info["pem"], m2.info["pem"]
    assert i2["iterations"] == i1["iterations"] and i2["stop"] == i1["stop"]
    ratio = _cost_ratio(weighting, ky)
    np.testing.assert_allclose(np.array(i2["cost"]) / ratio, i1["cost"], rtol=1e-8)
    np.testing.assert_allclose(np.array(i2["loss_history"]) / np.prod(ky ** 2),
                               i1["loss_history"], rtol=1e-8)
    # the same model, in the same state basis, mapped to the record's units
    back = _in_units(m2, 1.0 / ku, 1.0 / ky)
    for a, b in ((back.A, m1.A), (back.B, m1.B), (back.C, m1.C), (back.D, m1.D)):
        np.testing.assert_allclose(a, b, rtol=0, atol=rtol * max(np.abs(b).max(), 1e-300))
    if m1.K is not None:
        np.testing.assert_allclose(back.K, m1.K, rtol=0, atol=rtol * np.abs(m1.K).max())
    np.testing.assert_allclose(m2.noise_cov / np.outer(ky, ky), m1.noise_cov, rtol=1e-7)
    np.testing.assert_allclose(i2["x0_values"][0], i1["x0_values"][0], rtol=0,
                               atol=rtol * np.abs(i1["x0_values"][0]).max())
    p1, s1 = m1.poles(std=True)
    p2, s2 = m2.poles(std=True)
    o1, o2 = np.argsort(p1), np.argsort(p2)
    np.testing.assert_allclose(p2[o2], p1[o1], rtol=rtol)
    np.testing.assert_allclose(s2[o2].real, s1[o1].real, rtol=1e-6)
    np.testing.assert_allclose(s2[o2].imag, s1[o1].imag, rtol=1e-6, atol=1e-12)
    h1, sd1 = m1.freqresp(W, std=True)
    h2, sd2 = m2.freqresp(W, std=True)
    g = ky[None, :, None] / ku[None, None, :]
    np.testing.assert_allclose(h2 / g, h1, rtol=1e-7)
    np.testing.assert_allclose(sd2.real / g, sd1.real, rtol=1e-6)
    np.testing.assert_allclose(sd2.imag / g, sd1.imag, rtol=1e-6)


CASES = [  # focus, weighting, outputs
    ("simulation", "identity", 1),
    ("simulation", "identity", 2),
    ("simulation", "output", 2),
    ("simulation", "noise", 2),
    ("prediction", "noise", 1),
    ("prediction", "noise", 2),
    ("prediction", "identity", 2),
    ("prediction", "output", 2),
]


@pytest.mark.parametrize(("focus", "weighting", "l"), CASES)
def test_the_search_is_the_same_in_any_units(focus, weighting, l):
    u, y = _record(l)
    start = sysid.n4sid(sysid.IOData(u=u, y=y), 2 if l == 1 else 4)
    m = u.shape[1]
    m1 = _refit(u, y, start, np.ones(m), np.ones(l), focus=focus, weighting=weighting)
    assert m1.info["pem"]["iterations"] >= 2
    ku = np.array([1e-3, 1e2])[:m]
    # per-output units where the criterion allows them; one factor for the plain sum
    ky = np.full(l, 1e4) if weighting == "identity" else np.array([1e4, 3e-2])[:l]
    m2 = _refit(u, y, start, ku, ky, focus=focus, weighting=weighting)
    _check_same(m1, m2, ku, ky, weighting)
    # pem_loss: the same criterion, in the record's units
    d1 = sysid.IOData(u=u, y=y)
    d2 = sysid.IOData(u=u * ku, y=y * ky)
    assert sysid.pem_loss(d2, _in_units(start, ku, ky), focus=focus, weighting=weighting) \
        == pytest.approx(sysid.pem_loss(d1, start, focus=focus, weighting=weighting)
                         * _cost_ratio(weighting, ky), rel=1e-9)


def test_the_reported_criterion_and_channel_scales():
    # the criterion is reported in the record's units: the determinant of its prediction
    # errors (and the progress callback gets it too); the scales are in info
    u, y = _record(2, seed=1)
    start = sysid.n4sid(sysid.IOData(u=u, y=y), 4)
    ku, ky = np.array([10.0, 0.1]), np.array([1e3, 2.0])
    seen = []
    m = _refit(u, y, start, ku, ky, progress=lambda *a: seen.append(a[1]))
    info = m.info["pem"]
    assert seen == info["cost"][1:] and info["loss_history"] == info["cost"]
    scales = info["channel_scaling"]
    np.testing.assert_allclose(scales["input"], ku * np.sqrt(np.mean(u ** 2, 0)), rtol=1e-12)
    np.testing.assert_allclose(scales["output"], ky * np.sqrt(np.mean(y ** 2, 0)), rtol=1e-12)
    e = y * ky - _quiet(m.predict, u * ku, y * ky, x0=info["x0_values"][0])
    assert info["cost"][-1] == pytest.approx(np.linalg.det(e.T @ e / len(e)), rel=1e-8)


@settings(max_examples=12, deadline=None)
@given(st.lists(st.floats(-5.0, 5.0), min_size=4, max_size=4),
       st.sampled_from([("prediction", "noise"), ("simulation", "output")]))
def test_any_positive_units(decades, case):
    focus, weighting = case
    u, y = _record(2, seed=2, n=500)
    start = sysid.n4sid(sysid.IOData(u=u, y=y), 4)
    ref = _refit(u, y, start, np.ones(2), np.ones(2), focus=focus, weighting=weighting)
    ku, ky = 10.0 ** np.array(decades[:2]), 10.0 ** np.array(decades[2:])
    _check_same(ref, _refit(u, y, start, ku, ky, focus=focus, weighting=weighting), ku, ky,
                weighting, rtol=1e-7)


def test_a_regularised_search_stays_in_the_records_units():
    # its R and nominal are the record's parameters: no channel scaling, no balancing
    u, y = _record(1, seed=3)
    start = sysid.n4sid(sysid.IOData(u=u, y=y), 2)
    m = _quiet(sysid.pem, (u * 10.0, y), _in_units(start, np.array([10.0]), np.ones(1)),
               regularization={"lambda": 1.0, "nominal": "model"})
    assert m.info["pem"]["channel_scaling"] == {"input": [1.0], "output": [1.0]}
    assert m.info["pem"]["state_scale"] == 1.0
