"""``order="auto"`` of the subspace estimators and ``ssest`` at their defaults (issue 26 item
3): the order and the feedthrough chosen together by held-out simulation fit, and an order
whose model is unstable only when the data insist.

Each rule has a test that fails without it: on a simulated plant with a direct term, on the
shipped winding record (DaISy split: first 2/3 / last 1/3, its estimation means removed) and
on the shipped F-16 level-1 record (benches/realdata.py's split: periods 2-3 for estimation,
period 2 of the level-2 validation record).
"""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.validation.crossval import cross_validated_order, stable_first

from conftest import daisy_split, feedthrough_record, quiet


def validation_fit(model, val):
    return float(quiet(sysid.compare, model, val).mean_fit)


# -- feedthrough="auto" in the automatic path ----------------------------------------------
@pytest.mark.parametrize("name", ["n4sid", "moesp", "cva", "ssest"])
def test_order_auto_chooses_the_feedthrough_with_the_order(name):
    """Before: ``order="auto"`` kept ``D = 0`` (the given-order default), so a plant with a
    direct term got none."""
    fit = getattr(sysid, name)
    m = quiet(fit, feedthrough_record(0.8))
    assert abs(m.D[0, 0] - 0.8) < 0.05, m.D
    sel = m.info["feedthrough_selection"]
    assert sel["feedthrough"] and "with D" in sel["reason"]
    # the given-order default and an explicit choice are kept
    assert np.all(quiet(fit, feedthrough_record(0.8), 2).D == 0)
    assert np.all(quiet(fit, feedthrough_record(0.8), feedthrough=False).D == 0)


def test_order_auto_takes_no_spurious_feedthrough():
    m = quiet(sysid.moesp, feedthrough_record(0.0))
    assert np.all(m.D == 0) and not m.info["feedthrough_selection"]["feedthrough"]


@pytest.mark.parametrize("name", ["n4sid", "moesp", "cva"])
def test_default_subspace_fits_hold_up_on_the_winding_record(name):
    """Before: 66.7, 62.3 and 69.3 % on the validation part (no D at the automatic order);
    with D chosen with the order 75-76 %, as the best of the plain reference's grid."""
    est, val = daisy_split("winding")
    m = quiet(getattr(sysid, name), est)
    assert m.info["feedthrough_selection"]["feedthrough"]
    assert validation_fit(m, val) > 72.0, m.info["order_selection"]


# -- an unstable order only when the data insist -------------------------------------------
def f16_level1():
    d = sysid.datasets.load_f16()
    v = sysid.datasets.load_f16_level2()
    est = sysid.IOData(u=d.u[8192:3 * 8192], y=d.y[8192:3 * 8192])
    val = sysid.IOData(u=v.u[:8192], y=v.y[:8192])
    mu, my = est.u.mean(0), est.y.mean(0)
    return (sysid.IOData(u=est.u - mu, y=est.y - my), sysid.IOData(u=val.u - mu, y=val.y - my))


def test_default_cva_on_the_f16_is_stable_and_validates():
    """Before: order 19, a pole of modulus 1.006 (with or without D), validation fit below
    -999 %: the held-out blocks (a fifth of the record) score what the unstable mode does
    over a block, the longer validation record sees it grow. (With the channel scaling the
    choice is order 1, held-out 18.1 %, validation 17.2 %; in the record's units,
    ``scale=False``, order 18, held-out 27.0 %, validation 28.7 %: CVA's B and D differ with
    the output weighting, and this record is one where the raw units did better.)"""
    est, val = f16_level1()
    m = quiet(sysid.cva, est)
    assert np.max(np.abs(m.poles())) < 1.0, m.info["order_selection"]
    assert validation_fit(m, val) > 15.0


def test_an_unstable_order_is_kept_when_the_data_insist():
    """An integrating plant: the models of every order have a pole at 1 (a hair outside the
    unit circle); the rule must not push the choice to an order that cannot follow it."""
    rng = np.random.default_rng(3)
    true = sysid.StateSpaceModel([[1.0, 0.1], [0.0, 0.6]], [[0.0], [1.0]], [[1.0, 0.0]])
    u = rng.standard_normal((1500, 1))
    y = true.simulate(u) + 0.01 * rng.standard_normal((1500, 1))
    est = quiet(sysid.SubspaceEstimator, sysid.IOData(u=u, y=y))
    c = quiet(cross_validated_order, est.data, sysid.SubspaceEstimator, whole=est)
    assert c.order == 2 and "left out" not in c.reason.split("(")[0]
    m = quiet(est.fit, c.order, feedthrough=False)
    assert np.isclose(np.max(np.abs(m.poles())), 1.0, atol=0.01)


def test_stable_first_keeps_every_order_without_a_stable_one():
    folds = {1: [10.0, 12.0, 11.0], 2: [20.0, 25.0, 22.0]}
    score = {n: float(np.median(v)) for n, v in folds.items()}
    # no stable order: every one stays, and the reason says the choice is among unstable ones
    # (n4sid on an industrial robot record chose order 16, unstable, with nothing said of the
    # other orders, all unstable on the whole record as well)
    allowed, why = stable_first(score, folds, {1, 2})
    assert allowed == {1, 2} and "no order gave a model stable" in why
    allowed, why = stable_first(score, folds, {2})
    # order 2 wins on every block: insisted on, and the reason says so (n4sid's order 13 on
    # the robot arm, |pole| 1.033, was chosen with only the orders left out named)
    assert allowed == {1, 2} and "order(s) 2 unstable but kept" in why
    assert "best stable order (1)" in why and "whole record" not in why
    folds[2][1] = 5.0
    allowed, why = stable_first(score, folds, {2})
    assert allowed == {1} and "2 left out" in why



def test_stable_first_holds_an_insisted_unstable_order_to_the_whole_record():
    """An unstable order that wins every held-out block (its fitted initial state holds the
    unstable mode back over a block) is left out when its model simulates the whole record
    worse than the best stable order's: on a DC-DC converter record (not shipped) n4sid's
    order 16 (a pole of modulus 1.067, a factor 1e28 over its 1 000 samples) won every block
    and validated -inf; order 5 validated 47 %. The blocks' fits below are that record's."""
    folds = {5: [68.5, 56.4, 72.0, 82.9, 79.8], 16: [78.3, 68.8, 74.0, 84.7, 85.5]}
    score = {n: float(np.median(v)) for n, v in folds.items()}
    assert stable_first(score, folds, {16})[0] == {5, 16}  # the blocks alone insist on it
    whole = {5: 76.6, 16: -4.7e14}
    allowed, why = stable_first(score, folds, {16}, whole.get)
    assert allowed == {5} and "16 left out" in why and "whole record worse" in why
    whole[16] = 77.0  # a model that follows the whole record (an unstable plant): kept
    allowed, why = stable_first(score, folds, {16}, whole.get)
    assert allowed == {5, 16} and "16 unstable but kept" in why and "whole record" in why
    # no stable order: the choice is among the unstable ones that simulate the whole record
    # better than its mean, when any does
    allowed, why = stable_first(score, folds, {5, 16}, {5: 61.0, 16: -4.7e14}.get)
    assert allowed == {5} and "order(s) 16 do not" in why
    assert stable_first(score, folds, {5, 16}, {5: -3.0, 16: -4.7e14}.get)[0] == {5, 16}


def test_cva_order_auto_on_the_ball_and_beam_simulates_its_own_record():
    """Shipped ball and beam (an integrating plant), first 2/3 estimated, last 1/3
    validated. Before: CVA's automatic order 3 (|pole| 1.12) beat the best stable order on
    every held-out block and was taken; over the whole record its mode grows by 1e33, its
    simulation of its own record scored -7e18 % and the validation -1314 %. Now that order
    is left out (it simulates the whole record worse than the best stable order) and the
    choice is an unstable order that follows the record: order 5, |pole| 1.026, 90.7 %."""
    from sysid.validation.crossval import simulation_fit

    d = sysid.datasets.load_ballbeam()
    k = (2 * d.n_samples) // 3
    mu, my = d.u[:k].mean(0), d.y[:k].mean(0)
    est = sysid.IOData(u=d.u[:k] - mu, y=d.y[:k] - my, dt=d.dt)
    val = sysid.IOData(u=d.u[k:] - mu, y=d.y[k:] - my, dt=d.dt)
    m = quiet(sysid.cva, est)
    why = m.info["order_selection"]["reason"]
    assert "simulating the whole record worse than the best stable order" in why
    assert simulation_fit(m, est) > 50.0
    assert validation_fit(m, val) > 80.0
    # n4sid: no order's model is stable on the whole record; before, order 4 (|pole| 1.075,
    # its own record simulated at -4e6 %, validated 77.9 %); now among the orders that
    # simulate the record: order 3, 87.4 %
    m = quiet(sysid.n4sid, est)
    assert "that simulate the whole record better than its mean" in m.info[
        "order_selection"]["reason"]
    assert simulation_fit(m, est) > 50.0 and validation_fit(m, val) > 85.0

# -- ssest: the refined models confirm D ---------------------------------------------------
def test_ssest_keeps_d_only_when_the_refined_models_confirm_it():
    """pH record, estimated on its last 2/3 and validated on the first 1/3
    (benches/realdata.py --split reversed). The subspace models' held-out fits favour D
    (22.0 % against 16.6 %); refined (prediction focus) the model with D simulates its own
    record no better than the one without and has the higher BIC. Without the check: 25.0 %
    on the validation part; with it 37.1 %."""
    d = np.loadtxt(sysid.datasets.path("ph"))
    u, y = d[:, [1, 2]], d[:, [3]]
    k = u.shape[0] - (2 * u.shape[0]) // 3
    mu, my = u[k:].mean(0), y[k:].mean(0)
    est = sysid.IOData(u=u[k:] - mu, y=y[k:] - my)
    val = sysid.IOData(u=u[:k] - mu, y=y[:k] - my)
    m = quiet(sysid.ssest, est)
    sel = m.info["feedthrough_selection"]
    assert np.all(m.D == 0) and not sel["feedthrough"], sel
    assert sel["refined_bic"]["with D"] > sel["refined_bic"]["without D"]
    assert validation_fit(m, val) > 30.0


# -- ssest with a sequence of orders: the BIC of the refined models -------------------------
def test_ssest_with_a_range_of_orders_holds_up_on_the_winding_record():
    """Before: every order refined on the first 2/3 and scored on the last 1/3, and no D:
    order 1-2, 50-51 % on the validation part; the BIC of the models refined on the whole
    record (D chosen as with order="auto"): order 4, 74 %."""
    est, val = daisy_split("winding")
    m = quiet(sysid.ssest, est, order=range(1, 11))
    sel = m.info["order_selection"]
    assert sel["criterion"] == "BIC of refined models" and sorted(sel["table"]) == list(
        range(1, 11))
    assert sel["table"][m.nstates] == min(sel["table"].values())
    assert validation_fit(m, val) > 70.0, sel


@pytest.mark.parametrize("name", ["n4sid", "moesp", "cva"])
def test_a_sequence_of_orders_is_chosen_among(name):
    """MATLAB's ``n4sid(data, 1:10)``: the subspace estimators take a sequence of orders as
    ``ssest`` does, and choose among them by the held-out fit of ``order="auto"`` (they
    raised "order must be a positive integer, got range(1, 11)")."""
    rng = np.random.default_rng(2)
    true = sysid.StateSpaceModel([[0.9, 0.3, 0], [-0.3, 0.9, 0], [0, 0, 0.5]],
                                 [[1.0], [0.0], [1.0]], [[1.0, 0.5, 1.0]])
    u = rng.standard_normal(1500)
    data = sysid.IOData(u=u, y=true.simulate(u) + 0.05 * rng.standard_normal((1500, 1)))
    fit = getattr(sysid, name)
    m = quiet(fit, data, range(1, 11))
    assert m.nstates == 3 and sorted(m.info["order_selection"]["table"]) == list(range(1, 11))
    m = quiet(fit, data, [1, 2, 5])  # only these: the best of them
    assert m.nstates in (1, 2, 5) and sorted(m.info["order_selection"]["table"]) == [1, 2, 5]
    with pytest.raises(sysid.DataError, match="empty"):
        fit(data, [])
    with pytest.raises(sysid.OrderError, match="too large"):
        fit(data, [500, 600])


@pytest.mark.parametrize("method", ["n4sid", "moesp", "cva"])
def test_time_series_auto_order_is_cross_validated_on_prediction(method):
    # A 4-state time series (poles 0.9 and 0.7, a stable predictor). The singular-value gap
    # took order 19 for n4sid/moesp (whose Kalman gain then had no stabilising Riccati
    # solution) and 1 for cva; held-out one-step prediction takes the true order, and the
    # model predicts fresh data as well as the true one.
    from sysid.validation.crossval import prediction_fit

    rng = np.random.default_rng(7)
    p, q = 0.9 * np.exp(0.3j), 0.7 * np.exp(1.2j)
    A = np.zeros((4, 4))
    A[:2, :2] = [[p.real, p.imag], [-p.imag, p.real]]
    A[2:, 2:] = [[q.real, q.imag], [-q.imag, q.real]]
    K, C = np.array([[0.5], [0.2], [0.4], [-0.1]]), np.array([[1.0, 0.0, 1.0, 0.0]])
    y = sysid.StateSpaceModel(A, K, C, np.eye(1)).simulate(rng.standard_normal((7000, 1)))
    true = sysid.StateSpaceModel(A, np.zeros((4, 0)), C, np.zeros((1, 0)), K, dt=1.0)
    fresh = sysid.IOData(y=y[4000:])
    m = sysid.SubspaceEstimator(sysid.IOData(y=y[:4000]), method=method).fit("auto")
    sel = m.info["order_selection"]
    assert sel["criterion"] == "cross-validated one-step prediction fit", sel
    assert m.nstates == 4, sel
    assert prediction_fit(m, fresh) > prediction_fit(true, fresh) - 0.5


def test_a_held_out_block_whose_outputs_stand_still_scores_without_a_numpy_warning():
    # DaISy's flutter record (not shipped; benches/realdata.py reads it) ends in 225
    # samples of one held value (the logger ran on), and its reversed split estimates on
    # them: `ssest(data, focus="simulation")` showed
    # NumPy's "Mean of empty slice" 33 times, from the held-out score of a block where the
    # output stands still (no fit: it divides by the block's variation). Such a block still
    # scores -inf for every candidate (the order choice is unchanged), now without a warning
    # (warnings are errors here); an output that stands still beside one that moves is
    # left out of the block's mean fit, as before.
    from sysid.validation.crossval import simulation_fit

    rng = np.random.default_rng(1)
    plant = sysid.StateSpaceModel([[0.8, 0.3], [-0.3, 0.8]], [[1.0], [0.5]], [[1.0, 0.0]],
                                  dt=1.0)
    u = rng.standard_normal((300, 1))
    y = plant.simulate(u)
    still = sysid.IOData(u=u, y=np.zeros((300, 1)))
    assert simulation_fit(plant, still) == -np.inf
    two = sysid.StateSpaceModel(plant.A, plant.B, np.vstack([plant.C, 0 * plant.C]), dt=1.0)
    one_moves = sysid.IOData(u=u, y=np.hstack([y, np.zeros((300, 1))]))
    assert simulation_fit(two, one_moves) == pytest.approx(100.0)


@pytest.mark.parametrize("name", ["n4sid", "moesp"])
@pytest.mark.parametrize(("seed", "kind"), [(0, "prbs"), (2, "prbs"), (1, "gauss")])
def test_noise_free_data_give_the_true_order(name, seed, kind):
    """Held-out fits within ``RESOLUTION`` (0.1 point) of 100 % are ties, as for identify
    (one rule, :func:`sysid.validation.ties.tie`). Before: a 2-state plant simulated without
    noise, its means removed, got order 3 on every one of 16 records (PRBS and Gaussian),
    its third pole at 1 +- 1e-15 holding the offset the means left: order 2 scored
    99.98-99.997 % against 100.00 %, and 5 % of the best's error is nothing there."""
    plant = sysid.StateSpaceModel([[0.8, 0.3], [-0.3, 0.8]], [[1.0], [0.0]], [[1.0, 0.5]])
    rng = np.random.default_rng(seed)
    u = np.sign(rng.standard_normal(600)) if kind == "prbs" else rng.standard_normal(600)
    y = plant.simulate(u)[:, 0]
    m = getattr(sysid, name)(sysid.IOData(u=u - u.mean(), y=y - y.mean()), "auto")
    sel = m.info["order_selection"]
    assert m.nstates == sel["order"] == 2 and m.is_stable(), sel
    assert sel["table"][2] > 100.0 - 0.1 and sel["table"][3] > sel["table"][2]
    np.testing.assert_allclose(np.sort(np.abs(m.poles())), np.abs(plant.poles()), rtol=1e-3)


def test_a_fold_that_excites_too_little_is_left_out_not_the_cross_validation():
    """Three slow sines, with noise added in the first fifth only: the record without that
    block is not persistently exciting for the window, but the other four folds are. Before,
    that one fold made ``order="auto"`` fall back to the singular-value gap (a human-operator
    tracking record's gap sat at the data's numerical rank, where the fit gave non-finite
    estimates); now the fold is left out, as ``identify`` leaves it out."""
    rng = np.random.default_rng(0)
    t = np.arange(2500)
    u = sum(np.sin(w * t + p) for w, p in ((0.01, 0.3), (0.023, 1.0), (0.041, 2.0)))
    u[:400] += rng.standard_normal(400)
    true = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0], [0.5]], [[1.0, 0.0]],
                                 dt=1.0)
    d = sysid.IOData(u=u, y=true.simulate(u) + 0.01 * rng.standard_normal((t.size, 1)),
                     dt=1.0)
    m = quiet(sysid.n4sid, d)
    assert m.info["order_selection"]["criterion"] == "cross-validated simulation fit"
    assert m.A.shape == (2, 2) and validation_fit(m, d) > 99.0
