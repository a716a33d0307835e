"""Subspace candidates of :func:`sysid.identify` whose ``A`` is taken otherwise than by the
sweep's shift invariance: from the estimated state sequence (:func:`states_candidates`) and
with a stable ``A`` enforced when no candidate is stable (:func:`stabilised_candidates`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..data.iodata import IOData
from .board import Board

__all__ = ["STATES_METHOD", "states_candidates", "stabilised_candidates"]

#: the weighting of the state-sequence candidates (SIPPY's and nfoursid's N4SID)
STATES_METHOD = "n4sid"
#: unstable subspace candidates re-fitted with a stable A when no candidate is stable
N_STABILISED = 10


def _from_states(est: Any) -> Any:
    """``est`` taking ``A, B, C, D`` from its estimated state sequence (``matrices="states"``,
    :meth:`~sysid.SubspaceEstimator.with_matrices`: sharing its record, factor and SVDs)."""
    return est.with_matrices("states")


def states_candidates(board: Board) -> None:
    """N4SID candidates with ``A, B, C, D`` by least squares on the estimated state sequence,
    ``x(t+1)`` on ``x(t), u(t)`` (``SubspaceEstimator(..., matrices="states")``, as SIPPY's
    and nfoursid's N4SID), at each order and feedthrough choice whose N4SID candidate of the
    sweep (``A`` by the shift invariance of the observability matrix) is unstable on some
    held-out block: a slow pole estimated just outside the unit circle, which the state
    regression often keeps inside (a four-stage evaporator: every sweep fit of order 9 to 20
    unstable on some block; the state sequence's of order 10 validates at 64.4 % against the
    choice's 59.6 % without it, benches/results/identify_candidates.md). Leaderboard rows
    ``n4sid (states)``, criterion ``"subspace, states"``. Scored after the refinements:
    candidates only, not starts, so that every other row is as without them. Not under
    feedback: open-loop fits, biased there (the sweep's are starts only). When the record
    drifts (:meth:`.board.Board.unstable_verdict`: an unstable candidate wins only with the
    drift left in) they are held back unless the best of them beats the best stable candidate
    on every held-out block, with the drift left in and taken out
    (:meth:`.board.Board.beats_without_drift`, the test the data must pass to insist on an
    unstable candidate): a stable slow mode follows a drift as the unstable fits do (a
    first-order plant whose output drifts: order 7 chosen, the drift unreported; its
    residue after a line is removed: order 2), where on the evaporator the best of them,
    order 13, beats the choice without them on every block (held out 62.4 against 60.3 %,
    63.5 against 61.9 % with the drift taken out). :func:`.choice._choose` takes them after
    the other candidates near the best: stable where the sweep's spurious modes are not,
    they would crowd out the low orders (a 2-state plant: order 5 chosen)."""
    if board.subspace is None or board.feedback:
        return
    ests, estimator, top = board.subspace
    verdict, stable = board.unstable_verdict(), board.best()  # before they are added
    unstable = {(r["feedthrough"], r["order"]) for r in board.rows
                if r["family"] == STATES_METHOD and r["criterion"] == "subspace"
                and not r["stable"]}
    folds = [_from_states(e) for e in ests]

    def refit(data: IOData, n: int, ft: bool) -> Any:
        return _from_states(estimator(data)).fit(n, method=STATES_METHOD, feedthrough=ft)

    for ft in (False, True):
        for n in range(1, top + 1):
            if (ft, n) in unstable:
                board.add(STATES_METHOD, n, ft, None, "subspace, states",
                          lambda k, n=n, ft=ft: folds[k].fit(
                              n, method=STATES_METHOD, feedthrough=ft, kalman=False),
                          lambda data, n=n, ft=ft: refit(data, n, ft), budgeted=False)
    rows = [r for r in board.rows if r["criterion"] == "subspace, states"
            and np.isfinite(r["held_out_fit"])]
    if verdict != "drift" or stable is None or not rows:
        return
    if not board.beats_without_drift(max(rows, key=lambda r: r["held_out_fit"]), stable):
        for r in rows:
            r["start_only"] = True  # held back: not chosen
            r["note"] = r["note"] or ("the record drifts, and the best state-sequence "
                                      "candidate does not beat the best stable one on every "
                                      "held-out block with the drift left in and taken out: "
                                      "not chosen")


def stabilised_candidates(board: Board) -> None:
    """No stable candidate: the best subspace candidates with a stable ``A`` enforced
    (Maciejowski's zero-padded shift), so that a stable model can still be returned."""
    rows = sorted((r for r in board.rows if "stabilised" in r and np.isfinite(
        r["held_out_fit"])), key=lambda r: -r["held_out_fit"])
    for r in rows[:N_STABILISED]:
        fit_fn, refit = r["stabilised"]
        board.add(r["family"], r["order"], r["feedthrough"], None, "subspace, stable A",
                  fit_fn, refit, budgeted=False)
