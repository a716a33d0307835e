"""``sysid.identify``: the one call an engineer makes first, with no settings.

1. Offsets: the estimation record's input and output means are removed and kept with the
   model (:class:`IdentifiedModel` predicts raw data).
2. Checks: the input's persistent-excitation order and a feedback test are recorded; under
   feedback the closed-loop subspace methods (PBSID, SSARX) join the candidates, and the
   open-loop ones (biased there) are refined from but not returned
   (:meth:`.board.Board.starts_only`: unless every other candidate scores clearly below
   them; with ``refine=False`` they are candidates). A periodic
   input is noted (``checks["periodic"]``): its held-out blocks repeat the fitted input.
3. Candidates are scored on blocks of the estimation record held out from their fit: the
   record is cut into five contiguous blocks (fewer on short records; several experiments
   laid end to end, cut where one ends: :func:`~sysid.validation.crossval.record_folds`;
   a chirp into interleaved pieces, ``checks["held_out_design"]``,
   :mod:`sysid.validation.swept`), each held out once while the rest fits the candidate,
   which then simulates it (initial state fitted with the prior of where the block's input
   puts the state, :mod:`sysid.validation.state_prior`); the score is the fit of the
   held-out blocks pooled (each weighs its output variation), without the block where it
   fits worst and the one where it fits best (:mod:`.board`); a block where every output
   stands still is left out (:func:`~sysid.identify.board.informative`);
   ``checks["held_out_evidence"]`` notes when one block holds nearly all the output
   variation (fewer than two effective blocks).
   Candidates: every subspace weighting (MOESP, N4SID, CVA) at every order the horizon
   allows (up to 20, more for a method still rising there), with and without
   feedthrough; the best of each of the smallest orders near the best refined by
   prediction-error search on the simulation error
   (every output's errors relative to its scale, as the fit % counts them: ``pem``'s
   ``weighting="output"``) and the best one on the prediction error; output-error models for
   one input and output; near-best candidates unstable on some block, at orders not refined
   yet, with a stable ``A`` enforced and refined likewise, unless the data insist on an
   unstable candidate or it wins only by following the record's drift
   (:func:`_stabilised_refinements`); the orders above a refinement that rose past every
   subspace fit (:func:`.climb.higher_orders`); at orders whose N4SID fit is unstable on some
   block, N4SID from the estimated state sequence (:func:`.states.states_candidates`:
   candidates, not starts; not under feedback); when an unstable candidate wins only with the
   record's drift left in, every sweep candidate once more with one output differenced and
   summed back, a pole pinned at 1 (:mod:`.integrating`: an output that integrates, kept
   only if it beats the stable ones with the drift left in and taken out); for an input
   delay past the window's horizon, the sweep (closed-loop weightings under feedback) and its
   best refinements on the inputs shifted by it, chosen if the blocks show it (:mod:`.delay`).
   A refinement scored clearly below its start on the held-out blocks is never chosen; one
   below it, or below the best candidate so far, on most blocks is stopped there. On the
   held-out blocks a refinement's search stops once it has settled (:func:`settled`: its last
   iterations raised the fit its criterion implies by less than a tenth of what the blocks
   resolve); re-fitted on the whole record it runs to convergence (up to ``FINAL_ITER``
   iterations: a search can crawl along a plateau and then drop) when that is cheap. On long
   records the refinements' work is bounded (``FINAL_WORK``, ``FOLD_WORK``, ``REFINE_WORK``;
   :func:`iteration_work`): the whole-record re-fit stops once settled, the fold fits are
   capped, later refinements are not scored (the checks say so).
4. The held-out blocks rank the candidates but cannot tell apart those within half a fit
   point of the best (5 % of its error at most), nor any within ``RESOLUTION`` (0.1 point)
   of 100 % (:func:`.board.tie`), nor, for the final choice, those with no
   more parameters within one standard error of their block-by-block difference to the
   best (:meth:`.board.Board.paired_se`: blocks that disagree by ten points leave a gap of
   a few points to chance): those are re-fitted on the whole record and
   the one with the smallest BIC of its simulation errors is returned (:func:`.board.bic`);
   a subspace model keeps its Kalman gain (:func:`.uncertainty.with_uncertainty`); unstable
   candidates
   only when the data insist (:meth:`.board.Board.insisting`) or ``enforce_stability=False``.
   An unstable candidate that wins only while the record's drift is left in is not one
   the data insist on (``checks["drift"]`` says so).
   ``validation`` data, when given, are only reported on.
5. The chosen model's simulation errors on the record are checked for a drift the input does
   not explain (:mod:`.notes`, ``checks["trend"]``), its held-out fit for a model
   that explains less than half of the outputs' variation (``checks["weak"]``), and its
   re-fit for a stop at the iteration cap (``checks["final_refit"]``).
"""

from __future__ import annotations

import time
import warnings
from typing import Any

import numpy as np

from .._checks import as_real, require_inputs_vary, user_stacklevel
from .._display import modulus, pvalue, unstable_modes
from .._progress import Bar, show
from .._threads import one_blas_thread
from ..data.iodata import IOData
from ..data.offsets import remove_means
from ..data.preprocessing import spike_report
from ..data.segments import long_enough
from ..errors import (
    DataError,
    ExcitationError,
    InsufficientDataError,
    SysidWarning,
    several_records_hint,
)
from ..models.statespace import ss_parameter_count
from ..subspace.estimator import available_horizon
from ..validation.coverage import coverage_note
from ..validation.crossval import (
    MAX_ORDER,
    MIN_BLOCK,
    TOL,
    fold_horizon,
    grown_order,
    parts_too_short,
    record_folds,
    require_held_out_length,
    simulation_fit,
    tie,
)
from ..validation.output_error import feedback_checked
from ..validation.records import validation_record
from ..validation.swept import held_out_design
from .board import Board, free_poles, informative, unstable
from .choice import _choose
from .climb import higher_orders
from .delay import delay_candidates, detected_delays, keep_if_shown, within_delay
from .integrating import integrating_candidates, integrating_note
from .notes import (
    excitation_check,
    loop_checks,
    order_excitation_check,
    persistent_mode_check,
    refit_cap_check,
    trend_check,
    weak_check,
)
from .oversampled import record_feedback, retry_decimated
from .result import IdentifiedModel, IdentifyResult, _family, reported_fit
from .states import stabilised_candidates, states_candidates
from .steptest import STAIRCASE_BLOCKS, blocks_with_steps, identify_step_test, input_changes
from .uncertainty import with_uncertainty

__all__ = ["identify"]

SUBSPACE = ("moesp", "n4sid", "cva")
CLOSED_LOOP = ("pbsid", "ssarx")
#: subspace candidates (distinct order and feedthrough) refined by prediction-error search
N_REFINE = 3
#: iteration cap of a refinement re-fitted on the whole record (only near-best ones are): the
#: model returned is converged, not stopped at pem's default cap of 50 nor once settled (a
#: start far from the minimum needs more, and a search can crawl along a plateau before it
#: drops); the held-out blocks score refinements settled, at most at the default cap (cheaper)
FINAL_ITER = 300
#: a refinement has settled once its last ``SETTLE_WINDOW`` iterations raised the fit its
#: criterion implies on the data it is fitted to by less than ``SETTLE_POINTS`` fit points
#: (a tenth of the smallest difference the held-out blocks resolve, :data:`TOL`): further
#: iterations cannot change the choice, so the search stops there (statistical convergence at
#: the resolution of the score, not of the optimiser)
SETTLE_WINDOW = 5
SETTLE_POINTS = TOL / 10
#: the cost of refinements is counted in the work of their iterations (:func:`iteration_work`:
#: fitted samples x outputs x parameters squared, the normal equations' share; about 1e10 per
#: CPU second on one core of the machine the benches ran on), not in seconds, so that the
#: choice does not depend on the machine or its load. A whole-record re-fit runs to
#: convergence (``FINAL_ITER`` iterations at most) when that costs at most ``FINAL_WORK``;
#: beyond (long records of many outputs at high orders), at most ``FINAL_WORK`` worth of
#: iterations and it stops once settled, as the fits scored on the held-out blocks did
FINAL_WORK = 2e10
#: a refinement fitted on a fold stops once settled, at pem's default cap of 50 iterations,
#: or once it has spent ``FINAL_WORK / 5`` (the five fold fits of a refinement together cost
#: at most what its whole-record re-fit may): on long records the held-out blocks score it a
#: little before it has settled, which can only understate it against its start
FOLD_WORK = FINAL_WORK / 5
#: refinements after the first (more starts, the prediction focus) are scored only while the
#: work they are expected to take (``NOMINAL_ITER`` iterations on every fold) keeps the
#: refinements' total within ``REFINE_WORK``; the first is always scored
REFINE_WORK = 5e10
NOMINAL_ITER = 20


def _checks(data: IOData) -> tuple[dict[str, Any], bool, int | None]:
    import sysid

    checks: dict[str, Any] = {}
    feedback, counted = False, None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            checks["excitation"], counted = excitation_check(data)
        except Exception as e:  # noqa: BLE001 - recorded, not raised
            checks["excitation"] = f"not checked ({e})"
        try:
            fb = record_feedback() or sysid.check_feedback(data)  # decimated: the record's
            feedback = bool(fb.detected)
            checks["feedback"] = (f"{'detected' if feedback else 'not detected'} "
                                  f"({pvalue(fb.p_value)}; {fb.size_text()})")
        except Exception as e:  # noqa: BLE001
            checks["feedback"] = f"not checked ({e})"
    try:
        per = sysid.detect_period(data)
    except Exception:  # noqa: BLE001 - a record it cannot read has no period to report
        per = None
    if per is not None:
        checks["periodic"] = (
            f"the input repeats every {per.period} samples ({per.periods} periods): every "
            f"held-out block repeats input the rest of the record holds, so the held-out fits "
            f"say how a model reproduces this excitation (its nonlinear distortions included, "
            f"which repeat with it), not how it does on another input; validate on a record "
            f"of another excitation (another multisine realisation or amplitude), or fit "
            f"the averaged periods (sysid.ssest(data, order, periods='auto'))")
    spikes = spike_report(data)
    if spikes:
        checks["outliers"] = (f"{spikes}: every fit bends to them; repair them first "
                              f"(sysid.despike(data)) or cut them out")
        warnings.warn(f"identify: {checks['outliers']}", SysidWarning, stacklevel=user_stacklevel())
    return checks, feedback, counted


#: the smallest horizon identify gives a short record when its data matrix can still have
#: three times as many columns as rows (orders up to ``(SHORT_HORIZON - 1) l``)
SHORT_HORIZON = 4


def _horizon(data: IOData) -> int:
    """The subspace horizon of ``data``: :func:`~sysid.subspace.estimator.available_horizon`,
    from the experiments long enough for it, not the shortest one; on a short record, where
    that rule (ten columns a row) gives fewer than :data:`SHORT_HORIZON` block rows, up to
    :data:`SHORT_HORIZON` as long as the data matrix keeps three columns a row (as a fold's
    horizon does, :func:`~sysid.validation.crossval.fold_horizon`). With the ten-column rule
    alone a 100-sample record of one input and output had horizon 2, and every candidate
    order 1: a two-state plant validated at 35 %, where ``ssest(data, 2)`` gives 96 %."""
    h = available_horizon(data.lengths, data.n_inputs, data.n_outputs)
    if h >= SHORT_HORIZON:
        return h
    ch = data.n_inputs + data.n_outputs
    cols = max(data.lengths) + 1  # the columns of the longest experiment's window, + 2 i
    return max(h, min(SHORT_HORIZON, cols // (6 * ch + 2)))


def _subspace_candidates(board: Board, full: IOData, methods: tuple[str, ...],
                         max_order: int | None) -> None:
    from ..subspace.estimator import SubspaceEstimator

    ests, keep = [], []
    h_full = _horizon(full)
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


def implied_fit(cost: float, data: IOData, weighting: str | None) -> float:
    """The fit % (mean over outputs, roughly) that a refinement's criterion ``cost`` implies
    on ``data``: with ``weighting="output"`` the cost is half the sum over outputs of the
    squared errors relative to each output's mean square, ``N l`` times the mean squared
    NRMSE; with the noise weighting (prediction focus) it is ``det(E^T E / N)``, against
    ``det(Y^T Y / N)`` of the outputs (a geometric mean of the outputs' NRMSE)."""
    y = np.vstack([e[1] for e in data.experiments])
    n, l = y.shape
    if weighting == "output":
        r = np.sqrt(max(2.0 * cost, 0.0) / (n * l))
    else:
        sign, logdet = np.linalg.slogdet(y.T @ y / n)
        r = np.exp((np.log(max(cost, 1e-300)) - logdet) / (2 * l)) if sign > 0 else np.inf
    return float(100.0 * (1.0 - r))


def settled(data: IOData, weighting: str | None, then: Any = None) -> Any:
    """A progress callback for :func:`sysid.pem` that stops the search once it has settled:
    its last ``SETTLE_WINDOW`` iterations raised :func:`implied_fit` by less than
    ``SETTLE_POINTS``; ``then`` (another callback: a time budget's) may stop it earlier.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.core import settled
    >>> d = sysid.IOData(u=np.ones(100), y=np.linspace(-1, 1, 100))
    >>> cb = settled(d, "output")
    >>> [cb(i, 10.0) for i in range(7)][-1]  # the same cost for six calls: settled
    False
    """
    fits: list[float] = []

    def cb(*a: Any) -> bool:
        fits.append(implied_fit(float(a[1]), data, weighting))
        if len(fits) > SETTLE_WINDOW and fits[-1] - fits[-1 - SETTLE_WINDOW] < SETTLE_POINTS:
            return False
        return True if then is None else bool(then(*a))
    return cb


def iteration_work(data: IOData, order: int, feedthrough: bool, noise: bool) -> float:
    """The work of one refinement iteration on ``data``: samples x outputs x parameters
    squared (forming the normal equations dominates), the parameters those of ``A, B, C``
    in the modal chart, ``D`` with ``feedthrough``, ``K`` with a ``noise`` model, and an
    initial state per experiment.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.core import iteration_work
    >>> d = sysid.IOData(u=np.zeros(100), y=np.zeros(100))
    >>> iteration_work(d, 2, False, False)  # 100 samples, 1 output, 2 (1 + 1 + 1) = 6 parameters
    3600.0
    """
    p = ss_parameter_count(order, data.n_inputs, data.n_outputs, feedthrough=feedthrough,
                           noise_model=noise, x0=True, n_experiments=data.n_experiments)
    return float(sum(data.lengths) * data.n_outputs * p * p)


def _starts(board: Board, count: int) -> list[dict[str, Any]]:
    """Starts for the refinement: the best stable subspace candidate of each order among
    those the held-out blocks cannot tell from the best, smallest orders first (``count``
    of them); the best candidate's order when the near-best ones are all of one order."""
    best: dict[int, dict[str, Any]] = {}
    for r in board.near_best():
        if r["criterion"] == "subspace" and r["order"] not in best:
            best[r["order"]] = r
    return [best[n] for n in sorted(best)[:count]]


def _refine(board: Board, r: dict[str, Any], focus: str, criterion: str) -> None:
    """Candidate ``r`` refined by :func:`sysid.pem` with ``focus`` from its fold fits (each
    fold's search stops once settled, :func:`settled`; ``FOLD_WORK`` at most) and scored;
    left out (``board.skipped``) when the refinements' expected work would pass
    ``REFINE_WORK`` (the first one is always scored)."""
    import sysid

    # simulation focus: every output's errors relative to its scale, as the held-out fit
    # (the mean of the outputs' fit %) counts them; prediction: the determinant criterion
    wt = "output" if focus == "simulation" else None
    ft = r["feedthrough"]
    cost = NOMINAL_ITER * sum(iteration_work(part, r["order"], ft, focus == "prediction")
                              for part, _ in board.folds)
    if board.refine_work and board.refine_work + cost > REFINE_WORK:
        board.skipped.append(f"{focus}-focus refinement of order {r['order']} "
                             f"(from {r['family']})")
        return
    board.refine_work += cost

    def fit(k: int) -> Any:
        part = board.folds[k][0]
        cap = int(FOLD_WORK // iteration_work(part, r["order"], ft, focus == "prediction"))
        return within_delay(part, r["fit_fn"](k), lambda d, s: sysid.pem(
            d, s, focus=focus, feedthrough=ft, weighting=wt, progress=settled(
                d, wt, board.stopper()), max_iter=max(SETTLE_WINDOW + 1, min(50, cap))))

    mine: dict[str, Any] = {}  # this refinement's row, once scored

    def refit(data: IOData) -> Any:
        # its fold fits are further starts on the whole record only (on a fitted part they
        # would carry the held-out block)
        more = mine.get("fold_models", []) if data is board.whole else []
        return _final_refit(data, r["refit"](data), r["order"], ft, focus, wt, more)
    row = board.add("pem", r["order"], ft, focus, criterion, fit, refit, start=r)
    mine.update(row or {})


def _stabilised_refinements(board: Board) -> None:
    """Refinements from a stable ``A``: the subspace candidates the held-out blocks cannot
    tell from the best of all (stable or not), of orders no stable start was refined at,
    that are unstable on some block (a slow pole estimated just outside the unit circle from
    part of the record), with a stable ``A`` enforced on every fold (Maciejowski's
    zero-padded shift; a start only, not a candidate) and then refined on the simulation
    error as the stable starts are, the smallest ``N_REFINE`` orders. Only while the
    unstable candidates show nothing (:meth:`.board.Board.unstable_verdict`): not when
    they win only by following the record's drift, which a slow stable mode follows as
    well (on a four-stage evaporator, held-out 64 % against 60 %, validation 43 % against
    60 %), nor when the data insist on one (an integrating plant). With no stable candidate
    at all there is nothing the data could prefer an unstable one to: the best open-loop
    subspace fits, of any order, are then the starts (on a test building's heating, -28 % ->
    90 % in validation; a battery cell's pulse test, -394 % -> -120 %), and the test of
    :meth:`.board.Board.insisting` runs against their refinements
    (:func:`.states.stabilised_candidates` stays the last resort). On a heat exchanger whose
    subspace fits are unstable on some block from order 4 on, order 2 was the only choice
    (validation 55.6 %); from a stable ``A`` at order 4 it is 61.0 %."""
    done = {r["order"] for r in board.rows if r["criterion"].startswith("prediction error")}
    picks: dict[int, dict[str, Any]] = {}
    # no stable candidate: the best open-loop subspace fits (the closed-loop ones have no
    # stable variant) start from a stable A, and the test runs against their refinements
    none_stable = board.best() is None
    rows = board.near_best(stable_only=False) if not none_stable else sorted(
        (r for r in board.rows if r["family"] in SUBSPACE and np.isfinite(r["held_out_fit"])),
        key=lambda r: -r["held_out_fit"])
    for r in rows:
        if (r["criterion"] == "subspace" and not r["stable"] and "stabilised" in r
                and r["order"] not in done and r["order"] not in picks):
            picks[r["order"]] = r
    if not picks or (not none_stable and board.unstable_verdict() != "none"):
        return
    for n in sorted(picks)[:N_REFINE]:
        r = picks[n]
        start = board.add(r["family"], n, r["feedthrough"], None, "subspace, stable A",
                          *r["stabilised"], budgeted=False)
        if start is None:
            continue
        # a start, not a candidate: a zero-padded shift can distort the fit it stabilises
        # (one chosen by BIC on a flutter record, its OE candidate missing, validated -85 %)
        start["start_only"] = True
        start["note"] = start["note"] or "the start of the refinement below: not chosen"
        if start["stable"]:
            _refine(board, start, "simulation",
                    f"prediction error from {r['family']}, stable A")


def _refined_candidates(board: Board) -> None:
    """Each of the best subspace candidates refined by prediction-error search on the
    simulation error (its own feedthrough choice, initial state estimated), from the same
    fold's subspace model; the best also with prediction focus, and for one input and
    output an output-error model."""
    import sysid

    starts = _starts(board, N_REFINE)
    for focus in ("simulation", "prediction"):
        for r in starts if focus == "simulation" else starts[:1]:
            _refine(board, r, focus, f"prediction error from {r['family']}")
    first = board.folds[0][0]
    if first.n_inputs == 1 and first.n_outputs == 1:
        for r in starts[:2]:
            n, ft = r["order"], r["feedthrough"]
            if n > 8:
                continue
            nk, nb = (0, n + 1) if ft else (1, n)

            def fit_oe(data: IOData, n: int = n, nb: int = nb, nk: int = nk) -> Any:
                return sysid.oe(data, nb, n, nk, progress=False).to_statespace()
            board.add("oe", n, ft, "simulation", "output error",
                      lambda k, f=fit_oe: f(board.folds[k][0]), fit_oe)


def _final_refit(data: IOData, start: Any, order: int, ft: bool, focus: str,
                 wt: str | None, more: list[Any] | tuple[Any, ...] = ()) -> Any:
    """A refinement re-fitted on the whole record: to convergence (``FINAL_ITER``) when that
    costs at most ``FINAL_WORK``; else at most that much work and stopped once settled, from
    whichever of ``start`` and ``more`` (the refinement's fits on the folds) simulates the
    record best (a search stopped once settled ends where its start leads it; a fold fit has
    done most of the way). ``info["identify_refit"]`` says so."""
    import sysid

    w = iteration_work(data, order, ft, focus == "prediction")
    if FINAL_ITER * w <= FINAL_WORK:
        return within_delay(data, start, lambda d, s: sysid.pem(
            d, s, focus=focus, feedthrough=ft, weighting=wt, max_iter=FINAL_ITER, progress=False))
    cap = max(SETTLE_WINDOW + 1, int(FINAL_WORK // w))
    names = ["its start"] + [f"its fit on fold {k + 1}" for k in range(len(more))]
    fits = [simulation_fit(m, data) for m in [start, *more]]
    best = int(np.argmax(fits)) if np.any(np.isfinite(fits)) else 0
    m = within_delay(data, [start, *more][best], lambda d, s: sysid.pem(
        d, s, focus=focus, feedthrough=ft, weighting=wt, max_iter=cap, progress=settled(d, wt)))
    m.info["identify_refit"] = (
        f"re-fitted on the whole record from {names[best]} (of {len(names)} starts, the one "
        f"that simulates it best) until settled ({m.info['pem']['iterations']} iterations, at "
        f"most {cap}), not to convergence: at up to {FINAL_ITER} iterations it would cost "
        f"{FINAL_ITER * w / FINAL_WORK:.0f} times the work bound of a re-fit")
    return m


@retry_decimated  # a record sampled far faster than its input changes (oversampled.py)
@feedback_checked()  # its own check (_checks); candidates neither repeat nor say it
@one_blas_thread
def identify(
    data: IOData,
    validation: IOData | None = None,
    *,
    max_order: int | None = None,
    refine: bool = True,
    enforce_stability: bool | None = None,
    time_budget: float | None = 60.0,
    progress: bool | None = None,
) -> IdentifyResult:
    """Identify a linear model from a record with no settings: offsets, checks, candidate
    families and orders, chosen on data held out from the estimation record.

    A step test (every input changes at most four times: switched from rest and held, the
    changes in fewer than three held-out blocks, or parts that cannot be fitted without a
    block) has no part that can be held out and the subspace methods refuse it: it gets the
    process models of :func:`sysid.procest` (one to three poles, a zero, an underdamped
    pair, each with a dead time) fitted from rest around the levels before the first step,
    the one of smallest BIC chosen (:mod:`sysid.identify.steptest`; ``result.score ==
    "BIC"``, ``max_order`` bounds the poles, the other settings do not apply).

    Parameters
    ----------
    data : IOData or (u, y)
        The estimation record, raw (offsets are removed and recorded here).
    validation : IOData or (u, y), optional
        Fresh data, used only to report the chosen model's simulation fit.
    max_order : int, optional
        Largest order tried (default: what the horizon allows, at most 20).
    refine : bool
        Also refine the best subspace candidates by prediction-error search (simulation
        focus, and prediction focus for the best) and, for one input and output, fit
        output-error models (default). ``False`` keeps to subspace models.
    enforce_stability : bool, optional
        ``None`` (default): a stable model unless the data insist (an unstable candidate
        simulates every held-out block better than the best stable one, also once the
        record's drift is taken out: an integrating or unstable plant), then a
        :class:`sysid.StabilityWarning` names its largest pole; one that wins only with the
        drift left in is not returned (``result.checks["drift"]`` says so), but a model
        with an output summed from its increments (a pole at exactly 1, the stable ones
        beaten with the drift left in and taken out) can be (``checks["integrating"]``).
        ``True``: only stable models. ``False``: the best held-out fit, stable or not.
    time_budget : float or None
        CPU seconds of this process (default 60) after which no further refinement is
        scored: the subspace sweep is always complete (it works on compressions of the
        record), the refinements are scored most promising first until the budget is spent,
        and the choice is made among what was scored (``result.out_of_time`` and a warning
        say so). CPU time, not wall-clock time, so that other work on a busy machine does
        not change the result; ``None``: the full search, whatever it takes. Apart from
        it, on long records the refinements' work is bounded in iterations x samples x
        parameters^2 (the same on any machine; ``result.checks`` says what it changed).
    progress : bool, optional
        A progress bar over the candidates (default: only when stderr is a terminal).
        Ctrl-C stops the search (``KeyboardInterrupt``, as every other computation: a script
        or a batch must not carry on with a half-chosen model).

    Returns
    -------
    IdentifyResult
        ``.model`` (an :class:`IdentifiedModel` that predicts raw data; its state-space
        model of the deviations is ``.model.statespace``), ``.leaderboard``,
        ``.summary()``, ``.plot()``, ``.to_pandas()``. The held-out fit of each candidate
        is its simulation fit on each held-out block with the block's initial state and a
        constant offset per output fitted (every block keeps some offset after the record's
        means are removed): on a record that drifts it reads higher than :func:`sysid.compare`
        (which fits the initial state only) on the same block.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> true = sysid.StateSpaceModel([[0.8, 0.3], [-0.3, 0.8]], [[1.0], [0.0]], [[1.0, 0.5]])
    >>> u = rng.standard_normal(600)
    >>> y = true.simulate(u) + 5.0 + 0.05 * rng.standard_normal((600, 1))
    >>> res = sysid.identify(sysid.IOData(u=u + 2.0, y=y), refine=False)
    >>> res.model.nstates, bool(res.model.is_stable())
    (2, True)
    >>> bool(np.allclose(res.model.y_offset, 5.0, atol=0.5))
    True
    """
    t0 = time.perf_counter()
    if isinstance(data, tuple) and len(data) == 2:
        data = IOData(u=data[0], y=data[1])
    if not isinstance(data, IOData):
        raise DataError(f"data must be a sysid.IOData or a (u, y) pair, got "
                        f"{type(data).__name__}" + several_records_hint(data))
    if data.n_inputs == 0:
        raise DataError("identify needs inputs; for output-only data use sysid.n4sid(data) "
                        "(a time-series model) or the oma tools")
    if enforce_stability not in (None, True, False):
        raise DataError(f"enforce_stability must be True, False or None, got "
                        f"{enforce_stability!r}")
    if max_order is not None and (isinstance(max_order, bool) or not isinstance(
            max_order, (int, np.integer)) or max_order < 1):
        raise DataError(f"max_order must be a positive integer (or None for what the horizon "
                        f"allows), got {max_order!r}")
    if time_budget is not None:
        time_budget = as_real(time_budget, "time_budget (seconds, or None for no limit)",
                              positive=True)
    steps = input_changes(data)  # a step test: nothing to hold out (its own path below)
    # a staircase with steps in several held-out blocks is held out as any record is
    staircase = steps is not None and blocks_with_steps(data) >= STAIRCASE_BLOCKS
    # a few samples show "a step" at each one: too short as any record is, not a step test
    if steps is None or staircase or len(steps) >= sum(data.lengths) // 2:
        require_held_out_length(data)  # before the channel checks: 1 sample is "constant"
    require_inputs_vary(data.experiments, "identify", data.input_names)
    # before the means are removed (a constant output is then 0)
    require_inputs_vary(data.experiments, "identify", data.output_names, side=1)
    validation = validation_record(validation, data)  # before the search, not after it
    if steps is not None and not staircase:  # process models fitted from rest, by BIC
        return identify_step_test(data, validation, steps, t0, max_order)
    centred, mu, my = remove_means(data)
    checks, feedback, counted = _checks(centred)
    # six significant digits: rounding to decimals printed data in micro-units as [0.0]
    checks["offsets"] = (f"input means [{', '.join(f'{v:.6g}' for v in mu)}], output means "
                         f"[{', '.join(f'{v:.6g}' for v in my)}] removed (kept with the model)")
    parts, still = informative(record_folds(centred), centred)
    checks.update(held_out_design(centred, parts))  # a chirp's interleaved pieces
    h = _horizon(centred)
    short = [f"{k} ({n} samples)" for k, n in enumerate(centred.lengths) if n < 2 * h]
    if short:
        checks["experiments"] = (
            f"experiment(s) {', '.join(short)} shorter than the subspace window ({2 * h} "
            f"samples, horizon {h} from the longer experiments): left out of the subspace "
            f"fits, used by the prediction-error refinements and in the held-out scores")
    if still:
        checks["held_out"] = (f"{still} held-out block(s) left out of the choice: every output "
                              "stands still there (no variation to score a fit against)")
    shortest = min(min(h.lengths) for _, h in parts)
    if shortest < MIN_BLOCK:
        raise InsufficientDataError(
            f"the record is too short to hold out a part for the choice (a held-out block has "
            f"{shortest} samples, {MIN_BLOCK} needed); pass a longer record or fit one model "
            "directly")
    methods = SUBSPACE + (CLOSED_LOOP if feedback else ())
    # Ctrl-C stops identify (KeyboardInterrupt), as it stops every other computation: a
    # batch (identify_many) or a script must not carry on with a half-chosen model
    interrupted = False
    deadline = None if time_budget is None else time.process_time() + float(time_budget)
    with Bar(None, "identify", unit="candidates", enabled=show(progress)) as bar:
        board = Board(parts, bar, deadline)
        board.whole, board.feedback = centred, feedback
        blocks = board.effective_blocks()
        if blocks < min(2.0, len(parts) - 0.5):  # two blocks count 2.0 at most
            checks["held_out_evidence"] = (
                f"thin: the output varies mostly in one of the {len(parts)} held-out blocks "
                f"(their effective number, by each block's share of the output variation, is "
                f"{blocks:.1f}), so the choice rests on that block alone; data that move the "
                f"plant otherwise (other amplitudes or frequencies) may rank the candidates "
                f"differently: a longer, evenly excited record makes it firmer")
        try:
            _subspace_candidates(board, centred, methods, max_order)
        except ExcitationError:
            if not staircase:
                raise
            # the parts without a block are not excited enough: the step test's own path
            return identify_step_test(data, validation, steps, t0, max_order)
        if board.unexcited:
            checks["held_out_excitation"] = (
                f"{board.unexcited} held-out block(s) left out of the choice: the rest of the "
                f"record without them does not excite the input enough to fit a model (a "
                f"step inside the block)")
        if refine:
            _refined_candidates(board)
            _stabilised_refinements(board)
            if not feedback:
                higher_orders(board, _refine, N_REFINE)
            if all(r["criterion"].startswith("subspace") for r in board.rows):
                checks["refinement"] = (
                    "none scored: no stable subspace candidate to start a prediction-error "
                    "search from (every one was unstable on some held-out block); the model "
                    "is a subspace one")
        states_candidates(board)  # after the refinements: candidates, not starts
        integrating_candidates(board, h, SUBSPACE)  # an output that integrates
        if (shift := detected_delays(centred, shortest, h)) is not None:  # closed-loop
            fam = CLOSED_LOOP if feedback else SUBSPACE  # weightings only under feedback
            checks["input_delay"] = delay_candidates(board, shift, h, fam, max_order,
                                                     _refine if refine else None)
    if feedback and refine and board.starts_only(
            SUBSPACE, "open-loop subspace fit under feedback (biased): a start, not chosen"):
        checks["feedback"] += ("; the open-loop subspace fits (n4sid, moesp, cva), biased "
                               "by it, are refined from but not chosen")
    elif feedback and refine and board.kept_biased is not None:
        # an aircraft's flight test: "detected" above an n4sid choice, with nothing to say
        # why the biased fits were not set aside (as the FeedbackWarning of n4sid advises)
        b, a = board.kept_biased
        checks["feedback"] += (
            "; the open-loop subspace fits (n4sid, moesp, cva), biased by it, stay candidates: "
            + (f"without them the best held-out fit falls from {b:.1f} % to {a:.1f} %, "
               f"clearly below" if a is not None
               else "without them no stable candidate is left (the others are unstable on some "
                    "held-out block, below their start or not scored)"))
    if shift is not None:  # (once the biased fits are set aside)
        checks["input_delay"] += "; " + keep_if_shown(board)
    broken = board.broken()
    if broken:
        r = broken[0]
        checks["candidate_errors"] = (
            f"{len(broken)} candidate(s) failed with an error that says nothing of the data "
            f"(first: {r['family']} of order {r['order']}, {r['note']}); the choice was made "
            f"without them: check the installation (a failed import) or report it")
        warnings.warn(f"identify: {checks['candidate_errors']}", SysidWarning,
                      stacklevel=user_stacklevel())
    if board.skipped:
        checks["long_record"] = (
            f"not scored, to keep the work in proportion on this record: "
            f"{'; '.join(board.skipped)} (each would cost more than the refinements' work "
            f"bound; time_budget does not change this)")
    if board.out_of_time:
        warnings.warn(f"identify stopped scoring candidates after time_budget={time_budget} s "
                      f"({len(board.rows)} scored): the best so far is returned; raise "
                      "time_budget for the full search", SysidWarning, stacklevel=user_stacklevel())
    insist = board.insisting() if enforce_stability is None else None
    if board.drift is not None:
        u = board.drift["unstable"]
        checks["drift"] = (
            f"the record drifts: an unstable {u['family']} model of order {u['order']} "
            f"(largest pole modulus {modulus(u['max_abs_pole'])}) simulates every held-out block "
            f"better than the best stable one, but not once the record's trend is taken out "
            f"(a line per channel): it follows a drift, not the plant; " + (
                "the model with an integrator is returned (checks['integrating'])"
                if board.drift["stable"].get("integrating") else
                "the stable model is returned (remove the trend, sysid.detrend(data, "
                "'linear'), or difference the output if the plant integrates)"))
    if enforce_stability is not False and insist is None and not np.isfinite(board.best_fit()):
        stabilised_candidates(board)
    ranked = board.ranked(allow_unstable=enforce_stability is False or insist is not None)
    model, chosen = _choose(board, ranked, centred, enforce_stability is True or (
        enforce_stability is None and insist is None))
    if (note := integrating_note(model)) is not None:
        checks["integrating"] = note
    if unstable(model):
        from ..errors import StabilityWarning

        free = free_poles(model)  # an integrator made explicit is said by its own check
        rho = float(np.max(np.abs(free)))
        over = board.insisted_over
        # with no stable candidate scored there was nothing to compare it with: the data did
        # not show an unstable model better than a stable one, only that none was stable
        why = ("enforce_stability=False" if insist is None else
               "no stable candidate was scored (every subspace fit is unstable on some "
               "held-out block, and none was left to refine from), so the data were not shown "
               "to prefer it to a stable model: an integrating or unstable plant, or a stable "
               "one the subspace fits miss (a slow mode, a drift)" if over is None else
               f"it simulates every held-out block better than the best stable candidate "
               f"({_family(over)}, order {over['order']}: held-out fit "
               f"{chosen['held_out_fit']:.1f} % against {over['held_out_fit']:.1f} %), as "
               f"an integrating or unstable plant does; if the plant is stable, the mode is "
               f"one the record does not pin down")
        warnings.warn(f"identify returns an unstable model (largest pole modulus {modulus(rho)}; "
                      f"{unstable_modes(free, model.dt)}): {why}; pass "
                      f"enforce_stability=True for the best stable model",
                      StabilityWarning, stacklevel=user_stacklevel())
    for r in ranked:
        r["chosen"] = r is chosen
    rows = [{k: v for k, v in r.items()
             if k not in ("refit", "fit_fn", "start", "stabilised", "fold_models",
                          "fold_output_fits")}
            for r in ranked]
    desc = (f"{_family(chosen)}"
            + (f" ({chosen['focus']} focus)" if chosen["focus"] else "")
            + f", order {chosen['order']}, {'with' if chosen['feedthrough'] else 'no'} "
            f"feedthrough: held-out fit {chosen['held_out_fit']:.1f} %")
    model.info["identify"] = {k: chosen[k] for k in ("family", "order", "feedthrough", "focus",
                                                     "held_out_fit")}
    if "identify_refit" in model.info:
        checks["final_refit"] = model.info["identify_refit"]
    refit_cap_check(model, checks)
    order_excitation_check(int(chosen["order"]), centred, checks, counted)
    trend_check(model, centred, checks)
    persistent_mode_check(model, centred, checks)
    weak_check(float(chosen["held_out_fit"]), checks)
    loop_checks(chosen, feedback, checks)
    if getattr(model, "uncertainty", None) is None:
        model = within_delay(centred, model, lambda d, m: with_uncertainty(
            m, d, checks, SUBSPACE + CLOSED_LOOP))
    result_model = IdentifiedModel(model, mu, my)
    if validation is not None and (note := coverage_note(data, validation)) is not None:
        checks["validation"] = note
    out = IdentifyResult(result_model, rows, desc, checks, reported_fit(result_model, validation),
                         time.perf_counter() - t0, interrupted)
    out.out_of_time = board.out_of_time
    return out
