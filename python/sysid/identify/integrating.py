"""Candidates of :func:`sysid.identify` with an integrator made explicit: a subspace model of
the record with one output differenced, that output then integrated back (a pole pinned at
exactly 1), scored on the held-out blocks in the raw domain as every other candidate
(:func:`integrating_candidates`).

Many records hold an output that integrates another signal: a heading the yaw rate, a
speed the acceleration, a level the net flow, a cell's voltage its charge. The subspace
fits then place a pole near 1, often just outside the unit circle on part of the record,
and win every held-out block unstable; the drift test of :meth:`.board.Board.insisting`
takes a line out of every channel, which removes part of the integrated response as well,
and calls it a drift: the stable model returned then lacks the integrator (a tanker's
zigzag: order 1, validation 58 %, where stable-with-an-integrator fits reach 75-80 %).
Here the integrator is a family of its own, with the data asked whether they prefer it."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import SysidError
from ..models.statespace import StateSpaceModel
from .board import Board, free_poles
from .sweep import transformed_sweep

__all__ = ["MAX_OUTPUTS", "differenced", "integrated", "integrating_candidates",
           "integrating_note"]

#: records of at most this many outputs get integrating candidates (one set per output)
MAX_OUTPUTS = 4
CRITERION = "subspace, integrating"


def differenced(data: IOData, outputs: list[int]) -> IOData:
    """``data`` with each output of ``outputs`` replaced by its increment
    ``y(t+1) - y(t)``, paired with ``u(t)`` and the other outputs' ``y(t)`` (every
    experiment one sample shorter; those shorter than two samples are left out).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.integrating import differenced
    >>> d = sysid.IOData(u=np.arange(4.0), y=np.c_[np.arange(4.0) ** 2, np.ones(4)])
    >>> differenced(d, [0]).y[:, 0]
    array([1., 3., 5.])
    """
    us, ys = [], []
    for u, y in data.experiments:
        if y.shape[0] < 2:
            continue
        z = y[:-1].copy()
        z[:, outputs] = np.diff(y[:, outputs], axis=0)
        us.append(u[:-1])
        ys.append(z)
    if not ys:
        raise SysidError("no experiment of two samples or more to difference")
    return IOData(u=us if len(us) > 1 else us[0], y=ys if len(ys) > 1 else ys[0],
                  dt=getattr(data, "dt", None))


def integrated(model: Any, outputs: list[int]) -> StateSpaceModel:
    """The model of the raw outputs from ``model``, a model of the record with ``outputs``
    differenced (:func:`differenced`): one state per integrated output, ``z(t+1) = z(t) +
    C_i x(t) + D_i u(t)``, ``y_i(t) = z(t)``; the other outputs as ``model`` has them.
    ``info["integrating"]`` records the integrated outputs and the order of the free part
    (the first states): every pole of the free part is ``model``'s, each integrator's is
    exactly 1 (a marginally stable mode, not a diverging one: ``is_stable()`` is False, as
    for every pole on the unit circle).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.integrating import integrated
    >>> m = integrated(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), [0])
    >>> m.simulate(np.ones(4)).ravel()  # the step response of 1 / (1 - 0.5 q^-1) summed
    array([0. , 0. , 1. , 2.5])
    >>> m.info["integrating"]
    {'outputs': [0], 'free_order': 1}
    """
    A, B, C = (np.atleast_2d(np.asarray(v, float)) for v in (model.A, model.B, model.C))
    n, m, l, k = A.shape[0], B.shape[1], C.shape[0], len(outputs)
    D = np.zeros((l, m)) if model.D is None else np.asarray(model.D, float).reshape(l, m)
    Ai = np.zeros((n + k, n + k))
    Ai[:n, :n], Ai[n:, n:] = A, np.eye(k)
    Ai[n:, :n] = C[outputs]
    Bi = np.vstack([B, D[outputs]])
    Ci = np.hstack([C, np.zeros((l, k))])
    Di = D.copy()
    for j, i in enumerate(outputs):
        Ci[i] = 0.0
        Ci[i, n + j] = 1.0
        Di[i] = 0.0
    info = dict(getattr(model, "info", None) or {})
    info["integrating"] = {"outputs": list(outputs), "free_order": n}
    return StateSpaceModel(Ai, Bi, Ci, Di, dt=model.dt, info=info,
                           input_names=getattr(model, "input_names", None),
                           output_names=getattr(model, "output_names", None))


def _sweep(board: Board, horizon: int, methods: tuple[str, ...], top: int,
           outputs: list[int]) -> None:
    try:
        rows, _ = transformed_sweep(board, lambda d: differenced(d, outputs),
                                    lambda m: integrated(m, outputs), horizon, methods, top,
                                    CRITERION, extra_order=len(outputs))
    except (SysidError, ValueError, np.linalg.LinAlgError):
        return  # a fitted part that cannot be differenced and fitted: no such family
    for row in rows:
        row["integrating"] = list(outputs)


def integrating_candidates(board: Board, horizon: int, methods: tuple[str, ...]) -> None:
    """Subspace candidates (``methods``, every order and feedthrough choice of the sweep)
    fitted to the record with one output differenced and integrated back
    (:func:`integrated`), one family per output (records of at most :data:`MAX_OUTPUTS`
    outputs), leaderboard rows ``<method> (integrating)``. Only when an unstable candidate
    beats the stable ones on every held-out block but not once the record's drift is taken
    out (:meth:`.board.Board.unstable_verdict` ``"drift"``, which an integrating output
    gives as well: the line taken out of each channel takes part of its summed response),
    not under feedback (open-loop fits, biased there, as the sweep's), and kept as
    candidates only when the best of them beats the best stable candidate on every held-out
    block with the record's drift left in and taken out
    (:meth:`.board.Board.beats_without_drift`, the test an unstable candidate must pass):
    a drift the input does not explain is not an integrator's output, and a record whose
    output drifts keeps its stable model. Their free part's poles decide whether they count
    as stable; the pinned integrator does not (:func:`.board.free_poles`)."""
    if board.subspace is None or board.feedback or board.unstable_verdict() != "drift":
        return
    first = board.folds[0][0]
    if first.n_outputs > MAX_OUTPUTS:
        return
    stable = board.best()
    _, _, top = board.subspace
    for i in range(first.n_outputs):
        _sweep(board, horizon, methods, top, [i])
    rows = [r for r in board.rows if r["criterion"] == CRITERION
            and np.isfinite(r["held_out_fit"]) and r["stable"]]
    if not rows:
        return
    if stable is None or board.beats_without_drift(
            max(rows, key=lambda r: r["held_out_fit"]), stable):
        return
    for r in board.rows:
        if r["criterion"] == CRITERION:
            r["start_only"] = True  # held back: not chosen
            r["note"] = r["note"] or (
                "integrating: the best of these does not beat the best stable candidate on "
                "every held-out block with the record's drift left in and taken out: not "
                "chosen")


def integrating_note(model: Any) -> str | None:
    """``checks["integrating"]`` for a chosen model with an integrator made explicit (None
    for any other).

    Examples
    --------
    >>> import sysid
    >>> from sysid.identify.integrating import integrated, integrating_note
    >>> m = integrated(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0], [1.0]]), [1])
    >>> integrating_note(m)[:46]
    'output(s) y1 integrate: the model is fitted to'
    """
    info = (getattr(model, "info", None) or {}).get("integrating")
    if not info:
        return None
    names = getattr(model, "output_names", None)
    outs = ", ".join(names[i] if names and i < len(names) else f"y{i}"
                     for i in info["outputs"])
    rho = float(np.max(np.abs(free_poles(model)), initial=0.0))
    return (f"output(s) {outs} integrate: the model is fitted to their increments and sums "
            f"them, a pole at exactly 1 per integrated output (marginally stable: a bounded "
            f"input can drive the output without bound, the static gain to it is infinite, "
            f"and is_stable() is False, as for any pole on the unit circle); its other "
            f"{info['free_order']} pole(s) have modulus at most {rho:.4g}. The integrator is "
            f"fixed by the structure, not estimated: the standard deviation poles(std=True) "
            f"gives it is that of a free pole there")
