"""A search stopped at its cap says how far it stood from the minimum it was heading for,
and is silent when that is well inside the estimate's own uncertainty (issue 26: warnings
that do not matter erode the ones that do). The optimiser reports the Gauss-Newton
predicted decrease at the result in residual variances (``remaining_decrease``); twice it
is the squared distance to that minimum in standard deviations of the estimate. On the
unshipped DaISy dryer2 record, ``ssest(data)`` stopped at its cap 0.44 standard deviations
short (the rest of the way, 24 iterations, lowered the likelihood by 0.09) and warned."""
import warnings

import numpy as np
import pytest

import sysid
from sysid._checks import DISTANT, NEGLIGIBLE_REMAINING, warn_if_capped


def _record() -> sysid.IOData:
    rng = np.random.default_rng(1)
    n = 2000
    u = rng.standard_normal((n, 1))
    true = sysid.StateSpaceModel([[1.5, -0.7], [1.0, 0.0]], [[1.0], [0.0]], [[0.3, 0.2]])
    return sysid.IOData(u=u, y=true.simulate(u) + 0.1 * rng.standard_normal((n, 1)))


def _poor_start(data: sysid.IOData, a: float = 0.9, b: float = 0.5) -> sysid.StateSpaceModel:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        start = sysid.n4sid(data, 2)
    return sysid.StateSpaceModel(a * start.A, b * start.B, start.C, dt=start.dt)


def test_the_remaining_decrease_predicts_the_rest_of_the_way():
    data = _record()
    n = sum(data.lengths)
    for cap in (1, 2, 3, 4):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            m = sysid.pem(data, _poor_start(data), focus="simulation", max_iter=cap)
            end = sysid.pem(data, m, focus="simulation", max_iter=200)
        info = m.info["pem"]
        assert info["stop"] == "maximum iterations"
        # the criterion is the sum of squares: the residual variance of the capped fit is
        # cost / n; its decrease to the end, in those variances, is what was predicted
        # (about 900, 260, 74 and 22 here, each within 4 % of the search that went on)
        before, after = info["cost"][-1], end.info["pem"]["cost"][-1]
        actual = (before - after) / (before / n) / 2.0
        predicted = info["remaining_decrease"]
        assert np.isfinite(predicted) and predicted > 0
        assert abs(actual / predicted - 1) < 0.1, (cap, predicted, actual)
    assert np.isnan(end.info["pem"]["remaining_decrease"])  # converged: not capped


def test_a_capped_search_warns_exactly_when_it_stops_far_enough():
    # from A scaled by 0.95 the search stands about 320, 2.1 and 0.12 residual variances
    # short of its minimum after 1, 2 and 3 iterations: the third is not warned about
    data = _record()
    for cap in (1, 2, 3):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            m = sysid.pem(data, _poor_start(data, 0.95, 1.0), focus="simulation",
                          max_iter=cap)
        if m.info["pem"]["stop"] != "maximum iterations":
            continue
        capped = [w for w in caught if w.category is sysid.IterationLimitWarning]
        r = m.info["pem"]["remaining_decrease"]
        assert len(capped) == int(r >= NEGLIGIBLE_REMAINING), (cap, r)


def test_a_capped_search_far_from_its_minimum_says_how_far():
    data = _record()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = sysid.pem(data, _poor_start(data), focus="simulation", max_iter=1)
    capped = [str(w.message) for w in caught if w.category is sysid.IterationLimitWarning]
    r = m.info["pem"]["remaining_decrease"]
    assert r >= NEGLIGIBLE_REMAINING
    assert len(capped) == 1
    assert f"about {np.sqrt(2 * r):.2g} standard deviations of the estimate away" in capped[0]


@pytest.mark.parametrize("remaining,warned", [(0.05, False), (NEGLIGIBLE_REMAINING, True),
                                              (2.0, True), (float("nan"), True), (None, True)])
def test_a_cap_within_half_a_standard_deviation_is_not_warned_about(remaining, warned):
    # the last iteration still lowered the cost by 10 %: by the cost alone it had not settled
    info = {"stop": "maximum iterations", "cost": [10.0, 5.0, 4.5]}
    if remaining is not None:
        info["remaining_decrease"] = remaining
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warn_if_capped(info, "the search", 2)
    assert len(caught) == int(warned)
    if warned and remaining is not None and np.isfinite(remaining):
        assert f"about {np.sqrt(2 * remaining):.2g} standard deviations" in str(caught[0].message)


def test_a_polynomial_search_capped_at_its_minimum_is_not_warned_about():
    # oe from its ARX start converges in one iteration here; capped there, its last
    # iteration still lowered the cost by 0.003 % (more than the 0.001 % that counts as
    # settled) and it warned, though the rest of the way was 1e-5 residual variances
    rng = np.random.default_rng(0)
    u = rng.standard_normal(500)
    y = np.convolve(u, [0.0, 0.5, 0.3, 0.1])[:500] + 0.1 * rng.standard_normal(500)
    data = sysid.IOData(u=u, y=y)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = sysid.oe(data, 2, 2, 1, max_iter=1)
    assert m.info["stop"] == ["maximum iterations"]
    assert m.info["remaining_decrease"][0] < NEGLIGIBLE_REMAINING
    assert not [w for w in caught if w.category is sysid.IterationLimitWarning]


def test_a_capped_grey_box_search_says_how_far_it_stands():
    # the grey-box search runs through a change of parameters that now passes on the
    # residual count: it reports the distance, as pem does (it was NaN)
    def motor(p, dt=None):
        return [[-1.0 / p.tau]], [[p.K / p.tau]], [[1.0]], [[0.0]]
    u = np.sign(np.sin(np.arange(400) * 0.05))
    y = sysid.GreyBox(motor, {"K": 2.0, "tau": 0.3}).model(dt=0.05).simulate(u)
    y = y + 0.02 * np.random.default_rng(0).standard_normal(y.shape)
    data = sysid.IOData(u=u, y=y, dt=0.05)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        short = sysid.greyest(data, sysid.GreyBox(motor, {"K": 1.0, "tau": 1.0}), max_iter=1)
    r = short.info["remaining_decrease"]
    assert short.info["stop"] == "maximum iterations" and r >= NEGLIGIBLE_REMAINING
    capped = [str(w.message) for w in caught if w.category is sysid.IterationLimitWarning]
    assert len(capped) == 1
    assert f"about {np.sqrt(2 * r):.2g} standard deviations of the estimate away" in capped[0]


def test_each_output_s_own_distance_decides_and_a_flat_history_is_read_as_one():
    # per-output searches (oe on two outputs): the capped output's distance is the one read,
    # whether or not the costs come one history per output
    capped = {"stop": ["converged", "maximum iterations"], "remaining_decrease": [5.0, 0.01]}
    for cost in ([[3.0, 2.0], [10.0, 5.0, 4.5]], [10.0, 5.0, 4.5], []):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            warn_if_capped({**capped, "cost": cost}, "the search", 2, n_residuals=100)
        assert not caught, cost


def _saturating_record(seed: int) -> sysid.IOData:
    # a 2-state plant between tanh and the output, 600 samples
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, (600, 1))
    x, y = np.zeros(2), np.zeros((600, 1))
    for t, w in enumerate(np.tanh(2 * u[:, 0])):
        y[t] = x[0]
        x = np.array([[0.8, 0.2], [-0.2, 0.7]]) @ x + np.array([0.0, 1.0]) * w
    return sysid.IOData(u, y + 0.01 * rng.standard_normal(y.shape), 1.0)


def test_a_settled_network_search_is_not_warned_about_whatever_its_distance():
    # a sigmoid network's search is flat and ill-conditioned: the default nlhw, capped at 100
    # iterations, stood about 2 residual variances from its Gauss-Newton model's minimum,
    # yet the rest of the way to its own convergence lowered the cost by far less (0.009);
    # its last steps had settled, and that decides. (Seeds 1, 4, 5 of this plant sit on a
    # plateau at the cap, settled by every rule, and leave it hundreds of iterations later,
    # 1.2-2.6 residual variances lower: the rule's known miss, benches/results/nonlinear.md,
    # 2026-12-05; seed 0 is warned about, the test below. Seed 3 is the settled case.)
    data = _saturating_record(3)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        capped = sysid.nlhw(data, 2, 2, 1, progress=False)
        # its own convergence (a far larger cap lets another start's longer search win)
        done = sysid.nlhw(data, 2, 2, 1, progress=False, max_iter=400)
    assert capped.info["stop"] == "maximum iterations"
    assert capped.info["remaining_decrease"] >= NEGLIGIBLE_REMAINING
    assert done.info["stop"] != "maximum iterations"
    variance = 2 * capped.info["cost"][-1] / 600
    assert (capped.info["cost"][-1] - done.info["cost"][-1]) / variance < NEGLIGIBLE_REMAINING
    assert not [w for w in caught if w.category is sysid.IterationLimitWarning]


def _crawling_history(drop: float) -> list[float]:
    # 101 costs of 1 000 residuals at a residual variance of 1 (cost 500): a last step of
    # 0.001 variances, settled by itself, after the ten before it fell by ``drop`` variances
    tail = [500.0 + drop * (10 - k) / 10 for k in range(11)]
    tail[-2] = tail[-1] + 0.001
    return [600.0 - k for k in range(90)] + tail


@pytest.mark.parametrize("drop,warned", [(0.02, False), (1.9, True)])
def test_a_small_last_step_after_a_recent_drop_is_warned_about(drop, warned):
    # the last step alone read a search leaving a plateau as settled: an nlhw network capped
    # at 100 iterations whose last ten had lowered the cost by 1.9 residual variances went
    # on 3.4 variances lower (issue 26: stopping short warns); a crawl of 0.02 over ten is
    # settled
    info = {"stop": "maximum iterations", "cost": _crawling_history(drop),
            "remaining_decrease": 2.0}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warn_if_capped(info, "the search", 100, n_residuals=1000)
    assert len(caught) == int(warned)
    if warned:
        assert "the last 10 by" in str(caught[0].message)


def test_an_nlhw_search_leaving_a_plateau_at_its_cap_is_warned_about():
    # the seed-0 record of the settled test above: the last step lowered the cost by 0.006
    # residual variances, the ten before it by 1.9, and the search converges 3.4 lower
    data = _saturating_record(0)
    with pytest.warns(sysid.IterationLimitWarning, match="the last 10 by"):
        capped = sysid.nlhw(data, 2, 2, 1, progress=False)
    assert capped.info["stop"] == "maximum iterations"


@pytest.mark.parametrize("remaining,warned", [(2.5, False), (DISTANT, True), (9.5, True)])
def test_a_settled_history_far_from_the_gauss_newton_minimum_is_warned_about(remaining, warned):
    # a crawling polynomial search (bj on a heat exchanger, oe on a CD player arm: steps of
    # 1e-6 of the cost, settled by every history rule) stood 5.7 and 9.5 residual variances
    # from its Gauss-Newton model's minimum and went on to costs 0.18 % and 1.15 % lower:
    # three standard deviations or more away is warned about; a network's flat 2.5 is not
    info = {"stop": "maximum iterations", "cost": _crawling_history(0.02),
            "remaining_decrease": remaining}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warn_if_capped(info, "the search", 100, n_residuals=1000)
    assert len(caught) == int(warned)
    if warned:
        assert f"about {np.sqrt(2 * remaining):.2g} standard deviations" in str(caught[0].message)
