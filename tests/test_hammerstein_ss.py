"""MIMO Hammerstein-Wiener models with a state-space linear block (``sysid.nlhw_ss``): known
2 x 2 Hammerstein and Wiener systems recovered from noise-free data, starting from the linear
n4sid fit; protocol, saving and errors."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid

A = np.array([[1.3, -0.4], [1.0, 0.0]])          # poles 0.8 and 0.5
B = np.array([[1.0, 0.5], [0.2, -0.7]])
C = np.array([[0.6, 0.3], [-0.4, 0.9]])


def _simulate(u, f_in, g_out, x0=(0.0, 0.0)):
    x = np.array(x0, float)
    y = np.zeros((u.shape[0], 2))
    for t in range(u.shape[0]):
        y[t] = g_out(C @ x)
        x = A @ x + B @ f_in(u[t])
    return y


def _inputs(n=800, seed=3):
    return np.random.default_rng(seed).uniform(-1, 1, (n, 2))


def _poles(m):
    return np.sort(m.poles().real)


def test_hammerstein_2x2_saturation_and_cubic_recovered():
    u = _inputs()

    def f(v):
        return np.array([np.clip(v[0], -0.5, 0.6), v[1] + 0.3 * v[1] ** 2 - 0.2 * v[1] ** 3])

    y = _simulate(u, f, lambda v: v)
    m = sysid.nlhw_ss(sysid.IOData(u, y, 1.0), 2,
                      input_nl=[sysid.Saturation(), sysid.PolynomialNonlinearity(3)],
                      output_nl=None)
    np.testing.assert_allclose(_poles(m), [0.5, 0.8], atol=1e-6)
    np.testing.assert_allclose(m.input_nls[0].params, [-0.5, 0.6], atol=1e-6)
    np.testing.assert_allclose(m.input_nls[1].params, [0.3, -0.2], atol=1e-6)
    np.testing.assert_allclose(m.simulate(u), y, atol=1e-6)
    assert "Hammerstein" in repr(m) and m.info["iterations"] > 0


def test_wiener_2x2_polynomial_and_saturation_recovered():
    u = _inputs(seed=4)

    def g(v):
        return np.array([v[0] + 0.4 * v[0] ** 2, np.clip(v[1], -0.5, 0.45)])

    y = _simulate(u, lambda v: v, g)
    m = sysid.nlhw_ss(sysid.IOData(u, y, 1.0), 2,
                      output_nl=[sysid.PolynomialNonlinearity(2), sysid.Saturation()],
                      input_nl=None)
    np.testing.assert_allclose(_poles(m), [0.5, 0.8], atol=1e-6)
    np.testing.assert_allclose(m.output_nls[0].params, [0.4], atol=1e-6)
    np.testing.assert_allclose(m.output_nls[1].params, [-0.5, 0.45], atol=1e-6)
    assert "Wiener" in repr(m)


def test_protocol_saving_and_errors(tmp_path):
    u = _inputs(300, 5)
    y = _simulate(u, lambda v: np.clip(v, -0.5, 0.5), lambda v: v)
    d = sysid.IOData(u, y, 0.1)
    m = sysid.nlhw_ss(d, 2, input_nl=sysid.Saturation(), max_iter=50, output_nl=None)
    assert (m.ninputs, m.noutputs, m.order) == (2, 2, 2)
    assert m.freqresp([0.1]).shape[:2] == (2, 2) or m.freqresp([0.1]).size == 4
    assert sysid.compare(m, d).fit.min() > 99
    assert len(m.to_pandas()) == m.n_parameters
    assert "poles" in m.summary()
    path = tmp_path / "hw.json"
    sysid.save_model(m, path)
    m2 = sysid.load_model(path)
    np.testing.assert_allclose(m2.simulate(u), m.simulate(u), atol=1e-12)
    with pytest.raises(sysid.DataError, match="one nonlinearity per channel"):
        sysid.nlhw_ss(d, 2, input_nl=[sysid.Saturation()], output_nl=None)
    with pytest.raises(sysid.DataError, match="order"):
        sysid.nlhw_ss(d, 0)
    with pytest.raises(sysid.DataError, match="UserFunction"):
        sysid.nlhw_ss(d, 2, output_nl=sysid.UserFunction(np.tanh), input_nl=None)
    with pytest.raises(sysid.DataError, match="shape"):
        m.simulate(np.zeros((10, 3)))


def test_progress_is_the_shared_observer():
    u = _inputs(400, 7)
    y = _simulate(u, lambda v: np.clip(v, -0.5, 0.6), lambda v: v)
    calls = []
    m = sysid.nlhw_ss(sysid.IOData(u, y, 1.0), 2, input_nl=sysid.Saturation(),
                      progress=lambda *a: calls.append(a), output_nl=None)
    cost = m.info["cost"]
    assert len(cost) == m.info["iterations"] + 1 and cost[-1] < cost[0]
    # the chosen search's calls: the last run of iterations 1..k with the costs of info
    tail = calls[-m.info["iterations"]:]
    if [c[1] for c in tail] != cost[1:]:   # an earlier start won: find its run
        starts = [i for i, c in enumerate(calls) if c[0] == 1] + [len(calls)]
        runs = [calls[a:b] for a, b in zip(starts, starts[1:])]
        tail = next(r for r in runs if [c[1] for c in r] == cost[1:])
    assert [c[0] for c in tail] == list(range(1, m.info["iterations"] + 1))
    stopped = sysid.nlhw_ss(sysid.IOData(u, y, 1.0), 2, input_nl=sysid.Saturation(),
                            progress=lambda *a: False, output_nl=None)
    assert stopped.info["stop"] == "cancelled" and stopped.info["iterations"] == 1


def test_given_linear_start():
    # the true linear block as the start: the saturation is recovered from it; a start of
    # the wrong size or an unstable one is refused
    u = _inputs(seed=6)
    y = _simulate(u, lambda v: np.clip(v, -0.5, 0.6), lambda v: v)
    d = sysid.IOData(u, y, 1.0)
    true = sysid.StateSpaceModel(A, B, C, dt=1.0)
    m = sysid.nlhw_ss(d, 2, input_nl=sysid.Saturation(), linear=true, progress=False,
                      output_nl=None)
    np.testing.assert_allclose(m.simulate(u), y, atol=1e-6)
    # theta0: two saturations' bounds, then the start's A (the given one, not n4sid's)
    np.testing.assert_array_equal(m.info["theta0"][4:8], A.ravel())
    with pytest.raises(sysid.DataError, match="linear must be"):
        sysid.nlhw_ss(d, 3, linear=true)
    with pytest.raises(sysid.DataError, match="unstable"):
        sysid.nlhw_ss(d, 2, linear=sysid.StateSpaceModel(2 * A, B, C, dt=1.0))


def test_nlhw_ss_fits_about_the_operating_point(tmp_path):
    # The MIMO form keeps per-channel means the same way (nlhw's test has the reason).
    rng = np.random.default_rng(5)
    u = 5.0 + np.repeat(rng.uniform(-1, 1, (150, 1)), 8, axis=0)
    x = np.zeros(u.shape[0])
    for t in range(1, u.shape[0]):
        x[t] = 0.9 * x[t - 1] + 0.1 * u[t - 1, 0]
    y = np.column_stack([np.tanh(x - 5.0) + 3.0, 2.0 * x]) + 1e-3 * rng.standard_normal(
        (u.shape[0], 2))
    m = sysid.nlhw_ss(sysid.IOData(u, y, 1.0), 1, input_nl=sysid.SigmoidNetwork(2),
                      output_nl=sysid.SigmoidNetwork(2), progress=False, max_iter=400)
    np.testing.assert_allclose(m.u_offset, u.mean(0))
    # the outputs' levels start at their means and are estimated with the rest
    assert m.info["offsets"]["y_estimated"] and m.n_parameters == m.theta.size + 2
    np.testing.assert_allclose(m.y_offset, m.info["offsets"]["y"])
    fit = 100 * (1 - np.linalg.norm(y - m.simulate(u), axis=0)
                 / np.linalg.norm(y - y.mean(0), axis=0))
    assert np.all(fit > 90), fit
    sysid.save_model(m, tmp_path / "hwss.json")
    np.testing.assert_allclose(sysid.load_model(tmp_path / "hwss.json").simulate(u),
                               m.simulate(u), rtol=0, atol=1e-12)


def test_a_capped_nlhw_ss_search_warns():
    # The MIMO search says when it stopped at its cap still lowering the cost, and stops at
    # statistical convergence otherwise.
    rng = np.random.default_rng(14)
    u = rng.uniform(-1, 1, (2000, 1))
    x = np.zeros(u.shape[0])
    for t in range(1, u.shape[0]):
        x[t] = 0.8 * x[t - 1] + 0.5 * np.clip(u[t - 1, 0], -0.4, 0.6)
    y = x[:, None] + 0.02 * rng.standard_normal((u.shape[0], 1))
    d = sysid.IOData(u, y, 1.0)
    with pytest.warns(sysid.IterationLimitWarning, match="nlhw_ss search stopped at max_iter=2"):
        sysid.nlhw_ss(d, 1, input_nl=sysid.Saturation(), max_iter=2, progress=False, output_nl=None)
    m = sysid.nlhw_ss(d, 1, input_nl=sysid.Saturation(), progress=False, output_nl=None)
    assert m.info["stop"] == "statistical convergence"
    np.testing.assert_allclose(m.input_nls[0].params, [-0.4, 0.6], atol=0.02)


def test_nlhw_ss_offset_and_constant_input_are_named():
    # With nonlinearities whose levels are in the data's units the record is not centred;
    # the offset check then speaks (it was silenced with the start's other warnings), and a
    # constant input is named by its own value (it read 0 after centring, and blamed the
    # subspace start).
    rng = np.random.default_rng(15)
    u = rng.uniform(-1, 1, (600, 1))
    x = np.zeros(600)
    for t in range(1, 600):
        x[t] = 0.8 * x[t - 1] + 0.5 * np.clip(u[t - 1, 0], -0.4, 0.6)
    y = 97.0 + x[:, None] + 0.01 * rng.standard_normal((600, 1))
    with pytest.warns(sysid.OffsetWarning, match="offset"):
        sysid.nlhw_ss(sysid.IOData(u, y, 1.0), 1, input_nl=sysid.Saturation(),
                      max_iter=400, progress=False, output_nl=None, offsets=False)
    # offsets="auto" fits it both ways (levels in the data's units, a record off zero) and
    # keeps the fit about the means, which has the constant the other lacks: no warning due
    with warnings.catch_warnings():
        warnings.simplefilter("error", sysid.OffsetWarning)
        m = sysid.nlhw_ss(sysid.IOData(u, y, 1.0), 1, input_nl=sysid.Saturation(),
                          max_iter=400, progress=False, output_nl=None)
    assert m.info["offsets"]["removed"] and "with kept" in m.info["offsets"]["auto"]
    with pytest.raises(sysid.DataError, match="u0 is 3 in every sample: nlhw_ss"):
        sysid.nlhw_ss(sysid.IOData(np.full((600, 1), 3.0), y, 1.0), 1,
                      input_nl=sysid.SigmoidNetwork(2), progress=False, output_nl=None)


def test_an_unstable_subspace_start_is_stabilised_not_refused():
    # issue 26 (a default path that returns a model): nlhw_ss(pH, 2) raised "the linear
    # start (n4sid, or linear=) is unstable" (n4sid's order-2 model has a pole at 1.005 on
    # the centred record); it now starts from the same subspace fit with a stable A
    d = sysid.datasets.load_ph()
    train = sysid.IOData(d.u[:1200], d.y[:1200], d.dt)
    m = sysid.nlhw_ss(train, 2, output_nl=sysid.SigmoidNetwork(3), input_nl=None)
    assert "stable A enforced" in m.info["linear_start"]
    assert np.max(np.abs(np.linalg.eigvals(m.A))) < 1
    start = m.info["cost"][0]
    assert m.info["cost"][-1] <= start and np.isfinite(sysid.compare(train, m).fit).all()


def test_compare_fits_the_linear_blocks_state_as_of_a_linear_model():
    # compare ran Hammerstein-Wiener models from rest while it fitted a linear model's
    # initial state (the same for both: the Rust simulation from a given state)
    sat = sysid.Saturation()
    sat.params = np.array([-0.8, 0.8])
    m = sysid.HammersteinWienerSSModel([sat], [sysid.Nonlinearity(), sysid.Nonlinearity()],
                                       [[0.9, 0.2], [-0.2, 0.9]], [[0.0], [1.0]],
                                       [[1.0, 0.0], [0.5, 1.0]], dt=1.0)
    u = np.random.default_rng(2).standard_normal((300, 1))
    np.testing.assert_allclose(m.simulate(u, x0=[0.0, 0.0]), m.simulate(u), atol=0)
    y = m.simulate(u, x0=[4.0, -3.0])
    lin = m.linear()  # the outputs are the linear block's: its free response adds
    np.testing.assert_allclose(y - m.simulate(u), lin.simulate(np.zeros_like(u), x0=[4.0, -3.0]),
                               atol=1e-12)
    data = sysid.IOData(u, y, 1.0)
    np.testing.assert_allclose(sysid.estimate_x0(m, u, y), [4.0, -3.0], atol=1e-6)
    assert float(np.min(sysid.compare(data, m).fit)) > 99.999
    assert float(np.min(sysid.compare(data, m, x0="zero").fit)) < 90
    with pytest.raises(sysid.ShapeError, match="x0 has 3 entries but the linear block has 2"):
        m.simulate(u, x0=[1.0, 2.0, 3.0])


def test_experiments_starting_mid_response_are_fitted_with_their_initial_states():
    """Two noise-free 2 x 2 Hammerstein experiments (saturations, the poles 0.8 and 0.5)
    from different states: with ``initial_condition="estimate"`` the model and each
    experiment's output from its estimated state are exact; from rest they are not."""
    states = [(3.0, -2.0), (-1.5, 4.0)]
    us = [_inputs(400, seed=7 + e) for e in range(2)]
    ys = [_simulate(u, lambda v: np.clip(v, -0.5, 0.5), lambda v: v, x0)
          for u, x0 in zip(us, states)]
    d = sysid.IOData(us, ys, 1.0)
    m = sysid.nlhw_ss(d, 2, input_nl=sysid.Saturation(), output_nl=None,
                      initial_condition="estimate")
    assert m.info["initial_condition"] == "estimate" and len(m.info["initial_state"]) == 2
    np.testing.assert_allclose(_poles(m), [0.5, 0.8], rtol=1e-8)
    for f in m.input_nls:
        np.testing.assert_allclose(f.params, [-0.5, 0.5], rtol=1e-8)
    for u, y, x0 in zip(us, ys, m.info["initial_state"]):
        np.testing.assert_allclose(m.simulate(u, x0), y, rtol=1e-8, atol=1e-8 * np.abs(y).max())
    z = sysid.nlhw_ss(d, 2, input_nl=sysid.Saturation(), output_nl=None)
    assert z.info["initial_condition"] == "zero"
    assert all(not np.any(x) for x in z.info["initial_state"])
    assert max(np.max(np.abs(f.params - [-0.5, 0.5])) for f in z.input_nls) > 1e-4


@pytest.mark.parametrize("bad", ["est", "auto", 1])
def test_a_bad_initial_condition_is_a_data_error(bad):
    u = _inputs(200)
    y = _simulate(u, lambda v: v, lambda v: v)
    with pytest.raises(sysid.DataError, match="initial_condition"):
        sysid.nlhw_ss(sysid.IOData(u, y, 1.0), 2, input_nl=None, output_nl=None,
                      initial_condition=bad)
