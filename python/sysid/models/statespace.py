"""The identified model: :class:`StateSpaceModel` in innovation form.

.. math::

    x(t+1) = A x(t) + B u(t) + K e(t), \\qquad y(t) = C x(t) + D u(t) + e(t),
    \\qquad E[e e^T] = \\Lambda \\;(\\texttt{noise\\_cov})

Simulation and Kalman prediction run in the Rust core; poles, frequency responses and Markov
parameters are small dense computations done here.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_2d, as_count, as_int, as_matrix, check_covariance, unmask
from .._measured import predict_args
from ..errors import DataError, NumericalError, ShapeError
from .attributes import Matrix, SampleTime
from .linear import DampingTable, damping_table, minimal_basis, transmission_zeros
from .protocol import ModelMixin, TimeResponse, default_length

__all__ = ["StateSpaceModel", "delay_free_order", "delay_states", "ss_parameter_count"]


def minimal_dcgain(model: Any) -> np.ndarray | None:
    """The DC gain of ``model``'s controllable and observable part, when removing the rest
    removes the singularity (an integrator the input does not reach or the output does not
    see, as in the realisation of ``s / (s^2 + s)``); ``None`` when an integrator is left."""
    A, B, C = (np.asarray(x, float) for x in (model.A, model.B, model.C))
    T = minimal_basis(A, B, C, float(np.sqrt(np.finfo(float).eps)))
    if T.shape[1] == A.shape[0]:
        return None
    reduced = type(model)(T.T @ A @ T, T.T @ B, C @ T, model.D, **(
        {"dt": model.dt} if isinstance(model, StateSpaceModel) else {}))
    gain = np.asarray(reduced.freqresp([0.0])[0].real)  # inf at a pole at DC
    return gain if np.isfinite(gain).all() else None


def finite_dcgain(model: Any, at: str) -> np.ndarray:
    """``model``'s DC gain (its response at frequency 0, of its minimal part when the rest
    holds the integrator, :func:`minimal_dcgain`); a :class:`~sysid.NumericalError` when an
    integrator is left, its poles at DC counted where ``at`` (``"z = 1"`` or ``"s = 0"``)."""
    gain = model.freqresp([0.0])[0].real  # inf at a pole at DC
    if np.isfinite(gain).all():
        return gain
    gain = minimal_dcgain(model)
    if gain is not None:
        return gain
    dc = 1.0 if at == "z = 1" else 0.0
    count = sum(abs(p - dc) < 1e-9 for p in model.poles())
    raise NumericalError(
        f"the DC gain is infinite: the model has {count} pole(s) at {at} (an integrator), so "
        "its step response grows without bound; look at step() or freqresp() at low "
        "frequencies instead")


def ss_parameter_count(n: int, m: int, l: int, *, feedthrough: bool = True,
                       noise_model: bool = True, x0: bool = False,
                       n_experiments: int = 1) -> int:
    """Identifiable parameters ``n (2 l + m) + [D] l m + [x0] n n_exp`` of an innovation-form
    model (``n (l + m)`` without ``K``); see :mod:`sysid.validation.criteria`.

    Examples
    --------
    >>> from sysid.models.statespace import ss_parameter_count
    >>> ss_parameter_count(4, 1, 1)        # 4 (2 + 1) + 1
    13
    """
    d = n * ((2 * l if noise_model else l) + m)
    if feedthrough:
        d += l * m
    if x0:
        d += n * n_experiments
    return int(d)


def delay_states(model: Any) -> int:
    """States of the unit-delay chains of known input delays absorbed into a discrete
    state-space model (``info["input_delay"]``, :func:`sysid.models.input_delay.absorb_delay`):
    their initial values are past inputs and their entries fixed, no parameters; 0 when none.

    Examples
    --------
    >>> import sysid
    >>> from sysid.models.input_delay import absorb_delay
    >>> delay_states(absorb_delay(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), [2]))
    2
    """
    k = getattr(model, "info", {}).get("input_delay")
    if k is None:
        return 0
    nd = int(np.sum(np.maximum(np.asarray(k, dtype=int), 0)))
    return nd if nd <= model.nstates else 0


def delay_free_order(model: Any) -> tuple[int, bool]:
    """``(n, feedthrough)`` of the model without its absorbed input-delay states
    (:func:`delay_states`): the order, and whether the delay-free model has a non-zero
    ``D``, that a parameter count charges (absorbing moves a delayed input's feed-through
    into the column of ``C`` at the end of its delay line)."""
    nd = delay_states(model)
    n = int(model.nstates - nd)
    feedthrough = bool(np.any(np.asarray(model.D) != 0))
    if nd:
        ends = n - 1 + np.cumsum([k for k in model.info["input_delay"] if k > 0])
        feedthrough |= bool(np.any(np.asarray(model.C)[:, ends] != 0))
    return n, feedthrough


class StateSpaceModel(ModelMixin):
    """Discrete-time state-space model ``x(t+1) = A x + B u + K e``, ``y = C x + D u + e``.

    Parameters
    ----------
    A, B, C : array_like
        System matrices, shapes ``(n, n)``, ``(n, m)``, ``(l, n)``.
    D : array_like, optional
        Feed-through, ``(l, m)``; zero if omitted.
    K : array_like, optional
        Innovation-form (Kalman predictor) gain, ``(n, l)``; ``None`` for an output-error model.
    dt : float
        Sample time in seconds.
    noise_cov : array_like, optional
        Covariance of the innovations e, ``(l, l)``.
    x0 : array_like, optional
        Initial state estimated with the model, ``(n,)``.
    input_names, output_names : sequence of str, optional
        Channel names.
    info : dict, optional
        How the model was obtained (method, horizon, singular values, ...).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1)
    >>> m
    StateSpaceModel(nstates=1, ninputs=1, noutputs=1, dt=0.1, stable, no noise model)
    >>> m.simulate(np.array([1.0, 0.0, 0.0]))[:, 0]
    array([0. , 1. , 0.5])
    >>> m.markov(3)[:, 0, 0]
    array([0. , 1. , 0.5])

    The matrices are read-only: a model with other values is another model, made from
    copies (or by assigning a whole matrix of the same shape, or another ``dt``, checked as
    the constructor checks them; a replaced ``A, B, C, D, K`` or ``dt`` drops the
    :attr:`uncertainty`, which belonged to the old values, with a warning: see
    :mod:`sysid.models.attributes`)

    >>> m.A[0, 0] = 0.9
    Traceback (most recent call last):
    ...
    ValueError: assignment destination is read-only
    >>> A = m.A.copy(); A[0, 0] = 0.9
    >>> sysid.StateSpaceModel(A, m.B, m.C, dt=m.dt).poles()
    array([0.9+0.j])
    >>> m.A = [[np.nan]]
    Traceback (most recent call last):
    ...
    sysid.errors.NonFiniteError: A has non-finite entries (NaN or Inf)
    >>> m.dt = -0.1
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: dt must be a positive number of seconds, got -0.1; ...
    """

    A, B, C, D, K, noise_cov, x0 = (Matrix() for _ in range(7))
    dt = SampleTime()

    #: Parameter uncertainty (:class:`~sysid.ParameterUncertainty`) attached by the estimator
    #: (``sysid.pem``, ``fit(uncertainty="bootstrap")``, ...); ``None`` when unknown.
    uncertainty: Any = None

    def __init__(
        self,
        A: Any,
        B: Any,
        C: Any,
        D: Any = None,
        K: Any = None,
        *,
        dt: float = 1.0,
        noise_cov: Any = None,
        x0: Any = None,
        input_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
        info: dict[str, Any] | None = None,
    ) -> None:
        A = as_matrix(A, "A", (None, None))
        n = A.shape[0]
        if A.shape[1] != n:
            raise ShapeError(f"A has shape {A.shape} but should be square")
        B = np.asarray(unmask(B, "B"), dtype=float)
        if B.ndim < 2 and n and B.size % n:
            raise ShapeError(
                f"B has {B.size} entries but A is {n}x{n}: B must be {n}x(number of inputs), "
                f"e.g. a column of {n} values for one input"
            )
        if B.size == 0:  # no inputs (or no states): (n, m) zeros, m from a 2-D B
            B = np.zeros((n, B.shape[1] if B.ndim == 2 and B.shape[0] == n else 0))
        B = as_matrix(B.reshape(n, -1) if B.ndim < 2 else B, "B", (n, None)) if B.size else B
        C = np.asarray(unmask(C, "C"), dtype=float)
        if C.ndim < 2 and C.size != n:
            raise ShapeError(
                f"C has {C.size} entries but A is {n}x{n}: C must be (number of outputs)x{n}, "
                f"e.g. a row of {n} values for one output"
            )
        C = as_matrix(C, "C", (None, n))
        m, l = B.shape[1], C.shape[0]
        D = (
            np.zeros((l, m))
            if D is None
            else as_matrix(np.reshape(D, (l, m)) if np.size(D) == l * m else D, "D", (l, m))
        )
        self.A, self.B, self.C, self.D = A, B, C, D
        self.K = None if K is None else as_matrix(K, "K", (n, l))
        self.noise_cov = None if noise_cov is None else check_covariance(
            as_matrix(noise_cov, "noise_cov", (l, l)), "noise_cov")
        if x0 is not None and np.size(x0) != n:
            raise ShapeError(f"x0 has {np.size(x0)} entries but the model has {n} states")
        self.x0 = None if x0 is None else as_matrix(np.reshape(x0, (n, 1)), "x0", (n, 1))[:, 0]
        self.dt = dt  # checked by SampleTime (as_dt), as every later assignment
        self.input_names = (
            list(input_names) if input_names is not None else [f"u{i}" for i in range(m)]
        )
        self.output_names = (
            list(output_names) if output_names is not None else [f"y{i}" for i in range(l)]
        )
        if len(self.input_names) != m or len(self.output_names) != l:
            raise ShapeError("the number of channel names does not match B and C")
        self.info: dict[str, Any] = dict(info or {})

    # -- sizes (python-control names) ---------------------------------------------------
    @property
    def nstates(self) -> int:
        """Number of states n."""
        return self.A.shape[0]

    @property
    def ninputs(self) -> int:
        """Number of inputs m."""
        return self.B.shape[1]

    @property
    def noutputs(self) -> int:
        """Number of outputs l."""
        return self.C.shape[0]

    # -- time domain --------------------------------------------------------------------
    def _x0(self, x0: Any) -> np.ndarray | None:
        if x0 is None:
            return None
        if isinstance(x0, str):
            if x0 == "model":
                return self.x0
            raise DataError(f"x0 must be an array, None or 'model', got {x0!r}")
        return as_matrix(np.reshape(np.asarray(x0, dtype=float), (-1, 1)), "x0", (self.nstates, 1))[
            :, 0
        ]

    def _u(self, u: Any, n_samples: int | None = None) -> np.ndarray:
        if u is None:
            if self.ninputs:
                raise DataError("u is required: the model has inputs")
            if n_samples is None:
                raise DataError(
                    "u is None but the model has no inputs, so nothing gives the number of "
                    "samples: pass an empty input array of that length, e.g. "
                    "model.simulate(np.zeros((n_samples, 0))) (its noise-free output is "
                    "zero from rest, or the free response from x0)")
            return np.zeros((n_samples, 0))
        return as_2d(u, "u", ncols=self.ninputs, allow_empty=self.ninputs == 0)

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        """Simulate the deterministic part from ``x0`` (zero by default).

        Parameters
        ----------
        u : array_like
            Inputs ``(n_samples, ninputs)``.
        x0 : array_like or "model", optional
            Initial state; ``"model"`` uses the state estimated with the model.

        Returns
        -------
        ndarray
            Outputs ``(n_samples, noutputs)``.

        Examples
        --------
        >>> import sysid
        >>> sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]]).simulate([1, 1, 1])[:, 0]
        array([0. , 1. , 1.9])
        """
        u = self._u(u)
        try:
            return _sysid.simulate(self.A, self.B, self.C, self.D, u, self._x0(x0))
        except NumericalError as e:
            if not self.is_stable() or "overflow" not in str(e):
                raise
            big = float(np.max(np.abs(u))) if u.size else 0.0
            raise NumericalError(
                f"the simulated output overflowed although the model is stable: the input "
                f"reaches {big:.3g}, too close to the largest double ({np.finfo(float).max:.3g}) "
                "for the model's gain; scale the input (and the model) to order 1"
            ) from None

    def predict(self, u: Any, y: Any = None, horizon: int = 1, x0: Any = None) -> np.ndarray:
        """``horizon``-step-ahead prediction ``ŷ(t | t - horizon)`` with the Kalman predictor.

        Uses ``K``; a model without ``K`` (output error) predicts by simulation.

        Parameters
        ----------
        u, y : array_like
            Measured inputs and outputs; or a single-experiment record
            (:class:`~sysid.IOData`) in ``u``'s place and ``y`` left out (MATLAB's
            ``predict(sys, data, K)``).
        horizon : int
            Steps ahead, ``>= 1``.
        x0 : array_like or "model", optional
            Predictor state at time 0.

        Returns
        -------
        ndarray
            Predictions ``(n_samples, noutputs)``.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> m = sysid.StateSpaceModel([[0.9]], np.zeros((1, 0)), [[1.0]], K=[[0.9]])
        >>> m.predict(None, [1.0, 0.9, 0.81])[:, 0]
        array([0.  , 0.9 , 0.81])
        """
        u, y = predict_args(u, y)
        y = as_2d(y, "y", ncols=self.noutputs)
        u = self._u(u, y.shape[0])
        if u.shape[0] != y.shape[0]:
            raise ShapeError(f"u has {u.shape[0]} samples but y has {y.shape[0]}")
        if isinstance(horizon, (float, np.floating)) and horizon == np.inf:
            return self.simulate(u, x0)  # MATLAB's predict(..., Inf): the simulation
        horizon = as_int(horizon, "horizon", alt="np.inf (the simulation)")
        K = self.K if self.K is not None else np.zeros((self.nstates, self.noutputs))
        return _sysid.predict(self.A, self.B, self.C, self.D, K, u, y, self._x0(x0), int(horizon))

    # -- system properties --------------------------------------------------------------
    def poles(self, std: bool = False, method: str = "linear") -> Any:
        """Eigenvalues of A (discrete-time poles).

        Parameters
        ----------
        std : bool
            Also return their standard deviations (needs :attr:`uncertainty`): a pair
            ``(poles, sd)`` with ``sd`` complex, ``sd.real`` the std of the real part and
            ``sd.imag`` that of the imaginary part of each pole.
        method : {"linear", "monte-carlo"}
            First-order perturbation with left and right eigenvectors, or sampling. Poles
            that coincide with another (numerically, or within their uncertainty), where
            first order does not hold, get the Monte Carlo value and an
            ``UncertaintyWarning`` says so.

        A model with absorbed input delays (:func:`sysid.models.input_delay.absorb_delay`)
        has its delay-free model's poles, then one exact zero per delay state (standard
        deviation 0: the delay line has no parameters).

        Examples
        --------
        >>> import sysid
        >>> sysid.StateSpaceModel([[0.5, 0], [0, -0.2]], [[1], [1]], [[1, 1]]).poles()
        array([ 0.5+0.j, -0.2+0.j])
        """
        nd = delay_states(self)
        n = self.nstates - nd
        if nd and not np.any(self.A[n:, :n]) and not np.any(np.triu(self.A[n:, n:])):
            # block triangular with a nilpotent delay line: its zeros are exact
            free = self.info.get("delay_free")
            zeros = np.zeros(nd, dtype=complex)
            if not std:
                return np.r_[np.linalg.eigvals(self.A[:n, :n]).astype(complex), zeros]
            if (isinstance(free, StateSpaceModel) and free.uncertainty is not None
                    and np.array_equal(free.A, self.A[:n, :n])):
                p, sd = free.poles(std=True, method=method)
                return np.r_[p, zeros], np.r_[sd, zeros]
        if std:
            from .pole_uncertainty import pole_std

            return pole_std(self, method)
        return np.linalg.eigvals(self.A).astype(complex)

    def is_stable(self) -> bool:
        """True when every pole lies strictly inside the unit circle."""
        return bool(self.nstates == 0 or np.max(np.abs(self.poles())) < 1.0)

    def markov(self, count: int, std: bool = False) -> Any:
        """Markov parameters ``D, CB, CAB, ...``, shape ``(count, noutputs, ninputs)``.

        With ``std=True`` (needs :attr:`uncertainty`): ``(markov, std)``, first order.

        Examples
        --------
        >>> import sysid
        >>> sysid.StateSpaceModel([[0.5]], [[2.0]], [[1.0]], [[3.0]]).markov(3)[:, 0, 0]
        array([3., 2., 1.])
        """
        if std:
            from .uncertainty import complex_std

            return complex_std(self, lambda m: m.markov(count))
        count = as_count(count, "count", 8 * self.noutputs * self.ninputs, lo=0)
        out = np.empty((count, self.noutputs, self.ninputs))
        if count:
            out[0] = self.D
        ab = self.B
        for k in range(1, count):
            out[k] = self.C @ ab
            ab = self.A @ ab
        return out

    def freqresp(self, omega: Any, std: bool = False) -> Any:
        """Frequency response ``C (z I - A)^{-1} B + D`` at ``z = exp(j omega dt)``.

        Parameters
        ----------
        omega : array_like
            Angular frequencies in rad/s (the Nyquist frequency is ``pi / dt``).
        std : bool
            Also return the first-order std (needs :attr:`uncertainty`), complex: ``sd.real``
            of the real part, ``sd.imag`` of the imaginary part.

        Returns
        -------
        ndarray
            Complex response, shape ``(len(omega), noutputs, ninputs)``; with ``std=True`` the
            pair ``(H, sd)``. A frequency at a pole (``exp(j omega dt)`` an eigenvalue of
            ``A``) gives ``inf``.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> m = sysid.StateSpaceModel([[0.5]], [[0.5]], [[1.0]], dt=1.0)
        >>> float(np.round(m.freqresp([0.0])[0, 0, 0].real, 12))
        1.0
        """
        w = np.atleast_1d(np.asarray(omega, dtype=float))
        if w.ndim != 1 or not np.isfinite(w).all():
            raise DataError("omega must be a finite 1-D array of angular frequencies (rad/s)")
        if std:
            from .uncertainty import freqresp_std

            return freqresp_std(self, w)
        z = np.exp(1j * w * self.dt)
        n = self.nstates
        # Hessenberg-free but well-conditioned enough: one complex solve per frequency
        eye = np.eye(n)
        out = np.empty((w.size, self.noutputs, self.ninputs), dtype=complex)
        for i, zi in enumerate(z):
            try:
                out[i] = (self.C @ np.linalg.solve(zi * eye - self.A, self.B) + self.D
                          if n else self.D)
            except np.linalg.LinAlgError:  # omega at a pole: infinite gain, as MATLAB's
                out[i] = np.inf
        return out

    def impulse(self, n_samples: int | None = None, std: bool = False) -> TimeResponse:
        """Impulse responses: the Markov parameters; see :func:`sysid.impulse` (``std=True``:
        with a band)."""
        if std:
            from .uncertainty import response_band

            return response_band(self, self.impulse(n_samples), lambda m, n: m.impulse(n))
        N = default_length(self, n_samples)
        with np.errstate(over="ignore", invalid="ignore"):
            h = self.markov(N)
        if not np.isfinite(h).all():  # as step(), whose simulation raises on overflow
            k = int(np.argwhere(~np.isfinite(h))[0][0])
            raise NumericalError(
                f"numerical failure in impulse: the impulse response overflowed at sample {k} "
                f"of {N}; the model is unstable over this record length (largest |pole| "
                f"{float(np.max(np.abs(self.poles()))):.6g}): pass fewer n_samples")
        return TimeResponse("impulse", np.arange(N) * self.dt, h, self)

    def dcgain(self, std: bool = False) -> Any:
        """Steady-state gain ``C (I - A)^{-1} B + D``, shape ``(noutputs, ninputs)``; with
        ``std=True`` (needs :attr:`uncertainty`) the pair ``(gain, std)``, first order."""
        if std:
            from .uncertainty import complex_std

            return complex_std(self, lambda m: m.dcgain())
        return finite_dcgain(self, "z = 1")

    def __repr__(self) -> str:
        stab = "stable" if self.is_stable() else "UNSTABLE"
        noise = "innovation form" if self.K is not None else "no noise model"
        method = f", {self.info['method']}" if "method" in self.info else ""
        return (
            f"StateSpaceModel(nstates={self.nstates}, ninputs={self.ninputs}, "
            f"noutputs={self.noutputs}, dt={self.dt:g}, {stab}, {noise}{method})"
        )

    # -- the model protocol (sysid.Model) ------------------------------------------------
    @property
    def n_parameters(self) -> int:
        """Identifiable parameters: ``n (2 l + m)`` with ``K`` (``n (l + m)`` without) plus
        ``l m`` when ``D`` is non-zero; see :func:`sysid.n_parameters`. Known input delays
        absorbed as states (``info["input_delay"]``, :mod:`sysid.models.input_delay`) add
        none: ``n`` is the delay-free model's order and its ``D`` says whether there is a
        feed-through (as MATLAB, which does not count ``InputDelay`` as free parameters).

        Examples
        --------
        >>> import sysid
        >>> from sysid.models.input_delay import absorb_delay
        >>> m = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], K=[[0.3]])
        >>> d = absorb_delay(m, [5])
        >>> d.nstates, d.n_parameters, m.n_parameters
        (6, 3, 3)
        """
        n, feedthrough = delay_free_order(self)
        return ss_parameter_count(n, self.ninputs, self.noutputs, feedthrough=feedthrough,
                                  noise_model=self.K is not None)

    def _select(self, iy: list[int], iu: list[int]) -> StateSpaceModel:
        """Outputs ``iy`` from inputs ``iu`` (:meth:`select`): the columns of ``B``, rows of
        ``C``, ``D``, and the innovations of the outputs kept (``K``'s columns and their
        covariance), as MATLAB's ``sys(i, j)``."""
        from .subsystem import names

        return StateSpaceModel(
            self.A, self.B[:, iu], self.C[iy], self.D[np.ix_(iy, iu)],
            None if self.K is None else self.K[:, iy], dt=self.dt,
            noise_cov=None if self.noise_cov is None else self.noise_cov[np.ix_(iy, iy)],
            x0=self.x0, input_names=names(self.input_names, iu),
            output_names=names(self.output_names, iy), info=self.info)

    def to_statespace(self) -> StateSpaceModel:
        """The model itself (it is already in state-space form)."""
        return self

    def to_dict(self) -> dict[str, Any]:
        """Matrices, sample time, names and info (see :func:`sysid.save_model`)."""
        return {"nstates": self.nstates, "ninputs": self.ninputs, "noutputs": self.noutputs,
                "dt": self.dt, "A": self.A, "B": self.B, "C": self.C, "D": self.D,
                "K": self.K, "noise_cov": self.noise_cov, "x0": self.x0,
                "input_names": list(self.input_names), "output_names": list(self.output_names),
                "info": self.info}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> StateSpaceModel:
        """Inverse of :meth:`to_dict`, checking the shapes."""
        n, m, l = int(d["nstates"]), int(d["ninputs"]), int(d["noutputs"])

        def arr(key: str, shape: tuple[int, ...]) -> np.ndarray | None:
            v = d.get(key)
            return None if v is None else np.asarray(v, dtype=float).reshape(shape)

        return cls(
            arr("A", (n, n)), arr("B", (n, m)), arr("C", (l, n)), arr("D", (l, m)),
            arr("K", (n, l)), dt=float(d["dt"]), noise_cov=arr("noise_cov", (l, l)),
            x0=arr("x0", (n,)), input_names=d.get("input_names"),
            output_names=d.get("output_names"), info=d.get("info") or {},
        )

    # -- analysis shortcuts ---------------------------------------------------------------
    def zeros(self) -> np.ndarray:
        """Transmission zeros; see :func:`sysid.zeros`."""
        return transmission_zeros(self.A, self.B, self.C, self.D)

    def damp(self, std: bool = False) -> DampingTable:
        """Pole frequencies (rad/s, Hz) and damping; see :func:`sysid.damp` (``std=True``:
        with first-order standard deviations from :attr:`uncertainty`)."""
        if std:
            from .pole_uncertainty import damping_std

            d = damping_std(self, self.dt)
            return DampingTable(d["poles"], d["s"].astype(complex), self.dt, std=d)
        return damping_table(self.poles(), self.dt)

    # -- parameter uncertainty (sysid.models.uncertainty) ---------------------------------
    @property
    def covariance(self) -> np.ndarray | None:
        """Covariance of the free parameters (``uncertainty.covariance``), or ``None``."""
        return None if self.uncertainty is None else self.uncertainty.covariance

    @property
    def std(self) -> dict[str, np.ndarray] | None:
        """Standard deviations of the entries of ``A, B, C, D`` (and ``K``), first order from
        :attr:`uncertainty`; ``None`` without one.

        The entries are those of this realisation: for a fully parameterised model the
        similarity directions carry no information and the std refers to the identifiable
        directions only (the minimum-norm representative). Poles, frequency responses and
        other invariants are the meaningful quantities there.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
        >>> m.uncertainty = sysid.ParameterUncertainty(
        ...     [0.5, 1.0], np.diag([1e-4, 4e-4]),
        ...     lambda t: sysid.StateSpaceModel([[t[0]]], [[t[1]]], [[1.0]]))
        >>> {k: np.round(v, 4).tolist() for k, v in m.std.items()}
        {'A': [[0.01]], 'B': [[0.02]], 'C': [[0.0]], 'D': [[0.0]]}
        """
        if self.uncertainty is None:
            return None
        from .uncertainty import complex_std

        names = ["A", "B", "C", "D"] + (["K"] if self.K is not None else [])

        def parts(m: StateSpaceModel) -> np.ndarray:
            mats = [m.A, m.B, m.C, m.D] + ([m.K if m.K is not None else np.zeros(self.K.shape)]
                                           if self.K is not None else [])
            return np.concatenate([x.ravel() for x in mats])

        _, sd = complex_std(self, parts)
        out, o = {}, 0
        for name in names:
            shape = getattr(self, name).shape
            size = int(np.prod(shape))
            out[name] = sd[o:o + size].reshape(shape)
            o += size
        return out
