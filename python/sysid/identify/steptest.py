""":func:`sysid.identify` on a step test: process models chosen by BIC.

A step test (each input switched once or a few times from rest, then held) is the first
record of many a plant, and the rest of :func:`sysid.identify` cannot use it when its steps
fall in one held-out block (:func:`blocks_with_steps`): a block held out of it either holds
the step (the rest does not excite the plant) or does not (it has nothing to score), and
the subspace methods refuse it (:mod:`sysid.subspace.steptest`). A staircase, steps in
:data:`STAIRCASE_BLOCKS` blocks or more, is held out as any record is, and comes here only
when its parts cannot be fitted without a block.
What fits it is a model simulated from rest, so :func:`identify_step_test` fits the process
models (:func:`sysid.procest`: one, two or three poles, a zero, an underdamped pair, each
with a dead time) to the whole record around the levels it rests at before the first step
(not its means: they sit between the two levels and would start the record off rest), and
returns the one with the smallest Bayesian information criterion of its simulation errors
from rest, ``N log det(E^T E / N) + p log N`` with ``p`` its free parameters (among those
within :data:`TIE` of the smallest, the one with the fewest parameters). Its
leaderboard shows each type's fit to the record and BIC; there is no held-out fit.
"""

from __future__ import annotations

import time
import warnings
from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import NumericalError, SysidError
from ..subspace.steptest import step_changes
from .notes import persistent_mode_check
from .result import IdentifiedModel, IdentifyResult, reported_fit

__all__ = ["TYPES", "STAIRCASE_BLOCKS", "input_changes", "blocks_with_steps",
           "identify_step_test"]

#: the process-model types tried (MATLAB's type codes), simplest first
TYPES = ("P1D", "P1DZ", "P2D", "P2DZ", "P2DU", "P3D")
#: a step test whose changes fall in at least this many held-out blocks is a staircase, held
#: out as any record is (:func:`blocks_with_steps`); two steps either side of a block edge
#: (a pulse of ten samples) are one event, and held out they gave order 14 at 10 %
STAIRCASE_BLOCKS = 3
#: BIC differences below this are no evidence (Kass & Raftery's "not worth more than a bare
#: mention"): the type with fewer parameters is chosen among them
TIE = 2.0


def input_changes(data: IOData) -> list[int] | None:
    """The samples (counted over the experiments laid end to end) where some input changes,
    or ``None`` when there are more than :data:`~sysid.subspace.steptest.MAX_STEPS` (not a
    step test) or none (:func:`sysid.subspace.steptest.step_changes`).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = np.r_[np.zeros(20), np.ones(80)]
    >>> input_changes(sysid.IOData(u=u, y=np.zeros(100)))
    [20]
    """
    return step_changes(data.experiments)


def blocks_with_steps(data: IOData) -> int:
    """How many of the held-out blocks of :func:`~sysid.validation.crossval.record_folds`
    hold an input change (0 on a record too short to hold blocks out). A step test whose
    changes fall in one block gives the held-out choice one block with a response to score
    (HSM150's one torque step: validated at -258 % by that path); a staircase of steps in
    several blocks gives it one each (a heating system's three to four voltage levels:
    88.6 and 97.1 % by that path, 71.7 and 41.2 % by the process models of this module).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> one = np.r_[np.zeros(30), np.ones(270)]
    >>> stairs = np.repeat([0.0, 1.0, 3.0, 2.0], 75)
    >>> [blocks_with_steps(sysid.IOData(u=u, y=np.cumsum(u))) for u in (one, stairs)]
    [1, 3]
    """
    from ..validation.crossval import MIN_BLOCK, record_folds

    if sum(data.lengths) < 2 * MIN_BLOCK:
        return 0
    return sum(any(bool(np.any(np.diff(u, axis=0) != 0)) for u, _ in held.experiments)
               for _, held in record_folds(data))


def _rest_levels(data: IOData) -> tuple[np.ndarray, np.ndarray]:
    """Each channel's level before the first input change of each experiment (the mean of
    the samples before it, at least the first sample), pooled over the experiments."""
    us, ys = [], []
    for u, y in data.experiments:
        moved = np.flatnonzero(np.any(np.diff(u, axis=0) != 0, axis=1))
        k = int(moved[0]) + 1 if moved.size else u.shape[0]
        us.append(u[:k])
        ys.append(y[:k])
    return np.vstack(us).mean(0), np.vstack(ys).mean(0)


def _scores(model: Any, data: IOData, n_par: int) -> tuple[float, float]:
    """(simulation fit %, BIC) of ``model`` (state space, deviations) simulated from rest."""
    errs, devs, n = [], [], 0
    for u, y in data.experiments:
        yh = np.asarray(model.simulate(u), float).reshape(y.shape)
        errs.append(y - yh)
        devs.append(y - y.mean(0))
        n += y.shape[0]
    E, Y = np.vstack(errs), np.vstack(devs)
    if not np.all(np.isfinite(E)):
        return -np.inf, np.inf
    with np.errstate(divide="ignore", invalid="ignore"):
        fit = 100.0 * (1.0 - np.linalg.norm(E, axis=0) / np.linalg.norm(Y, axis=0))
        sign, logdet = np.linalg.slogdet(E.T @ E / n)
    fit = fit[np.isfinite(fit)]
    crit = n * logdet + n_par * np.log(n) if sign > 0 else -np.inf
    return (float(np.mean(fit)) if fit.size else -np.inf), float(crit)


def identify_step_test(data: IOData, validation: IOData | None, changes: list[int],
                       t0: float, max_order: int | None = None) -> IdentifyResult:
    """:func:`sysid.identify` of a step test (module docs): the process model of smallest
    BIC, fitted to the whole record around the levels before the step; ``changes`` are the
    samples where an input changes (:func:`input_changes`), ``t0`` when identify began,
    ``max_order`` the most poles a type may have.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> true = sysid.ProcessModel("P1D", Kp=2.0, Tp1=20.0, Td=3.0)
    >>> u = np.r_[np.zeros(10), np.ones(190)]
    >>> y = 21.0 + true.to_statespace(dt=1.0).simulate(u).ravel()
    >>> res = sysid.identify(sysid.IOData(u=u, y=y, dt=1.0), progress=False)
    >>> res.leaderboard[0]["family"], round(float(res.model.y_offset[0]), 3)
    ('procest P1D', 21.0)
    """
    import sysid

    u0, y0 = _rest_levels(data)
    kw = {"dt": data.dt, "input_names": data.input_names, "output_names": data.output_names}
    us = [u - u0 for u, _ in data.experiments]
    ys = [y - y0 for _, y in data.experiments]
    dev = IOData(u=us[0], y=ys[0], **kw) if len(us) == 1 else IOData(u=us, y=ys, **kw)
    rows: list[dict[str, Any]] = []
    fits: list[Any] = []
    for code in [c for c in TYPES if max_order is None or int(c[1]) <= max_order]:
        c0 = time.perf_counter()
        row: dict[str, Any] = {"family": f"procest {code}", "feedthrough": False,
                               "focus": "simulation", "criterion": "BIC", "held_out_fit": np.nan}
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                pm = sysid.procest(dev, code)
                ss = pm.to_statespace(dt=data.dt)
            except (SysidError, FloatingPointError, np.linalg.LinAlgError) as e:
                pm = ss = None
                row["note"] = f"failed: {str(e).splitlines()[0][:120]}"
        row["seconds"] = time.perf_counter() - c0
        if ss is None:
            row.update(order=int(code[1]), mean_fit=-np.inf, stable=False, max_abs_pole=np.nan,
                       bic=np.inf, n_parameters=0)
        else:
            fit, crit = _scores(ss, dev, int(pm.n_parameters))
            poles = np.abs(ss.poles())
            said = [str(w.message).split(":")[0][:80] for w in caught
                    if issubclass(w.category, UserWarning)]
            row.update(order=int(code[1]), mean_fit=fit, bic=crit,
                       n_parameters=int(pm.n_parameters), stable=bool(ss.is_stable()),
                       max_abs_pole=float(poles.max()) if poles.size else 0.0,
                       note=f"BIC {crit:.1f}" + (f"; {said[0]}" if said else ""))
        rows.append(row)
        fits.append(ss)
    ok = [k for k, r in enumerate(rows) if r["stable"] and np.isfinite(r["bic"])]
    if not ok:
        raise NumericalError(
            "identify: the record is a step test (the input changes at sample(s) "
            f"{', '.join(map(str, changes))} only) and no process model fitted it stably; "
            "fit one yourself (sysid.procest(data, 'P1D'), sysid.tfest, sysid.oe) around the "
            "levels before the step")
    # within TIE of the smallest BIC (no real evidence between them), the fewest parameters:
    # an underdamped pair that ends critically damped is the two real poles' model
    low = min(rows[k]["bic"] for k in ok)
    best = min((k for k in ok if rows[k]["bic"] <= low + TIE),
               key=lambda k: (rows[k]["n_parameters"], rows[k]["bic"]))
    for k, r in enumerate(rows):
        r["chosen"] = k == best
    order = sorted(range(len(rows)), key=lambda k: (not rows[k]["stable"], rows[k]["bic"]))
    board = [rows[k] for k in order]
    model = IdentifiedModel(fits[best], u0, y0)
    chosen = rows[best]
    model.info["identify"] = {k: chosen[k] for k in ("family", "order", "feedthrough",
                                                     "focus", "held_out_fit")}
    levels = (f"input levels [{', '.join(f'{v:.6g}' for v in u0)}], output levels "
              f"[{', '.join(f'{v:.6g}' for v in y0)}] before the first step removed (kept "
              f"with the model; not the means, which sit between the levels)")
    checks = {
        "step_test": (f"the input changes at sample(s) {', '.join(map(str, changes))} only: a "
                      f"step test, so no part of it can be held out (the parts without one "
                      f"block are not excited, or only one block holds a step) and the "
                      f"subspace methods do not apply; the process models of each type were "
                      f"fitted to the "
                      f"whole record from rest and the smallest BIC chosen (a fresh record, "
                      f"validation=, tells how it predicts)"),
        "offsets": levels}
    persistent_mode_check(fits[best], dev, checks)  # an integrating plant: a pole at 1 - eps
    desc = (f"{chosen['family']} (a step test: fitted from rest, chosen by BIC), "
            f"{chosen['order']} pole(s) and a dead time ({fits[best].nstates} states with its "
            f"delay line): fit {chosen['mean_fit']:.1f} % to the record")
    return IdentifyResult(model, board, desc, checks, reported_fit(model, validation),
                          time.perf_counter() - t0, score="BIC")
