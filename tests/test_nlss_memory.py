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
