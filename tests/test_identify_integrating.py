"""identify's candidates with an integrator made explicit (sysid.identify.integrating)."""

import warnings

import numpy as np

import sysid
from sysid.identify.board import free_poles
from sysid.identify.integrating import CRITERION, differenced, integrated

PLANT = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0], [0.5]], [[0.3, 0.1]])


def _heading(seed: int, n: int = 900) -> tuple[sysid.IOData, sysid.IOData]:
    """Random steps -> a rate (second order) and the heading that sums it; the rate is offset
    by a bias the input does not explain (a rudder whose neutral is not the input's mean),
    so the heading also ramps; noise of 5 % of each output's spread. Two thirds estimate,
    the last third validates."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.standard_normal(n // 8 + 1), 8)[:n]
    r = PLANT.simulate(u).ravel()
    y = np.cumsum(r + 0.3 * np.std(r))
    Y = np.c_[r + 0.05 * np.std(r) * rng.standard_normal(n),
              y + 0.05 * np.std(y) * rng.standard_normal(n)]
    k = 2 * n // 3
    return sysid.IOData(u=u[:k], y=Y[:k]), sysid.IOData(u=u[k:], y=Y[k:])


def test_an_integrated_model_sums_the_increments_of_the_differenced_output():
    rng = np.random.default_rng(0)
    u = rng.standard_normal(50)
    rate = sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0], [0.5]], [[0.0], [0.2]])
    m = integrated(rate, [1])
    y, z = m.simulate(u), rate.simulate(u)
    assert np.allclose(y[:, 0], z[:, 0])  # the other output as it was
    assert np.allclose(y[1:, 1], np.cumsum(z[:-1, 1]))  # y(t+1) - y(t) = the increment
    assert y[0, 1] == 0.0
    assert not m.is_stable() and np.allclose(np.sort(np.abs(m.poles())), [0.7, 1.0])
    assert np.allclose(free_poles(m), [0.7])
    d = differenced(sysid.IOData(u=u, y=y), [1])
    assert np.allclose(d.y[:, 1], np.diff(y[:, 1])) and np.allclose(d.y[:, 0], y[:-1, 0])


def test_an_integrating_output_that_looks_like_a_drift_gets_its_integrator():
    # the heading ramps with the rate's bias: the unstable subspace fits win every held-out
    # block, but not once a line per channel is taken out (which removes part of the summed
    # response too), and the drift verdict returned a stable model without the integrator:
    # validation -0.7 %. A model of the rate and the heading's increments, the heading
    # summed back (a pole at exactly 1), beats the best stable candidate on every block with
    # the drift left in and taken out, and is returned
    est, val = _heading(1)
    with warnings.catch_warnings():
        warnings.simplefilter("error", sysid.StabilityWarning)  # a pole at 1 is no divergence
        res = sysid.identify(est, val, progress=False)
    m = res.model.statespace
    assert m.info["integrating"]["outputs"] == [1]
    assert "y1 integrate" in res.checks["integrating"]
    assert "integrator on y1" in repr(res.model) and "UNSTABLE" not in repr(res.model)
    assert "persistent_mode" not in res.checks  # the pinned pole is said as an integrator
    assert np.sum(np.isclose(m.poles(), 1.0)) == 1 and np.all(np.abs(free_poles(m)) < 1.0)
    assert res.validation_fit > 30.0
    assert "integrator is returned" in res.checks["drift"]
    p, s = m.poles(std=True)  # an uncertainty, from the simulation error at it
    assert np.all(np.isfinite(s))
    assert "(integrating)" in res.summary()


def test_a_drift_the_input_does_not_explain_keeps_its_stable_model():
    # a stable first-order plant whose output drifts by a line (the case of
    # test_identify_trust.py): the integrating candidates are scored, but the best of them
    # does not beat the best stable candidate once the drift is taken out: held back, the
    # choice as before them (a slow mode fitted to a drift is not an integrator)
    rng = np.random.default_rng(2)
    u = rng.standard_normal((400, 1))
    t = np.arange(400.0)[:, None]
    y = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]]).simulate(u) + 0.05 * t + 100.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(sysid.IOData(u=u + 0.01 * t,
                                          y=y + 0.01 * rng.standard_normal((400, 1))),
                             progress=False)
    rows = [r for r in res.leaderboard if r["criterion"] == CRITERION]
    assert rows and all(r.get("start_only") and "drift" in r["note"] for r in rows)
    assert "drift" in res.checks and "integrating" not in res.checks
    assert res.model.is_stable()


def test_no_integrating_candidates_when_no_unstable_candidate_wins():
    rng = np.random.default_rng(3)
    u = rng.standard_normal((600, 1))
    y = PLANT.simulate(u) + 0.02 * rng.standard_normal((600, 1))
    res = sysid.identify(sysid.IOData(u=u, y=y), refine=False, progress=False)
    assert not any(r["criterion"] == CRITERION for r in res.leaderboard)


def test_a_search_from_an_integrating_model_does_not_keep_its_pinned_integrator_mark():
    # pem frees every pole: its result is no longer built with an integrator, and identify's
    # reading of it (free_poles, the uncertainty's criterion) must not take it for one
    rng = np.random.default_rng(1)
    u = rng.standard_normal(300)
    start = integrated(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), [0])
    y = start.simulate(u) + 0.01 * rng.standard_normal((300, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the search creeps along the stability bound
        m = sysid.pem(sysid.IOData(u=u, y=y), start, focus="simulation", max_iter=3,
                      progress=False)
    assert "integrating" not in m.info and "integrating" in start.info
    assert len(free_poles(m)) == 2
