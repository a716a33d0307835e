"""Input/output records: :class:`IOData`, the one data type every estimator accepts.

A record holds inputs ``u`` and outputs ``y`` sampled together at a uniform sample time
``dt``, time-first ``(samples, channels)``, possibly as several experiments (segments) that
estimators treat as separate (no Hankel column or correlation lag spans two of them). Channels
carry names and units; each experiment its start time. Pre-processing that removes a trend or
scales channels records what it did (:attr:`IOData.trend`) so that model outputs can be mapped
back to engineering units.

Readers and writers for pandas, CSV, NPZ and MATLAB files are methods of :class:`IOData`
(``from_pandas``/``to_pandas``, ``from_csv``/``to_csv``, ``from_npz``/``to_npz``,
``from_mat``/``to_mat``).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from .._checks import as_2d
from ..errors import DataError, InsufficientDataError, NonFiniteError, ShapeError

__all__ = ["IOData", "Trend", "SplitData", "DataSummary", "sample_time", "check_unit"]


# --------------------------------------------------------------------------------------------
# units
# --------------------------------------------------------------------------------------------

_PREFIXABLE = {
    "m", "g", "s", "A", "K", "mol", "cd", "N", "Pa", "J", "W", "V", "Ohm", "ohm", "Hz",
    "rad", "bar", "L", "l", "T", "Wb", "C", "F", "S", "H", "lm", "lx", "Wh", "VA", "t",
}
_PLAIN = {
    "deg", "degC", "degF", "°", "°C", "°F", "%", "-", "1", "rpm", "min", "h", "d", "ft",
    "in", "mi", "nmi", "lbf", "lb", "lbs", "kt", "kn", "kts", "psi", "g0", "G", "counts",
    "count", "bit", "bits", "dB", "dBm", "ppm", "pH", "mmHg", "inHg", "atm", "rev", "cycle",
    "cycles", "sample", "samples", "unit", "units", "pu", "p.u.", "m3", "m2", "cm", "mm",
}
_PREFIXES = ("k", "M", "G", "m", "u", "µ", "n", "p", "c", "d", "h")
_UNIT_TOKEN = re.compile(r"[*/·\s()]+")


def _known_symbol(sym: str) -> bool:
    sym = re.sub(r"\^?-?\d+$", "", sym)  # exponent: m^2, s-1, m2
    if sym in _PLAIN or sym in _PREFIXABLE:
        return True
    return any(sym.startswith(p) and sym[len(p):] in _PREFIXABLE for p in _PREFIXES)


def check_unit(unit: Any, channel: str = "channel") -> str:
    """Validate a unit string such as ``"m/s^2"``, ``"deg/s"``, ``"N*m"`` or ``""`` (none).

    Units are products and quotients of known symbols (SI with prefixes, ``deg``, ``degC``,
    ``%``, ``rpm``, ``ft``, ``kt``, ``psi``, ``g0``, ``counts``, ``-`` for dimensionless...)
    with optional integer exponents. An unknown symbol raises :class:`~sysid.DataError`.

    Examples
    --------
    >>> from sysid.data.iodata import check_unit
    >>> check_unit("m/s^2", "y0")
    'm/s^2'
    >>> check_unit("furlong", "y0")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: unknown unit 'furlong' for channel y0 (symbol 'furlong'); ...
    """
    if unit is None:
        return ""
    if not isinstance(unit, str):
        raise DataError(f"the unit of channel {channel} must be a string, got {unit!r}")
    u = unit.strip()
    if u == "":
        return ""
    for sym in _UNIT_TOKEN.split(u):
        if sym and not _known_symbol(sym):
            raise DataError(
                f"unknown unit {unit!r} for channel {channel} (symbol {sym!r}); use SI symbols "
                "with prefixes (e.g. 'm/s^2', 'deg/s', 'N*m', 'V'), '-' for dimensionless, "
                "or '' for none"
            )
    return u


# --------------------------------------------------------------------------------------------
# sample time
# --------------------------------------------------------------------------------------------


def sample_time(time: Any, *, rtol: float = 0.01) -> float:
    """The sample time of a time vector: its median spacing, after checking it is uniform.

    Parameters
    ----------
    time : array_like
        Sample instants in seconds, 1-D, at least two.
    rtol : float
        Largest accepted relative deviation of any spacing from the median.

    Returns
    -------
    float
        The median spacing.

    Raises
    ------
    DataError
        If the vector repeats or goes back in time, or has gaps or jitter beyond ``rtol``
        (the message names the first offending sample and suggests
        :meth:`IOData.from_irregular` to resample onto a uniform grid).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> sysid.sample_time(np.arange(100) * 0.02 + 5.0)
    0.02
    """
    t = np.asarray(time, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise ShapeError(f"time must be a 1-D vector of at least 2 instants, got shape {t.shape}")
    if not np.isfinite(t).all():
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise NonFiniteError(f"time has a non-finite value at sample {i}")
    d = np.diff(t)
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        i = int(bad[0])
        what = "repeats" if d[i] == 0 else "goes back"
        raise DataError(
            f"time {what} at sample {i + 1} (t[{i}] = {t[i]:g}, t[{i + 1}] = {t[i + 1]:g}; "
            f"{bad.size} such place(s)); remove duplicate samples or sort the record first"
        )
    h = float(np.median(d))
    dev = np.abs(d - h) > rtol * h
    if dev.any():
        i = int(np.flatnonzero(dev)[0])
        kind = "a gap" if d[i] > h else "jitter"
        raise DataError(
            f"irregular sampling: {kind} at sample {i + 1} (spacing {d[i]:g} s against the "
            f"median {h:g} s; {int(dev.sum())} spacing(s) off by more than {rtol:.0%}); "
            "resample onto a uniform grid with sysid.IOData.from_irregular(time, u, y, dt), "
            "or cut the record at the gap"
        )
    # round-off of summed float steps: report a clean value when it is one
    r = float(f"{h:.12g}")
    return r if abs(r - h) <= 1e-9 * h else h


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------


def _as_list(x: Any) -> list[Any] | None:
    if x is None:
        return None
    if isinstance(x, (list, tuple)):
        return list(x)
    return [x]


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" + ("" if n == 1 else "s")


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

    estimation: IOData
    validation: IOData


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
        ylist = _as_list(y)
        if not ylist:
            raise ShapeError("y is an empty list: give at least one experiment")
        ys = [as_2d(v, "y" if i == 0 else f"y[{i}]") for i, v in enumerate(ylist)]
        n_out = ys[0].shape[1]
        for i, v in enumerate(ys):
            if v.shape[1] != n_out:
                raise ShapeError(f"y[{i}] has {v.shape[1]} outputs but y[0] has {n_out}")
        us_in = _as_list(u)
        if us_in is None:
            us = [np.zeros((v.shape[0], 0)) for v in ys]
        else:
            if len(us_in) != len(ys):
                raise ShapeError(
                    f"u has {len(us_in)} experiment(s) but y has {len(ys)}; give one array each"
                )
            us = [as_2d(v, "u" if i == 0 else f"u[{i}]") for i, v in enumerate(us_in)]
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
            tl = _as_list(time)
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
        dt = 1.0 if dt is None else dt
        try:
            dt = float(dt)
        except (TypeError, ValueError):
            raise DataError(f"dt must be a positive number of seconds, got {dt!r}") from None
        if not np.isfinite(dt) or dt <= 0:
            raise DataError(f"dt must be a positive number of seconds, got {dt}")
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

    def __repr__(self) -> str:
        exp = f" in {self.n_experiments} experiments" if self.n_experiments > 1 else ""
        tr = ", detrended" if self.has_trend else ""
        return (
            f"IOData: {_plural(self.n_samples, 'sample')}{exp}, {_plural(self.n_inputs, 'input')}, "
            f"{_plural(self.n_outputs, 'output')}, dt = {self.dt:g} s{tr}"
        )

    def __eq__(self, other: object) -> bool:
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
            if not isinstance(o, IOData):
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

    # ---------------------------------------------------------------- trend bookkeeping

    @property
    def has_trend(self) -> bool:
        """Whether a trend or scaling was removed (see :attr:`trend`)."""
        return any(e.tu is not None or e.ty is not None for e in self._exps) or not (
            np.all(self._u_scale == 1.0) and np.all(self._y_scale == 1.0)
        )

    @property
    def trend(self) -> Trend:
        """What pre-processing removed: ``original = scale * data + trend`` per channel."""
        return Trend(
            [e.tu if e.tu is not None else np.zeros_like(e.u) for e in self._exps],
            [e.ty if e.ty is not None else np.zeros_like(e.y) for e in self._exps],
            self._u_scale.copy(),
            self._y_scale.copy(),
        )

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

    # ---------------------------------------------------------------- raw and irregular data

    @classmethod
    def from_raw(
        cls,
        u: Any,
        y: Any,
        dt: float | None = None,
        *,
        time: Any = None,
        nan: str = "error",
        max_gap: int = 5,
        min_length: int = 2,
        input_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
        input_units: Sequence[str] | None = None,
        output_units: Sequence[str] | None = None,
    ) -> IOData:
        """A record from raw arrays that may contain NaN drop-outs.

        Parameters
        ----------
        u, y : array_like
            One experiment each, ``(n_samples, channels)``; ``u`` may be ``None``.
        dt, time : optional
            Sample time or time vector, as for :class:`IOData`.
        nan : {"error", "interpolate", "split"}
            ``"error"`` raises on any NaN/Inf; ``"interpolate"`` fills gaps of at most
            ``max_gap`` consecutive samples linearly (per channel) and splits the record at
            longer ones; ``"split"`` cuts the record at every gap, each clean run becoming
            its own experiment.
        max_gap : int
            Longest gap (samples) that ``"interpolate"`` fills.
        min_length : int
            Clean runs shorter than this are dropped.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> y = np.arange(12.0); y[3] = np.nan; y[6:9] = np.nan
        >>> sysid.IOData.from_raw(None, y, nan="interpolate", max_gap=1).lengths
        [6, 3]
        >>> sysid.IOData.from_raw(None, y, nan="split").lengths
        [3, 2, 3]
        """
        from .preprocessing import repair_nan

        ua = None if u is None else _raw2d(u, "u")
        ya = _raw2d(y, "y")
        if ua is not None and ua.shape[0] != ya.shape[0]:
            raise ShapeError(f"u has {ua.shape[0]} samples but y has {ya.shape[0]}")
        t0 = 0.0
        if time is not None:
            t = np.asarray(time, dtype=float).ravel()
            if t.size != ya.shape[0]:
                raise ShapeError(f"time has {t.size} instants but y has {ya.shape[0]} samples")
            h = sample_time(t)
            if dt is not None and abs(float(dt) - h) > 0.01 * h:
                raise DataError(f"dt = {dt} disagrees with the time vector (median {h:g} s)")
            dt, t0 = h, float(t[0])
        runs = repair_nan(ua, ya, nan=nan, max_gap=max_gap, min_length=min_length)
        h = 1.0 if dt is None else float(dt)
        return cls(
            None if ua is None else [r[0] for r in runs],
            [r[1] for r in runs],
            h,
            time=[t0 + r[2] * h + np.arange(len(r[1])) * h for r in runs],
            input_names=input_names,
            output_names=output_names,
            input_units=input_units,
            output_units=output_units,
        )

    @classmethod
    def from_irregular(
        cls,
        time: Any,
        u: Any,
        y: Any,
        dt: float | None = None,
        *,
        method: str = "linear",
        input_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
        input_units: Sequence[str] | None = None,
        output_units: Sequence[str] | None = None,
    ) -> IOData:
        """A uniformly sampled record interpolated from irregularly timed samples.

        Parameters
        ----------
        time : array_like
            Strictly increasing sample instants (repeats are an error: remove them first).
        u, y : array_like
            Values at those instants (``u`` may be ``None``).
        dt : float, optional
            New sample time; default the median spacing of ``time``.
        method : {"linear", "cubic"}
            Interpolation (``"cubic"``: SciPy's ``CubicSpline``). No anti-alias filter is
            applied: choose ``dt`` no longer than the typical spacing.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> t = np.array([0.0, 0.1, 0.2, 0.35, 0.4, 0.5])
        >>> d = sysid.IOData.from_irregular(t, None, 2 * t, dt=0.1)
        >>> d.y.ravel()
        array([0. , 0.2, 0.4, 0.6, 0.8, 1. ])
        """
        t = np.asarray(time, dtype=float).ravel()
        ya = as_2d(y, "y")
        ua = None if u is None else as_2d(u, "u")
        if t.size != ya.shape[0] or (ua is not None and ua.shape[0] != t.size):
            raise ShapeError("time, u and y must have the same number of samples")
        if t.size < 2 or not np.isfinite(t).all():
            raise DataError("time must hold at least 2 finite instants")
        d = np.diff(t)
        if (d <= 0).any():
            i = int(np.flatnonzero(d <= 0)[0])
            raise DataError(
                f"time is not strictly increasing at sample {i + 1} ({t[i]:g} then {t[i + 1]:g});"
                " sort the samples and remove duplicates first"
            )
        h = float(np.median(d)) if dt is None else float(dt)
        if not np.isfinite(h) or h <= 0:
            raise DataError(f"dt must be positive, got {dt}")
        grid = t[0] + np.arange(int(np.floor((t[-1] - t[0]) / h + 1e-9)) + 1) * h
        if method == "linear":
            def interp(x: np.ndarray) -> np.ndarray:
                return np.column_stack([np.interp(grid, t, c) for c in x.T]).reshape(
                    grid.size, x.shape[1]
                )
        elif method == "cubic":
            from scipy.interpolate import CubicSpline

            def interp(x: np.ndarray) -> np.ndarray:
                return CubicSpline(t, x, axis=0)(grid)
        else:
            raise DataError(f"method must be 'linear' or 'cubic', got {method!r}")
        return cls(
            None if ua is None else interp(ua),
            interp(ya),
            h,
            time=grid,
            input_names=input_names,
            output_names=output_names,
            input_units=input_units,
            output_units=output_units,
        )

    # ---------------------------------------------------------------- pandas

    def to_pandas(self) -> Any:
        """A DataFrame: one column per channel plus ``experiment``, indexed by ``time``.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> df = sysid.IOData(u=np.ones(3), y=np.zeros(3), dt=0.5).to_pandas()
        >>> list(df.columns)
        ['experiment', 'u0', 'y0']
        """
        pd = _pandas()
        frames = []
        for k, (e, t) in enumerate(zip(self._exps, self.times)):
            cols: dict[str, Any] = {"experiment": np.full(len(t), k)}
            for j, n in enumerate(self.input_names):
                cols[n] = e.u[:, j]
            for j, n in enumerate(self.output_names):
                cols[n] = e.y[:, j]
            frames.append(pd.DataFrame(cols, index=pd.Index(t, name="time")))
        df = pd.concat(frames)
        df.attrs.update(
            {
                "dt": self.dt,
                "inputs": list(self.input_names),
                "outputs": list(self.output_names),
                "units": dict(zip(self.input_names + self.output_names,
                                  self.input_units + self.output_units)),
            }
        )
        return df

    @classmethod
    def from_pandas(
        cls,
        df: Any,
        inputs: Sequence[str] | None = None,
        outputs: Sequence[str] | None = None,
        *,
        time: str | None = None,
        dt: float | None = None,
        experiment: str | None = None,
        units: dict[str, str] | None = None,
        nan: str = "error",
        max_gap: int = 5,
    ) -> IOData:
        """A record from a DataFrame's columns.

        Parameters
        ----------
        df : pandas.DataFrame
        inputs, outputs : list of str
            Column names. Default: those stored by :meth:`to_pandas` in ``df.attrs``.
        time : str, optional
            Column holding the time in seconds; default the index when it is numeric and
            ``dt`` is not given (a ``DatetimeIndex`` is converted to seconds).
        dt : float, optional
            Sample time (when there is no time information).
        experiment : str, optional
            Column numbering the experiments (default ``"experiment"`` if present).
        units : dict, optional
            Unit per column name.
        nan, max_gap :
            Handling of missing values (single-experiment frames), as in :meth:`from_raw`.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> d = sysid.IOData(u=np.ones(3), y=np.arange(3.0), dt=0.5)
        >>> sysid.IOData.from_pandas(d.to_pandas()) == d
        True
        """
        pd = _pandas()
        if not isinstance(df, pd.DataFrame):
            raise DataError(f"from_pandas takes a pandas DataFrame, got {type(df).__name__}")
        inputs = list(df.attrs.get("inputs", [])) if inputs is None else list(inputs)
        if outputs is None:
            if "outputs" not in df.attrs:
                raise DataError("name the output columns: IOData.from_pandas(df, inputs, outputs)")
            outputs = list(df.attrs["outputs"])
        outputs = list(outputs)
        missing = [c for c in inputs + outputs if c not in df.columns]
        if missing:
            raise DataError(
                f"column(s) {missing} not in the DataFrame (columns: {list(df.columns)})"
            )
        units = dict(df.attrs.get("units", {})) if units is None else dict(units)
        if experiment is None and "experiment" in df.columns:
            experiment = "experiment"
        groups = [df] if experiment is None else [g for _, g in df.groupby(experiment, sort=True)]
        us, ys, ts = [], [], []
        for g in groups:
            us.append(g[inputs].to_numpy(dtype=float) if inputs else None)
            ys.append(g[outputs].to_numpy(dtype=float))
            if time is not None:
                ts.append(g[time].to_numpy(dtype=float))
            elif dt is None and isinstance(g.index, pd.DatetimeIndex):
                ts.append((g.index - groups[0].index[0]).total_seconds().to_numpy())
            elif dt is None and g.index.dtype.kind in "if":
                ts.append(g.index.to_numpy(dtype=float))
        if dt is None and not ts:
            dt = df.attrs.get("dt")
        kw: dict[str, Any] = {
            "input_names": inputs,
            "output_names": outputs,
            "input_units": [units.get(c, "") for c in inputs],
            "output_units": [units.get(c, "") for c in outputs],
        }
        if nan != "error":
            if len(groups) != 1:
                raise DataError("nan= repairs single-experiment frames; split them first")
            return cls.from_raw(us[0], ys[0], dt, time=ts[0] if ts else None, nan=nan,
                                max_gap=max_gap, **kw)
        return cls(
            us if inputs else None,
            ys,
            dt,
            time=ts if ts else None,
            **kw,
        )

    # ---------------------------------------------------------------- CSV

    def to_csv(self, path: str | Path) -> None:
        """Write a CSV file: header ``time,experiment,<inputs>,<outputs>``, one row a sample.

        Units are written into the header as ``name [unit]``; :meth:`from_csv` reads them back.
        """
        head = ["time", "experiment"] + [
            f"{n} [{u}]" if u else n
            for n, u in zip(self.input_names + self.output_names,
                            self.input_units + self.output_units)
        ]
        rows = [
            np.column_stack([t, np.full(len(t), k), e.u, e.y])
            for k, (e, t) in enumerate(zip(self._exps, self.times))
        ]
        np.savetxt(
            path, np.vstack(rows), delimiter=",", header=",".join(head), comments="",
            fmt="%.17g",
        )

    @classmethod
    def from_csv(
        cls,
        path: str | Path,
        inputs: Sequence[str | int] | None = None,
        outputs: Sequence[str | int] | None = None,
        *,
        time: str | int | None = None,
        dt: float | None = None,
        experiment: str | int | None = None,
        delimiter: str = ",",
        nan: str = "error",
        max_gap: int = 5,
    ) -> IOData:
        """Read a CSV file with a header row (the format of :meth:`to_csv`, or any other).

        Columns are chosen by header name or 0-based index; ``name [unit]`` headers give
        units. Without ``inputs``/``outputs``, a file written by :meth:`to_csv` is read back
        whole. Empty fields become NaN and are handled as ``nan`` says (see
        :meth:`from_raw`; only for single-experiment files). Trailing delimiters are ignored.
        """
        p = Path(path)
        if not p.exists():
            raise DataError(f"no such file: {p}")
        with open(p, encoding="utf-8") as fh:
            header = fh.readline().strip()
        raw_names = [h.strip().strip('"') for h in header.split(delimiter)]
        while raw_names and raw_names[-1] == "":
            raw_names.pop()
        names, unit_of = [], {}
        for h in raw_names:
            m = re.fullmatch(r"(.*?)\s*\[(.*)\]", h)
            n = m.group(1) if m else h
            names.append(n)
            unit_of[n] = m.group(2) if m else ""
        data = np.genfromtxt(p, delimiter=delimiter, skip_header=1, dtype=float)
        data = np.atleast_2d(data)[:, : len(names)]

        def col(c: str | int) -> int:
            if isinstance(c, (int, np.integer)):
                if not 0 <= c < len(names):
                    raise DataError(f"column {c} out of range: the file has {len(names)} columns")
                return int(c)
            if c not in names:
                raise DataError(f"no column {c!r} in {p.name}; its columns are {names}")
            return names.index(c)

        if inputs is None and outputs is None and names[:2] == ["time", "experiment"]:
            # our own format: which are inputs is not stored, so everything after is outputs
            raise DataError(
                f"{p.name}: say which columns are inputs and outputs, e.g. "
                f"IOData.from_csv(path, inputs=[...], outputs=[...]); columns: {names[2:]}"
            )
        if outputs is None:
            raise DataError(f"name the output columns of {p.name}; its columns are {names}")
        iu = [col(c) for c in (inputs or [])]
        iy = [col(c) for c in outputs]
        if time is None and "time" in names and dt is None:
            time = "time"
        if experiment is None and "experiment" in names:
            experiment = "experiment"
        tcol = None if time is None else col(time)
        ecol = None if experiment is None else col(experiment)
        kw: dict[str, Any] = {
            "input_names": [names[i] for i in iu],
            "output_names": [names[i] for i in iy],
            "input_units": [unit_of[names[i]] for i in iu],
            "output_units": [unit_of[names[i]] for i in iy],
        }
        if ecol is not None:
            ks = data[:, ecol]
            parts = [data[ks == k] for k in np.unique(ks)]
            return cls(
                [q[:, iu] for q in parts] if iu else None,
                [q[:, iy] for q in parts],
                dt,
                time=None if tcol is None else [q[:, tcol] for q in parts],
                **kw,
            )
        return cls.from_raw(
            data[:, iu] if iu else None,
            data[:, iy],
            dt,
            time=None if tcol is None else data[:, tcol],
            nan=nan,
            max_gap=max_gap,
            **kw,
        )

    # ---------------------------------------------------------------- NPZ and MAT

    def _arrays(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "dt": self.dt,
            "t0": np.array([e.t0 for e in self._exps]),
            "input_names": np.array(self.input_names, dtype=str),
            "output_names": np.array(self.output_names, dtype=str),
            "input_units": np.array(self.input_units, dtype=str),
            "output_units": np.array(self.output_units, dtype=str),
            "n_experiments": self.n_experiments,
        }
        for k, e in enumerate(self._exps):
            out[f"u_{k}"] = e.u
            out[f"y_{k}"] = e.y
        return out

    @classmethod
    def _from_arrays(cls, get: Any, what: str) -> IOData:
        try:
            n = int(np.asarray(get("n_experiments")).ravel()[0])
            dt = float(np.asarray(get("dt")).ravel()[0])
            t0 = np.asarray(get("t0"), dtype=float).ravel()

            def strs(key: str) -> list[str]:
                out = []
                for s in np.asarray(get(key), dtype=object).ravel():
                    while isinstance(s, np.ndarray):  # MATLAB cells arrive nested
                        s = s.ravel()[0] if s.size else ""
                    out.append(str(s).strip())
                return out

            us = [np.asarray(get(f"u_{k}"), dtype=float) for k in range(n)]
            ys = [np.asarray(get(f"y_{k}"), dtype=float) for k in range(n)]
        except KeyError as e:
            raise DataError(f"{what} was not written by IOData (missing {e}); "
                            "read it with numpy or scipy.io and build IOData yourself") from None
        in_names = strs("input_names") if us[0].size and us[0].shape[-1] else []
        us = [u.reshape(len(y), len(in_names)) for u, y in zip(us, ys)]
        out_names = strs("output_names")
        ys = [y.reshape(-1, len(out_names)) for y in ys]
        return cls(
            us if in_names else None,
            ys,
            dt,
            time=[t + np.arange(len(y)) * dt for t, y in zip(t0, ys)],
            input_names=in_names,
            output_names=out_names,
            input_units=strs("input_units")[: len(in_names)] if in_names else [],
            output_units=strs("output_units")[: len(out_names)],
        )

    def to_npz(self, path: str | Path) -> None:
        """Save to a NumPy ``.npz`` archive (all experiments, names, units, dt, start times)."""
        np.savez(path, **self._arrays())

    @classmethod
    def from_npz(cls, path: str | Path) -> IOData:
        """Load a record saved by :meth:`to_npz`.

        Examples
        --------
        >>> import numpy as np, sysid, tempfile, os
        >>> d = sysid.IOData(u=np.ones((4, 2)), y=np.arange(4.0), dt=0.1, output_units=["m"])
        >>> f = os.path.join(tempfile.mkdtemp(), "rec.npz")
        >>> d.to_npz(f)
        >>> sysid.IOData.from_npz(f) == d
        True
        """
        with np.load(path, allow_pickle=False) as z:
            return cls._from_arrays(lambda k: z[k], str(path))

    def to_mat(self, path: str | Path) -> None:
        """Save to a MATLAB ``.mat`` file (``scipy.io.savemat``); one experiment also gets the
        plain variables ``u``, ``y``, ``dt`` that MATLAB users expect."""
        from scipy.io import savemat

        d = self._arrays()
        d = {k: (np.array(list(v), dtype=object) if k.endswith(("names", "units")) else v)
             for k, v in d.items()}
        if self.n_experiments == 1:
            d["u"], d["y"] = self._exps[0].u, self._exps[0].y
        savemat(path, d)

    @classmethod
    def from_mat(
        cls,
        path: str | Path,
        *,
        u: str = "u",
        y: str = "y",
        dt: float | str | None = None,
        input_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
    ) -> IOData:
        """Load a MATLAB ``.mat`` file: one written by :meth:`to_mat`, or any file with
        input/output matrices under the variable names ``u`` and ``y`` (samples in rows).

        ``dt`` may be a number or the name of a variable holding it.
        """
        from scipy.io import loadmat

        m = loadmat(path)
        if "n_experiments" in m and dt is None and u == "u" and y == "y":
            return cls._from_arrays(lambda k: m[k], str(path))
        if y not in m:
            have = sorted(k for k in m if not k.startswith("__"))
            raise DataError(f"no variable {y!r} in {path}; it holds {have}")
        if isinstance(dt, str):
            if dt not in m:
                raise DataError(f"no variable {dt!r} (sample time) in {path}")
            dt = float(np.asarray(m[dt]).ravel()[0])
        uu = m.get(u)
        yy = np.asarray(m[y], dtype=float)
        if yy.ndim == 2 and yy.shape[0] < yy.shape[1] and yy.shape[0] <= 16:
            raise DataError(
                f"{y!r} in {path} has shape {yy.shape}: samples must be rows; transpose it"
            )
        return cls(uu, yy, dt, input_names=input_names, output_names=output_names)


def _raw2d(x: Any, name: str) -> np.ndarray:
    arr = np.asarray(x)
    if arr.dtype.kind not in "biuf":
        raise DataError(f"{name} must be a real numeric array, got dtype {arr.dtype}")
    arr = arr.astype(np.float64)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] == 0:
        raise ShapeError(f"{name} must be a non-empty (samples, channels) array, got {arr.shape}")
    return arr


def _pandas() -> Any:
    try:
        import pandas as pd
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("this needs pandas: pip install 'sysid[pandas]'") from e
    return pd


# --------------------------------------------------------------------------------------------
# Trend and summary
# --------------------------------------------------------------------------------------------


class Trend:
    """What pre-processing removed from a record, so that it can be added back.

    Per channel, ``original = scale * processed + trend``, with the trend a value per sample
    of every experiment (offsets, lines, piecewise lines) and one scale per channel.
    Obtained from :attr:`IOData.trend`.

    Attributes
    ----------
    u_trend, y_trend : list of ndarray
        Per experiment, shaped like its ``u`` and ``y``.
    u_scale, y_scale : ndarray
        One factor per input and output channel.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.ones(4), y=np.full(4, 3.0))
    >>> tr = sysid.detrend(d, "mean").trend
    >>> tr.add_outputs(np.zeros((4, 1))).ravel()
    array([3., 3., 3., 3.])
    """

    def __init__(
        self,
        u_trend: list[np.ndarray],
        y_trend: list[np.ndarray],
        u_scale: np.ndarray,
        y_scale: np.ndarray,
    ) -> None:
        self.u_trend = u_trend
        self.y_trend = y_trend
        self.u_scale = u_scale
        self.y_scale = y_scale

    def add_outputs(self, y: Any, experiment: int = 0, start: int = 0) -> np.ndarray:
        """Map model outputs (in processed units) of one experiment back to original units.

        Parameters
        ----------
        y : array_like
            ``(n, n_outputs)``, e.g. a model's simulation of experiment ``experiment``.
        experiment : int
            Which experiment's trend to add.
        start : int
            Sample of the experiment where ``y`` begins.
        """
        arr = as_2d(y, "y", ncols=len(self.y_scale))
        tr = self.y_trend[experiment]
        if start < 0 or start + arr.shape[0] > tr.shape[0]:
            raise ShapeError(
                f"y covers samples {start}..{start + arr.shape[0] - 1} but experiment "
                f"{experiment} has {tr.shape[0]}"
            )
        return arr * self.y_scale + tr[start : start + arr.shape[0]]

    def add_inputs(self, u: Any, experiment: int = 0, start: int = 0) -> np.ndarray:
        """Map inputs in processed units back to original units (as :meth:`add_outputs`)."""
        arr = as_2d(u, "u", ncols=len(self.u_scale))
        tr = self.u_trend[experiment]
        if start < 0 or start + arr.shape[0] > tr.shape[0]:
            raise ShapeError(f"u does not fit inside experiment {experiment}")
        return arr * self.u_scale + tr[start : start + arr.shape[0]]

    def __repr__(self) -> str:
        return (
            f"Trend({len(self.y_trend)} experiment(s), input scale {np.round(self.u_scale, 6)}, "
            f"output scale {np.round(self.y_scale, 6)})"
        )


@dataclass
class DataSummary:
    """Per-channel statistics of a record (from :meth:`IOData.summary`)."""

    title: str
    rows: list[dict[str, Any]]
    lengths: list[int]
    dt: float

    def to_pandas(self) -> Any:
        """The table as a DataFrame indexed by channel."""
        return _pandas().DataFrame(self.rows).set_index("channel")

    def __repr__(self) -> str:
        head = f"{'channel':<14}{'kind':<8}{'unit':<8}" + "".join(
            f"{k:>12}" for k in ("mean", "std", "min", "max", "rms")
        )
        lines = [self.title, head]
        for r in self.rows:
            lines.append(
                f"{r['channel'][:13]:<14}{r['kind']:<8}{r['unit'][:7]:<8}"
                + "".join(f"{r[k]:>12.4g}" for k in ("mean", "std", "min", "max", "rms"))
            )
        if len(self.lengths) > 1:
            lines.append(f"experiment lengths: {self.lengths}")
        return "\n".join(lines)
