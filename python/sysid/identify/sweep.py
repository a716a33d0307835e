"""The subspace sweep of :func:`sysid.identify` on a transformed record: every weighting, with
and without feed-through, at every order the windows allow, fitted to each fold's part as a
map makes it and mapped back to a model of the record, then scored on the board's blocks.
The families built on it: an output that integrates (:mod:`.integrating`: one output
differenced, summed back) and an input delay (:mod:`.delay`: the inputs shifted, the delays
absorbed as states)."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

from ..data.iodata import IOData
from ..data.segments import long_enough
from ..validation.crossval import fold_horizon
from .board import Board

__all__ = ["transformed_sweep"]


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
