"""PNLSS: the clamped (bounded) extrapolation and the decoupled variant."""

import numpy as np
import pytest

import sysid
from sysid.errors import DataError, NumericalError


def _saturating(u):
    # x(t+1) = 0.7 x + tanh(1.5 u), y = x: bounded for any input (|y| <= 1 / 0.3)
    x = np.zeros(len(u) + 1)
    for t in range(len(u)):
        x[t + 1] = 0.7 * x[t] + np.tanh(1.5 * u[t])
    return x[:-1]


def _record(seed, n=1500, scale=1.0):
    u = scale * np.random.default_rng(seed).uniform(-1, 1, n)
    return sysid.IOData(u, _saturating(u), 1.0)


def test_clamp_leaves_the_fit_unchanged_and_bounds_extrapolation():
    d = _record(0)
    m = sysid.pnlss(d, 1, degree=3, terms="full", output_terms="none", tol=1e-6,
                    progress=False)
    assert m.clamp is not None and m.info["extrapolation"] == "clamp"
    lo, hi = m.clamp
    # the box covers the estimation data's states and inputs: there the clamp is inactive
    z = np.hstack([m.states(d.u), (d.u - m.scaling.u_offset) / m.scaling.u_scale])
    assert np.all(z >= lo) and np.all(z <= hi)
    plain = sysid.PNLSSModel(m.A, m.B, m.C, m.D, m.E, m.F, zeta=m.zeta, eta=m.eta,
                             scaling=m.scaling.to_dict(), dt=m.dt)
    np.testing.assert_array_equal(plain.simulate(d.u), m.simulate(d.u))
    assert sysid.compare(m, _record(1), x0="zero").fit[0, 0] > 90
    # four times the estimation amplitude: the true output stays below 1 / 0.3; the plain
    # polynomial runs away (or diverges), the clamped one stays bounded (only its linear
    # part extrapolates) and closer
    big = _record(2, scale=4.0)
    yc = m.simulate(big.u)
    assert np.all(np.isfinite(yc)) and np.max(np.abs(yc)) < 4 * 4 / 0.3
    ec = np.sqrt(np.mean((yc - big.y) ** 2))
    try:
        ep = np.sqrt(np.mean((plain.simulate(big.u) - big.y) ** 2))
    except NumericalError:
        ep = np.inf
    assert ec < ep


def test_clamp_round_trips_and_is_checked(tmp_path):
    d = _record(3, n=600)
    m = sysid.pnlss(d, 1, degree=[2, 3], terms="states", output_terms="none", tol=1e-6,
                    progress=False)
    p = tmp_path / "m.json"
    sysid.save_model(m, p)
    back = sysid.load_model(p)
    np.testing.assert_array_equal(back.clamp[0], m.clamp[0])
    u = 3 * np.random.default_rng(1).standard_normal((80, 1))
    np.testing.assert_array_equal(back.simulate(u), m.simulate(u))
    poly = sysid.pnlss(d, 1, degree=3, extrapolation="polynomial", tol=1e-4, progress=False)
    assert poly.clamp is None
    with pytest.raises(DataError, match="extrapolation"):
        sysid.pnlss(d, 1, extrapolation="linear")
    with pytest.raises(DataError, match="clamp"):
        sysid.PNLSSModel([[0.5]], [[1.0]], [[1.0]], [[0.0]], [[0.1]], np.zeros((1, 0)),
                         zeta=[[0, 0]], eta=[], clamp=([1.0, 0.0], [0.0, 1.0]))


def _wiener_hammerstein(u):
    # two states with a cubic coupling: x1+ = 0.6 x1 + u, x2+ = 0.5 x2 + 0.4 x1 - 0.1 (x1 +
    # x2)^3, y = x2
    x = np.zeros((len(u) + 1, 2))
    for t in range(len(u)):
        a, b = x[t]
        x[t + 1] = 0.6 * a + u[t], 0.5 * b + 0.4 * a - 0.1 * (a + b) ** 3
    return x[:-1, 1]


def test_decoupled_variant_fits_with_fewer_parameters(tmp_path):
    rng = np.random.default_rng(4)
    u = rng.uniform(-1, 1, 2000)
    d = sysid.IOData(u, _wiener_hammerstein(u), 1.0)
    uv = rng.uniform(-1, 1, 800)
    v = sysid.IOData(uv, _wiener_hammerstein(uv), 1.0)
    dec = sysid.pnlss(d, 2, degree=3, branches=2, tol=1e-6, progress=False)
    full = sysid.pnlss(d, 2, degree=3, terms="full", tol=1e-6, progress=False)
    lin = sysid.ssest(d, 2, focus="simulation", progress=False)
    assert isinstance(dec, sysid.DecoupledPNLSSModel) and dec.branches == 2
    assert dec.theta.size < full.theta.size
    fd = sysid.compare(dec, v, x0="zero").fit[0, 0]
    fl = sysid.compare(lin, v, x0="zero").fit[0, 0]
    assert fd > 99 and fd > fl + 5
    assert dec.info["fit"]["cost"][-1] <= dec.info["fit"]["cost"][0]
    for ext in ("json", "npz"):
        p = tmp_path / f"m.{ext}"
        sysid.save_model(dec, p)
        back = sysid.load_model(p)
        np.testing.assert_array_equal(back.simulate(uv), dec.simulate(uv))
    assert "DecoupledPNLSSModel" in repr(dec) and "parameters" in dec.summary()
    np.testing.assert_allclose(dec.freqresp([0.1, 1.0]), dec.linear().freqresp([0.1, 1.0]))
    with pytest.raises(DataError, match="branches"):
        sysid.pnlss(d, 2, branches=0, progress=False)


def test_period_averaging_fits_on_the_averaged_period():
    # noise-free periodic data: fitting on the average of periods 2..4 (two copies, the
    # first the transient) recovers the saturating system as well as the full record does
    u = np.tile(np.random.default_rng(6).uniform(-1, 1, 300), 4)
    y = _saturating(np.tile(u[:300], 8))[-1200:]  # steady state
    d = sysid.IOData(u, y, 1.0)
    m = sysid.pnlss(d, 1, degree=3, periods=4, average=True, tol=1e-6, progress=False)
    assert m.info["fit"]["transient"] == [300]
    assert sysid.compare(m, _record(1), x0="zero").fit[0, 0] > 90
    with pytest.raises(DataError, match="periods"):
        sysid.pnlss(d, 1, average=True, progress=False)
    with pytest.raises(DataError, match="whole periods"):
        sysid.pnlss(sysid.IOData(u[:1001], y[:1001], 1.0), 1, periods=4, average=True,
                    progress=False)
    two = sysid.IOData([u, u[:600]], [y, y[:600]], 1.0)
    m2 = sysid.pnlss(two, 1, degree=3, periods=[4, 2], average=True, tol=1e-6, progress=False)
    assert m2.info["fit"]["transient"] == [300, 300]
    with pytest.raises(DataError, match="one per experiment"):
        sysid.pnlss(two, 1, periods=[4], progress=False)


def test_output_terms_use_the_output_aligned_states():
    # three states, one output y = x0; the nonlinearity is the cube of the output's state
    truth = sysid.PNLSSModel(
        [[0.6, 0.3, 0.0], [-0.3, 0.6, 0.2], [0.0, -0.2, 0.5]], [[1.0], [0.3], [0.5]],
        [[1.0, 0.0, 0.0]], [[0.0]], [[-0.05], [0.02], [0.03]], np.zeros((1, 0)),
        zeta=[[0, 0, 0]], eta=[], dt=1.0)
    u = sysid.multisine(400, band=(0, 0.5), phases="random", seed=3, periods=2, rms=0.6)
    d = sysid.IOData(u, truth.simulate(u), 1.0)
    kw = dict(degree=3, output_terms="none", periods=2, progress=False, max_iter=60)
    m = sysid.pnlss(d, 3, terms="outputs", **kw)
    # monomials of the first state (the output's direction) and the input (index 3) only:
    # the constant, three of degree 2, four of degree 3
    assert {v for t in m.zeta for v in t} == {0, 3}
    assert len(m.zeta) == 1 + 3 + 4
    # the input monomials alone cannot describe it
    m_in = sysid.pnlss(d, 3, terms="inputs", **kw)
    e_out = np.linalg.norm(m.simulate(u) - d.y)
    e_in = np.linalg.norm(m_in.simulate(u) - d.y)
    assert e_out < 0.1 * e_in
    with pytest.raises(DataError, match="terms must be"):
        sysid.pnlss(d, 3, terms="output", progress=False)


def test_decoupled_iteration_cap_names_the_cap_given():
    # The decoupled fit's random starts (3 x 8 iterations) were counted into the cap the
    # warning named: "stopped at max_iter=26" for max_iter=10, and "raise max_iter" advice
    # that did not match the argument.
    rng = np.random.default_rng(0)
    u = rng.standard_normal(2000)
    y = np.convolve(u, [0, 0.1, 0.05])[:2000] ** 3
    with pytest.warns(sysid.IterationLimitWarning, match=r"stopped at max_iter=10 "):
        m = sysid.pnlss(sysid.IOData(u, y, 1.0), 2, degree=3, branches=2, max_iter=10,
                        progress=False)
    fit = m.info["fit"]
    # the path returned: its best start's 8 iterations, then 2 more, one per cost entry
    assert fit["iterations"] == len(fit["cost"]) - 1 == 10
    assert fit["iterations_all_trials"] > 10  # the other starts' iterations, separately


def test_decoupled_fit_reports_the_returned_path_s_iterations():
    # max_iter=2 reported 6 iterations (three random starts of 2 summed) beside a cost
    # history of 3 entries (the start returned: its 2 iterations)
    rng = np.random.default_rng(1)
    u = rng.uniform(-1, 1, 300)
    x = np.zeros(300)
    for t in range(1, 300):
        x[t] = 0.7 * x[t - 1] + 0.5 * u[t - 1]
    d = sysid.IOData(u, x + 0.5 * x ** 3 + 0.01 * rng.standard_normal(300), 0.1)
    with pytest.warns(sysid.IterationLimitWarning, match="max_iter=2 "):
        m = sysid.pnlss(d, 1, degree=3, branches=1, max_iter=2, progress=False)
    fit = m.info["fit"]
    assert fit["iterations"] == len(fit["cost"]) - 1 == 2
    assert fit["iterations_all_trials"] == 6
    assert fit["evaluations"] < fit["evaluations_all_trials"]
    coupled = sysid.pnlss(d, 1, degree=2, max_iter=40, progress=False).info["fit"]
    assert coupled["iterations_all_trials"] == coupled["iterations"] == len(coupled["cost"]) - 1


def test_a_cancelled_decoupled_fit_stops_at_once():
    # progress returning False ends the fit: the remaining random starts ran one iteration
    # each before (the callable was called again after it asked to stop)
    rng = np.random.default_rng(5)
    u = rng.uniform(-1, 1, 600)
    d = sysid.IOData(u, _wiener_hammerstein(u), 1.0)
    calls: list[int] = []

    def stop_at_third(*args):
        calls.append(args[0])
        return len(calls) < 3

    with pytest.warns(UserWarning, match="cancelled"):
        m = sysid.pnlss(d, 2, degree=3, branches=2, max_iter=30, progress=stop_at_third)
    assert len(calls) == 3 and m.info["fit"]["stop"] == "cancelled"
