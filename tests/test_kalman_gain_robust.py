"""The subspace estimators' Kalman gain on nearly noise-free records at orders above the
system's: covariances that defeat the Riccati doubling in the given state basis (R many orders
below Q, spurious modes), solved in a scaled basis and refined by Newton's iteration. Oracle:
SciPy's generalised-Schur solver on the same covariances."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy import linalg, signal

import sysid


def _record(seed: int, noise: float) -> sysid.IOData:
    """A 4th-order system (a lightly damped pair at 0.97, two real poles), band-limited input,
    output noise ``noise`` times the output's standard deviation."""
    rng = np.random.default_rng(seed)
    th = np.pi * rng.uniform(0.02, 0.3)
    a = np.zeros((4, 4))
    a[:2, :2] = 0.97 * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    a[2, 2], a[3, 3] = rng.uniform(0.3, 0.9, 2)
    true = sysid.StateSpaceModel(a, rng.standard_normal((4, 1)), rng.standard_normal((1, 4)))
    u = signal.lfilter(*signal.butter(4, 0.4), rng.standard_normal(4000))
    y = true.simulate(u)
    return sysid.IOData(u, y + noise * y.std() * rng.standard_normal(y.shape))


@pytest.mark.parametrize(("seed", "order"), [(7, 7), (15, 5), (2, 7)])
def test_overordered_cva_on_a_nearly_noise_free_record_gets_the_stabilising_gain(seed, order):
    data = _record(seed, 1e-9)
    est = sysid.SubspaceEstimator(data, 10, method="cva")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # spurious unstable modes: StabilityWarning
        m = est.fit(order)  # RiccatiError before (the doubling's A - K C unstable)
        bare = est.fit(order, kalman=False)
    A, C = bare.A, bare.C
    Q, R, S = (bare.info[k] for k in "QRS")

    def residual(P, K):  # of the Riccati equation, relative
        rhs = A @ P @ A.T + Q - K @ (A @ P @ C.T + S).T
        return np.abs(rhs - P).max() / max(np.abs(P).max(), np.abs(Q).max())

    K, P, _ = sysid._sysid.kalman_gain(A, C, Q, R, S)
    assert np.max(np.abs(np.linalg.eigvals(m.A - m.K @ m.C))) < 1
    assert np.linalg.norm(m.K - K) <= 1e-6 * np.linalg.norm(K)
    assert residual(P, K) < 1e-9
    assert m.info["kalman_regularization"] in (0.0, 1e-12, 1e-10, 1e-8, 1e-6)
    # the same gain as SciPy's where SciPy's solution satisfies the equation as closely
    P_ref = linalg.solve_discrete_are(A.T, C.T, Q, R, s=S)
    K_ref = (A @ P_ref @ C.T + S) @ np.linalg.inv(C @ P_ref @ C.T + R)
    if residual(P_ref, K_ref) < 1e-9:
        assert np.linalg.norm(K - K_ref) <= 1e-5 * np.linalg.norm(K_ref)
    else:  # the oracle lost accuracy (seed 15: 9e-7); ours is the better solution
        assert residual(P, K) < residual(P_ref, K_ref)


@pytest.mark.parametrize("order", [19, 20])
def test_a_riccati_equation_whose_newton_iteration_stalls_still_gets_its_gain(order):
    # MOESP of 19 and 20 states on the robot arm's last 800 samples (a real record): modes at
    # 1.003-1.06 and a nearly noise-free output; the doubling reached a relative residual of
    # 3e-7 and Newton's iteration stalled at 3e-10 to 5e-9 (its Stein solves' floor), so
    # `sysid.moesp(data, 19)` raised RiccatiError. Oracle: SciPy's Schur solver (6e-12 here).
    d = sysid.datasets.load_robot_arm()
    data = sysid.IOData(u=d.u[-800:], y=d.y[-800:])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # unstable modes: StabilityWarning
        m = sysid.moesp(data, order=order)
        bare = sysid.moesp(data, order=order, kalman=False)
    A, C = bare.A, bare.C
    Q, R, S = (bare.info[k] for k in "QRS")
    assert 0.0 <= m.info["kalman_residual"] <= 1e-6
    K, P, _ = sysid._sysid.kalman_gain(A, C, Q, R, S)
    assert np.max(np.abs(np.linalg.eigvals(A - K @ C))) < 1
    P_ref = linalg.solve_discrete_are(A.T, C.T, Q, R, s=S)
    K_ref = (A @ P_ref @ C.T + S) @ np.linalg.inv(C @ P_ref @ C.T + R)
    assert np.linalg.norm(K - K_ref) <= 1e-4 * np.linalg.norm(K_ref)
    assert np.linalg.norm(m.K - K) <= 1e-6 * np.linalg.norm(K)  # the model carries that gain


def test_schur_gain_matches_the_core_where_both_solve():
    from sysid.subspace.kalman import schur_gain

    rng = np.random.default_rng(3)
    A = np.diag([0.9, -0.5, 0.3]) + 0.05 * rng.standard_normal((3, 3))
    C = rng.standard_normal((2, 3))
    W = rng.standard_normal((5, 5))
    J = W @ W.T / 5  # joint covariance of (w, v), positive definite
    Q, S, R = J[:3, :3], J[:3, 3:], J[3:, 3:]
    K, P, innov = sysid._sysid.kalman_gain(A, C, Q, R, S)
    out = schur_gain({"A": A, "C": C, "Q": Q, "R": R, "S": S})
    assert out is not None and out["kalman_residual"] < 1e-10
    assert np.allclose(out["K"], K, rtol=1e-8, atol=1e-10)
    assert np.allclose(out["noise_cov"], innov, rtol=1e-8)
    # an unstable mode the output cannot see: no stabilising solution, None (not a wrong gain)
    A2, C2 = np.diag([1.5, 0.5]), np.array([[0.0, 1.0]])
    assert schur_gain({"A": A2, "C": C2, "Q": np.eye(2), "R": np.eye(1),
                       "S": np.zeros((2, 1))}) is None


def test_a_core_riccati_failure_falls_back_to_the_schur_solver(monkeypatch):
    # the core refuses where SciPy's Schur solver still solves the equation accurately (DaISy-
    # style gas furnace record, n4sid order 7: the core's Newton start had an indefinite
    # innovation covariance, SciPy reached a relative residual of 6e-8); emulated here by a
    # core that always refuses, on a small simulated record
    data = _record(1, 0.05)
    est = sysid.SubspaceEstimator(data, 10, method="n4sid")
    ref = est.fit(4)
    real = est._subspace

    class Refusing:
        def __init__(self, sub):
            self.sub = sub

        def fit(self, n, ft, kalman, stable, *rest):
            if kalman:
                raise sysid.RiccatiError("no stabilising solution (emulated)")
            return self.sub.fit(n, ft, kalman, stable, *rest)

        def __getattr__(self, name):
            return getattr(self.sub, name)

    monkeypatch.setattr(est, "_subspace", lambda method=None: Refusing(real(method)))
    m = est.fit(4)
    assert m.info["kalman_solver"] == "scipy.linalg.solve_discrete_are"
    assert np.allclose(m.K, ref.K, rtol=1e-6, atol=1e-9)
    assert np.max(np.abs(np.linalg.eigvals(m.A - m.K @ m.C))) < 1
    assert ref.info["kalman_solver"].startswith("doubling")


def test_the_python_kalman_gain_falls_back_to_the_schur_solver(monkeypatch):
    # one helper for Python code that needs a stabilising gain (ssregest's noise model too):
    # the core's solvers first, SciPy's Schur solver where they refuse, the core's error
    # where neither solves the equation accurately
    from sysid.subspace import kalman

    A, C = np.array([[0.9, 0.2], [0.0, 0.5]]), np.array([[1.0, 0.0]])
    Q, R, S = np.eye(2), np.eye(1), np.zeros((2, 1))
    K_core, innov_core = kalman.kalman_gain(A, C, Q, R, S)

    def refuses(*a):
        raise sysid.RiccatiError("no stabilising solution (emulated)")

    monkeypatch.setattr(sysid._sysid, "kalman_gain", refuses)
    K, innov = kalman.kalman_gain(A, C, Q, R, S)
    assert np.allclose(K, K_core, rtol=1e-8) and np.allclose(innov, innov_core, rtol=1e-8)
    with pytest.raises(sysid.RiccatiError, match="emulated"):  # unstable, unobservable mode
        kalman.kalman_gain(np.diag([1.5, 0.5]), np.array([[0.0, 1.0]]), Q, R, S)
