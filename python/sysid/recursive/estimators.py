r"""Online estimators of single-output polynomial models.

The model ``A(q) y(t) = sum_j B_j(q)/F_j(q) u_j(t - nk_j) + C(q)/D(q) e(t)`` is written as
a pseudo-linear regression ``y(t) = phi(t)^T theta + e(t)`` with
``theta = [a, b_1, .., b_m, c, d, f_1, .., f_m]`` (MATLAB's order). Each sample gives the
prior prediction ``yhat(t) = phi(t)^T theta(t-1)``, the error ``eps = y - yhat`` and the
update ``theta(t) = theta(t-1) + K(t) eps(t)`` with

* ``"forgetting"``: ``K = P psi / (lambda + psi^T P psi)``,
  ``P <- (P - K psi^T P) / lambda`` (recursive least squares for ARX);
* ``"kalman"``: ``K = P psi / (R2 + psi^T P psi)``, ``P <- P - K psi^T P + R1``;
* ``"normalized_gradient"``: ``K = gamma psi / (bias + psi^T psi)``;
* ``"gradient"``: ``K = gamma psi``;

where ``psi`` is the gradient of the prediction (``phi`` filtered by ``D/C``, ``D/(C F_j)``
or ``1/C``; ``psi = phi`` for ARX): the recursive prediction-error method. With those
filters, method ``"forgetting"`` starts with a smaller factor that tends to ``lambda``,
``lambda(t) = 0.99 lambda(t-1) + 0.01 lambda`` from ``min(lambda, 0.95)`` (Ljung &
Soderstrom 1983; ``startup_forgetting=False`` turns it off): it forgets the first updates,
made from the starting values, so that ``covariance`` times the noise variance is the
estimate's covariance (with a constant ``lambda = 1`` a few percent of the estimates stayed
many standard deviations off). ``step`` and ``run`` execute the same Rust code, so a record
processed either way gives bit-identical results.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_2d, as_dt, as_int, as_option
from ..errors import DataError, ShapeError, is_record


def _orders(v: Any, name: str, lo: int = 0) -> list[int]:
    vals = list(np.atleast_1d(np.asarray(v, dtype=object)).ravel())
    if not vals:
        raise DataError(f"{name} needs one entry per input, got none")
    return [as_int(x, name, lo) for x in vals]


def _one_vector(first: Any, rest: tuple[Any, ...], names: str, who: str) -> list[Any] | None:
    """MATLAB's ``recursiveARX([na nb nk])``: the orders as one vector in the first argument
    (``names`` as MATLAB writes them, the per-input ones with a ``*``), split into the
    constructor's arguments; None when the orders come separately."""
    if np.ndim(first) == 0 or any(r is not None for r in rest):
        return None
    vec = list(np.asarray(first, dtype=object).ravel())
    fields = names.split()
    scalar = sum(1 for f in fields if not f.endswith("*"))
    per = len(fields) - scalar
    m, left = divmod(len(vec) - scalar, per)
    if m < 1 or left:
        raise DataError(
            f"{who}'s orders as one vector are [{', '.join(f.rstrip('*') for f in fields)}] "
            f"({'one number each' if per == len(fields) else 'the starred ones one per input'}"
            f": {' '.join(fields)}), got {len(vec)} numbers; or give them separately")
    out, k = [], 0
    for f in fields:
        n = m if f.endswith("*") else 1
        out.append(vec[k:k + n] if f.endswith("*") else vec[k])
        k += n
    return out


def _given(first: Any, rest: tuple[Any, ...], names: str, who: str) -> list[Any]:
    """The constructor's orders from either form (:func:`_one_vector`), each one given (the
    delay ``nk``, last, defaults to 1), or a :class:`DataError` naming the missing ones."""
    one = _one_vector(first, rest, names, who)
    vals = one if one is not None else [first, *rest]
    fields = [f.rstrip("*") for f in names.split()]
    missing = [f for f, v in zip(fields[:-1], vals[:-1]) if v is None]
    if missing:
        said = " and ".join([", ".join(missing[:-1]), missing[-1]] if len(missing) > 1
                            else missing)
        raise DataError(f"{who} needs {said}: {who}({', '.join(fields)}) or "
                        f"{who}([{', '.join(fields)}])")
    vals[-1] = 1 if vals[-1] is None else vals[-1]
    return vals


def _per_input(v: Any, m: int, name: str, lo: int = 0) -> list[int]:
    vals = _orders(v, name, lo)
    if len(vals) == 1:
        return vals * m
    if len(vals) != m:
        raise DataError(f"{name} has {len(vals)} entries but the model has {m} input(s); "
                        f"give one per input or a single number for all")
    return vals


class RecursiveResult:
    """What :meth:`run` returns: the prior predictions and the parameter trajectory.

    Attributes
    ----------
    yhat : ndarray (n_samples,)
        One-step predictions ``yhat(t | t-1)`` made before each update.
    error : ndarray (n_samples,)
        Prediction errors ``y - yhat``.
    parameters : ndarray (n_samples, n_parameters) or None
        ``theta`` after each sample (``store_parameters=True``).
    names : list of str
        Parameter names (``a1``, ``b1_1``, ...).
    """

    def __init__(self, yhat: np.ndarray, error: np.ndarray, parameters: np.ndarray | None,
                 names: list[str], dt: float) -> None:
        self.yhat, self.error, self.parameters, self.names, self.dt = (
            yhat, error, parameters, names, dt)

    def to_pandas(self) -> Any:
        """A DataFrame indexed by time: ``yhat``, ``error`` and one column per parameter."""
        import pandas as pd

        cols: dict[str, Any] = {"yhat": self.yhat, "error": self.error}
        if self.parameters is not None:
            cols.update({n: self.parameters[:, i] for i, n in enumerate(self.names)})
        return pd.DataFrame(cols, index=np.arange(self.yhat.size) * self.dt)

    def plot(self, fig: Any = None) -> Any:
        """Parameter trajectories (top) and prediction errors (bottom); returns the figure."""
        import matplotlib.pyplot as plt

        fig = fig or plt.figure()
        ax1, ax2 = fig.subplots(2, 1, sharex=True)
        t = np.arange(self.yhat.size) * self.dt
        if self.parameters is not None:
            for i, n in enumerate(self.names):
                ax1.plot(t, self.parameters[:, i], label=n)
            ax1.legend(fontsize="small", ncol=4)
        ax1.set_ylabel("parameters")
        ax2.plot(t, self.error, lw=0.5)
        ax2.set_ylabel("prediction error")
        ax2.set_xlabel("time")
        return fig

    def summary(self) -> str:
        """The record's length, the prediction error's root mean square over the whole
        record and its last tenth, and the final parameters."""
        tail = self.error[-max(1, self.error.size // 10):]
        lines = [repr(self), "  rms prediction error, last tenth: "
                 f"{float(np.sqrt(np.mean(tail ** 2))) if tail.size else float('nan'):.4g}"]
        if self.parameters is not None and self.parameters.shape[0]:
            lines += [f"  {n} = {v:.6g}" for n, v in zip(self.names, self.parameters[-1])]
        return "\n".join(lines)

    def __repr__(self) -> str:
        rms = float(np.sqrt(np.mean(self.error ** 2))) if self.error.size else float("nan")
        return (f"RecursiveResult({self.yhat.size} samples, {len(self.names)} parameters, "
                f"rms prediction error {rms:.4g})")


class _Recursive:
    """Shared machinery of the four online estimators (see the module documentation)."""

    _kind = ""

    def __init__(self, na: int, nb: Any, nc: int, nd: int, nf: Any, nk: Any, *,
                 method: str, forgetting: float, process_noise: Any, noise_variance: float,
                 gain: float, bias: float, initial_parameters: Any, initial_covariance: Any,
                 dt: float | None, startup_forgetting: bool = True) -> None:
        method = as_option(method, "recursive_method", "method")
        na_i = as_int(na, "na", 0)  # the orders in the signature's order: na first
        nb_v = _orders(nb, "nb")
        m = len(nb_v)
        nc_i, nd_i = as_int(nc, "nc", 0), as_int(nd, "nd", 0)
        nf_v, nk_v = _per_input(nf, m, "nf"), _per_input(nk, m, "nk")
        self._orders = (na_i, nb_v, nc_i, nd_i, nf_v, nk_v)
        # dt: the constructor's, else that of the first record run() gets (1 until then)
        self.method, self._dt = method, 1.0 if dt is None else as_dt(dt)
        self._dt_from = None if dt is None else "the constructor's dt"
        P0 = np.asarray(initial_covariance, dtype=float)
        theta0 = None if initial_parameters is None else np.ascontiguousarray(
            np.asarray(initial_parameters, dtype=float).ravel())

        def build(q: np.ndarray | None) -> Any:
            return _sysid.RecursiveEstimator(
                *self._orders, method=method, forgetting=float(forgetting), process_noise=q,
                noise_variance=float(noise_variance), gain=float(gain), bias=float(bias),
                theta0=theta0, p0=float(P0) if P0.ndim == 0 else 1.0,
                startup_forgetting=bool(startup_forgetting))

        # the core checks the structure (and its size) first: the process-noise matrix is
        # sized from the parameter count it accepted, never from unchecked orders
        self._core = build(None)
        if process_noise is not None:
            p = self.n_parameters
            q = np.asarray(process_noise, dtype=float)
            q = q * np.eye(p) if q.ndim == 0 else q
            if q.shape != (p, p):
                raise ShapeError(f"process_noise has shape {q.shape} but should be ({p}, {p}) "
                                 f"or a number (times the identity)")
            self._core = build(np.ascontiguousarray(q))
        if P0.ndim != 0:
            self._set_covariance(P0, "initial_covariance")

    # -- state ---------------------------------------------------------------------------
    @property
    def dt(self) -> float:
        """Sample time (settable): the constructor's, else the first record's, else 1."""
        return self._dt

    @dt.setter
    def dt(self, value: Any) -> None:
        self._dt, self._dt_from = as_dt(value), "the dt set on it"

    @property
    def ninputs(self) -> int:
        """Number of inputs."""
        return len(self._orders[1])

    @property
    def n_parameters(self) -> int:
        """Number of parameters."""
        return int(self._core.n_parameters)

    @property
    def parameters(self) -> np.ndarray:
        """Current ``theta = [a, b_j, c, d, f_j]`` (settable)."""
        return np.asarray(self._core.parameters)

    @parameters.setter
    def parameters(self, theta: Any) -> None:
        self._core.set_parameters(np.ascontiguousarray(np.asarray(theta, float).ravel()))

    @property
    def covariance(self) -> np.ndarray:
        """Current ``P`` (settable; for the forgetting factor and Kalman methods the
        parameter covariance up to the noise variance)."""
        return np.asarray(self._core.covariance)

    @covariance.setter
    def covariance(self, P: Any) -> None:
        self._set_covariance(P, "covariance")

    def _set_covariance(self, P: Any, name: str) -> None:
        p = self.n_parameters
        P = np.asarray(P, dtype=float)
        P = P * np.eye(p) if P.ndim == 0 else P
        if P.shape != (p, p):
            raise ShapeError(f"{name} has shape {P.shape} but should be ({p}, {p}) (the model "
                             f"has {p} parameters) or a number (times the identity)")
        self._core.set_covariance(np.ascontiguousarray(P))

    @property
    def regressor(self) -> np.ndarray:
        """The regressor ``phi`` of the last sample."""
        return np.asarray(self._core.regressor)

    @property
    def samples(self) -> int:
        """Samples processed so far."""
        return int(self._core.samples)

    @property
    def rejected(self) -> int:
        """Updates refused because they would have made the estimate non-finite."""
        return int(self._core.rejected)

    @property
    def names(self) -> list[str]:
        """Parameter names in the order of :attr:`parameters`."""
        na, nb, nc, nd, nf, _ = self._orders
        out = [f"a{i + 1}" for i in range(na)]
        out += [f"b{j + 1}_{i + 1}" for j, n in enumerate(nb) for i in range(n)]
        out += [f"c{i + 1}" for i in range(nc)] + [f"d{i + 1}" for i in range(nd)]
        return out + [f"f{j + 1}_{i + 1}" for j, n in enumerate(nf) for i in range(n)]

    def _split(self) -> dict[str, Any]:
        na, nb, nc, nd, nf, _ = self._orders
        th = self.parameters
        cuts = np.cumsum([na, *nb, nc, nd, *nf])[:-1]
        parts = np.split(th, cuts)
        m = len(nb)
        return {"a": parts[0], "b": parts[1:1 + m], "c": parts[1 + m], "d": parts[2 + m],
                "f": parts[3 + m:]}

    # -- data ----------------------------------------------------------------------------
    def _u_row(self, u: Any) -> list[float]:
        row = np.asarray(u, dtype=float).ravel()
        if row.size != self.ninputs:
            raise ShapeError(f"u has {row.size} value(s) but the model has {self.ninputs} "
                             f"input(s); pass one value per input")
        return [float(v) for v in row]

    def step(self, u: Any, y: float) -> float:
        """Process one sample (``u`` at time t, one value per input; ``y`` at time t);
        returns the prediction ``yhat(t | t-1)`` made before the update."""
        yv = np.asarray(y, dtype=float)
        if yv.size != 1:
            raise ShapeError(f"y must be one number per sample (single output), got shape "
                             f"{yv.shape}; use run() for a record")
        return float(self._core.step(self._u_row(u), float(yv.ravel()[0])))

    def run(self, u: Any, y: Any = None, *, store_parameters: bool = True) -> RecursiveResult:
        """Process a record in the Rust core (GIL released, Ctrl-C honoured): an
        :class:`~sysid.IOData` of one experiment and one output, or the arrays
        ``u (n_samples, ninputs)`` and ``y (n_samples,)``; the estimator's state carries
        over, so records can be fed in pieces. A record's ``dt`` becomes the estimator's
        when its constructor got none."""
        rec_dt = None
        if is_record(u):
            if y is not None:
                raise DataError("run takes a record (IOData) or the arrays u and y, not both: "
                                "run(data) or run(data.u, data.y)")
            if u.n_experiments != 1:
                raise DataError(f"the record has {u.n_experiments} experiments; an online "
                                "estimator runs through one: run(data.experiment(k)) each")
            if u.n_outputs != 1:
                raise ShapeError(f"the record has {u.n_outputs} outputs; online estimators "
                                 "model one output: make one estimator per output and run "
                                 "each on data.select(outputs=[k])")
            rec_dt = u.dt
            u, y = u.u, u.y
        if y is None:
            raise DataError("run needs the outputs: run(data) for a record (IOData), or "
                            "run(u, y) with the arrays u (n_samples, ninputs), y (n_samples,)")
        y2 = as_2d(y, "y")
        if y2.shape[1] != 1:
            raise ShapeError(f"y has shape {y2.shape}: online estimators model one output; "
                             f"make one estimator per output")
        u2 = as_2d(u, "u", ncols=self.ninputs)
        if u2.shape[0] != y2.shape[0]:
            raise ShapeError(f"u has {u2.shape[0]} samples but y has {y2.shape[0]}")
        yv = np.ascontiguousarray(y2[:, 0])
        if rec_dt is not None:
            self._take_dt(rec_dt)
        before = self.rejected
        yhat, th = self._core.run(np.ascontiguousarray(u2), yv, bool(store_parameters))
        refused = self.rejected - before
        if refused > 0.1 * max(len(yv), 1) or not np.all(np.isfinite(self.parameters)):
            import warnings

            from .._checks import user_stacklevel
            from ..errors import StabilityWarning

            warnings.warn(StabilityWarning(
                f"the {self.method} updates diverged: {refused} of {len(yv)} were refused "
                f"(largest parameter {np.max(np.abs(self.parameters)):.3g}); the estimate "
                "is not to be trusted: lower the gain (or use method='forgetting' or "
                "'kalman'), or normalise the signals"), stacklevel=user_stacklevel())
        return RecursiveResult(np.asarray(yhat), yv - yhat, None if th is None
                               else np.asarray(th), self.names, self.dt)

    def _take_dt(self, dt: Any) -> None:
        """The record's sample time becomes the estimator's when none was given (to the
        constructor or by an earlier record); a different one raises."""
        dt = float(dt)
        if self._dt_from is None:
            self._dt, self._dt_from = dt, "the dt of the first record it ran through"
        elif abs(dt - self.dt) > 1e-9 * max(dt, self.dt):
            raise DataError(
                f"the record's sample time dt={dt:g} differs from the estimator's dt="
                f"{self.dt:g} ({self._dt_from}); the parameters would mean other dynamics: "
                f"resample the record (sysid.resample) or make the estimator with "
                f"dt={dt:g}")

    def reset_history(self) -> None:
        """Forget the signal history (keep the parameters and ``P``): the next sample
        starts a new record from rest."""
        self._core.reset_history()

    def copy(self) -> Any:
        """An independent copy of the estimator and its state."""
        import copy

        new = copy.copy(self)
        new._core = self._core.copy()
        return new

    def to_model(self) -> Any:
        """The current estimate as a :class:`~sysid.PolynomialModel`."""
        from ..polynomial.model import PolynomialModel

        p = self._split()
        m = len(p["b"])
        model = PolynomialModel([[p["a"]]], [list(p["b"])], [self._orders[5]], self.dt,
                                c=[p["c"]], d=[p["d"]], f=[list(p["f"])])
        model.info = {"method": f"recursive {self._kind} ({self.method})",
                      "samples": self.samples}
        del m
        return model

    def __repr__(self) -> str:
        na, nb, nc, nd, nf, nk = self._orders
        return (f"Recursive{self._kind.upper()}(na={na}, nb={nb}, nc={nc}, nd={nd}, nf={nf}, "
                f"nk={nk}, method={self.method!r}, {self.samples} samples)")


_SETTINGS_DOC = """
    method : {"forgetting", "kalman", "normalized_gradient", "gradient"}
        How the parameters follow the data (see :mod:`sysid.recursive.estimators`).
    forgetting : float
        Forgetting factor ``lambda`` in ``(0, 1]`` (method ``"forgetting"``).
    process_noise : float or array_like (p, p), optional
        ``R1`` of method ``"kalman"`` (default ``0.1 I``).
    noise_variance : float
        ``R2`` of method ``"kalman"``.
    gain, bias : float
        ``gamma`` and the bias of the gradient methods.
    initial_parameters : array_like, optional
        ``theta(0)`` (zeros by default).
    initial_covariance : float or array_like (p, p)
        ``P(0)`` (a number: times the identity; default 1e4).
    dt : float, optional
        Sample time of the models :meth:`to_model` returns and of :meth:`run`'s time axis;
        by default the ``dt`` of the first record (:class:`~sysid.IOData`) :meth:`run`
        gets, else 1. A record of another ``dt`` than the estimator's raises.
"""

_STARTUP_DOC = """    startup_forgetting : bool
        With method ``"forgetting"``, let the factor start at ``min(forgetting, 0.95)`` and
        tend to ``forgetting`` (default; see :mod:`sysid.recursive.estimators`), so that the
        first updates, made from the starting values, are forgotten and ``covariance`` times
        the noise variance is the estimate's covariance. False: the constant factor, for
        ``initial_parameters`` and ``initial_covariance`` already right (a batch estimate
        and its covariance), which the start-up forgetting would discount.
"""


class RecursiveARX(_Recursive):
    __doc__ = """Online ARX ``A(q) y(t) = B(q) u(t - nk) + e(t)``.

    Parameters
    ----------
    na : int
        Order of ``A``.
    nb, nk : int or sequence of int
        ``B`` coefficients and delay per input.
""" + _SETTINGS_DOC + """
    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(500); y = np.zeros(500)
    >>> for t in range(1, 500): y[t] = 0.5 * y[t - 1] + u[t - 1]
    >>> est = sysid.RecursiveARX(1, 1)
    >>> res = est.run(u, y)
    >>> np.round(est.parameters, 6)
    array([-0.5,  1. ])
    """
    _kind = "arx"

    def __init__(self, na: Any, nb: Any = None, nk: Any = None, *,
                 method: str = "forgetting",
                 forgetting: float = 1.0, process_noise: Any = None,
                 noise_variance: float = 1.0, gain: float = 1.0, bias: float = 2.2e-16,
                 initial_parameters: Any = None, initial_covariance: Any = 1e4,
                 dt: float | None = None) -> None:
        na, nb, nk = _given(na, (nb, nk), "na nb* nk*", "RecursiveARX")
        na = as_int(na, "na", 0)
        nbv = _orders(nb, "nb")
        super().__init__(na, nbv, 0, 0, [0] * len(nbv), nk, method=method,
                         forgetting=forgetting, process_noise=process_noise,
                         noise_variance=noise_variance, gain=gain, bias=bias,
                         initial_parameters=initial_parameters,
                         initial_covariance=initial_covariance, dt=dt)


class RecursiveARMAX(_Recursive):
    __doc__ = """Online ARMAX ``A(q) y(t) = B(q) u(t - nk) + C(q) e(t)`` (recursive
    prediction-error method: the regressor filtered by ``1/C``).

    Parameters
    ----------
    na, nc : int
        Orders of ``A`` and ``C``.
    nb, nk : int or sequence of int
        ``B`` coefficients and delay per input.
""" + _SETTINGS_DOC + _STARTUP_DOC + """
    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(1)
    >>> u = rng.standard_normal(20000); e = 0.3 * rng.standard_normal(20000)
    >>> y = np.zeros(20000)
    >>> for t in range(1, 20000): y[t] = 0.8 * y[t-1] + u[t-1] + e[t] + 0.5 * e[t-1]
    >>> est = sysid.RecursiveARMAX(1, 1, 1)
    >>> _ = est.run(u, y)
    >>> np.round(est.parameters, 1)
    array([-0.8,  1. ,  0.5])
    """
    _kind = "armax"

    def __init__(self, na: Any, nb: Any = None, nc: Any = None, nk: Any = None, *,
                 method: str = "forgetting",
                 forgetting: float = 1.0, process_noise: Any = None,
                 noise_variance: float = 1.0, gain: float = 1.0, bias: float = 2.2e-16,
                 initial_parameters: Any = None, initial_covariance: Any = 1e4,
                 dt: float | None = None, startup_forgetting: bool = True) -> None:
        na, nb, nc, nk = _given(na, (nb, nc, nk), "na nb* nc nk*", "RecursiveARMAX")
        na = as_int(na, "na", 0)
        nbv = _orders(nb, "nb")
        super().__init__(na, nbv, nc, 0, [0] * len(nbv), nk, method=method,
                         forgetting=forgetting, process_noise=process_noise,
                         noise_variance=noise_variance, gain=gain, bias=bias,
                         initial_parameters=initial_parameters,
                         initial_covariance=initial_covariance, dt=dt,
                         startup_forgetting=startup_forgetting)


class RecursiveOE(_Recursive):
    __doc__ = """Online output-error model ``y(t) = B(q)/F(q) u(t - nk) + e(t)``.

    Parameters
    ----------
    nb, nf, nk : int or sequence of int
        ``B`` coefficients, ``F`` order and delay per input.
""" + _SETTINGS_DOC + _STARTUP_DOC + """
    Examples
    --------
    >>> import numpy as np, sysid
    >>> from scipy import signal
    >>> rng = np.random.default_rng(2)
    >>> u = rng.standard_normal(20000)
    >>> y = signal.lfilter([0, 1.0], [1, -0.7], u) + 0.2 * rng.standard_normal(20000)
    >>> est = sysid.RecursiveOE(1, 1)
    >>> _ = est.run(u, y)
    >>> np.round(est.parameters, 1)
    array([ 1. , -0.7])
    """
    _kind = "oe"

    def __init__(self, nb: Any, nf: Any = None, nk: Any = None, *,
                 method: str = "forgetting",
                 forgetting: float = 1.0, process_noise: Any = None,
                 noise_variance: float = 1.0, gain: float = 1.0, bias: float = 2.2e-16,
                 initial_parameters: Any = None, initial_covariance: Any = 1e4,
                 dt: float | None = None, startup_forgetting: bool = True) -> None:
        nb, nf, nk = _given(nb, (nf, nk), "nb* nf* nk*", "RecursiveOE")
        super().__init__(0, nb, 0, 0, nf, nk, method=method, forgetting=forgetting,
                         process_noise=process_noise, noise_variance=noise_variance,
                         gain=gain, bias=bias, initial_parameters=initial_parameters,
                         initial_covariance=initial_covariance, dt=dt,
                         startup_forgetting=startup_forgetting)


class RecursiveBJ(_Recursive):
    __doc__ = """Online Box-Jenkins ``y(t) = B(q)/F(q) u(t - nk) + C(q)/D(q) e(t)``.

    Parameters
    ----------
    nb, nf, nk : int or sequence of int
        ``B`` coefficients, ``F`` order and delay per input.
    nc, nd : int
        Orders of ``C`` and ``D``.
""" + _SETTINGS_DOC + _STARTUP_DOC + """
    Examples
    --------
    >>> import numpy as np, sysid
    >>> from scipy import signal
    >>> rng = np.random.default_rng(3)
    >>> u = rng.standard_normal(40000); e = 0.2 * rng.standard_normal(40000)
    >>> y = signal.lfilter([0, 1.0], [1, -0.7], u) + signal.lfilter([1, 0.5], [1, -0.6], e)
    >>> est = sysid.RecursiveBJ(1, 1, 1, 1)
    >>> _ = est.run(u, y)
    >>> np.round(est.parameters, 1)
    array([ 1. ,  0.5, -0.6, -0.7])
    """
    _kind = "bj"

    def __init__(self, nb: Any, nc: Any = None, nd: Any = None, nf: Any = None,
                 nk: Any = None, *,
                 method: str = "forgetting", forgetting: float = 1.0,
                 process_noise: Any = None, noise_variance: float = 1.0, gain: float = 1.0,
                 bias: float = 2.2e-16, initial_parameters: Any = None,
                 initial_covariance: Any = 1e4, dt: float | None = None,
                 startup_forgetting: bool = True) -> None:
        nb, nc, nd, nf, nk = _given(nb, (nc, nd, nf, nk), "nb* nc nd nf* nk*",
                                    "RecursiveBJ")
        super().__init__(0, nb, nc, nd, nf, nk, method=method, forgetting=forgetting,
                         process_noise=process_noise, noise_variance=noise_variance,
                         gain=gain, bias=bias, initial_parameters=initial_parameters,
                         initial_covariance=initial_covariance, dt=dt,
                         startup_forgetting=startup_forgetting)
