"""The subspace sweep of :func:`sysid.identify`: every weighting, with and without
feed-through, at every order the windows allow, fitted to each fold's part and scored on the
board's blocks (:func:`subspace_candidates`, with the horizon rule :func:`horizon`); and the
same sweep on a transformed record (:func:`transformed_sweep`), each fold's part as a map
makes it, mapped back to a model of the record. The families built on the latter: an output
that integrates (:mod:`.integrating`: one output differenced, summed back) and an input delay
(:mod:`.delay`: the inputs shifted, the delays absorbed as states)."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

from ..data.iodata import IOData
from ..data.segments import long_enough
from ..errors import ExcitationError, InsufficientDataError
from ..subspace.estimator import available_horizon
from ..validation.crossval import (
    MAX_ORDER,
    fold_horizon,
    grown_order,
    parts_too_short,
    tie,
)
from .board import Board

__all__ = ["CLOSED_LOOP", "SHORT_HORIZON", "SUBSPACE", "horizon", "subspace_candidates",
           "transformed_sweep"]

SUBSPACE = ("moesp", "n4sid", "cva")
CLOSED_LOOP = ("pbsid", "ssarx")

#: the smallest horizon identify gives a short record when its data matrix can still have
#: three times as many columns as rows (orders up to ``(SHORT_HORIZON - 1) l``)
SHORT_HORIZON = 4


def horizon(data: IOData) -> int:
    """The subspace horizon of ``data``: :func:`~sysid.subspace.estimator.available_horizon`,
    from the experiments long enough for it, not the shortest one; on a short record, where
    that rule (ten columns a row) gives fewer than :data:`SHORT_HORIZON` block rows, up to
    :data:`SHORT_HORIZON` as long as the data matrix keeps three columns a row (as a fold's
    horizon does, :func:`~sysid.validation.crossval.fold_horizon`). With the ten-column rule
    alone a 100-sample record of one input and output had horizon 2, and every candidate
    order 1: a two-state plant validated at 35 %, where ``ssest(data, 2)`` gives 96 %.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.sweep import horizon
    >>> horizon(sysid.IOData(u=np.zeros(100), y=np.zeros(100)))  # short: SHORT_HORIZON
    4
    """
    h = available_horizon(data.lengths, data.n_inputs, data.n_outputs)
    if h >= SHORT_HORIZON:
        return h
    ch = data.n_inputs + data.n_outputs
    cols = max(data.lengths) + 1  # the columns of the longest experiment's window, + 2 i
    return max(h, min(SHORT_HORIZON, cols // (6 * ch + 2)))


def subspace_candidates(board: Board, full: IOData, methods: tuple[str, ...],
                         max_order: int | None) -> None:
    """The subspace sweep of :func:`sysid.identify` on ``board``: ``methods`` (with and
    without feedthrough) at every order 1 to ``max_order`` (default: what every fold's window
    allows, at most :data:`~sysid.validation.crossval.MAX_ORDER`, grown past it for a method
    whose best order is the grid's top), each fitted to every fold's part (its horizon, by
    :func:`horizon` of ``full``, as the fold allows it) and scored on the held-out blocks; each
    row carries its stable-``A`` variant (open-loop weightings), and ``board.subspace`` the
    fold estimators for the state-sequence candidates. Folds whose fitted part does not excite
    the input enough are left out (``board.unexcited``); with fewer than two left it raises.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.sweep import Board, subspace_candidates
    >>> from sysid.validation.crossval import record_folds
    >>> from sysid._progress import Bar
    >>> plant = sysid.StateSpaceModel([[0.5, 0.4], [-0.4, 0.5]], [[1.0], [0.0]], [[1.0, 0.0]])
    >>> u = np.random.default_rng(1).standard_normal(800)
    >>> d = sysid.IOData(u=u, y=plant.simulate(u))
    >>> board = Board(record_folds(d), Bar(None, "sweep", enabled=False))
    >>> subspace_candidates(board, d, ("n4sid",), 2)
    >>> best = max(board.rows, key=lambda r: r["held_out_fit"])
    >>> len(board.rows), best["order"]  # orders 1-2, with and without feedthrough
    (4, 2)
    """
    from ..subspace.estimator import SubspaceEstimator

    ests, keep = [], []
    h_full = horizon(full)
    short = 0  # fitted parts too short for the smallest subspace window
    for k, fold in enumerate(board.folds):
        h = fold_horizon(h_full, fold[0])
        part = long_enough(fold[0], 2 * h)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                if part is None:
                    raise InsufficientDataError("no experiment long enough for the window")
                ests.append(SubspaceEstimator(part, h))
            except InsufficientDataError:
                short += 1
                continue
            except ExcitationError:
                continue  # the rest of the record without this block excites too little
        keep.append(k)
    if len(keep) < len(board.folds):
        if len(keep) < 2 and short:
            raise parts_too_short(full, board.folds)
        if len(keep) < 2:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                SubspaceEstimator(long_enough(full, 2 * h_full) or full, h_full)  # its own error
            raise ExcitationError(
                f"the input excites too little of the record to hold parts of it out: "
                f"{len(board.folds) - len(keep)} of the {len(board.folds)} parts fitted "
                f"without one block are not persistently exciting (a step or a few steps, "
                f"inside some blocks only); fit one model to the whole record instead "
                f"(sysid.n4sid, sysid.ssest with an order, sysid.procest for a step test)")
        board.keep_folds(keep)
    top = min(min(e.max_order for e in ests), max_order or MAX_ORDER)
    # the last record re-fitted on and its compression, once per record; the record itself
    # is held, not its id(): the detrended fold parts of the drift test are made and freed
    # one after another, and a freed one's id can come back as the next one's
    whole: list[Any] = [None, None]

    def estimator(data: IOData) -> Any:
        if whole[0] is not data:
            whole[:] = [data, SubspaceEstimator(long_enough(data, 2 * h_full) or data, h_full)]
        return whole[1]

    def refit(data: IOData, m: str, n: int, ft: bool, stable: bool = False) -> Any:
        return estimator(data).fit(n, method=m, feedthrough=ft, stable=stable)

    def add_orders(low: int, high: int, series: Any) -> None:
        for meth in methods:
            for ft in (False, True):
                for n in range(low, high + 1) if (meth, ft) in series else ():
                    row = board.add(meth, n, ft, None, "subspace",
                                    lambda k, m=meth, n=n, ft=ft: ests[k].fit(
                                        n, method=m, feedthrough=ft, kalman=False),
                                    lambda data, m=meth, n=n, ft=ft: refit(data, m, n, ft),
                                    budgeted=False)
                    if row is not None and meth not in CLOSED_LOOP:  # its stable-A variant
                        row["stabilised"] = (  # (none for ssarx, pbsid: their fit refuses it)
                            lambda k, m=meth, n=n, ft=ft: ests[k].fit(
                                n, method=m, feedthrough=ft, kalman=False, stable=True),
                            lambda data, m=meth, n=n, ft=ft: refit(data, m, n, ft, True))

    add_orders(1, top, {(m, ft) for m in methods for ft in (False, True)})
    # a method's best order at the top of the grid: its grid grows while the window allows,
    # kept only where a larger order beats the grid's best by more than a tie (else a
    # near-tie moves the near-best set that the refinements start from)
    ceiling, first, grid_best = (top if max_order is not None else min(
        e.max_order for e in ests)), top, board.best_fit()
    while top < ceiling and (rising := board.rising(top)):
        low, top = top + 1, grown_order(top, ceiling)
        add_orders(low, top, rising)
    if top > first and board.best_fit() <= grid_best + tie(grid_best):
        board.rows = [r for r in board.rows if r["order"] <= first]
        top = first
    board.subspace = (ests, estimator, top)  # for the state-sequence candidates



def transformed_sweep(board: Board, to_data: Callable[[IOData], IOData],
                      to_model: Callable[[Any], Any], horizon: int, methods: tuple[str, ...],
                      top: int, criterion: str, *, extra_order: int = 0,
                      refit_kalman: bool = False) -> tuple[list[dict[str, Any]], int]:
    """Subspace candidates of ``methods`` (with and without feed-through, orders 1 to
    ``top`` or what every part's window allows) fitted to ``to_data`` of each fold's part
    (horizon ``horizon`` as the fold allows it), their models ``to_model`` of the fit,
    leaderboard rows of ``criterion`` and order ``n + extra_order``; re-fitted on a whole
    record the same way (with a Kalman gain when ``refit_kalman``). Returns the rows and the
    top order. A part that cannot be mapped or fitted raises (before any row is added).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid._progress import Bar
    >>> from sysid.identify.board import Board
    >>> from sysid.identify.sweep import transformed_sweep
    >>> from sysid.validation.crossval import record_folds
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(900)
    >>> y = sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]]).simulate(u).ravel()
    >>> y = y + 0.05 * rng.standard_normal(900)
    >>> board = Board(record_folds(sysid.IOData(u=u, y=y)), Bar(None, "sweep", enabled=False))
    >>> rows, top = transformed_sweep(board, lambda d: d, lambda m: m, 10, ("moesp",), 2,
    ...                               "subspace, as it is")
    >>> [(r["order"], r["feedthrough"]) for r in rows], top
    ([(1, False), (2, False), (1, True), (2, True)], 2)
    >>> bool(rows[0]["held_out_fit"] > 95)
    True
    """
    from ..subspace.estimator import SubspaceEstimator

    ests = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for part, _ in board.folds:
            d = to_data(part)
            h = fold_horizon(horizon, d)
            ests.append(SubspaceEstimator(long_enough(d, 2 * h) or d, h))
    top = min(top, *(e.max_order for e in ests))
    whole: list[Any] = [None, None]  # the record last re-fitted on and its compression

    def refit(data: IOData, meth: str, n: int, ft: bool) -> Any:
        if whole[0] is not data:
            d = to_data(data)
            whole[:] = [data, SubspaceEstimator(long_enough(d, 2 * horizon) or d, horizon)]
        return to_model(whole[1].fit(n, method=meth, feedthrough=ft, kalman=refit_kalman))

    rows = []
    for meth in methods:
        for ft in (False, True):
            for n in range(1, top + 1):
                row = board.add(meth, n + extra_order, ft, None, criterion,
                                lambda k, m=meth, n=n, ft=ft: to_model(ests[k].fit(
                                    n, method=m, feedthrough=ft, kalman=False)),
                                lambda data, m=meth, n=n, ft=ft: refit(data, m, n, ft),
                                budgeted=False)
                if row is not None:
                    rows.append(row)
    return rows, top
