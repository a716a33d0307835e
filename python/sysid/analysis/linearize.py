"""Steady operating points and linearisations of any model (MATLAB's ``findop(sys, 'steady',
u0)`` and ``linearize(sys, u0, x0)``), from its simulation alone.

:func:`findop` holds the input at ``u0`` from rest and simulates until the output stops
changing: the steady output ``y0`` (a model whose output keeps moving, a limit cycle or a
divergence, has no steady point, and says so). :func:`linearize` then perturbs each input by
a small impulse at the operating point, in both directions: the central differences of the
responses are the Markov parameters of the linearisation (``h_0 = D``, ``h_k = C A^(k-1) B``
of the small-signal model, exact to second order in the perturbation), realised by the
eigensystem realisation algorithm (:func:`sysid.era`) at the rank they show. One path serves
every model family (NARX, Hammerstein-Wiener, PNLSS, neural state space, grey boxes): what it
needs is ``simulate(u)`` from rest. The result maps deviations ``u - u0`` to deviations ``y
- y0``.

Examples
--------
>>> import numpy as np, sysid
>>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
>>> op = sysid.findop(m, 2.0)
>>> float(np.round(op.y0[0], 8))
4.0
>>> lin = sysid.linearize(m, 2.0)
>>> lin.nstates, bool(np.allclose(lin.freqresp([0.3]), m.freqresp([0.3])))
(1, True)
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._checks import as_int, user_stacklevel
from ..errors import DataError, NumericalError, StabilityWarning
from ..models.statespace import StateSpaceModel

__all__ = ["OperatingPoint", "findop", "linearize"]

#: the output counts as settled when it moved by less than this (relative to its size) over
#: the last quarter of the run
SETTLE_TOL = 1e-10
FIRST_RUN = 256
#: Hankel singular values below this fraction of the largest are the differences' error
RANK_TOL = 1e-7
#: block rows of the Hankel matrix (twice as many columns): orders up to that times outputs
MAX_ROWS = 60


@dataclass
class OperatingPoint:
    """A steady operating point of a model: input ``u0``, output ``y0``, and the samples
    from rest it took to settle (``samples``)."""

    u0: np.ndarray
    y0: np.ndarray
    samples: int

    def __repr__(self) -> str:
        return (f"OperatingPoint(u0={np.round(self.u0, 6).tolist()}, "
                f"y0={np.round(self.y0, 6).tolist()}, settled after {self.samples} samples)")


def _inputs(model: Any, u0: Any) -> np.ndarray:
    m = int(model.ninputs)
    u = np.zeros(m) if u0 is None else np.atleast_1d(np.asarray(u0, dtype=float)).ravel()
    if u.size == 1 and m > 1:
        u = np.repeat(u, m)
    if u.size != m or not np.all(np.isfinite(u)):
        raise DataError(f"u0 must be finite, one value per input ({m}), got {u0!r}")
    if m == 0:
        raise DataError("a time-series model has no input to hold: no operating point")
    return u


def _simulate(model: Any, u: np.ndarray) -> np.ndarray:
    y = np.asarray(model.simulate(u), dtype=float)
    return y.reshape(u.shape[0], -1)


def _continuous(model: Any) -> bool:
    """A continuous-time model (``dt == 0``): its simulation needs a sample time, and a linear
    one has its steady point in closed form."""
    dt = getattr(model, "dt", None)
    return dt is not None and float(dt) == 0.0


def _continuous_op(model: Any, u: np.ndarray) -> OperatingPoint:
    """The steady output of a continuous linear model, ``dcgain() u0``."""
    if not hasattr(model, "dcgain"):
        raise DataError(
            f"this continuous-time {type(model).__name__} has no closed-form steady state and "
            "its simulation needs a sample time: sample it first (for example "
            "model.sampled(dt) or sysid.c2d(model, dt)) and pass the sampled model")
    try:
        g = np.asarray(model.dcgain(), dtype=float).reshape(-1, u.size)
    except NumericalError as e:
        raise NumericalError(f"no steady operating point: {e}") from None
    if not np.all(np.isfinite(g)):
        raise NumericalError("no steady operating point: the model integrates its input (an "
                             "infinite DC gain), so its output does not settle")
    if hasattr(model, "is_stable") and not model.is_stable():
        raise NumericalError("no steady operating point: the model is unstable, so its output "
                             "does not settle with the input held")
    return OperatingPoint(u, g @ u, 0)


def _settled(y: np.ndarray) -> bool:
    tail = y[-max(2, y.shape[0] // 4):]
    size = max(1.0, float(np.max(np.abs(tail))))
    return bool(np.all(np.isfinite(tail))
                and np.max(np.ptp(tail, axis=0)) <= SETTLE_TOL * size)


def findop(model: Any, u0: Any = None, *, max_samples: int = 1_000_000) -> OperatingPoint:
    """The steady output of ``model`` with its input held at ``u0`` (from rest).

    Parameters
    ----------
    model : any sysid model with ``simulate(u)`` and ``ninputs``
        A continuous-time linear model's steady output is ``dcgain() u0`` (``samples`` 0).
    u0 : float or array_like, optional
        The held input, one value per input (or one for all); default zero.
    max_samples : int
        The longest run tried (runs double from 256 samples).

    Returns
    -------
    OperatingPoint

    Examples
    --------
    >>> import sysid
    >>> sysid.findop(sysid.StateSpaceModel([[0.8]], [[1.0]], [[2.0]]), 1.0).y0.round(8)
    array([10.])
    """
    u = _inputs(model, u0)
    if _continuous(model):
        return _continuous_op(model, u)
    n = FIRST_RUN
    while True:
        try:
            y = _simulate(model, np.tile(u, (n, 1)))
        except NumericalError:  # an overflow: the output runs away
            y = np.full((n, 1), np.inf)
        if _settled(y):
            return OperatingPoint(u, y[-1].copy(), n)
        if n >= max_samples or not np.all(np.isfinite(y)):
            moved = np.max(np.ptp(y[-n // 4:], axis=0)) if np.all(np.isfinite(y)) else np.inf
            raise NumericalError(
                f"the model's output does not settle with the input held at "
                f"{np.round(u, 6).tolist()} (still moving by {moved:.3g} over the last "
                f"quarter of {n} samples): no steady operating point there (a limit cycle or "
                "a divergence); try another u0")
        n = min(2 * n, int(max_samples))


def linearize(model: Any, u0: Any = None, *, order: int | None = None,
              step: float | None = None, max_samples: int = 1_000_000) -> StateSpaceModel:
    """The linear model of small deviations about a steady operating point.

    Parameters
    ----------
    model : any sysid model with ``simulate(u)`` and ``ninputs``
        Nonlinear models (NARX, Hammerstein-Wiener, PNLSS, neural state space, ...) and
        linear ones alike.
    u0 : float or array_like, optional
        The input of the operating point (default zero); its output is found by
        :func:`findop`.
    order : int, optional
        The order of the linear model; default the rank its Markov parameters show.
    step : float, optional
        Size of the input impulses (default ``1e-5 max(1, |u0|)`` per input).
    max_samples : int

    Returns
    -------
    StateSpaceModel
        Deviations ``u - u0`` to ``y - y0`` (``info["operating_point"]``; MATLAB's
        ``linearize``). A NARX model's own ``linearize()`` is its first-order terms about
        zero; this is the linearisation at the operating point. A continuous-time linear
        model (``ContinuousStateSpace``, ``TransferFunction``, ``ProcessModel``) is returned
        as itself (a copy), its operating point from its DC gain.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> hw = sysid.HammersteinWienerModel(sysid.UserFunction(lambda u: u + u**3),
    ...                                   sysid.Nonlinearity(), b=[1.0], f=[-0.5], nk=1,
    ...                                   dt=1.0)
    >>> lin = sysid.linearize(hw, 1.0)   # gain f'(1) = 4 times 1 / (1 - 0.5)
    >>> float(np.round(lin.dcgain()[0, 0], 6))
    8.0
    """
    if order is not None:
        order = as_int(order, "order", 0)
    max_samples = as_int(max_samples, "max_samples", FIRST_RUN)
    op = findop(model, u0, max_samples=max_samples)
    if _continuous(model):  # a linear model is its own linearisation (MATLAB's linearize)
        import copy

        lin = copy.deepcopy(model)
        lin.info = {**dict(getattr(model, "info", {}) or {}), "method": "linearize",
                    "operating_point": op}
        return lin
    u, m = op.u0, op.u0.size
    h = np.full(m, 1e-5) * np.maximum(1.0, np.abs(u)) if step is None else \
        np.full(m, float(step))
    if not np.all(h > 0) or not np.all(np.isfinite(h)):
        raise DataError(f"step must be positive and finite, got {step!r}")
    n = max(op.samples, FIRST_RUN)
    while True:  # a response long enough to have died out
        markov = _markov(model, u, h, op.samples, n)
        size = max(1e-300, float(np.max(np.abs(markov))))
        if np.max(np.abs(markov[-max(2, n // 4):])) <= 1e-9 * size or n >= max_samples:
            break
        n = min(2 * n, int(max_samples))
    from ..realization.realize import era

    markov = markov[: _useful(markov)]
    # Ho-Kalman is exact once the Hankel matrix spans the order: a bounded one suffices
    rows = min(MAX_ROWS, max(2, (markov.shape[0] - 1) // 2))
    cols = min(2 * MAX_ROWS, markov.shape[0] - 1 - rows)
    if order is None:  # the rank the differences show (their error is ~1e-10 relative)
        H = np.vstack([np.hstack(list(markov[1 + r:1 + r + cols])) for r in range(rows)])
        sv = np.linalg.svd(H, compute_uv=False)
        order = int(np.sum(sv > RANK_TOL * sv[0])) if sv.size and sv[0] > 0 else 0
    if order == 0:  # a static map: D alone
        return _static(model, markov[0], op)
    with warnings.catch_warnings():  # said below, in the linearisation's own terms
        warnings.simplefilter("ignore")
        lin = era(markov, int(order), rows=rows, cols=cols, dt=_dt(model), scale=False).model
    if not lin.is_stable():
        warnings.warn(f"the linearisation at {np.round(u, 6).tolist()} has a pole outside the "
                      f"unit circle although the model settles there: its order "
                      f"({lin.nstates}) is likely too high; pass order=",
                      StabilityWarning, stacklevel=user_stacklevel())
    return StateSpaceModel(lin.A, lin.B, lin.C, lin.D, dt=_dt(model),
                           input_names=getattr(model, "input_names", None),
                           output_names=getattr(model, "output_names", None),
                           info={"method": "linearize", "operating_point": op,
                                 "markov_samples": int(markov.shape[0])})


def _static(model: Any, d: np.ndarray, op: OperatingPoint) -> StateSpaceModel:
    l, m = d.shape
    return StateSpaceModel(np.zeros((0, 0)), np.zeros((0, m)), np.zeros((l, 0)), d,
                           dt=_dt(model), info={"method": "linearize", "operating_point": op,
                                                "markov_samples": 1})


def _dt(model: Any) -> float:
    dt = getattr(model, "dt", 1.0)
    return float(dt) if dt else 1.0


def _markov(model: Any, u: np.ndarray, h: np.ndarray, settle: int, n: int) -> np.ndarray:
    """``(n, l, m)`` central differences of the responses to impulses at sample ``settle``."""
    U = np.tile(u, (settle + n, 1))
    cols = []
    for j in range(u.size):
        up, dn = U.copy(), U.copy()
        up[settle, j] += h[j]
        dn[settle, j] -= h[j]
        try:
            d = (_simulate(model, up) - _simulate(model, dn))[settle:] / (2 * h[j])
        except NumericalError:  # the simulation overflowed: the impulse response runs away
            d = np.full((n, 1), np.inf)
        if not np.all(np.isfinite(d)):
            raise NumericalError(
                "the model's response to a small input impulse at the operating point grows "
                "without bound: the operating point is not a stable one (an unstable model "
                "rests there only from rest), so it is not linearisable by its response; a "
                "linear model is its own linearisation (model.to_statespace())")
        cols.append(d)
    return np.stack(cols, axis=2)


def _useful(markov: np.ndarray) -> int:
    """Samples up to where the response has decayed to round-off (a shorter Hankel matrix
    without the tail of noise)."""
    mag = np.max(np.abs(markov), axis=(1, 2))
    above = np.nonzero(mag > 1e-9 * max(1e-300, mag.max()))[0]
    return int(min(markov.shape[0], max(8, 2 * (above[-1] + 1) if above.size else 8)))
