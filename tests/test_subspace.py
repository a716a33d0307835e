"""The subspace engine against systems whose answer is known (issue 2's 'done means')."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid
from sysid import _sysid

from conftest import markov, match_poles, random_system, simulate

METHODS = ["moesp", "n4sid", "cva", "ordinary-moesp", "pi-moesp"]


@pytest.mark.parametrize("seed", range(16))
def test_noise_free_random_mimo_systems_are_recovered(seed):
    rng = np.random.default_rng(seed)
    n = 1 + seed % 10
    m = 1 + seed % 4
    l = 1 + (seed // 4) % 4
    a, b, c, d = random_system(n, m, l, rng)
    u = rng.standard_normal((1500, m))
    y = simulate(a, b, c, d, u)
    horizon = -(-(n + 1) // min(l, m)) + 2  # PI-MOESP needs p m > n past inputs
    est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), horizon=horizon)
    for method in METHODS:
        assert est.singular_values_for(method).size > 0
        model = est.fit("auto", method=method, kalman=False, feedthrough=True)  # d != 0
        assert model.nstates == n, f"{method}: order {model.nstates} != {n}"
        h_true = markov(a, b, c, d, 40)
        h_est = model.markov(40)
        assert np.max(np.abs(h_est - h_true)) < 1e-8 * np.max(np.abs(h_true)), method
        poles_err = match_poles(model.poles(), np.linalg.eigvals(a))
        assert poles_err < 1e-8, f"{method}: pole error {poles_err:.2e}"


def test_seed_slides_second_order_system_shows_two_dominant_singular_values():
    # seed 000, slides 24-26: order-2 system, 500 samples of white noise, i = 10, j = 490
    rng = np.random.default_rng(0)
    a = np.array([[1.5, -0.7], [1.0, 0.0]])
    b = np.array([[1.0], [0.0]])
    c = np.array([[1.0, 0.5]])
    d = np.zeros((1, 1))
    u = rng.standard_normal((509, 1))  # j = N - 2i + 1 = 490 columns
    y = simulate(a, b, c, d, u)
    est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), horizon=10, method="ordinary-moesp")
    assert est.factor.n_columns == 490
    sv = est.singular_values
    assert sv.size == 10
    assert sv[1] / sv[2] > 1e10  # two dominant values, the rest round-off
    assert est.auto_order == 2
    # with measurement noise v ~ (0, 0.01), slide 38: still two dominant values
    yv = y + 0.1 * rng.standard_normal(y.shape)
    sv = sysid.SubspaceEstimator(sysid.IOData(u=u, y=yv), horizon=10).singular_values
    assert sv[1] / sv[2] > 5 * sv[2] / sv[-1]


def _first_order_pole(method, seed, N, sw, sv):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((N, 1))
    w = sw * rng.standard_normal((N, 1))
    v = sv * rng.standard_normal((N, 1))
    y = simulate(np.array([[0.7]]), np.eye(1), np.eye(1), np.zeros((1, 1)), u, w=w, v=v)
    est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), horizon=5, method=method)
    return est.fit(1, kalman=False).poles()[0].real


def test_seed_slides_process_noise_biases_ordinary_moesp_but_not_po_moesp():
    # seed 000, slides 44-49: A = 0.7, B = 1, C = 1, D = 0. Monte Carlo over fixed seeds; the
    # bound is statistical: a consistent estimator's mean lies within 4 standard errors of the
    # truth (probability of a false failure ~ 6e-5), a biased one outside it.
    runs, N = 40, 2000
    po = np.array([_first_order_pole("moesp", s, N, 1.0, 0.5) for s in range(runs)])
    om = np.array([_first_order_pole("ordinary-moesp", s, N, 1.0, 0.5) for s in range(runs)])
    se_po = po.std(ddof=1) / np.sqrt(runs)
    se_om = om.std(ddof=1) / np.sqrt(runs)
    assert abs(po.mean() - 0.7) < 4 * se_po + 1e-3
    assert abs(om.mean() - 0.7) > 4 * se_om
    # without process noise ordinary MOESP is consistent too (slides 34-41)
    om0 = np.array([_first_order_pole("ordinary-moesp", s, N, 0.0, 0.5) for s in range(runs)])
    assert abs(om0.mean() - 0.7) < 4 * om0.std(ddof=1) / np.sqrt(runs) + 1e-3


@pytest.mark.parametrize("method", ["moesp", "n4sid", "cva"])
def test_pole_errors_shrink_as_n_grows_with_process_and_measurement_noise(method):
    a = np.array([[0.6, 0.5, 0.0], [-0.5, 0.6, 0.0], [0.0, 0.0, 0.85]])
    b = np.array([[1.0], [0.0], [0.7]])
    c = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, -0.5]])
    d = np.zeros((2, 1))
    k = np.array([[0.3, 0.1], [0.0, 0.2], [0.1, 0.0]])
    true = np.linalg.eigvals(a)
    errors = []
    for N in (1_000, 10_000, 100_000):
        errs = []
        for seed in range(4):
            rng = np.random.default_rng(100 + seed)
            u = rng.standard_normal((N, 1))
            e = 0.5 * rng.standard_normal((N, 2))
            y = simulate(a, b, c, d, u, w=e @ k.T, v=e)
            model = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), horizon=6, method=method).fit(
                3, kalman=False
            )
            errs.append(match_poles(model.poles(), true))
        errors.append(float(np.mean(errs)))
    assert errors[1] < errors[0] and errors[2] < errors[1], errors
    # root-N consistency: two decades of N should cut the error by well over a factor 3
    assert errors[2] < errors[0] / 3, errors


def test_innovation_model_is_recovered_with_kalman_gain():
    rng = np.random.default_rng(5)
    a = np.array([[0.7, 0.3], [-0.3, 0.7]])
    b = np.array([[1.0], [0.5]])
    c = np.array([[1.0, 0.0]])
    d = np.zeros((1, 1))
    k = np.array([[0.5], [0.2]])
    N = 200_000
    u = rng.standard_normal((N, 1))
    e = 0.3 * rng.standard_normal((N, 1))
    y = simulate(a, b, c, d, u, w=e @ k.T, v=e)
    model = sysid.n4sid(sysid.IOData(u=u, y=y), order=2, horizon=8)
    true_pred = np.linalg.eigvals(a - k @ c)
    assert match_poles(np.linalg.eigvals(model.A - model.K @ model.C), true_pred) < 0.02
    assert abs(model.noise_cov[0, 0] - 0.09) < 0.005
    # the one-step predictor's errors are the innovations
    yh = model.predict(u[:5000], y[:5000])
    assert abs(np.var((y - 0)[:5000] - yh) - 0.09) < 0.01


def test_stability_enforcement_is_opt_in_and_recorded():
    rng = np.random.default_rng(2)
    # a short noisy record of an almost integrating system: the LS estimate can be unstable
    u = rng.standard_normal((120, 1))
    y = simulate(np.array([[0.999]]), np.eye(1), np.eye(1), np.zeros((1, 1)), u)
    y = y + 2.0 * rng.standard_normal(y.shape)
    data = sysid.IOData(u=u, y=y)
    for seed_h in (3, 4, 5, 6):
        est = sysid.SubspaceEstimator(data, horizon=seed_h)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            free = est.fit(1, kalman=False)
        # an unstable result is said (issue 26), a stable one is not
        said = [w for w in caught if issubclass(w.category, sysid.StabilityWarning)]
        assert bool(said) == (not free.is_stable())
        forced = est.fit(1, kalman=False, stable=True)
        assert forced.is_stable()
        assert forced.info["stable_enforced"] is True
        if free.is_stable():
            np.testing.assert_allclose(forced.A, free.A)


def test_feedthrough_false_forces_zero_d_and_x0_estimate_matches():
    rng = np.random.default_rng(9)
    a, b, c, d = random_system(3, 2, 2, rng, feedthrough=False)
    u = rng.standard_normal((800, 2))
    x0 = np.array([2.0, -1.0, 0.5])
    y = simulate(a, b, c, d, u, x0=x0)
    data = sysid.IOData(u=u, y=y)
    model = sysid.SubspaceEstimator(data, horizon=5).fit(3, feedthrough=False, x0=True)
    assert np.all(model.D == 0)
    np.testing.assert_allclose(model.simulate(u, x0="model"), y, atol=1e-8 * np.abs(y).max())


def test_x0_estimate_over_several_experiments():
    # one B, D for all experiments and an initial state per experiment (MATLAB's n4sid with
    # multi-experiment data and InitialState 'estimate'); noise-free: exact
    rng = np.random.default_rng(10)
    a, b, c, d = random_system(3, 2, 2, rng)
    us = [rng.standard_normal((400, 2)), rng.standard_normal((300, 2))]
    x0s = [np.array([2.0, -1.0, 0.5]), np.array([-1.0, 0.0, 3.0])]
    ys = [simulate(a, b, c, d, u, x0=x) for u, x in zip(us, x0s)]
    model = sysid.SubspaceEstimator(sysid.IOData(u=us, y=ys), horizon=5).fit(
        3, feedthrough=True, x0=True)
    assert model.x0 is None
    got = model.info["x0_experiments"]
    assert len(got) == 2
    for u, y, x in zip(us, ys, got):
        np.testing.assert_allclose(model.simulate(u, x0=x), y, atol=1e-8 * np.abs(y).max())
    # the kernel: exact on one record and on two
    b1, d1, (x1,) = _sysid.estimate_bd_x0_records(a, c, us[:1], ys[:1], True)
    np.testing.assert_allclose(b1, b, atol=1e-9)
    np.testing.assert_allclose(x1, x0s[0], atol=1e-8)
    bb, dd, xx = _sysid.estimate_bd_x0_records(a, c, us, ys, True)
    np.testing.assert_allclose(bb, b, atol=1e-9)
    np.testing.assert_allclose(dd, d, atol=1e-9)
    for x, x_true in zip(xx, x0s):
        np.testing.assert_allclose(x, x_true, atol=1e-8)
    # with an input delay the delay-free fit's states are not the returned model's (these
    # records have none: the shifted fit warns of feedback, rightly)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        delayed = sysid.n4sid(sysid.IOData(u=us, y=ys), 3, feedthrough=True, x0=True,
                              input_delay=[1, 0])
    assert delayed.nstates == 4 and "x0_experiments" not in delayed.info
    assert len(delayed.info["delay_free"].info["x0_experiments"]) == 2
    with pytest.raises(ValueError, match="one of each per experiment"):
        _sysid.estimate_bd_x0_records(a, c, us, ys[:1], True)
    with pytest.raises(sysid.ShapeError, match="record 1"):
        _sysid.estimate_bd_x0_records(a, c, us, [ys[0], ys[1][:, :1]], True)


def test_separate_past_and_future_horizons():
    rng = np.random.default_rng(4)
    a, b, c, d = random_system(4, 1, 2, rng)
    u = rng.standard_normal((600, 1))
    y = simulate(a, b, c, d, u)
    est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), past=8, future=4)
    assert (est.past, est.future) == (8, 4)
    assert est.factor.l.shape == (12 * 3, 12 * 3)
    model = est.fit(4, kalman=False, feedthrough=True)  # random_system has a D
    np.testing.assert_allclose(model.markov(20), markov(a, b, c, d, 20), atol=1e-8)


def test_default_horizon_rule_is_used():
    rng = np.random.default_rng(0)
    u = rng.standard_normal((400, 2))
    y = simulate(*random_system(2, 2, 1, rng), u)
    est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y))
    assert est.past == est.future == sysid.default_horizon(400, 2, 1)


def test_multiple_experiments_identify_one_model():
    rng = np.random.default_rng(8)
    a, b, c, d = random_system(3, 1, 1, rng)
    us = [rng.standard_normal((300, 1)) for _ in range(3)]
    ys = [simulate(a, b, c, d, u) for u in us]
    est = sysid.SubspaceEstimator(sysid.IOData(u=us, y=ys), horizon=5)
    assert est.factor.n_experiments == 3
    assert est.factor.n_columns == 3 * (300 - 10 + 1)
    model = est.fit("auto", kalman=False, feedthrough=True)  # random_system has a D
    np.testing.assert_allclose(model.markov(20), markov(a, b, c, d, 20), atol=1e-8)


def test_output_only_data_gives_a_stochastic_model():
    rng = np.random.default_rng(12)
    a = np.array([[0.8, 0.4], [-0.4, 0.8]])
    c = np.array([[1.0, 0.0]])
    k = np.array([[0.6], [0.3]])
    N = 50_000
    e = rng.standard_normal((N, 1))
    y = simulate(a, np.zeros((2, 0)), c, np.zeros((1, 0)), np.zeros((N, 0)), w=e @ k.T, v=e)
    model = sysid.SubspaceEstimator(sysid.IOData(u=None, y=y), horizon=6).fit(2)
    assert model.ninputs == 0
    assert match_poles(model.poles(), np.linalg.eigvals(a)) < 0.05


def test_a_given_order_gets_a_horizon_that_allows_it():
    # 60 samples of 5 inputs and 3 outputs: the default horizon 2 allows 3 states, and
    # n4sid(data, 4) / ssest(data, 4) raised OrderError although the data support order 4
    rng = np.random.default_rng(8)
    A = np.diag([0.9, 0.7, -0.5, 0.3])
    true = sysid.StateSpaceModel(A, rng.standard_normal((4, 5)), rng.standard_normal((3, 4)))
    u = rng.standard_normal((60, 5))
    d = sysid.IOData(u, true.simulate(u))
    assert sysid.SubspaceEstimator(d).max_order == 3
    m = sysid.n4sid(d, 4)
    np.testing.assert_allclose(np.sort(m.poles().real), np.sort(np.diag(A)), atol=1e-6)
    assert sysid.ssest(d, 4).nstates == 4
    with pytest.raises(sysid.OrderError, match="at most 3 states"):
        sysid.n4sid(d, 4, horizon=2)  # a horizon given is kept


@pytest.mark.parametrize("seed", range(4))
def test_noise_free_systems_are_recovered_from_the_state_sequence(seed):
    rng = np.random.default_rng(100 + seed)
    n, m, l = 2 + seed, 1 + seed % 2, 1 + seed // 2
    a, b, c, d = random_system(n, m, l, rng)
    u = rng.standard_normal((800, m))
    data = sysid.IOData(u=u, y=simulate(a, b, c, d, u))
    est = sysid.SubspaceEstimator(data, horizon=n + 3, matrices="states")
    for method in ("moesp", "n4sid", "cva"):
        model = est.fit(n, method=method, kalman=False, feedthrough=True)
        h_true = markov(a, b, c, d, 40)
        assert np.max(np.abs(model.markov(40) - h_true)) < 1e-8 * np.max(np.abs(h_true))
        assert model.info["settings"]["matrices"] == "states"


def test_with_matrices_fits_what_an_estimator_built_with_them_fits():
    # identify's state-sequence candidates shallow-copied an estimator and set its matrices
    # from outside; SubspaceEstimator.with_matrices builds that estimator itself, sharing the
    # factor and SVDs, and leaves the original as it was
    rng = np.random.default_rng(7)
    a, b, c, d = random_system(3, 1, 1, rng)
    u = rng.standard_normal((600, 1))
    y = simulate(a, b, c, d, u) + 0.05 * rng.standard_normal((600, 1))
    data = sysid.IOData(u=u, y=y)
    est = sysid.SubspaceEstimator(data, horizon=6)
    states = est.with_matrices("states")
    built = sysid.SubspaceEstimator(data, horizon=6, matrices="states")
    assert states.factor is est.factor and est.matrices == "shift"
    for ft in (False, True):
        got = states.fit(3, method="n4sid", feedthrough=ft)
        want = built.fit(3, method="n4sid", feedthrough=ft)
        assert got.info["settings"]["matrices"] == "states"
        assert np.allclose(got.markov(30), want.markov(30), rtol=1e-10, atol=1e-12)
        assert np.allclose(np.sort_complex(got.poles()), np.sort_complex(want.poles()))
    shift = est.fit(3, method="n4sid")
    assert shift.info["settings"]["matrices"] == "shift"
    assert np.allclose(shift.markov(30), sysid.SubspaceEstimator(data, horizon=6).fit(
        3, method="n4sid").markov(30))
    with pytest.raises(sysid.DataError, match="matrices"):
        est.with_matrices("diagonal")


def test_every_way_to_build_an_estimator_sets_the_same_state():
    # the constructor, from_factor and with_matrices set their attributes through one
    # initialiser: an attribute added to one and forgotten in another broke the copy's fits
    rng = np.random.default_rng(8)
    u = rng.standard_normal((400, 1))
    y = simulate(*random_system(2, 1, 1, rng), u)
    est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), horizon=5)
    est.fit(2)  # fills the shared caches
    twins = [est.with_matrices("states"),
             sysid.SubspaceEstimator.from_factor(est.factor, matrices="auto"),
             sysid.SubspaceEstimator.from_factor(est.factor).with_matrices("states")]
    for other in twins:
        assert set(vars(other)) == set(vars(est))
        assert (other.past, other.future) == (est.past, est.future)
    copy = twins[0]
    assert copy._svd is est._svd and copy.scaled_factor is est.scaled_factor
    assert twins[1]._svd is not est._svd  # a new estimator starts its own caches
    assert np.allclose(twins[1].fit(2).markov(20), sysid.SubspaceEstimator(
        sysid.IOData(u=u, y=y), horizon=5, matrices="auto").fit(2).markov(20))


def test_the_state_sequence_keeps_a_slow_pole_inside_the_unit_circle():
    # a slow pole (0.99) under white output noise, fitted with more states than the system
    # has: the shift invariance of the observability matrix puts a pole outside the unit
    # circle on many records (issue 26: the evaporator's order-16 fits), the least squares
    # on the state sequence on none
    a = np.diag([0.99, 0.5])
    b, c = np.ones((2, 1)), np.array([[0.1, 1.0]])
    unstable = {"shift": 0, "states": 0, "auto": 0}
    for seed in range(20):
        rng = np.random.default_rng(seed)
        u = rng.standard_normal((1000, 1))
        y = simulate(a, b, c, np.zeros((1, 1)), u)
        data = sysid.IOData(u=u, y=y + 0.3 * y.std() * rng.standard_normal(y.shape))
        models = {}
        for matrices in unstable:
            est = sysid.SubspaceEstimator(data, horizon=10, matrices=matrices)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", sysid.StabilityWarning)
                models[matrices] = est.fit(6)
            unstable[matrices] += not models[matrices].is_stable()
        # "auto": the shift's estimate where it is stable, the states' where it is not
        want = models["shift"] if models["shift"].is_stable() else models["states"]
        np.testing.assert_allclose(models["auto"].A, want.A, rtol=1e-12, atol=1e-12)
    assert unstable["shift"] >= 3, unstable
    assert unstable["states"] == unstable["auto"] == 0, unstable


def test_matrices_is_checked_and_reaches_the_order_choice():
    rng = np.random.default_rng(3)
    u = rng.standard_normal((400, 1))
    data = sysid.IOData(u=u, y=simulate(np.array([[0.7]]), np.ones((1, 1)), np.ones((1, 1)),
                                        np.zeros((1, 1)), u))
    with pytest.raises(sysid.DataError, match='matrices must be "shift", "states" or "auto"'):
        sysid.SubspaceEstimator(data, horizon=4, matrices="gamma")
    est = sysid.SubspaceEstimator(data, horizon=4, matrices="states")
    seen = []
    real = sysid.SubspaceEstimator.__init__

    def spy(self, *args, **kwargs):
        seen.append(kwargs.get("matrices"))
        real(self, *args, **kwargs)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(sysid.SubspaceEstimator, "__init__", spy)
        model = est.fit("auto", feedthrough=False)
    assert seen and set(seen) == {"states"}  # every fold's estimator
    assert model.nstates == 1


def test_an_order_at_the_data_matrix_rank_says_why_it_cannot_be_fitted():
    """A tracking loop's record: a slow seven-sine reference, an operator's force (a filter
    of it plus coloured remnant) and a cursor integrated from that force (deterministic).
    The weighted data matrix has rank 22 (the force's 20 future rows and the cursor's two
    states); at order 22 the least-squares design of B has deficient rank, and the fit said
    "non-finite estimates; the data may be degenerate". Now the error names the cause and
    the order to take (a minimum-norm B was tried: it simulated nothing of the record)."""
    from scipy import signal

    rng = np.random.default_rng(1)
    dt, n_samples = 1 / 60, 2700
    t = np.arange(n_samples) * dt
    r = sum(np.sin(2 * np.pi * f * t + rng.uniform(0, 6)) / p
            for f, p in ((0.1, 2), (0.15, 3), (0.25, 5), (0.35, 7), (0.55, 11), (0.65, 13),
                         (0.85, 17)))
    r *= np.minimum(1.0, (t / 5) ** 2)
    force = (signal.lfilter([0.05], [1, -0.95], r)
             + signal.lfilter([0.02], [1, -0.9], rng.standard_normal(n_samples)))
    cursor, speed = np.zeros(n_samples), 0.0
    for k in range(1, n_samples):
        speed += dt * (force[k - 1] - speed)
        cursor[k] = cursor[k - 1] + dt * speed
    d = sysid.IOData(u=r, y=np.c_[force, cursor], dt=dt)
    est = sysid.SubspaceEstimator(d)
    top = est.max_order
    sv = est.singular_values
    assert top == 22 and sv[top] < 1e-12 * sv[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # order 22 is more than the seven sines excite
        assert np.all(np.isfinite(est.fit(top - 1).B))
        with pytest.raises(sysid.errors.NumericalError,
                           match="does not determine B at order 22.*choose order 21"):
            est.fit(top)
