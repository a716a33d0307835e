"""The leaderboard of :func:`sysid.identify`: candidates scored on blocks of the estimation
record held out from their fit, ranked, and the rules that pick one.

Each candidate is fitted on every fold's fitted part and simulated on its held-out block
(initial state and a constant offset per output fitted,
:func:`sysid.validation.crossval.simulation_fit`). Its score (:func:`held_out_score`) is
the fit of the held-out blocks **pooled**, per output ``100 (1 - sqrt(sum |e_k|^2 / sum
|y_k - mean(y_k)|^2))`` over the blocks ``k``, **trimmed**: without the block where the
candidate fits worst and the one where it fits best (from three blocks on). A record often
holds one block unlike the others (a saturation, a change of operating point, a stretch
where some input is idle), and the pooled fit would then rank the candidates by that block
alone; without it they are ranked by what they do on the typical stretches of the record,
which is what fresh data from the same plant will be.

Pooled, not averaged: the fit on fresh data is one ratio of error to output variation over the
whole record, and its estimate from the blocks is the ratio of their sums (the ratio
estimator), not the mean of the blocks' ratios. The mean of ratios gives a quiet block (an
operating point where the output barely moves, the tail of a decaying test) as much weight as
a lively one, and there the fit divides by a tiny variation: it swings by tens of points
between candidates for errors a lively block would not notice, and ranks them alone (on a
record whose last blocks are quiet, every candidate scored far below zero there and the
choice followed that noise). Pooled, each block weighs what its output variation weighs in
the record. The mean and every fold's fit are kept in the leaderboard.
"""

from __future__ import annotations

import time
import warnings
from contextlib import closing
from typing import Any

import numpy as np

from .._parallel import ordered
from .._progress import Bar
from ..data.iodata import IOData
from ..errors import SysidError
from ..models.input_delay import delay_free_view
from ..models.statespace import delay_free_order, ss_parameter_count
from ..validation.crossval import output_fits, preceding_inputs, simulation_errors, variation
from ..validation.ties import (  # the subspace automatic order's rule too
    RESOLUTION,
    slack,
    tie,
    wins_every_block,
)

__all__ = ["Board", "informative", "RESOLUTION", "slack", "tie", "bic", "free_poles",
           "held_out_score", "noise_fitted", "unstable"]

def block_fit(fits: Any) -> float:
    """A block's fit: the mean over its outputs (those that move), ``-inf`` when none does."""
    f = np.asarray(fits, float)
    f = f[~np.isnan(f)]
    return float(np.mean(f)) if f.size else -np.inf


def held_out_score(fits: Any, weights: Any = None, trim: bool = True) -> float:
    """The held-out score of a candidate from its fits on the blocks: pooled over the blocks,
    without the one where it fits worst and the one where it fits best (from three blocks on;
    ``trim=False``: all of them).

    ``fits`` is ``(blocks, outputs)`` (or one value per block), the fit % of every output on
    every block; ``weights`` the same shape (or per block), the output variation of each
    block, ``|y_k - mean(y_k)|^2`` (default: equal). Per output, the kept blocks' squared
    errors ``(1 - f / 100)^2 w`` and variations ``w`` are summed and their ratio is the
    pooled fit (the fit of the blocks as one record); the score is the mean over outputs.

    Examples
    --------
    >>> from sysid.identify.board import held_out_score
    >>> round(held_out_score([10.0, 80.0, 90.0, 90.0, 99.0]), 2)  # the extremes left out
    85.86
    >>> fits = [90.0, 95.0, -100.0, -120.0, -150.0]  # two lively blocks, three quiet ones
    >>> round(held_out_score(fits), 2), round(held_out_score(fits, [1, 1, 0.01, 0.01, 0.01]), 2)
    (-71.76, 68.94)
    """
    F = np.asarray(fits, float)
    F = F[:, None] if F.ndim == 1 else F
    W = np.ones_like(F) if weights is None else np.asarray(weights, float)
    W = np.broadcast_to(W[:, None] if W.ndim == 1 else W, F.shape)
    keep = np.arange(F.shape[0])
    if trim and F.shape[0] >= 3:
        keep = np.sort(np.argsort([block_fit(f) for f in F], kind="stable")[1:-1])
    out = []
    with np.errstate(all="ignore"):
        for f, w in zip(F[keep].T, W[keep].T):
            ok = (w > 0) & ~np.isnan(f)
            if np.any(ok):
                out.append(100.0 * (1.0 - np.sqrt(np.sum((1.0 - f[ok] / 100.0) ** 2 * w[ok])
                                                  / np.sum(w[ok]))))
    score = float(np.mean(out)) if out else -np.inf
    return score if np.isfinite(score) else -np.inf


def noise_fitted(model: Any) -> bool:
    """Whether ``model``'s Kalman gain ``K`` was estimated with its dynamics (a
    prediction-focus :func:`sysid.pem` fit, ``info["pem"]["focus"]``): its entries then
    shaped ``A, B, C, D`` and count among the parameters fitted to the record. A subspace
    fit's ``K`` is solved from the residuals once ``A, B, C, D`` are fixed, and plays no
    part in their simulation: it is not counted (as :meth:`Board.parameters` counts the
    candidates).

    Examples
    --------
    >>> import sysid
    >>> from sysid.identify.board import noise_fitted
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], K=[[0.3]])
    >>> noise_fitted(m)
    False
    >>> m.info["pem"] = {"focus": "prediction"}
    >>> noise_fitted(m)
    True
    """
    K = getattr(model, "K", None)
    if K is None or not np.any(np.asarray(K) != 0):
        return False
    fit = (getattr(model, "info", None) or {}).get("pem")
    return isinstance(fit, dict) and fit.get("focus") == "prediction"


def bic(model: Any, data: IOData) -> float:
    """Bayesian information criterion of a model fitted on ``data``, from its simulation
    errors there (initial state and output offsets fitted): ``N log det(E^T E / N) + p log
    N``, an output's errors taken as at least :data:`RESOLUTION` fit points of its spread (a
    fit within that of 100 % is a tie), with ``p = n (m + l + e) + m l`` (the last term
    with a feedthrough) ``+ n l`` (with a Kalman gain estimated with the dynamics,
    :func:`noise_fitted`), the identifiable parameter count of ``A, B, C``, ``D``, ``K`` and
    the initial states of the record's ``e`` experiments (each fitted: counted once, a
    record cut into experiments by its gaps had a model of order 10 chosen where its blocks
    could not tell it from order 3, 50 fitted initial values counted as 10). A subspace
    fit's ``K``, on which no simulation error depends, is not counted: the leaderboard
    charged it to every subspace candidate, while the model returned, the same fit without
    its ``K``, scored without it. ``n`` leaves out the states of known input delays the
    model absorbed (:func:`~sysid.models.statespace.delay_free_order`): a delay is no
    parameter, nor are its delay line's initial values.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.board import bic
    >>> u = np.random.default_rng(0).standard_normal(400)
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    >>> y = m.simulate(u) + 0.1 * np.random.default_rng(1).standard_normal((400, 1))
    >>> d = sysid.IOData(u, y)
    >>> idle = sysid.StateSpaceModel(np.diag([0.5, 0.1]), [[1.0], [0.0]], [[1.0, 0.0]])
    >>> bool(bic(m, d) < bic(idle, d))  # a state that explains nothing costs its parameters
    True
    """
    errs = simulation_errors(model, data, prior=False)  # x0 counted in p
    E = np.vstack([e for _, e in errs])
    N = E.shape[0]
    S = E.T @ E / N
    # an output's errors within RESOLUTION fit points of 100 % count as that large: fits
    # closer than that are ties (records with next to no noise), and the parameters decide
    floor = (RESOLUTION / 100.0) ** 2 * variation(data) / N
    S = S + np.diag(np.maximum(floor - np.diag(S), 0.0))
    sign, logdet = np.linalg.slogdet(S)
    if sign <= 0 or not np.isfinite(logdet):
        return -np.inf if sign == 0 else np.inf
    n, feedthrough = delay_free_order(model)  # known input delays' states cost nothing
    p = ss_parameter_count(n, model.ninputs, model.noutputs, feedthrough=feedthrough,
                           noise_model=noise_fitted(model), x0=True,
                           n_experiments=data.n_experiments)
    return float(N * logdet + p * np.log(N))


def free_poles(model: Any) -> np.ndarray:
    """The poles of ``model`` apart from the integrators it was built with
    (:func:`.integrating.integrated`, ``info["integrating"]``: each a pole pinned at exactly
    1, a marginally stable mode, not a diverging one): all poles but the one nearest 1 for
    each integrated output (in any basis of the states).

    Examples
    --------
    >>> import sysid
    >>> from sysid.identify.board import free_poles
    >>> m = sysid.StateSpaceModel([[0.5, 0.0], [1.0, 1.0]], [[1.0], [0.0]], [[0.0, 1.0]])
    >>> m.info["integrating"] = {"outputs": [0], "free_order": 1}
    >>> free_poles(m), m.poles()  # the pole at 1 is the integrator's
    (array([0.5+0.j]), array([1. +0.j, 0.5+0.j]))
    """
    poles = np.asarray(model.poles())
    spec = (getattr(model, "info", None) or {}).get("integrating")
    if not spec:
        return poles
    pinned = np.argsort(np.abs(poles - 1.0), kind="stable")[:len(spec["outputs"])]
    return np.delete(poles, pinned)


def unstable(model: Any) -> bool:
    """Whether a pole of ``model`` other than its integrators made explicit
    (:func:`free_poles`) lies on or outside the unit circle: the stability identify judges,
    warns about and reports."""
    return bool(np.any(np.abs(free_poles(model)) >= 1.0))


def block_fits(model: Any, held: IOData, whole: IOData | None = None, **kw: Any
               ) -> np.ndarray:
    """:func:`~sysid.validation.crossval.output_fits` of ``model`` on a held-out block; a
    model with absorbed input delays as its delay-free model sees the block
    (:func:`~sysid.models.input_delay.delay_free_view`), simulated at the delay-free order's
    cost, not the delay lines'. Its delay lines hold the inputs recorded before the block in
    ``whole``, the record it was cut from
    (:func:`~sysid.validation.crossval.preceding_inputs`), not fitted; without ``whole``,
    the block's first input.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.models.input_delay import absorb_delay
    >>> m = absorb_delay(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), [30])
    >>> u = np.random.default_rng(0).standard_normal(600)
    >>> d = sysid.IOData(u=u, y=m.simulate(u))
    >>> held = sysid.IOData(u=d.u[300:], y=d.y[300:])  # a block cut from d
    >>> bool(block_fits(m, held)[0] < 99), bool(block_fits(m, held, whole=d)[0] > 99.9)
    (True, True)
    """
    delays = (getattr(model, "info", None) or {}).get("input_delay")
    before = None
    if delays is not None and whole is not None:
        before = preceding_inputs(whole, held, int(np.max(delays, initial=0)))
    return output_fits(*delay_free_view(model, held, before), **kw)


class Board:
    """Candidates with their held-out scores and a way to re-fit each on the whole record."""

    def __init__(self, folds: list[tuple[IOData, IOData]], bar: Bar,
                 deadline: float | None = None) -> None:
        self.rows: list[dict[str, Any]] = []
        self.folds, self.bar, self.deadline = folds, bar, deadline
        #: (blocks, outputs): every held-out block's output variation (:func:`held_out_score`)
        self.weights = np.array([variation(held) for _, held in folds])
        #: every block's share of the output variation of all blocks (mean over outputs)
        total = self.weights.sum(0)
        self.shares = np.mean(self.weights / np.where(total > 0, total, 1.0), axis=1)
        self.out_of_time = False
        #: the whole record (its refinements' fold fits are further starts of their re-fit)
        self.whole: IOData | None = None
        #: refinements left out to keep the work in proportion (:data:`.refine.REFINE_WORK`)
        self.skipped: list[str] = []
        #: the expected work of the refinements scored so far (:data:`.refine.REFINE_WORK`)
        self.refine_work = 0.0
        #: folds left out because their fitted part does not excite the input enough
        self.unexcited = 0
        #: set by :meth:`insisting` when an unstable candidate wins only by following a drift
        self.drift: dict[str, Any] | None = None
        #: set by :meth:`insisting` when the data insist on an unstable candidate: the best
        #: stable candidate it beat (``None`` when no stable candidate was left)
        self.insisted_over: dict[str, Any] | None = None
        #: the subspace sweep's fold estimators, whole-record estimator (a function of the
        #: record) and largest order, and whether the record shows feedback: for the
        #: state-sequence candidates (:func:`.states.states_candidates`)
        self.subspace: tuple[list[Any], Any, int] | None = None
        self.feedback = False
        #: the best held-out fit with and without the open-loop subspace fits, when they stay
        #: candidates under feedback (:meth:`starts_only`)
        self.kept_biased: tuple[float, float | None] | None = None

    def keep_folds(self, keep: list[int]) -> None:
        """Only the folds ``keep`` (indices, in order) stay: their blocks, output variations
        and shares (a fold left out of the middle had the scores of the later blocks weighed
        by the variations of the earlier ones)."""
        self.unexcited += len(self.folds) - len(keep)
        self.folds[:] = [self.folds[k] for k in keep]
        self.weights = self.weights[keep]
        total = self.weights.sum(0)
        self.shares = np.mean(self.weights / np.where(total > 0, total, 1.0), axis=1)

    def time_left(self) -> bool:
        """False once the time budget (CPU seconds of this process) is spent."""
        if self.deadline is not None and time.process_time() > self.deadline:
            self.out_of_time = True
        return not self.out_of_time

    def effective_blocks(self) -> float:
        """The effective number of held-out blocks, ``1 / sum(share^2)`` of their shares of
        the output variation (Kish's effective sample size): the count when they vary alike,
        about 1 when one block holds nearly all of it (the score then rests on it alone)."""
        return float(1.0 / np.sum(self.shares ** 2)) if np.sum(self.shares) > 0 else 0.0

    def score(self, fits: Any) -> float:
        """:func:`held_out_score` of per-output fits on the first ``len(fits)`` blocks."""
        return held_out_score(fits, self.weights[:len(fits)])

    def lower_score(self, row: dict[str, Any]) -> float:
        """The lower of ``row``'s held-out score and its blocks pooled without leaving out
        the extremes: what the blocks say with or without their atypical ones (on a maglev
        record the worst block, left out, was the one that resembled fresh data)."""
        outs = row.get("fold_output_fits") or []
        whole = held_out_score(outs, self.weights[:len(outs)], trim=False) if outs else np.inf
        return float(min(row["held_out_fit"], whole))

    def stopper(self) -> Any:
        """A progress callback for iterative fits: stops them once the budget is spent."""
        def cb(*_: Any) -> bool:
            return self.time_left()
        return cb

    def add(self, family: str, order: int, feedthrough: bool, focus: str | None,
            criterion: str, fit_fn: Any, refit: Any, start: dict[str, Any] | None = None,
            budgeted: bool = True) -> dict[str, Any] | None:
        """Score a candidate: ``fit_fn(k)`` fits it on fold ``k``, ``refit(data)`` on the whole
        record; ``start`` is the leaderboard row it was refined from, if any. ``budgeted``
        candidates are skipped once the time budget is spent (the subspace sweep is not)."""
        if budgeted and not self.time_left():
            return None
        t = time.perf_counter()
        row: dict[str, Any] = {"family": family, "order": order, "feedthrough": feedthrough,
                               "focus": focus, "criterion": criterion, "refit": refit,
                               "fit_fn": fit_fn, "start": start, "note": ""}
        hopeless = False
        # the budgeted candidates (refinements, output-error models) are fitted on the
        # blocks in parallel, in order (the same fits as one after another; the blocks
        # fitted ahead of a hopeless one's stop are stopped); the subspace sweep's fits are
        # too short to gain from threads. The warnings filter is the process's: the fits'
        # own warnings are silenced around the threads, not inside them.
        tasks = [lambda k=k: fit_fn(k) for k in range(len(self.folds))]
        try:
            fits, outs, rho = [], [], 0.0
            with warnings.catch_warnings(), closing(ordered(tasks, None if budgeted else 1)
                                                    ) as models:
                warnings.simplefilter("ignore")
                for k, ((_, held), model) in enumerate(zip(self.folds, models)):
                    outs.append(block_fits(model, held, self.whole, dev=self.weights[k]))
                    fits.append(block_fit(outs[-1]))
                    if start is not None:  # a refinement's fold fits: starts for its re-fit
                        row.setdefault("fold_models", []).append(model)
                    poles = free_poles(model)
                    rho = max(rho, float(np.max(np.abs(poles))) if len(poles) else 0.0)
                    if start is not None and self._below_start(fits, outs, start):
                        hopeless = True  # the remaining blocks cannot save it: not fitted
                        break
            f = np.asarray(fits)
            row["held_out_fit"] = self.score(outs)
            row["mean_fit"] = float(np.mean(f)) if np.all(np.isfinite(f)) else -np.inf
            row["fold_fits"] = [float(x) for x in f]
            row["fold_output_fits"] = outs
            row["max_abs_pole"] = rho
            row["stable"] = rho < 1.0
        except KeyboardInterrupt:
            raise
        except Exception as e:  # noqa: BLE001 - a failed candidate is listed, not raised
            row.update(held_out_fit=-np.inf, mean_fit=-np.inf, fold_fits=[], fold_output_fits=[],
                       max_abs_pole=np.nan, stable=False, error=type(e),
                       note=f"{type(e).__name__}: {e}"[:120])
        if hopeless:
            row["note"] = (f"below its start or the best candidate on most of the "
                           f"{len(self.folds)} held-out blocks after {len(fits)}: stopped, "
                           "not chosen")
            row["worse_than_start"] = True
        elif budgeted and not self.time_left():
            row["note"] = "time budget spent while it was fitted: not chosen"
            row["worse_than_start"] = True
        elif (start is not None and not start.get("start_only")
              and row["held_out_fit"] < start["held_out_fit"] - tie(start["held_out_fit"])):
            # (a start that is not a candidate is no alternative: the board's best is)
            row["note"] = (f"held-out fit below its start's ({start['held_out_fit']:.1f} %): "
                           "not chosen")
            row["worse_than_start"] = True
        row["seconds"] = time.perf_counter() - t
        self.rows.append(row)
        self.bar.update(1, best=f"{self.best_fit():.1f}%")
        return row

    def _below_start(self, fits: list[float], outs: list[np.ndarray], start: dict[str, Any]
                     ) -> bool:
        """A refinement below its start (one that is itself a candidate: a stabilised
        subspace fit is only a start), or below the best stable candidate scored so far
        (by more than :func:`tie`), on most of the held-out blocks (blocks holding more
        than half of their output variation, as the score weighs them: most of them when
        they vary alike), whatever it does on the blocks not yet scored: no typical stretch
        of the record favours it; or one whose
        score would stay below theirs by more than the slack even if it did as well as they
        do, plus the slack, on every block not yet scored: it cannot catch up. It is not
        fitted on the remaining blocks and not chosen (the costly refinements of high orders
        are mostly these)."""
        best = self.best() if len(fits) < len(self.folds) else None  # (once all are scored,
        # the held-out score decides whether it is near the best)
        refs = [r for r in (start, best) if r is not None and not r.get("start_only")]
        for ref_row in (refs if best is not start else refs[:1]):
            ref = ref_row.get("fold_fits") or []
            if len(ref) != len(self.folds):
                continue
            s = tie(ref_row["held_out_fit"])
            below = sum(w for w, a, b in zip(self.shares, fits, ref) if a < b - s)
            if below > 0.5 + 1e-9:
                return True
            # even as good as the reference plus the slack on every block not yet scored, its
            # score would stay below the reference's by more than the slack
            more = ref_row["fold_output_fits"][len(fits):]
            if len(fits) < len(ref) and self.score_bound(
                    list(outs) + [b + s for b in more], len(fits)) < ref_row["held_out_fit"] - s:
                return True
        return False

    def score_bound(self, outs: list[Any], known: int) -> float:
        """The highest score a candidate can reach whose per-output fits are ``outs`` on the
        first ``known`` blocks and at most ``outs`` on the others. :func:`held_out_score`
        leaves out the blocks where the candidate fits worst and best, so a fit that falls
        can move the cut to a block of more variation and raise the score: the score of
        ``outs`` bounds only fits that keep the same cut. The bound is the best pooled fit
        over every cut the unknown fits can still make (the worst block cannot be a known one
        above another block's reach, nor the best a known one below a known block; with a
        known best block, the unknown ones reach at most its fit).

        Examples
        --------
        >>> import numpy as np
        >>> from sysid.identify.board import Board
        >>> b = Board.__new__(Board)
        >>> b.weights = np.array([[1472.0], [1937.0], [335.0], [1124.0], [554.0]])
        >>> outs = [[81.4], [82.0], [59.3], [74.9], [62.7]]  # the first block known
        >>> bool(b.score_bound(outs, 1) > b.score(outs))  # 82.0 falling keeps block 2
        True
        >>> bool(b.score_bound(outs, 5) == b.score(outs))  # all known: the score itself
        True
        """
        F = np.asarray(outs, float)
        F = F[:, None] if F.ndim == 1 else F
        K = F.shape[0]
        W = self.weights[:K]
        if K < 3 or known >= K:
            return held_out_score(F, W)
        f = np.array([block_fit(x) for x in F])
        top_known = float(np.max(f[:known])) if known else -np.inf
        best = -np.inf
        for i in range(K):  # the block left out as the worst
            if i < known and (np.any(f[:known] < f[i]) or np.any(f[known:] < f[i])):
                continue  # a known block above another's reach cannot be the worst
            for j in range(K):  # the block left out as the best
                if j == i or (j < known and np.any(f[:known] > f[j])) or (
                        j >= known and f[j] < top_known):
                    continue
                G = F.copy()
                if j < known:  # the unknown blocks reach at most the best one's fit
                    G[known:] -= np.maximum(f[known:] - f[j], 0.0)[:, None]
                best = max(best, held_out_score(np.delete(G, [i, j], 0),
                                                np.delete(W, [i, j], 0), trim=False))
        return best

    def starts_only(self, families: tuple[str, ...], note: str) -> int:
        """Make the plain subspace candidates of ``families`` starts only (refined from, not
        chosen; ``note`` says why), unless the best stable candidate left scores clearly
        below the best one (by more than :func:`tie`: the
        blocks then prefer the biased fit to every other) or none is left; returns how many.
        When they are kept, ``kept_biased`` holds the best held-out fit with and without them
        (None: no stable candidate is left without them).
        Under feedback the open-loop subspace fits are biased (the future inputs the data
        matrix projects on are correlated with the past noise): on a buck converter in
        closed loop the choice was ``n4sid`` order 3, validated at 46.6 %, where the
        refinement of order 18 the blocks scored best validates at 59.8 %."""
        rows = [r for r in self.rows if r["criterion"] == "subspace"
                and r["family"] in families and not r.get("start_only")]
        before = self.best()
        for r in rows:
            r["start_only"] = True
        after = self.best()
        if after is None or (before is not None and after["held_out_fit"]
                             < before["held_out_fit"] - tie(before["held_out_fit"])):
            for r in rows:
                r["start_only"] = False
            if rows and before is not None:  # kept: the best fits with and without them
                self.kept_biased = (before["held_out_fit"],
                                    None if after is None else after["held_out_fit"])
            return 0
        for r in rows:
            r["note"] = r["note"] or note
        return len(rows)

    def eligible(self, r: dict[str, Any], stable_only: bool = True) -> bool:
        """Whether ``r`` can be chosen: scored, not below its start, not only a start (a
        subspace fit with a stable ``A`` enforced, refined from), of an order the input's
        excitation determines (:func:`~sysid.identify.notes.undetermined_orders`), and
        stable unless
        ``stable_only`` is off (and the data insisted on it, when they were asked)."""
        return (bool(np.isfinite(r["held_out_fit"])) and not r.get("worse_than_start")
                and not r.get("start_only") and not r.get("undetermined")
                and (r["stable"] or not (stable_only or r.get("not_insisted"))))

    def rising(self, top: int) -> set[tuple[str, bool]]:
        """The subspace methods (with their feedthrough choice) whose best stable candidate
        on the held-out blocks has the grid's top order ``top``: their fit still rises there
        (a 2 x 28 flexible structure: CVA with ``D`` best at order 20 of 1-20, 32 %, and
        90-93 % from order 26 on, while the best of all was order 16)."""
        best: dict[tuple[str, bool], dict[str, Any]] = {}
        for r in self.rows:
            key = (r["family"], r["feedthrough"])
            if r["criterion"] == "subspace" and self.eligible(r) and (
                    key not in best or r["held_out_fit"] > best[key]["held_out_fit"]):
                best[key] = r
        return {key for key, r in best.items() if r["order"] == top}

    def best_fit(self, stable_only: bool = True) -> float:
        best = self.best(stable_only)
        return best["held_out_fit"] if best is not None else -np.inf

    def best(self, stable_only: bool = True) -> dict[str, Any] | None:
        """The eligible candidate with the best score (None when there is none)."""
        rows = [r for r in self.rows if self.eligible(r, stable_only)]
        return max(rows, key=lambda r: r["held_out_fit"]) if rows else None

    def is_near(self, r: dict[str, Any], best: dict[str, Any] | None,
                stable_only: bool = True, paired: bool = False) -> bool:
        """``r`` is eligible and the held-out blocks cannot tell it from ``best``: its score
        is within :func:`tie` of the best's (``paired``: or, with no more parameters than
        the best, within one standard error of its block-by-block difference to the best,
        :meth:`paired_se`: the blocks may trade score for simplicity within their spread,
        never for more parameters, which would only fit the record's noise better)."""
        if best is None or not self.eligible(r, stable_only):
            return False
        gap = tie(best["held_out_fit"])
        if paired and self.parameters(r) <= self.parameters(best):
            gap = max(gap, self.paired_se(r, best))
        return bool(r["held_out_fit"] >= best["held_out_fit"] - gap)

    def parameters(self, r: dict[str, Any]) -> int:
        """The identifiable parameter count of candidate ``r`` (as :func:`bic` counts them):
        ``A, B, C`` and an initial state per experiment of the whole record, ``D`` with a
        feedthrough, ``K`` with the prediction focus."""
        first = self.folds[0][0] if self.folds and self.folds[0] is not None else None
        rec = getattr(self, "whole", None)  # (a board made bare, as in tests, has none)
        return ss_parameter_count(int(r.get("order") or 0),
                                  first.n_inputs if first is not None else 1,
                                  first.n_outputs if first is not None else 1,
                                  feedthrough=bool(r.get("feedthrough")),
                                  noise_model=r.get("focus") == "prediction", x0=True,
                                  n_experiments=rec.n_experiments if rec is not None else 1)

    def paired_se(self, r: dict[str, Any], best: dict[str, Any]) -> float:
        """The standard error of the mean block-by-block difference of the fits of ``r`` and
        ``best`` (each block weighing its share of the output variation): how far apart
        the held-out blocks put two candidates by chance alone. 0 when a fit is not finite
        or the blocks differ.

        Examples
        --------
        >>> import numpy as np
        >>> from sysid.identify.board import Board
        >>> b = Board.__new__(Board)
        >>> b.shares = np.full(4, 0.25)
        >>> r = {"fold_fits": [70.0, 64.0, 67.0, 75.0]}
        >>> best = {"fold_fits": [76.0, 49.0, 74.0, 72.0]}
        >>> round(b.paired_se(r, best), 2)  # differences -6, 15, -7, 3: mean 1.25
        5.11
        """
        a, b = np.asarray(r.get("fold_fits") or [], float), np.asarray(
            best.get("fold_fits") or [], float)
        w = np.asarray(self.shares, float)
        if a.shape != b.shape or a.shape != w.shape or not (
                np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
            return 0.0
        w = w / np.sum(w)
        d = a - b
        keff = 1.0 / np.sum(w ** 2)
        var = np.sum(w * (d - np.sum(w * d)) ** 2) / max(keff - 1.0, 1.0)
        return float(np.sqrt(var))

    def insisting(self) -> dict[str, Any] | None:
        """An unstable candidate the data insist on: better than the best stable candidate
        on every held-out block (a sign test at ``2**-K``, K >= 4 blocks) and by more than
        :func:`tie` on the score (an integrating or open-loop unstable plant), and so against
        every stable candidate the blocks cannot tell from the best stable one
        (:meth:`is_near`: any of them could be the best, the top score being the maximum of
        noisy scores; a test against the top one alone passes by the luck of which it is
        far more often than ``2**-K``), also once the
        record's drift is taken out (:meth:`_trend_fits`; otherwise it follows a drift and
        :attr:`drift` records it). The best scoring such candidate is returned, not the best
        scoring unstable one: the trimmed score forgives one block, and an unstable model
        that diverges on one block (a fast unstable mode the other blocks do not excite) is
        just what the sign test must not pass. Once the data insist, the unstable candidates
        that do not win on every block are not eligible (``not_insisted``): the choice among
        unstable models is made among those the data insist on."""
        outcome, best_u, best_s, winners = self._insist_test()
        if outcome == "insist":
            for r in self.rows:
                if (self.eligible(r, False) and not r["stable"]
                        and not any(r is w for w in winners)):
                    r["not_insisted"] = True
                    r["note"] = r["note"] or ("unstable and not better than the best stable "
                                              "candidate on every held-out block: not chosen")
            self.insisted_over = best_s
            return best_u
        if outcome == "drift":
            self.drift = {"unstable": best_u, "stable": best_s}
        return None

    def broken(self) -> list[dict[str, Any]]:
        """Candidates that failed with an error that says nothing of the data (not a
        :class:`~sysid.SysidError`, an arithmetic or a linear-algebra failure, nor a
        ``ValueError``): an import that failed, a bug. The choice was made without them."""
        return [r for r in self.rows if isinstance(r.get("error"), type)
                and not issubclass(r["error"], (SysidError, ArithmeticError, ValueError))]

    def unstable_verdict(self) -> str:
        """What the unstable candidates show so far, by the test of :meth:`insisting`
        (the board is not marked): ``"insist"`` (the data insist on one: an integrating or
        unstable plant, or no stable candidate at all), ``"drift"`` (one beats the stable
        ones on every held-out block only while the record's drift is left in) or
        ``"none"``."""
        return self._insist_test()[0]

    def _insist_test(self) -> tuple[str, Any, Any, list[dict[str, Any]]]:
        """:meth:`insisting`'s test: ``("insist" | "drift" | "none", best unstable winner,
        best stable candidate, the winners)``; the board is left as it is."""
        stable = [r for r in self.rows if self.eligible(r)]
        unstable = [r for r in self.rows if self.eligible(r, False) and not r["stable"]]
        if not unstable or len(self.folds) < 4:
            return "none", None, None, []
        if not stable:
            best_u = max(unstable, key=lambda r: r["held_out_fit"])
            if all(np.isfinite(best_u["fold_fits"])):  # no stable one: none is marked
                return "insist", best_u, None, unstable
            return "none", None, None, []
        best_s = max(stable, key=lambda r: r["held_out_fit"])
        # every stable candidate the blocks cannot tell from the best stable one could be
        # it (the best score is the maximum of noisy scores): the test holds against each
        refs = [r for r in stable if self.is_near(r, best_s)]
        winners = [r for r in unstable if all(
            self._wins(r["fold_output_fits"], s["fold_output_fits"]) for s in refs)]
        if not winners:
            return "none", None, best_s, []
        best_u = max(winners, key=lambda r: r["held_out_fit"])
        if all(self._wins(*self._trend_fits([best_u, best_s], d)) for d in (False, True)):
            return "insist", best_u, best_s, winners
        return "drift", best_u, best_s, winners

    def beats_without_drift(self, r: dict[str, Any], ref: dict[str, Any]) -> bool:
        """Whether ``r`` beats ``ref`` as :meth:`insisting` asks of an unstable candidate:
        better on every held-out block and by more than :func:`tie` on the score, both as
        scored and once the record's drift is taken out of the held-out blocks and the
        fitted parts (:meth:`_trend_fits`)."""
        return all(self._wins(*self._trend_fits([r, ref], d)) for d in (False, True))

    def _wins(self, ou: list[Any], os: list[Any]) -> bool:
        """Better on every block, and by more than :func:`tie` on the score (per-output fits
        on every block): a stable candidate within :data:`RESOLUTION` of 100 % is never
        beaten."""
        score, ref = self.score(ou), self.score(os)
        return len(ou) == len(self.folds) == len(os) and wins_every_block(
            [block_fit(f) for f in ou], [block_fit(f) for f in os], score, ref
        ) and score > ref + tie(score)

    def _trend_fits(self, rows: list[dict[str, Any]], detrended: bool
                    ) -> list[list[np.ndarray]]:
        """The held-out fits of ``rows`` with a straight line per output fitted on every
        held-out block (with the initial state), the models fitted on every fold's fitted
        part as scored (``detrended=False``) or re-fitted on it with a straight line removed
        from each channel (:func:`sysid.detrend`): the record's drift taken out of the
        blocks, and of the fitted parts too. A slow unstable mode can follow a drift (an
        output trend the input does not explain, or the residue of a removed one) on every
        block; an unstable model that wins only with the drift left in follows it, not the
        plant, and the data do not insist on it."""
        from ..data.preprocessing import detrend

        # kept on each row (``r["trend_fits"]``): the test runs before the stable-A
        # refinements (:meth:`unstable_verdict`) and again for the choice
        todo = [r for r in rows if detrended not in r.setdefault("trend_fits", {})]
        fits: list[list[np.ndarray]] = [[] for _ in todo]
        for k, (fit_part, held) in enumerate(self.folds):
            part = detrend(fit_part, "linear") if detrended and todo else None
            for i, r in enumerate(todo):
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        model = r["refit"](part) if detrended else r["fit_fn"](k)
                    fits[i].append(block_fits(model, held, self.whole, trend=True))
                except KeyboardInterrupt:
                    raise
                except Exception:  # noqa: BLE001 - a fit that fails now scores -inf
                    fits[i].append(np.full(held.n_outputs, -np.inf))
        for r, f in zip(todo, fits):
            r["trend_fits"][detrended] = f
        return [r["trend_fits"][detrended] for r in rows]

    def near_best(self, stable_only: bool = True, paired: bool = False
                  ) -> list[dict[str, Any]]:
        """Eligible candidates the held-out blocks cannot tell from the best
        (:meth:`is_near`): refined ones first, then by score."""
        best = self.best(stable_only)
        near = [r for r in self.rows if self.is_near(r, best, stable_only, paired)]
        # refined candidates first (few; each the refinement of a near-best start)
        return sorted(near, key=lambda r: (r["criterion"].startswith("subspace"),
                                           -r["held_out_fit"]))

    def ranked(self, allow_unstable: bool = False) -> list[dict[str, Any]]:
        """Eligible stable candidates first (unstable ones too when ``allow_unstable``);
        among those the blocks cannot tell from the best (:meth:`is_near`) the smallest order
        first, then
        by score; the rest by score."""
        best = self.best(not allow_unstable)

        def key(r: dict[str, Any]) -> tuple[bool, bool, int, float]:
            ok = self.eligible(r, not allow_unstable)
            near = self.is_near(r, best, not allow_unstable)
            return (not ok, not near, r["order"] if near else 0, -r["held_out_fit"])
        return sorted(self.rows, key=key)


def informative(parts: list[tuple[IOData, IOData]], data: IOData
                ) -> tuple[list[tuple[IOData, IOData]], int]:
    """The folds whose held-out block has output variation to score against, and how many
    were dropped. A block where every output stands still (a logger that ran on after the
    test, a held or padded signal) has no fit: the fit divides by the block's variation, so
    every candidate scored -inf there and the trimmed score lost its one atypical block to
    it. Still blocks are dropped, unless fewer than two would remain; they stay in the
    fitted parts.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.board import informative
    >>> from sysid.validation.crossval import folds
    >>> u = np.random.default_rng(0).standard_normal(500)
    >>> y = np.r_[np.convolve(u, [0.5, 0.3])[:400], np.zeros(100)]
    >>> d = sysid.IOData(u=u, y=y)
    >>> len(informative(folds(d, 5), d)[0])
    4
    """
    y = np.vstack([e[1] for e in data.experiments])
    scale = np.sqrt(np.mean((y - y.mean(0)) ** 2, axis=0))

    def moves(held: IOData) -> bool:
        return any(bool(np.any(np.ptp(e[1], axis=0) > 1e-9 * scale))
                   for e in held.experiments if e[1].shape[0])
    keep = [p for p in parts if moves(p[1])]
    return (keep, len(parts) - len(keep)) if len(keep) >= 2 else (parts, 0)
