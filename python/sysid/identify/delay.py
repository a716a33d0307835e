"""Candidates with an input delay for :func:`sysid.identify` (MATLAB users run ``delayest``
and pass ``InputDelay``; identify does both when the record shows a long delay).

A subspace model absorbs a delay of ``k`` samples only with ``k`` of its states, and its
window's horizon bounds how far back it looks: a wave probe 26 m down a basin, where the
flap acts after about 80 samples, is fitted at orders the window cannot give. So when
:func:`sysid.polynomial.delayest.delays` finds, for some input, a delay to every output it
determines that reaches past the horizon (:func:`detected_delays`; shorter ones are the
sweep's to absorb), the subspace candidates (under feedback the closed-loop weightings
only, as the open-loop ones are biased there) are fitted once more to the record with each
input shifted by its delay less one (the one sample a model without feed-through already
has; as ``input_delay="auto"`` does), the delays returned as states
(:func:`~sysid.models.input_delay.absorb_delay`, no parameters), and the best of them are
refined on the simulation error as the others are (:func:`within_delay`: the search moves
the delay-free model). All are scored on the same held-out blocks as every other candidate,
their delay line holding the inputs recorded before the block
(:func:`~sysid.models.input_delay.delay_free_view`,
:func:`~sysid.validation.crossval.preceding_inputs`; the block's first input held where the
record has none).

The delay is itself taken from the record (the first significant lag of a search over many),
so a delayed candidate is kept only when the blocks show it clearly: its best must beat the
best candidate without a delay by more than the blocks' resolution and by two standard
errors of their block-by-block difference (:func:`keep_if_shown`); otherwise the delayed
candidates stay on the leaderboard, not chosen, and ``checks["input_delay"]`` says why.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import DataError, ExcitationError, InsufficientDataError, SysidError
from ..models.input_delay import absorb_delay, shift_inputs
from ..validation.crossval import MAX_ORDER, tie
from .board import Board
from .sweep import transformed_sweep

__all__ = ["delay_candidates", "detected_delays", "keep_if_shown", "within_delay"]

#: the smallest shift (samples) that gets its own candidates, with the subspace horizon:
#: a shorter delay costs a model as many states, within what the sweep's window looks back
MIN_SHIFT = 2
#: the longest delay searched, in samples, and in regressors of the ARX model that finds it
#: (inputs x lags: the search's cost grows with their square)
NK_CAP = 150
NK_REGRESSORS = 300
#: the standard errors of the block-by-block difference a delayed candidate must clear
SHOWN_SE = 2.0
#: delayed starts refined on the simulation error (distinct orders, best first)
N_DELAYED_REFINE = 2


def detected_delays(data: IOData, shortest_block: int, horizon: int) -> np.ndarray | None:
    """The shift of each input (its delay less one sample) when some input's is at least
    ``horizon`` (the subspace window's block rows: the sweep's models look no further back)
    and ``MIN_SHIFT``, else None: the smallest delay to the outputs whose delay the data
    determine (:func:`~sysid.polynomial.delayest.delays`, searched up to ``NK_CAP`` samples,
    a quarter of the shortest held-out block and ``NK_REGRESSORS`` regressors); an input
    whose delay to no output is determined is not shifted.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from scipy import signal
    >>> rng = np.random.default_rng(1)
    >>> u = rng.standard_normal(3000)
    >>> y = signal.lfilter([0] * 12 + [1.0], [1, -0.7], u) + 0.1 * rng.standard_normal(3000)
    >>> detected_delays(sysid.IOData(u=u, y=y), 600, 10).tolist()   # delay 12: shift 11
    [11]
    >>> detected_delays(sysid.IOData(u=u, y=y), 600, 20) is None  # within a 20-row window
    True
    """
    from ..polynomial.delayest import delays

    m = data.n_inputs
    least = max(MIN_SHIFT, int(horizon))
    nk_max = int(min(NK_CAP, shortest_block // 4, max(20, NK_REGRESSORS // m)))
    if nk_max < least + 1:  # no delay the search can find needs candidates of its own
        return None
    big = np.iinfo(np.int64).max
    nk = np.full(m, big, dtype=np.int64)
    # one output at a time, stopping once every input acts on some output within the window
    # (a 2 x 28 structure: one of its outputs' searches, not 28)
    for i in range(data.n_outputs):
        one = IOData(u=[u for u, _ in data.experiments], y=[y[:, [i]] for _, y in
                                                              data.experiments])
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out, weak, _, _ = delays(one, nk_max=nk_max)
        except (DataError, ExcitationError, InsufficientDataError):
            continue
        known = np.ones(m, dtype=bool)
        for _, j, _ in weak:
            known[j] = False
        nk = np.minimum(nk, np.where(known, out[0], big))
        if np.all(nk <= least):
            return None
    shift = np.where(nk == big, 0, np.maximum(nk - 1, 0)).astype(int)
    return shift if int(shift.max()) >= least else None


def within_delay(data: IOData, model: Any, fit: Callable[[IOData, Any], Any]) -> Any:
    """``fit(data, model)`` for a model without an absorbed input delay; for one with
    (``info["input_delay"]``), ``fit`` of the shifted record from its delay-free model, the
    delays absorbed again: a search moves the model's parameters, never its delay line.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.models.input_delay import absorb_delay
    >>> m = absorb_delay(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), [3])
    >>> d = sysid.IOData(u=np.ones(50), y=np.ones(50))
    >>> out = within_delay(d, m, lambda data, start: start)   # fitted to 47 samples
    >>> out.nstates, out.info["input_delay"]
    (4, [3])
    """
    k = (getattr(model, "info", None) or {}).get("input_delay")
    if k is None:
        return fit(data, model)
    k = np.asarray(k, dtype=int)
    return absorb_delay(fit(shift_inputs(data, k), model.info["delay_free"]), k)


def delay_candidates(board: Board, shift: np.ndarray, h_full: int,
                     methods: tuple[str, ...], max_order: int | None,
                     refine: Callable[[Board, dict[str, Any], str, str], None] | None) -> str:
    """The subspace candidates (every weighting in ``methods``, with and without
    feed-through, orders up to what every shifted part's window allows) fitted to the
    record with its inputs shifted by ``shift``, the delays absorbed, scored on the board's
    blocks (:func:`.sweep.transformed_sweep`); the best ``N_DELAYED_REFINE`` orders refined
    by ``refine`` (None: not refined). Returns what was done, for ``checks["input_delay"]``."""
    try:
        rows, top = transformed_sweep(board, lambda d: shift_inputs(d, shift),
                                      lambda m: absorb_delay(m, shift), h_full, methods,
                                      max_order or MAX_ORDER, "subspace, input delay",
                                      refit_kalman=True)
    except (SysidError, ValueError, np.linalg.LinAlgError) as e:
        return f"not fitted: a part shifted by the delays cannot be ({e})"[:200]
    starts: dict[int, dict[str, Any]] = {}
    for r in sorted((r for r in rows if board.eligible(r)), key=lambda r: -r["held_out_fit"]):
        if r["order"] not in starts and len(starts) < N_DELAYED_REFINE:
            starts[r["order"]] = r
    if refine is not None:
        for r in starts.values():
            refine(board, r, "simulation", f"prediction error from {r['family']}, input delay")
    for r in board.rows:
        if r["criterion"].endswith("input delay"):
            r["input_delay"] = shift.tolist()
    return (f"inputs delayed by {shift.tolist()} samples (delayest: the first significant lag "
            f"less one): subspace candidates of orders 1-{top} fitted to the shifted record"
            + (f", {len(starts)} refined" if refine is not None and starts else ""))


def keep_if_shown(board: Board) -> str:
    """Leave the delayed candidates out of the choice (``start_only``, noted) unless the best
    of them beats the best candidate without a delay by more than :func:`tie` and
    ``SHOWN_SE`` standard errors of their block-by-block difference
    (:meth:`.board.Board.paired_se`): among the stable candidates, or among all (an
    integrating plant's, such as a ship's heading; whether an unstable one is then chosen is
    the board's usual test, :meth:`.board.Board.insisting`). Returns the verdict, for
    ``checks["input_delay"]``."""
    said = "none of them was scored above its start"
    for stable in (True, False):
        delayed = [r for r in board.rows if "input_delay" in r and board.eligible(r, stable)]
        plain = [r for r in board.rows if "input_delay" not in r and board.eligible(r, stable)]
        if not delayed:
            continue
        d = max(delayed, key=lambda r: r["held_out_fit"])
        kind = "stable " if stable else ""
        if not plain:
            return (f"kept: no {kind}candidate without the delay (best with it: held-out fit "
                    f"{d['held_out_fit']:.1f} %)")
        p = max(plain, key=lambda r: r["held_out_fit"])
        gap = d["held_out_fit"] - p["held_out_fit"]
        need = max(tie(p["held_out_fit"]), SHOWN_SE * board.paired_se(d, p))
        said = (f"best held-out fit of the {kind}candidates {d['held_out_fit']:.1f} % with "
                f"it, {p['held_out_fit']:.1f} % without, a gain of {gap:.1f} points where the "
                f"blocks resolve {need:.1f}")
        if gap > need:
            return f"kept: {said}"
    for r in board.rows:
        if "input_delay" in r and not r.get("start_only"):
            r["start_only"] = True
            r["note"] = r["note"] or "input delay not shown by the held-out blocks: not chosen"
    return (f"not chosen: {said} (their spread; the delay was itself chosen from the "
            f"record)")
