"""The prediction-error refinements of :func:`sysid.identify`: the best subspace candidates
refined on the simulation error (and the best one on the prediction error) from each fold's
subspace fit, scored on the held-out blocks, settled on the folds and re-fitted on the whole
record to convergence when that is cheap (:func:`_final_refit`); refinements from a stable
``A`` for near-best candidates unstable on some block (:func:`_stabilised_refinements`);
output-error models for one input and output. Their work is bounded in iterations x samples
x parameters squared (:func:`iteration_work`), the same on any machine."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..data.preprocessing import line_share
from ..models.statespace import ss_parameter_count
from ..validation.crossval import TOL, simulation_fit
from .board import Board
from .delay import within_delay
from .sweep import SUBSPACE

__all__ = ["FINAL_ITER", "FINAL_WORK", "FOLD_WORK", "NOMINAL_ITER", "N_REFINE", "REFINE_WORK",
           "SETTLE_POINTS", "SETTLE_WINDOW", "INPUT_TREND_SHARE", "implied_fit", "inputs_trend",
           "iteration_work", "settled"]

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
    >>> from sysid.identify.refine import settled
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
    >>> from sysid.identify.refine import iteration_work
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


#: an input trends when a straight line over its experiment takes out at least this share
#: of its variation (a heater at full power for most of the record, then held low: 61 %)
INPUT_TREND_SHARE = 0.25


def inputs_trend(data: IOData) -> bool:
    """Whether some input of ``data`` trends: in some experiment, a straight line over it
    takes out at least :data:`INPUT_TREND_SHARE` of the input's variation
    (:func:`sysid.data.preprocessing.line_share`). The output's response to such an input
    trends too, and a record's "drift" (:meth:`.board.Board.unstable_verdict`, tested with a
    line taken out of every channel) may then be the plant's response.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.refine import inputs_trend
    >>> step = np.r_[np.ones(300), np.zeros(200)]            # on for 3/5 of the record
    >>> inputs_trend(sysid.IOData(u=step, y=np.zeros(500)))
    True
    >>> prbs = np.sign(np.random.default_rng(0).standard_normal(500))
    >>> inputs_trend(sysid.IOData(u=prbs, y=np.zeros(500)))
    False
    """
    return any(bool(np.any(line_share(u) >= INPUT_TREND_SHARE)) for u, _ in data.experiments)


def _stabilised_refinements(board: Board, data: IOData | None = None) -> None:
    """Refinements from a stable ``A``: the subspace candidates the held-out blocks cannot
    tell from the best of all (stable or not), of orders no stable start was refined at,
    that are unstable on some block (a slow pole estimated just outside the unit circle from
    part of the record), with a stable ``A`` enforced on every fold (Maciejowski's
    zero-padded shift; a start only, not a candidate) and then refined on the simulation
    error as the stable starts are, the smallest ``N_REFINE`` orders. Only while the
    unstable candidates show nothing (:meth:`.board.Board.unstable_verdict`): not when
    they win only by following the record's drift, which a slow stable mode follows as
    well (on a four-stage evaporator, held-out 64 % against 60 %, validation 43 % against
    60 %), unless an input of the record (``data``) trends as well (:func:`inputs_trend`):
    then the output's "drift" can be its response, and taking a line out of every channel
    distorts the input it answers (a pot of water heated at full power for 2/3 of the record,
    then held near 90 degC by a PI loop: only order 1 was left, validation 19.9 %; from a
    stable ``A`` at order 14, 89.5 %; no other choice moved on the 121 records of
    ``benches/realdata_tally.py`` under either split, 20 of which have a trending input), nor
    when the data insist on one (an integrating plant). With no stable candidate
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
    if not picks:
        return
    verdict = "none" if none_stable else board.unstable_verdict()
    if verdict == "drift" and data is not None and inputs_trend(data):
        verdict = "none"  # the drift may be the response to the input's trend
    if verdict != "none":
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
