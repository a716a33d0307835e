"""What pre-processing removed from a record (:class:`Trend`), so that it can be added back,
and applied to other records (MATLAB's ``getTrend``/``retrend``).

``d, tr = sysid.detrend(data, "linear", return_trend=True)`` returns, besides the detrended
record, the offsets and slopes it removed. ``tr.apply(validation)`` removes the *estimation*
record's offsets and slopes from another record (validation data must be treated like the
estimation data, not detrended on their own), ``tr.restore(...)`` adds them back to a record
or to model outputs, and ``tr.attach(model)`` gives a model that takes and returns raw data
(:class:`~sysid.models.trended.TrendedModel`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_2d
from ..errors import DataError, ShapeError

__all__ = ["Trend"]


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
    kind : {"mean", "linear"} or None
        With ``detrend(..., return_trend=True)``: what was removed, as offsets and slopes
        that apply to other records (None: only the per-sample values above).
    u_offset, y_offset, u_slope, y_slope : ndarray or None
        Per channel: the removed trend is ``offset + slope * t``, ``t`` in seconds from the
        first sample of each experiment (slopes are zero for ``"mean"``); several
        experiments give their sample-weighted average.
    dt : float or None
        Sample time of the record the trend was fitted on.
    t0 : float or None
        Start time (s) of the record the trend was fitted on (one experiment); ``None`` for
        several experiments. :meth:`apply` evaluates the line at another record's own
        instants on this clock, so the validation part of the same record (from
        :meth:`IOData.split` or :meth:`IOData.slice`, which keep the start time) gets the
        line where it is, not restarted at its first sample.

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
        *,
        kind: str | None = None,
        offsets: tuple[np.ndarray, np.ndarray] | None = None,
        slopes: tuple[np.ndarray, np.ndarray] | None = None,
        dt: float | None = None,
        t0: float | None = None,
    ) -> None:
        self.u_trend = u_trend
        self.y_trend = y_trend
        self.u_scale = u_scale
        self.y_scale = y_scale
        self.kind = kind
        self.u_offset, self.y_offset = offsets if offsets is not None else (None, None)
        self.u_slope, self.y_slope = slopes if slopes is not None else (None, None)
        self.dt = dt
        self.t0 = t0

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
        tr = self._record_values("y", experiment)
        if start < 0 or start + arr.shape[0] > tr.shape[0]:
            raise ShapeError(
                f"y covers samples {start}..{start + arr.shape[0] - 1} but experiment "
                f"{experiment} has {tr.shape[0]}"
            )
        return arr * self.y_scale + tr[start : start + arr.shape[0]]

    def add_inputs(self, u: Any, experiment: int = 0, start: int = 0) -> np.ndarray:
        """Map inputs in processed units back to original units (as :meth:`add_outputs`)."""
        arr = as_2d(u, "u", ncols=len(self.u_scale))
        tr = self._record_values("u", experiment)
        if start < 0 or start + arr.shape[0] > tr.shape[0]:
            raise ShapeError(f"u does not fit inside experiment {experiment}")
        return arr * self.u_scale + tr[start : start + arr.shape[0]]

    # -- applying the estimation record's trend to other data (getTrend / retrend) ----------
    def _parametric(self) -> None:
        if self.kind is None or self.u_offset is None:
            raise DataError(
                "this Trend holds per-sample values of one record only; get one that applies "
                "to other data with d, trend = sysid.detrend(data, 'mean' or 'linear', "
                "return_trend=True)")

    def values(self, n: int, which: str = "y", dt: float | None = None,
               start: float = 0.0) -> np.ndarray:
        """The trend ``offset + slope * t`` over ``n`` samples from ``t = start`` (seconds
        after the first sample of the record it was fitted on), for the outputs
        (``which="y"``) or inputs (``"u"``), shape ``(n, channels)``."""
        self._parametric()
        off, slope = (self.y_offset, self.y_slope) if which == "y" else (self.u_offset,
                                                                          self.u_slope)
        step = float(dt if dt is not None else (self.dt or 1.0))
        t = float(start) + np.arange(n)[:, None] * step
        return np.asarray(off)[None, :] + t * np.asarray(slope)[None, :]

    def remove_inputs(self, u: Any, dt: float | None = None) -> np.ndarray:
        """Raw inputs ``(n, n_inputs)`` minus the trend (what a model fitted on the detrended
        record expects)."""
        arr = as_2d(u, "u", ncols=len(self.u_scale))
        return (arr - self.values(arr.shape[0], "u", dt)) / self.u_scale

    def remove_outputs(self, y: Any, dt: float | None = None) -> np.ndarray:
        """Raw outputs ``(n, n_outputs)`` minus the trend."""
        arr = as_2d(y, "y", ncols=len(self.y_scale))
        return (arr - self.values(arr.shape[0], "y", dt)) / self.y_scale

    def restore_outputs(self, y: Any, dt: float | None = None,
                        start: float = 0.0) -> np.ndarray:
        """Detrended (model) outputs ``(n, n_outputs)`` plus the trend (from ``t = start``,
        as :meth:`values`): raw units."""
        arr = as_2d(y, "y", ncols=len(self.y_scale))
        return arr * self.y_scale + self.values(arr.shape[0], "y", dt, start)

    def start_of(self, t0: float) -> float:
        """Where on this trend's line a record (experiment) that starts at time ``t0``
        begins: ``t0 - self.t0`` on the estimation record's clock, 0 without one."""
        return 0.0 if self.t0 is None else float(t0) - self.t0

    def apply(self, data: Any) -> Any:
        """Another record with *this* trend removed (MATLAB: ``detrend(z, T)``).

        Validation data must be processed like the estimation data: subtract the estimation
        record's offsets (and slopes), not their own mean. A line is evaluated at the
        record's own instants on the estimation record's clock (each experiment's start time,
        :attr:`t0`): the validation part of the same record continues the line, where a
        record with the estimation record's start time (the default 0 for both) starts it
        again. The result remembers what was removed, so ``tr.apply(v).retrend()`` is ``v``.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> est = sysid.IOData(u=[1.0, 3.0], y=[10.0, 14.0])
        >>> d, tr = sysid.detrend(est, "mean", return_trend=True)
        >>> v = tr.apply(sysid.IOData(u=[2.0, 2.0], y=[12.0, 13.0]))
        >>> np.round(v.u, 12).ravel().tolist(), np.round(v.y, 12).ravel().tolist()
        ([0.0, 0.0], [0.0, 1.0])
        >>> np.round(v.retrend().y, 12).ravel().tolist()
        [12.0, 13.0]
        >>> line = sysid.IOData(u=np.zeros(6), y=np.arange(6.0))   # one record, split
        >>> _, tr = sysid.detrend(line.slice(0, 3), "linear", return_trend=True)
        >>> bool(np.allclose(tr.apply(line.slice(3, 6)).y, 0.0))
        True
        """
        self._parametric()
        if data.n_inputs != len(self.u_scale) or data.n_outputs != len(self.y_scale):
            raise ShapeError(
                f"the trend has {len(self.u_scale)} input(s) and {len(self.y_scale)} output(s) "
                f"but the data have {data.n_inputs} and {data.n_outputs}")
        def trend_of(n: int, t0: float) -> tuple[np.ndarray, np.ndarray]:
            start = self.start_of(t0)
            return (self.values(n, "u", data.dt, start), self.values(n, "y", data.dt, start))
        out = data._minus_trend(trend_of)
        mine = (np.asarray(self.u_scale, float), np.asarray(self.y_scale, float))
        theirs = (np.asarray(data._u_scale, float), np.asarray(data._y_scale, float))
        if all(np.array_equal(a, b) for a, b in zip(mine, theirs)):
            return out
        if all(np.all(b == 1.0) for b in theirs):  # scaled like the estimation record
            return out._scaled(*mine)
        raise DataError("this record is scaled differently from the one the trend was fitted "
                        "on; apply the trend to the unscaled record")

    def restore(self, x: Any, t0: float | None = None) -> Any:
        """Add this trend back: to a record (:class:`~sysid.IOData`, like ``retrend``) or to
        model outputs (an array ``(n, n_outputs)``). An array has no clock: its first sample
        is at ``t0`` on the estimation record's clock (a validation record's ``time[0]``, as
        :meth:`apply` takes it), by default where the trend starts; without it a model's
        simulation of the second half of a drifting record came back off by the drift over
        the first half.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> d, tr = sysid.detrend(sysid.IOData(u=[1.0, 3.0], y=[10.0, 14.0]), "mean",
        ...                       return_trend=True)
        >>> np.round(tr.restore(np.zeros((2, 1))), 12).ravel().tolist()
        [12.0, 12.0]
        """
        if hasattr(x, "experiments"):
            return x.retrend()
        return self.restore_outputs(x, start=0.0 if t0 is None else self.start_of(t0))

    def attach(self, model: Any) -> Any:
        """``model`` (fitted on the detrended record) wrapped to take and return raw data:
        a :class:`~sysid.models.trended.TrendedModel`."""
        from ..models.trended import TrendedModel

        self._parametric()
        return TrendedModel(model, self)

    def to_dict(self) -> dict[str, Any]:
        """What applies to other data (kind, offsets, slopes, scales, sample and start time),
        for saving with a :class:`~sysid.models.trended.TrendedModel`; the per-sample values
        of the record it was fitted on are not kept (:meth:`add_outputs` needs the record).

        Examples
        --------
        >>> import numpy as np, sysid
        >>> d, tr = sysid.detrend(sysid.IOData(u=[1.0, 3.0], y=[10.0, 14.0]), "linear",
        ...                       return_trend=True)
        >>> back = sysid.Trend.from_dict(tr.to_dict())
        >>> np.round(back.restore_outputs(np.zeros((2, 1))), 9).ravel().tolist()
        [10.0, 14.0]
        """
        self._parametric()
        return {"kind": self.kind, "u_offset": np.asarray(self.u_offset, float),
                "y_offset": np.asarray(self.y_offset, float),
                "u_slope": np.asarray(self.u_slope, float),
                "y_slope": np.asarray(self.y_slope, float),
                "u_scale": np.asarray(self.u_scale, float),
                "y_scale": np.asarray(self.y_scale, float), "dt": self.dt, "t0": self.t0}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Trend:
        """Inverse of :meth:`to_dict` (a trend that applies to other data, without the
        fitted record's per-sample values)."""
        def vec(k: str) -> np.ndarray:
            return np.asarray(d[k], float).ravel()
        if d["kind"] not in ("mean", "linear"):
            raise DataError(f"a saved trend's kind must be 'mean' or 'linear', got {d['kind']!r}")
        return cls([], [], vec("u_scale"), vec("y_scale"), kind=str(d["kind"]),
                   offsets=(vec("u_offset"), vec("y_offset")),
                   slopes=(vec("u_slope"), vec("y_slope")),
                   dt=None if d.get("dt") is None else float(d["dt"]),
                   t0=None if d.get("t0") is None else float(d["t0"]))

    def _record_values(self, which: str, experiment: int) -> np.ndarray:
        """The fitted record's per-sample trend of one experiment."""
        values = self.y_trend if which == "y" else self.u_trend
        if not values:
            raise DataError("this Trend holds no per-sample values (it was loaded with a saved "
                            "model: only its offsets and slopes); use restore_outputs or "
                            "apply, which evaluate the line on any record")
        if not 0 <= experiment < len(values):
            raise DataError(f"experiment must be 0..{len(values) - 1}, got {experiment}")
        return values[experiment]

    def __repr__(self) -> str:
        if self.kind is not None and self.u_offset is not None:
            return (f"Trend({self.kind}, input offset {np.round(self.u_offset, 6)}, output "
                    f"offset {np.round(self.y_offset, 6)}"
                    + (f", output slope {np.round(self.y_slope, 6)} per s"
                       if self.kind == "linear" else "") + ")")
        return (
            f"Trend({len(self.y_trend)} experiment(s), input scale {np.round(self.u_scale, 6)}, "
            f"output scale {np.round(self.y_scale, 6)})"
        )


def _register() -> None:
    from ..models.serialize import register_model

    register_model(Trend)  # saved inside a TrendedModel


_register()
