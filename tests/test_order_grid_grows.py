"""The automatic order grid grows when its best order is its top.

Orders 1 to 20 were tried and the best held-out one taken; a record whose held-out fit still
rose at order 20 got order 20 without a word (a 3 x 3 piezo steering mirror, published
linear models of order 28: identify 88.9 % -> 94.7 % in validation, n4sid 85.2 -> 87.4 %,
moesp 86.1 -> 91.9 %). Now the grid grows by half (:func:`grown_order`) while the best order
is its top and the subspace window allows more.
"""

from __future__ import annotations

import warnings

import numpy as np

import sysid
from sysid.validation.crossval import MAX_ORDER, cross_validated_order, grown_order


def _record(seed: int = 0, order: int = 26) -> tuple[sysid.IOData, sysid.IOData]:
    """13 lightly damped modes (poles of modulus 0.93-0.985), one input, two outputs."""
    rng = np.random.default_rng(seed)
    k = order // 2
    A = np.zeros((order, order))
    for i, (r, th) in enumerate(zip(np.linspace(0.93, 0.985, k), np.linspace(0.15, 2.6, k))):
        a, b = r * np.cos(th), r * np.sin(th)
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[a, b], [-b, a]]
    plant = sysid.StateSpaceModel(A, rng.standard_normal((order, 1)),
                                  rng.standard_normal((2, order)), np.zeros((2, 1)))
    u = rng.standard_normal((6000, 1))
    y = plant.simulate(u)
    y = y + 0.01 * y.std(0) * rng.standard_normal(y.shape)
    return sysid.IOData(u=u[:4000], y=y[:4000]), sysid.IOData(u=u[4000:], y=y[4000:])


def test_grown_order_adds_half_as_many_orders_again_up_to_the_ceiling():
    assert grown_order(20, 57) == 30 and grown_order(30, 57) == 45
    assert grown_order(20, 24) == 24 and grown_order(3, 57) == 7


def test_order_auto_goes_past_twenty_when_the_held_out_fit_still_rises():
    est, val = _record()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        choice = cross_validated_order(est, sysid.SubspaceEstimator)
        model = sysid.n4sid(est)
    assert max(choice.table) > MAX_ORDER and choice.order > MAX_ORDER
    assert model.A.shape[0] == 26
    assert np.mean(sysid.compare(val, model).fit) > 98.0


def test_identify_grows_its_subspace_grid_and_a_given_max_order_bounds_it():
    est, val = _record()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(est, refine=False, progress=False)
        capped = sysid.identify(est, refine=False, progress=False, max_order=20)
    assert res.to_pandas()["order"].max() > MAX_ORDER
    assert np.mean(sysid.compare(val, res.model).fit) > 98.0
    assert capped.to_pandas()["order"].max() == 20


def test_a_best_order_below_the_top_keeps_the_grid():
    rng = np.random.default_rng(1)
    plant = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0], [0.5]], [[1.0, 0.0]])
    u = rng.standard_normal((2000, 1))
    y = plant.simulate(u) + 0.05 * rng.standard_normal((2000, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        choice = cross_validated_order(sysid.IOData(u=u, y=y), sysid.SubspaceEstimator)
    assert max(choice.table) <= MAX_ORDER and choice.order == 2


def test_identify_grows_the_methods_still_rising_at_the_top():
    """The best of all at order 16 but CVA with ``D`` best at the top, 20: CVA with ``D``
    grows (a 2 x 28 flexible structure, 90-93 % held out from order 26 on: identify
    validated at 68.6 % with the grid at 20, 95.2 % with it grown)."""
    from sysid.identify.board import Board

    board = Board.__new__(Board)

    def row(family, ft, order, fit):
        return {"family": family, "feedthrough": ft, "order": order, "criterion": "subspace",
                "held_out_fit": fit, "stable": True}
    board.rows = ([row("cva", True, n, 20.0 + 0.5 * n) for n in range(1, 21)]
                  + [row("moesp", False, n, 40.0 - abs(n - 16)) for n in range(1, 21)]
                  + [row("cva", True, 20, np.nan), dict(row("moesp", True, 20, 99.0),
                                                        stable=False)])
    assert board.rising(20) == {("cva", True)}
    assert board.rising(30) == set()


def test_identify_drops_grown_orders_that_gain_no_more_than_a_tie():
    """Twenty states: every method is best at the grid's top, 20, so the grid grows; orders
    21-30 gain nothing past a tie and are dropped again (kept, a near-tie among them moved
    the near-best set the refinements start from: a ventilator 80.2 -> 78.5 %)."""
    est, _ = _record(0, order=20)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(est, refine=False, progress=False)
    assert res.to_pandas()["order"].max() == MAX_ORDER
