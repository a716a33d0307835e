"""Balanced truncation of unstable models (MATLAB's balred): the unstable part is kept, the
stable part reduced, for discrete and continuous models."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
from hypothesis import given, settings
from hypothesis import strategies as st
from test_realization import random_system

import sysid
from sysid import _sysid


def _hidden(stable: np.ndarray, unstable: np.ndarray, m: int, l: int, seed: int
            ) -> tuple[np.ndarray, ...]:
    """``(A, B, C, D, As, Bs, Cs)``: block-diagonal stable + unstable parts behind a random
    well-conditioned similarity; ``(As, Bs, Cs, D)`` is the stable part of the model."""
    rng = np.random.default_rng(seed)
    ns, nu = stable.shape[0], unstable.shape[0]
    n = ns + nu
    B, C, D = rng.standard_normal((n, m)), rng.standard_normal((l, n)), rng.standard_normal((l, m))
    Q = sla.qr(rng.standard_normal((n, n)))[0]
    T = Q @ np.diag(rng.uniform(0.5, 2.0, n))
    A = sla.block_diag(stable, unstable)
    return (np.linalg.solve(T, A @ T), np.linalg.solve(T, B), C @ T, D,
            stable, B[:ns], C[:, :ns])


def _stable_discrete(ns: int, seed: int) -> np.ndarray:
    A = np.random.default_rng(seed).standard_normal((ns, ns))
    return 0.9 * A / np.max(np.abs(np.linalg.eigvals(A)))


UNSTABLE_Z = np.array([[1.1, 0.3, 0.0], [-0.3, 1.1, 0.0], [0.0, 0.0, -1.4]])
UNSTABLE_S = np.array([[0.5, 1.0, 0.0], [-1.0, 0.5, 0.0], [0.0, 0.0, 2.0]])


def _unstable_poles(model, dt: float) -> np.ndarray:
    p = model.poles()
    return np.sort_complex(p[np.abs(p) > 1] if dt else p[p.real > 0])


def _hinf_error(full, red, w: np.ndarray) -> float:
    return float(np.max(np.linalg.norm(full.freqresp(w) - red.freqresp(w), ord=2, axis=(1, 2))))


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 10_000), ns=st.integers(2, 7), extra=st.integers(0, 7))
def test_discrete_unstable_poles_are_kept_and_the_stable_part_meets_its_bound(
        seed: int, ns: int, extra: int) -> None:
    dt = 0.1
    A, B, C, D, As, Bs, Cs = _hidden(_stable_discrete(ns, seed), UNSTABLE_Z, 2, 2, seed)
    model = sysid.StateSpaceModel(A, B, C, D, dt=dt)
    hsv = sysid.hankel_singular_values(sysid.StateSpaceModel(As, Bs, Cs, D, dt=dt))
    order = 3 + min(extra, ns)
    red = sysid.balanced_truncation(model, order)
    assert red.nstates == order and red.info["unstable_states"] == 3
    np.testing.assert_allclose(_unstable_poles(red, dt), np.sort_complex(sla.eigvals(UNSTABLE_Z)),
                               atol=1e-10)
    np.testing.assert_allclose(red.info["hankel_singular_values"], hsv, rtol=1e-7,
                               atol=1e-10 * hsv[0])
    bound = 2 * hsv[order - 3:].sum()
    assert red.info["error_bound"] == pytest.approx(bound, rel=1e-7, abs=1e-12)
    err = _hinf_error(model, red, np.linspace(0, np.pi / dt, 1501))
    assert err <= bound * (1 + 1e-7) + 1e-9
    if order - 3 < ns:
        assert err >= hsv[order - 3] * (1 - 1e-2)  # ||G - G_r|| >= sigma_{r+1}
    np.testing.assert_allclose(red.info["T_inv"] @ red.info["T"], np.eye(order), atol=1e-8)


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 10_000), ns=st.integers(2, 7), extra=st.integers(0, 7))
def test_continuous_unstable_poles_are_kept_and_the_stable_part_meets_its_bound(
        seed: int, ns: int, extra: int) -> None:
    rng = np.random.default_rng(seed)
    S = rng.standard_normal((ns, ns))
    S -= (np.max(np.linalg.eigvals(S).real) + 0.2 + rng.random()) * np.eye(ns)
    A, B, C, D, As, Bs, Cs = _hidden(S, UNSTABLE_S, 1, 2, seed)
    model = sysid.ContinuousStateSpace(A, B, C, D)
    wc = sla.solve_continuous_lyapunov(As, -Bs @ Bs.T)
    wo = sla.solve_continuous_lyapunov(As.T, -Cs.T @ Cs)
    hsv = np.sqrt(np.sort(np.abs(np.linalg.eigvals(wc @ wo)))[::-1])
    order = 3 + min(extra, ns)
    red = sysid.balanced_truncation(model, order)
    assert isinstance(red, sysid.ContinuousStateSpace) and red.nstates == order
    np.testing.assert_allclose(_unstable_poles(red, 0.0), np.sort_complex(sla.eigvals(UNSTABLE_S)),
                               atol=1e-10)
    # compared as squares, the eigenvalues the reference computes: a Hankel singular value
    # near sqrt(eps) * hsv[0] has no digits left after the reference's square root (seed
    # found by hypothesis: 1.646e-8 against the reference's 1.593e-8, hsv[0] = 0.43)
    np.testing.assert_allclose(red.info["hankel_singular_values"] ** 2, hsv ** 2, rtol=1e-6,
                               atol=1e-12 * hsv[0] ** 2)
    bound = 2 * hsv[order - 3:].sum()
    w = np.r_[0.0, np.logspace(-3, 3, 1500)]
    err = _hinf_error(model, red, w)
    # round-off of the balancing is about sqrt(eps) * hsv[0] on the smallest values (seed
    # 6479, ns 7, extra 5: err 3.5370e-6 against the bound 3.5356e-6, hsv[0] = 1.22, the
    # last Hankel singular value 1.6e-8)
    assert err <= bound * (1 + 1e-6) + 1e-8 * hsv[0]


def test_a_stable_model_is_truncated_as_before() -> None:
    model = random_system(8, 2, 2, 13, rmax=0.9)
    red = sysid.balanced_truncation(model, 4)
    ref = _sysid.balanced_truncation(model.A, model.B, model.C, model.D, 4)
    for mine, key in zip((red.A, red.B, red.C, red.D), "abcd"):
        np.testing.assert_array_equal(mine, ref[key])
    assert red.info["unstable_states"] == 0
    assert red.info["error_bound"] == pytest.approx(ref["error_bound"])


def test_continuous_stable_model_balances_its_continuous_gramians() -> None:
    rng = np.random.default_rng(5)
    A = rng.standard_normal((6, 6)) - 4 * np.eye(6)
    model = sysid.ContinuousStateSpace(A, rng.standard_normal((6, 2)), rng.standard_normal((1, 6)))
    red = sysid.balanced_truncation(model, 3)
    wc = sla.solve_continuous_lyapunov(red.A, -red.B @ red.B.T)
    wo = sla.solve_continuous_lyapunov(red.A.T, -red.C.T @ red.C)
    hsv = red.info["hankel_singular_values"]
    np.testing.assert_allclose(wc, np.diag(hsv[:3]), atol=1e-9 * hsv[0])  # balanced
    np.testing.assert_allclose(wo, np.diag(hsv[:3]), atol=1e-9 * hsv[0])
    assert red.info["unstable_states"] == 0


def test_order_below_the_unstable_poles_and_kalman_projection() -> None:
    A, B, C, D, *_ = _hidden(_stable_discrete(4, 1), UNSTABLE_Z, 1, 1, 1)
    model = sysid.StateSpaceModel(A, B, C, D, K=np.ones((7, 1)), x0=np.arange(7.0),
                                  noise_cov=np.eye(1))
    with pytest.raises(sysid.DataError, match="fewer than the 3 unstable poles.*order >= 3"):
        sysid.balanced_truncation(model, 2)
    with pytest.raises(sysid.DataError, match="between 1 and 7"):
        sysid.balanced_truncation(model, 8)
    cont = sysid.ContinuousStateSpace(UNSTABLE_S, np.ones((3, 1)), np.ones((1, 3)))
    with pytest.raises(sysid.DataError, match="fewer than the 3 unstable poles"):
        sysid.balanced_truncation(cont, 1)
    red = sysid.balanced_truncation(model, 7)  # nothing discarded: the same model
    np.testing.assert_allclose(red.K, red.info["T_inv"] @ model.K)
    np.testing.assert_allclose(red.x0, red.info["T_inv"] @ model.x0)
    u = np.random.default_rng(0).standard_normal((30, 1))
    np.testing.assert_allclose(red.simulate(u, "model"), model.simulate(u, "model"),
                               rtol=1e-8, atol=1e-8 * np.abs(model.simulate(u, "model")).max())
    only = sysid.balanced_truncation(model, 3)  # the stable part reduced to its D
    assert only.nstates == 3
    np.testing.assert_allclose(_unstable_poles(only, 0.1), np.sort_complex(sla.eigvals(UNSTABLE_Z)),
                               atol=1e-10)
