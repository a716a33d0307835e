"""Gramians, Hankel singular values and balanced realisations of unstable and continuous
models (MATLAB's gram, hsvd and balreal): inf for each unstable pole, the stable part
balanced, continuous models with their continuous gramians; stable discrete results as before.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
from hypothesis import given, settings
from hypothesis import strategies as st
from test_realization import random_system

import sysid
from sysid import _sysid


def _rotation_blocks(radii: np.ndarray, angles: np.ndarray, real: np.ndarray) -> np.ndarray:
    """Block-diagonal real matrix: ``r [[cos, sin], [-sin, cos]]`` blocks and real entries."""
    blocks = [r * np.array([[np.cos(t), np.sin(t)], [-np.sin(t), np.cos(t)]])
              for r, t in zip(radii, angles)]
    return sla.block_diag(*blocks, np.diag(real)) if blocks or real.size else np.zeros((0, 0))


def _stable_part(ns: int, dt: float, rng: np.random.Generator) -> np.ndarray:
    """Random stable ``(ns, ns)`` A: ``|z| <= 0.9``, or ``Re s <= -0.2``."""
    if ns == 0:
        return np.zeros((0, 0))
    if dt:
        A = rng.standard_normal((ns, ns))
        return rng.uniform(0.3, 0.9) * A / np.max(np.abs(np.linalg.eigvals(A)))
    A = rng.standard_normal((ns, ns))
    return A - (np.max(np.linalg.eigvals(A).real) + rng.uniform(0.2, 2.0)) * np.eye(ns)


def _unstable_part(nu: int, dt: float, rng: np.random.Generator) -> np.ndarray:
    """Random unstable ``(nu, nu)`` A in a random basis: ``|z| >= 1.1``, or ``Re s >= 0.1``
    (complex pairs and real poles)."""
    pairs = rng.integers(0, nu // 2 + 1)
    nreal = nu - 2 * pairs
    if dt:
        radii = rng.uniform(1.1, 2.0, pairs)
        real = rng.uniform(1.1, 2.0, nreal) * rng.choice([-1.0, 1.0], nreal)
        J = _rotation_blocks(radii, rng.uniform(0.2, 2.9, pairs), real)
    else:
        J = _rotation_blocks(np.zeros(pairs), np.zeros(pairs), rng.uniform(0.1, 3.0, nreal))
        for k in range(pairs):  # sigma +- j omega with sigma > 0
            s, w = rng.uniform(0.1, 2.0), rng.uniform(0.5, 5.0)
            J[2 * k:2 * k + 2, 2 * k:2 * k + 2] = [[s, w], [-w, s]]
    S = np.eye(nu) + 0.3 * rng.standard_normal((nu, nu))
    return np.linalg.solve(S, J @ S)


def _hidden_model(ns: int, nu: int, dt: float, seed: int, m: int = 2, l: int = 2,
                  ) -> tuple[object, tuple[np.ndarray, ...], np.ndarray]:
    """A model whose stable part ``(As, Bs, Cs, D)`` and unstable poles are known, behind a
    random well-conditioned change of basis: ``(model, stable part, unstable poles)``."""
    rng = np.random.default_rng(seed)
    As, Au = _stable_part(ns, dt, rng), _unstable_part(nu, dt, rng)
    n = ns + nu
    B, C, D = rng.standard_normal((n, m)), rng.standard_normal((l, n)), rng.standard_normal((l, m))
    T = sla.qr(rng.standard_normal((n, n)))[0] @ np.diag(rng.uniform(0.5, 2.0, n))
    A = np.linalg.solve(T, sla.block_diag(As, Au) @ T)
    Bt, Ct = np.linalg.solve(T, B), C @ T
    model = (sysid.StateSpaceModel(A, Bt, Ct, D, dt=dt) if dt else
             sysid.ContinuousStateSpace(A, Bt, Ct, D))
    return model, (As, B[:ns], C[:, :ns], D), np.sort_complex(np.linalg.eigvals(Au))


def _gram(A: np.ndarray, B: np.ndarray, C: np.ndarray, dt: float) -> tuple[np.ndarray, ...]:
    """Reference gramians from scipy (discrete or continuous Lyapunov equations)."""
    if dt:
        return (sla.solve_discrete_lyapunov(A, B @ B.T), sla.solve_discrete_lyapunov(A.T, C.T @ C))
    return (sla.solve_continuous_lyapunov(A, -B @ B.T),
            sla.solve_continuous_lyapunov(A.T, -C.T @ C))


def _ref_hsv(A: np.ndarray, B: np.ndarray, C: np.ndarray, dt: float) -> np.ndarray:
    wc, wo = _gram(A, B, C, dt)
    return np.sqrt(np.sort(np.abs(np.linalg.eigvals(wc @ wo)))[::-1])


def _unstable_poles(A: np.ndarray, dt: float) -> np.ndarray:
    p = np.linalg.eigvals(A)
    return np.sort_complex(p[np.abs(p) > 1] if dt else p[p.real > 0])


# -- stable discrete models: bit-identical to the Rust core (as before the change) ----------

@pytest.mark.parametrize("n, m, l, seed", [(2, 1, 1, 0), (6, 2, 3, 4), (11, 3, 2, 8)])
def test_stable_discrete_results_are_the_rust_cores_bit_for_bit(n: int, m: int, l: int,
                                                                 seed: int) -> None:
    model = sysid.StateSpaceModel(*(lambda s: (s.A, s.B, s.C, s.D))(random_system(n, m, l, seed)),
                                  K=np.ones((n, l)), x0=np.arange(float(n)), noise_cov=np.eye(l))
    A, B, C, D = model.A, model.B, model.C, model.D
    g = sysid.gramians(model)
    wc, wo = _sysid.gramians(A, B, C, D)
    np.testing.assert_array_equal(g.controllability, wc)
    np.testing.assert_array_equal(g.observability, wo)
    np.testing.assert_array_equal(sysid.hankel_singular_values(model),
                                  _sysid.hankel_singular_values(A, B, C, D))
    bal = sysid.balanced_realization(model)
    ref = _sysid.balanced_truncation(A, B, C, D, None)
    for mine, key in zip((bal.A, bal.B, bal.C, bal.D), "abcd"):
        np.testing.assert_array_equal(mine, ref[key])
    np.testing.assert_array_equal(bal.info["T_inv"], ref["t_inv"])
    np.testing.assert_array_equal(bal.K, ref["t_inv"] @ model.K)
    assert bal.info["unstable_states"] == 0 and bal.info["method"] == "balanced"


# -- unstable models: inf for each unstable pole, then the stable part's values -------------

@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 100_000), ns=st.integers(0, 7), nu=st.integers(1, 5),
       continuous=st.booleans())
def test_hsv_of_an_unstable_model_is_inf_then_the_stable_parts(
        seed: int, ns: int, nu: int, continuous: bool) -> None:
    dt = 0.0 if continuous else 0.05
    model, (As, Bs, Cs, _), _ = _hidden_model(ns, nu, dt, seed)
    hsv = sysid.hankel_singular_values(model)
    assert hsv.shape == (ns + nu,)
    np.testing.assert_array_equal(hsv[:nu], np.inf)
    if ns:
        ref = _ref_hsv(As, Bs, Cs, dt)
        np.testing.assert_allclose(hsv[nu:], ref, rtol=1e-7, atol=1e-10 * ref[0])


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 100_000), ns=st.integers(1, 7), nu=st.integers(0, 4),
       continuous=st.booleans())
def test_balanced_realization_keeps_the_unstable_poles_first_and_balances_the_rest(
        seed: int, ns: int, nu: int, continuous: bool) -> None:
    dt = 0.0 if continuous else 0.05
    model, (As, Bs, Cs, _), poles_u = _hidden_model(ns, nu, dt, seed)
    bal = sysid.balanced_realization(model)
    assert type(bal) is type(model) and bal.nstates == ns + nu
    assert bal.info["unstable_states"] == nu
    # unstable states first, decoupled, with exactly the unstable poles
    np.testing.assert_array_equal(bal.A[:nu, nu:], 0.0)
    np.testing.assert_array_equal(bal.A[nu:, :nu], 0.0)
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(bal.A[:nu, :nu])), poles_u,
                               atol=1e-10)
    np.testing.assert_allclose(_unstable_poles(bal.A, dt), poles_u, atol=1e-10)
    # the stable part balanced: both gramians diag(hsv of the known stable part)
    ref = _ref_hsv(As, Bs, Cs, dt)
    info_hsv = bal.info["hankel_singular_values"]
    np.testing.assert_array_equal(info_hsv[:nu], np.inf)
    np.testing.assert_allclose(info_hsv[nu:], ref, rtol=1e-7, atol=1e-10 * ref[0])
    np.testing.assert_allclose(info_hsv, sysid.hankel_singular_values(model), rtol=1e-12,
                               atol=1e-14 * ref[0])
    wc, wo = _gram(bal.A[nu:, nu:], bal.B[nu:], bal.C[:, nu:], dt)
    np.testing.assert_allclose(wc, np.diag(ref), atol=1e-8 * ref[0])
    np.testing.assert_allclose(wo, np.diag(ref), atol=1e-8 * ref[0])
    # the same input-output behaviour, and a consistent transformation
    w = np.logspace(-2, 2, 60) if continuous else np.linspace(0.01, np.pi / dt, 60)
    full = model.freqresp(w)
    np.testing.assert_allclose(bal.freqresp(w), full, rtol=1e-7, atol=1e-8 * np.abs(full).max())
    T, T_inv = bal.info["T"], bal.info["T_inv"]
    np.testing.assert_allclose(T_inv @ T, np.eye(ns + nu), atol=1e-8)
    np.testing.assert_allclose(T_inv @ model.A @ T, bal.A, atol=1e-8 * np.abs(model.A).max())


def test_unstable_discrete_balanced_realization_transforms_kalman_gain_and_state() -> None:
    base, *_ = _hidden_model(3, 2, 0.1, 7, m=1, l=2)
    model = sysid.StateSpaceModel(base.A, base.B, base.C, base.D, K=np.ones((5, 2)),
                                  x0=np.arange(5.0), noise_cov=np.eye(2), dt=0.1)
    bal = sysid.balanced_realization(model)
    np.testing.assert_allclose(bal.K, bal.info["T_inv"] @ model.K)
    np.testing.assert_allclose(bal.x0, bal.info["T_inv"] @ model.x0)
    u = np.random.default_rng(0).standard_normal((25, 1))
    y = model.simulate(u, "model")
    np.testing.assert_allclose(bal.simulate(u, "model"), y, rtol=1e-8, atol=1e-8 * np.abs(y).max())


# -- continuous stable models: continuous gramians ------------------------------------------

@pytest.mark.parametrize("seed", [0, 1, 2])
def test_continuous_gramians_solve_the_continuous_lyapunov_equations(seed: int) -> None:
    model, *_ = _hidden_model(6, 0, 0.0, seed, m=2, l=3)
    g = sysid.gramians(model)
    A, B, C = model.A, model.B, model.C
    wc, wo = g.controllability, g.observability
    np.testing.assert_allclose(A @ wc + wc @ A.T + B @ B.T, 0.0, atol=1e-12 * np.abs(wc).max())
    np.testing.assert_allclose(A.T @ wo + wo @ A + C.T @ C, 0.0, atol=1e-12 * np.abs(wo).max())
    np.testing.assert_array_equal(wc, wc.T)
    control = pytest.importorskip("control")
    np.testing.assert_allclose(wc, control.lyap(A, B @ B.T), rtol=1e-9,
                               atol=1e-12 * np.abs(wc).max())
    np.testing.assert_allclose(wo, control.lyap(A.T, C.T @ C), rtol=1e-9,
                               atol=1e-12 * np.abs(wo).max())


def test_continuous_balanced_realization_has_equal_diagonal_gramians() -> None:
    model, *_ = _hidden_model(7, 0, 0.0, 11, m=2, l=2)
    bal = sysid.balanced_realization(model)
    assert isinstance(bal, sysid.ContinuousStateSpace) and bal.info["unstable_states"] == 0
    hsv = bal.info["hankel_singular_values"]
    np.testing.assert_allclose(hsv, sysid.hankel_singular_values(model), rtol=1e-12,
                               atol=1e-14 * hsv[0])
    g = sysid.gramians(bal)
    np.testing.assert_allclose(g.controllability, np.diag(hsv), rtol=0, atol=1e-9 * hsv[0])
    np.testing.assert_allclose(g.observability, np.diag(hsv), rtol=0, atol=1e-9 * hsv[0])
    np.testing.assert_allclose(np.diag(g.controllability), hsv, rtol=1e-9)
    w = np.logspace(-2, 2, 50)
    np.testing.assert_allclose(bal.freqresp(w), model.freqresp(w), rtol=1e-9, atol=1e-12)


# -- python-control as the oracle -----------------------------------------------------------

def _control_hsvd(control, sys) -> np.ndarray:
    """control.hsvd; without slycot (its gram needs sb03md) its own formula,
    sqrt(eig(Wo Wc)) sorted high to low, with control.lyap / control.dlyap."""
    try:
        return np.asarray(control.hsvd(sys))
    except (control.ControlSlycot, NotImplementedError):  # slycot missing / discrete time
        lyap = control.dlyap if sys.isdtime(strict=True) else control.lyap
        wc = lyap(sys.A, sys.B @ sys.B.T)
        wo = lyap(sys.A.T, sys.C.T @ sys.C)
        return np.sort(np.sqrt(np.linalg.eigvals(wo @ wc)).real)[::-1]


@pytest.mark.parametrize("dt, seed", [(0.0, 3), (0.0, 4), (0.02, 5), (0.02, 6)])
def test_stable_hsv_match_python_control(dt: float, seed: int) -> None:
    control = pytest.importorskip("control")
    model, *_ = _hidden_model(6, 0, dt, seed, m=2, l=2)
    sys = control.ss(model.A, model.B, model.C, model.D, dt if dt else 0)
    hsv = sysid.hankel_singular_values(model)
    np.testing.assert_allclose(hsv, _control_hsvd(control, sys), rtol=1e-8, atol=1e-11 * hsv[0])


def test_python_control_refuses_unstable_models_where_hsvd_gives_inf() -> None:
    control = pytest.importorskip("control")
    model, (As, Bs, Cs, D), _ = _hidden_model(3, 2, 0.0, 9)
    with pytest.raises(ValueError, match="unstable"):
        control.hsvd(control.ss(model.A, model.B, model.C, model.D))
    stable = control.ss(As, Bs, Cs, D)
    hsv = sysid.hankel_singular_values(model)
    np.testing.assert_allclose(hsv, np.r_[np.inf, np.inf, _control_hsvd(control, stable)],
                               rtol=1e-7)


def test_continuous_hsv_are_those_of_the_tustin_discretisation_and_of_the_hankel_matrix() -> None:
    """Two oracles independent of any Lyapunov solver: the bilinear transform keeps the Hankel
    singular values, and a discrete model's are the singular values of its Hankel matrix."""
    model, *_ = _hidden_model(5, 0, 0.0, 21, m=1, l=2)
    disc = sysid.c2d(model, 0.3, "tustin")
    np.testing.assert_allclose(sysid.hankel_singular_values(model),
                               sysid.hankel_singular_values(disc), rtol=1e-8)
    markov = disc.markov(400)[1:]  # h_1, h_2, ...: (l, m) each
    k = 200
    H = np.block([[markov[i + j] for j in range(k)] for i in range(k)])
    np.testing.assert_allclose(np.linalg.svd(H, compute_uv=False)[:5],
                               sysid.hankel_singular_values(disc), rtol=1e-8)


def test_continuous_transfer_function_goes_through_its_realisation() -> None:
    tf = sysid.TransferFunction([1.0], [1.0, 2.0])  # python-control's hsvd example: 0.25
    np.testing.assert_allclose(sysid.hankel_singular_values(tf), [0.25])
    assert float(sysid.gramians(tf).controllability[0, 0]) == pytest.approx(
        float(sysid.gramians(tf.to_statespace()).controllability[0, 0]))
    assert isinstance(sysid.balanced_realization(tf), sysid.ContinuousStateSpace)


# -- errors ---------------------------------------------------------------------------------

@pytest.mark.parametrize("continuous", [False, True])
def test_gramians_of_an_unstable_model_name_the_pole_and_the_way_out(continuous: bool) -> None:
    dt = 0.0 if continuous else 0.1
    model, *_ = _hidden_model(3, 1, dt, 2)
    pole = _unstable_poles(model.A, dt)[0].real
    with pytest.raises(sysid.DataError, match="not stable") as err:
        sysid.gramians(model)
    text = str(err.value)
    assert f"{pole:.6g}" in text
    for name in ("hankel_singular_values", "balanced_truncation"):
        assert name in text


@pytest.mark.parametrize("A, dt, shown", [
    ([[1.0 - 1e-10, 0.0], [0.0, 0.5]], 0.1, "modulus 0.9999999999"),  # inside by < 1e-8
    ([[-1.0, 0.0], [0.0, 0.0]], 0.0, "real part 0 "),                  # an integrator
    ([[-2.0, 0.0], [0.0, -1e-10]], 0.0, "real part -1e-10"),           # left of 0 by < 1e-8
])
def test_poles_on_the_boundary_within_the_margin_count_as_unstable(A, dt, shown) -> None:
    B, C = np.ones((2, 1)), np.ones((1, 2))
    model = (sysid.StateSpaceModel(A, B, C, dt=dt) if dt else
             sysid.ContinuousStateSpace(A, B, C))
    with pytest.raises(sysid.DataError, match=f"not stable.*{shown}.*1e-8"):
        sysid.gramians(model)
    hsv = sysid.hankel_singular_values(model)
    assert hsv[0] == np.inf and np.isfinite(hsv[1])
    assert sysid.balanced_realization(model).info["unstable_states"] == 1


def test_stable_and_unstable_poles_too_close_to_separate_is_a_numerical_error() -> None:
    A = np.array([[1.0 - 1.1e-8, 1.0], [0.0, 1.0 - 0.9e-8]])  # across the margin, 2e-9 apart
    model = sysid.StateSpaceModel(A, np.ones((2, 1)), np.ones((1, 2)), dt=1.0)
    for fn in (sysid.hankel_singular_values, sysid.balanced_realization):
        with pytest.raises(sysid.NumericalError, match="too close"):
            fn(model)


def test_non_minimal_stable_part_cannot_be_balanced() -> None:
    cont = sysid.ContinuousStateSpace(np.diag([-1.0, -2.0, 0.5]), [[1.0], [0.0], [1.0]],
                                      [[1.0, 1.0, 1.0]])
    np.testing.assert_allclose(sysid.hankel_singular_values(cont)[[0, 2]], [np.inf, 0.0],
                               atol=1e-12)
    with pytest.raises(sysid.DataError, match="non-zero Hankel singular values"):
        sysid.balanced_realization(cont)
