"""MATLAB's canon: modal and companion forms keep the model's maps and have their structure."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sysid


def _random_model(seed, n, m, l):
    rng = np.random.default_rng(seed)
    # distinct poles: real ones and complex pairs, well inside the unit circle and at least
    # 0.05 apart (nearly repeated poles, 0.0654 and 0.0655 in one draw, make the companion
    # form itself ill-conditioned: its maps then hold to about 1e-5, not to these tolerances)
    while True:
        blocks, k = [], 0
        while k < n:
            if n - k >= 2 and rng.random() < 0.5:
                r, th = rng.uniform(0.2, 0.9), rng.uniform(0.2, 2.8)
                blocks.append(r * np.array([[np.cos(th), np.sin(th)],
                                            [-np.sin(th), np.cos(th)]]))
                k += 2
            else:
                blocks.append(np.array([[rng.uniform(-0.9, 0.9)]]))
                k += 1
        p = np.concatenate([np.linalg.eigvals(b) for b in blocks])
        if n == 1 or np.abs(p[:, None] - p[None, :])[~np.eye(n, dtype=bool)].min() >= 0.05:
            break
    A0 = np.zeros((n, n))
    o = 0
    for b in blocks:
        A0[o:o + len(b), o:o + len(b)] = b
        o += len(b)
    S = rng.standard_normal((n, n)) + 3 * np.eye(n)
    A = S @ A0 @ np.linalg.inv(S)
    return sysid.StateSpaceModel(A, rng.standard_normal((n, m)), rng.standard_normal((l, n)),
                                 rng.standard_normal((l, m)), K=0.1 * rng.standard_normal((n, l)),
                                 x0=rng.standard_normal(n), dt=0.1)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**16), n=st.integers(1, 6), m=st.integers(1, 2),
       l=st.integers(1, 2))
def test_forms_keep_every_map(seed, n, m, l):
    model = _random_model(seed, n, m, l)
    rng = np.random.default_rng(seed + 1)
    u, y = rng.standard_normal((40, m)), rng.standard_normal((40, l))
    w = np.linspace(0.1, 30.0, 9)
    for form in ("modal", "companion"):
        c = sysid.canon(model, form)
        scale = 1 + np.abs(model.freqresp(w)).max()
        assert np.abs(c.freqresp(w) - model.freqresp(w)).max() < 1e-6 * scale
        assert np.abs(c.predict(u, y, 1) - model.predict(u, y, 1)).max() < 1e-6 * (
            1 + np.abs(model.predict(u, y, 1)).max())
        # the initial state moved with the states: the same free response
        np.testing.assert_allclose(c.info["T"] @ c.x0, model.x0, atol=1e-8)
        np.testing.assert_allclose(c.info["T_inv"] @ c.info["T"], np.eye(n), atol=1e-8)
        np.testing.assert_allclose(np.sort_complex(c.poles()), np.sort_complex(model.poles()),
                                   atol=1e-7)
        assert c.info["canonical_form"] == form


def test_modal_form_is_real_block_diagonal():
    m = _random_model(3, 5, 1, 1)
    A = sysid.canon(m, "modal").A
    i = 0
    while i < 5:  # each block: [[s, w], [-w, s]] with w > 0, or a real pole; zeros elsewhere
        if i + 1 < 5 and A[i, i + 1] != 0:
            s, w = A[i, i], A[i, i + 1]
            assert w > 0 and A[i + 1, i] == -w and A[i + 1, i + 1] == pytest.approx(s)
            assert np.all(A[i:i + 2, i + 2:] == 0) and np.all(A[i + 2:, i:i + 2] == 0)
            i += 2
        else:
            assert np.all(A[i, i + 1:] == 0) and np.all(A[i + 1:, i] == 0)
            i += 1


def test_companion_form_holds_the_characteristic_polynomial():
    m = _random_model(5, 4, 2, 1)
    c = sysid.canon(m, "companion")
    np.testing.assert_array_equal(c.A[:, :-1], np.eye(4, 3, -1))
    np.testing.assert_array_equal(c.B[:, 0], [1.0, 0, 0, 0])
    np.testing.assert_allclose(c.A[::-1, -1], -np.poly(m.A)[1:], atol=1e-9)
    # a polynomial model through its state-space form
    p = sysid.PolynomialModel([[[-0.5]]], [[[0.0, 1.0]]], [[1]], 1.0)
    assert sysid.canon(p, "companion").nstates >= 1


def test_forms_that_do_not_exist_say_why():
    jordan = sysid.StateSpaceModel([[0.5, 1.0], [0.0, 0.5]], [[0.0], [1.0]], [[1.0, 0.0]])
    with pytest.raises(sysid.NumericalError, match="no modal form"):
        sysid.canon(jordan, "modal")
    assert sysid.canon(jordan, "companion").A[1, 1] == pytest.approx(1.0)  # trace 1.0
    unreachable = sysid.StateSpaceModel(np.diag([0.5, 0.3]), [[1.0], [0.0]], [[1.0, 1.0]])
    with pytest.raises(sysid.DataError, match="minreal"):
        sysid.canon(unreachable, "companion")
    with pytest.raises(sysid.DataError, match="'modal' or 'companion'"):
        sysid.canon(jordan, "jordan")
    # a continuous model: the same forms, and it stays continuous
    cont = sysid.ContinuousStateSpace([[-1.0, 2.0], [-3.0, -0.5]], [[1.0], [0.0]],
                                      [[1.0, 1.0]])
    cm = sysid.canon(cont, "modal")
    assert isinstance(cm, sysid.ContinuousStateSpace) and cm.A[0, 1] > 0
    w = np.array([0.1, 1.0, 10.0])
    np.testing.assert_allclose(cm.freqresp(w), cont.freqresp(w), rtol=1e-9)


@pytest.mark.parametrize("scale", [1.0, 1e-6, 1e-12])
def test_minreal_does_not_depend_on_units(scale):
    # a stiff oscillator in SI units (m = 100 kg, k = 1e9 N/m, metres per newton: |B| 1e-9)
    # reduced to 0 states, its static gain 1e-9 -> 0, silently; and a minimal 3-state model
    # with B scaled by 1e-6 lost every state
    from scipy.signal import cont2discrete

    m, k = 100.0, 1e9
    Ac = np.array([[0.0, 1.0], [-k / m, -2 * 0.02 * np.sqrt(k * m) / m]])
    Bc, Cc = np.array([[0.0], [1 / m]]) * scale, np.array([[1.0, 0.0]])
    Ad, Bd, Cd, Dd, _ = cont2discrete((Ac, Bc, Cc, np.zeros((1, 1))), 1e-4)
    for G in (sysid.StateSpaceModel(Ad, Bd, Cd, Dd, dt=1e-4),
              sysid.ContinuousStateSpace(Ac, Bc, Cc, np.zeros((1, 1)))):
        r = sysid.minreal(G)
        assert r.nstates == 2
        np.testing.assert_allclose(r.dcgain(), G.dcgain(), rtol=1e-8)
    # units do not make a non-minimal model minimal: an unreached mode still goes
    A = np.diag([0.5, 0.9, -0.3])
    G = sysid.StateSpaceModel(A, np.array([[1.0], [0.0], [1.0]]) * scale, [[1.0, 1.0, 1.0]])
    assert sysid.minreal(G).nstates == 2
