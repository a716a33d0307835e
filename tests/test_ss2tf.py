"""``sysid.ss2tf`` (MATLAB's ``tf(sys)``): the transfer function of a state-space model has
the model's frequency response (hypothesis, discrete and continuous, MIMO), known
coefficients, the ARX polynomials back from an ARX model's state-space form, and the model's
uncertainty carried through (the same response and pole standard deviations)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sysid
from sysid.errors import DataError

W = np.array([0.05, 0.4, 1.3, 2.9])


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 5), st.integers(1, 3), st.integers(1, 3), st.booleans(),
       st.integers(0, 10_000))
def test_same_frequency_response(n, m, l, continuous, seed):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    if n:
        A *= 0.9 / max(1e-3, np.max(np.abs(np.linalg.eigvals(A))))
    B, C, D = rng.standard_normal((n, m)), rng.standard_normal((l, n)), rng.standard_normal((l, m))
    if continuous:
        model = sysid.ContinuousStateSpace(A - np.eye(n), B, C, D)
    else:
        model = sysid.StateSpaceModel(A, B, C, D, dt=0.5)
    G = sysid.ss2tf(model)
    assert (G.dt == 0.0) == continuous and (G.noutputs, G.ninputs) == (l, m)
    H, Hm = G.freqresp(W), model.freqresp(W)
    assert np.allclose(H, Hm, rtol=1e-8, atol=1e-9 * max(1.0, np.abs(Hm).max()))


def test_known_coefficients_and_arx_round_trip():
    m = sysid.StateSpaceModel([[0.9, 0.2], [0.0, 0.5]], [[1.0], [1.0]], [[1.0, 0.0]], [[0.5]])
    G = sysid.ss2tf(m)
    # (z - 0.3) / ((z - 0.9)(z - 0.5)) + 0.5
    assert np.allclose(G.den[0][0], [1.0, -1.4, 0.45])
    assert np.allclose(G.num[0][0], np.array([0.0, 1.0, -0.3]) + 0.5 * np.array([1, -1.4, 0.45]))
    rng = np.random.default_rng(0)
    u = rng.standard_normal(400)
    y = sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]]).simulate(u) + 0.1 * rng.standard_normal(
        (400, 1))
    arx = sysid.arx(sysid.IOData(u=u, y=y), 2, 2, 1)
    Ga = sysid.minreal(sysid.ss2tf(arx))  # B(q) / A(q), from the model's state-space form
    Hq = arx.freqresp(W)
    assert np.allclose(Ga.freqresp(W), Hq, rtol=1e-8)
    assert len(Ga.den[0][0]) == 3  # A(q) of order 2


def test_uncertainty_carried_through():
    rng = np.random.default_rng(1)
    true = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0, 0.3], [0.0, 1.0]],
                                 [[1.0, 0.5], [0.0, 1.0]])
    u = rng.standard_normal((600, 2))
    data = sysid.IOData(u=u, y=true.simulate(u) + 0.05 * rng.standard_normal((600, 2)))
    m = sysid.ssest(data, 2, focus="simulation")
    G = sysid.ss2tf(m)
    H, sd = G.freqresp(W, std=True)
    Hm, sdm = m.freqresp(W, std=True)
    assert np.allclose(H, Hm) and np.allclose(sd, sdm, rtol=1e-5)
    p, ps = m.poles(std=True)
    pg, psg = G.poles(std=True)
    for pole, s in zip(p, ps):  # every pair's denominator has the model's poles, same std
        k = np.argmin(np.abs(pg - pole))
        assert abs(pg[k] - pole) < 1e-10 and np.isclose(abs(psg[k]), abs(s), rtol=1e-4)


def test_refusals():
    with pytest.raises(DataError, match="state-space model"):
        sysid.ss2tf(np.eye(2))
