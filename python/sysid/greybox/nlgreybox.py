"""Nonlinear grey-box structures (MATLAB's ``idnlgrey``): an ODE right-hand side and an output
function of named parameters, integrated in the Rust core.

``f(t, x, u, p) -> dx/dt`` and ``h(t, x, u, p) -> y`` with ``p`` a
:class:`~sysid.greybox.greybox.Parameters` (attribute access). The input is held constant over
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
from .._checks import as_2d, as_dt, as_int, as_option
from ..errors import DataError
from ..models.protocol import ModelMixin
from .greybox import Param, Parameters, as_params

__all__ = ["NonlinearGreyBox"]

_MAX_SUBSTEPS = 10_000

_JACOBIANS = ("auto", "fd", "sensitivity")
#: relative central-difference step for derivatives of f and h not given by the user
_CD_STEP = float(np.finfo(float).eps ** (1 / 3))


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


def _matrix(out: Any, shape: tuple[int, int], what: str) -> np.ndarray:
    try:
        return np.asarray(out, dtype=float).reshape(shape)
    except ValueError as e:
        raise DataError(f"the derivative {what} returned {np.shape(out)}, expected {shape}"
                        ) from e


def _param_matrix(out: Any, rows: int, names: list[str]) -> np.ndarray:
    """``(rows, n_params)`` from an array in parameter order or a dict ``{name: column}``."""
    if isinstance(out, Mapping):
        unknown = set(out) - set(names)
        if unknown:
            raise DataError(f"the parameter derivative names unknown parameters "
                            f"{sorted(unknown)}; the structure has {names}")
        res = np.zeros((rows, len(names)))
        for k, col in out.items():
            res[:, names.index(k)] = np.asarray(col, dtype=float).reshape(rows)
        return res
    return _matrix(out, (rows, len(names)), "d/dp")


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
    dfdx, dfdp, dhdx, dhdp : callable, optional
        Derivatives ``(t, x, u, p)`` at one point (``x`` of shape ``(nx,)``, float
        parameters): ``dfdx -> (nx, nx)``, ``dhdx -> (ny, nx)``; ``dfdp``/``dhdp`` return
        ``(nx, n_params)``/``(ny, n_params)`` in the order of ``params`` or a dict
        ``{name: column}`` (missing names are zero). With them ``greyest`` forms the Jacobian by
        the forward sensitivity equations ``dS/dt = f_x S + f_p`` integrated beside the
        states by the same integrator.
    jacobian : {"auto", "fd", "sensitivity"}
        ``"auto"``: sensitivity equations when ``dfdx`` and ``dfdp`` are given, otherwise
        forward differences of the whole simulation (``"fd"``). ``"sensitivity"`` without
        (some) derivatives takes the missing ones by central differences of ``f``/``h`` at
        each integrator stage.

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
                 output_names: Any = None, dfdx: Callable[..., Any] | None = None,
                 dfdp: Callable[..., Any] | None = None, dhdx: Callable[..., Any] | None = None,
                 dhdp: Callable[..., Any] | None = None, jacobian: str = "auto") -> None:
        if not (callable(f) and callable(h)):
            raise DataError("f and h must be callables f(t, x, u, p), h(t, x, u, p)")
        if jacobian not in _JACOBIANS:
            raise DataError(f"jacobian must be 'auto', 'fd' or 'sensitivity', got {jacobian!r}")
        for name, fn in (("dfdx", dfdx), ("dfdp", dfdp), ("dhdx", dhdx), ("dhdp", dhdp)):
            if fn is not None and not callable(fn):
                raise DataError(f"{name} must be a callable (t, x, u, p) -> array")
        self.dfdx, self.dfdp, self.dhdx, self.dhdp = dfdx, dfdp, dhdx, dhdp
        self.jacobian = jacobian
        integrator = as_option(integrator, "integrator")
        self.f, self.h = f, h
        self.params: dict[str, Param] = as_params(params)
        self.nx = as_int(nx, "nx")
        self.x0 = np.zeros((1, self.nx)) if x0 is None else \
            np.atleast_2d(np.asarray(x0, dtype=float))
        if self.x0.shape[1] != self.nx:
            raise DataError(f"x0 has {self.x0.shape[1]} entries per experiment, nx is {nx}")
        free = np.asarray(x0_free)
        if not (free.dtype.kind == "b"
                or (free.dtype.kind in "iu" and np.isin(free, (0, 1)).all())):
            raise DataError(f"x0_free must be True, False or a boolean array (per state, or "
                            f"experiments x states), got {x0_free!r}")
        self.x0_free = np.broadcast_to(np.asarray(x0_free, dtype=bool),
                                       (self.x0.shape[0], self.nx)).copy() \
            if np.ndim(x0_free) < 2 else np.asarray(x0_free, dtype=bool)
        if isinstance(substeps, bool) or int(substeps) != substeps or not \
                1 <= substeps <= _MAX_SUBSTEPS:
            raise DataError(f"substeps must be an integer from 1 to {_MAX_SUBSTEPS} (fixed "
                            f"Runge-Kutta steps per sample), got {substeps!r}; for fast or "
                            "stiff dynamics use integrator='adaptive'")
        self.integrator, self.substeps = integrator, int(substeps)
        self.rtol, self.atol = float(rtol), float(atol)
        self.vectorized = bool(vectorized)
        self.dt = 0.0 if dt is None else as_dt(dt)
        self._ninputs = None if ninputs is None else as_int(ninputs, "ninputs", 0)
        self._noutputs = None if noutputs is None else as_int(noutputs, "noutputs")
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
        """The integrator as the core functions take it (their ``integration`` dict)."""
        return {"integrator_name": self.integrator, "substeps": self.substeps,
                "rtol": self.rtol, "atol": self.atol}

    @property
    def jacobian_method(self) -> str:
        """``"sensitivity"`` or ``"fd"``: how ``greyest`` forms the Jacobian."""
        if self.jacobian == "auto":
            given = self.dfdx is not None and self.dfdp is not None
            return "sensitivity" if given else "fd"
        return self.jacobian

    def jacobian_options(self, free: list[str]) -> dict[str, Any]:
        """The Jacobian as the core functions take it (their ``jacobian`` dict): the
        method and, for the sensitivity equations, the point-wise derivative callables
        ``(t, x, u, p) -> (value, d/dx, d/dp)`` (user derivatives, or central differences of
        ``f``/``h`` in the free parameters)."""
        if self.jacobian_method == "fd":
            return {"jacobian": "fd"}
        return {"jacobian": "sensitivity",
                "rhs_derivatives": self._point_derivatives(self.f, self.dfdx, self.dfdp, free),
                "output_derivatives": self._point_derivatives(self.h, self.dhdx, self.dhdp,
                                                              free)}

    def _point_derivatives(self, fn: Callable[..., Any], ddx: Callable[..., Any] | None,
                           ddp: Callable[..., Any] | None, free: list[str]
                           ) -> Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray]]:
        names = self.names
        idx = [names.index(k) for k in free]
        nx = self.nx
        typical = np.array([self.params[k].typical for k in names])

        def call(t: float, x: np.ndarray, u: np.ndarray, P: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
            need_x, need_p = ddx is None, ddp is None
            p = Parameters({n: float(P[i]) for i, n in enumerate(names)})
            if ddx is not None and ddp is not None:   # all given: three plain calls
                v = np.asarray(fn(t, x, u, p) if not self.vectorized else
                               self._call(fn, t, x[:, None], u, P[:, None]), dtype=float)
                v = v.reshape(-1, 1)
                rows = v.shape[0]
                return (v, _matrix(ddx(t, x, u, p), (rows, nx), "d/dx"),
                        _param_matrix(ddp(t, x, u, p), rows, names))
            kx, kp = (nx if need_x else 0), (len(idx) if need_p else 0)
            # the point and its central-difference neighbours in one call: column 0, then
            # +h/-h pairs for each state entry and free parameter not given by the user
            X = np.repeat(x[:, None], 1 + 2 * (kx + kp), axis=1)
            Pm = np.repeat(P[:, None], 1 + 2 * (kx + kp), axis=1)
            hx = _CD_STEP * np.maximum(np.abs(x[:kx]), 1.0)
            hp = _CD_STEP * np.maximum(np.abs(P[idx[:kp]]), typical[idx[:kp]])
            for i in range(kx):
                X[i, 1 + 2 * i] += hx[i]
                X[i, 2 + 2 * i] -= hx[i]
            for c, i in enumerate(idx[:kp]):
                Pm[i, 1 + 2 * (kx + c)] += hp[c]
                Pm[i, 2 + 2 * (kx + c)] -= hp[c]
            V = self._call(fn, t, X, u, Pm)
            v, rows = V[:, :1], V.shape[0]
            D = (V[:, 1::2] - V[:, 2::2]) / np.concatenate([hx, hp]) / 2
            dx = D[:, :nx] if ddx is None else _matrix(ddx(t, x, u, p), (rows, nx), "d/dx")
            if ddp is None:
                dp = np.zeros((rows, len(names)))
                dp[:, idx] = D[:, kx:]
            else:
                dp = _param_matrix(ddp(t, x, u, p), rows, names)
            return v, np.ascontiguousarray(dx, dtype=float), dp
        return call

    # -- the sysid.Model protocol ---------------------------------------------------------
    def simulate(self, u: Any, x0: Any = None, *, dt: float | None = None) -> np.ndarray:
        """Outputs ``(n_samples, noutputs)`` for inputs held between samples (``x0``: the
        initial state, default the structure's first)."""
        dt = self.dt if dt is None else as_dt(dt)
        if not dt > 0:
            raise DataError("simulate needs the sample time: dt=...")
        u = as_2d(u, "u", ncols=self._ninputs)
        x = self.x0[0] if x0 is None else np.asarray(x0, dtype=float).reshape(self.nx)
        return np.asarray(_sysid.greybox_ode_simulate(
            self.rhs(), self.out(), np.ascontiguousarray(u), self.nx, list(self.values),
            list(map(float, x)), dt, integration=self.core_options()))

    def predict(self, u: Any, y: Any = None, horizon: int = 1) -> np.ndarray:
        """No noise model: the simulation (``y`` and ``horizon`` are checked)."""
        from .._measured import as_horizon, as_measured, predict_args

        as_horizon(horizon)
        u, _ = as_measured(*predict_args(u, y), self.ninputs, self.noutputs)
        return self.simulate(u)

    def linearize(self, x: Any = None, u: Any = None, dt: float | None = None) -> Any:
        """The sampled linearisation at ``(x, u)`` (default: the first initial state and
        zero input), by central differences, as a :class:`sysid.StateSpaceModel`."""
        from ..models.continuous import ContinuousStateSpace

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

    #: ``to_statespace()`` is a linearisation, not the model (:func:`sysid.compare`)
    statespace_is_exact = False

    def to_statespace(self) -> Any:
        """The sampled linearisation (see :meth:`linearize`)."""
        return self.linearize()

    def freqresp(self, omega: Any) -> np.ndarray:
        """Frequency response of the linearisation."""
        return np.asarray(self.linearize().freqresp(omega))

    # -- saving ----------------------------------------------------------------------------
    _FUNCTIONS = ("f", "h", "dfdx", "dfdp", "dhdx", "dhdp")

    def to_dict(self) -> dict[str, Any]:
        """Everything but code (see :func:`sysid.save_model`): parameter values, fixed flags,
        bounds, scales, units; initial states; integrator; sample time; the covariance of the
        free parameters when estimated; ``f``, ``h`` (and the derivatives) as
        ``"module:qualname"`` references, imported again on load. Lambdas, nested functions
        and functions defined in ``__main__`` cannot be referred to: a
        :class:`~sysid.DataError` names the function and the fix."""
        from ..models.callref import callable_ref

        refs = {k: None if getattr(self, k) is None else callable_ref(getattr(self, k), k)
                for k in self._FUNCTIONS}
        params = [{"name": k, "value": v.value, "lower": v.bounds[0], "upper": v.bounds[1],
                   "fixed": v.fixed, "scale": v.scale, "unit": v.unit,
                   "description": v.description} for k, v in self.params.items()]
        unc = getattr(self, "uncertainty", None)
        cov = None if unc is None else {"names": list(unc.names), "covariance": unc.covariance,
                                        "dof": unc.dof}
        return {"functions": refs, "params": params, "nx": self.nx, "x0": self.x0,
                "x0_free": self.x0_free, "integrator": self.integrator,
                "substeps": self.substeps, "rtol": self.rtol, "atol": self.atol,
                "vectorized": self.vectorized, "jacobian": self.jacobian, "dt": self.dt,
                "ninputs": self._ninputs, "noutputs": self._noutputs,
                "input_names": None if self._input_names is None else list(self._input_names),
                "output_names": None if self._output_names is None else
                list(self._output_names), "uncertainty": cov, "info": self.info}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> NonlinearGreyBox:
        """Inverse of :meth:`to_dict`: imports the functions again (a
        :class:`~sysid.DataError` naming the one that cannot be imported)."""
        from ..models.callref import resolve_ref
        from .greybox import param

        refs = d.get("functions") or {}
        fns = {k: None if refs.get(k) is None else resolve_ref(refs[k], k)
               for k in cls._FUNCTIONS}
        params = {r["name"]: param(r["value"], bounds=(r["lower"], r["upper"]),
                                   fixed=bool(r["fixed"]), scale=r.get("scale"),
                                   unit=r.get("unit", ""), description=r.get("description", ""))
                  for r in d["params"]}
        dt = float(d.get("dt") or 0.0)
        out = cls(fns["f"], fns["h"], params, nx=int(d["nx"]), x0=d.get("x0"),
                  x0_free=np.asarray(d.get("x0_free", False), dtype=bool),
                  integrator=d.get("integrator", "rk4"), substeps=int(d.get("substeps", 1)),
                  rtol=float(d.get("rtol", 1e-8)), atol=float(d.get("atol", 1e-10)),
                  vectorized=bool(d.get("vectorized", False)), dt=dt or None,
                  ninputs=None if d.get("ninputs") is None else int(d["ninputs"]),
                  noutputs=None if d.get("noutputs") is None else int(d["noutputs"]),
                  input_names=d.get("input_names"), output_names=d.get("output_names"),
                  dfdx=fns["dfdx"], dfdp=fns["dfdp"], dhdx=fns["dhdx"], dhdp=fns["dhdp"],
                  jacobian=d.get("jacobian", "auto"))
        out.info = dict(d.get("info") or {})
        unc = d.get("uncertainty")
        if unc is not None:
            from ..models.uncertainty import ParameterUncertainty

            names = list(unc["names"])

            def build(theta: np.ndarray) -> NonlinearGreyBox:
                return out.with_values(dict(zip(names, np.asarray(theta, dtype=float))))
            out.uncertainty = ParameterUncertainty(
                [out.params[k].value for k in names], unc["covariance"], build, names=names,
                dof=None if unc.get("dof") is None else int(unc["dof"]))
        return out

    def __repr__(self) -> str:
        p = len(self.params)
        return (f"NonlinearGreyBox({p} parameter{'s' if p != 1 else ''} "
                f"({len(self.free_names)} free), {self.nx} state{'s' if self.nx != 1 else ''}, "
                f"{self.integrator})")
