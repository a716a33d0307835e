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
   (:func:`.refine._stabilised_refinements`); the orders above a refinement that rose past every
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
   held-out blocks a refinement's search stops once it has settled
   (:func:`.refine.settled`: its last iterations raised the fit its criterion implies by
   less than a tenth of what the blocks resolve); re-fitted on the whole record it runs to
   convergence (up to ``FINAL_ITER`` iterations: a search can crawl along a plateau and then
   drop) when that is cheap. On long records the refinements' work is bounded
   (``FINAL_WORK``, ``FOLD_WORK``, ``REFINE_WORK``; :func:`.refine.iteration_work`): the
   whole-record re-fit stops once settled, the fold fits are capped, later refinements are
   not scored (the checks say so).
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
   the data insist on (``checks["drift"]`` says so). An order the input's excitation does
   not determine (``2 n`` above its spectral count) is set aside when a determined one can be
   chosen, unless the blocks insist on it (:func:`.notes.undetermined_orders`).
   ``validation`` data, when given, are only reported on.
5. The chosen model's simulation errors on the record are checked for a drift the input does
   not explain (:mod:`.notes`, ``checks["trend"]``), its held-out fit for a model
   that explains less than half of the outputs' variation (``checks["weak"]``) or that
   simulates the whole record clearly worse than its held-out blocks
   (``checks["whole_record"]``: an error that builds up over longer than a block; the choice
   is then made again by the whole record's BIC among the stable candidates within 10
   points, :func:`.choice.rechoose_on_whole_record`), and its
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
from ..data.preprocessing import repair_isolated_spikes, spike_report
from ..errors import (
    DataError,
    ExcitationError,
    InsufficientDataError,
    SysidWarning,
    several_records_hint,
)
from ..validation.coverage import coverage_note
from ..validation.crossval import (
    MIN_BLOCK,
    record_folds,
    require_held_out_length,
)
from ..validation.output_error import feedback_checked
from ..validation.records import validation_record
from ..validation.swept import held_out_design
from .board import Board, free_poles, informative, unstable
from .choice import _choose, rechoose_on_whole_record
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
    undetermined_orders,
    weak_check,
    whole_record_check,
)
from .oversampled import record_feedback, retry_decimated
from .refine import N_REFINE, _refine, _refined_candidates, _stabilised_refinements
from .result import IdentifiedModel, IdentifyResult, _family, reported_fit
from .states import stabilised_candidates, states_candidates
from .steptest import STAIRCASE_BLOCKS, blocks_with_steps, identify_step_test, input_changes
from .sweep import CLOSED_LOOP, SUBSPACE
from .sweep import horizon as _horizon
from .sweep import subspace_candidates as _subspace_candidates
from .uncertainty import with_uncertainty

__all__ = ["identify"]



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
    return checks, feedback, counted



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
    time_budget: float | None = None,
    progress: bool | None = None,
    repair_spikes: bool = True,
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
        CPU seconds of this process after which no further refinement is scored: the
        subspace sweep is always complete (it works on compressions of the record), the
        refinements are scored most promising first until the budget is spent, and the
        choice is made among what was scored (``result.out_of_time`` and a warning say so).
        A clock: where it binds, the choice depends on the machine, its load and the
        threads (on a busy machine the same work takes more CPU seconds). Default ``None``:
        no clock; the refinements' work is bounded in iterations x samples x parameters^2
        instead, the same on any machine (``result.checks`` says what it changed; the
        longest of 121 real records took 63 CPU seconds in all, on an idle machine).
    progress : bool, optional
        A progress bar over the candidates (default: only when stderr is a terminal).
        Ctrl-C stops the search (``KeyboardInterrupt``, as every other computation: a script
        or a batch must not carry on with a half-chosen model).
    repair_spikes : bool
        Replace the outputs' isolated spikes (a single sample far from both neighbours and
        far out in the record: a logger glitch, which every fit bends to) by the mean of
        their neighbours before anything is fitted, except next to a spike of an input
        and where the glitch spans several samples (then it is only reported;
        :func:`sysid.data.preprocessing.repair_isolated_spikes`); ``result.checks
        ["outliers"]`` and a warning name the samples. The test is conservative: it finds
        none in the 121 real records of ``benches/realdata_tally.py``. ``False``: fit the
        record as it is (then the check only warns).

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
    where: dict[str, list[int]] = {}
    if repair_spikes:  # before the means: a glitch moves them too
        data, where = repair_isolated_spikes(data)
    left = spike_report(data)  # kept: asked to, several samples, or next to an input's spike
    notes = [f"output {k}: {len(v)} isolated spike(s) at sample(s) "
             f"{', '.join(map(str, v[:8]))}{' ...' if len(v) > 8 else ''}"
             for k, v in where.items()]
    spiked = "; ".join(notes) + (" replaced by the mean of their neighbours before the fit "
                                 "(logger glitches that every fit would bend to); to fit them "
                                 "as recorded: sysid.identify(data, repair_spikes=False)"
                                 if notes else "")
    if left:
        spiked += (("; left in the record: " if notes else "") + f"{left}: every fit bends to "
                   "them; repair them first (sysid.despike(data)) or cut them out")
    centred, mu, my = remove_means(data)
    checks, feedback, counted = _checks(centred)
    if spiked:
        checks["outliers"] = spiked
        warnings.warn(f"identify: {spiked}", SysidWarning, stacklevel=user_stacklevel())
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
            _stabilised_refinements(board, centred)
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
    if (note := undetermined_orders(board, centred, counted)) is not None:
        checks["order_excitation_choice"] = note
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
    whole_record_check(model, centred, board.lower_score(chosen), shortest, checks)
    model, chosen = rechoose_on_whole_record(board, centred, model, chosen, checks)
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
                          "fold_output_fits", "whole_refit")}
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
    if validation is not None and (glitch := spike_report(validation)) is not None:
        checks["validation_outliers"] = (
            f"the validation record has {glitch}: its reported fit counts them, as recorded "
            f"(sysid.despike(validation) to score the model without them)")
    out = IdentifyResult(result_model, rows, desc, checks, reported_fit(result_model, validation),
                         time.perf_counter() - t0, interrupted)
    out.out_of_time = board.out_of_time
    return out
