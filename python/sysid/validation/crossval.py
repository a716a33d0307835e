"""Order choice by simulation error cross-validated inside the estimation record.

The singular values of a subspace projection fall off smoothly on real records (unmodelled
dynamics, coloured noise, nonlinearity), so the largest gap of their logarithms usually sits
after the first one or two and picks order 1-2 where the data support more. What an engineer
checks instead is how well a model of each order *simulates data it was not fitted on*. This
module does that without touching the user's validation data: the estimation record is cut
into five contiguous blocks (fewer on short records; or the experiments themselves; a chirp
into interleaved pieces, :mod:`.swept`), models
of every order are fitted on the rest and simulated on the block left out (initial state
fitted by least squares, with the prior of where the block's input puts the model's state:
:mod:`.state_prior`), and the order whose median held-out simulation fit is best wins (the
median: a record often holds one block unlike the others, which would otherwise decide
alone); a smaller order within ``tol`` fit points (and 5 % of the best's error) of the best
is preferred (a smaller model generalises better), and so is one within :data:`RESOLUTION`
of 100 %, identify's tie (:func:`tie`). Given the estimator on the whole record
(``whole=``), an order whose model there is unstable is chosen only when the data insist
(:func:`stable_first`). Fits are on compressions of the blocks, so a sweep costs about one
pass over the record per block plus one simulation per order and block.

Weighed on the real records of ``benches/realdata.py`` under its three splits (29 record x
split pairs x 3 weightings; the validation fit of the order chosen, clipped at -100 %, mean
over them; D chosen with the order, 19.7 % with D = 0): median 26.9 %, the trimmed mean of
identify's board 31.4 %, a one-standard-error rule (the smallest order within a standard
error of the paired fold differences) 23.4 %; with the stable-first rule 37.0 % (median),
33.7 % (trimmed mean). The one-standard-error rule falls to order 1 wherever the folds
disagree (one block unlike the others), and the trimmed mean lost the F-16's high orders;
the median with stable-first is kept.

Identify's pooled score (:mod:`sysid.identify.board`: per output the held-out blocks' summed
squared errors over their summed output variation, still blocks left out) was weighed here too
(issue 26; ssest / n4sid / moesp / cva at their defaults, the 26 record x split pairs every
tool accepts and the two F-16 levels, validation fits clipped at -100 % and summed): median
1215 / 1065 / 1168 / 1024, pooled and trimmed as identify's 1047 / 1008 / 939 / 933, pooled
over every block 1209 / 1121 / 1058 / 1076. The differences are orders whose validation fit
swings by tens of points between neighbours (flutter, ball and beam, pH, the F-16 at orders
13-18; order 18 of MOESP on F-16 level 1 diverges on one held-out block and validates at 59 %,
which only the median forgives); left out, the still blocks of flutter under the swap split
leave one lively block to choose by, and every tool then validates below -100 % (n4sid -58 %,
moesp 24 %, cva 14 % with the median). The median is kept.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import _sysid
from ..data.iodata import IOData
from ..errors import DataError, ExcitationError, InsufficientDataError, SysidError
from .stable_orders import stable_first, unstable_orders
from .swept import PIECES, SHORTEST, interleaved_folds, swept
from .ties import RESOLUTION, TOL, slack, tie, wins_every_block

__all__ = ["OrderChoice", "cross_validated_order", "fold_count", "fold_horizon", "folds",
           "grown_order", "held_out_fit", "held_out_folds", "insists", "output_fits",
           "preceding_inputs", "prediction_fit", "predictor", "record_folds", "simulation_errors",
           "simulation_fit", "slack", "stable_first", "tie", "variation", "wins_every_block",
           "RESOLUTION"]

#: largest order tried by the automatic choice, unless the best held-out order is this one
#: (:func:`grown_order`)
MAX_ORDER = 20
#: blocks of a record, each held out once (the rest fits the candidates)
FOLDS = 5
#: samples per channel a held-out block keeps at least (fewer blocks on short records)
MIN_BLOCK = 20


@dataclass
class OrderChoice:
    """The automatic order, the table it was read from, and why.

    Attributes
    ----------
    order : int
    table : dict
        ``{order: held-out simulation fit %}`` (mean over outputs, median over blocks).
    reason : str
    criterion : str
    """

    order: int
    table: dict[int, float] = field(default_factory=dict)
    reason: str = ""
    criterion: str = "cross-validated simulation fit"

    def as_dict(self) -> dict[str, Any]:
        return {"order": self.order, "criterion": self.criterion, "reason": self.reason,
                "table": {int(k): float(v) for k, v in self.table.items()}}


def fold_count(data: IOData) -> int:
    """How many blocks :func:`folds` cuts a record into for the automatic choices: one per
    experiment; for one experiment ``FOLDS``, fewer when a block would hold less than
    ``MIN_BLOCK`` samples per channel (at least three of 20 samples, or two).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.crossval import fold_count
    >>> fold_count(sysid.IOData(u=np.zeros(1000), y=np.ones(1000))), fold_count(
    ...     sysid.IOData(u=np.zeros(50), y=np.ones(50)))
    (5, 2)
    """
    if data.n_experiments > 1:
        return data.n_experiments
    per = MIN_BLOCK * (data.n_inputs + data.n_outputs)
    N = data.lengths[0]
    # a short record: three blocks of at least 20 samples keep two thirds for each fit
    return int(max(2, min(FOLDS, N // max(per, 20)), min(3, N // 20)))


def fold_horizon(h: int, fit_part: IOData) -> int:
    """The subspace horizon for a fold: ``h``, the whole record's (the model class of the
    final fit), unless the fitted part is too short for a data matrix with three times as
    many columns as rows."""
    ch = fit_part.n_inputs + fit_part.n_outputs
    cols = sum(max(n - 2 * h + 1, 0) for n in fit_part.lengths)
    return h if cols >= 6 * ch * h else max(2, min(h, max(fit_part.lengths) // (6 * ch)))


def folds(data: IOData, k: int = 2) -> list[tuple[IOData, IOData]]:
    """(fit, held-out) pairs: leave one experiment out, or for one experiment its ``k``
    contiguous blocks, each held out once; the fitted part is what lies before and after the
    held-out block (at most two contiguous experiments, so no data are lost to block edges).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.crossval import folds
    >>> d = sysid.IOData(u=np.arange(10.0), y=np.arange(10.0))
    >>> [(f.lengths, h.lengths) for f, h in folds(d, 5)][2]
    ([4, 4], [2])
    """
    exps = data.experiments
    kw = {"dt": data.dt, "input_names": data.input_names, "output_names": data.output_names}
    out = []
    if len(exps) >= 2:
        for i in range(len(exps)):
            out.append((_io([e for j, e in enumerate(exps) if j != i], kw), _io([exps[i]], kw)))
        return out
    u, y = exps[0]
    edges = np.linspace(0, u.shape[0], k + 1).astype(int)
    for a, b in zip(edges[:-1], edges[1:]):
        rest = [(u[s:t], y[s:t]) for s, t in ((0, a), (b, u.shape[0])) if t > s]
        out.append((_io(rest, kw), _io([(u[a:b], y[a:b])], kw)))
    return out


def require_held_out_length(data: IOData) -> None:
    """Refuse a record shorter than two held-out blocks (``2 * MIN_BLOCK`` samples) with
    the reason, before any check of its channels: on one sample every channel is
    "constant" (``identify`` on 1 sample said "input u0 is 0 in every sample").

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.crossval import require_held_out_length
    >>> require_held_out_length(sysid.IOData(u=np.arange(3.0), y=np.arange(3.0) ** 2))
    Traceback (most recent call last):
    ...
    sysid.errors.InsufficientDataError: the record is too short to hold out a part ...
    """
    n = sum(data.lengths)
    if n < 2 * MIN_BLOCK:
        raise InsufficientDataError(
            f"the record is too short to hold out a part for the choice ({n} sample"
            f"{'s' if n != 1 else ''}; two held-out blocks of {MIN_BLOCK} need "
            f"{2 * MIN_BLOCK}); pass a longer record or fit one model directly")


def parts_too_short(full: IOData, folds: list[tuple[IOData, IOData]]
                    ) -> InsufficientDataError:
    """The error of a record whose parts fitted without one held-out block (``folds``) are
    too short for the smallest subspace window (horizon 2): the samples one such part needs,
    the record's, and the fix (many channels on a short record: 57 samples of 5 inputs and 2
    outputs).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.crossval import parts_too_short, record_folds
    >>> d = sysid.IOData(u=np.zeros((57, 5)), y=np.zeros((57, 2)))
    >>> str(parts_too_short(d, record_folds(d)))[:60]
    'the record is too short for identify with 5 input(s) and 2 o'
    """
    m, l = full.n_inputs, full.n_outputs
    # a data matrix of horizon 2 has 4 (m + l) rows and needs as many columns (window 4)
    need = 4 * (m + l) + 3
    longest = max(max(f.lengths) for f, _ in folds)
    return InsufficientDataError(
        f"the record is too short for identify with {m} input(s) and {l} output(s): each part "
        f"fitted without one held-out block needs an experiment of at least {need} samples "
        f"for the smallest subspace window (horizon 2), and the longest such part here has "
        f"{longest} (the record: {sum(full.lengths)} samples); pass a longer record (about "
        f"{2 * need} samples or more) or more experiments, or fit one model to the whole "
        f"record directly (sysid.ssest(data, order), sysid.n4sid(data, order), sysid.arx)")


def record_folds(data: IOData) -> list[tuple[IOData, IOData]]:
    """(fit, held-out) pairs over the whole record, whatever its experiments' lengths: the
    experiments laid end to end and cut into ``fold_count`` of their total length contiguous
    blocks (as one experiment of that length would be), each held out once; a block is cut
    where an experiment ends (its pieces are separate experiments, no window spans two),
    and a block edge within a quarter of a block (at least ``MIN_BLOCK`` samples) of an
    experiment's end moves onto it, so that no held-out piece is a sliver. Experiments
    shorter than ``MIN_BLOCK`` are never held out (their initial state would take most of
    their samples), and the fitted parts keep only pieces of at least ``MIN_BLOCK`` samples.
    One experiment: :func:`folds` with :func:`fold_count`, or, when its input sweeps its
    band (a chirp: each block holds a band the rest never excited,
    :func:`sysid.validation.swept.swept`), as many folds of interleaved pieces
    (:func:`~sysid.validation.swept.interleaved_folds`). Several: leaving one experiment
    out fitted every candidate on the other ones alone, so a short experiment next to a
    long one left a fold fitted on the short one, and every candidate was held to what it
    could support (order 1 from 30 samples next to 500).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.crossval import record_folds
    >>> d = sysid.IOData(u=[np.zeros(500), np.zeros(30)], y=[np.ones(500), np.ones(30)])
    >>> [(f.lengths, h.lengths) for f, h in record_folds(d)][4]
    ([424], [76, 30])
    """
    exps = data.experiments
    if len(exps) == 1:
        pairs = folds(data, fold_count(data))
        k = len(pairs)
        # a swept input (a chirp): every contiguous block is a band the rest never excited
        if data.lengths[0] // (k * PIECES) >= SHORTEST and swept(pairs):
            return interleaved_folds(data, k)
        return pairs
    kw = {"dt": data.dt, "input_names": data.input_names, "output_names": data.output_names}
    lengths = [u.shape[0] for u, _ in exps]
    holdable = [i for i, n in enumerate(lengths) if n >= MIN_BLOCK]
    # the holdable experiments end to end: where each starts on that axis
    starts = np.cumsum([0] + [lengths[i] for i in holdable])
    total = int(starts[-1])
    one = IOData(u=np.zeros((total, data.n_inputs)), y=np.zeros((total, data.n_outputs)))
    k = fold_count(one)
    edges = np.linspace(0, total, k + 1).astype(int)
    snap = max(MIN_BLOCK, total // (4 * k))
    for j in range(1, k):
        near = starts[np.argmin(np.abs(starts - edges[j]))]
        if abs(near - edges[j]) <= snap:
            edges[j] = near
    out = []
    for a, b in zip(edges[:-1], edges[1:]):
        if b <= a:
            continue
        held, rest = [], []
        for i, n in enumerate(lengths):
            u, y = exps[i]
            if i not in holdable:
                rest.append((u, y))
                continue
            s = int(starts[holdable.index(i)])
            lo, hi = min(max(a - s, 0), n), min(max(b - s, 0), n)
            if hi > lo:
                held.append((u[lo:hi], y[lo:hi]))
            rest += [(u[p:q], y[p:q]) for p, q in ((0, lo), (hi, n)) if q - p >= MIN_BLOCK]
        if held and rest:
            out.append((_io(rest, kw), _io(held, kw)))
    return out


def preceding_inputs(whole: IOData, held: IOData, depth: int) -> list[np.ndarray]:
    """The inputs recorded before each experiment of the held-out block ``held`` in the
    record ``whole`` it was cut from (:func:`record_folds` cuts views of its experiments):
    per experiment, at most ``depth`` rows (samples x inputs), fewer where its experiment of
    ``whole`` starts sooner, none for a piece that starts one or is not a slice of ``whole``.
    What a delay line holds when the block starts: a model with input delays scored on the
    block feeds them, not a guess (:func:`sysid.models.input_delay.delay_free_view`).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.crossval import preceding_inputs, record_folds
    >>> d = sysid.IOData(u=np.arange(1000.0), y=np.zeros(1000))
    >>> held = record_folds(d)[1][1]
    >>> preceding_inputs(d, held, 3)[0].ravel().tolist(), float(held.u[0, 0])
    ([197.0, 198.0, 199.0], 200.0)
    """
    depth = max(int(depth), 0)
    out = []
    for u, _ in held.experiments:
        before = u[:0]
        for w, _ in whole.experiments:
            if w.ndim != 2 or w.shape[1] != u.shape[1] or not np.may_share_memory(w, u) \
                    or w.strides != u.strides or u.shape[0] == 0:
                continue
            start, rem = divmod(u.ctypes.data - w.ctypes.data, w.strides[0])
            if rem == 0 and 0 <= start and start + u.shape[0] <= w.shape[0] \
                    and np.array_equal(w[start:start + u.shape[0]], u):
                before = w[max(0, start - depth):start]
                break
        out.append(before)
    return out


def _io(exps: list[tuple[np.ndarray, np.ndarray]], kw: dict[str, Any]) -> IOData:
    if len(exps) == 1:
        return IOData(u=exps[0][0], y=exps[0][1], **kw)
    return IOData(u=[e[0] for e in exps], y=[e[1] for e in exps], **kw)


def simulation_errors(model: Any, data: IOData, trend: bool = False, prior: bool = True
                      ) -> list[tuple[np.ndarray, np.ndarray]]:
    """``(y, y - yhat)`` per experiment: the model's simulation with its initial state and a
    constant offset per output fitted by least squares (see :func:`simulation_fit`); with
    ``trend``, a straight line per output instead of the offset. The initial state is
    fitted with the prior of where the experiment's input can put the model's state
    (:mod:`.state_prior`: a mode the input does not drive cannot fit the block's noise);
    ``prior=False`` fits it freely. Raises when the model cannot be simulated on the
    data."""
    from .state_prior import input_state_covariance

    A = np.ascontiguousarray(model.A, dtype=float)
    C = np.ascontiguousarray(model.C, dtype=float)
    B = np.asarray(getattr(model, "B", np.zeros((A.shape[0], 0))), dtype=float)
    out = []
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        for u, y in data.experiments:
            ys = np.asarray(model.simulate(u), dtype=float)
            P = None  # the prior covariance of the initial state
            if prior and B.ndim == 2 and B.shape[0] == A.shape[0] and u is not None:
                P = input_state_covariance(A, B, np.asarray(u, dtype=float).reshape(len(y), -1))
            # the offsets and the initial state fitted in the core (sysid_core::model::
            # initial_state: block by block, no (N l, n) array of free responses, as thousands
            # of candidates are scored on blocks of long records; normal equations, or QR where
            # a growing mode makes them ill-conditioned), rows weighed by 1 / each output's
            # spread (the fit % is relative to it: the shared initial state does not follow
            # whichever output has the largest numbers in its units)
            e = _sysid.fitted_errors(A, C, np.asarray(y, dtype=float), ys, trend, P)
            if e is None:
                raise FloatingPointError("the model diverges on these data")
            out.append((y, e))
    return out


def trend_share(model: Any, data: IOData) -> tuple[np.ndarray, np.ndarray]:
    """Per output, what a straight line per output and experiment takes out of ``model``'s
    simulation errors on ``data`` (initial state and an offset fitted,
    :func:`simulation_errors`): as a share of those errors' sum of squares, and of the
    output's own variation. Near 0 when the model explains the record's slow movements,
    large when the output drifts in a way the input does not explain. Raises when the model
    cannot be simulated on the data.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.crossval import trend_share
    >>> rng = np.random.default_rng(0)
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    >>> u = rng.standard_normal(400)
    >>> y = m.simulate(u) + 0.1 * rng.standard_normal((400, 1))
    >>> float(trend_share(m, sysid.IOData(u=u, y=y))[0][0]) < 0.05
    True
    >>> ramp = y + np.linspace(0.0, 2.0, 400)[:, None]  # a drift the input does not explain
    >>> of_errors, of_output = trend_share(m, sysid.IOData(u=u, y=ramp))
    >>> float(of_errors[0]) > 0.5, float(of_output[0]) > 0.1
    (True, True)
    """
    flat = simulation_errors(model, data)
    line = simulation_errors(model, data, trend=True)
    ss0 = sum(np.sum(e ** 2, axis=0) for _, e in flat)
    ss1 = sum(np.sum(e ** 2, axis=0) for _, e in line)
    sy = sum(np.sum((y - y.mean(0)) ** 2, axis=0) for y, _ in flat)
    with np.errstate(all="ignore"):
        of_errors = np.where(ss0 > 0, 1.0 - ss1 / np.where(ss0 > 0, ss0, 1.0), 0.0)
        of_output = np.where(sy > 0, (ss0 - ss1) / np.where(sy > 0, sy, 1.0), 0.0)
    return np.clip(of_errors, 0.0, 1.0), np.clip(of_output, 0.0, 1.0)


def simulation_fit(model: Any, data: IOData, trend: bool = False) -> float:
    """Held-out simulation fit (NRMSE %, mean over outputs and experiments); ``-inf`` for a
    model that diverges (a model with a pole just outside the unit circle is scored on what
    it does over the block).

    The initial state and a constant offset per output are fitted by least squares (as
    :func:`sysid.compare` fits the initial state): every block keeps some offset after the
    record's means are removed, and without the free offset a slow mode of an over-fitted
    model (a pole near 1 excited by ``x0``) would absorb it and look better than it predicts.
    ``trend=True`` fits a straight line per output instead of the offset (the same for a
    drift: :meth:`sysid.identify.board.Board.insisting`).
    """
    try:
        errs = simulation_errors(model, data, trend)
    except Exception:  # noqa: BLE001 - a model that cannot be simulated scores -inf
        return -np.inf
    fits = []
    with np.errstate(all="ignore"):
        for y, e in errs:
            dev = np.linalg.norm(y - y.mean(0), axis=0)
            f = 100.0 * (1.0 - np.linalg.norm(e, axis=0) / np.where(dev > 0, dev, np.nan))
            f = f[~np.isnan(f)]  # outputs that stand still in the block have no fit
            fits.append(float(np.mean(f)) if f.size else np.nan)
    out = float(np.mean(fits))
    return out if np.isfinite(out) else -np.inf


def predictor(model: Any) -> Any:
    """The one-step-ahead predictor of ``model`` (with its Kalman gain ``K``) as a
    state-space model whose inputs are ``[u, y]``: ``x+ = (A - K C) x + (B - K D) u + K y``,
    ``yhat = C x + D u``. Simulating it on ``[u, y]`` gives the one-step predictions.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.crossval import predictor
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]], [[0.0]], [[0.5]], dt=1.0)
    >>> p = predictor(m)
    >>> p.A.tolist(), p.B.tolist()
    ([[0.4]], [[1.0, 0.5]])
    """
    from ..models.statespace import StateSpaceModel

    A, B, C, D = (np.asarray(getattr(model, k), float) for k in ("A", "B", "C", "D"))
    K = np.asarray(model.K, float)
    l = C.shape[0]
    return StateSpaceModel(A - K @ C, np.hstack([B - K @ D, K]), C,
                           np.hstack([D, np.zeros((l, l))]), dt=model.dt)


def prediction_fit(model: Any, data: IOData) -> float:
    """Held-out one-step-ahead prediction fit (NRMSE %, mean over outputs and experiments)
    of a model with a noise model (``K``): :func:`simulation_fit` of its :func:`predictor`
    driven by the measured inputs and outputs (initial state and offsets fitted by least
    squares as there); ``-inf`` for a model without ``K`` or whose predictor diverges. The
    held-out score of a time-series model, whose simulation is zero.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.crossval import prediction_fit
    >>> m = sysid.StateSpaceModel([[0.9]], np.zeros((1, 0)), [[1.0]], np.zeros((1, 0)),
    ...                           [[0.5]], dt=1.0)
    >>> e = np.random.default_rng(0).standard_normal((500, 1))
    >>> y = sysid.StateSpaceModel([[0.9]], [[0.5]], [[1.0]], [[1.0]]).simulate(e)
    >>> bool(prediction_fit(m, sysid.IOData(y=y)) > 0)
    True
    """
    if getattr(model, "K", None) is None:
        return -np.inf
    try:
        p = predictor(model)
    except Exception:  # noqa: BLE001 - a model whose predictor cannot be formed
        return -np.inf
    kw = {"dt": data.dt}
    exps = [(np.hstack([u, y]), y) for u, y in data.experiments]
    return simulation_fit(p, _io(exps, kw))


def variation(data: IOData) -> np.ndarray:
    """Per output, ``|y - mean(y)|^2`` summed over the experiments of ``data`` (each about
    its own mean): the denominator of :func:`output_fits`, and the weight of a held-out
    block in identify's score (:func:`sysid.identify.board.held_out_score`)."""
    return np.asarray(sum(np.sum((y - y.mean(0)) ** 2, axis=0) for _, y in data.experiments))


def output_fits(model: Any, data: IOData, trend: bool = False,
                dev: np.ndarray | None = None) -> np.ndarray:
    """Per output, the simulation fit (NRMSE %) of ``model`` on ``data`` with its
    experiments pooled (``100 (1 - |e| / |y - mean(y)|)``, sums of squares over the
    experiments, each about its own mean; initial state and offset fitted as in
    :func:`simulation_fit`); ``-inf`` for every output when the model diverges, NaN for an
    output that stands still. For one experiment their mean is :func:`simulation_fit`.
    ``dev``: the data's :func:`variation`, when the caller holds it (thousands of
    candidates are scored on the same blocks).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.crossval import output_fits
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0], [2.0]], dt=1.0)
    >>> u = np.random.default_rng(0).standard_normal(200)
    >>> output_fits(m, sysid.IOData(u=u, y=m.simulate(u))).round(6)
    array([100., 100.])
    """
    try:
        errs = simulation_errors(model, data, trend)
    except Exception:  # noqa: BLE001 - a model that cannot be simulated scores -inf
        return np.full(data.n_outputs, -np.inf)
    err = sum(np.sum(e ** 2, axis=0) for _, e in errs)
    dev = variation(data) if dev is None else dev
    with np.errstate(all="ignore"):
        f = 100.0 * (1.0 - np.sqrt(err / np.where(dev > 0, dev, np.nan)))
    return np.where(np.isnan(f) & (dev > 0), -np.inf, f)


def insists(better: Any, worse: Any) -> bool:
    """Whether per-block fits ``better`` beat the paired ``worse`` by more than twice the
    standard error of their differences (mean), and in the median: the held-out blocks
    insist on the change rather than allow it (the richer model structures of ``pnlss``'s
    degree and ``nlhw``'s nonlinearities are taken only then).

    Examples
    --------
    >>> from sysid.validation.crossval import insists
    >>> insists([90, 91, 92, 90, 93], [80, 82, 81, 80, 84]), insists([90, 60, 92], [80, 82, 81])
    (True, False)
    """
    d = np.subtract(better, worse, dtype=float)
    if d.size < 2:
        return False
    se = d.std(ddof=1) / np.sqrt(d.size)
    return bool(d.mean() > 2 * se and np.median(better) > np.median(worse))


def held_out_fit(model: Any, block: IOData, floor: float = -100.0) -> float:
    """``model``'s simulation fit on a held-out ``block`` (:func:`sysid.compare`, its
    initial state fitted; % mean over outputs), at least ``floor``: one runaway block is one
    bad block, not the whole score."""
    from .compare import compare_quiet

    fit = float(np.mean(compare_quiet(block, model).fit))
    return max(floor, fit) if np.isfinite(fit) else floor


def held_out_folds(pairs: list[tuple[IOData, IOData]], kinds: Sequence[Any],
                   fit: Callable[[IOData, Any, dict[Any, Any]], Any],
                   tick: Callable[[int, float], Any] | None = None, floor: float = -100.0
                   ) -> tuple[dict[Any, list[float]], dict[Any, list[SysidError]]]:
    """Each of ``kinds`` fitted on every (part, block) pair of :func:`record_folds` and
    scored on the block by :func:`held_out_fit`: the loop of the automatic structures
    (``pnlss``'s degree, ``nlhw``'s nonlinearities, ``nlarx``'s terms). ``fit(part, kind,
    fitted)`` gets the models of the kinds fitted before it on that part (``None`` where
    that fit failed: a shared start is fitted once); ``tick(count, fit)`` after each, in
    order. Returns per kind its block fits (a failed fit or score counts ``floor``) and its
    errors. The fits' own warnings are not the caller's: they are silenced.

    The parts are fitted on the cores at hand (:func:`sysid._parallel.ordered`: the same
    results as one after another; Ctrl-C stops the fits on the other threads too).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.crossval import held_out_folds, record_folds
    >>> u = np.random.default_rng(0).standard_normal((200, 1))
    >>> d = sysid.IOData(u, np.convolve(u[:, 0], [0, 1.0, 0.5])[:200, None])
    >>> folds, failed = held_out_folds(record_folds(d), [1],
    ...                                lambda part, k, fitted: sysid.n4sid(part, 2))
    >>> len(folds[1]), min(folds[1]) > 99, failed[1]
    (5, True, [])
    """
    from contextlib import closing

    from .._parallel import ordered
    from .._progress import stop_requested

    def one(pair: tuple[IOData, IOData]) -> list[tuple[float, SysidError | None]]:
        part, block = pair
        fitted: dict[Any, Any] = {}
        out: list[tuple[float, SysidError | None]] = []
        for k in kinds:
            fitted[k] = None
            if stop_requested():  # stopped (Ctrl-C): the part's other fits are not started
                break
            try:
                fitted[k] = fit(part, k, fitted)
                out.append((held_out_fit(fitted[k], block, floor), None))
            except SysidError as e:
                out.append((floor, e))
        return out

    folds: dict[Any, list[float]] = {k: [] for k in kinds}
    failed: dict[Any, list[SysidError]] = {k: [] for k in kinds}
    with warnings.catch_warnings():  # around the threads: the filters are the process's
        warnings.simplefilter("ignore")
        with closing(ordered([lambda pair=pair: one(pair) for pair in pairs])) as results:
            for res in results:
                for k, (f, err) in zip(kinds, res):
                    folds[k].append(f)
                    if err is not None:
                        failed[k].append(err)
                    if tick is not None:
                        tick(sum(map(len, folds.values())), f)
    return folds, failed


def choose(table: dict[int, float], tol: float = TOL, what: str = "simulation"
           ) -> tuple[int, str]:
    """The smallest order within :func:`tie` of the best held-out fit (``min(tol, 5 % of the
    best's error)`` fit points, and every fit within :data:`RESOLUTION` of 100 %): a smaller
    model generalises better, and on noise-free data only round-off separates the orders
    from the true one up, and the true one is taken.

    Examples
    --------
    >>> from sysid.validation.crossval import choose
    >>> choose({1: 40.0, 2: 99.98, 3: 100.0})[0], choose({1: 40.0, 2: 97.0, 3: 97.3})[0]
    (2, 3)
    """
    finite = {n: f for n, f in table.items() if np.isfinite(f)}
    if not finite:
        raise InsufficientDataError(
            f"no order gave a model whose {what} scores on the held-out data (every order "
            f"failed to fit on the rest of the record or to simulate a held-out block): the "
            f"record is too short or too little excited to choose the order from held-out "
            f"blocks; pass an order, or use a longer record")
    best_n = max(finite, key=lambda n: finite[n])
    best = finite[best_n]
    margin = tie(best, tol)
    n = min(o for o, f in finite.items() if f >= best - margin)
    why = (f"held-out {what} fit {finite[n]:.1f} % at order {n}"
           + (f" (best {best:.1f} % at order {best_n}; a smaller order within {margin:.2g} "
              "points is preferred)" if n != best_n else " (the best)"))
    return n, why


def cross_validated_order(
    data: IOData,
    estimator: Any,
    *,
    method: str = "moesp",
    past: int | None = None,
    future: int | None = None,
    feedthrough: bool = False,
    orders: list[int] | None = None,
    tol: float = TOL,
    whole: Any = None,
    focus: str = "simulation",
) -> OrderChoice:
    """Choose a subspace model's order by simulation fit on blocks of the record held out
    (one-step-ahead prediction fit with ``focus="prediction"``, the choice for a time series).

    Parameters
    ----------
    data : IOData
        The estimation record (the user's validation data are never needed).
    estimator : type
        :class:`sysid.SubspaceEstimator` (or a class with its constructor and ``fit``).
    method : str
        Subspace weighting.
    past, future : int, optional
        Horizons (default: :func:`sysid.default_horizon` of the shortest fitted block).
    feedthrough : bool
        Estimate ``D`` in the fits.
    orders : list of int, optional
        Orders to try (default ``1 .. min(max_order, 20)``, grown by :func:`grown_order`
        while the best is the top).
    tol : float
        Fit points a smaller order may give up and still win.
    whole : SubspaceEstimator, optional
        The estimator on the whole record, whose model of the chosen order is the one
        returned: an order whose model there is unstable is chosen only when the data insist
        (:func:`stable_first`).
    focus : {"simulation", "prediction"}
        Score the held-out blocks by simulation (:func:`simulation_fit`) or by one-step
        prediction with the fitted noise model (:func:`prediction_fit`).

    Returns
    -------
    OrderChoice

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.crossval import cross_validated_order
    >>> rng = np.random.default_rng(0)
    >>> true = sysid.StateSpaceModel([[0.9, 0.3, 0], [-0.3, 0.9, 0], [0, 0, 0.5]],
    ...                              [[1.0], [0.0], [1.0]], [[1.0, 0.5, 1.0]])
    >>> u = rng.standard_normal(1000)
    >>> y = true.simulate(u) + 0.1 * rng.standard_normal((1000, 1))
    >>> cross_validated_order(sysid.IOData(u=u, y=y), sysid.SubspaceEstimator).order
    3
    """
    if focus not in ("simulation", "prediction"):
        raise DataError(f"focus must be 'simulation' or 'prediction', got {focus!r}")
    predict = focus == "prediction"
    table: dict[int, list[float]] = {}
    h = 0
    if past is None and future is None:  # the whole record's default horizon
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            h = estimator(data, method=method).past
    from ..data.segments import long_enough

    fitted, skipped = [], 0  # (estimator, held-out block) per fold; folds left out
    for fit_part, held in record_folds(data):
        # the given horizons, clipped to a quarter of the fitted part; else the record's
        longest = max(fit_part.lengths)
        kw = {k: min(v, max(1, longest // 4)) for k, v in (("past", past), ("future", future))
              if v is not None} or {"horizon": fold_horizon(h, fit_part)}
        # pieces too short for the window are left out of this fit (not allowed to fail it)
        part = long_enough(fit_part, kw.get("past", 0) + kw.get("future", 0)
                           or 2 * kw["horizon"]) or fit_part
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                fitted.append((estimator(part, method=method, **kw), held))
            except ExcitationError:
                # the record without this block excites too little for the window (a
                # ramp or a step inside the block): the other folds judge, as in identify
                skipped += 1
    if len(fitted) < 2 and skipped:
        raise ExcitationError(f"{skipped} of the {skipped + len(fitted)} parts fitted without "
                              f"one held-out block are not persistently exciting for the "
                              f"window: too few left to cross-validate")

    def score(grid: Any) -> dict[int, float]:
        for est, held in fitted:
            for n in grid:
                if n > est.max_order:
                    continue
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        m = est.fit(n, feedthrough=feedthrough, kalman=predict)
                    table.setdefault(n, []).append(prediction_fit(m, held) if predict
                                                   else simulation_fit(m, held))
                except Exception:  # noqa: BLE001 - an order the block cannot support
                    table.setdefault(n, []).append(-np.inf)
        k = max(map(len, table.values()))
        return {n: float(np.median(v)) if len(v) == k else -np.inf for n, v in table.items()}

    ceiling = min(est.max_order for est, _ in fitted)
    top = min(ceiling, MAX_ORDER)
    med = score(orders or range(1, top + 1))
    # the best order at the top of the default grid: the grid grows while the window allows
    while not orders and top < ceiling and max(med, key=lambda n: med[n]) == top:
        low, top = top + 1, grown_order(top, ceiling)
        med = score(range(low, top + 1))
    models: dict[int, Any] = {}
    unstable = (unstable_orders(whole, med, method, feedthrough, models) if whole is not None
                else set())

    def whole_fit(n: int) -> float:
        # the order's model on the whole record simulating it (stable_first's last check)
        return simulation_fit(models[n], data) if n in models else -np.inf

    # a time series has no simulation to check (its models are scored by prediction)
    check = whole_fit if whole is not None and not predict else None
    allowed, note = stable_first(med, table, unstable, check)
    what = "one-step prediction" if predict else "simulation"
    n, why = choose({o: f for o, f in med.items() if o in allowed}, tol, what)
    return OrderChoice(n, med, why + note, f"cross-validated {what} fit")


def grown_order(top: int, ceiling: int) -> int:
    """The next top of an order grid whose best held-out order is its top ``top``: half as
    many orders again (at least four), at most ``ceiling`` (what the subspace window allows).

    An automatic order choice tries orders 1 to :data:`MAX_ORDER`; a record whose held-out
    fit still rises at the top (a piezo steering mirror, 3 x 3 with lightly damped modes:
    84.6, 85.9 % at orders 19, 20, its published linear models of order 28) was given order
    20 without a word. The grid grows instead, as long as the best order is its top.

    Examples
    --------
    >>> from sysid.validation.crossval import grown_order
    >>> grown_order(20, 57), grown_order(30, 33), grown_order(2, 57)
    (30, 33, 6)
    """
    return int(min(ceiling, top + max(4, top // 2)))
