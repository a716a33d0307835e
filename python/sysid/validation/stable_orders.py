"""Which orders an automatic order choice chooses among: stable ones first.

An order whose model is unstable on the whole record simulates its held-out blocks well and
any longer record badly; it stays a candidate only where the data insist on it
(:func:`stable_first`, used by :func:`sysid.validation.crossval.cross_validated_order` and
:func:`sysid.ssregest`).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from .ties import wins_every_block

__all__ = ["stable_first", "unstable_orders"]


def unstable_orders(whole: Any, table: dict[int, float], method: str, feedthrough: bool,
                     models: dict[int, Any]) -> set[int]:
    """The orders of ``table`` whose model fitted on the whole record (``whole.fit``) has a
    pole of modulus >= 1 (or cannot be fitted); the models fitted go into ``models``."""
    out = set()
    for n in table:
        try:
            fit = getattr(whole, "_quiet_fit", None)  # keeps the user's feedback warning
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                models[n] = (fit or whole.fit)(n, method=method, feedthrough=feedthrough,
                                               kalman=False)
            poles = models[n].poles()
            if len(poles) and float(np.max(np.abs(poles))) >= 1.0:
                out.add(n)
        except Exception:  # noqa: BLE001 - an order the record cannot support
            out.add(n)
    return out


def stable_first(score: dict[int, float], folds: dict[int, list[float]], unstable: set[int],
                 whole_fit: Callable[[int], float] | None = None) -> tuple[set[int], str]:
    """The orders the choice is made among: those whose model is stable, unless the data
    insist on an unstable one, and why (empty when nothing was left out).

    An unstable model that simulates held-out blocks well is scored on what it does over a
    block; on a longer record (the user's validation data, a simulation) its unstable mode
    grows without bound. An unstable order stays a candidate only when it beats the best
    stable order on *every* held-out block and by more than :func:`tie` on the score (a sign
    test at ``2**-K``: an integrating or open-loop unstable plant), the rule
    :meth:`sysid.identify.board.Board.insisting` applies to its candidates; with no stable
    order at all, every order is, and the note says so.

    ``whole_fit(n)``, when given, is the simulation fit of order ``n``'s model on the whole
    record it was fitted to (initial state fitted, :func:`simulation_fit`): an unstable
    order is then also held to simulate that record at least as well as the best stable
    order does. A held-out block is short, and its fitted initial state can hold back an
    unstable mode over it however fast the mode grows; over the whole record, the longest
    stretch at hand, a mode that grows too fast to be followed in double precision (a pole of
    modulus 1.067 over 1 000 samples: a factor 1e28) cannot, and neither can it on the
    user's validation data (DC-DC converter record: order 16, insisted on by every block,
    validated -inf; order 5 validated 47 %). :func:`sysid.identify` makes the same check
    through the BIC of its candidates' whole-record fits. With no stable order, the choice
    is among the unstable orders whose model simulates the whole record better than its mean
    (fit above 0 %), when any does.

    Examples
    --------
    >>> from sysid.validation.stable_orders import stable_first
    >>> folds = {1: [60.0, 62, 61], 2: [70.0, 55, 72], 3: [80.0, 81, 79]}
    >>> score = {n: sorted(v)[1] for n, v in folds.items()}
    >>> sorted(stable_first(score, folds, {2})[0]), sorted(stable_first(score, folds, {3})[0])
    ([1, 3], [1, 2, 3])
    """
    stable = {n: f for n, f in score.items() if n not in unstable and np.isfinite(f)}
    if not unstable:
        return set(score), ""
    if not stable:
        note = ("; no order gave a model stable on the whole record and scored on the held-out "
                "blocks: the choice is among unstable ones")
        if whole_fit is None:
            return set(score), note
        scored = sorted(n for n in score if np.isfinite(score[n]))
        follow = {n for n in scored if whole_fit(n) >= 0.0}
        if not follow or len(follow) == len(scored):
            return set(score), note
        out = ", ".join(str(n) for n in scored if n not in follow)
        return follow, note + (f" that simulate the whole record better than its mean (order(s) "
                               f"{out} do not: an unstable mode that grows too fast to follow "
                               f"over the record)")
    best_s = max(stable, key=lambda n: stable[n])
    ref = folds[best_s]
    insisted = {n for n in unstable if np.isfinite(score[n])
                and wins_every_block(folds[n], ref, score[n], stable[best_s])}
    diverging = set()
    if whole_fit is not None and insisted:
        bar = whole_fit(best_s)
        diverging = {n for n in insisted if not whole_fit(n) >= bar}
        insisted -= diverging
    allowed = set(score) - (unstable - insisted)
    shown = sorted(n for n in unstable - insisted - diverging if np.isfinite(score[n]))
    note = ""
    if shown:
        note += (f"; order(s) {', '.join(map(str, shown))} left out: unstable on the whole "
                 "record and not better than the best stable order on every held-out block")
    if diverging:
        note += (f"; order(s) {', '.join(map(str, sorted(diverging)))} left out: unstable, "
                 f"better on every held-out block, but simulating the whole record worse than "
                 f"the best stable order (its unstable mode grows too fast to follow over the "
                 f"record)")
    if insisted:
        note += (f"; order(s) {', '.join(map(str, sorted(insisted)))} unstable but kept: "
                 f"better than the best stable order ({best_s}) on every held-out block"
                 + (" and over the whole record" if whole_fit is not None else "")
                 + " (an integrating or unstable plant, or a mode the data insist on)")
    return allowed, note
