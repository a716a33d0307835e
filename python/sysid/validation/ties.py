"""When held-out fits are ties: the rule by which :func:`sysid.identify`'s board and the
subspace automatic order (:func:`sysid.validation.crossval.choose`,
:func:`~sysid.validation.stable_orders.stable_first`) compare candidates scored on blocks of the
record held out from their fit.

Two fits are ties when they differ by less than :func:`tie` of the better one: ``TOL``
points (held-out fits scatter about this much between neighbouring orders), at most 5 % of
the better one's error (:func:`slack`), and at least down to ``100 - RESOLUTION`` % (a fit
that close to 100 % is as good as a record resolves). A simpler candidate within it of the
best is preferred; the data insist on an unstable one only beyond it
(:func:`wins_every_block`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["RESOLUTION", "TOL", "slack", "tie", "wins_every_block"]

#: fit points a smaller order may give up and still win (held-out fits of half-record
#: models scatter by about this much between neighbouring orders)
TOL = 0.5


def slack(best: float, tol: float = TOL) -> float:
    """Fit points the held-out blocks cannot tell from ``best`` away from 100 %: ``tol``, at
    most 5 % of the best's error; 0 for a score that is not finite. Near 100 % (noise-free
    data, where round-off decides the error) :func:`tie` allows more."""
    return max(min(tol, 0.05 * (100.0 - best)), 1e-6) if np.isfinite(best) else 0.0


#: fit points below 100 % that the held-out rules do not choose on: a held-out fit of ``100 -
#: RESOLUTION`` % or more (errors within a thousandth of the output's spread, 60 dB) is as
#: good as a record resolves, and candidates that reach it are ties, whatever :func:`slack`
#: (5 % of the best's error, next to nothing on a record with next to no noise) says. On a
#: noise-free record a model of the true order scoring 99.94-99.98 % lost to ones with a
#: spurious pole at 1 (a state holding the offset the means left, excited by the initial
#: state alone; 100.00 %, its pole 1 - 1e-15 or 1 + 1e-15 by round-off), in identify (6 of
#: 16 records reported as an unstable plant the data insist on) and in the subspace
#: ``order="auto"`` (n4sid, moesp, cva: order 3 on each of 16 such records, the means
#: removed, PRBS or Gaussian input). The held-out rules of both
#: compare within :func:`tie`, the data insist on an unstable candidate only beyond it, and
#: :func:`sysid.identify.board.bic` counts smaller errors as this large. Measured records
#: score far below it (the best held-out fit of ``benches/results/realdata.md`` is 98.6 %),
#: where nothing changes.
RESOLUTION = 0.1


def tie(best: float, tol: float = TOL) -> float:
    """Fit points the held-out rules (identify's board, the subspace automatic order) cannot
    tell from ``best``: :func:`slack`, and at least down to ``100 - RESOLUTION``
    (:data:`RESOLUTION`); 0 for a score that is not finite. A simpler candidate may give up
    this much against the best and still be preferred.

    Examples
    --------
    >>> from sysid.validation.ties import tie
    >>> tie(80.0), tie(99.0), round(tie(99.95), 6), round(tie(100.0), 6)
    (0.5, 0.05, 0.05, 0.1)
    """
    if not np.isfinite(best):
        return 0.0
    return max(slack(best, tol), best - (100.0 - RESOLUTION))


def wins_every_block(fits: Any, ref: Any, score: float, ref_score: float) -> bool:
    """``fits`` (per held-out block) better than ``ref`` on every block, and its ``score``
    above ``ref_score`` by more than :func:`tie`: the sign test (at ``2**-K``) by which
    the data insist on an unstable model against the best stable one
    (:func:`sysid.validation.stable_orders.stable_first`,
    :meth:`sysid.identify.board.Board.insisting`)."""
    return (len(fits) == len(ref) and all(a > b for a, b in zip(fits, ref))
            and score > ref_score + tie(score))
