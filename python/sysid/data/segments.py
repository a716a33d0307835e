"""Taking records apart and putting them together: experiments, sample and time slices,
channel selection, estimation/validation splits and merging.

These are methods of :class:`~sysid.IOData` (``data.slice(...)``, ``data[100:500]``,
``data.select(...)``, ``data.split(0.7)``, ``data.merge(other)``); they live here, in a base
class of :class:`~sysid.IOData`, so that the container module stays short.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from ..errors import DataError, InsufficientDataError

if TYPE_CHECKING:
    from .iodata import IOData, _Exp

__all__ = ["SplitData"]


class SplitData(NamedTuple):
    """An estimation part and a validation part of a record."""

    estimation: IOData
    validation: IOData


class _Segments:
    """Selection, splitting and merging of :class:`~sysid.IOData` (a base class of it)."""

    _exps: list[_Exp]
    dt: float
    input_names: list[str]
    output_names: list[str]
    input_units: list[str]
    output_units: list[str]
    _u_scale: np.ndarray
    _y_scale: np.ndarray

    # ---------------------------------------------------------------- selection

    def experiment(self, k: int | Sequence[int]) -> IOData:
        """The record of one experiment (or a list of them).

        Examples
        --------
        >>> import numpy as np, sysid
        >>> d = sysid.IOData([np.ones(5), np.ones(7)], [np.ones(5), np.ones(7)])
        >>> d.experiment(1).n_samples
        7
        """
        ks = [k] if isinstance(k, (int, np.integer)) else list(k)
        for j in ks:
            if not -self.n_experiments <= j < self.n_experiments:
                raise DataError(f"experiment {j} does not exist (record has {self.n_experiments})")
        return self._derive([self._exps[j] for j in ks])

    def slice(self, start: int | None = None, stop: int | None = None, step: int = 1) -> IOData:
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
        return self._derive([e.rows(sl, self.dt) for e in self._exps], dt=self.dt * step)

    def time_slice(self, start: float | None = None, stop: float | None = None) -> IOData:
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
        for e, t in zip(self._exps, self.times):
            keep = np.flatnonzero((t >= lo - 1e-9 * self.dt) & (t < hi - 1e-9 * self.dt))
            if keep.size:
                out.append(e.rows(slice(int(keep[0]), int(keep[-1]) + 1), self.dt))
        if not out:
            raise InsufficientDataError(
                f"no samples between t = {lo:g} s and {hi:g} s; the record spans "
                f"{min(t[0] for t in self.times):g} to {max(t[-1] for t in self.times):g} s"
            )
        return self._derive(out)

    def __getitem__(self, key: Any) -> IOData:
        """``data[a:b]`` slices samples; ``data["y1"]`` or ``data[["u0", "y1"]]`` selects
        channels by name (a kind not named, inputs or outputs, is kept whole)."""
        if isinstance(key, slice):
            return self.slice(key.start, key.stop, 1 if key.step is None else key.step)
        if isinstance(key, str):
            key = [key]
        if isinstance(key, (list, tuple)) and all(isinstance(k, str) for k in key):
            ins = [k for k in key if k in self.input_names]
            outs = [k for k in key if k in self.output_names]
            unknown = [k for k in key if k not in self.input_names and k not in self.output_names]
            if unknown:
                raise DataError(self._unknown_names(unknown))
            # a kind not named is kept whole: data["y1"] keeps every input
            return self.select(inputs=ins or None, outputs=outs or None)
        raise DataError(
            "index IOData with a slice of samples (data[100:500]) or channel names "
            "(data['y0'], data[['u0', 'y1']]); use .experiment(k) for experiments"
        )

    def _unknown_names(self, names: list[str]) -> str:
        return (
            f"unknown channel name(s) {names}; inputs are {self.input_names}, "
            f"outputs are {self.output_names}"
        )

    def _index(self, sel: Any, names: list[str], kind: str) -> list[int]:
        if sel is None:
            return list(range(len(names)))
        if isinstance(sel, (str, int, np.integer)):
            sel = [sel]
        out = []
        for s in sel:
            if isinstance(s, str):
                if s not in names:
                    raise DataError(f"no {kind} named {s!r}; the {kind}s are {names}")
                out.append(names.index(s))
            elif isinstance(s, (int, np.integer)) and -len(names) <= s < len(names):
                out.append(int(s) % len(names))
            else:
                raise DataError(f"{kind} {s!r} does not exist; the {kind}s are {names}")
        if len(set(out)) != len(out):
            raise DataError(f"{kind} selection {list(sel)} repeats a channel")
        return out

    def select(self, inputs: Any = None, outputs: Any = None) -> IOData:
        """A record with the chosen channels (by name or index; ``None`` keeps all).

        ``inputs=[]`` drops every input (a time series).

        Examples
        --------
        >>> import numpy as np, sysid
        >>> d = sysid.IOData(u=np.ones((4, 2)), y=np.ones((4, 3)), input_names=["a", "b"])
        >>> d.select(inputs="b", outputs=["y2", "y0"]).output_names
        ['y2', 'y0']
        """
        iu = self._index(inputs, self.input_names, "input")
        iy = self._index(outputs, self.output_names, "output")
        if not iy:
            raise DataError("select at least one output")
        return self._derive([e.cols(iu, iy) for e in self._exps], iu=iu, iy=iy)

    def split(self, fraction: float = 0.5, *, at: int | None = None) -> SplitData:
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
            if self.n_experiments != 1:
                raise DataError("split(at=...) needs a single experiment; use fraction instead")
            n = self.n_samples
            if not isinstance(at, (int, np.integer)) or not 0 < at < n:
                raise DataError(f"at must be an integer sample index in 1..{n - 1}, got {at!r}")
            cuts = [int(at)]
        else:
            if not 0.0 < float(fraction) < 1.0:
                raise DataError(f"fraction must lie strictly between 0 and 1, got {fraction}")
            cuts = [int(round(fraction * len(e.y))) for e in self._exps]
            for k, (c, e) in enumerate(zip(cuts, self._exps)):
                if not 0 < c < len(e.y):
                    raise InsufficientDataError(
                        f"experiment {k} has {len(e.y)} samples: too few to split at "
                        f"{fraction:.0%}; drop it or use .experiment() to split by experiment"
                    )
        est = [e.rows(slice(0, c), self.dt) for e, c in zip(self._exps, cuts)]
        val = [e.rows(slice(c, None), self.dt) for e, c in zip(self._exps, cuts)]
        return SplitData(self._derive(est), self._derive(val))

    def merge(self, *others: IOData) -> IOData:
        """One record holding the experiments of ``self`` and ``others`` (same channels, dt).

        Examples
        --------
        >>> import numpy as np, sysid
        >>> a = sysid.IOData(u=np.ones(5), y=np.ones(5))
        >>> a.merge(a, a)
        IOData: 15 samples in 3 experiments, 1 input, 1 output, dt = 1 s
        """
        exps = list(self._exps)
        for k, o in enumerate(others):
            if not isinstance(o, _Segments):
                raise DataError(f"merge takes IOData records, got {type(o).__name__}")
            for attr in ("input_names", "output_names"):
                if getattr(o, attr) != getattr(self, attr):
                    raise DataError(
                        f"record {k + 1} has {attr} {getattr(o, attr)} but the first has "
                        f"{getattr(self, attr)}; rename or select channels so they agree"
                    )
            for attr in ("input_units", "output_units"):
                if getattr(o, attr) != getattr(self, attr):
                    raise DataError(
                        f"record {k + 1} has {attr} {getattr(o, attr)} but the first has "
                        f"{getattr(self, attr)}; convert them to the same units first"
                    )
            if abs(o.dt - self.dt) > 1e-9 * self.dt:
                raise DataError(
                    f"record {k + 1} has dt = {o.dt:g} s but the first has {self.dt:g} s; "
                    "resample first (sysid.resample)"
                )
            if not (
                np.array_equal(o._u_scale, self._u_scale)
                and np.array_equal(o._y_scale, self._y_scale)
            ):
                raise DataError("records scaled differently cannot be merged; scale after merging")
            mine, theirs = self.has_trend, o.has_trend
            for e in o._exps:
                exps.append(e)
            if mine != theirs:
                exps = [self._with_zero_trend(e) for e in exps]
        return self._derive(exps)

    @staticmethod
    def _with_zero_trend(e: _Exp) -> _Exp:
        return replace(
            e,
            tu=np.zeros_like(e.u) if e.tu is None else e.tu,
            ty=np.zeros_like(e.y) if e.ty is None else e.ty,
        )
