"""The orders above a refinement that rose past every subspace fit (:func:`higher_orders`):
``sysid.identify`` refines the orders its subspace candidates' held-out scores point at, and
those scores can understate what the model class reaches at the orders above."""

from __future__ import annotations

import warnings
from typing import Any, Callable

import numpy as np

from ..data.iodata import IOData
from ..errors import SysidError
from .board import Board, tie

__all__ = ["higher_orders", "ssest_start"]


def ssest_start(data: IOData, order: int, ft: bool) -> Any:
    """:func:`sysid.ssest`'s start at ``order``: the subspace weighting (with ``B, D`` and the
    initial state by least squares too) of the lowest prediction-error cost, not refined.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.climb import ssest_start
    >>> u = np.random.default_rng(0).standard_normal(300)
    >>> y = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]]).simulate(u)
    >>> ssest_start(sysid.IOData(u=u, y=y), 1, False).A.shape
    (1, 1)
    """
    import sysid

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return sysid.ssest(data, order=order, feedthrough=ft, max_iter=0)


def higher_orders(board: Board, refine: Callable[..., None], limit: int) -> None:
    """One order above the best simulation-focus refinement, refined likewise (``refine``:
    :func:`.refine._refine`) from :func:`ssest_start` on every fold, and on up while each order
    scores above the last by more than :func:`.board.tie` (``limit`` orders at most). Only when
    that refinement is of the highest order refined and scores above every subspace candidate
    (stable or not) by more than a tie: the subspace scores, which picked the orders to
    refine, then understate what the model class reaches, and cannot rule out the orders
    above (up to the sweep's largest order). On a gantry crane's load swing (trolley motor
    voltage to rope angle: a lightly damped pendulum behind the motor) the order-2 refinement
    rose 13 points above the best subspace fit of any order (most unstable on some held-out
    block), and no order above was refined: orders 3 and 4 then score 79.8 and 80.2 % held
    out against 73.7 %, and order 4 validates at 87.2 % against 56.2 %
    (benches/results/realdata_fresh9.md).

    Under feedback too: the start, an open-loop subspace fit, is only a start there, as are
    those of the other refinements (a simulation-error search from it). On a flask titrated
    under a pH controller (the closed-loop subspace fits' scores pointing at order 1 alone)
    the order-1 refinement rose past every subspace fit and validated at 3.4 %; the order-2
    refinement above it validates at 71.4 % (benches/results/realdata_fresh28.md).

    Examples
    --------
    >>> from sysid.identify.climb import higher_orders
    >>> from sysid.identify.board import Board
    >>> b = Board.__new__(Board)
    >>> b.rows = []  # nothing refined: nothing to climb from
    >>> higher_orders(b, lambda *a: None, 3)
    """
    sub = [r for r in board.rows if r["criterion"] == "subspace" and board.eligible(r, False)]
    ref = [r for r in board.rows if r["criterion"].startswith("prediction error")
           and r["focus"] == "simulation" and board.eligible(r)]
    if not sub or not ref:
        return
    best = max(ref, key=lambda r: r["held_out_fit"])
    top = max(r["held_out_fit"] for r in sub)
    if best["order"] < max(r["order"] for r in ref) or best["held_out_fit"] <= top + tie(top):
        return
    n, ft = best["order"], best["feedthrough"]
    top_order = board.subspace[2] if board.subspace else max(r["order"] for r in sub)
    for _ in range(limit):
        n += 1
        if n > top_order or any(r["order"] == n and r["feedthrough"] == ft for r in ref):
            return
        start = {"family": "ssest's start", "order": n, "feedthrough": ft,
                 "held_out_fit": -np.inf,
                 "fit_fn": lambda k, n=n: ssest_start(board.folds[k][0], n, ft),
                 "refit": lambda data, n=n: ssest_start(data, n, ft)}
        rows = len(board.rows)
        try:
            refine(board, start, "simulation", "prediction error from ssest's start")
        except SysidError:  # no start at this order: none above either
            return
        if len(board.rows) == rows:  # left out: the refinements' work bound
            return
        row = board.rows[-1]
        if not board.eligible(row) or row["held_out_fit"] <= best["held_out_fit"] + tie(
                best["held_out_fit"]):
            return
        best = row
