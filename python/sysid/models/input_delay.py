"""Known input delays of discrete state-space models (MATLAB's ``InputDelay`` option of
``ssest``/``n4sid`` and ``absorbDelay``).

An estimator given ``input_delay`` fits the delay-free model to the record with each input
``j`` shifted by its delay ``k_j`` samples (``u_j(t - k_j)``; the first ``max k`` samples of
each experiment are dropped, as their shifted inputs are not recorded), then returns the model
of the raw record with the delays absorbed as states: each delayed input passes through a
chain of ``k_j`` unit delays (``k_j`` states, poles at zero) before the delay-free model. The
delay-free fit is ``info["delay_free"]``, the delays ``info["input_delay"]``; predictions,
simulations, ``compare`` and the parameter uncertainty (the delay-free model's parameters,
through the same map) apply to the absorbed model unchanged.

``input_delay="auto"`` takes the delays from :func:`sysid.delayest` (ARX models over delays 0
to 10): per input, the smallest delay to any output, less the one sample a model without
feedthrough already has.

Examples
--------
>>> import numpy as np, sysid
>>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
>>> d = absorb_delay(m, [2])
>>> d.nstates, np.round(d.impulse(5).y[:, 0, 0], 3).tolist()
(3, [0.0, 0.0, 0.0, 1.0, 0.5])
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .._checks import as_int, user_stacklevel
from ..data.iodata import IOData
from ..errors import DataError
from .statespace import StateSpaceModel

__all__ = ["absorb_delay", "delay_free_view", "delayed_fit", "input_delays", "nkshift",
           "shift_inputs"]


def input_delays(data: IOData, input_delay: Any, feedthrough: Any = None) -> np.ndarray:
    """The delay of every input in samples (``input_delay``: one number for all, one per
    input, or ``"auto"``), checked against the record before anything is fitted."""
    m = data.n_inputs
    if isinstance(input_delay, str):
        if input_delay != "auto":
            raise DataError(f"input_delay must be samples (one per input, or one for all) or "
                            f"'auto', got {input_delay!r}")
        from ..polynomial.delayest import DelayWarning, delays

        out, weak, _, _ = delays(data)
        # each input's smallest delay over the outputs it acts on: a pair whose delay the
        # data do not determine (its input explains nothing, or does not excite its lags
        # independently) is left out
        known = np.ones(out.shape, dtype=bool)
        for i, j, _ in weak:
            known[i, j] = False
        nk = np.where(known, out, np.iinfo(np.int64).max).min(axis=0)
        blind = ~known.any(axis=0)
        nk[blind] = 0
        if blind.any():
            warnings.warn(
                "input_delay='auto': the data do not determine the delay of "
                + ", ".join(data.input_names[j] for j in np.flatnonzero(blind))
                + " on any output (no delay in the range searched makes it explain one, or "
                "it does not excite its lags independently; sysid.delayest says which "
                "pairs): no delay is given to it; pass input_delay= if it has one",
                DelayWarning, stacklevel=user_stacklevel())
        return np.maximum(nk - (0 if feedthrough is True else 1), 0).astype(int)
    k = np.atleast_1d(np.asarray(input_delay))
    if k.ndim != 1 or k.size not in (1, m):
        raise DataError(f"input_delay must be one number or one per input ({m}), got "
                        f"{input_delay!r}")
    k = np.array([as_int(v, "input_delay", 0) for v in k], dtype=int)
    k = np.repeat(k, m) if k.size == 1 else k
    shortest = min(data.lengths)
    if k.max(initial=0) >= shortest // 2:
        raise DataError(f"input_delay {k.max()} samples leaves too little of the shortest "
                        f"experiment ({shortest} samples): check the delay's units (samples, "
                        "not seconds)")
    return k


def delayed_fit(data: IOData, input_delay: Any, feedthrough: Any,
                fit: Callable[[IOData], StateSpaceModel]) -> StateSpaceModel:
    """``fit`` of the record with its inputs shifted by their delays (:func:`input_delays`),
    returned with the delays absorbed: what every estimator's ``input_delay=`` does."""
    k = input_delays(data, input_delay, feedthrough)
    return absorb_delay(fit(shift_inputs(data, k)), k)


def shift_inputs(data: IOData, delays: np.ndarray, hold: bool = False,
                 before: Sequence[np.ndarray] | None = None) -> IOData:
    """Each input ``j`` delayed by ``delays[j]`` samples (advanced when negative), the
    samples whose shifted inputs were not recorded dropped from every experiment; with
    ``hold`` (delays ``>= 0``), every sample kept, the inputs before each experiment taken
    from ``before`` (per experiment, the rows recorded before it, latest last), and held at
    the earliest value known before that (what a delay line holding those values feeds).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.arange(1.0, 7.0), y=np.zeros(6))
    >>> shift_inputs(d, [2]).u.ravel().tolist()
    [1.0, 2.0, 3.0, 4.0]
    >>> shift_inputs(d, [2], hold=True).u.ravel().tolist()
    [1.0, 1.0, 1.0, 2.0, 3.0, 4.0]
    >>> shift_inputs(d, [3], hold=True, before=[np.array([[-2.0], [-1.0]])]).u.ravel().tolist()
    [-2.0, -2.0, -1.0, 1.0, 2.0, 3.0]
    """
    delays = np.asarray(delays, dtype=int)
    if hold and np.any(delays < 0):
        raise DataError(f"holding the first input needs delays >= 0, got {delays.tolist()}")
    top = 0 if hold else max(0, int(np.max(delays, initial=0)))
    bottom = max(0, -int(np.min(delays, initial=0)))
    us, ys = [], []
    for i, (u, y) in enumerate(data.experiments):
        n = u.shape[0]
        if hold:
            past = u[:0] if before is None else np.asarray(before[i]).reshape(-1, u.shape[1])
            known = np.vstack([past, u])  # the inputs known, from the earliest, held before
            line = np.vstack([np.repeat(known[:1], int(np.max(delays, initial=0)), 0), known])
            s = len(line) - n  # where the experiment starts on the line
            us.append(np.column_stack([line[s - k:s - k + n, j] for j, k in enumerate(delays)])
                      if u.shape[1] else u)
            ys.append(y)
            continue
        us.append(np.column_stack([u[top - k:n - bottom - k, j] for j, k in enumerate(delays)])
                  if u.shape[1] else u[top:n - bottom])
        ys.append(y[top:n - bottom])
    return IOData(u=us if len(us) > 1 else us[0], y=ys if len(ys) > 1 else ys[0], dt=data.dt,
                  input_names=data.input_names, output_names=data.output_names)


def absorb_delay(model: StateSpaceModel, delays: Any) -> StateSpaceModel:
    """The model of the raw inputs: ``delays[j]`` unit-delay states ahead of input ``j``
    (module docstring); ``K``, the noise covariance and the uncertainty carried."""
    k = np.asarray(delays, dtype=int).ravel()
    n, m, l = model.nstates, model.ninputs, model.noutputs
    if k.size != m:
        raise DataError(f"need one delay per input ({m}), got {k.size}")
    if np.any(k < 0):
        raise DataError(f"input delays are samples >= 0, got {k.tolist()}: an input that "
                        "leads the output is a model with feed-through, not a delay")
    nd = int(k.sum())
    A = np.zeros((n + nd, n + nd))
    B = np.zeros((n + nd, m))
    A[:n, :n] = model.A
    C = np.hstack([model.C, np.zeros((l, nd))])
    D = model.D.copy()
    o = n
    for j in range(m):
        if k[j] == 0:
            B[:n, j] = model.B[:, j]
            continue
        # u_j enters the chain's first state; its last feeds the model (and no direct term)
        B[o, j] = 1.0
        for s in range(k[j] - 1):
            A[o + s + 1, o + s] = 1.0
        A[:n, o + k[j] - 1] = model.B[:, j]
        C[:, o + k[j] - 1] += model.D[:, j]
        D[:, j] = 0.0
        o += k[j]
    K = None if model.K is None else np.vstack([model.K, np.zeros((nd, l))])
    # initial states of the delay-free fit (the shifted record's start, fewer states) are
    # not this model's: they stay with ``info["delay_free"]``
    info = {key: v for key, v in model.info.items() if key != "x0_experiments"}
    out = StateSpaceModel(A, B, C, D, K=K, dt=model.dt, noise_cov=model.noise_cov,
                          input_names=model.input_names, output_names=model.output_names,
                          info={**info, "input_delay": k.tolist(), "delay_free": model})
    unc = getattr(model, "uncertainty", None)
    if unc is not None:  # the delay-free model's parameters, through the same map
        out.uncertainty = unc.through(lambda m: absorb_delay(m, k))
    return out


def delay_free_view(model: Any, data: IOData, before: Sequence[np.ndarray] | None = None
                    ) -> tuple[Any, IOData]:
    """``(model, data)`` as the delay-free model sees them: for a model with absorbed input
    delays (``info["input_delay"]``) its ``info["delay_free"]`` and the record with each input
    delayed (:func:`shift_inputs` with ``hold``): before each experiment, the inputs recorded
    before it when ``before`` gives them (per experiment, latest last), else its first value
    held; any other model and the record unchanged. The delay-free model simulates that
    record as the absorbed one does from a delay line holding those inputs, at the cost of
    its own order, not of the delay line's states.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = absorb_delay(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), [3])
    >>> free, d = delay_free_view(m, sysid.IOData(u=np.arange(1.0, 7.0), y=np.ones(6)))
    >>> free.nstates, d.u.ravel().tolist()
    (1, [1.0, 1.0, 1.0, 1.0, 2.0, 3.0])
    """
    k = (getattr(model, "info", None) or {}).get("input_delay")
    if k is None:
        return model, data
    return model.info["delay_free"], shift_inputs(data, np.asarray(k, dtype=int), hold=True,
                                                  before=before)


def nkshift(data: Any, nk: Any) -> IOData:
    """The record with each input shifted by ``nk`` samples (MATLAB's ``nkshift``): positive
    values delay an input (``u_j(t - nk_j)``), negative ones advance it; the samples whose
    shifted inputs were not recorded are dropped from every experiment.

    Parameters
    ----------
    data : IOData or (u, y)
    nk : int or sequence of int
        One shift for all inputs, or one per input.

    Returns
    -------
    IOData

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.nkshift(sysid.IOData(u=np.arange(5.0), y=np.arange(5.0)), 2)
    >>> d.u.ravel().tolist(), d.y.ravel().tolist()
    ([0.0, 1.0, 2.0], [2.0, 3.0, 4.0])
    """
    from ..data.iodata import as_record

    data = as_record(data)
    m = data.n_inputs
    k = np.atleast_1d(np.asarray(nk))
    if k.ndim != 1 or k.size not in (1, m) or not np.all(np.isfinite(k.astype(float))) \
            or np.any(k != np.round(k)):
        raise DataError(f"nk must be whole samples, one for all inputs or one per input ({m}), "
                        f"got {nk!r}")
    k = np.repeat(k.astype(int), m) if k.size == 1 else k.astype(int)
    span = max(0, int(k.max(initial=0))) + max(0, -int(k.min(initial=0)))
    if span > min(data.lengths) - 2:
        raise DataError(f"shifts dropping {span} samples leave too little of the shortest "
                        f"experiment ({min(data.lengths)} samples)")
    return shift_inputs(data, k)
