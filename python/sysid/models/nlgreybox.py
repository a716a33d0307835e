"""Nonlinear grey-box structures (MATLAB's ``idnlgrey``): an ODE right-hand side and an output
function of named parameters, integrated in the Rust core.

``f(t, x, u, p) -> dx/dt`` and ``h(t, x, u, p) -> y`` with ``p`` a
:class:`~sysid.models.greybox.Parameters` (attribute access). The input is held constant over
each sample interval. With ``vectorized=True`` the functions receive ``x`` as an ``(nx, K)``
array and every parameter as a length-``K`` array (the nominal point and the
finite-difference perturbations of all free parameters), so one call per integrator stage
serves the whole Jacobian; written with NumPy arithmetic, most right-hand sides work both ways.

Examples
--------
>>> import numpy as np, sysid
>>> tank = sysid.NonlinearGreyBox(
...     lambda t, x, u, p: [-p.a * np.sqrt(np.maximum(x[0], 0.0)) + p.b * u[0]],
...     lambda t, x, u, p: [x[0]], params={"a": 0.5, "b": 1.0}, nx=1, x0=[1.0],
...     vectorized=True)
>>> y = tank.simulate(np.ones((20, 1)), dt=0.1)
>>> y.shape, bool(y[-1, 0] > 1.0)
((20, 1), True)
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from .. import _sysid
from ..errors import DataError
from .greybox import Param, Parameters, as_params
from .protocol import ModelMixin

__all__ = ["NonlinearGreyBox"]

_INTEGRATORS = ("rk4", "adaptive")


def _stack(out: Any, rows: int, k: int, what: str) -> np.ndarray:
    """``(rows, k)`` from what ``f``/``h`` returned (rows may be scalars or length-k)."""
    res = np.empty((rows, k))
    try:
        if isinstance(out, (list, tuple)):
            if len(out) != rows:
                raise DataError(f"{what} returned {len(out)} entries, expected {rows}")
            for i, r in enumerate(out):
                res[i] = r
        else:
            a = np.asarray(out, dtype=float)
            res[...] = a[:, None] if a.ndim == 1 else a
    except ValueError as e:
        raise DataError(f"{what} returned values that do not fit ({rows}, {k}): {e}") from e
    return res


class NonlinearGreyBox(ModelMixin):
    """A nonlinear state-space structure ``dx/dt = f(t, x, u, p)``, ``y = h(t, x, u, p)``.

    Parameters
    ----------
    f, h : callable
        ``f(t, x, u, p)`` returns ``dx/dt`` (length nx), ``h(t, x, u, p)`` the outputs.
    params : dict
        ``{name: value | sysid.param(...) | sysid.fixed(...)}``.
    nx : int
        Number of states.
    x0 : array_like, optional
        Initial state, ``(nx,)`` for every experiment or ``(n_experiments, nx)``; zero by
        default.
    x0_free : bool or array_like of bool
        Which initial-state entries ``greyest`` estimates (all, none, a mask ``(nx,)`` or
        ``(n_experiments, nx)``). Default: none.
    integrator : {"rk4", "adaptive"}
        Classical Runge-Kutta with ``substeps`` steps per sample, or Dormand-Prince 5(4) with
        tolerances ``rtol``, ``atol``.
    vectorized : bool
        ``f`` and ``h`` accept ``x`` of shape ``(nx, K)`` and parameters of shape ``(K,)``.
    dt : float, optional
        Sample time (set by ``greyest`` from the data).
    ninputs, noutputs : int, optional
        Channel counts (otherwise found from the data / one call of ``h``).
    input_names, output_names : sequence of str, optional

    Examples
    --------
    >>> import sysid
    >>> s = sysid.NonlinearGreyBox(lambda t, x, u, p: [-p.k * x[0] ** 3 + u[0]],
    ...                            lambda t, x, u, p: [x[0]], {"k": 1.0}, nx=1, ninputs=1)
    >>> s
    NonlinearGreyBox(1 parameter (1 free), 1 state, rk4)
    """

    def __init__(self, f: Callable[..., Any], h: Callable[..., Any], params: Mapping[str, Any],
                 nx: int, x0: Any = None, *, x0_free: Any = False, integrator: str = "rk4",
                 substeps: int = 1, rtol: float = 1e-8, atol: float = 1e-10,
                 vectorized: bool = False, dt: float | None = None, ninputs: int | None = None,
                 noutputs: int | None = None, input_names: Any = None,
                 output_names: Any = None) -> None:
        if not (callable(f) and callable(h)):
            raise DataError("f and h must be callables f(t, x, u, p), h(t, x, u, p)")
        if integrator not in _INTEGRATORS:
            raise DataError(f"integrator must be 'rk4' or 'adaptive', got {integrator!r}")
        self.f, self.h = f, h
        self.params: dict[str, Param] = as_params(params)
        self.nx = int(nx)
        if self.nx < 1:
            raise DataError(f"nx must be >= 1, got {nx}")
        self.x0 = np.zeros((1, self.nx)) if x0 is None else \
            np.atleast_2d(np.asarray(x0, dtype=float))
        if self.x0.shape[1] != self.nx:
            raise DataError(f"x0 has {self.x0.shape[1]} entries per experiment, nx is {nx}")
        self.x0_free = np.broadcast_to(np.asarray(x0_free, dtype=bool),
                                       (self.x0.shape[0], self.nx)).copy() \
            if np.ndim(x0_free) < 2 else np.asarray(x0_free, dtype=bool)
        self.integrator, self.substeps = integrator, int(substeps)
        self.rtol, self.atol = float(rtol), float(atol)
        self.vectorized = bool(vectorized)
        self.dt = 0.0 if dt is None else float(dt)
        self._ninputs, self._noutputs = ninputs, noutputs
        self._input_names, self._output_names = input_names, output_names
        self.info: dict[str, Any] = {"method": "nonlinear grey-box structure"}

    # -- sizes and names ------------------------------------------------------------------
    @property
    def ninputs(self) -> int:
        """Number of inputs (from the data once estimated)."""
        if self._ninputs is None:
            raise DataError("the number of inputs is unknown: give ninputs= or estimate first")
        return int(self._ninputs)

    @property
    def noutputs(self) -> int:
        """Number of outputs (one call of ``h`` when not given)."""
        if self._noutputs is None:
            u = np.zeros(self._ninputs or 0)
            y = self._call(self.h, 0.0, self.x0[0][:, None], u, self.values[:, None])
            self._noutputs = y.shape[0]
        return int(self._noutputs)

    @property
    def input_names(self) -> list[str]:
        """Input channel names (``u0, u1, ...`` unless given)."""
        n = self._input_names
        return list(n) if n is not None else [f"u{i}" for i in range(self.ninputs)]

    @property
    def output_names(self) -> list[str]:
        """Output channel names (``y0, y1, ...`` unless given)."""
        n = self._output_names
        return list(n) if n is not None else [f"y{i}" for i in range(self.noutputs)]

    @property
    def names(self) -> list[str]:
        """All parameter names."""
        return list(self.params)

    @property
    def free_names(self) -> list[str]:
        """Names of the free parameters."""
        return [k for k, v in self.params.items() if not v.fixed]

    @property
    def values(self) -> np.ndarray:
        """All parameter values."""
        return np.array([v.value for v in self.params.values()])

    @property
    def n_parameters(self) -> int:
        """Number of free parameters."""
        return len(self.free_names)

    @property
    def nstates(self) -> int:
        """Number of states."""
        return self.nx

    def with_values(self, values: Mapping[str, float], x0: Any = None,
                    dt: float | None = None) -> NonlinearGreyBox:
        """A copy with other parameter values (and initial states, sample time)."""
        out = object.__new__(NonlinearGreyBox)
        out.__dict__.update(self.__dict__)
        out.params = {k: replace(v, value=float(values.get(k, v.value)))
                      for k, v in self.params.items()}
        if x0 is not None:
            out.x0 = np.atleast_2d(np.asarray(x0, dtype=float))
            out.x0_free = np.zeros_like(out.x0, dtype=bool)
        if dt is not None:
            out.dt = float(dt)
        out.info = dict(self.info)
        return out

    # -- evaluation ------------------------------------------------------------------------
    def _call(self, fn: Callable[..., Any], t: float, X: np.ndarray, u: np.ndarray,
              P: np.ndarray) -> np.ndarray:
        names = self.names
        k = X.shape[1]
        if self.vectorized:
            p = Parameters({n: P[i] for i, n in enumerate(names)})
            out = fn(t, X, u, p)
            rows = len(out) if isinstance(out, (list, tuple)) else np.shape(out)[0]
            return _stack(out, rows, k, getattr(fn, "__name__", "f/h"))
        cols = []
        for c in range(k):
            p = Parameters({n: float(P[i, c]) for i, n in enumerate(names)})
            cols.append(np.asarray(fn(t, X[:, c], u, p), dtype=float).reshape(-1))
        return np.ascontiguousarray(np.column_stack(cols))

    def rhs(self) -> Callable[..., np.ndarray]:
        """The state equation as the core calls it: ``(t, X, u, P) -> (nx, K)``."""
        def call(t: float, X: np.ndarray, u: np.ndarray, P: np.ndarray) -> np.ndarray:
            out = self._call(self.f, t, X, u, P)
            if out.shape != X.shape:
                raise DataError(f"f returned shape {out.shape}, expected {X.shape}")
            return out
        return call

    def out(self) -> Callable[..., np.ndarray]:
        """The output equation as the core calls it: ``(t, X, u, P) -> (l, K)``."""
        return lambda t, X, u, P: self._call(self.h, t, X, u, P)

    def core_options(self) -> dict[str, Any]:
        """Integrator keywords of the core functions."""
        return {"integrator_name": self.integrator, "substeps": self.substeps,
                "rtol": self.rtol, "atol": self.atol}

    # -- the sysid.Model protocol ---------------------------------------------------------
    def simulate(self, u: Any, x0: Any = None, *, dt: float | None = None) -> np.ndarray:
        """Outputs ``(n_samples, noutputs)`` for inputs held between samples (``x0``: the
        initial state, default the structure's first)."""
        dt = self.dt if dt is None else float(dt)
        if not dt > 0:
            raise DataError("simulate needs the sample time: dt=...")
        u = np.asarray(u, dtype=float)
        u = u.reshape(-1, 1) if u.ndim == 1 else u
        x = self.x0[0] if x0 is None else np.asarray(x0, dtype=float).reshape(self.nx)
        return np.asarray(_sysid.greybox_ode_simulate(
            self.rhs(), self.out(), np.ascontiguousarray(u), self.nx, list(self.values),
            list(map(float, x)), dt, **self.core_options()))

    def predict(self, u: Any, y: Any, horizon: int = 1) -> np.ndarray:
        """No noise model: the simulation."""
        return self.simulate(u)

    def linearize(self, x: Any = None, u: Any = None, dt: float | None = None) -> Any:
        """The sampled linearisation at ``(x, u)`` (default: the first initial state and
        zero input), by central differences, as a :class:`sysid.StateSpaceModel`."""
        from .continuous import ContinuousStateSpace

        x = self.x0[0] if x is None else np.asarray(x, dtype=float)
        u = np.zeros(self.ninputs) if u is None else np.asarray(u, dtype=float)
        P = self.values[:, None]

        def jac(fn: Callable[..., Any], wrt: str) -> np.ndarray:
            base = x if wrt == "x" else u
            cols = []
            for i in range(base.size):
                h = 1e-6 * max(1.0, abs(base[i]))
                up, dn = base.copy(), base.copy()
                up[i] += h
                dn[i] -= h
                a = (up, u) if wrt == "x" else (x, up)
                b = (dn, u) if wrt == "x" else (x, dn)
                cols.append((self._call(fn, 0.0, a[0][:, None], a[1], P)
                             - self._call(fn, 0.0, b[0][:, None], b[1], P))[:, 0] / (2 * h))
            return np.column_stack(cols) if cols else np.zeros((0, 0))
        cont = ContinuousStateSpace(jac(self.f, "x"), jac(self.f, "u"), jac(self.h, "x"),
                                    jac(self.h, "u"))
        dt = self.dt if dt is None else dt
        return cont.c2d(dt) if dt else cont

    def to_statespace(self) -> Any:
        """The sampled linearisation (see :meth:`linearize`)."""
        return self.linearize()

    def freqresp(self, omega: Any) -> np.ndarray:
        """Frequency response of the linearisation."""
        return np.asarray(self.linearize().freqresp(omega))

    def __repr__(self) -> str:
        p = len(self.params)
        return (f"NonlinearGreyBox({p} parameter{'s' if p != 1 else ''} "
                f"({len(self.free_names)} free), {self.nx} state{'s' if self.nx != 1 else ''}, "
                f"{self.integrator})")
