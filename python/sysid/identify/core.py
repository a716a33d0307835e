"""``sysid.identify``: the one call an engineer makes first, with no settings.

1. Offsets: the estimation record's input and output means are removed and kept with the
   model (:class:`IdentifiedModel` predicts raw data).
2. Checks: the input's persistent-excitation order and a feedback test are recorded; under
   feedback the closed-loop subspace methods (PBSID, SSARX) join the candidates.
3. Candidates are scored by two-fold cross-validation inside the estimation record: fitted
   on one half, scored by their simulation fit on the other (initial state fitted), both
   ways, averaged (or leave one experiment out): every subspace weighting (MOESP,
   N4SID, CVA) at every order the horizon allows (up to 20), with and without feedthrough;
   the best configurations refined by ``ssest`` with both focuses; an output-error model
   for a single input and output.
4. The candidate with the best held-out fit (the smallest order within 0.5 points, as the
   order rule of ``order="auto"``) is re-fitted on the whole estimation record; if
   that model is unstable, the next one is taken. ``validation`` data, when given, are
   only reported on.
"""

from __future__ import annotations

import time
import warnings
from typing import Any

import numpy as np

from .._progress import Bar, show
from ..data.iodata import IOData
from ..errors import DataError, InsufficientDataError
from ..validation.crossval import MAX_ORDER, TOL, folds, simulation_fit
from .result import IdentifiedModel, IdentifyResult

__all__ = ["identify"]

SUBSPACE = ("moesp", "n4sid", "cva")
CLOSED_LOOP = ("pbsid", "ssarx")
#: subspace configurations (order, feedthrough) refined by ssest
N_REFINE = 3
#: blocks of the estimation record, each held out once (the rest fits the candidates)
FOLDS = 3
#: fit points a re-fit on the whole record may lose against its held-out score on the
#: record's own blocks before the next candidate is taken
REFIT_LOSS = 2.0


def _offsets(data: IOData) -> tuple[IOData, np.ndarray, np.ndarray]:
    u = np.vstack([e[0] for e in data.experiments])
    y = np.vstack([e[1] for e in data.experiments])
    mu, my = u.mean(0), y.mean(0)
    kw = {"dt": data.dt, "input_names": data.input_names, "output_names": data.output_names}
    us = [e[0] - mu for e in data.experiments]
    ys = [e[1] - my for e in data.experiments]
    out = IOData(u=us[0], y=ys[0], **kw) if len(us) == 1 else IOData(u=us, y=ys, **kw)
    return out, mu, my


def _checks(data: IOData) -> tuple[dict[str, Any], bool]:
    import sysid

    checks: dict[str, Any] = {}
    feedback = False
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            pe = sysid.persistent_excitation_order([e[0] for e in data.experiments]
                                                   if data.n_experiments > 1
                                                   else data.experiments[0][0], 40)
            checks["excitation"] = f"input persistently exciting of order >= {pe}"
        except Exception as e:  # noqa: BLE001 - recorded, not raised
            checks["excitation"] = f"not checked ({e})"
        try:
            fb = sysid.check_feedback(data)
            feedback = bool(fb.detected)
            checks["feedback"] = (f"{'detected' if feedback else 'not detected'} "
                                  f"(p = {fb.p_value:.2g})")
        except Exception as e:  # noqa: BLE001
            checks["feedback"] = f"not checked ({e})"
    return checks, feedback


class _Board:
    """Candidates with their held-out scores and a way to re-fit each on the whole record.

    Each candidate is fitted on every fold's fitted part and scored on its held-out part;
    the score is the mean held-out simulation fit (two folds: each half of the record held
    out once, so a record whose halves differ cannot favour one candidate by chance)."""

    def __init__(self, folds: list[tuple[IOData, IOData]], bar: Bar) -> None:
        self.rows: list[dict[str, Any]] = []
        self.folds, self.bar = folds, bar

    def add(self, family: str, order: int, feedthrough: bool, focus: str | None,
            criterion: str, fit_fn: Any, refit: Any) -> None:
        """``fit_fn(k)`` fits on fold ``k``; ``refit(data)`` on the whole record."""
        t = time.perf_counter()
        row: dict[str, Any] = {"family": family, "order": order, "feedthrough": feedthrough,
                               "focus": focus, "criterion": criterion, "refit": refit}
        try:
            fits, rho = [], 0.0
            for k, (_, held) in enumerate(self.folds):
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    model = fit_fn(k)
                fits.append(simulation_fit(model, held))
                poles = model.poles()
                rho = max(rho, float(np.max(np.abs(poles))) if len(poles) else 0.0)
                if not np.isfinite(fits[-1]):
                    break
            row["held_out_fit"] = float(np.mean(fits))
            row["max_abs_pole"] = rho
            row["stable"] = rho < 1.0
            row["note"] = ""
        except KeyboardInterrupt:
            raise
        except Exception as e:  # noqa: BLE001 - a failed candidate is listed, not raised
            row.update(held_out_fit=-np.inf, max_abs_pole=np.nan, stable=False,
                       note=f"{type(e).__name__}: {e}"[:120])
        row["seconds"] = time.perf_counter() - t
        self.rows.append(row)
        self.bar.update(1, best=f"{self.best_fit():.1f}%")

    def best_fit(self) -> float:
        fits = [r["held_out_fit"] for r in self.rows if r["stable"]]
        return max(fits) if fits else -np.inf

    def ranked(self) -> list[dict[str, Any]]:
        """Stable candidates first; among those within the order rule's slack of the best
        held-out fit (:func:`sysid.validation.crossval.choose`: 0.5 points, at most 5 % of
        the best's error) the smallest order first, then by held-out fit."""
        best = self.best_fit()
        slack = max(min(TOL, 0.05 * (100.0 - best)), 1e-6) if np.isfinite(best) else 0.0

        def key(r: dict[str, Any]) -> tuple[bool, bool, int, float]:
            near = bool(r["stable"] and r["held_out_fit"] >= best - slack)
            return (not r["stable"], not near, r["order"] if near else 0, -r["held_out_fit"])
        return sorted(self.rows, key=key)


def _subspace_candidates(board: _Board, full: IOData, methods: tuple[str, ...],
                         max_order: int | None) -> None:
    from ..subspace.estimator import SubspaceEstimator, default_horizon

    ests = []
    ch = full.n_inputs + full.n_outputs
    for fit_part, _ in board.folds:
        # the whole record's horizon (the orders it supports), unless the part is too short
        # for a data matrix with three times as many columns as rows
        h = min(default_horizon(min(full.lengths), full.n_inputs, full.n_outputs),
                max(2, min(fit_part.lengths) // (6 * ch)))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ests.append(SubspaceEstimator(fit_part, h))
    top = min(min(e.max_order for e in ests), max_order or MAX_ORDER)
    for meth in methods:
        for ft in (False, True):
            for n in range(1, top + 1):
                board.add(meth, n, ft, None, "subspace",
                          lambda k, m=meth, n=n, ft=ft: ests[k].fit(n, method=m, feedthrough=ft,
                                                                    kalman=False),
                          lambda data, m=meth, n=n, ft=ft: SubspaceEstimator(
                              data, method=m).fit(n, feedthrough=ft))


def _refined_candidates(board: _Board) -> None:
    import sysid

    configs: list[tuple[int, bool]] = []
    for r in board.ranked():
        c = (r["order"], r["feedthrough"])
        if r["criterion"] == "subspace" and r["stable"] and c not in configs:
            configs.append(c)
        if len(configs) == N_REFINE:
            break
    for n, ft in configs:
        for focus in ("simulation", "prediction"):
            def fit(k: int, n: int = n, ft: bool = ft, focus: str = focus) -> Any:
                return sysid.ssest(board.folds[k][0], n, focus=focus, feedthrough=ft,
                                   progress=False)

            def refit(data: IOData, n: int = n, ft: bool = ft, focus: str = focus) -> Any:
                return sysid.ssest(data, n, focus=focus, feedthrough=ft, progress=False)
            board.add("ssest", n, ft, focus, "prediction error", fit, refit)
    first = board.folds[0][0]
    if first.n_inputs == 1 and first.n_outputs == 1 and configs:
        for n, ft in configs[:2]:
            if n > 8:
                continue
            nk, nb = (0, n + 1) if ft else (1, n)

            def fit_oe(data: IOData, n: int = n, nb: int = nb, nk: int = nk) -> Any:
                return sysid.oe(data, nb, n, nk, progress=False).to_statespace()
            board.add("oe", n, ft, "simulation", "output error",
                      lambda k, f=fit_oe: f(board.folds[k][0]), fit_oe)


def identify(
    data: IOData,
    validation: IOData | None = None,
    *,
    max_order: int | None = None,
    refine: bool = True,
    progress: bool | None = None,
) -> IdentifyResult:
    """Identify a linear model from a record with no settings: offsets, checks, candidate
    families and orders, chosen on data held out from the estimation record.

    Parameters
    ----------
    data : IOData or (u, y)
        The estimation record, raw (offsets are removed and recorded here).
    validation : IOData or (u, y), optional
        Fresh data, used only to report the chosen model's simulation fit.
    max_order : int, optional
        Largest order tried (default: what the horizon allows, at most 20).
    refine : bool
        Also try ``ssest`` refinements (both focuses) and, for one input and output, an
        output-error model of the best subspace configurations (default). ``False`` keeps
        to subspace models (seconds on long records).
    progress : bool, optional
        A progress bar over the candidates (default: only when stderr is a terminal).
        Ctrl-C stops the search and returns the best candidate found so far.

    Returns
    -------
    IdentifyResult
        ``.model`` (an :class:`IdentifiedModel` that predicts raw data; its state-space
        model of the deviations is ``.model.statespace``), ``.leaderboard``,
        ``.summary()``, ``.plot()``, ``.to_pandas()``.

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
                        f"{type(data).__name__}")
    if data.n_inputs == 0:
        raise DataError("identify needs inputs; for output-only data use sysid.n4sid(data) "
                        "(a time-series model) or the oma tools")
    centred, mu, my = _offsets(data)
    checks, feedback = _checks(centred)
    checks["offsets"] = (f"input means {np.round(mu, 6).tolist()}, output means "
                         f"{np.round(my, 6).tolist()} removed (kept with the model)")
    parts = folds(centred, FOLDS)
    if min(min(h.lengths) for _, h in parts) < 20:
        raise InsufficientDataError(
            "the record is too short to hold out a part for the choice (a held-out block has "
            f"{min(min(h.lengths) for _, h in parts)} samples, 20 needed); pass a longer "
            "record or fit one model directly")
    methods = SUBSPACE + (CLOSED_LOOP if feedback else ())
    # Ctrl-C stops identify (KeyboardInterrupt), as it stops every other computation: a
    # batch (identify_many) or a script must not carry on with a half-chosen model
    interrupted = False
    with Bar(None, "identify", unit="candidates", enabled=show(progress)) as bar:
        board = _Board(parts, bar)
        _subspace_candidates(board, centred, methods, max_order)
        if refine:
            _refined_candidates(board)
    ranked = board.ranked()
    model, chosen = _refit(ranked, centred, parts)
    for r in ranked:
        r["chosen"] = r is chosen
    rows = [{k: v for k, v in r.items() if k != "refit"} for r in ranked]
    desc = (f"{chosen['family']}"
            + (f" ({chosen['focus']} focus)" if chosen["focus"] else "")
            + f", order {chosen['order']}, {'with' if chosen['feedthrough'] else 'no'} "
            f"feedthrough: held-out fit {chosen['held_out_fit']:.1f} %")
    model.info["identify"] = {k: chosen[k] for k in ("family", "order", "feedthrough", "focus",
                                                     "held_out_fit")}
    result_model = IdentifiedModel(model, mu, my)
    vfit = None
    if validation is not None:
        if isinstance(validation, tuple):
            validation = IOData(u=validation[0], y=validation[1], dt=data.dt)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                vfit = float(result_model.compare(validation).mean_fit)
        except Exception:  # noqa: BLE001 - reported, never raised: a diverging model
            vfit = -np.inf
    return IdentifyResult(result_model, rows, desc, checks, vfit,
                          time.perf_counter() - t0, interrupted)


def _refit(ranked: list[dict[str, Any]], data: IOData,
           parts: list[tuple[IOData, IOData]]) -> tuple[Any, dict[str, Any]]:
    """The best candidate re-fitted on the whole record; the next one if that is unstable or
    simulates the record's blocks clearly worse (by more than ``REFIT_LOSS`` points) than
    the candidate's held-out fits promised (a fit on more data that went wrong)."""
    for r in ranked:
        if not np.isfinite(r["held_out_fit"]):
            break
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                m = r["refit"](data)
        except Exception:  # noqa: BLE001 - try the next candidate
            continue
        if not m.is_stable():
            r["note"] = "re-fit on the whole record unstable"
            continue
        own = float(np.mean([simulation_fit(m, held) for _, held in parts]))
        if own < r["held_out_fit"] - REFIT_LOSS:
            r["note"] = f"re-fit on the whole record simulates it worse ({own:.1f} %)"
            continue
        return m, r
    raise DataError("no candidate gave a stable model on this record; check the data "
                    "(offsets, an integrating process: difference the output) or fit one "
                    "model directly")
