"""Continuous-time models: :class:`ContinuousStateSpace`, and :func:`c2d`/:func:`d2c`.

.. math::

    \\dot x(t) = A x(t) + B u(t), \\qquad y(t) = C x(t) + D u(t)

Measured data are samples every ``dt``; between samples the input is held constant
(zero-order hold, ``"zoh"``) or interpolated linearly (first-order hold, ``"foh"``). Both are
exact discretisations, computed once from the exponential of an augmented matrix
(:mod:`sysid.models.discretisation`, on the Rust core's ``expm_frechet``):

- ZOH: ``expm([[A, B], [0, 0]] dt) = [[Ad, G1], [0, I]]``, ``Bd = G1``.
- FOH: ``expm([[A, B, 0], [0, 0, I/dt], [0, 0, 0]] dt)`` holds ``Ad``, ``G1`` and ``G2 =
  int_0^dt e^{A s} B (dt - s)/dt ds``; ``x(k+1) = Ad x(k) + G1 u(k) + G2 (u(k+1) - u(k))``.
  With the state ``xi = x - G2 u`` this is the ordinary model ``Bd = G1 + (Ad - I) G2``,
  ``Cd = C``, ``Dd = D + C G2`` (the realisation of ``scipy.signal.cont2discrete``). Its
  state differs from the continuous one: rest (``x(0) = 0``) is ``xi(0) = -G2 u(0)``,
  which :meth:`ContinuousStateSpace.simulate` applies (and :func:`sysid.compare`, through
  :meth:`ContinuousStateSpace.sampled`); the discrete model alone starts from ``xi(0) = 0``.
- Tustin (bilinear): with ``M = (I - A dt / 2)^{-1}``, ``Ad = M (I + A dt / 2)``,
  ``Bd = M B dt``, ``Cd = C M``, ``Dd = D + C M B dt / 2``. With a prewarp frequency ``w``
  (MATLAB's ``c2dOptions('PrewarpFrequency', w)``) ``dt`` in these formulas becomes
  ``h = 2 tan(w dt / 2) / w``, i.e. ``s = (w / tan(w dt / 2)) (z - 1) / (z + 1)``: the
  discrete frequency response equals the continuous one exactly at ``w``.
- Impulse invariant (MATLAB's ``'impulse'``): ``Ad = e^{A dt}``, ``Bd = Ad B dt``,
  ``Cd = C``, ``Dd = D + C B dt``, so the discrete impulse response is ``dt`` times the
  continuous one sampled, ``h_d[k] = dt C e^{A k dt} B`` (``k = 0`` included, no half weight;
  the convention of MATLAB and ``scipy.signal.cont2discrete``, which refuses ``D != 0``; a
  feedthrough ``D`` is kept as the discrete ``D`` on top: the response to MATLAB's discrete
  impulse, ``1/dt`` high for one sample, is then the sampled continuous impulse response, its
  Dirac part ``D delta(t)`` a pulse of the same area in the first sample). The DC gain is
  matched only as ``dt -> 0``.
- Matched pole-zero (single input and output): poles and zeros ``e^{s dt}``, all but one
  zero at infinity put at ``z = -1`` (as MATLAB), the DC gain kept; see
  :mod:`sysid.models.matched`.

The discrete model is then simulated by the Rust simulator.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
import scipy.linalg

from .._checks import as_2d, as_dt, user_stacklevel
from ..errors import DataError, NumericalError, SysidWarning
from .attributes import ContinuousTime, Matrix
from .carried import carry
from .discretisation import expm, hold_blocks, require_finite_sampling
from .linear import transmission_zeros
from .matched import matched_c2d, matched_d2c
from .negative_real import negative_real, zoh_doubled
from .protocol import ModelMixin, TimeResponse, continuous_grid, slowest_decay
from .statespace import StateSpaceModel, finite_dcgain, ss_parameter_count

__all__ = ["ContinuousStateSpace", "SampledContinuous", "c2d", "d2c", "d2d"]

_METHODS = ("zoh", "foh", "tustin", "matched", "impulse")
_D2C_METHODS = ("zoh", "foh", "tustin", "matched")


class ContinuousStateSpace(ModelMixin):
    """Continuous-time model ``dx/dt = A x + B u``, ``y = C x + D u``.

    Satisfies :class:`sysid.Model` with ``dt = 0.0``; simulating measured data needs the
    data's sample time (``simulate(u, dt=...)``, or an :class:`~sysid.IOData` given to
    :func:`sysid.compare`).

    Parameters
    ----------
    A, B, C : array_like
        Shapes ``(n, n)``, ``(n, m)``, ``(l, n)``.
    D : array_like, optional
        ``(l, m)``; zero if omitted.
    input_names, output_names : sequence of str, optional
        Channel names.
    hold : {"zoh", "foh"}
        How the input behaves between samples, used when the model meets sampled data
        (:func:`sysid.compare`, :func:`sysid.residuals`, ...).
    info : dict, optional
        How the model was obtained.

    Examples
    --------
    >>> import sysid
    >>> sys = sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]])
    >>> sys
    ContinuousStateSpace(nstates=1, ninputs=1, noutputs=1, stable)
    >>> float(sys.dcgain()[0, 0])
    1.0
    >>> sys.simulate([1.0, 1.0, 1.0], dt=0.5)[:, 0].round(4)
    array([0.    , 0.3935, 0.6321])

    The matrices are replaced only whole, checked as the constructor checks them (a
    parameter uncertainty of the old values is dropped, as for a StateSpaceModel); dt stays 0

    >>> sys.B = [[1.0, 2.0]]
    Traceback (most recent call last):
    ...
    sysid.errors.ShapeError: B has shape (1, 2) but should have shape (1, 1); ...
    """

    A, B, C, D = (Matrix() for _ in range(4))
    dt = ContinuousTime()  # 0.0: continuous time (python-control's convention)

    def __init__(
        self,
        A: Any,
        B: Any,
        C: Any,
        D: Any = None,
        *,
        input_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
        hold: str = "zoh",
        info: dict[str, Any] | None = None,
    ) -> None:
        # reuse the discrete model's checks, then keep only the matrices
        ref = StateSpaceModel(A, B, C, D, input_names=input_names, output_names=output_names)
        self.A, self.B, self.C, self.D = ref.A, ref.B, ref.C, ref.D
        self.input_names, self.output_names = ref.input_names, ref.output_names
        self.hold = _method(hold, ("zoh", "foh"), "hold")
        self.info: dict[str, Any] = dict(info or {})
        self.uncertainty: Any = None  # a ParameterUncertainty when estimated (or d2c'd)

    def _select(self, iy: list[int], iu: list[int]) -> ContinuousStateSpace:
        """Outputs ``iy`` from inputs ``iu`` (:meth:`select`)."""
        from .subsystem import names

        return ContinuousStateSpace(
            self.A, self.B[:, iu], self.C[iy], self.D[np.ix_(iy, iu)],
            input_names=names(self.input_names, iu), output_names=names(self.output_names, iy),
            hold=self.hold, info=self.info)

    nstates = property(lambda self: self.A.shape[0], doc="Number of states n.")
    ninputs = property(lambda self: self.B.shape[1], doc="Number of inputs m.")
    noutputs = property(lambda self: self.C.shape[0], doc="Number of outputs l.")

    @property
    def n_parameters(self) -> int:
        """Identifiable parameters ``n (l + m) + [D != 0] l m`` (no noise model)."""
        return ss_parameter_count(self.nstates, self.ninputs, self.noutputs,
                                  feedthrough=bool(np.any(self.D != 0)), noise_model=False)

    def poles(self, std: bool = False, method: str = "linear") -> Any:
        """Eigenvalues of A (continuous-time poles, rad/s); with ``std=True`` (needs
        :attr:`uncertainty`) the pair ``(poles, sd)`` as for
        :meth:`sysid.StateSpaceModel.poles`."""
        if std:
            from .pole_uncertainty import pole_std

            return pole_std(self, method)
        return np.linalg.eigvals(self.A).astype(complex)

    def zeros(self) -> np.ndarray:
        """Transmission zeros (``s``-plane); see :func:`sysid.zeros`."""
        return transmission_zeros(self.A, self.B, self.C, self.D)

    def is_stable(self) -> bool:
        """True when every pole has a strictly negative real part."""
        return bool(self.nstates == 0 or np.max(self.poles().real) < 0)

    def freqresp(self, omega: Any, std: bool = False) -> Any:
        """``C (j omega I - A)^{-1} B + D``, shape ``(len(omega), noutputs, ninputs)``; with
        ``std=True`` (needs :attr:`uncertainty`) the pair ``(H, sd)``, ``sd`` complex; ``inf``
        at a frequency on a pole (``j omega`` an eigenvalue of ``A``)."""
        if std:
            from .uncertainty import freqresp_std

            return freqresp_std(self, omega)
        w = np.atleast_1d(np.asarray(omega, dtype=float))
        if w.ndim != 1 or not np.isfinite(w).all():
            raise DataError("omega must be a finite 1-D array of angular frequencies (rad/s)")
        eye = np.eye(self.nstates)
        out = np.empty((w.size, self.noutputs, self.ninputs), dtype=complex)
        for i, wi in enumerate(w):
            try:
                out[i] = self.C @ np.linalg.solve(1j * wi * eye - self.A, self.B) + self.D
            except np.linalg.LinAlgError:  # omega at a pole: infinite gain, as MATLAB's
                out[i] = np.inf
        return out

    def dcgain(self, std: bool = False) -> Any:
        """``D - C A^{-1} B``, shape ``(noutputs, ninputs)``; a pole at ``s = 0`` (an
        integrator) raises :class:`~sysid.NumericalError`, as for a discrete model. With
        ``std=True`` (needs :attr:`uncertainty`, as :func:`d2c` carries over) the pair
        ``(gain, std)``, first order."""
        if std:
            from .uncertainty import complex_std

            return complex_std(self, lambda m: m.dcgain())
        return finite_dcgain(self, "s = 0")

    def c2d(self, dt: float, method: str | None = None, *,
            prewarp: float | None = None) -> StateSpaceModel:
        """Discretise (default: the model's ``hold``); see :func:`c2d`."""
        return c2d(self, dt, method or self.hold, prewarp=prewarp)

    def sampled(self, dt: float) -> SampledContinuous:
        """The model as it meets data sampled every ``dt`` with its ``hold``; see
        :class:`SampledContinuous` (what :func:`sysid.compare` uses)."""
        return SampledContinuous(self, dt)

    # -- sampled data ---------------------------------------------------------------------
    def simulate(self, u: Any, t: Any = None, *, dt: float | None = None,
                 method: str | None = None, x0: Any = None) -> np.ndarray:
        """Response to sampled inputs held between samples by ZOH or FOH (exact).

        Parameters
        ----------
        u : array_like
            Inputs ``(n_samples, ninputs)`` at times ``0, dt, 2 dt, ...``.
        t : array_like, optional
            Sample times (uniform); gives ``dt``. Pass ``t`` or ``dt``.
        dt : float, optional
            Sample time in seconds.
        method : {"zoh", "foh"}, optional
            Hold between samples (default: the model's ``hold``).
        x0 : array_like, optional
            Continuous state at time 0 (zero by default).

        Returns
        -------
        ndarray
            Outputs ``(n_samples, noutputs)`` at the sample times.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> sys = sysid.ContinuousStateSpace([[0.0]], [[1.0]], [[1.0]])   # an integrator
        >>> t = np.arange(4.0)
        >>> sys.simulate(t, t, method="foh")[:, 0]    # integral of a ramp: t^2 / 2
        array([0. , 0.5, 2. , 4.5])
        """
        u = as_2d(u, "u", ncols=self.ninputs, allow_empty=self.ninputs == 0)
        step = _sample_time(t, dt, u.shape[0])
        method = _method(method or self.hold, ("zoh", "foh"))
        Ad, Bd, Cd, Dd, G2 = _discretise(self, step, method)
        x = np.zeros(self.nstates)
        if x0 is not None:
            x = np.asarray(x0, dtype=float).reshape(-1)
            if x.size != self.nstates:
                raise DataError(f"x0 has {x.size} entries but the model has {self.nstates} "
                                "states")
        # the discrete state is xi = x - G2 u (G2 = 0 for ZOH): from rest, xi(0) = -G2 u(0)
        xi0 = x - G2 @ u[0] if u.shape[0] else x
        d = StateSpaceModel(Ad, Bd, Cd, Dd, dt=step)
        return d.simulate(u, x0=xi0 if np.any(xi0) else None)

    def predict(self, u: Any, y: Any = None, horizon: int = 1, *, t: Any = None,
                dt: float | None = None, method: str | None = None,
                x0: Any = None) -> np.ndarray:
        """No noise model: the prediction is the simulation (``y`` only sets the length)."""
        from .._measured import predict_args, record_dt

        dt = dt if t is not None else record_dt(u, dt)
        u, y = predict_args(u, y)
        y = np.asarray(y, dtype=float)
        if y.shape[0] != np.shape(u)[0]:
            raise DataError(f"u has {np.shape(u)[0]} samples but y has {y.shape[0]}")
        return self.simulate(u, t, dt=dt, method=method, x0=x0)

    def _grid(self, n_samples: int | None, dt: float | None) -> tuple[int, float]:
        slow = slowest_decay(self.poles()) or 0.1
        t_final = 5.0 / slow  # e^-5 < 1 %
        step = None if dt is None else _sample_time(None, dt, 1)
        return continuous_grid(self.poles(), t_final, n_samples, step, 100000)

    def step(self, n_samples: int | None = None, *, dt: float | None = None,
             std: bool = False) -> TimeResponse:
        """Unit-step response sampled every ``dt`` (exact: a step is held by ZOH).

        Without ``dt`` the grid spans five time constants of the slowest pole. With
        ``std=True`` (needs :attr:`uncertainty`) ``resp.std`` is the first-order standard
        deviation of each sample, every model of the propagation evaluated on this grid.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> r = sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]]).step(3, dt=1.0)
        >>> bool(np.allclose(r.y[:, 0, 0], 1 - np.exp(-r.t)))
        True
        >>> build = lambda t: sysid.ContinuousStateSpace([[-t[0]]], [[1.0]], [[1.0]])
        >>> c = build([1.0])
        >>> c.uncertainty = sysid.ParameterUncertainty([1.0], [[0.01]], build)
        >>> r = c.step(3, dt=1.0, std=True)       # 0.1 |t e^-t - (1 - e^-t)|
        >>> np.round(r.std[:, 0, 0], 4)
        array([0.    , 0.0264, 0.0594])
        """
        if std:
            return self._banded("step", n_samples, dt)
        N, step = self._grid(n_samples, dt)
        m = self.ninputs
        y = np.empty((N, self.noutputs, m))
        for j in range(m):
            u = np.zeros((N, m))
            u[:, j] = 1.0
            y[:, :, j] = self.simulate(u, dt=step, method="zoh")
        return TimeResponse("step", np.arange(N) * step, y, self)

    def impulse(self, n_samples: int | None = None, *, dt: float | None = None,
                std: bool = False) -> TimeResponse:
        """Impulse response ``C e^{A t} B`` at the samples (the Dirac part ``D`` is left
        out); the grid as :meth:`step`, and ``std=True`` as there.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> r = sysid.ContinuousStateSpace([[-2.0]], [[1.0]], [[3.0]]).impulse(4, dt=0.5)
        >>> bool(np.allclose(r.y[:, 0, 0], 3 * np.exp(-2 * r.t)))
        True
        """
        if std:
            return self._banded("impulse", n_samples, dt)
        N, step = self._grid(n_samples, dt)
        m = self.ninputs
        y = np.empty((N, self.noutputs, m))
        zero = np.zeros((N, m))
        for j in range(m):
            y[:, :, j] = self.simulate(zero, dt=step, x0=self.B[:, j], method="zoh")
        return TimeResponse("impulse", np.arange(N) * step, y, self)

    def _banded(self, kind: str, n_samples: int | None, dt: float | None) -> TimeResponse:
        """The ``kind`` response with its std band, every draw on this model's grid."""
        from .uncertainty import response_band

        resp = getattr(self, kind)(n_samples, dt=dt)
        return response_band(self, resp, lambda m, n: getattr(m, kind)(n))

    # -- saving -----------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Matrices, names, hold and info (see :func:`sysid.save_model`)."""
        return {"A": self.A, "B": self.B, "C": self.C, "D": self.D, "hold": self.hold,
                "input_names": list(self.input_names), "output_names": list(self.output_names),
                "info": self.info}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ContinuousStateSpace:
        """Inverse of :meth:`to_dict`."""
        n = np.asarray(d["A"]).shape[0]
        B = np.asarray(d["B"], float).reshape(n, -1)
        C = np.asarray(d["C"], float).reshape(-1, n)
        return cls(d["A"], B, C, d["D"], input_names=d.get("input_names"),
                   output_names=d.get("output_names"), hold=d.get("hold", "zoh"),
                   info=d.get("info"))

    def __repr__(self) -> str:
        stab = "stable" if self.is_stable() else "UNSTABLE"
        return (
            f"ContinuousStateSpace(nstates={self.nstates}, ninputs={self.ninputs}, "
            f"noutputs={self.noutputs}, {stab})"
        )


class SampledContinuous:
    """A :class:`ContinuousStateSpace` seen at sample time ``dt``: a discrete
    :class:`sysid.Model` whose ``simulate``/``predict`` are the continuous model's exact
    hold simulation, with ``x0`` the *continuous* state (zero is rest, also under FOH).

    ``A, B, C, D`` are the hold's discrete realisation (for the initial-state regression);
    there is no noise model, so prediction is simulation.

    Examples
    --------
    >>> import sysid
    >>> s = sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]], hold="foh").sampled(0.5)
    >>> s
    SampledContinuous(ContinuousStateSpace(nstates=1, ninputs=1, noutputs=1, stable), dt=0.5, foh)
    >>> s.simulate([[1.0], [1.0]], x0=[0.0])[:, 0].round(4)
    array([0.    , 0.3935])
    """

    def __init__(self, sys: ContinuousStateSpace, dt: float) -> None:
        self.continuous, self.dt = sys, dt
        self.K, self.x0 = None, None
        self.input_names, self.output_names = sys.input_names, sys.output_names
        self.info = sys.info

    @property
    def dt(self) -> float:
        """The sample time; writing it (checked as in the constructor) samples again."""
        return self._dt

    @dt.setter
    def dt(self, value: Any) -> None:
        self._dt = dt = _sample_time(None, value, 1)
        self.A, self.B, self.C, self.D, _ = _discretise(self.continuous, dt, self.continuous.hold)

    nstates = property(lambda self: self.A.shape[0], doc="Number of states n.")
    ninputs = property(lambda self: self.B.shape[1], doc="Number of inputs m.")
    noutputs = property(lambda self: self.C.shape[0], doc="Number of outputs l.")
    n_parameters = property(lambda self: self.continuous.n_parameters,
                            doc="Free parameters of the continuous model.")

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        """The continuous model's response with its hold (``x0``: continuous state)."""
        return self.continuous.simulate(u, dt=self.dt, x0=x0)

    def predict(self, u: Any, y: Any = None, horizon: int = 1, x0: Any = None) -> np.ndarray:
        """No noise model: the simulation."""
        return self.continuous.predict(u, y, horizon, dt=self.dt, x0=x0)

    def freqresp(self, omega: Any) -> np.ndarray:
        """Frequency response of the discrete realisation (``z = exp(j omega dt)``)."""
        return StateSpaceModel(self.A, self.B, self.C, self.D, dt=self.dt).freqresp(omega)

    def poles(self) -> np.ndarray:
        """Discrete poles ``exp(s dt)``."""
        return np.linalg.eigvals(self.A).astype(complex)

    def __repr__(self) -> str:
        return f"SampledContinuous({self.continuous!r}, dt={self.dt:g}, {self.continuous.hold})"


def _method(method: Any, allowed: tuple[str, ...] = _METHODS, what: str = "method") -> str:
    key = {"bilinear": "tustin"}.get(str(method).lower(), str(method).lower())
    if key not in allowed:
        raise DataError(f"{what} must be one of {', '.join(repr(a) for a in allowed)}, "
                        f"got {method!r}")
    return key


def _sample_time(t: Any, dt: Any, n: int) -> float:
    if t is not None:
        if dt is not None:
            raise DataError("give the sample times t or the sample time dt, not both")
        t = np.asarray(t, dtype=float).ravel()
        if t.size != n:
            raise DataError(f"t has {t.size} entries but u has {n} samples")
        if n < 2:
            raise DataError("t needs at least two samples to give a sample time; pass dt")
        d = np.diff(t)
        if not np.allclose(d, d[0], rtol=1e-9, atol=0):
            raise DataError("t must be uniformly spaced; resample the data or pass dt")
        dt = d[0]
    if dt is None:
        raise DataError("a continuous-time model needs the sample time of the data: pass dt "
                        "(or t), or discretise it with c2d")
    return as_dt(dt)


def _hold_integrals(A: np.ndarray, B: np.ndarray, dt: float
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``Ad = e^{A dt}``, ``G1``, ``G2`` from one exponential of the FOH augmented matrix."""
    n, m = B.shape
    E = expm(hold_blocks(A, B, dt, "foh"))[0]
    return E[:n, :n], E[:n, n:n + m], E[:n, n + m:]


def _discretise(sys: ContinuousStateSpace, dt: float, method: str, warp: float | None = None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(Ad, Bd, Cd, Dd, G2)`` with ``G2`` the FOH state shift (zero otherwise); ``warp``
    is Tustin's ``h`` (``dt`` when not prewarped)."""
    with np.errstate(over="ignore", invalid="ignore"):
        out = _discretise_raw(sys, dt, method, dt if warp is None else warp)
    require_finite_sampling(out, np.linalg.eigvals(sys.A) if sys.A.size else [], dt)
    return out


def _discretise_raw(sys: ContinuousStateSpace, dt: float, method: str, h: float
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    A, B, C, D = sys.A, sys.B, sys.C, sys.D
    n, m = B.shape
    if method in ("zoh", "impulse"):
        E = expm(hold_blocks(A, B, dt, "zoh"))[0]
        if method == "impulse":
            Ad = E[:n, :n]
            return Ad, Ad @ B * dt, C.copy(), D + C @ B * dt, np.zeros((n, m))
        return E[:n, :n], E[:n, n:], C.copy(), D.copy(), np.zeros((n, m))
    if method == "foh":
        Ad, G1, G2 = _hold_integrals(A, B, dt)
        return Ad, G1 + (Ad - np.eye(n)) @ G2, C.copy(), D + C @ G2, G2
    if method == "matched":
        return (*matched_c2d(A, B, C, D, dt), np.zeros((n, m)))
    ima = np.eye(n) - 0.5 * h * A
    half = 0.5 * h * np.linalg.eigvals(A) if n else np.zeros(0)
    try:
        if np.any(np.abs(1.0 - half) <= 8 * np.finfo(float).eps * np.maximum(1, np.abs(half))):
            raise np.linalg.LinAlgError
        Ad = np.linalg.solve(ima, np.eye(n) + 0.5 * h * A)
        Bd = np.linalg.solve(ima, h * B)
        Cd = np.linalg.solve(ima.T, C.T).T
    except np.linalg.LinAlgError:  # the bilinear map sends s = 2/h to z = infinity
        pole = 2.0 * half[np.argmin(np.abs(1.0 - half))] / h
        at = "2/dt" if h == dt else "2/h (h of the prewarped transform)"
        raise DataError(
            f"the model has a pole at s = {pole:.6g} rad/s, at {at} = {2.0 / h:.6g} rad/s, "
            "which the Tustin transform maps to z = infinity; use another method "
            f"(method='zoh' or 'foh') or another sample time than dt = {dt:g} s") from None
    return Ad, Bd, Cd, D + 0.5 * C @ Bd, np.zeros((n, m))


def _warp(prewarp: Any, dt: float, method: str, direction: str) -> float:
    """Tustin's ``h = 2 tan(w dt / 2) / w`` for a prewarp frequency ``w`` (rad/s); ``dt``
    when ``prewarp`` is None or 0 (MATLAB's default: no prewarping)."""
    if prewarp is None:
        return dt
    try:
        w = float(prewarp)
    except (TypeError, ValueError):
        raise DataError(f"prewarp must be a frequency in rad/s, got {prewarp!r}") from None
    if isinstance(prewarp, (bool, np.bool_)) or not np.isfinite(w) or w < 0:
        raise DataError(f"prewarp must be a non-negative frequency in rad/s, got {prewarp!r}")
    if w == 0.0:
        return dt
    if method != "tustin":
        raise DataError(f"{direction}: prewarp applies to method='tustin' only (got "
                        f"method={method!r}); drop prewarp or use method='tustin'")
    nyquist = np.pi / dt
    if w >= nyquist:
        raise DataError(
            f"{direction}: prewarp = {w:g} rad/s is at or beyond the Nyquist frequency "
            f"pi/dt = {nyquist:g} rad/s of dt = {dt:g} s, where tan(w dt / 2) has no finite "
            f"value; choose a prewarp frequency below {nyquist:g} rad/s or a smaller dt")
    return 2.0 * np.tan(0.5 * w * dt) / w


def _convertible(sys: Any, kind: type, purpose: str) -> Any:
    """``sys`` as a ``kind`` (a transfer function or polynomial model through its
    ``to_statespace()``, which carries its parameter uncertainty), or a :class:`DataError`
    saying which conversion applies instead."""
    if isinstance(sys, kind):
        return sys
    want = "continuous" if kind is ContinuousStateSpace else "discrete"
    dt = getattr(sys, "dt", None)
    if isinstance(sys, (ContinuousStateSpace, StateSpaceModel)) or (
            dt is not None and bool(dt) != (want == "discrete")):
        other = "d2c" if purpose == "c2d" else "c2d"
        raise DataError(f"{purpose} needs a {want}-time model (a sysid.{kind.__name__} or a "
                        f"TransferFunction), but this "
                        f"{type(sys).__name__} has dt = {dt:g}; use {other} for the other "
                        "direction")
    if np.any(np.asarray(getattr(sys, "iodelay", 0.0)) > 0) and want == "continuous":
        raise DataError(f"{purpose}: this {type(sys).__name__} has input-output delays, which "
                        "a continuous state-space model cannot hold; sample it exactly, delays "
                        "included, with model.to_statespace(dt) (its hold: model.hold)")
    conv = getattr(sys, "to_statespace", None)
    ss = conv() if conv is not None else None
    if not isinstance(ss, kind):
        raise DataError(f"{purpose} needs a sysid.{kind.__name__} (or a transfer function), "
                        f"got {type(sys).__name__}")
    return ss


def c2d(sys: ContinuousStateSpace, dt: float, method: str = "zoh", *,
        prewarp: float | None = None) -> StateSpaceModel:
    """Discretise a continuous model: zero- or first-order hold, Tustin (optionally
    prewarped), impulse invariant or matched pole-zero.

    See the module documentation for the formulas (``"bilinear"`` is accepted for Tustin).

    Parameters
    ----------
    sys : ContinuousStateSpace or TransferFunction
        A continuous model; a transfer function goes through its realisation (one with
        delays needs ``sys.to_statespace(dt)``, which samples them exactly).
    dt : float
        Sample time in seconds.
    method : {"zoh", "foh", "tustin", "bilinear", "impulse", "matched"}
        Hold of the input between samples, the bilinear transform, the impulse-invariant
        map (discrete impulse response ``dt`` times the continuous one sampled, MATLAB's
        scaling) or matched pole-zero (``z = e^{s dt}`` for poles and zeros, all but one
        zero at infinity at ``z = -1`` as MATLAB, DC gain kept; one input and one output).
    prewarp : float, optional
        Tustin only: the frequency (rad/s, below the Nyquist frequency ``pi / dt``) at which
        the discrete frequency response equals the continuous one exactly (MATLAB's
        ``PrewarpFrequency``); None or 0 for none.

    Returns
    -------
    StateSpaceModel
        The discrete model (no noise model); the parameter uncertainty is carried (the same
        parameters, through the conversion).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.c2d(sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]]), 0.1)
    >>> bool(np.isclose(d.A[0, 0], np.exp(-0.1)))
    True
    >>> float(sysid.c2d(sysid.ContinuousStateSpace([[0.0]], [[1.0]], [[1.0]]), 1.0, "foh").D[0, 0])
    0.5
    >>> lag = sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]])
    >>> t = sysid.c2d(lag, 0.5, "tustin", prewarp=2.0)
    >>> bool(np.isclose(t.freqresp([2.0])[0, 0, 0], lag.freqresp([2.0])[0, 0, 0]))
    True
    """
    sys = _convertible(sys, ContinuousStateSpace, "c2d")
    dt = _sample_time(None, dt, 1)
    method = _method(method)
    warp = _warp(prewarp, dt, method, "c2d")
    Ad, Bd, Cd, Dd, _ = _discretise(sys, dt, method, warp)
    out = StateSpaceModel(
        Ad, Bd, Cd, Dd, dt=dt, input_names=sys.input_names, output_names=sys.output_names,
        info={"method": f"c2d ({method})" if warp == dt
              else f"c2d ({method}, prewarp {float(prewarp):g} rad/s)"},
    )
    return carry(sys, out, lambda m: c2d(m, dt, method, prewarp=prewarp))


def _real_log(M: np.ndarray, p: np.ndarray, method: str) -> np.ndarray:
    bad = negative_real(p) | (np.abs(p) <= 1e-12)
    if bad.any():
        if abs(p[bad][0]) <= 1e-12:
            raise NumericalError(
                f"the model has a pole at z = 0, which has no {method.upper()} continuous "
                "equivalent (no logarithm); if it is a delay realised as a state, give the "
                "delay as the model's iodelay instead (sysid.TransferFunction(num, den, dt=dt, "
                "iodelay=k)), which d2c keeps as k dt seconds; method='tustin' maps it to a "
                "pole at s = -2/dt, an approximation")
        other = "'tustin'" if method == "zoh" else "'zoh' or 'tustin'"
        raise NumericalError(
            f"the model has a pole at z = {p[bad][0].real:g} on the negative real axis: it "
            f"has no {method.upper()} continuous equivalent; use method={other}"
        )
    L = np.real_if_close(scipy.linalg.logm(M), tol=1e6)
    if np.iscomplexobj(L):
        raise NumericalError("the matrix logarithm is complex: no real continuous equivalent")
    return np.asarray(L)


def d2c(model: StateSpaceModel, method: str = "zoh", *,
        prewarp: float | None = None) -> ContinuousStateSpace:
    """Continuous-time equivalent of a discrete model (inverse of :func:`c2d`).

    ``zoh`` takes the principal matrix logarithm of ``[[A, B], [0, I]]``; a pole on the
    negative real axis, which has no real logarithm, is doubled first (as MATLAB does: the
    order rises by one per such pole, each becoming a complex pair at the Nyquist frequency,
    with a warning). ``foh`` takes ``A = log(Ad) / dt`` and solves the FOH relations for
    ``B`` and ``D``; it fails with a :class:`NumericalError` on the negative real axis. Both
    fail for a pole at zero (no logarithm). ``tustin`` fails when a pole is at ``z = -1``;
    with ``prewarp`` it inverts the prewarped transform. ``matched`` (one input and one
    output) maps poles and zeros by ``log(z) / dt`` and keeps the DC gain. The noise model
    (``K``) is not converted; the parameter uncertainty is (the same parameters, through the
    conversion). A discrete transfer function with delays of ``k`` samples gives a continuous
    :class:`~sysid.TransferFunction` with delays of ``k dt`` seconds (as MATLAB's ``d2c``;
    realised as states, a delay is a pole at ``z = 0``, which has no continuous equivalent).

    Parameters
    ----------
    model : StateSpaceModel or TransferFunction
        A discrete model; a transfer function goes through its realisation.
    method : {"zoh", "foh", "tustin", "bilinear", "matched"}
        The discretisation to invert.
    prewarp : float, optional
        Tustin only: the prewarp frequency (rad/s) the model was discretised with.

    Returns
    -------
    ContinuousStateSpace
        With ``hold="foh"`` after ``method="foh"``, ``"zoh"`` otherwise (a TransferFunction
        for a transfer function with delays).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> c = sysid.d2c(sysid.StateSpaceModel([[np.exp(-0.1)]], [[1.0]], [[1.0]], dt=0.1))
    >>> bool(np.isclose(c.A[0, 0], -1.0))
    True
    >>> g = sysid.d2c(sysid.TransferFunction([0.1], [1.0, -0.9], dt=0.1, iodelay=2))
    >>> g.iodelay.tolist(), bool(np.isclose(g.poles()[0], np.log(0.9) / 0.1))
    ([[0.2]], True)
    """
    delayed = getattr(model, "_continuous_with_delays", None)
    if delayed is not None and float(getattr(model, "dt", 0.0) or 0.0) > 0 and np.any(
            np.asarray(getattr(model, "iodelay", 0.0)) > 0):
        out = delayed(_method(method, _D2C_METHODS), prewarp)
        return carry(model, out, lambda m: m._continuous_with_delays(method, prewarp))
    return _d2c(model, method, prewarp, quiet=False)


def _d2c(model: StateSpaceModel, method: str, prewarp: float | None, quiet: bool
         ) -> ContinuousStateSpace:
    model = _convertible(model, StateSpaceModel, "d2c")
    method = _method(method, _D2C_METHODS)
    A, B, C, D, dt = model.A, model.B, model.C, model.D, model.dt
    h = _warp(prewarp, dt, method, "d2c")
    n, m = B.shape
    p = model.poles()
    if method == "zoh" and negative_real(p).any() and not np.any(np.abs(p) <= 1e-12):
        Ac, Bc, Cc = zoh_doubled(A, B, C, dt)
        Dc = D.copy()
        if not quiet and Ac.shape[0] > n:
            warnings.warn(
                f"d2c: the model has {Ac.shape[0] - n} pole(s) on the negative real axis "
                f"(z = {p[negative_real(p)][0].real:g}), which no continuous model of its "
                "order samples to; each is doubled into a complex pair at the Nyquist "
                f"frequency (order {n} -> {Ac.shape[0]}, as MATLAB's d2c); method='tustin' "
                "keeps the order", SysidWarning, stacklevel=user_stacklevel())
    elif method == "zoh":
        big = np.eye(n + m)
        big[:n, :n], big[:n, n:] = A, B
        L = _real_log(big, p, method) / dt
        Ac, Bc, Cc, Dc = L[:n, :n], L[:n, n:], C.copy(), D.copy()
    elif method == "foh":
        Ac = _real_log(A, p, method) / dt if n else np.zeros((0, 0))
        Ad, F1, F2 = _hold_integrals(Ac, np.eye(n), dt)
        Bc = np.linalg.solve(F1 + (Ad - np.eye(n)) @ F2, B) if n else np.zeros((0, m))
        Cc, Dc = C.copy(), D - C @ F2 @ Bc
    elif method == "matched":
        Ac, Bc, Cc, Dc = matched_d2c(A, B, C, D, dt)
    else:
        api = A + np.eye(n)
        if n and np.linalg.cond(api) > 1e12:
            raise NumericalError("the model has a pole at z = -1: no Tustin continuous equivalent")
        inv = np.linalg.inv(api) if n else api
        Ac = (2.0 / h) * (np.eye(n) - 2.0 * inv)
        Bc = 2.0 * inv @ B / h
        Cc = 2.0 * C @ inv
        Dc = D - 0.5 * Cc @ B
    out = ContinuousStateSpace(
        Ac, Bc, Cc, Dc, input_names=model.input_names, output_names=model.output_names,
        hold="foh" if method == "foh" else "zoh",
    )
    return carry(model, out, lambda m: _d2c(m, method, prewarp, quiet=True))


def d2d(model: StateSpaceModel, dt: float, method: str = "zoh", *,
        prewarp: float | None = None) -> StateSpaceModel:
    """Resample a discrete model to another sample time (MATLAB's ``d2d``).

    With ``method="zoh"`` and ``dt`` a whole multiple ``k`` of the model's sample time the
    result is exact for any model, poles on the negative real axis included: the input held
    over ``k`` old samples gives ``A^k``, ``(I + A + ... + A^(k-1)) B``, ``C``, ``D``.
    Otherwise the model goes through its continuous equivalent, ``c2d(d2c(model, method),
    dt, method)`` (which needs one: :func:`d2c`'s conditions). The noise model (``K``) is
    not converted; the parameter uncertainty is (the same parameters, through the map).

    Parameters
    ----------
    model : StateSpaceModel or TransferFunction
        A discrete model; a transfer function goes through its realisation.
    dt : float
        The new sample time in seconds.
    method : {"zoh", "foh", "tustin", "bilinear"}
        The hold (or the bilinear map) of both conversions.
    prewarp : float, optional
        Tustin only: the prewarp frequency (rad/s) of both conversions.

    Returns
    -------
    StateSpaceModel
        Sampled every ``dt`` (no noise model).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[-0.5]], [[1.0]], [[1.0]], dt=0.1)   # a pole at z < 0
    >>> r = sysid.d2d(m, 0.3)                                           # 3 samples held
    >>> float(r.A[0, 0]), float(r.B[0, 0]), r.dt
    (-0.125, 0.75, 0.3)
    >>> c = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]], dt=0.2)
    >>> bool(np.isclose(sysid.d2d(c, 0.1).A[0, 0], np.sqrt(0.9)))       # through d2c
    True
    """
    model = _convertible(model, StateSpaceModel, "d2d")
    new = _sample_time(None, dt, 1)
    method = _method(method, _D2C_METHODS)
    if method == "matched":
        raise DataError("d2d resamples through a hold or the bilinear map: method must be "
                        "'zoh', 'foh', 'tustin' or 'bilinear'")
    k = new / model.dt
    if method == "zoh" and abs(k - round(k)) <= 1e-9 * k and round(k) >= 1:
        k = int(round(k))
        n = model.nstates
        Ak, S = np.eye(n), np.zeros((n, n))
        for _ in range(k):  # S = I + A + ... + A^(k-1), Ak = A^k
            S, Ak = S + Ak, Ak @ model.A
        out = StateSpaceModel(Ak, S @ model.B, model.C.copy(), model.D.copy(), dt=new,
                              input_names=model.input_names, output_names=model.output_names,
                              info={"method": f"d2d (zoh, {k} samples held)"})
    else:
        ct = d2c(StateSpaceModel(model.A, model.B, model.C, model.D, dt=model.dt), method,
                 prewarp=prewarp)
        out = c2d(ct, new, "tustin" if method == "bilinear" else method, prewarp=prewarp)
        out.input_names, out.output_names = model.input_names, model.output_names
        out.info = {"method": f"d2d ({method}, through the continuous equivalent)"}
    return carry(model, out, lambda m: d2d(m, new, method, prewarp=prewarp))
