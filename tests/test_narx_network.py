"""nlarx with network nonlinearities: sigmoid network, wavelet network, tree partition."""

from __future__ import annotations

import numpy as np
import pytest
from _guides import assert_prints_shown, guide_text, run_blocks

import sysid
from sysid.errors import DataError, InsufficientDataError


def _truth_sigmoid() -> sysid.NetworkNARXModel:
    """y(t) = F(y(t-1), y(t-2), u(t-1), u(t-2)) with two sigmoid units."""
    net = {"type": "network", "kinds": ["sigmoid", "sigmoid"],
           "theta": [[0.8, -0.3, 1.5, 0.2, 0.1], [0.4, 0.3, -1.2, 1.1, -0.2]],
           "linear": [0.1, 0.4, -0.2, 0.7, 0.3, 0.9, -0.6]}
    return sysid.NetworkNARXModel([2], [2], [1], [net], [0.0] * 4, [1.0] * 4, dt=1.0)


def _wiener(n: int, seed: int) -> sysid.IOData:
    """A Wiener system: second-order linear block, then a saturating output."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-0.6, 0.6, n)
    x = np.zeros(n)
    for t in range(2, n):
        x[t] = 1.3 * x[t - 1] - 0.5 * x[t - 2] + 0.6 * u[t - 1] + 0.2 * u[t - 2]
    y = np.tanh(x) + 0.01 * rng.standard_normal(n)
    return sysid.IOData(u[:, None], y[:, None], 1.0)


def _fit(model, data) -> float:
    """Free-run fit (%) on data, from the measured initial outputs."""
    y = data.y
    ys = (model.simulate(data.u, x0=y[:2]) if hasattr(model, 'max_lag')
          else model.simulate(data.u))
    return float(100 * (1 - np.linalg.norm(ys[2:] - y[2:]) / np.linalg.norm(y[2:] - y[2:].mean())))


def test_sigmoid_network_recovered_from_noise_free_data_near_the_truth():
    truth = _truth_sigmoid()
    u = np.random.default_rng(1).uniform(-1, 1, (800, 1))
    y = truth.simulate(u)
    data = sysid.IOData(u, y, 1.0)
    start = sysid.NetworkNARXModel.from_dict(truth.to_dict())
    start.nonlinearities[0]["theta"] = start.nonlinearities[0]["theta"] + 0.05
    m = sysid.nlarx(data, 2, 2, 1, basis=start, max_iter=200)
    assert m.info["search"][0]["cost"] < 1e-22
    got, want = m.nonlinearities[0], truth.nonlinearities[0]
    np.testing.assert_allclose(got["theta"], want["theta"], atol=1e-8)
    np.testing.assert_allclose(got["linear"], want["linear"], atol=1e-8)
    uv = np.random.default_rng(2).uniform(-1, 1, (300, 1))
    np.testing.assert_allclose(m.simulate(uv), truth.simulate(uv), atol=1e-9)


def test_tree_partition_recovers_a_piecewise_affine_arx_system():
    rng = np.random.default_rng(3)
    n = 1500
    u = rng.uniform(-1, 1, n)
    y = np.zeros(n)

    def step(yp, up):
        return 0.5 * yp + up + 0.2 if yp <= 0.1 else -0.3 * yp + 0.5 * up - 0.1

    for t in range(1, n):
        y[t] = step(y[t - 1], u[t - 1])
    m = sysid.nlarx(sysid.IOData(u[:, None], y[:, None], 1.0), 1, 1, 1,
                    basis=sysid.TreePartition(8))
    assert m.n_units() == 2, m.info["tree"]
    uv = rng.uniform(-1, 1, 400)
    yv = np.zeros(400)
    for t in range(1, 400):
        yv[t] = step(yv[t - 1], uv[t - 1])
    np.testing.assert_allclose(m.simulate(uv[:, None])[:, 0], yv, atol=1e-9)
    # the local ARX models: a1 = -0.5, b1 = 1 below the switch, a1 = 0.3, b1 = 0.5 above
    lo, hi = m.linearize(at=[-0.5, 0.0]), m.linearize(at=[0.8, 0.0])
    np.testing.assert_allclose([lo.a[0][0][0], lo.b[0][0][0]], [-0.5, 1.0], atol=1e-8)
    np.testing.assert_allclose([hi.a[0][0][0], hi.b[0][0][0]], [0.3, 0.5], atol=1e-8)


@pytest.mark.parametrize("basis", [sysid.SigmoidNetwork(8), sysid.WaveletNetwork(8)])
def test_networks_beat_linear_arx_on_a_wiener_system(basis):
    est, val = _wiener(1500, 4), _wiener(800, 5)
    arx = sysid.arx(est, 2, 2, 1)
    m = sysid.nlarx(est, 2, 2, 1, basis=basis, max_iter=300, progress=False)
    lin, net = _fit(arx, val), _fit(m, val)
    assert net > lin + 5, (net, lin)
    assert net > 85, net


def test_simulation_focus_lowers_the_simulation_error_from_the_prediction_fit():
    est = _wiener(800, 6)
    kw = dict(basis=sysid.SigmoidNetwork(4), max_iter=300, progress=False)
    p = sysid.nlarx(est, 2, 2, 1, **kw)
    s = sysid.nlarx(est, 2, 2, 1, focus="simulation", **kw)
    r = s.info["refine"]
    assert r["history"][-1] <= r["history"][0]
    e = est.y[2:, 0]
    err = [np.sum((m.simulate(est.u, x0=est.y[:2])[2:, 0] - e) ** 2) for m in (p, s)]
    assert err[1] <= err[0] * (1 + 1e-12)
    assert err[1] == pytest.approx(2 * r["cost"], rel=1e-6)


def test_info_reports_iterations_cost_and_stop_reason():
    m = sysid.nlarx(_wiener(400, 7), 2, 2, 1, basis=sysid.SigmoidNetwork(3), max_iter=300,
                    progress=False)
    s = m.info["search"][0]
    assert s["iterations"] >= 1 and s["stop"] in ("cost tolerance", "step tolerance",
                                                   "gradient tolerance", "no further decrease",
                                                   "maximum iterations")
    assert all(b <= a for a, b in zip(s["history"], s["history"][1:]))
    assert "iterations" in m.summary()


def test_progress_callback_can_stop_the_search_and_a_cap_warns():
    calls = []

    def cb(it, cost, *rest):
        calls.append(cost)
        return it < 2

    m = sysid.nlarx(_wiener(400, 8), 2, 2, 1, basis=sysid.SigmoidNetwork(3), progress=cb)
    assert len(calls) == 2 and m.info["search"][0]["stop"] == "cancelled"
    with pytest.warns(sysid.IterationLimitWarning, match="standard deviations of the estimate"):
        capped = sysid.nlarx(_wiener(400, 8), 2, 2, 1, basis=sysid.SigmoidNetwork(3),
                             max_iter=1, progress=False)
    # how far the capped search stood from its minimum, in residual variances
    assert capped.info["search"][0]["remaining_decrease"] >= 0.125


def test_callback_exception_propagates():
    def cb(*a):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sysid.nlarx(_wiener(300, 9), 2, 2, 1, basis=sysid.SigmoidNetwork(2), progress=cb)


@pytest.mark.filterwarnings("ignore::sysid.IterationLimitWarning")
@pytest.mark.parametrize("basis", [sysid.SigmoidNetwork(3), sysid.WaveletNetwork(2, 1),
                                   sysid.TreePartition(4)])
@pytest.mark.parametrize("fmt", ["json", "npz"])
def test_save_load_round_trip(tmp_path, basis, fmt):
    rng = np.random.default_rng(10)
    u = rng.uniform(-1, 1, (500, 2))
    y = np.zeros((500, 2))
    for t in range(1, 500):
        y[t, 0] = 0.5 * y[t - 1, 0] + np.tanh(u[t - 1, 0] + u[t - 1, 1])
        y[t, 1] = 0.3 * y[t - 1, 1] + 0.2 * y[t - 1, 0] + u[t - 1, 1] ** 2
    data = sysid.IOData(u, y, 0.5, input_names=["a", "b"], output_names=["p", "q"])
    m = sysid.nlarx(data, [1, 1], [1, 1], [1, 1], basis=basis, max_iter=10, progress=False)
    path = tmp_path / f"m.{fmt}"
    sysid.save_model(m, path)
    back = sysid.load_model(path)
    assert type(back) is sysid.NetworkNARXModel and back.output_names == ["p", "q"]
    np.testing.assert_array_equal(back.simulate(u[:50]), m.simulate(u[:50]))
    np.testing.assert_array_equal(back.predict(u[:50], y[:50], 3), m.predict(u[:50], y[:50], 3))
    assert repr(back) == repr(m) and back.dt == 0.5


def test_prediction_horizon_one_is_the_one_step_predictor():
    truth = _truth_sigmoid()
    u = np.random.default_rng(11).uniform(-1, 1, (60, 1))
    y = truth.simulate(u) + 0.1
    p1 = truth.predict(u, y, 1)
    x = np.column_stack([y[1:-1, 0], y[:-2, 0], u[1:-1, 0], u[:-2, 0]])
    np.testing.assert_allclose(p1[2:, 0], truth.evaluate(x)[:, 0], atol=1e-14)
    np.testing.assert_allclose(truth.predict(u, y, 1000), truth.simulate(u, x0=y[:2]),
                               atol=1e-12)


def test_bad_input_is_refused_with_the_fix_named():
    data = _wiener(200, 12)
    with pytest.raises(InsufficientDataError, match="fewer units"):
        sysid.nlarx(data, 2, 2, 1, basis=sysid.SigmoidNetwork(60))
    with pytest.raises(DataError, match="focus"):
        sysid.nlarx(data, 2, 2, 1, basis=sysid.SigmoidNetwork(2), focus="sim")
    with pytest.raises(DataError, match="focus='simulation' needs a network"):
        sysid.nlarx(data, 2, 2, 1, basis=sysid.PolynomialBasis(2), focus="simulation")
    with pytest.raises(DataError, match="noise_terms"):
        sysid.nlarx(data, 2, 2, 1, basis=sysid.SigmoidNetwork(2), noise_terms=1)
    flat = sysid.IOData(np.ones((200, 1)), data.y, 1.0)
    with pytest.raises(DataError, match="constant"):
        sysid.nlarx(flat, 2, 2, 1, basis=sysid.WaveletNetwork(2))
    with pytest.raises(DataError, match="units"):
        sysid.WaveletNetwork(0)
    with pytest.raises(DataError, match="max_leaves"):
        sysid.TreePartition(0)
    with pytest.raises(DataError, match="orders"):
        sysid.nlarx(data, 1, 2, 1, basis=_truth_sigmoid())
    with pytest.raises(DataError, match="shape"):
        _truth_sigmoid().simulate(np.zeros((10, 2)))
    with pytest.raises(DataError, match="non-finite"):
        bad = sysid.IOData(np.where(np.arange(200)[:, None] == 50, np.nan, data.u), data.y, 1.0)
        sysid.nlarx(bad, 2, 2, 1, basis=sysid.SigmoidNetwork(2))


def test_linearize_at_the_truth_matches_its_derivative():
    truth = _truth_sigmoid()
    lin = truth.linearize(at=[0.2, -0.1, 0.3, 0.0])
    assert lin.noutputs == 1 and np.all(np.isfinite(truth.freqresp([0.1, 1.0])))
    assert truth.poles().size == 2 and truth.n_parameters == 17


def test_guide_section_runs_and_prints_what_it_shows(capsys):
    """The network section of docs/nonlinear.md runs and prints the numbers it shows: the
    network fits are local minima of a nonconvex search, and the rounding of the vector
    kernels differs between processors (AVX2 against AVX-512), so a fit may settle up to a
    few points away on another machine (seen: 88.3 against 90.8); the claims below hold
    on both."""
    section = guide_text("nonlinear.md", "Network nonlinearities")
    ns = run_blocks(section, "docs/nonlinear.md (network section)",
                    {"np": np, "sysid": sysid})
    assert_prints_shown(section, capsys.readouterr().out, atol=3.0, rtol=0.0)
    fits = ns["w_fits"]
    assert all(v > fits["arx(2,2,1)"] for k, v in fits.items() if "simulation" in k)
    ph = [v[1] for v in ns["ph_nets"].values()]
    assert all(v < 1.849 for v in ph)  # every network below the linear model's RMSE
    assert min(ph) < 1.364  # the best one below polynomial NARX's


def test_ctrl_c_stops_the_training_loop():
    """SIGINT during a long search (no progress callback) raises KeyboardInterrupt promptly:
    the search checks for signals after every iteration."""
    import os
    import signal
    import threading
    import time

    est = _wiener(20000, 13)
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    t0 = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            sysid.nlarx(est, 2, 2, 1, basis=sysid.SigmoidNetwork(20), max_iter=10000,
                        progress=False)
    finally:
        timer.cancel()
    assert time.perf_counter() - t0 < 60


def test_simulation_focus_reports_each_outputs_error_variance():
    # two outputs with different noise: each output's variance is its own free-run mean
    # squared error (it was their pool, the same number for both)
    rng = np.random.default_rng(31)
    u = rng.uniform(-1, 1, (600, 1))
    x = np.zeros(600)
    for t in range(1, 600):
        x[t] = 0.7 * x[t - 1] + np.tanh(2 * u[t - 1, 0])
    y = np.column_stack([x + 0.01 * rng.standard_normal(600),
                         0.5 * x + 0.3 * rng.standard_normal(600)])
    d = sysid.IOData(u, y, 1.0)
    m = sysid.nlarx(d, 1, 1, 1, basis=sysid.SigmoidNetwork(2), focus="simulation",
                    max_iter=50, progress=False)
    e = (y - m.simulate(u, x0=y[:1]))[1:]
    np.testing.assert_allclose(m.noise_variance, np.mean(e ** 2, axis=0), rtol=1e-9)
    assert m.noise_variance[1] > 20 * m.noise_variance[0]
