"""Step-response characteristics with MATLAB's definitions (``stepinfo``).

For a response ``y(t)`` from ``y_init`` to ``y_final`` (``dy = y_final - y_init``):

- rise time: from ``y_init + 0.1 dy`` to ``y_init + 0.9 dy`` (first crossings, linearly
  interpolated between samples; ``rise_limits``);
- settling time: the last time ``|y - y_final|`` exceeds ``2 % |dy|`` (``threshold``),
  interpolated; transient time the same with ``2 %`` of the largest ``|y - y_final|``;
- settling min/max: extremes of ``y`` after the rise;
- overshoot: ``100 (max y - y_final) / dy`` (>= 0, on the side of ``dy``); undershoot:
  ``100 (y_init - min y) / dy`` in the other direction;
- peak: largest ``|y - y_init|`` and its time.

A model's step response is computed on a fine grid (continuous models exactly sampled) and
``y_final`` is its steady-state gain. Every step starts from rest: ``y_init`` is 0 by default
(MATLAB's ``stepinfo(y, t)`` too), not the first sample, which a direct term lifts off 0; a
model's :class:`~sysid.TimeResponse` (``sysid.step(G)``) ends at the model's steady-state gain,
not at its last sample.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_int
from ..errors import DataError, NonFiniteError, NumericalError

__all__ = ["stepinfo", "StepInfo"]

_KEYS = ("rise_time", "transient_time", "settling_time", "settling_min", "settling_max",
         "overshoot", "undershoot", "peak", "peak_time", "steady_state")


class StepInfo:
    """Step-response characteristics of each output/input pair (see :func:`stepinfo`).

    Attributes are arrays ``(noutputs, ninputs)``; for one pair, floats. ``as_dict()`` gives
    MATLAB's field names (``RiseTime``, ``SettlingTime``, ...).
    """

    def __init__(self, values: dict[str, np.ndarray], output_names: Any = None,
                 input_names: Any = None) -> None:
        self._v = values
        l, m = values["rise_time"].shape
        #: the channels' names (the model's or the response's; ``y0..``/``u0..`` for arrays)
        self.output_names = list(output_names) if output_names is not None else \
            [f"y{i}" for i in range(l)]
        self.input_names = list(input_names) if input_names is not None else \
            [f"u{j}" for j in range(m)]
        single = values["rise_time"].size == 1
        for k, v in values.items():
            setattr(self, k, float(v.ravel()[0]) if single else v)

    def as_dict(self) -> dict[str, Any]:
        """MATLAB's field names and values."""
        names = {"rise_time": "RiseTime", "transient_time": "TransientTime",
                 "settling_time": "SettlingTime", "settling_min": "SettlingMin",
                 "settling_max": "SettlingMax", "overshoot": "Overshoot",
                 "undershoot": "Undershoot", "peak": "Peak", "peak_time": "PeakTime",
                 "steady_state": "SteadyStateValue"}
        return {names[k]: getattr(self, k) for k in _KEYS}

    def to_pandas(self) -> Any:
        """One row per output/input pair."""
        import pandas as pd

        l, m = self._v["rise_time"].shape
        rows = [{"output": self.output_names[i], "input": self.input_names[j],
                 **{k: float(self._v[k][i, j]) for k in _KEYS}}
                for i in range(l) for j in range(m)]
        return pd.DataFrame(rows)

    def summary(self) -> str:
        """One line per output/input pair with every characteristic.

        Examples
        --------
        >>> import sysid
        >>> s = sysid.stepinfo(sysid.TransferFunction([1.0], [1.0, 1.0])).summary()
        >>> s.splitlines()[1].split()[:2]
        ['y0', '<-']
        """
        df = self.to_pandas()
        lines = [repr(self) if self._v["rise_time"].size > 1 else "StepInfo"]
        for _, r in df.iterrows():
            lines.append(f"  {r['output']} <- {r['input']}: "
                         + ", ".join(f"{k} {r[k]:.4g}" for k in _KEYS))
        return "\n".join(lines)

    def __repr__(self) -> str:
        if self._v["rise_time"].size == 1:
            return "StepInfo(" + ", ".join(f"{k}={getattr(self, k):.4g}" for k in _KEYS) + ")"
        return f"StepInfo({self._v['rise_time'].shape[0]} x {self._v['rise_time'].shape[1]})"


def _cross(t: np.ndarray, y: np.ndarray, level: float, sign: float) -> float:
    """First time ``sign * (y - level) >= 0``, interpolated linearly."""
    idx = np.flatnonzero(sign * (y - level) >= 0)
    if idx.size == 0:
        return float("nan")
    k = int(idx[0])
    if k == 0:
        return float(t[0])
    y0, y1 = y[k - 1], y[k]
    return float(t[k - 1] + (level - y0) / (y1 - y0) * (t[k] - t[k - 1]))


def _settle(t: np.ndarray, e: np.ndarray, bound: float) -> float:
    """Time after which ``e <= bound`` for good (interpolated on the last exit)."""
    out = np.flatnonzero(e > bound)
    if out.size == 0:
        return float(t[0])
    k = int(out[-1])
    if k == t.size - 1:
        return float("nan")
    e0, e1 = e[k], e[k + 1]
    return float(t[k] + (e0 - bound) / (e0 - e1) * (t[k + 1] - t[k]))


def _one(t: np.ndarray, y: np.ndarray, yinit: float, yfinal: float, thr: float,
         lim: tuple[float, float]) -> dict[str, float]:
    dy = yfinal - yinit
    if not np.isfinite(yfinal) or dy == 0:
        nan = float("nan")
        k = int(np.argmax(np.abs(y - yinit)))
        # an unbounded response (integrator, unstable): no peak, as MATLAB says (Inf)
        peak, when = ((float(abs(y[k] - yinit)), float(t[k])) if np.isfinite(yfinal)
                      else (float("inf"), float("inf")))
        return {"rise_time": nan, "transient_time": nan, "settling_time": nan,
                "settling_min": nan, "settling_max": nan, "overshoot": nan,
                "undershoot": nan, "peak": peak, "peak_time": when,
                "steady_state": float(yfinal)}
    s = np.sign(dy)
    t_lo = _cross(t, y, yinit + lim[0] * dy, s)
    t_hi = _cross(t, y, yinit + lim[1] * dy, s)
    e = np.abs(y - yfinal)
    after = y[np.searchsorted(t, t_hi):] if np.isfinite(t_hi) else y[-1:]
    k = int(np.argmax(np.abs(y - yinit)))
    return {
        "rise_time": t_hi - t_lo,
        "transient_time": _settle(t, e, thr * float(np.max(e))),
        "settling_time": _settle(t, e, thr * abs(dy)),
        "settling_min": float(np.min(after)), "settling_max": float(np.max(after)),
        "overshoot": max(0.0, 100.0 * float(np.max(s * (y - yfinal))) / abs(dy)),
        "undershoot": max(0.0, 100.0 * float(np.max(-s * (y - yinit))) / abs(dy)),
        "peak": float(abs(y[k] - yinit)), "peak_time": float(t[k]),
        "steady_state": float(yfinal),
    }


def stepinfo(sys: Any, t: Any = None, *, yfinal: Any = None, yinit: Any = None,
             threshold: float = 0.02, rise_limits: tuple[float, float] = (0.1, 0.9),
             n_samples: int = 4000) -> StepInfo:
    """Rise time, settling time, overshoot and peak of a step response (MATLAB's
    ``stepinfo``).

    Parameters
    ----------
    sys : model, TimeResponse or array_like
        A sysid model (its step response is computed), a
        :class:`~sysid.models.protocol.TimeResponse` from ``step``, or samples ``y``
        (``(n,)`` or ``(n, outputs)``) with their times ``t``.
    t : array_like, optional
        Sample times of ``y`` (needed for arrays).
    yfinal : float or array_like, optional
        Steady-state value (default: the model's steady-state gain, also for the step
        response of a linear model; the last sample for samples or other responses).
    yinit : float or array_like, optional
        The value before the step (default 0, as MATLAB's: a response from rest; its first
        sample is not it when a direct term makes the output jump). Pass ``y[0]`` for a
        record that starts off zero.
    threshold : float
        Settling band as a fraction (MATLAB's ``SettlingTimeThreshold``, 2 %).
    rise_limits : (float, float)
        Rise-time fractions (MATLAB's ``RiseTimeLimits``).
    n_samples : int
        Grid size of a model's step response.

    Returns
    -------
    StepInfo
        The characteristics per output/input pair. A model whose step does not settle (an
        integrator, or any unstable pole, as MATLAB has it) has every characteristic NaN
        but ``peak`` and ``peak_time``, which are ``inf``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> info = sysid.stepinfo(sysid.TransferFunction([1.0], [1.0, 1.0]))   # 1 / (s + 1)
    >>> round(info.rise_time, 4), round(info.settling_time, 4)     # ln 9, ln 50
    (2.1972, 3.912)
    >>> round(sysid.stepinfo(sysid.TransferFunction([1.0], [1.0, 0.6, 1.0])).overshoot, 2)
    37.23

    A direct term: ``(s + 3) / (s + 1)`` jumps to 1 and rises from rest (0) to 3, over
    ``ln(2 / 0.3)`` from 10 % to 90 %, as its step response (a ``TimeResponse``) says too:

    >>> G = sysid.TransferFunction([1.0, 3.0], [1.0, 1.0])
    >>> round(sysid.stepinfo(sysid.step(G)).rise_time, 3), round(float(np.log(2 / 0.3)), 3)
    (1.897, 1.897)
    """
    if not 0 < threshold < 1:
        raise DataError(f"threshold must lie in (0, 1), got {threshold}")
    lo, hi = float(rise_limits[0]), float(rise_limits[1])
    if not 0 <= lo < hi <= 1:
        raise DataError(f"rise_limits must satisfy 0 <= low < high <= 1, got {rise_limits}")
    tt, Y, yf, yi = _response(sys, t, as_int(n_samples, "n_samples", 2))
    l, m = Y.shape[1], Y.shape[2]
    yf = _fill(yfinal, (l, m), "yfinal") if yfinal is not None else yf
    yi = _fill(yinit, (l, m), "yinit") if yinit is not None else yi
    out = {k: np.empty((l, m)) for k in _KEYS}
    for i in range(l):
        for j in range(m):
            for k, v in _one(tt, Y[:, i, j], yi[i, j], yf[i, j], threshold, (lo, hi)).items():
                out[k][i, j] = v
    names = getattr(sys, "output_names", None), getattr(sys, "input_names", None)
    ok = [n if n is not None and len(n) == size else None for n, size in zip(names, (l, m))]
    return StepInfo(out, *ok)


def _fill(x: Any, shape: tuple[int, int], name: str) -> np.ndarray:
    try:
        out = np.broadcast_to(np.asarray(x, dtype=float), shape).copy()
    except (TypeError, ValueError):
        raise DataError(f"{name} must be one number or an array {shape}") from None
    if not np.isfinite(out).all():
        raise NonFiniteError(f"{name} must be finite, got {x!r}; leave it out for the "
                             "default")
    return out


def _response(sys: Any, t: Any, n: int
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    from ..models.protocol import TimeResponse

    if isinstance(sys, TimeResponse):   # a response from rest: it starts at 0
        Y = np.asarray(sys.y, dtype=float)
        return np.asarray(sys.t, float), Y, _response_final(sys, Y), np.zeros(Y.shape[1:])
    if hasattr(sys, "freqresp") and hasattr(sys, "dt"):
        return _model_step(sys, n)
    if t is None:
        raise DataError("stepinfo of samples needs their times t: stepinfo(y, t)")
    y = np.asarray(sys, dtype=float)
    if y.ndim == 1:
        y = y[:, None]
    if y.ndim != 2:
        raise DataError(f"y must be (n_samples,) or (n_samples, outputs), got shape {y.shape}")
    tt = np.asarray(t, dtype=float).ravel()
    if tt.size != y.shape[0] or tt.size < 2 or np.any(np.diff(tt) <= 0):
        raise DataError(f"t must be increasing with one time per sample ({y.shape[0]}), got "
                        f"{tt.size} values")
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(tt))):
        raise DataError("y and t must be finite")
    Y = y[:, :, None]
    return tt, Y, Y[-1], np.zeros(Y.shape[1:])


def _response_final(resp: Any, Y: np.ndarray) -> np.ndarray:
    """The final value of a :class:`~sysid.TimeResponse`: its linear model's steady-state gain
    for a step response (``inf`` when it does not settle), else its last sample."""
    src = getattr(resp, "model", None)
    if (resp.kind != "step" or not (hasattr(src, "freqresp") and hasattr(src, "poles"))
            or _nonlinear(src)):
        return Y[-1].copy()
    try:
        p = np.asarray(src.poles())
    except (DataError, np.linalg.LinAlgError, NumericalError):
        return Y[-1].copy()
    if Y.shape[1:] != (getattr(src, "noutputs", -1), getattr(src, "ninputs", -1)):
        return Y[-1].copy()
    return _final_value(src, Y.shape[1:], _unstable(p, float(getattr(src, "dt", 0.0) or 0.0)))


def _unstable(p: np.ndarray, dt: float) -> bool:
    """A pole outside the unit circle (``dt > 0``) or in the right half plane."""
    if dt > 0:
        return bool(p.size and np.max(np.abs(p)) > 1.0 + 1e-9)
    return bool(np.any(p.real > 1e-9 * np.maximum(1.0, np.abs(p))))


def _nonlinear(sys: Any) -> bool:
    """A nonlinear model (its ``freqresp`` is its linear part's or its linearisation's)."""
    return (not getattr(sys, "statespace_is_exact", True)
            or type(sys).__module__.startswith(("sysid.nonlinear.", "sysid.nlss.")))


def _final_value(sys: Any, shape: tuple[int, ...], unstable: bool) -> np.ndarray:
    """The step's final value: the model's DC gain (a pole at ``s = 0`` or ``z = 1`` that a
    zero cancels leaves it finite), ``inf`` when an integrator makes the step unbounded or
    the model is unstable (MATLAB: every characteristic NaN, the peak and its time Inf; the
    DC gain of an unstable model is no value its step tends to)."""
    if unstable:
        return np.full(shape, np.inf)
    try:
        gain = sys.dcgain() if hasattr(sys, "dcgain") else sys.freqresp([0.0])[0].real
        gain = np.asarray(gain, dtype=float).reshape(shape)
    except (np.linalg.LinAlgError, NumericalError):
        return np.full(shape, np.inf)
    return np.where(np.isnan(gain), np.inf, gain)


def _model_step(sys: Any, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    p = np.asarray(sys.poles()) if hasattr(sys, "poles") else np.zeros(0)
    delay = float(np.max(getattr(sys, "iodelay", 0.0), initial=0.0))
    if sys.dt and sys.dt > 0:
        r = np.abs(p)
        rho = float(np.max(r)) if r.size else 0.0
        N = 200 if rho >= 1 or rho == 0 else int(np.ceil(np.log(1e-4) / np.log(rho))) + 10
        N = int(min(max(N, 20), 100000)) + int(delay)
        nonlinear = _nonlinear(sys)
        if nonlinear:
            N *= 2  # its step's end (its linear part's poles only estimate its settling)
        resp = sys.step(N)
        Y = np.asarray(resp.y)
        if nonlinear:
            # the response's own final value: the linear part's (or the linearisation's)
            # static gain is not the nonlinear model's (0.909 for a step that ends at 0.934)
            return np.asarray(resp.t, float), Y, Y[-1].copy(), np.zeros_like(Y[-1])
        gain = _final_value(sys, Y.shape[1:], _unstable(p, float(sys.dt)))
        return np.asarray(resp.t, float), Y, gain, np.zeros_like(gain)
    re = -p.real
    slow = float(np.min(re[re > 1e-12])) if np.any(re > 1e-12) else 0.0
    if slow == 0.0 or np.any(re < -1e-12):
        t_final = 100.0 if slow == 0.0 else 10.0 / slow
    else:
        t_final = 10.0 / slow + 1.2 * delay
    resp = sys.step(n, dt=t_final / (n - 1))
    gain = _final_value(sys, resp.y.shape[1:], _unstable(p, 0.0))
    return np.asarray(resp.t, float), np.asarray(resp.y), gain, np.zeros_like(gain)
