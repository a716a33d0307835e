"""The choice among :func:`sysid.identify`'s candidates: the near-best ones re-fitted on the
whole record, the smallest BIC kept (:func:`_choose`)."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .._checks import PERSISTENT_DECAY
from ..data.iodata import IOData
from ..errors import DataError
from .board import Board, bic, unstable
from .notes import LONG_GAP, integrates_within

#: candidates the held-out blocks cannot tell apart that are re-fitted and compared by BIC
N_FINAL = 12


def _choose(board: Board, ranked: list[dict[str, Any]], data: IOData, stable_only: bool
            ) -> tuple[Any, dict[str, Any]]:
    """Among the candidates the held-out blocks cannot tell apart (within the slack of the
    best score, or with no more parameters within one standard error of their difference
    to it, :meth:`.board.Board.paired_se`; at most ``N_FINAL``), the one whose re-fit on
    the whole record has the
    smallest BIC (its simulation errors there against its parameter count); when none
    re-fits well, the next candidates of the ranking."""
    fitted = []
    # the state-sequence rows last: stable where the sweep's spurious modes are not, their
    # high orders would crowd the others out (:func:`.states.states_candidates`)
    near = sorted(board.near_best(stable_only, paired=True),
                  key=lambda r: r["criterion"] == "subspace, states")[:N_FINAL]
    if board.out_of_time:  # one refined re-fit at most (each is a search on the whole record)
        refined = [r for r in near if not r["criterion"].startswith("subspace")]
        near = [r for r in near if r["criterion"].startswith("subspace") or r is refined[0]]
    for r in near:
        got = _whole_bic(r, data, stable_only)
        if got is not None:
            fitted.append((got[0], r, got[1]))
    if fitted:
        # a re-fit with a mode that acts as an integrator over the record, held inside the
        # unit circle by nothing the data say (often the search's stability bound), follows
        # the record's drift; among candidates the blocks cannot tell apart, one whose long-
        # term behaviour the data determine is preferred when there is one
        determined = [t for t in fitted if not follows_drift(t[2], data)]
        _, r, m = min(determined or fitted, key=lambda t: t[0])
        if determined and len(determined) < len(fitted):
            r["note"] = r["note"] or ("chosen by BIC over near-best re-fits whose mode acts as "
                                      "an integrator over the record")
        return m, r
    for r in ranked:
        if not board.eligible(r, stable_only) or "bic" in r:
            continue
        m = _refit_one(r, data, stable_only)
        if m is not None:
            return m, r
    # none of those re-fits stable: the stable candidates held back as starts or as below
    # their start, by score, before giving up
    for r in sorted(ranked, key=lambda r: -r["held_out_fit"]):
        if not np.isfinite(r["held_out_fit"]) or not r["stable"] or "bic" in r or (
                board.eligible(r, stable_only)):
            continue
        m = _refit_one(r, data, stable_only)
        if m is not None:
            r["note"] = ("chosen although held back (" + (r.get("note") or "") + "): no "
                         "eligible candidate re-fitted stable on the whole record")
            return m, r
    raise DataError("no candidate gave a stable model on this record; check the data "
                    "(offsets, an integrating process: difference the output) or fit one "
                    "model directly")


#: the share of a model's response to the record's input (RMS, per output) above which
#: its modes that act as integrators over the record count (:func:`follows_drift`)
MATERIAL = 0.05
#: samples per experiment :func:`follows_drift` simulates the modes over
SHARE_SAMPLES = 20000


def follows_drift(model: Any, data: IOData) -> bool:
    """Whether ``model`` has modes that act as integrators over the record
    (:func:`.notes.integrates_within`) and carry more than :data:`MATERIAL` of its response
    to the record's input (RMS, the largest over the outputs; from rest): a slow mode that a
    near-cancelling zero leaves unexcited does not count (a staircase test's output-error
    fit: a pole at 1 - 1e-9 beside 0.975 and 0.896, validation 99.3 %), one that follows the
    record's drift does (a twin rotor's: 37.7 %). The persistent modes are split off by
    :func:`sysid.analysis.stable_split.split_stable` at the modulus where they keep
    ``PERSISTENT_DECAY`` over the record; a model that split fails for counts when it
    integrates.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.random.default_rng(0).standard_normal(500), y=np.zeros(500))
    >>> slow = [[1 - 1e-9, 0.0], [0.0, 0.5]]
    >>> [follows_drift(sysid.StateSpaceModel(slow, [[b], [1.0]], [[1.0, 1.0]]), d)
    ...  for b in (1.0, 1e-6)]
    [True, False]
    """
    if not integrates_within(model, data):
        return False
    from ..analysis.stable_split import split_stable
    from ..models.statespace import StateSpaceModel

    try:  # the persistent modes split off (ordered Schur form), each part simulated
        ss = model if hasattr(model, "A") else model.to_statespace()
        radius = PERSISTENT_DECAY ** (1.0 / max(data.lengths))  # |z|^n above: persistent
        slow = split_stable(np.asarray(ss.A, float), np.asarray(ss.B, float),
                            np.asarray(ss.C, float), 1.0, radius=radius).unstable
        m, l = slow[1].shape[1], slow[2].shape[0]
        part = StateSpaceModel(*slow, np.zeros((l, m)))
        us = [u[:SHARE_SAMPLES] for u, _ in data.experiments]
        share = (np.sqrt(np.mean(np.vstack([part.simulate(u) for u in us]) ** 2, 0))
                 / np.maximum(np.sqrt(np.mean(np.vstack([ss.simulate(u) for u in us]) ** 2,
                                              0)), 1e-300))
        return bool(np.max(share) > MATERIAL)
    except Exception:  # noqa: BLE001 - no split to be had: the pole test alone
        return True


def _whole_bic(r: dict[str, Any], data: IOData, stable_only: bool) -> tuple[float, Any] | None:
    """``(BIC, model)`` of candidate ``r`` re-fitted on the whole record ``data``
    (:func:`.board.bic`, also kept as ``r["bic"]``); the re-fit is made once per record and
    kept in the row (the choice and the whole-record re-choice weigh the same re-fits). None
    (noted) when the re-fit fails, is unstable where a stable model is wanted, or cannot be
    simulated on the record."""
    kept = r.get("whole_refit")
    if kept is None or kept[0] is not data:
        kept = r["whole_refit"] = [data, _refit_one(r, data, False), None]
    _, m, value = kept
    if m is None:
        return None
    if stable_only and unstable(m):  # (an integrator made explicit is not unstable)
        r["note"] = "re-fit on the whole record unstable"
        return None
    if value is None:
        try:
            value = kept[2] = r["bic"] = bic(m, data)
        except Exception:  # noqa: BLE001 - cannot be simulated on the record
            r["note"] = "re-fit on the whole record cannot be simulated"
            kept[1] = None
            return None
    return value, m


def _refit_one(r: dict[str, Any], data: IOData, stable_only: bool) -> Any:
    """Candidate ``r`` re-fitted on the whole record, or None (noted) when that fails or is
    unstable where a stable model is wanted."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            m = r["refit"](data)
    except Exception as e:  # noqa: BLE001 - try the next candidate
        r["note"] = f"re-fit on the whole record failed ({type(e).__name__})"
        return None
    if stable_only and unstable(m):  # an integrator made explicit (:mod:`.integrating`) is
        # a pole pinned at 1, not a diverging mode
        r["note"] = "re-fit on the whole record unstable"
        return None
    return m


def rechoose_on_whole_record(board: Board, data: IOData, model: Any, chosen: dict[str, Any],
                             checks: dict[str, Any]) -> tuple[Any, dict[str, Any]]:
    """When ``checks["whole_record"]`` says the chosen model simulates the whole record
    ``data`` more than :data:`~.notes.LONG_GAP` points below its held-out fit, the held-out
    blocks have shown they cannot judge what builds up over longer than a block: the choice
    is made again by the criterion of the final choice (:func:`.board.bic` of the simulation
    errors over the whole record), among the stable candidates whose held-out fit lies within
    that gap of the chosen one's (at most ``N_FINAL``, by held-out fit; refinements stopped on
    the blocks as below their start included: a stop there is a judgement of the blocks),
    each re-fitted on the whole record. The note says what was chosen and why. On a
    hovercraft's yaw the choice moved from a subspace model held out at 96.4 % (whole record
    78.6 %, another run -136 %) to a refinement of order 12 (whole record 98.5 %, another run
    28.5 %); on a tracking rig from 13.0 to 20.3 % on its validation run.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.choice import rechoose_on_whole_record
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    >>> d = sysid.IOData(u=np.ones(50), y=np.ones(50))
    >>> row = {"held_out_fit": 90.0}
    >>> rechoose_on_whole_record(None, d, m, row, {})[1] is row  # no note: no new choice
    True
    """
    if "whole_record" not in checks:
        return model, chosen
    floor = chosen["held_out_fit"] - LONG_GAP
    pool = sorted((r for r in board.rows if r is not chosen and r["stable"]
                   and np.isfinite(r["held_out_fit"]) and r["held_out_fit"] >= floor
                   and not r.get("start_only") and not r.get("undetermined")
                   and "error" not in r),
                  key=lambda r: -r["held_out_fit"])[:N_FINAL]
    try:
        own = chosen["bic"] if "bic" in chosen else bic(model, data)
    except Exception:  # noqa: BLE001 - cannot be simulated on the record: any other will do
        own = np.inf
    best = (own, chosen, model)
    for r in pool:  # (the near-best ones were re-fitted by the choice already)
        got = _whole_bic(r, data, True)
        if got is not None and got[0] < best[0]:
            best = (got[0], r, got[1])
    _, r, m = best
    if r is chosen:
        checks["whole_record"] += (
            f"; no stable candidate within {LONG_GAP:.0f} points of its held-out fit "
            f"({len(pool)} re-fitted) simulates the whole record with a smaller BIC")
        return model, chosen
    from ..validation.crossval import simulation_fit
    from .result import _family

    def name(row: dict[str, Any]) -> str:
        focus = f" ({row['focus']} focus)" if row.get("focus") else ""
        return f"{_family(row)}{focus}, order {row['order']}"

    note = checks["whole_record"].replace("the chosen model", "the held-out blocks' choice "
                                          f"({name(chosen)})", 1)
    checks["whole_record"] = note + (
        f"; re-chosen by the BIC of the simulation errors over the whole record among the "
        f"{len(pool) + 1} stable candidates within {LONG_GAP:.0f} points of its held-out fit: "
        f"{name(r)} (held out {r['held_out_fit']:.1f} %, the whole record "
        f"{simulation_fit(m, data):.1f} %; BIC {r['bic']:.6g} against {own:.6g})")
    r["note"] = "chosen by the BIC of the whole record (checks['whole_record'])"
    return m, r
