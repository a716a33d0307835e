"""The model protocol: what every sysid model offers, and defaults written once.

Every model family (:class:`~sysid.StateSpaceModel`, :class:`~sysid.ContinuousStateSpace`,
:class:`~sysid.PolynomialModel`, and any class of your own) satisfies :class:`Model`, so
:func:`sysid.compare`, :func:`sysid.residuals`, :func:`sysid.error_spectrum`,
:func:`sysid.criteria`, :func:`sysid.select_order`, the plots, :func:`sysid.report` and
:func:`sysid.save_model` work on all of them.

Required members
----------------
``simulate(u, x0=None)``
    Noise-free output ``(n_samples, noutputs)`` for inputs ``(n_samples, ninputs)``.
``predict(u, y, horizon=1)``
    ``horizon``-step-ahead prediction ``yhat(t | t - horizon)`` from measured ``u`` and ``y``.
``freqresp(omega)``
    Complex response ``(len(omega), noutputs, ninputs)`` at angular frequencies (rad/s).
``dt``
    Sample time in seconds; ``0.0`` for a continuous-time model (python-control's convention).
``ninputs``, ``noutputs``, ``input_names``, ``output_names``
    Channel counts and names.
``n_parameters``
    Number of free (identifiable) parameters, used by the information criteria.
``info``
    A dict saying how the model was obtained.

Optional members
----------------
``poles()``, ``zeros()``
    Poles and (transmission) zeros, discrete ``z`` or continuous ``s``.
``to_statespace()``
    An equivalent :class:`~sysid.StateSpaceModel`; functions needing state-space internals
    (initial-state estimation, damping) go through it.
``nstates`` with ``simulate(u, x0=array)``
    A model with a state can have its initial state estimated by :func:`sysid.compare`.
``to_dict()`` / ``from_dict(d)``
    Saving; see :func:`sysid.register_model`.

:class:`ModelMixin` gives ``predict`` (through ``to_statespace()``), ``poles``, ``zeros``,
``step`` and ``impulse`` to a class that defines the rest.

Examples
--------
A finite-impulse-response model in a few lines satisfies the protocol:

>>> import numpy as np, sysid
>>> class FIR(sysid.ModelMixin):
...     def __init__(self, h, dt=1.0):
...         self.h, self.dt, self.info = np.asarray(h, float), dt, {"method": "fir"}
...         self.ninputs = self.noutputs = 1
...         self.input_names, self.output_names = ["u0"], ["y0"]
...     n_parameters = property(lambda self: self.h.size)
...     def simulate(self, u, x0=None):
...         u = np.asarray(u, float).reshape(-1)
...         return np.convolve(u, self.h)[: u.size, None]
...     def predict(self, u, y, horizon=1):
...         return self.simulate(u)
...     def freqresp(self, omega):
...         z = np.exp(-1j * np.outer(omega, np.arange(self.h.size)) * self.dt)
...         return (z @ self.h)[:, None, None]
>>> isinstance(FIR([0.0, 1.0, 0.5]), sysid.Model)
True
>>> FIR([0.0, 1.0, 0.5]).step(4).y[:, 0, 0]
array([0. , 1. , 1.5, 1.5])
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol, runtime_checkable

import numpy as np

from ..errors import DataError
from .checks import REQUIRED, _optional, as_statespace, check_model
from .subsystem import ChannelSelection

__all__ = ["Model", "ModelMixin", "REQUIRED", "check_model", "as_statespace", "TimeResponse",
           "no_pole_std"]


def no_pole_std(model: Any, std: Any) -> None:
    """Refuse ``poles(std=True)`` on a model that carries no pole uncertainty (nonlinear
    models: their poles are the linear part's or the linearisation's) with a named error,
    not a TypeError for an unknown keyword.

    Examples
    --------
    >>> from sysid.models.protocol import no_pole_std
    >>> no_pole_std(object(), False)  # nothing asked, nothing to refuse
    """
    if std:
        raise DataError(
            f"{type(model).__name__}.poles(std=True): this model carries no pole "
            "uncertainty (its poles are those of its linear part or linearisation); fit a "
            "linear model (sysid.ssest, sysid.pem) for poles with standard deviations")


@runtime_checkable
class Model(Protocol):
    """The interface every sysid model satisfies (see the module documentation).

    ``isinstance(obj, sysid.Model)`` checks that the members exist.

    Examples
    --------
    >>> import sysid
    >>> isinstance(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), sysid.Model)
    True
    >>> isinstance(sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]]), sysid.Model)
    True
    """

    @property
    def dt(self) -> float:
        """Sample time in seconds (``0.0``: continuous time)."""

    @property
    def ninputs(self) -> int:
        """Number of inputs."""

    @property
    def noutputs(self) -> int:
        """Number of outputs."""

    @property
    def input_names(self) -> Sequence[str]:
        """Input channel names."""

    @property
    def output_names(self) -> Sequence[str]:
        """Output channel names."""

    @property
    def n_parameters(self) -> int:
        """Number of free parameters."""

    @property
    def info(self) -> dict[str, Any]:
        """How the model was obtained."""

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        """Noise-free output ``(n_samples, noutputs)``."""

    def predict(self, u: Any, y: Any = None, horizon: int = 1) -> np.ndarray:
        """``horizon``-step-ahead prediction ``(n_samples, noutputs)`` from measured ``u``,
        ``y`` (or a record in ``u``'s place)."""

    def freqresp(self, omega: Any) -> np.ndarray:
        """Complex frequency response ``(len(omega), noutputs, ninputs)``."""


# -- time responses ---------------------------------------------------------------------
class TimeResponse:
    """Step or impulse response: ``y[t, i, j]`` is output i for input j at time ``t[t]``.

    Examples
    --------
    >>> import sysid
    >>> sysid.step(sysid.StateSpaceModel([[0.5]], [[0.5]], [[1.0]]), 3)
    TimeResponse(step, 3 samples, 1 output(s) x 1 input(s))
    """

    def __init__(self, kind: str, t: np.ndarray, y: np.ndarray, model: Any,
                 std: np.ndarray | None = None) -> None:
        self.kind, self.t, self.y = kind, t, y
        self.std = std  # first-order std of y (step(..., std=True)); plotted as bands
        #: what it is the response of (``stepinfo`` reads a model's steady-state gain there)
        self.model = model
        self.input_names, self.output_names = list(model.input_names), list(model.output_names)
        #: the response of a continuous-time model (plotted as a line, not a staircase)
        self.continuous = not float(getattr(model, "dt", 1.0) or 0.0) > 0

    def plot(self, fig: Any = None) -> Any:
        """One axis per (output, input) pair; returns the figure."""
        from ..plot.model import plot_time_response

        return plot_time_response(self, fig=fig)

    def _pairs(self) -> list[tuple[int, int, str]]:
        return [(i, j, f"{o} <- {u}") for i, o in enumerate(self.output_names)
                for j, u in enumerate(self.input_names or ["e"] * self.y.shape[2])]

    def to_pandas(self) -> Any:
        """A DataFrame indexed by time, one column per ``"output <- input"`` pair (and its
        ``"... std"`` with ``std=True``).

        Examples
        --------
        >>> import sysid
        >>> r = sysid.step(sysid.StateSpaceModel([[0.5]], [[0.5]], [[1.0]]), 3)
        >>> r.to_pandas()["y0 <- u0"].tolist()
        [0.0, 0.5, 0.75]
        """
        import pandas as pd

        cols: dict[str, Any] = {}
        for i, j, name in self._pairs():
            cols[name] = self.y[:, i, j]
            if self.std is not None:
                cols[f"{name} std"] = self.std[:, i, j]
        return pd.DataFrame(cols, index=pd.Index(self.t, name="time"))

    def summary(self) -> str:
        """Per ``output <- input`` pair: the last value (with its standard deviation when
        computed) and the largest in magnitude, with its time.

        Examples
        --------
        >>> import sysid
        >>> print(sysid.step(sysid.StateSpaceModel([[0.5]], [[0.5]], [[1.0]]), 20).summary())
        TimeResponse(step, 20 samples, 1 output(s) x 1 input(s))
          y0 <- u0: final 1, peak 1 at t = 19
        """
        lines = [repr(self)]
        for i, j, name in self._pairs():
            v = self.y[:, i, j]
            k = int(np.argmax(np.abs(v))) if v.size else 0
            sd = "" if self.std is None else f" (std {self.std[-1, i, j]:.3g})"
            lines.append(f"  {name}: final {v[-1]:.4g}{sd}, peak {v[k]:.4g} at "
                         f"t = {self.t[k]:.4g}" if v.size else f"  {name}: empty")
        return "\n".join(lines)

    def __repr__(self) -> str:
        return (
            f"TimeResponse({self.kind}, {len(self.t)} samples, {self.y.shape[1]} output(s) x "
            f"{self.y.shape[2]} input(s))"
        )


def default_length(model: Any, n_samples: int | None) -> int:
    """``n_samples``, or long enough for the slowest pole to decay to 1 % (20..10000)."""
    if n_samples is not None:
        from .._checks import as_count

        return as_count(n_samples, "n_samples", 8 * (model.noutputs + 1) * max(model.ninputs, 1))
    try:
        p = _optional(model, "poles", "the default response length")
    except DataError:
        return 100
    rho = float(np.max(np.abs(p))) if np.size(p) else 0.0
    n = 100 if rho >= 1 or rho == 0 else int(np.ceil(np.log(0.01) / np.log(rho))) + 10
    return int(min(max(n, 20), 10000))


def slowest_decay(poles: Any) -> float:
    """The slowest decay rate (1/s) among a continuous model's poles, integrators left out:
    the horizon of its default responses is five of its time constants. A pole whose rate is
    below ``1e-6`` of the median rate acts as an integrator over any horizon the others
    need (a fitted pole at ``-5e-12`` beside dynamics at ``1e-3`` rad/s set a horizon of
    ``1e12`` s, over which a model within the estimate's uncertainty overflowed); 0 when no
    pole decays.

    Examples
    --------
    >>> slowest_decay([-5e-12, -2e-3, -0.03 + 0.1j, -0.03 - 0.1j])
    0.002
    >>> slowest_decay([0.0, 1e-3])
    0.0
    """
    rate = -np.real(np.asarray(poles, complex).ravel())
    rate = rate[rate > 0]
    if rate.size == 0:
        return 0.0
    return float(np.min(rate[rate >= 1e-6 * np.median(rate)]))


def continuous_grid(poles: Any, t_final: float, n_samples: int | None, dt: float | None,
                    cap: int) -> tuple[int, float]:
    """Samples and step of a continuous model's default response grid over ``t_final``:
    ``n_samples`` (200 by default) evenly over it, or, by default, finer where the fastest
    pole needs it (10 samples per its time constant ``1/|s|``, at most ``cap`` samples): 200
    samples over a slow pole's five time constants aliased a 3 rad/s resonance beside it
    into a slow oscillation. With ``dt``: that step, up to ``cap`` samples.

    Examples
    --------
    >>> N, h = continuous_grid([-0.01, -0.1 + 3j, -0.1 - 3j], 500.0, None, None, 20000)
    >>> N, round(h, 6)  # 21 samples per period of the 3 rad/s resonance
    (15010, 0.033313)
    """
    if n_samples is not None:
        from .._checks import as_count

        n_samples = as_count(n_samples, "n_samples", 8 * 64)
    if dt is not None:
        N = int(min(np.ceil(t_final / dt) + 1, cap)) if n_samples is None else n_samples
        return N, float(dt)
    if n_samples is not None:
        return n_samples, t_final / max(n_samples - 1, 1)
    fast = float(np.max(np.abs(poles), initial=0.0))
    N = 200 if fast == 0 else int(min(max(200, np.ceil(t_final * fast * 10) + 1), cap))
    return N, t_final / max(N - 1, 1)


def sampled_response(model: Any, kind: str, n_samples: int | None) -> TimeResponse:
    """Step (``u = 1``) or impulse (``u(0) = 1``) response of a discrete model via simulate."""
    N = default_length(model, n_samples)
    m = model.ninputs
    y = np.empty((N, model.noutputs, m))
    for j in range(m):
        u = np.zeros((N, m))
        if kind == "step":
            u[:, j] = 1.0
        else:
            u[0, j] = 1.0
        y[:, :, j] = np.asarray(model.simulate(u)).reshape(N, model.noutputs)
    return TimeResponse(kind, np.arange(N) * model.dt, y, model)


def _plain(v: Any) -> str:
    """A fact of a fit's ``info`` for a line of text: one value bare, several joined."""
    if isinstance(v, (list, tuple)):
        return ", ".join(map(_plain, v)) if len(v) != 1 else _plain(v[0])
    return f"{v:.6g}" if isinstance(v, float) else str(v)


def _last(cost: Any) -> str:
    """The final cost of a search's history (one per output for per-output searches)."""
    if isinstance(cost, (list, tuple)) and cost and isinstance(cost[0], (list, tuple)):
        return ", ".join(_last(c) for c in cost)
    if isinstance(cost, (list, tuple)):
        return _plain(float(cost[-1])) if cost else "-"
    return _plain(cost)


class ModelMixin(ChannelSelection):
    """Default implementations of the protocol's derived members, written once.

    A class defining ``simulate``, ``freqresp``, ``dt``, the channel names and counts,
    ``n_parameters`` and ``info`` gets from this mixin:

    - ``predict(u, y, horizon)`` through ``to_statespace()`` (its innovation form);
    - ``poles()``, ``zeros()`` through ``to_statespace()``;
    - ``step(n_samples)``, ``impulse(n_samples)`` through ``simulate``;
    - ``save(path)`` through :func:`sysid.save_model` (needs ``to_dict``).

    Each raises a :class:`~sysid.DataError` naming the missing method when the class does
    not provide what it needs. ``model * other``, ``+`` and ``-`` with another model or a
    number (MATLAB's interconnections) raise a ``TypeError`` that names python-control's
    (``sysid.to_control``); with an :class:`~sysid.FRD` they are the FRD's.

    Examples
    --------
    >>> import sysid
    >>> class Integrator(sysid.ModelMixin):          # only the state-space form is given
    ...     def to_statespace(self):
    ...         return sysid.StateSpaceModel([[1.0]], [[1.0]], [[1.0]])
    >>> Integrator().poles()
    array([1.+0.j])
    >>> Integrator().predict([1.0, 1.0, 1.0], [0.0, 1.0, 2.0], 2)[:, 0]
    array([0., 1., 2.])
    """

    def _interconnect(self, other: Any) -> Any:
        from numbers import Number

        if isinstance(other, Number) or callable(getattr(other, "simulate", None)):
            raise TypeError(
                "sysid models are not combined with * + - (MATLAB's series, parallel and "
                "gains): convert them with sysid.to_control(model) and use python-control's "
                "operators, series, parallel, feedback or interconnect (sysid.from_control "
                "brings the result back)")
        return NotImplemented

    __mul__ = __rmul__ = __add__ = __radd__ = __sub__ = __rsub__ = _interconnect

    def __getstate__(self) -> dict[str, Any]:
        """Pickling (and copying): a covariance still deferred (the sandwich of
        :mod:`sysid.pem.sandwich`, formed when first used) is formed first, so that the
        ``info`` naming it is written as it ends, not before."""
        from .uncertainty import form_deferred

        form_deferred(self)
        return self.__dict__

    def _delegate(self, name: str) -> Any:
        ss = as_statespace(self, f"{name}()" if name != "predict" else name)
        if ss is self:  # its own to_statespace(): the mixin's default would call itself
            raise DataError(f"{type(self).__name__}.to_statespace() returns the model itself; "
                            f"define {name}() on the class")
        return getattr(ss, name)

    def predict(self, u: Any, y: Any = None, horizon: int = 1) -> np.ndarray:
        """``horizon``-step prediction with the Kalman predictor of ``to_statespace()``."""
        return np.asarray(self._delegate("predict")(u, y, horizon))

    def poles(self, std: bool = False) -> np.ndarray:
        """Poles of ``to_statespace()`` (``std=True`` is refused: see :func:`no_pole_std`)."""
        no_pole_std(self, std)
        return np.asarray(self._delegate("poles")())

    def zeros(self) -> np.ndarray:
        """Transmission zeros of ``to_statespace()``."""
        return np.asarray(self._delegate("zeros")())

    def step(self, n_samples: int | None = None, std: bool = False) -> TimeResponse:
        """Response to a unit step on each input, from rest (by simulation); ``std=True``
        (needs ``uncertainty``): with its first-order std as a band."""
        resp = sampled_response(self, "step", n_samples)
        if std:
            from .uncertainty import response_band

            return response_band(self, resp, lambda m, n: m.step(n))
        return resp

    def dcgain(self, std: bool = False) -> Any:
        """Steady-state gain ``(noutputs, ninputs)``: the frequency response at 0; with
        ``std=True`` (needs ``uncertainty``) the pair ``(gain, std)``, first order."""
        if std:
            from .uncertainty import complex_std

            return complex_std(self, lambda m: m.dcgain())
        return np.asarray(self.freqresp(np.array([0.0])))[0].real

    def impulse(self, n_samples: int | None = None, std: bool = False) -> TimeResponse:
        """Response to a unit pulse ``u(0) = 1`` on each input, from rest (by simulation);
        ``std=True`` (needs ``uncertainty``): with its first-order std as a band."""
        resp = sampled_response(self, "impulse", n_samples)
        if std:
            from .uncertainty import response_band

            return response_band(self, resp, lambda m, n: m.impulse(n))
        return resp

    def summary(self) -> str:
        """What the model is and how it was obtained, as text: family, sampling, channels,
        order, free parameters, method and stability; the search's iterations, stop and
        cost when it was refined; its poles with natural frequency and damping; and the
        parameter table with standard deviations when it carries an uncertainty.

        Examples
        --------
        >>> import sysid
        >>> print(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1).summary())
        StateSpaceModel(nstates=1, ninputs=1, noutputs=1, dt=0.1, stable, no noise model)
          family: StateSpaceModel
          time: discrete, dt = 0.1 s
          inputs: u0
          outputs: y0
          states: 1
          free parameters: 2
          stable: yes (largest |pole| 0.5)
        poles:
                            pole   |pole|    wn [Hz]   damping
                          0.5+0j   0.5000      1.103    1.0000
        """
        from .._display import _poles, model_facts, pole_rows

        lines = [repr(self)] + [f"  {k}: {v}" for k, v in model_facts(self)]
        info = getattr(self, "info", None) or {}
        run = info.get("pem") if isinstance(info.get("pem"), dict) else info
        done = [f"{k} {_last(run[k]) if k == 'cost' else _plain(run[k])}"
                for k in ("iterations", "stop", "cost") if run.get(k) not in (None, [])]
        if done:
            lines.append("  search: " + ", ".join(map(str, done)))
        p = _poles(self)
        if p is not None and p.size:
            dt = float(getattr(self, "dt", 0.0) or 0.0)
            lines += ["poles:", f"{'pole':>24} {'|pole|':>8} {'wn [Hz]':>10} {'damping':>9}"]
            lines += [f"{format(pl, '.4g'):>24} {r:8.4f} {f:10.4g} {z:9.4f}"
                      for pl, r, f, z in pole_rows(p, dt)]
        unc = getattr(self, "uncertainty", None)
        if unc is not None and hasattr(unc, "summary"):
            lines += ["parameters:", unc.summary(max_rows=20)]
        return "\n".join(lines)

    def to_pandas(self) -> Any:
        """The model's poles as a :class:`pandas.DataFrame` (:func:`sysid.damp`: natural
        frequency, damping and time constant, with standard deviations when the model
        carries an uncertainty).

        Examples
        --------
        >>> import sysid
        >>> df = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1).to_pandas()
        >>> list(df.columns)[:3]
        ['pole', 'magnitude', 'wn [rad/s]']
        """
        from .linear import damping

        return damping(self, std=getattr(self, "uncertainty", None) is not None).to_pandas()

    def _repr_html_(self) -> str:
        """Notebook display: facts, poles (see :mod:`sysid._display`)."""
        from .._display import model_html

        return model_html(self)

    def save(self, path: Any, *, format: str | None = None) -> None:
        """Write the model to a ``.json`` or ``.npz`` file; see :func:`sysid.save_model`."""
        from .serialize import save_model

        save_model(self, path, format=format)
