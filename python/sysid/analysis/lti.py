"""Model analysis: zeros, damping, controllability, responses, time-domain conversions.

Everything here works on the small matrices of a model (no pass over data), with NumPy and
SciPy. Discrete-time models are :class:`~sysid.StateSpaceModel`; continuous-time ones are
:class:`ContinuousStateSpace`, obtained with :func:`d2c` and turned back with :func:`c2d`.

Conventions
-----------
- Frequencies of discrete poles use the continuous equivalent ``s = log(p) / dt``: natural
  frequency ``|s|``, damping ``-cos(angle(s))``, damped frequency ``|Im s| = |angle(p)| / dt``.
- ``c2d``/``d2c`` with ``method="tustin"`` use SciPy's realisation of the bilinear transform
  (``scipy.signal.cont2discrete(..., method="bilinear")``, the one python-control uses), so
  the matrices agree with both, not only the transfer functions.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import scipy.linalg

from .._checks import as_int, as_matrix
from ..errors import DataError, NumericalError, ShapeError
from ..models.statespace import StateSpaceModel
from .controllability import ctrb, is_controllable, is_observable, obsv  # noqa: F401 (moved)

__all__ = [
    "ContinuousStateSpace",
    "DampingTable",
    "TimeResponse",
    "zeros",
    "damp",
    "ctrb",
    "obsv",
    "is_controllable",
    "is_observable",
    "step",
    "impulse",
    "c2d",
    "d2c",
    "to_control",
    "from_control",
    "to_scipy",
    "from_scipy",
]


class ContinuousStateSpace:
    """Continuous-time model ``dx/dt = A x + B u``, ``y = C x + D u``.

    Parameters
    ----------
    A, B, C : array_like
        Shapes ``(n, n)``, ``(n, m)``, ``(l, n)``.
    D : array_like, optional
        ``(l, m)``; zero if omitted.
    input_names, output_names : sequence of str, optional
        Channel names.

    Examples
    --------
    >>> import sysid
    >>> sys = sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]])
    >>> sys
    ContinuousStateSpace(nstates=1, ninputs=1, noutputs=1, stable)
    >>> float(sys.dcgain()[0, 0])
    1.0
    """

    def __init__(
        self,
        A: Any,
        B: Any,
        C: Any,
        D: Any = None,
        *,
        input_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
    ) -> None:
        # reuse the discrete model's checks, then keep only the matrices
        ref = StateSpaceModel(A, B, C, D, input_names=input_names, output_names=output_names)
        self.A, self.B, self.C, self.D = ref.A, ref.B, ref.C, ref.D
        self.input_names, self.output_names = ref.input_names, ref.output_names

    nstates = property(lambda self: self.A.shape[0], doc="Number of states n.")
    ninputs = property(lambda self: self.B.shape[1], doc="Number of inputs m.")
    noutputs = property(lambda self: self.C.shape[0], doc="Number of outputs l.")

    def poles(self) -> np.ndarray:
        """Eigenvalues of A (continuous-time poles, rad/s)."""
        return np.linalg.eigvals(self.A).astype(complex)

    def is_stable(self) -> bool:
        """True when every pole has a strictly negative real part."""
        return bool(self.nstates == 0 or np.max(self.poles().real) < 0)

    def freqresp(self, omega: Any) -> np.ndarray:
        """``C (j omega I - A)^{-1} B + D``, shape ``(len(omega), noutputs, ninputs)``."""
        w = np.atleast_1d(np.asarray(omega, dtype=float))
        eye = np.eye(self.nstates)
        out = np.empty((w.size, self.noutputs, self.ninputs), dtype=complex)
        for i, wi in enumerate(w):
            out[i] = self.C @ np.linalg.solve(1j * wi * eye - self.A, self.B) + self.D
        return out

    def dcgain(self) -> np.ndarray:
        """``D - C A^{-1} B``, shape ``(noutputs, ninputs)``."""
        return self.freqresp([0.0])[0].real

    def c2d(self, dt: float, method: str = "zoh") -> StateSpaceModel:
        """Discretise; see :func:`c2d`."""
        return c2d(self, dt, method)

    def __repr__(self) -> str:
        stab = "stable" if self.is_stable() else "UNSTABLE"
        return (
            f"ContinuousStateSpace(nstates={self.nstates}, ninputs={self.ninputs}, "
            f"noutputs={self.noutputs}, {stab})"
        )


def _model(model: Any) -> StateSpaceModel:
    if not isinstance(model, StateSpaceModel):
        raise DataError(f"expected a sysid.StateSpaceModel, got {type(model).__name__}")
    return model


# -- zeros ------------------------------------------------------------------------------
def _pencil_zeros(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray) -> np.ndarray:
    n = A.shape[0]
    M = np.block([[A, B], [C, D]])
    N = np.zeros_like(M)
    N[:n, :n] = np.eye(n)
    w = scipy.linalg.eigvals(M, N, homogeneous_eigvals=True)
    alpha, beta = w
    scale = max(float(np.abs(M).max()), 1.0)
    # infinite eigenvalues come out with beta at round-off level
    finite = np.abs(alpha) < 1e8 * scale * np.abs(beta)
    z = alpha[finite] / beta[finite]
    return z.astype(complex)


def zeros(model: StateSpaceModel | ContinuousStateSpace, tol: float = 1e-6) -> np.ndarray:
    """Transmission zeros: finite generalised eigenvalues of the Rosenbrock pencil.

    ``[[A - z I, B], [C, D]]`` loses rank at a zero. For a square system the pencil's
    generalised eigenvalues are the zeros (``scipy.linalg.eigvals``). A non-square system is
    squared down twice with random (seeded) combinations of its outputs or inputs; zeros
    common to both, within ``tol`` relative, are kept (the spurious zeros of a squaring-down
    move with the combination, the true ones do not).

    Parameters
    ----------
    model : StateSpaceModel or ContinuousStateSpace
    tol : float
        Relative tolerance for matching zeros of the two squared-down systems.

    Returns
    -------
    ndarray
        Complex zeros (discrete ``z`` or continuous ``s``), sorted by modulus.

    Examples
    --------
    >>> import sysid
    >>> m = sysid.StateSpaceModel([[0.5, 0.0], [0.0, 0.2]], [[1.0], [1.0]], [[1.0, 1.0]])
    >>> sysid.zeros(m)
    array([0.35+0.j])
    """
    A, B, C, D = model.A, model.B, model.C, model.D
    l, m = D.shape
    if l == m:
        z = _pencil_zeros(A, B, C, D)
    else:
        rng = np.random.default_rng(12345)
        k = min(l, m)
        cands = []
        for _ in range(2):
            if l > m:
                W = rng.standard_normal((k, l))
                cands.append(_pencil_zeros(A, B, W @ C, W @ D))
            else:
                W = rng.standard_normal((m, k))
                cands.append(_pencil_zeros(A, B @ W, C, D @ W))
        z1, z2 = cands
        keep = [a for a in z1 if z2.size and np.min(np.abs(z2 - a)) <= tol * max(1.0, abs(a))]
        z = np.array(keep, dtype=complex)
    return z[np.argsort(np.abs(z), kind="stable")]


# -- damping ----------------------------------------------------------------------------
class DampingTable:
    """Poles with their natural frequency, damping ratio and time constant.

    Attributes
    ----------
    poles : ndarray
        Poles of the model (discrete ``z`` or continuous ``s``), sorted by frequency.
    s : ndarray
        Continuous-time equivalents ``log(z) / dt`` (equal to ``poles`` for continuous models).
    wn, wn_hz : ndarray
        Natural frequency ``|s|`` in rad/s and Hz.
    wd, wd_hz : ndarray
        Damped frequency ``|Im s|`` in rad/s and Hz (``|angle(z)| / (2 pi dt)`` in Hz).
    zeta : ndarray
        Damping ratio ``-Re(s) / |s|``.
    tau : ndarray
        Time constant ``-1 / Re(s)`` in seconds (``inf`` on the stability boundary).
    pole_std, wn_std, wn_hz_std, zeta_std : ndarray or None
        First-order standard deviations (``damp(model, std=True)``, from the model's
        parameter uncertainty); ``pole_std`` is complex (std of the real and imaginary parts).
    """

    def __init__(self, poles: np.ndarray, s: np.ndarray, dt: float | None,
                 std: dict[str, np.ndarray] | None = None) -> None:
        order = np.lexsort((s.imag, np.abs(s)))
        self.poles, self.s, self.dt = poles[order], s[order], dt
        self.pole_std = self.wn_std = self.wn_hz_std = self.zeta_std = None
        if std is not None:
            self.pole_std = std["pole_std"][order]
            self.wn_std, self.wn_hz_std = std["wn_std"][order], std["wn_hz_std"][order]
            self.zeta_std = std["zeta_std"][order]
        with np.errstate(divide="ignore", invalid="ignore"):
            self.wn = np.abs(self.s)
            safe = np.where(self.wn > 0, self.wn, 1.0)
            self.zeta = np.where(self.wn > 0, -self.s.real / safe, -1.0)
            self.zeta = np.where(np.isinf(self.s.real), 1.0, self.zeta)
            self.wd = np.abs(self.s.imag)
            self.tau = np.where(self.s.real != 0, -1.0 / self.s.real, np.inf)
        self.wn_hz = self.wn / (2 * np.pi)
        self.wd_hz = self.wd / (2 * np.pi)

    def to_pandas(self) -> Any:
        """The table as a :class:`pandas.DataFrame`."""
        import pandas as pd

        cols = {
            "pole": self.poles, "magnitude": np.abs(self.poles), "wn [rad/s]": self.wn,
            "wn [Hz]": self.wn_hz, "damping": self.zeta, "wd [Hz]": self.wd_hz,
            "tau [s]": self.tau,
        }
        if self.pole_std is not None:
            cols.update({"std Re(pole)": self.pole_std.real, "std Im(pole)": self.pole_std.imag,
                         "std wn [Hz]": self.wn_hz_std, "std damping": self.zeta_std})
        return pd.DataFrame(cols)

    def __len__(self) -> int:
        return len(self.poles)

    def __repr__(self) -> str:
        head = (f"{'pole':>24} {'|pole|':>8} {'wn rad/s':>10} {'wn Hz':>9} {'damping':>8} "
                f"{'wd Hz':>9}")
        if self.pole_std is not None:
            head += f" {'std Hz':>9} {'std damp':>9}"
        rows = [head]
        for k, (p, wn, fz, z, fd) in enumerate(
                zip(self.poles, self.wn, self.wn_hz, self.zeta, self.wd_hz)):
            rows.append(
                f"{p.real:>11.5g}{p.imag:>+11.5g}j {abs(p):8.4f} {wn:10.4g} {fz:9.4g} "
                f"{z:8.4f} {fd:9.4g}"
                + ("" if self.wn_hz_std is None or self.zeta_std is None else
                   f" {self.wn_hz_std[k]:9.3g} {self.zeta_std[k]:9.3g}")
            )
        where = f"dt = {self.dt:g} s" if self.dt is not None else "continuous time"
        return f"DampingTable ({where})\n" + "\n".join(rows)


def damp(model: StateSpaceModel | ContinuousStateSpace, std: bool = False) -> DampingTable:
    """Natural frequencies (rad/s and Hz), damping ratios and time constants of the poles.

    Discrete poles are mapped through ``s = log(z) / dt``; a pole at ``z = 0`` gets
    ``s = -inf`` (infinitely fast, damping 1). With ``std=True`` (a discrete model with
    ``uncertainty``) the table also has the first-order standard deviations of the poles,
    natural frequencies and damping ratios (NaN, with a warning, for a pole too close to
    another one for first order to hold).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> dt = 0.01
    >>> p = np.exp(dt * (-1.0 + 10.0j))
    >>> A = [[p.real, -p.imag], [p.imag, p.real]]
    >>> table = sysid.damp(sysid.StateSpaceModel(A, [[1.0], [0.0]], [[1.0, 0.0]], dt=dt))
    >>> np.round(table.wd, 6)
    array([10., 10.])
    >>> np.round(table.zeta, 4)
    array([0.0995, 0.0995])
    """
    p = model.poles()
    if isinstance(model, ContinuousStateSpace):
        if std:
            raise DataError("damp(std=True) needs a discrete-time model with uncertainty")
        return DampingTable(p, p.copy(), None)
    _model(model)
    if std:
        from ..models.uncertainty import damping_std

        d = damping_std(model, model.dt)
        return DampingTable(d["poles"], d["s"].astype(complex), model.dt, std=d)
    with np.errstate(divide="ignore"):
        s = np.where(np.abs(p) > 0, np.log(np.where(np.abs(p) > 0, p, 1)) / model.dt, -np.inf)
    return DampingTable(p, s.astype(complex), model.dt)


# -- time responses ---------------------------------------------------------------------
class TimeResponse:
    """Step or impulse response: ``y[t, i, j]`` is output i for input j at time ``t[t]``."""

    def __init__(self, kind: str, t: np.ndarray, y: np.ndarray, model: StateSpaceModel,
                 std: np.ndarray | None = None) -> None:
        self.kind, self.t, self.y = kind, t, y
        self.std = std  # first-order std of y (step(..., std=True)); plotted as bands
        self.input_names, self.output_names = model.input_names, model.output_names

    def plot(self, fig: Any = None) -> Any:
        """One axis per (output, input) pair; returns the figure."""
        from ..plot.model import plot_time_response

        return plot_time_response(self, fig=fig)

    def __repr__(self) -> str:
        return (
            f"TimeResponse({self.kind}, {len(self.t)} samples, {self.y.shape[1]} output(s) x "
            f"{self.y.shape[2]} input(s))"
        )


def _n_samples(model: StateSpaceModel, n_samples: int | None) -> int:
    if n_samples is None:
        rho = np.max(np.abs(model.poles())) if model.nstates else 0.0
        # long enough for the slowest mode to decay to 1 % (bounded)
        n = 100 if rho >= 1 or rho == 0 else int(np.ceil(np.log(0.01) / np.log(rho))) + 10
        return int(min(max(n, 20), 10000))
    return as_int(n_samples, "n_samples")


def step(model: StateSpaceModel, n_samples: int | None = None, std: bool = False
         ) -> TimeResponse:
    """Response to a unit step on each input (zero initial state).

    With ``std=True`` (a model with ``uncertainty``) ``resp.std`` holds the first-order
    standard deviation of each sample, drawn as a 95 % band by ``resp.plot()``.

    Examples
    --------
    >>> import sysid
    >>> r = sysid.step(sysid.StateSpaceModel([[0.5]], [[0.5]], [[1.0]]), 4)
    >>> r.y[:, 0, 0]
    array([0.   , 0.5  , 0.75 , 0.875])
    """
    model = _model(model)
    N = _n_samples(model, n_samples)
    m = model.ninputs
    y = np.empty((N, model.noutputs, m))
    for j in range(m):
        u = np.zeros((N, m))
        u[:, j] = 1.0
        y[:, :, j] = model.simulate(u)
    sd = None
    if std:
        from ..models.uncertainty import complex_std

        _, sd = complex_std(model, lambda m: step(m, N).y)
    return TimeResponse("step", np.arange(N) * model.dt, y, model, std=sd)


def impulse(model: StateSpaceModel, n_samples: int | None = None) -> TimeResponse:
    """Response to a unit pulse ``u(0) = 1`` on each input: the Markov parameters.

    Examples
    --------
    >>> import sysid
    >>> sysid.impulse(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), 3).y[:, 0, 0]
    array([0. , 1. , 0.5])
    """
    model = _model(model)
    N = _n_samples(model, n_samples)
    return TimeResponse("impulse", np.arange(N) * model.dt, model.markov(N), model)


# -- continuous <-> discrete ------------------------------------------------------------
_METHODS = ("zoh", "tustin")


def _conv_method(method: str) -> str:
    key = {"bilinear": "tustin"}.get(str(method).lower(), str(method).lower())
    if key not in _METHODS:
        raise DataError(f"method must be 'zoh' or 'tustin', got {method!r}")
    return key


def c2d(sys: ContinuousStateSpace, dt: float, method: str = "zoh") -> StateSpaceModel:
    """Discretise a continuous model with a zero-order hold or the Tustin transform.

    ``zoh``: ``expm([[A, B], [0, 0]] dt) = [[Ad, Bd], [0, I]]``, ``Cd = C``, ``Dd = D``.
    ``tustin`` (bilinear): with ``M = (I - A dt / 2)^{-1}``, ``Ad = M (I + A dt / 2)``,
    ``Bd = M B dt``, ``Cd = C M``, ``Dd = D + C M B dt / 2`` (SciPy's realisation).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.c2d(sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]]), 0.1)
    >>> bool(np.isclose(d.A[0, 0], np.exp(-0.1)))
    True
    """
    if not isinstance(sys, ContinuousStateSpace):
        raise DataError(f"c2d needs a sysid.ContinuousStateSpace, got {type(sys).__name__}")
    dt = float(dt)
    if not np.isfinite(dt) or dt <= 0:
        raise DataError(f"dt must be a positive number of seconds, got {dt}")
    method = _conv_method(method)
    A, B, C, D = sys.A, sys.B, sys.C, sys.D
    n, m = B.shape
    if method == "zoh":
        big = np.zeros((n + m, n + m))
        big[:n, :n], big[:n, n:] = A, B
        E = scipy.linalg.expm(big * dt)
        Ad, Bd, Cd, Dd = E[:n, :n], E[:n, n:], C.copy(), D.copy()
    else:
        ima = np.eye(n) - 0.5 * dt * A
        Ad = np.linalg.solve(ima, np.eye(n) + 0.5 * dt * A)
        Bd = np.linalg.solve(ima, dt * B)
        Cd = np.linalg.solve(ima.T, C.T).T
        Dd = D + 0.5 * C @ Bd
    return StateSpaceModel(
        Ad, Bd, Cd, Dd, dt=dt, input_names=sys.input_names, output_names=sys.output_names,
        info={"method": f"c2d ({method})"},
    )


def d2c(model: StateSpaceModel, method: str = "zoh") -> ContinuousStateSpace:
    """Continuous-time equivalent of a discrete model (inverse of :func:`c2d`).

    ``zoh`` takes the principal matrix logarithm of ``[[A, B], [0, I]]`` and fails with a
    :class:`NumericalError` when a pole lies on the negative real axis or at zero (no real
    logarithm). ``tustin`` fails when a pole is at ``z = -1``. The noise model (``K``) is not
    converted.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> c = sysid.d2c(sysid.StateSpaceModel([[np.exp(-0.1)]], [[1.0]], [[1.0]], dt=0.1))
    >>> bool(np.isclose(c.A[0, 0], -1.0))
    True
    """
    model = _model(model)
    method = _conv_method(method)
    A, B, C, D, dt = model.A, model.B, model.C, model.D, model.dt
    n, m = B.shape
    p = model.poles()
    if method == "zoh":
        bad = (np.abs(p.imag) <= 1e-12 * np.maximum(1, np.abs(p))) & (p.real <= 0)
        if bad.any():
            raise NumericalError(
                f"the model has a pole at z = {p[bad][0].real:g} on the negative real axis or at "
                "zero: it has no zero-order-hold continuous equivalent; use method='tustin'"
            )
        big = np.eye(n + m)
        big[:n, :n], big[:n, n:] = A, B
        L = scipy.linalg.logm(big)
        L = np.real_if_close(L, tol=1e6)
        if np.iscomplexobj(L):
            raise NumericalError("the matrix logarithm is complex: no real continuous equivalent")
        L = L / dt
        Ac, Bc, Cc, Dc = L[:n, :n], L[:n, n:], C.copy(), D.copy()
    else:
        api = A + np.eye(n)
        if n and np.linalg.cond(api) > 1e12:
            raise NumericalError("the model has a pole at z = -1: no Tustin continuous equivalent")
        inv = np.linalg.inv(api) if n else api
        Ac = (2.0 / dt) * (np.eye(n) - 2.0 * inv)
        Bc = 2.0 * inv @ B / dt
        Cc = 2.0 * C @ inv
        Dc = D - 0.5 * Cc @ B
    return ContinuousStateSpace(
        Ac, Bc, Cc, Dc, input_names=model.input_names, output_names=model.output_names
    )


# -- other libraries --------------------------------------------------------------------
def _control() -> Any:
    try:
        import control
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("this conversion needs python-control: pip install control") from e
    return control


def to_control(model: StateSpaceModel | ContinuousStateSpace) -> Any:
    """A ``control.StateSpace`` (discrete with ``dt``, or continuous); ``K`` is dropped.

    Needs python-control (optional; the examples are skipped by the doctest run, the
    conversions are tested against it in ``tests/test_analysis.py`` when it is installed).

    Examples
    --------
    >>> import sysid
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1)
    >>> sysid.to_control(m).dt  # doctest: +SKIP
    0.1
    """
    ct = _control()
    dt = model.dt if isinstance(model, StateSpaceModel) else 0
    return ct.ss(
        model.A, model.B, model.C, model.D, dt,
        inputs=list(model.input_names), outputs=list(model.output_names),
    )


def _from_matrices(A: Any, B: Any, C: Any, D: Any, dt: Any, names: tuple[Any, Any]) -> Any:
    A = as_matrix(A, "A", (None, None))
    n = A.shape[0]
    B = np.asarray(B, dtype=float).reshape(n, -1)
    C = np.asarray(C, dtype=float).reshape(-1, n)
    if dt is None or dt is True or dt == 0:
        if dt is True:
            raise DataError("the system is discrete with an unspecified sample time; set dt")
        return ContinuousStateSpace(A, B, C, D, input_names=names[0], output_names=names[1])
    return StateSpaceModel(A, B, C, D, dt=float(dt), input_names=names[0], output_names=names[1])


def from_control(sys: Any) -> StateSpaceModel | ContinuousStateSpace:
    """Convert a ``control.StateSpace`` (or transfer function) to a sysid model.

    Examples
    --------
    >>> import control, sysid  # doctest: +SKIP
    >>> sysid.from_control(control.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], 0.1))  # doctest: +SKIP
    StateSpaceModel(nstates=1, ninputs=1, noutputs=1, dt=0.1, stable, no noise model)
    """
    ct = _control()
    if not isinstance(sys, ct.StateSpace):
        sys = ct.ss(sys)
    names = (getattr(sys, "input_labels", None), getattr(sys, "output_labels", None))
    return _from_matrices(sys.A, sys.B, sys.C, sys.D, sys.dt, names)


def to_scipy(model: StateSpaceModel | ContinuousStateSpace) -> Any:
    """A ``scipy.signal.StateSpace`` (with ``dt`` for a discrete model).

    Examples
    --------
    >>> import sysid
    >>> sysid.to_scipy(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1)).dt
    0.1
    """
    import scipy.signal

    if isinstance(model, StateSpaceModel):
        return scipy.signal.StateSpace(model.A, model.B, model.C, model.D, dt=model.dt)
    return scipy.signal.StateSpace(model.A, model.B, model.C, model.D)


def from_scipy(sys: Any) -> StateSpaceModel | ContinuousStateSpace:
    """Convert a ``scipy.signal`` LTI object (state space, transfer function, zpk).

    Examples
    --------
    >>> import scipy.signal, sysid
    >>> sysid.from_scipy(scipy.signal.StateSpace([[-1.0]], [[1.0]], [[1.0]], [[0.0]]))
    ContinuousStateSpace(nstates=1, ninputs=1, noutputs=1, stable)
    """
    import scipy.signal

    if not isinstance(sys, scipy.signal.lti) and not isinstance(sys, scipy.signal.dlti):
        raise ShapeError(f"expected a scipy.signal LTI object, got {type(sys).__name__}")
    ss = sys.to_ss()
    return _from_matrices(ss.A, ss.B, ss.C, ss.D, getattr(ss, "dt", None), (None, None))
