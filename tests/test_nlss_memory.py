"""A nonlinear state-space model that does not forget its initial state (two stable
equilibria for one input) is named by a StabilityWarning; fading-memory fits stay silent."""

import warnings

import numpy as np
import pytest

import sysid
from sysid.nlss.memory import MEMORY_TOLERANCE, check_memory


def _bistable() -> sysid.PNLSSModel:
    # x+ = 0.5 x + 0.75 x^2 - 0.25 x^3 + u: equilibria 0 and 2 stable (slope 0.5), 1 unstable;
    # its linear part (0.5) is stable, so only a simulation from another start shows it
    return sysid.PNLSSModel([[0.5]], [[1.0]], [[1.0]], [[0.0]], [[0.75, -0.25]],
                            np.zeros((1, 0)), zeta=[[0, 0], [0, 0, 0]], eta=[])


def _input(kick: bool) -> np.ndarray:
    u = 0.01 * np.random.default_rng(3).standard_normal((600, 1))
    if kick:
        u[10, 0] = 1.5  # early in the first half: the whole record's run settles at 2
    return u


def test_a_model_with_two_stable_equilibria_is_named() -> None:
    m, u = _bistable(), _input(kick=True)
    y = m.simulate(u)
    assert abs(y[-1, 0] - 2.0) < 0.1 and abs(m.simulate(u[300:])[-1, 0]) < 0.1
    with pytest.warns(sysid.StabilityWarning, match=r"does not forget its initial state.*"
                      r"middle of the record.*another stable behaviour.*sysid.compare"):
        check_memory(m, sysid.IOData(u, y), "pnlss")
    assert m.info["memory"]["difference"][0] > 10 * MEMORY_TOLERANCE
    assert m.info["memory"]["repeats"] == [1]


def test_the_same_model_on_an_input_that_keeps_one_equilibrium_is_silent() -> None:
    m, u = _bistable(), _input(kick=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_memory(m, sysid.IOData(u, m.simulate(u)), "pnlss")
    assert m.info["memory"]["difference"][0] < 1e-3  # the 0.1 % the settling time allows


def test_a_short_record_is_judged_on_its_input_repeated() -> None:
    # 25 samples: the second half (13) leaves 6 after the linear part's 7-sample settling
    # time, too few to compare on; the check repeats the input. Its kick (sample 10) sends the
    # state from 0 to the equilibrium 2 and from 2 (through 3.5) back near 0, so the run from
    # rest and the run from the middle toggle in opposite phase on every copy: never agree
    m = _bistable()
    u = _input(kick=True)[:25]
    with pytest.warns(sysid.StabilityWarning, match=r"middle of the record, its input "
                      r"repeated 2 times end to end"):
        check_memory(m, sysid.IOData(u, m.simulate(u)), "pnlss")
    assert m.info["memory"]["repeats"] == [2]
    assert m.info["memory"]["difference"][0] > 10 * MEMORY_TOLERANCE
    u = _input(kick=False)[:25]  # no kick: both runs stay at 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_memory(m, sysid.IOData(u, m.simulate(u)), "pnlss")
    assert m.info["memory"]["repeats"] == [2]
    assert m.info["memory"]["difference"][0] < MEMORY_TOLERANCE


def test_too_slow_or_unstable_linear_parts_are_not_judged() -> None:
    m, u = _bistable(), _input(kick=False)
    m.A = np.array([[1.0 - 1e-6]])  # 4.6 million samples to settle: beyond MAX_SAMPLES
    check_memory(m, sysid.IOData(u, m.simulate(u)), "pnlss")
    assert m.info["memory"]["difference"] == [None]
    assert m.info["memory"]["repeats"] == [0]
    m.A = np.array([[1.01]])  # warned on its own as an unstable linear part
    check_memory(m, sysid.IOData(u, m.simulate(u)), "pnlss")
    assert m.info["memory"]["difference"] == [None]


def test_the_estimators_record_the_check() -> None:
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, (1500, 1))
    x, y = 0.0, np.zeros((1500, 1))
    for t in range(1500):  # a fading-memory Wiener system
        y[t, 0] = np.tanh(x)
        x = 0.7 * x + u[t, 0]
    d = sysid.IOData(u, y + 0.01 * rng.standard_normal((1500, 1)), 1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sysid.IterationLimitWarning)
        for m in (sysid.pnlss(d, 1, degree=3, max_iter=10, progress=False),
                  sysid.pnlss(d, 1, degree=3, branches=2, max_iter=5, progress=False),
                  sysid.nlssest(d, 1, hidden=4, epochs=3, progress=False)):
            diff = m.info["memory"]["difference"]
            assert len(diff) == 1 and diff[0] is not None and diff[0] < MEMORY_TOLERANCE


def _quintic(s: float) -> sysid.PNLSSModel:
    # x+ = 0.5 x + s (0.75 x^3 - 0.25 x^5) + u: for s = 1 a second stable equilibrium at
    # sqrt(2) (slope 0) beside 0; for s <= 0.8 the only one is 0
    return sysid.PNLSSModel([[0.5]], [[1.0]], [[1.0]], [[0.0]], [[0.75 * s, -0.25 * s]],
                            np.zeros((1, 0)), zeta=[[0, 0, 0], [0, 0, 0, 0, 0]], eta=[])


def _pulse() -> np.ndarray:
    u = np.zeros((400, 1))
    u[:5] = 0.6  # takes the s = 1 model's whole-record run to sqrt(2), where it stays
    return u


def test_latest_forgetting_finds_the_last_iterate_that_forgets() -> None:
    from sysid.nlss.memory import differences, forgets, latest_forgetting

    u = _pulse()
    data = sysid.IOData(u, _quintic(0.0).simulate(u))
    ladder = np.linspace(0.0, 1.0, 41)[:, None]  # iterates s = 0, 0.025, ..., 1
    verdict = [forgets(differences(_quintic(s), data)[0]) for s in ladder[:, 0]]
    assert verdict[0] and not verdict[-1]
    k, m, d = latest_forgetting(lambda th: _quintic(th[0]), ladder, data)
    # the grid (stride 5) and the bisection after it find the exact last one that forgets
    last = max(i for i, v in enumerate(verdict) if v)
    assert all(not v for v in verdict[last + 1:])  # a clean switch on this ladder
    assert k == last and forgets(d[0]) and m.E[0, 0] == pytest.approx(0.75 * ladder[k, 0])
    # none forgets: None; one iterate: itself when it forgets
    assert latest_forgetting(lambda th: _quintic(th[0]), ladder[-3:], data) is None
    assert latest_forgetting(lambda th: _quintic(th[0]), ladder[:1], data)[0] == 0


def test_pnlss_returns_the_latest_iterate_that_forgets_with_a_warning(tmp_path) -> None:
    from sysid.nlss.pnlss import _forgetting

    u = _pulse()
    data = sysid.IOData(u, _quintic(0.0).simulate(u))
    ladder = np.linspace(0.0, 1.0, 11)[:, None]
    history = list(np.linspace(10.0, 1.0, 11))
    res = {"theta": ladder[-1], "iterates": ladder, "history": history}

    def build(th: np.ndarray) -> sysid.PNLSSModel:
        m = _quintic(th[0])
        m.info = {"fit": {"cost": history}}
        return m

    with pytest.warns(sysid.StabilityWarning, match=r"last model \(iteration 10, cost 1\) does "
                      r"not forget.*returned the model of iteration 9 \(cost 1\.9\)"):
        m = _forgetting(build, res, data)
    assert m.E[0, 0] == pytest.approx(0.75 * 0.9)
    ret = m.info["fit"]["returned"]
    assert ret["iteration"] == 9 and ret["cost"] == pytest.approx(1.9)
    assert ret["last_cost"] == 1.0 and ret["last_difference"] > 10 * MEMORY_TOLERANCE
    assert m.info["memory"]["difference"][0] < MEMORY_TOLERANCE
    sysid.save_model(m, tmp_path / "m.json")  # what it returned is kept with the model
    back = sysid.load_model(tmp_path / "m.json")
    assert back.info["fit"]["returned"] == ret
    np.testing.assert_array_equal(back.simulate(u), m.simulate(u))
    # a last iterate that forgets is returned as it is, silently
    res = {"theta": ladder[5], "iterates": ladder[:6], "history": history[:6]}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m = _forgetting(build, res, data)
    assert m.E[0, 0] == pytest.approx(0.75 * 0.5) and "returned" not in m.info["fit"]


@pytest.mark.parametrize("branches", [None, 2])
def test_the_fits_iterates_follow_their_cost_history(branches: int | None,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    # row k of the report's iterates is the model whose training cost is history[k]: the
    # simulation error in engineering units over the cost's samples is one fixed multiple of
    # the (scaled) cost for every row, the start's row and, for the decoupled fit, the rows of
    # its best start's path and of that path's continuation alike
    from sysid.nlss import decoupled
    from sysid.nlss import pnlss as pn

    rng = np.random.default_rng(1)
    u = rng.uniform(-1, 1, (800, 1))
    x, y = 0.0, np.zeros((800, 1))
    for t in range(800):
        y[t, 0] = x + 0.3 * x ** 2
        x = 0.6 * x + u[t, 0]
    data = sysid.IOData(u, y + 0.02 * rng.standard_normal((800, 1)), 1.0)
    seen = {}

    def spy(build, res, d, startup=None):  # the glue's inputs, kept
        seen.update(build=build, res=res)
        return build(np.asarray(res["theta"]))

    monkeypatch.setattr(pn, "_forgetting", spy)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sysid.IterationLimitWarning)
        sysid.pnlss(data, 1, degree=[2], branches=branches, max_iter=decoupled.STARTS_ITER + 4,
                    progress=False)
    res, build = seen["res"], seen["build"]
    its, hist = res["iterates"], res["history"]
    assert its.shape[0] == len(hist) and np.array_equal(its[-1], res["theta"])
    transient = build(its[-1]).info["fit"]["transient"][0]
    sse = np.array([np.sum((build(th).simulate(u)[transient:] - data.y[transient:]) ** 2)
                    for th in its])
    ratio = sse / np.asarray(hist)
    assert np.allclose(ratio, ratio[0], rtol=1e-6), ratio


def test_a_quick_verdict_stops_at_the_first_experiment_that_fails() -> None:
    from sysid.nlss.memory import differences

    m = _bistable()
    quiet, kicked = _input(kick=False), _input(kick=True)
    data = sysid.IOData([quiet, kicked], [m.simulate(quiet), m.simulate(kicked)], 1.0)
    full = differences(m, data)
    assert full[0][0] < MEMORY_TOLERANCE < full[0][1] and full[1] == [1, 1]
    # the failing experiment first: the other is not simulated
    assert differences(m, data, order=[1, 0], quick=True) == ([None, full[0][1]], [0, 1])
    # in the data's order every experiment up to the failing one is, and the result agrees
    assert differences(m, data, quick=True) == full
