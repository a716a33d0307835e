"""Input/output records: :class:`IOData`, the one data type every estimator accepts.

A record holds inputs ``u`` and outputs ``y`` sampled together at a uniform sample time
``dt``, time-first ``(samples, channels)``, possibly as several experiments (segments) that
estimators treat as separate (no Hankel column or correlation lag spans two of them). Channels
carry names and units; each experiment its start time. Pre-processing that removes a trend or
scales channels records what it did (:attr:`IOData.trend`) so that model outputs can be mapped
back to engineering units.

The container is here; its methods come from base classes kept by topic: selection,
splitting and merging in :mod:`sysid.data.segments`, raw records (drop-outs, irregular
sampling) in :mod:`sysid.data.raw`, readers and writers for pandas, CSV, NPZ and MATLAB files
in :mod:`sysid.data.formats`; units and the sample time in :mod:`sysid.data.units`, the
removed trend in :mod:`sysid.data.trend`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._checks import as_2d, as_dt
from .._display import HTMLResult
from ..errors import (
    DataError,
    InsufficientDataError,
    ShapeError,
    refuse_frd,
    several_records_hint,
)
from . import formats as _formats
from . import raw as _raw
from . import segments as _segments
from .formats import _pandas
from .layout import time_first
from .segments import SplitData, _Exp
from .trend import Trend
from .units import check_unit, sample_time

__all__ = ["IOData", "Trend", "SplitData", "DataSummary", "sample_time", "check_unit"]


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------


def _is_array(v: Any) -> bool:
    """An array of one dimension or more: a NumPy scalar (``np.float64(1.0)``, shape ``()``)
    is a number, so ``list(np.arange(5.0))`` is one signal, not five experiments."""
    return hasattr(v, "shape") and hasattr(v, "dtype") and len(v.shape) >= 1


def _as_list(x: Any, name: str = "data") -> list[Any] | None:
    """Experiments of an argument: a list of arrays is several; anything else is one.

    A (nested) list of numbers is one experiment, as NumPy would read it; only a list whose
    items are arrays means one array per experiment. A list mixing both is refused.
    """
    if x is None:
        return None
    if isinstance(x, (list, tuple)):
        if not x:
            return []
        arrays = [_is_array(v) for v in x]
        if all(arrays):
            return list(x)
        if any(arrays):
            raise DataError(
                f"{name} is a list mixing arrays and other values; a list of numbers (or of "
                "rows of numbers) is one experiment, a list of numpy arrays is one experiment "
                "per array"
            )
        return [x]
    return [x]


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" + ("" if n == 1 else "s")


# --------------------------------------------------------------------------------------------
# IOData
# --------------------------------------------------------------------------------------------


class IOData:
    """Measured inputs and outputs, time-first, possibly several experiments.

    Parameters
    ----------
    u : array_like or list of array_like or None
        Inputs shaped ``(n_samples, n_inputs)`` (1-D means one input). A list gives one
        array per experiment. ``None`` for output-only (time-series) data.
    y : array_like or list of array_like
        Outputs shaped ``(n_samples, n_outputs)``, one per experiment if a list.
    dt : float, optional
        Sample time in seconds. Default: from ``time`` if given, else 1.
    input_names, output_names : sequence of str, optional
        Channel names (unique); default ``u0, u1, ...`` and ``y0, y1, ...``.
    input_units, output_units : sequence of str, optional
        Channel units such as ``"deg"``, ``"m/s^2"`` (checked by :func:`check_unit`).
    time : array_like or list of array_like, optional
        Sample instants of each experiment; must be uniform (see :func:`sample_time`) and
        agree with ``dt`` if both are given. Only the start time of each experiment is kept.

    Notes
    -----
    Values must be finite: raw records with NaN drop-outs go through :meth:`from_raw`,
    irregularly sampled ones through :meth:`from_irregular`.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.zeros((100, 1)), y=np.ones((100, 2)), dt=0.1)
    >>> d
    IOData: 100 samples, 1 input, 2 outputs, dt = 0.1 s
    >>> d.experiments[0][1].shape
    (100, 2)
    """

    # Readers, writers, selection and splitting are plain functions of the data (their
    # modules never import this one); bound here as methods, signatures and docs unchanged.
    from_raw = classmethod(_raw.from_raw)
    from_irregular = classmethod(_raw.from_irregular)
    to_pandas = _formats.to_pandas
    from_pandas = classmethod(_formats.from_pandas)
    to_csv = _formats.to_csv
    from_csv = classmethod(_formats.from_csv)
    to_npz = _formats.to_npz
    from_npz = classmethod(_formats.from_npz)
    to_mat = _formats.to_mat
    from_mat = classmethod(_formats.from_mat)
    experiment = _segments.experiment
    slice = _segments.slice_samples
    time_slice = _segments.time_slice
    __getitem__ = _segments.getitem
    select = _segments.select
    split = _segments.split
    merge = _segments.merge

    def __init__(
        self,
        u: Any = None,
        y: Any = None,
        dt: float | None = None,
        *,
        input_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
        input_units: Sequence[str] | None = None,
        output_units: Sequence[str] | None = None,
        time: Any = None,
    ) -> None:
        if y is None:
            raise DataError("y is required: IOData(u=..., y=..., dt=...)")
        ylist = _as_list(y, "y")
        if not ylist:
            raise ShapeError("y is an empty list: give at least one experiment")
        ys = [time_first(as_2d(v, "y" if i == 0 else f"y[{i}]"), "y" if i == 0 else f"y[{i}]")
              for i, v in enumerate(ylist)]
        n_out = ys[0].shape[1]
        if n_out == 0:
            raise ShapeError(
                f"y has shape {ys[0].shape}: no output channel; a record needs at least one "
                "output (the measured signal to model): give y as (n_samples, n_outputs) with "
                "n_outputs >= 1 (an input-only signal has nothing to identify)"
            )
        for i, v in enumerate(ys):
            if v.shape[1] != n_out:
                raise ShapeError(f"y[{i}] has {v.shape[1]} outputs but y[0] has {n_out}")
        us_in = _as_list(u, "u")
        if us_in is None:
            us = [np.zeros((v.shape[0], 0)) for v in ys]
        else:
            if len(us_in) != len(ys):
                raise ShapeError(
                    f"u has {len(us_in)} experiment(s) but y has {len(ys)}; give one array each"
                )
            us = [time_first(as_2d(v, "u" if i == 0 else f"u[{i}]"),
                              "u" if i == 0 else f"u[{i}]") for i, v in enumerate(us_in)]
        n_in = us[0].shape[1]
        for i, (a, b) in enumerate(zip(us, ys)):
            if a.shape[1] != n_in:
                raise ShapeError(f"u[{i}] has {a.shape[1]} inputs but u[0] has {n_in}")
            if a.shape[0] != b.shape[0]:
                raise ShapeError(
                    f"u has {a.shape[0]} samples but y has {b.shape[0]}"
                    + (f" in experiment {i}" if len(ys) > 1 else "")
                    + "; inputs and outputs must be sampled together"
                )
        t0s = [0.0] * len(ys)
        if time is not None:
            tl = _as_list(time, "time")
            assert tl is not None
            if len(tl) != len(ys):
                raise ShapeError(f"time has {len(tl)} experiment(s) but y has {len(ys)}")
            dts = []
            for i, (t, v) in enumerate(zip(tl, ys)):
                t = np.asarray(t, dtype=float).ravel()
                if t.size != v.shape[0]:
                    raise ShapeError(
                        f"time{'' if len(ys) == 1 else f'[{i}]'} has {t.size} instants but y "
                        f"has {v.shape[0]} samples"
                    )
                if t.size >= 2:
                    dts.append(sample_time(t))
                t0s[i] = float(t[0])
            if dts:
                h = float(np.median(dts))
                if any(abs(x - h) > 0.01 * h for x in dts):
                    raise DataError(
                        f"the experiments are sampled at different rates ({sorted(set(dts))}); "
                        "resample them to one dt first (sysid.resample)"
                    )
                if dt is not None and abs(float(dt) - h) > 0.01 * h:
                    raise DataError(
                        f"dt = {dt} disagrees with the time vector (median spacing {h:g} s); "
                        "give one or the other"
                    )
                if dt is None:
                    dt = h
        dt = 1.0 if dt is None else as_dt(dt)
        self._exps = [_Exp(a, b, t) for a, b, t in zip(us, ys, t0s)]
        self.dt = dt
        self.input_names = self._names(input_names, n_in, "u", "input")
        self.output_names = self._names(output_names, n_out, "y", "output")
        if set(self.input_names) & set(self.output_names):
            both = sorted(set(self.input_names) & set(self.output_names))
            raise DataError(f"channel name(s) {both} used for both an input and an output")
        self.input_units = self._units(input_units, self.input_names, "input")
        self.output_units = self._units(output_units, self.output_names, "output")
        self._u_scale = np.ones(n_in)
        self._y_scale = np.ones(n_out)
        #: what interpolation onto a uniform grid did (:class:`~sysid.data.raw.Resampling`:
        #: from_irregular, the readers' resample=), None for a record read as sampled
        self.resampling: _raw.Resampling | None = None

    # ---------------------------------------------------------------- construction helpers

    @staticmethod
    def _names(names: Sequence[str] | None, n: int, prefix: str, kind: str) -> list[str]:
        if names is None:
            return [f"{prefix}{i}" for i in range(n)]
        if isinstance(names, str):
            names = [names]
        names = list(names)
        if not all(isinstance(s, str) and s for s in names):
            raise DataError(f"{kind} names must be non-empty strings, got {names!r}")
        if len(names) != n:
            raise ShapeError(f"{len(names)} {kind} name(s) given for {n} {kind} channel(s)")
        dup = sorted({s for s in names if names.count(s) > 1})
        if dup:
            raise DataError(f"duplicate {kind} name(s) {dup}; channel names must be unique")
        return names

    @staticmethod
    def _units(units: Sequence[str] | None, names: list[str], kind: str) -> list[str]:
        if units is None:
            return [""] * len(names)
        if isinstance(units, str):
            units = [units]
        units = list(units)
        if len(units) != len(names):
            raise ShapeError(f"{len(units)} {kind} unit(s) given for {len(names)} channel(s)")
        return [check_unit(x, n) for x, n in zip(units, names)]

    def _derive(
        self,
        exps: list[_Exp],
        *,
        iu: list[int] | None = None,
        iy: list[int] | None = None,
        dt: float | None = None,
    ) -> IOData:
        """A new record sharing metadata, with other experiments (and channel subsets)."""
        if not exps:
            raise InsufficientDataError("the operation left no samples (every segment is empty)")
        for e in exps:
            if e.y.shape[0] == 0:
                raise InsufficientDataError(
                    "the operation would leave an empty experiment; choose a non-empty range"
                )
        new = object.__new__(IOData)
        iu = list(range(self.n_inputs)) if iu is None else iu
        iy = list(range(self.n_outputs)) if iy is None else iy
        new._exps = exps
        new.dt = self.dt if dt is None else dt
        new.input_names = [self.input_names[i] for i in iu]
        new.output_names = [self.output_names[i] for i in iy]
        new.input_units = [self.input_units[i] for i in iu]
        new.output_units = [self.output_units[i] for i in iy]
        new._u_scale = self._u_scale[iu].copy()
        new._y_scale = self._y_scale[iy].copy()
        new.resampling = self.resampling
        return new

    # ---------------------------------------------------------------- basic properties

    @property
    def experiments(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """``[(u, y), ...]``, one float64 pair per experiment, shaped (samples, channels)."""
        return [(e.u, e.y) for e in self._exps]

    @property
    def u(self) -> np.ndarray:
        """Inputs of a single-experiment record, ``(n_samples, n_inputs)``."""
        return self._single("u").u

    @property
    def y(self) -> np.ndarray:
        """Outputs of a single-experiment record, ``(n_samples, n_outputs)``."""
        return self._single("y").y

    @property
    def time(self) -> np.ndarray:
        """Sample instants of a single-experiment record, ``(n_samples,)`` in seconds."""
        e = self._single("time")
        return e.t0 + np.arange(e.y.shape[0]) * self.dt

    @property
    def times(self) -> list[np.ndarray]:
        """Sample instants of every experiment."""
        return [e.t0 + np.arange(e.y.shape[0]) * self.dt for e in self._exps]

    def _single(self, name: str) -> _Exp:
        if len(self._exps) != 1:
            raise DataError(
                f"this record has {len(self._exps)} experiments; use .experiments (or "
                f".experiment(k)) instead of .{name}"
            )
        return self._exps[0]

    @property
    def n_inputs(self) -> int:
        """Number of input channels."""
        return self._exps[0].u.shape[1]

    @property
    def n_outputs(self) -> int:
        """Number of output channels."""
        return self._exps[0].y.shape[1]

    @property
    def n_experiments(self) -> int:
        """Number of experiments."""
        return len(self._exps)

    @property
    def n_samples(self) -> int:
        """Total number of samples over all experiments."""
        return sum(e.y.shape[0] for e in self._exps)

    @property
    def lengths(self) -> list[int]:
        """Number of samples of each experiment."""
        return [e.y.shape[0] for e in self._exps]

    def __len__(self) -> int:
        return self.n_samples

    def _repr_html_(self) -> str:
        """Notebook display: channel statistics and a small plot each (see
        :mod:`sysid._display`)."""
        from .._display import iodata_html

        return iodata_html(self)

    def __repr__(self) -> str:
        exp = f" in {self.n_experiments} experiments" if self.n_experiments > 1 else ""
        tr = (", resampled" if self.resampling is not None else "") + (
            ", detrended" if self.has_trend else "")
        return (
            f"IOData: {_plural(self.n_samples, 'sample')}{exp}, {_plural(self.n_inputs, 'input')}, "
            f"{_plural(self.n_outputs, 'output')}, dt = {self.dt:g} s{tr}"
        )

    def __eq__(self, other: object) -> bool:
        """Same samples: sample time, channel names, experiments' lengths and values.

        Units, start times, a removed trend's bookkeeping and :attr:`resampling` are not
        compared: ``resampling`` says how the samples were obtained (interpolated from
        irregular stamps), not what they are, and a record with the same samples is equal
        whether it was resampled or not (a resampled record written with :meth:`to_csv`,
        which has no place for the note, reads back equal).

        Examples
        --------
        >>> import numpy as np, sysid
        >>> t = np.array([0.0, 0.1, 0.2, 0.35, 0.4, 0.5])
        >>> r = sysid.IOData.from_irregular(t, None, 2 * t, dt=0.1)
        >>> r == sysid.IOData(y=r.y, dt=0.1), r.resampling is None
        (True, False)
        """
        if not isinstance(other, IOData):
            return NotImplemented
        return (
            self.dt == other.dt
            and self.input_names == other.input_names
            and self.output_names == other.output_names
            and self.lengths == other.lengths
            and all(
                np.array_equal(a.u, b.u) and np.array_equal(a.y, b.y)
                for a, b in zip(self._exps, other._exps)
            )
        )

    __hash__ = None  # type: ignore[assignment]

    # ---------------------------------------------------------------- trend bookkeeping

    @property
    def has_trend(self) -> bool:
        """Whether a trend or scaling was removed (see :attr:`trend`)."""
        return any(e.tu is not None or e.ty is not None for e in self._exps) or not (
            np.all(self._u_scale == 1.0) and np.all(self._y_scale == 1.0)
        )

    def _trend_info(self) -> tuple[bool, np.ndarray, np.ndarray]:
        """(any nonzero trend removed, input scales, output scales) without building
        :attr:`trend` (which allocates record-sized zero arrays)."""
        removed = any(t is not None and bool(np.any(t != 0))
                      for e in self._exps for t in (e.tu, e.ty))
        return removed, self._u_scale.copy(), self._y_scale.copy()

    @property
    def trend(self) -> Trend:
        """What pre-processing removed: ``original = scale * data + trend`` per channel."""
        return Trend(
            [e.tu if e.tu is not None else np.zeros_like(e.u) for e in self._exps],
            [e.ty if e.ty is not None else np.zeros_like(e.y) for e in self._exps],
            self._u_scale.copy(),
            self._y_scale.copy(),
        )

    def _minus_trend(self, trend_of: Any) -> IOData:
        """This record minus a given trend: ``trend_of(n, t0) -> (u_trend, y_trend)`` per
        experiment of ``n`` samples starting at time ``t0`` (original units), recorded like
        ``detrend``'s so that :meth:`retrend` adds it back (used by :meth:`Trend.apply`)."""
        exps = []
        for e in self._exps:
            tu, ty = trend_of(e.y.shape[0], e.t0)
            parts = []
            for x, old, sc, t in ((e.u, e.tu, self._u_scale, tu), (e.y, e.ty, self._y_scale, ty)):
                prev = np.zeros_like(x) if old is None else old
                parts.append((x - t / sc, prev + t))  # t / sc: in this record's units
            exps.append(_Exp(parts[0][0], parts[1][0], e.t0, parts[0][1], parts[1][1]))
        return self._derive(exps)

    def _scaled(self, su: np.ndarray, sy: np.ndarray) -> IOData:
        """Every channel divided by its factor, recorded (see :func:`sysid.scale`)."""
        new = self._derive([_Exp(e.u / su, e.y / sy, e.t0, e.tu, e.ty) for e in self._exps])
        new._u_scale = self._u_scale * su
        new._y_scale = self._y_scale * sy
        return new

    def retrend(self) -> IOData:
        """The record in original units: trend and scaling added back.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> d = sysid.IOData(u=np.arange(6.0), y=np.arange(6.0) ** 2)
        >>> back = sysid.detrend(d, "linear").retrend()
        >>> bool(np.allclose(back.y, d.y))
        True
        """
        tr = self.trend
        exps = [
            _Exp(e.u * tr.u_scale + a, e.y * tr.y_scale + b, e.t0)
            for e, a, b in zip(self._exps, tr.u_trend, tr.y_trend)
        ]
        new = self._derive(exps)
        new._u_scale = np.ones(self.n_inputs)
        new._y_scale = np.ones(self.n_outputs)
        return new

    # ---------------------------------------------------------------- statistics

    def summary(self) -> DataSummary:
        """Per-channel statistics (mean, standard deviation, min, max, RMS) over all experiments.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> s = sysid.IOData(u=np.arange(4.0), y=np.ones(4), input_units=["V"]).summary()
        >>> s.rows[0]["mean"], s.rows[0]["unit"]
        (1.5, 'V')
        """
        rows = []
        for kind, names, units, idx in (
            ("input", self.input_names, self.input_units, 0),
            ("output", self.output_names, self.output_units, 1),
        ):
            for j, (n, un) in enumerate(zip(names, units)):
                x = np.concatenate([ex[idx][:, j] for ex in self.experiments])
                rows.append(
                    {
                        "channel": n,
                        "kind": kind,
                        "unit": un,
                        "mean": float(x.mean()),
                        "std": float(x.std()),
                        "min": float(x.min()),
                        "max": float(x.max()),
                        "rms": float(np.sqrt(np.mean(x * x))),
                    }
                )
        return DataSummary(repr(self), rows, self.lengths, self.dt)

    # ---------------------------------------------------------------- plotting

    def plot(self, fig: Any = None) -> Any:
        """Plot every channel against time (see :func:`sysid.plot.data.plot_data`)."""
        from ..plot.data import plot_data

        return plot_data(self, fig=fig)


@dataclass
class DataSummary(HTMLResult):
    """Per-channel statistics of a record (from :meth:`IOData.summary`)."""

    title: str
    rows: list[dict[str, Any]]
    lengths: list[int]
    dt: float

    def to_pandas(self) -> Any:
        """The table as a DataFrame indexed by channel."""
        return _pandas().DataFrame(self.rows).set_index("channel")

    def __repr__(self) -> str:
        w = max([13] + [len(r["channel"]) for r in self.rows]) + 1  # names whole
        head = f"{'channel':<{w}}{'kind':<8}{'unit':<8}" + "".join(
            f"{k:>12}" for k in ("mean", "std", "min", "max", "rms")
        )
        lines = [self.title, head]
        for r in self.rows:
            lines.append(
                f"{r['channel']:<{w}}{r['kind']:<8}{r['unit'][:7]:<8}"
                + "".join(f"{r[k]:>12.4g}" for k in ("mean", "std", "min", "max", "rms"))
            )
        if len(self.lengths) > 1:
            lines.append(f"experiment lengths: {self.lengths}")
        return "\n".join(lines)


def as_record(data: Any) -> Any:
    """``data`` as an IOData record: a ``(u, y)`` pair of arrays is wrapped (``dt = 1``), as
    :func:`sysid.ssest` and :func:`sysid.compare` accept it; anything else is returned as it
    is (the caller's own checks name what is wrong).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.data.iodata import as_record
    >>> as_record((np.ones(4), np.zeros(4))).n_samples
    4
    """
    if isinstance(data, tuple) and len(data) == 2:
        return IOData(u=data[0], y=data[1])
    return data


def require_record(data: Any, who: str, pairs: bool = True) -> IOData:
    """``data`` as a record, or a :class:`~sysid.errors.DataError` naming ``who`` and the
    fix (a bare array does not say which columns are inputs, nor its sample time).
    ``pairs``: a ``(u, y)`` pair is wrapped (:func:`as_record`, ``dt = 1``); ``False`` for
    functions whose result depends on the sample time (filters, resampling).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.data.iodata import require_record
    >>> require_record((np.ones(4), np.zeros(4)), "advice").n_samples
    4
    """
    if pairs:
        data = as_record(data)
    refuse_frd(data, who)
    if not isinstance(data, IOData):
        pair = " or a (u, y) pair of arrays" if pairs else ""
        raise DataError(
            f"{who} takes an IOData record{pair}, got {type(data).__name__}"
            + (several_records_hint(data) or ": wrap the arrays first, "
               f"sysid.{who}(sysid.IOData(u=u, y=y, dt=dt)) (u=None for output-only data)"))
    return data
