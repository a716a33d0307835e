"""Taking records apart and putting them together: experiments, sample and time slices,
channel selection, estimation/validation splits and merging.

These are methods of :class:`~sysid.IOData` (``data.slice(...)``, ``data[100:500]``,
``data.select(...)``, ``data.split(0.7)``, ``data.merge(other)``): plain functions of the
record, bound as methods in :mod:`sysid.data.iodata` (this module never imports that one), with
the per-experiment arrays :class:`_Exp` they work on.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, NamedTuple

import numpy as np

from ..errors import DataError, InsufficientDataError

__all__ = ["SplitData"]


@dataclass(frozen=True)
class _Exp:
    """One experiment: arrays and, when a trend was removed, the trend values per sample."""

    u: np.ndarray
    y: np.ndarray
    t0: float = 0.0
    tu: np.ndarray | None = None
    ty: np.ndarray | None = None

    def rows(self, sl: slice | np.ndarray, dt: float) -> _Exp:
        idx = np.arange(self.y.shape[0])[sl]
        start = int(idx[0]) if idx.size else 0
        return _Exp(
            self.u[sl], self.y[sl], self.t0 + start * dt,
            None if self.tu is None else self.tu[sl],
            None if self.ty is None else self.ty[sl],
        )

    def cols(self, iu: list[int], iy: list[int]) -> _Exp:
        return _Exp(
            self.u[:, iu], self.y[:, iy], self.t0,
            None if self.tu is None else self.tu[:, iu],
            None if self.ty is None else self.ty[:, iy],
        )


class SplitData(NamedTuple):
    """An estimation part and a validation part of a record."""

    estimation: Any  # IOData
    validation: Any  # IOData


def experiment(data: Any, k: int | Sequence[int]) -> Any:
    """The record of one experiment (or a list of them).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData([np.ones(5), np.ones(7)], [np.ones(5), np.ones(7)])
    >>> d.experiment(1).n_samples
    7
    """
    ks = list(k) if isinstance(k, (list, tuple, range, np.ndarray)) else [k]
    for j in ks:
        if not isinstance(j, (int, np.integer)) or isinstance(j, (bool, np.bool_)):
            raise DataError(f"experiments are indexed by their position, an integer from 0 to "
                            f"{data.n_experiments - 1} (or a list of them), got {j!r}")
        if not -data.n_experiments <= j < data.n_experiments:
            raise DataError(f"experiment {j} does not exist (record has {data.n_experiments})")
    return data._derive([data._exps[j] for j in ks])


def slice_samples(data: Any, start: int | None = None, stop: int | None = None,
                  step: int = 1) -> Any:
    """Samples ``start:stop:step`` of every experiment (Python slice semantics).

    ``step > 1`` keeps every ``step``-th sample without filtering (use
    :func:`sysid.decimate` to filter first); ``dt`` is multiplied by ``step``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.arange(10.0), y=np.arange(10.0), dt=0.5)
    >>> d.slice(2, 6).y.ravel()
    array([2., 3., 4., 5.])
    >>> d.slice(2, 6).time
    array([1. , 1.5, 2. , 2.5])
    """
    if not isinstance(step, (int, np.integer)) or step < 1:
        raise DataError(f"step must be a positive integer, got {step!r}")
    sl = slice(start, stop, step)
    return data._derive([e.rows(sl, data.dt) for e in data._exps], dt=data.dt * step)


def time_slice(data: Any, start: float | None = None, stop: float | None = None) -> Any:
    """Samples with ``start <= t < stop`` (seconds); experiments outside are dropped.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.arange(10.0), y=np.arange(10.0), dt=0.5)
    >>> d.time_slice(1.0, 2.0).time
    array([1. , 1.5])
    """
    lo = -np.inf if start is None else float(start)
    hi = np.inf if stop is None else float(stop)
    if not lo < hi:
        raise DataError(f"time_slice needs start < stop, got {start} and {stop}")
    out = []
    for e, t in zip(data._exps, data.times):
        keep = np.flatnonzero((t >= lo - 1e-9 * data.dt) & (t < hi - 1e-9 * data.dt))
        if keep.size:
            out.append(e.rows(slice(int(keep[0]), int(keep[-1]) + 1), data.dt))
    if not out:
        raise InsufficientDataError(
            f"no samples between t = {lo:g} s and {hi:g} s; the record spans "
            f"{min(t[0] for t in data.times):g} to {max(t[-1] for t in data.times):g} s"
        )
    return data._derive(out)


def getitem(data: Any, key: Any) -> Any:
    """``data[a:b]`` slices samples; ``data["y1"]`` or ``data[["u0", "y1"]]`` selects
    channels by name (a kind not named, inputs or outputs, is kept whole)."""
    if isinstance(key, slice):
        return slice_samples(data, key.start, key.stop, 1 if key.step is None else key.step)
    if isinstance(key, str):
        key = [key]
    if isinstance(key, (list, tuple)) and all(isinstance(k, str) for k in key):
        ins = [k for k in key if k in data.input_names]
        outs = [k for k in key if k in data.output_names]
        unknown = [k for k in key if k not in data.input_names and k not in data.output_names]
        if unknown:
            raise DataError(unknown_names(data, unknown))
        # a kind not named is kept whole: data["y1"] keeps every input
        return data.select(inputs=ins or None, outputs=outs or None)
    raise DataError(
        "index IOData with a slice of samples (data[100:500]) or channel names "
        "(data['y0'], data[['u0', 'y1']]); use .experiment(k) for experiments"
    )


def unknown_names(data: Any, names: list[str]) -> str:
    """The message for channel names that are neither inputs nor outputs of ``data``."""
    return (
        f"unknown channel name(s) {names}; inputs are {data.input_names}, "
        f"outputs are {data.output_names}"
    )


def channel_index(sel: Any, names: list[str], kind: str) -> list[int]:
    """Indices of the channels ``sel`` among ``names``: an index, a name, a slice, or a list,
    tuple, range or integer array of indices and names; ``None`` for all. The one rule of
    records (:meth:`sysid.IOData.select`), FRDs and models (``model[i, j]``): anything else
    (a float such as ``0.0``, even a whole one, which MATLAB's ``y(:, 1.0)`` would take; a
    boolean or boolean mask, which would read as the indices 0 and 1) is refused with what
    to pass instead.

    Examples
    --------
    >>> from sysid.data.segments import channel_index
    >>> channel_index([1, "y0"], ["y0", "y1"], "output")
    [1, 0]
    >>> channel_index(0.0, ["y0", "y1"], "output")
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: output 0.0 is not a channel: ... use 0
    """
    if sel is None:
        return list(range(len(names)))
    if isinstance(sel, slice):
        sel = range(len(names))[sel]
    items = sel.tolist() if isinstance(sel, np.ndarray) else sel
    if isinstance(items, (str, int, np.integer, float, np.floating)) or np.ndim(items) == 0:
        items = [items]
    elif not isinstance(items, (list, tuple, range)):
        raise DataError(f"the {kind} selection {sel!r} is not an index, a name or a list of "
                        f"them: select {kind}s by integer index, name, slice or a list of "
                        "those")
    out = []
    for s in items:
        if isinstance(s, (bool, np.bool_)):
            raise DataError(
                f"{kind} {s!r} is not a channel: a boolean reads as the index "
                f"{int(s)}; select {kind}s by integer index or name (a boolean mask: pass "
                "np.flatnonzero(mask))")
        if isinstance(s, str):
            if s not in names:
                raise DataError(f"no {kind} named {s!r}; the {kind}s are {names}")
            out.append(names.index(s))
        elif isinstance(s, (int, np.integer)):
            if not -len(names) <= s < len(names):
                raise DataError(f"{kind} {s!r} does not exist; the {kind}s are {names}")
            out.append(int(s) % len(names))
        else:
            whole = isinstance(s, (float, np.floating)) and float(s).is_integer()
            raise DataError(
                f"{kind} {s!r} is not a channel: select {kind}s by integer index, name, "
                "slice or a list of those" + (f"; use {int(s)}" if whole else ""))
    if len(set(out)) != len(out):
        raise DataError(f"{kind} selection {list(items)} repeats a channel")
    return out


def select(data: Any, inputs: Any = None, outputs: Any = None) -> Any:
    """A record with the chosen channels (by name, index, slice or a list of them; ``None``
    keeps all; :func:`channel_index`'s rule).

    ``inputs=[]`` drops every input (a time series).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.ones((4, 2)), y=np.ones((4, 3)), input_names=["a", "b"])
    >>> d.select(inputs="b", outputs=["y2", "y0"]).output_names
    ['y2', 'y0']
    """
    iu = channel_index(inputs, data.input_names, "input")
    iy = channel_index(outputs, data.output_names, "output")
    if not iy:
        raise DataError("select at least one output")
    return data._derive([e.cols(iu, iy) for e in data._exps], iu=iu, iy=iy)


def split(data: Any, fraction: float = 0.5, *, at: int | None = None) -> SplitData:
    """Split into an estimation and a validation part.

    Parameters
    ----------
    fraction : float
        Share of every experiment (its first part) used for estimation.
    at : int, optional
        Split a single-experiment record at this sample instead.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.ones(100), y=np.ones(100))
    >>> est, val = d.split(0.7)
    >>> est.n_samples, val.n_samples
    (70, 30)
    """
    if at is not None:
        if data.n_experiments != 1:
            raise DataError("split(at=...) needs a single experiment; use fraction instead")
        n = data.n_samples
        if not isinstance(at, (int, np.integer)) or not 0 < at < n:
            raise DataError(f"at must be an integer sample index in 1..{n - 1}, got {at!r}")
        cuts = [int(at)]
    else:
        if not 0.0 < float(fraction) < 1.0:
            raise DataError(f"fraction must lie strictly between 0 and 1, got {fraction}")
        cuts = [int(round(fraction * len(e.y))) for e in data._exps]
        for k, (c, e) in enumerate(zip(cuts, data._exps)):
            if not 0 < c < len(e.y):
                raise InsufficientDataError(
                    f"experiment {k} has {len(e.y)} samples: too few to split at "
                    f"{fraction:.0%}; drop it or use .experiment() to split by experiment"
                )
    est = [e.rows(slice(0, c), data.dt) for e, c in zip(data._exps, cuts)]
    val = [e.rows(slice(c, None), data.dt) for e, c in zip(data._exps, cuts)]
    return SplitData(data._derive(est), data._derive(val))


def merge(data: Any, *others: Any) -> Any:
    """One record holding the experiments of ``data`` and ``others`` (same channels, dt).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> a = sysid.IOData(u=np.ones(5), y=np.ones(5))
    >>> a.merge(a, a)
    IOData: 15 samples in 3 experiments, 1 input, 1 output, dt = 1 s
    """
    if not hasattr(data, "_exps"):
        raise DataError(
            f"merge is called on a record, got {type(data).__name__}: first.merge(second, "
            "third, ...); for a list of records, records[0].merge(*records[1:])")
    exps = list(data._exps)
    for k, o in enumerate(others):
        if not isinstance(o, type(data)):
            raise DataError(f"merge takes IOData records, got {type(o).__name__}")
        for attr in ("input_names", "output_names"):
            if getattr(o, attr) != getattr(data, attr):
                raise DataError(
                    f"record {k + 1} has {attr} {getattr(o, attr)} but the first has "
                    f"{getattr(data, attr)}; rename or select channels so they agree"
                )
        for attr in ("input_units", "output_units"):
            if getattr(o, attr) != getattr(data, attr):
                raise DataError(
                    f"record {k + 1} has {attr} {getattr(o, attr)} but the first has "
                    f"{getattr(data, attr)}; convert them to the same units first"
                )
        if abs(o.dt - data.dt) > 1e-9 * data.dt:
            raise DataError(
                f"record {k + 1} has dt = {o.dt:.10g} s but the first has {data.dt:.10g} s; "
                "resample first (sysid.resample)"
            )
        if not (
            np.array_equal(o._u_scale, data._u_scale)
            and np.array_equal(o._y_scale, data._y_scale)
        ):
            raise DataError("records scaled differently cannot be merged; scale after merging")
        mine, theirs = data.has_trend, o.has_trend
        for e in o._exps:
            exps.append(e)
        if mine != theirs:
            exps = [_with_zero_trend(e) for e in exps]
    return data._derive(exps)



def long_enough(data: Any, window: int) -> Any:
    """The experiments of ``data`` of at least ``window`` samples (``data`` itself when all
    are; None when none is): the part a subspace fit of that window can use."""
    exps = [e for e in data.experiments if e[0].shape[0] >= window]
    if len(exps) == len(data.experiments):
        return data
    if not exps:
        return None
    kw: dict[str, Any] = {"dt": data.dt, "input_names": data.input_names,
                          "output_names": data.output_names}
    if len(exps) == 1:
        return type(data)(u=exps[0][0], y=exps[0][1], **kw)
    return type(data)(u=[e[0] for e in exps], y=[e[1] for e in exps], **kw)

def _with_zero_trend(e: _Exp) -> _Exp:
    return replace(
        e,
        tu=np.zeros_like(e.u) if e.tu is None else e.tu,
        ty=np.zeros_like(e.y) if e.ty is None else e.ty,
    )
