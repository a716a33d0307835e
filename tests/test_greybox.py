"""Grey-box estimation (sysid.GreyBox, sysid.greyest): exactness, calibration, options."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from _guides import guide_text, python_blocks, run_guide

import sysid
from sysid.errors import DataError

# -- the gyroplane lateral/directional structure (report 003, pedal-input model) -------------
# Tables 6.1-6.3, rudder-pedal column; Lr and Np fixed at zero, U0 and g fixed as in the
# report's model file (g enters with the file's sign, -9.81).
TRUE = {"Yv": 0.878698, "Yd_ped": 0.0456625, "Lv": 0.00208104, "Lp": -0.0669935,
        "Ld_lat": -0.00146285, "Ld_ped": 0.00060241, "Nv": 0.0586699, "Nr": -1.8769,
        "Nd_lat": 0.00775002, "Nd_ped": 0.0102646}
KNOWN = {"U0": sysid.fixed(55.0), "g": sysid.fixed(-9.81), "Lr": sysid.fixed(0.0),
         "Np": sysid.fixed(0.0)}


def lateral(p, dt=None):
    A = [[p.Yv, 0, -p.U0, p.g], [p.Lv, p.Lp, p.Lr, 0], [p.Nv, p.Np, p.Nr, 0], [0, 1, 0, 0]]
    B = [[0, p.Yd_ped], [p.Ld_lat, p.Ld_ped], [p.Nd_lat, p.Nd_ped], [0, 0]]
    return A, B, np.eye(4), np.zeros((4, 2))


def _sweeps(n: int, dt: float) -> np.ndarray:
    t = np.arange(n) * dt
    T = n * dt

    def sweep(f0: float, f1: float) -> np.ndarray:
        return np.sin(2 * np.pi * (f0 * t + (f1 - f0) * t ** 2 / (2 * T)))
    return np.column_stack([10 * sweep(0.05, 1.5), 10 * sweep(1.5, 0.05)])


@pytest.fixture(scope="module")
def lateral_case():
    dt, n = 0.05, 1200
    u = _sweeps(n, dt)
    truth = sysid.GreyBox(lateral, {**TRUE, **KNOWN})
    y0 = truth.model(dt=dt).simulate(u)
    sigma = 0.05 * y0.std(axis=0)
    start = sysid.GreyBox(lateral, {**{k: 1.3 * v for k, v in TRUE.items()}, **KNOWN})
    return u, y0, sigma, start, dt


def test_lateral_monte_carlo_calibration(lateral_case):
    """400 noisy records (fixed seeds): each free derivative's 95 % interval covers the truth
    in 90-98 % of runs, the mean estimate is within 4 standard errors of the truth (far
    inside the issue's "within one predicted std"), and the spread of the estimates matches
    the predicted std.

    Why 400 runs and these bounds. If the intervals are calibrated and the runs independent,
    the number of runs in which one parameter's interval covers the truth is
    X ~ Binomial(n, 0.95). The band 90-98 % is left with probability
    P(X < 0.90 n) + P(X > 0.98 n): 1.0e-2 for n = 200 (mostly the upper side,
    P(X >= 197) = 9.0e-3), so with ten parameters a calibrated estimator failed up to one
    seed set in ten (the union bound; the 98 % of Lv in the earlier 200-run version was such
    a fluctuation: 2000 runs give 1915/2000 = 95.75 %, Clopper-Pearson 95 % interval
    [94.8, 96.6] %, and z = (est - truth) / std has mean 0.02 and spread 0.99). For
    n = 400 it is 6.2e-4 + 1.4e-5 per parameter, at most 0.63 % for all ten, so the band is
    the issue's own and a failure means a miscalibration, not bad luck. The mean of
    z = (est - truth) / std over n runs has standard error 1/sqrt(n) = 0.05; 4/sqrt(n) is
    beyond the two-sided Bonferroni point for ten parameters at 1e-3 (3.89). The spread ratio
    std(est) / mean(std) of Gaussian estimates has standard error 1/sqrt(2 n) = 0.035; 15 %
    is 4.2 of them. The fits start at the truth: calibration is a property of the optimum
    (they land within 4e-5 std of the fits started 30 % off, which the other tests and the
    docs cover), and it halves the cost (400 fits in about 8 s CPU).
    """
    u, y0, sigma, _, dt = lateral_case
    start = sysid.GreyBox(lateral, {**TRUE, **KNOWN})
    names = list(TRUE)
    runs = 400
    est = np.zeros((runs, len(names)))
    std = np.zeros_like(est)
    for r in range(runs):
        rng = np.random.default_rng(1000 + r)
        y = y0 + sigma * rng.standard_normal(y0.shape)
        fit = sysid.greyest(sysid.IOData(u=u, y=y, dt=dt), start, x0="zero")
        est[r] = [fit.parameters[k]["value"] for k in names]
        std[r] = [fit.parameters[k]["std"] for k in names]
    truth = np.array([TRUE[k] for k in names])
    coverage = np.mean(np.abs(est - truth) <= 1.959964 * std, axis=0)
    assert np.all((coverage >= 0.90) & (coverage <= 0.98)), dict(zip(names, coverage))
    z = (est - truth) / std
    assert np.all(np.abs(z.mean(axis=0)) <= 4 / np.sqrt(runs)), dict(zip(names, z.mean(0)))
    assert np.all(np.abs(est.mean(axis=0) - truth) <= std.mean(axis=0)), names
    ratio = est.std(axis=0) / std.mean(axis=0)
    assert np.all(np.abs(ratio - 1) < 0.15), dict(zip(names, ratio))


def test_lateral_fixed_parameters_never_move(lateral_case):
    u, y0, sigma, start, dt = lateral_case
    rng = np.random.default_rng(7)
    y = y0 + sigma * rng.standard_normal(y0.shape)
    wrong = sysid.GreyBox(lateral, {**{k: 1.3 * v for k, v in TRUE.items()},
                                    **KNOWN, "U0": sysid.fixed(50.0)})
    fit = sysid.greyest(sysid.IOData(u=u, y=y, dt=dt), wrong, x0="zero")
    t = fit.parameters
    for k in ("U0", "g", "Lr", "Np"):
        assert t[k]["fixed"] and t[k]["std"] == 0.0
    assert t["U0"]["value"] == 50.0 and t["g"]["value"] == -9.81 and t["Lr"]["value"] == 0.0
    assert fit.structure.params["U0"].value == 50.0
    # the table, the model's uncertainty and the covariance agree
    free = fit.free_names
    assert free == list(TRUE)
    np.testing.assert_allclose(fit.model.uncertainty.std, [t[k]["std"] for k in free])
    assert fit.correlation.shape == (10, 10)
    np.testing.assert_allclose(np.diag(fit.correlation), 1.0)
    df = fit.to_pandas()
    assert list(df.index) == list(t.names) and bool(df.loc["U0", "fixed"])
    assert "Yv" in repr(fit.parameters) and "fixed" in fit.summary()


def test_lateral_model_is_usable_everywhere(lateral_case):
    u, y0, sigma, start, dt = lateral_case
    y = y0 + sigma * np.random.default_rng(3).standard_normal(y0.shape)
    data = sysid.IOData(u=u, y=y, dt=dt)
    fit = sysid.greyest(data, start, x0="zero")
    assert isinstance(fit.model, sysid.ContinuousStateSpace)
    cmp = sysid.compare(fit.model, data)
    assert np.all(np.asarray(cmp.fit) > 90)
    sysid.residuals(fit.model, data)
    # any function of the model gets a std from the grey-box covariance
    g = fit.model.uncertainty.propagate(lambda m: np.sort(m.poles().real))
    assert np.all(np.isfinite(g.std)) and np.all(g.std > 0)


def test_dc_motor_matches_least_squares_on_noise_free_data():
    """y(t+1) = a y(t) + b u(t) exactly for a ZOH-sampled first-order motor: least squares
    gives a, b, hence tau = -dt / ln a and K = b / (1 - a); greyest must agree to 1e-8."""
    dt = 0.02

    def motor(p, dt=None):
        return [[-1.0 / p.tau]], [[p.K / p.tau]], [[1.0]], [[0.0]]

    rng = np.random.default_rng(0)
    u = np.repeat(rng.standard_normal(60), 10)
    y = sysid.GreyBox(motor, {"K": 3.7, "tau": 0.45}).model(dt=dt).simulate(u)[:, 0]
    Phi = np.column_stack([y[:-1], u[:-1]])
    a, b = np.linalg.lstsq(Phi, y[1:], rcond=None)[0]
    tau_ls, K_ls = -dt / np.log(a), b / (1 - a)
    s = sysid.GreyBox(motor, {"K": 1.0, "tau": sysid.param(1.0, bounds=(1e-3, 100))})
    fit = sysid.greyest(sysid.IOData(u=u, y=y, dt=dt), s, x0="zero")
    assert abs(fit.parameters["tau"]["value"] - tau_ls) < 1e-8
    assert abs(fit.parameters["K"]["value"] - K_ls) < 1e-8
    # the user-supplied derivative path gives the same answer
    s2 = sysid.GreyBox(motor, {"K": 1.0, "tau": 1.0}, jacobian=lambda p: {
        "K": ([[0.0]], [[1 / p.tau]], [[0.0]], [[0.0]]),
        "tau": ([[1 / p.tau ** 2]], [[-p.K / p.tau ** 2]], [[0.0]], [[0.0]])})
    fit2 = sysid.greyest(sysid.IOData(u=u, y=y, dt=dt), s2, x0="zero")
    np.testing.assert_allclose(fit2.parameters.value, [K_ls, tau_ls], atol=1e-8)


def _product(p, dt=None):
    return [[-p.a * p.b]], [[1.0]], [[1.0]], [[0.0]]


def _product_record(a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
    """A square wave through ``1 / (s + a b)`` sampled at 0.05 s, with a little noise: only
    the product ``a b`` is determined."""
    u = np.sign(np.sin(np.arange(300) * 0.07))
    y = sysid.GreyBox(_product, {"a": a, "b": b}).model(dt=0.05).simulate(u)
    return u, y + 0.01 * np.random.default_rng(0).standard_normal(y.shape)


def test_product_only_parameters_are_named():
    u, y = _product_record(1.0, 2.0)
    s = sysid.GreyBox(_product, {"a": 1.5, "b": 1.5})
    with pytest.warns(sysid.IdentifiabilityWarning, match=r"a, b") as rec:
        fit = sysid.greyest(sysid.IOData(u=u, y=y, dt=0.05), s, x0="zero")
    assert rec[0].filename == __file__  # at the user's line, not inside sysid
    assert fit.info["rank"] == 1
    # no finite std for parameters the data cannot separate (it was 0.00124 each, with
    # intervals that excluded the truth), as tfest reports them
    assert np.all(np.isinf(fit.parameters.std))
    assert abs(np.prod(fit.parameters.value) - 2.0) < 0.02
    # the model's own uncertainty says the same (its table showed 0.00124 each), keeps it
    # through saving and pickling, and still propagates to what the data determine: the pole
    unc = fit.model.uncertainty
    assert np.all(np.isinf(unc.std)) and np.all(np.isinf(unc.to_pandas()["std"]))
    assert "inf" in unc.summary() and np.all(np.isnan(unc.correlation))
    import pickle
    assert np.all(np.isinf(pickle.loads(pickle.dumps(fit.model)).uncertainty.std))
    assert np.all(np.isinf(sysid.model_from_dict(sysid.model_to_dict(fit.model))
                           .uncertainty.std))
    _, pole_sd = fit.model.poles(std=True)
    assert np.all(np.isfinite(pole_sd)) and abs(pole_sd[0]) < 0.05
    # fixing one of them removes the warning
    s = sysid.GreyBox(_product, {"a": sysid.fixed(1.0), "b": 1.5})
    with warnings.catch_warnings():
        warnings.simplefilter("error", sysid.IdentifiabilityWarning)
        fit = sysid.greyest(sysid.IOData(u=u, y=y, dt=0.05), s, x0="zero")
    assert abs(fit.parameters["b"]["value"] - 2.0) < 0.02


def _motor_data(tau=0.3, K=2.0, n=400, noise=0.02, seed=0, x0=None, dt=0.05):
    def motor(p, dt=None):
        return [[-1.0 / p.tau]], [[p.K / p.tau]], [[1.0]], [[0.0]]
    u = np.sign(np.sin(np.arange(n) * 0.05))
    y = sysid.GreyBox(motor, {"K": K, "tau": tau}).model(dt=dt).simulate(u, x0=x0)
    y = y + noise * np.random.default_rng(seed).standard_normal(y.shape)
    return motor, sysid.IOData(u=u, y=y, dt=dt)


def test_active_bound_is_reported():
    motor, data = _motor_data()
    s = sysid.GreyBox(motor, {"K": 1.0, "tau": sysid.param(0.1, bounds=(0.01, 0.2))})
    fit = sysid.greyest(data, s, x0="zero")
    row = fit.parameters["tau"]
    assert row["value"] == 0.2 and row["bound"] == "upper"
    assert fit.parameters["K"]["bound"] == ""
    assert "upper" in str(fit.parameters)
    free = sysid.greyest(data, sysid.GreyBox(motor, {"K": 1.0, "tau": 0.1}), x0="zero")
    assert abs(free.parameters["tau"]["value"] - 0.3) < 0.01


def test_options_change_the_result():
    motor, data = _motor_data(x0=[1.5])
    s = sysid.GreyBox(motor, {"K": 1.0, "tau": 1.0})
    est = sysid.greyest(data, s, x0="estimate")
    zero = sysid.greyest(data, s, x0="zero")
    assert abs(est.initial_states[0][0] - 1.5) < 0.05
    assert est.info["loss"] < 0.5 * zero.info["loss"]
    given = sysid.greyest(data, s, x0=[1.5])
    assert given.initial_states[0][0] == 1.5
    # weighting: identity vs noise (two outputs with very different noise)
    ident = sysid.greyest(data, s, weighting="identity")
    assert ident.info["weighted_cost"][-1] != est.info["weighted_cost"][-1]
    # hold: the same data seen through FOH gives other parameters
    foh = sysid.greyest(data, sysid.GreyBox(motor, {"K": 1.0, "tau": 1.0}, hold="foh"))
    assert abs(foh.parameters["tau"]["value"] - est.parameters["tau"]["value"]) > 1e-3
    # max_iter stops early
    with pytest.warns(sysid.IterationLimitWarning, match="greyest search stopped at max_iter=1"):
        short = sysid.greyest(data, s, max_iter=1)  # it stopped short silently
    assert short.info["iterations"] == 1 and short.info["stop"] == "maximum iterations"
    with pytest.raises(DataError):
        sysid.greyest(data, s, focus="bogus")
    with pytest.raises(DataError):
        sysid.greyest(data, s, x0="model")


def test_focus_and_noise_model():
    """Process noise through a Kalman gain: prediction focus with K estimated fits the
    one-step predictor better than the output-error model."""
    dt = 0.1

    def first(p, dt=None):
        return [[p.a]], [[p.b]], [[1.0]], [[0.0]]

    rng = np.random.default_rng(2)
    n = 2000
    u = rng.standard_normal(n)
    e = 0.3 * rng.standard_normal(n)
    x = 0.0
    y = np.zeros(n)
    for t in range(n):
        y[t] = x + e[t]
        x = 0.9 * x + 0.5 * u[t] + 0.7 * e[t]
    data = sysid.IOData(u=u, y=y, dt=dt)
    s = sysid.GreyBox(first, {"a": 0.5, "b": 1.0}, continuous=False)
    oe = sysid.greyest(data, s, noise="none")
    kal = sysid.greyest(data, s, noise="estimate")
    sim = sysid.greyest(data, s, noise="estimate", focus="simulation")
    assert kal.info["loss"] < 0.7 * oe.info["loss"]
    assert kal.model.K is not None and abs(kal.model.K[0, 0] - 0.7) < 0.05
    assert abs(kal.parameters["a"]["value"] - 0.9) < 3 * kal.parameters["a"]["std"] + 1e-9
    assert sim.model.K is None or not np.any(sim.model.K)
    assert sim.info["noise"] == "none"
    # K as a function of the parameters (returned by the structure)
    s2 = sysid.GreyBox(lambda p: ([[p.a]], [[p.b]], [[1.0]], [[0.0]], [[p.k]]),
                       {"a": 0.5, "b": 1.0, "k": 0.2}, continuous=False)
    fit2 = sysid.greyest(data, s2)
    assert abs(fit2.parameters["k"]["value"] - 0.7) < 0.05


def test_multistart_escapes_a_local_minimum():
    """A lightly damped oscillator: the simulation error is multimodal in the frequency."""
    dt = 0.05

    def osc(p, dt=None):
        return [[0.0, 1.0], [-p.w ** 2, -0.1 * p.w]], [[0.0], [p.w ** 2]], [[1.0, 0.0]], [[0.0]]

    rng = np.random.default_rng(1)
    u = np.repeat(rng.standard_normal(40), 15)
    y = sysid.GreyBox(osc, {"w": 2.0}).model(dt=dt).simulate(u)
    data = sysid.IOData(u=u, y=y + 0.01 * rng.standard_normal(y.shape), dt=dt)
    s = sysid.GreyBox(osc, {"w": sysid.param(3.5, bounds=(0.5, 4.0))})
    single = sysid.greyest(data, s, focus="simulation", x0="zero")
    multi = sysid.greyest(data, s, focus="simulation", x0="zero", multistart=10, rng=0)
    assert abs(multi.parameters["w"]["value"] - 2.0) < 0.01
    assert multi.info["loss"] < single.info["loss"]
    assert len(multi.info["multistart"]) == 10
    assert abs(single.parameters["w"]["value"] - 2.0) > 0.1


def test_input_delay():
    motor, _ = _motor_data()
    dt = 0.05
    u = np.sign(np.sin(np.arange(400) * 0.05))
    truth = sysid.GreyBox(motor, {"K": 2.0, "tau": 0.3}, input_delay=0.15)
    y = truth.model(dt=dt).simulate(u)
    assert np.all(y[:5] == 0) and y[5, 0] != 0  # u[0] = 0, 3 samples of delay, 1 of ZOH
    data = sysid.IOData(u=u, y=y, dt=dt)
    s = sysid.GreyBox(motor, {"K": 1.0, "tau": 1.0}, input_delay=0.15)
    fit = sysid.greyest(data, s, x0="zero")
    np.testing.assert_allclose(fit.parameters.value, [2.0, 0.3], atol=1e-7)
    assert fit.model.nstates == 4  # 1 state + 3 delay states
    nodelay = sysid.greyest(data, sysid.GreyBox(motor, {"K": 1.0, "tau": 1.0}), x0="zero")
    assert nodelay.info["loss"] > 1e3 * fit.info["loss"]
    # a delay between samples (tests/test_greybox_delay.py): whole samples + one more state
    assert sysid.GreyBox(motor, {"K": 1.0, "tau": 1.0}, input_delay=0.123
                         ).model(dt=dt).nstates == 1 + 3


def test_scale_keeps_the_optimum():
    motor, data = _motor_data()
    a = sysid.greyest(data, sysid.GreyBox(motor, {"K": 1.0, "tau": 1.0}))
    b = sysid.greyest(data, sysid.GreyBox(motor, {"K": sysid.param(1.0, scale=100.0),
                                                  "tau": sysid.param(1.0, scale=1e-3)}))
    np.testing.assert_allclose(a.parameters.value, b.parameters.value, rtol=1e-6)
    np.testing.assert_allclose(a.parameters.std, b.parameters.std, rtol=1e-4)


def test_from_structure_equals_the_function_form():
    A = np.array([[0.8, 0.2], [-0.1, 0.7]])
    B = np.array([[1.0], [0.5]])
    C = np.array([[1.0, 0.0]])
    rng = np.random.default_rng(4)
    u = rng.standard_normal(500)
    y = sysid.StateSpaceModel(A, B, C).simulate(u)
    data = sysid.IOData(u=u, y=y, dt=1.0)
    free = {"A": [[1, 1], [0, 1]]}
    s = sysid.GreyBox.from_structure(np.array([[0.6, 0.1], [-0.1, 0.6]]), B, C, free=free,
                                     dt=1.0)
    assert s.free_names == ["A_0_0", "A_0_1", "A_1_1"]
    fit = sysid.greyest(data, s, x0="zero")
    np.testing.assert_allclose(fit.parameters.value, [0.8, 0.2, 0.7], atol=1e-8)

    def same(p):
        return [[p.A_0_0, p.A_0_1], [-0.1, p.A_1_1]], B, C, [[0.0]]
    g = sysid.GreyBox(same, {k: s.params[k].value for k in s.free_names}, continuous=False)
    fit2 = sysid.greyest(data, g, x0="zero")
    np.testing.assert_allclose(fit2.parameters.value, fit.parameters.value, atol=1e-10)
    # B_1_0 free as well: four parameters for three transfer-function coefficients
    s4 = sysid.GreyBox.from_structure(np.array([[0.6, 0.1], [-0.1, 0.6]]), B * [[1], [0.6]],
                                      C, free={**free, "B": [[0], [1]]}, dt=1.0)
    with pytest.warns(sysid.IdentifiabilityWarning, match="A_0_0, A_0_1, A_1_1, B_1_0"):
        sysid.greyest(data, s4, x0="zero")
    with pytest.raises(DataError):
        sysid.GreyBox.from_structure(A, B, C, free={"Q": [[1]]})


def test_foh_sampling_and_frechet_derivatives():
    def sys2(p, dt=None):
        return ([[p.a, 1.0], [-2.0, p.c]], [[0.0], [p.b]], [[1.0, 0.0]], [[0.0]])
    vals = {"a": -0.3, "b": 1.2, "c": -0.8}
    for hold in ("zoh", "foh"):
        s = sysid.GreyBox(sys2, vals, hold=hold)
        ref = sysid.c2d(s.model(), 0.2, hold)
        got = s.sampled(None, 0.2)
        np.testing.assert_allclose(got["A"], ref.A, atol=1e-13)
        np.testing.assert_allclose(got["B"], ref.B, atol=1e-13)
        np.testing.assert_allclose(got["D"], ref.D, atol=1e-13)
        base, ders = s.sampled_derivatives(None, 0.2, ["a", "b", "c"])
        for k, d in zip("abc", ders):
            h = 1e-6
            up = s.sampled({**vals, k: vals[k] + h}, 0.2)
            dn = s.sampled({**vals, k: vals[k] - h}, 0.2)
            for key in ("A", "B", "D"):
                np.testing.assert_allclose(d[key], (up[key] - dn[key]) / (2 * h), atol=1e-8)


def test_bad_structures_raise():
    with pytest.raises(DataError):
        sysid.param(2.0, bounds=(0, 1))
    with pytest.raises(DataError):
        sysid.GreyBox(lambda p: ([[p.a]], [[1.0]]), {"a": 1.0})
    s = sysid.GreyBox(lambda p: ([[p.a]], [[1.0]], [[1.0]], [[0.0]]), {"a": 1.0})
    u = np.sin(0.3 * np.arange(50.0))  # a varying input (a constant one is refused first)
    with pytest.raises(DataError, match="unstable"):
        sysid.greyest(sysid.IOData(u=u, y=u, dt=0.1), s)
    with pytest.raises(ZeroDivisionError):
        sysid.greyest(sysid.IOData(u=u, y=u, dt=0.1), sysid.GreyBox(
            lambda p: ([[-1 / p.a]], [[1.0]], [[1.0]], [[0.0]]), {"a": sysid.param(0.5)}),
            progress=lambda *a: 1 / 0)


# -- nonlinear grey-box ------------------------------------------------------------------------
def lateral_ode(t, x, u, p):
    return [p.Yv * x[0] - p.U0 * x[2] + p.g * x[3] + p.Yd_ped * u[1],
            p.Lv * x[0] + p.Lp * x[1] + p.Lr * x[2] + p.Ld_lat * u[0] + p.Ld_ped * u[1],
            p.Nv * x[0] + p.Np * x[1] + p.Nr * x[2] + p.Nd_lat * u[0] + p.Nd_ped * u[1],
            x[1]]


def states(t, x, u, p):
    return [x[0], x[1], x[2], x[3]]


def test_lateral_as_ode_gives_the_same_parameters(lateral_case):
    """The same equations as a nonlinear grey-box (RK4 at the sample time, vectorised
    Jacobian): the estimates agree with the linear grey-box within a small fraction of their
    standard deviations, and so do the standard deviations."""
    u, y0, sigma, start, dt = lateral_case
    n = 600
    y = y0[:n] + sigma * np.random.default_rng(11).standard_normal((n, 4))
    data = sysid.IOData(u=u[:n], y=y, dt=dt)
    lin = sysid.greyest(data, start, x0="zero")
    init = {**{k: 1.3 * v for k, v in TRUE.items()}, **KNOWN}
    nl = sysid.NonlinearGreyBox(lateral_ode, states, init, nx=4, vectorized=True)
    fit = sysid.greyest(data, nl)
    free = list(TRUE)
    a = np.array([fit.parameters[k]["value"] for k in free])
    b = np.array([lin.parameters[k]["value"] for k in free])
    sa = np.array([fit.parameters[k]["std"] for k in free])
    sb = np.array([lin.parameters[k]["std"] for k in free])
    assert np.all(np.abs(a - b) < 0.05 * sb), (a - b) / sb
    # both fits' std are the sandwich for coloured simulation errors, formed on these
    # white ones with the AR orders AIC picks per output (up to 7 % from Gauss-Newton here)
    for note in (lin.info["covariance"], fit.info["covariance"]):
        assert note.startswith("sandwich for coloured"), note
    np.testing.assert_allclose(sa, sb, rtol=0.1)
    assert fit.parameters["U0"]["value"] == 55.0 and fit.parameters["U0"]["fixed"]
    assert fit.info["rhs_calls"] > 0 and fit.info["seconds"] > 0
    # the estimated structure is a model: simulate, compare
    assert fit.model.dt == dt
    np.testing.assert_allclose(fit.model.simulate(u[:n]), lin.model.simulate(u[:n], dt=dt),
                               atol=1e-3 * np.abs(y0).max())


def _pendulum():
    def f(t, x, u, p):
        return [x[1], -p.w2 * np.sin(x[0]) - p.c * x[1] + p.b * u[0]]

    def h(t, x, u, p):
        return [x[0]]
    return f, h


def test_nonlinear_exact_on_noise_free_data_with_several_experiments():
    """A pendulum (sin nonlinearity), two experiments with their own initial states: the
    first experiment's angle is estimated, its rate is fixed, the second's state is fixed."""
    f, h = _pendulum()
    dt = 0.05
    rng = np.random.default_rng(5)
    truth = {"w2": 9.0, "c": 0.4, "b": 2.0}
    x0s = np.array([[0.8, 0.0], [-0.3, 0.5]])
    exps = []
    for e in range(2):
        u = np.repeat(rng.standard_normal(15), 10)[:, None]
        s = sysid.NonlinearGreyBox(f, h, truth, nx=2, x0=x0s[e], integrator="rk4", substeps=2)
        exps.append((u, s.simulate(u, dt=dt)))
    data = sysid.IOData(u=[e[0] for e in exps], y=[e[1] for e in exps], dt=dt)
    guess = x0s.copy()
    guess[0, 0] = 0.5
    s = sysid.NonlinearGreyBox(f, h, {"w2": 6.0, "c": 0.2, "b": 1.0}, nx=2, x0=guess,
                               x0_free=[[True, False], [False, False]], substeps=2)
    for vec in (True, False):
        s.vectorized = vec
        fit = sysid.greyest(data, s)
        np.testing.assert_allclose(fit.parameters.value, [9.0, 0.4, 2.0], atol=1e-6)
        assert abs(fit.initial_states[0][0] - 0.8) < 1e-6
        assert fit.initial_states[0][1] == 0.0 and np.all(fit.initial_states[1] == x0s[1])
    # the adaptive integrator reproduces the data of the fine RK4 to its tolerance
    s.integrator = "adaptive"
    fit = sysid.greyest(data, s)
    np.testing.assert_allclose(fit.parameters.value, [9.0, 0.4, 2.0], rtol=1e-3)


def test_nonlinear_bounds_fixed_and_options():
    f, h = _pendulum()
    dt = 0.05
    rng = np.random.default_rng(6)
    u = np.repeat(rng.standard_normal(30), 15)[:, None]
    y = sysid.NonlinearGreyBox(f, h, {"w2": 9.0, "c": 0.4, "b": 2.0}, nx=2, x0=[0.5, 0]
                               ).simulate(u, dt=dt)
    y = y + 0.01 * rng.standard_normal(y.shape)
    data = sysid.IOData(u=u, y=y, dt=dt)
    s = sysid.NonlinearGreyBox(f, h, {"w2": 8.5, "c": sysid.param(0.1, bounds=(0.0, 0.3)),
                                      "b": sysid.fixed(2.0)}, nx=2, x0=[0.5, 0.0],
                               vectorized=True)
    fit = sysid.greyest(data, s)
    assert fit.parameters["c"]["value"] == 0.3 and fit.parameters["c"]["bound"] == "upper"
    assert fit.parameters["b"]["value"] == 2.0 and fit.parameters["b"]["std"] == 0.0
    # x0: "zero" (the data start at 0.5) fits worse than "estimate"
    s2 = sysid.NonlinearGreyBox(f, h, {"w2": 8.5, "c": 0.2, "b": 1.5}, nx=2, vectorized=True)
    est = sysid.greyest(data, s2, x0="estimate")
    zero = sysid.greyest(data, s2, x0="zero")
    assert abs(est.initial_states[0][0] - 0.5) < 0.01
    assert est.info["loss"] < 0.5 * zero.info["loss"]
    assert abs(est.parameters["w2"]["value"] - 9.0) < 3 * est.parameters["w2"]["std"] + 1e-6
    with pytest.raises(DataError):
        sysid.NonlinearGreyBox(f, h, {"w2": 1.0}, nx=2, integrator="euler")
    with pytest.raises(DataError, match="f returned"):
        sysid.greyest(data, sysid.NonlinearGreyBox(lambda t, x, u, p: [x[1]], h,
                                                   {"w2": 1.0}, nx=2, vectorized=True))


def test_docs_examples_run():
    assert len(python_blocks(guide_text("greybox.md"))) >= 4
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sysid.IdentifiabilityWarning)
        namespace = run_guide("greybox.md")
    assert namespace["worst"] < 0.1
    assert "IdentifiabilityWarning" in type(namespace["caught"][0].message).__name__ or \
        "a, b" in str(namespace["caught"][0].message)


def test_report_shows_the_parameter_table(tmp_path):
    motor, data = _motor_data()
    fit = sysid.greyest(data, sysid.GreyBox(motor, {"K": 1.0, "tau": sysid.param(
        1.0, unit="s", description="time constant"), "unused": sysid.fixed(3.0)}))
    files = sysid.report(fit.model, data, tmp_path)
    page = next(p for p in (files.values() if isinstance(files, dict) else files)
                if str(p).endswith(".html"))
    from pathlib import Path
    text = Path(page).read_text()
    assert 'id="parameters"' in text and "time constant" in text and "fixed" in text
    assert f"{fit.parameters['tau']['value']:.6g}" in text


def test_progress_reports_and_stops():
    motor, data = _motor_data()
    s = sysid.GreyBox(motor, {"K": 1.0, "tau": 1.0})
    seen = []
    fit = sysid.greyest(data, s, progress=lambda it, cost, *rest: seen.append(cost))
    assert len(seen) == fit.info["iterations"] >= 2
    stopped = sysid.greyest(data, s, progress=lambda *a: False)
    assert stopped.info["iterations"] == 1 and stopped.info["stop"] == "cancelled"
    nl = sysid.NonlinearGreyBox(lambda t, x, u, p: [(-x[0] + p.K * u[0]) / p.tau],
                                lambda t, x, u, p: [x[0]], {"K": 1.0, "tau": 1.0}, nx=1,
                                vectorized=True)
    nfit = sysid.greyest(data, nl, progress=lambda *a: False)
    assert nfit.info["stop"] == "cancelled"


def test_nonlinear_result_is_a_model_and_plots():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    motor, data = _motor_data()
    nl = sysid.NonlinearGreyBox(lambda t, x, u, p: [(-x[0] + p.K * u[0]) / p.tau],
                                lambda t, x, u, p: [x[0]], {"K": 1.0, "tau": 1.0}, nx=1,
                                vectorized=True)
    fit = sysid.greyest(data, nl)
    assert isinstance(fit.model, sysid.Model)
    assert np.all(np.asarray(sysid.compare(fit.model, data).fit) > 90)
    lin = fit.model.linearize()
    assert abs(lin.A[0, 0] - np.exp(-data.dt / fit.parameters["tau"]["value"])) < 1e-6
    ax = fit.plot()
    assert len(ax.get_xticklabels()) == 2
    plt.close("all")


def test_an_estimate_on_a_bound_has_its_interval_cut_there():
    """c = 1 on its upper bound 1.0 printed [0.958, 1.042]: the 95 % interval is cut at the
    bound, as procest's; a parameter off its bounds keeps value -+ 1.96 std."""
    z = 1.959963984540054
    motor, data = _motor_data()
    s = sysid.GreyBox(motor, {"K": 1.0, "tau": sysid.param(0.1, bounds=(0.01, 0.2))})
    t = sysid.greyest(data, s, x0="zero").parameters
    tau, k = t["tau"], t["K"]
    assert tau["bound"] == "upper" and tau["std"] > 0
    assert tau["ci95"] == (pytest.approx(0.2 - z * tau["std"], rel=1e-12), 0.2)
    assert k["ci95"] == pytest.approx((k["value"] - z * k["std"], k["value"] + z * k["std"]),
                                      rel=1e-12)
    assert f"[{0.2 - z * tau['std']:9.4g}, {0.2:9.4g}]" in str(t)
    f, h = _pendulum()
    rng = np.random.default_rng(6)
    u = np.repeat(rng.standard_normal(30), 15)[:, None]
    y = sysid.NonlinearGreyBox(f, h, {"w2": 9.0, "c": 0.4, "b": 2.0}, nx=2, x0=[0.5, 0]
                               ).simulate(u, dt=0.05)
    y = y + 0.01 * rng.standard_normal(y.shape)
    s = sysid.NonlinearGreyBox(f, h, {"w2": 8.5, "c": sysid.param(0.1, bounds=(0.0, 0.3)),
                                      "b": sysid.fixed(2.0)}, nx=2, x0=[0.5, 0.0],
                               vectorized=True)
    c = sysid.greyest(sysid.IOData(u=u, y=y, dt=0.05), s).parameters["c"]
    assert c["bound"] == "upper" and c["std"] > 0
    assert c["ci95"] == (pytest.approx(0.3 - z * c["std"], rel=1e-12), 0.3)


def test_an_undetermined_direction_names_every_parameter_it_moves_relatively():
    """The direction a product ``a * b`` leaves free moves ``a`` (1000) by 1000 times more
    than ``b`` (0.002) in absolute terms, the same fraction of each. The warning named ``a``
    alone ("the combination 1*a does not change the fit", untrue without ``b``); it now names
    ``b`` as moved along with it (on a stirred-tank record in the modal form: two entries of
    K and, moved along, the block's frequency, entries of C and the initial state)."""
    u, y = _product_record(1000.0, 0.002)
    s = sysid.GreyBox(_product, {"a": 1500.0, "b": 0.0015})
    with pytest.warns(sysid.IdentifiabilityWarning, match=r"a \(the combination .*\*a, with "
                                                          r"smaller changes of 1 other .*\(b\)"):
        fit = sysid.greyest(sysid.IOData(u=u, y=y, dt=0.05), s, x0="zero")
    assert abs(np.prod(fit.parameters.value) - 2.0) < 0.02
    assert np.all(np.isinf(fit.parameters.std))  # b's was finite: only a's was inf


def test_a_direction_through_parameters_at_zero_names_only_them():
    # with the named parameters at zero (no relative change to compare with), every other
    # parameter met "a comparable fraction" (0 >= 0.05 * 0) and was named and made inf
    from sysid.greybox.results import _warn_unidentifiable

    with pytest.warns(sysid.IdentifiabilityWarning, match=r"separately: a \(the combination "
                                                          r"1\*a does not change the fit\)"):
        weak = _warn_unidentifiable(np.array([[1.0], [0.0], [0.0]]), ["a", "b", "c"],
                                    np.ones(3), np.array([0.0, 1.0, 2.0]))
    assert weak == [0]


def test_a_one_sided_bound_is_written_with_none():
    """param(0.5, bounds=(0.01, None)), SciPy's way of saying "no upper bound", raised
    float()'s TypeError; None is no bound on that side, and a malformed pair is named."""
    p = sysid.param(0.5, bounds=(0.01, None))
    assert p.bounds == (0.01, np.inf)
    assert sysid.param(-2.0, bounds=(None, 0.0)).bounds == (-np.inf, 0.0)
    with pytest.raises(sysid.DataError, match="a pair"):
        sysid.param(0.5, bounds=0.01)
    with pytest.raises(sysid.DataError, match="outside its bounds"):
        sysid.param(0.005, bounds=(0.01, None))


def _motor(p, dt=None):
    """MATLAB's DC-motor grey box: angle and speed, an integrator and a time constant."""
    return ([[0.0, 1.0], [0.0, -1.0 / p.tau]], [[0.0], [p.G / p.tau]], np.eye(2),
            np.zeros((2, 1)))


def test_a_structural_integrator_is_estimated_and_its_std_calibrated():
    # greyest refused MATLAB's DC-motor example ("the predictor A - K C at the initial
    # parameters is unstable"): its pole at s = 0 samples to exactly z = 1. A structure's
    # integrator is admitted (to 1e-9 of the unit circle); 200 records: the first-order std
    # of tau and G within 20 % of the sample std, 95 % intervals covering 90-99 %
    true = sysid.c2d(sysid.ContinuousStateSpace([[0.0, 1.0], [0.0, -2.0]], [[0.0], [4.0]],
                                                np.eye(2)), 0.05)
    rng = np.random.default_rng(1)
    est, sd = [], []
    for _ in range(200):
        u = np.repeat(rng.standard_normal((80, 1)), 5, axis=0)
        y = true.simulate(u) + 0.05 * rng.standard_normal((400, 2))
        g = sysid.greyest(sysid.IOData(u, y, 0.05),
                          sysid.GreyBox(_motor, {"tau": 1.0, "G": 1.0}))
        est.append(g.parameters.to_pandas()["value"].to_numpy())
        sd.append(np.sqrt(np.diag(g.covariance)))
    est, sd = np.array(est), np.array(sd)
    ratio = np.median(sd, axis=0) / est.std(axis=0)
    assert np.all((ratio > 0.8) & (ratio < 1.2)), ratio
    cover = np.mean(np.abs(est - [0.5, 2.0]) <= 1.96 * sd, axis=0)
    assert np.all((cover >= 0.90) & (cover <= 0.99)), cover
    # a start that is truly unstable (tau < 0) is still refused with the fix
    with pytest.raises(DataError, match="unstable"):
        sysid.greyest(sysid.IOData(u, y, 0.05), sysid.GreyBox(_motor, {"tau": -1.0, "G": 1.0}))
