"""Grey-box structures: linear state-space models written in named physical parameters.

A structure is a function ``fn(p, dt=None) -> (A, B, C, D[, K[, x0]])`` of named parameters
(``p.Yv``, ``p["Yv"]``), each free or fixed, with bounds, a scale, a unit and a description
(:func:`param`, :func:`fixed`). Continuous structures (``continuous=True``) are sampled at the
data's sample time exactly, by zero-order hold (or first-order hold) through the matrix
exponential of the augmented matrix

.. math::

    \\exp\\left(\\begin{bmatrix} A & B \\\\ 0 & 0 \\end{bmatrix} \\Delta t\\right)
    = \\begin{bmatrix} A_d & B_d \\\\ 0 & I \\end{bmatrix},

and the derivatives of ``(A_d, B_d)`` with respect to a parameter come from the Fréchet
derivative of the exponential in the direction of that parameter's ``(dA, dB)`` (the
augmented-block form, scaling and squaring in the Rust core); ``dA/dp`` itself by central
differences of ``fn`` unless a ``jacobian`` is given. ``K`` (when returned) is the
innovation gain of the *sampled* model.

Examples
--------
>>> import numpy as np, sysid
>>> def motor(p, dt=None):
...     return [[-1 / p.tau]], [[p.K / p.tau]], [[1.0]], [[0.0]]
>>> s = sysid.GreyBox(motor, params={"K": 2.0, "tau": sysid.param(0.5, bounds=(0.01, 10))})
>>> s
GreyBox(2 parameters (2 free), 1 state, 1 input, 1 output, continuous)
>>> m = s.model(dt=0.1)
>>> round(float(m.A[0, 0]), 6) == round(float(np.exp(-0.2)), 6)
True
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..errors import DataError, IdentifiabilityWarning
from ..models.discretisation import expm, from_blocks, hold_blocks
from .delays import check_fraction, delayed_blocks, input_taps, split_delays, tap_states

__all__ = ["Param", "param", "fixed", "Parameters", "GreyBox", "IdentifiabilityWarning"]

_HOLDS = ("zoh", "foh")


@dataclass(frozen=True)
class Param:
    """One named parameter of a grey-box structure (see :func:`param`)."""

    value: float
    bounds: tuple[float, float] = (-np.inf, np.inf)
    fixed: bool = False
    scale: float | None = None
    unit: str = ""
    description: str = ""

    @property
    def typical(self) -> float:
        """The scale, or ``max(|value|, 1e-3)`` when none was given."""
        if self.scale is not None:
            return float(self.scale)
        return max(abs(self.value), 1e-3)


def param(value: float, bounds: tuple[float, float] | None = None, fixed: bool = False,
          scale: float | None = None, unit: str = "", description: str = "") -> Param:
    """A grey-box parameter: initial value, bounds, fixed or free, scale, unit, description.

    Parameters
    ----------
    value : float
        Initial value (the value itself when ``fixed``).
    bounds : (float, float), optional
        Lower and upper bound (``None``, ``-inf`` or ``inf`` for none, as SciPy's bounds);
        the search stays inside and the parameter table reports an active bound.
    fixed : bool
        Keep the value: it never moves.
    scale : float, optional
        Typical magnitude: the search works on ``value / scale``; also sets difference steps
        and the multistart range. Default ``max(|value|, 1e-3)``.
    unit, description : str
        Shown in the parameter table.

    Examples
    --------
    >>> import sysid
    >>> sysid.param(0.5, bounds=(0, 1), unit="1/s")
    Param(value=0.5, bounds=(0.0, 1.0), fixed=False, scale=None, unit='1/s', description='')
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise DataError(f"a parameter value must be a real number, got {value!r}") from None
    if not np.isfinite(v):
        raise DataError(f"a parameter value must be finite, got {value!r}")
    lo, hi = _bounds(bounds)
    if not lo <= hi:
        raise DataError(f"bounds must satisfy lower <= upper, got {bounds!r}")
    if not fixed and not lo <= v <= hi:
        raise DataError(f"the initial value {v} lies outside its bounds {bounds!r}: start inside")
    if scale is not None and not (np.isfinite(scale) and scale > 0):
        raise DataError(f"scale must be a positive number, got {scale!r}")
    return Param(v, (lo, hi), bool(fixed), None if scale is None else float(scale), str(unit),
                 str(description))


def _bounds(bounds: Any) -> tuple[float, float]:
    """``(lower, upper)`` of ``param``'s bounds: ``None`` for no bound on that side."""
    if bounds is None:
        return -np.inf, np.inf
    try:
        lo, hi = bounds
        return (-np.inf if lo is None else float(lo)), (np.inf if hi is None else float(hi))
    except (TypeError, ValueError):
        raise DataError(f"bounds must be a pair (lower, upper) of numbers or None, got "
                        f"{bounds!r}") from None


def fixed(value: float, unit: str = "", description: str = "") -> Param:
    """A fixed (known) parameter: ``param(value, fixed=True)``.

    Examples
    --------
    >>> import sysid
    >>> sysid.fixed(9.81, unit="m/s^2").fixed
    True
    """
    return param(value, fixed=True, unit=unit, description=description)


class Parameters(Mapping[str, Any]):
    """Named parameter values with attribute access (``p.Yv`` or ``p["Yv"]``).

    Values are floats, or arrays when a nonlinear structure is evaluated on several
    perturbed parameter sets at once.

    Examples
    --------
    >>> from sysid.greybox.greybox import Parameters
    >>> p = Parameters({"a": 1.0, "b": 2.0})
    >>> p.a + p["b"]
    3.0
    """

    def __init__(self, values: Mapping[str, Any]) -> None:
        # plain instance attributes: attribute access at C speed inside user functions
        self.__dict__.update(values)

    def __getattr__(self, name: str) -> Any:
        raise AttributeError(f"no parameter named {name!r}; the structure has "
                             f"{', '.join(self.__dict__)}")

    def __getitem__(self, name: str) -> Any:
        return self.__dict__[name]

    def __iter__(self) -> Any:
        return iter(self.__dict__)

    def __len__(self) -> int:
        return len(self.__dict__)

    def __repr__(self) -> str:
        return "Parameters(" + ", ".join(f"{k}={v!r}" for k, v in self.__dict__.items()) + ")"


def as_params(params: Mapping[str, Any]) -> dict[str, Param]:
    """``{name: Param}`` from a dict whose values are numbers or :class:`Param`."""
    if not isinstance(params, Mapping) or not params:
        raise DataError("params must be a non-empty dict {name: value or sysid.param(...)}")
    out = {}
    for k, v in params.items():
        if not isinstance(k, str) or not k.isidentifier():
            raise DataError(f"parameter names must be identifiers, got {k!r}")
        try:
            out[k] = v if isinstance(v, Param) else param(v)
        except DataError as e:
            raise DataError(f"parameter {k!r}: {e}") from None
    return out


def _takes_dt(fn: Callable[..., Any]) -> bool:
    try:
        sig = inspect.signature(fn)
    except (TypeError, ValueError):
        return False
    return "dt" in sig.parameters or any(
        q.kind == q.VAR_KEYWORD for q in sig.parameters.values())


class GreyBox:
    """A linear grey-box structure: system matrices as a function of named parameters.

    Parameters
    ----------
    fn : callable
        ``fn(p, dt=None) -> (A, B, C, D[, K[, x0]])`` with ``p`` a :class:`Parameters`
        (attribute access to the named values). ``dt`` is the sample time (``None`` for a
        continuous structure evaluated in continuous time).
    params : dict
        ``{name: value | sysid.param(...) | sysid.fixed(...)}`` in the order of the table.
    continuous : bool
        ``fn`` returns a continuous-time model (sampled exactly at the data's sample time).
    dt : float, optional
        Sample time of a discrete structure (default: the data's).
    input_delay : float or array_like, optional
        Known input delays in seconds (per input). Any delay for a continuous structure
        (a fraction of the sample time is sampled exactly under ZOH and FOH, see
        :mod:`sysid.greybox.delays`); whole multiples of the sample time for a discrete one.
    hold : {"zoh", "foh"}
        Inter-sample behaviour for a continuous structure.
    jacobian : callable, optional
        ``jacobian(p, dt=None) -> {name: (dA, dB, dC, dD[, dK[, dx0]])}`` derivatives of the
        matrices with respect to the free parameters (otherwise central differences).
    input_names, output_names : sequence of str, optional

    Examples
    --------
    >>> import sysid
    >>> s = sysid.GreyBox(lambda p: ([[p.a]], [[1.0]], [[1.0]], [[0.0]]),
    ...                   params={"a": 0.5}, continuous=False, dt=1.0)
    >>> s.names, s.free_names
    (['a'], ['a'])
    """

    def __init__(self, fn: Callable[..., Any], params: Mapping[str, Any], *,
                 continuous: bool = True, dt: float | None = None, input_delay: Any = None,
                 hold: str = "zoh", jacobian: Callable[..., Any] | None = None,
                 input_names: Any = None, output_names: Any = None) -> None:
        if not callable(fn):
            raise DataError("fn must be a callable fn(p, dt=None) -> (A, B, C, D[, K, x0])")
        self.fn = fn
        self.params = as_params(params)
        self.continuous = bool(continuous)
        self.dt = None if dt is None else float(dt)
        if self.dt is not None and not (np.isfinite(self.dt) and self.dt > 0):
            raise DataError(f"dt must be a positive sample time, got {dt!r}")
        if hold not in _HOLDS:
            raise DataError(f"hold must be 'zoh' or 'foh', got {hold!r}")
        self.hold = hold
        self.jacobian_fn = jacobian
        self.input_names, self.output_names = input_names, output_names
        self._dt_arg = _takes_dt(fn)
        mats = self.matrices()
        self.nstates, self.ninputs = mats["B"].shape
        self.noutputs = mats["C"].shape[0]
        delay = np.zeros(self.ninputs) if input_delay is None else np.broadcast_to(
            np.asarray(input_delay, dtype=float), (self.ninputs,)).copy()
        if np.any(delay < 0) or not np.all(np.isfinite(delay)):
            raise DataError("input_delay must be finite and >= 0 (seconds)")
        self.input_delay = delay

    # -- parameters ---------------------------------------------------------------------
    @property
    def names(self) -> list[str]:
        """All parameter names, in table order."""
        return list(self.params)

    @property
    def free_names(self) -> list[str]:
        """Names of the free parameters."""
        return [k for k, v in self.params.items() if not v.fixed]

    @property
    def values(self) -> np.ndarray:
        """All parameter values (initial, or estimated for a structure from ``greyest``)."""
        return np.array([v.value for v in self.params.values()])

    def with_values(self, values: Mapping[str, float] | np.ndarray) -> GreyBox:
        """A copy whose parameters (free and fixed) take ``values``."""
        if not isinstance(values, Mapping):
            values = dict(zip(self.names, np.asarray(values, dtype=float)))
        out = object.__new__(GreyBox)
        out.__dict__.update(self.__dict__)
        out.params = {k: replace(v, value=float(values.get(k, v.value)))
                      for k, v in self.params.items()}
        return out

    # -- matrices -----------------------------------------------------------------------
    def _call(self, values: Mapping[str, Any], dt: float | None) -> dict[str, np.ndarray | None]:
        p = Parameters(values)
        out = self.fn(p, dt=dt) if self._dt_arg else self.fn(p)
        if not isinstance(out, (tuple, list)) or not 4 <= len(out) <= 6:
            raise DataError("the structure function must return (A, B, C, D), (A, B, C, D, K) "
                            "or (A, B, C, D, K, x0)")
        try:
            A = np.atleast_2d(np.asarray(out[0], dtype=float))
            n = A.shape[0]
            B = np.asarray(out[1], dtype=float).reshape(n, -1)
            C = np.atleast_2d(np.asarray(out[2], dtype=float)).reshape(-1, n)
            D = np.asarray(out[3], dtype=float).reshape(C.shape[0], B.shape[1])
            K = None if len(out) < 5 or out[4] is None else \
                np.asarray(out[4], dtype=float).reshape(n, C.shape[0])
            x0 = None if len(out) < 6 or out[5] is None else \
                np.asarray(out[5], dtype=float).reshape(n)
        except (ValueError, TypeError) as e:
            raise DataError(f"the structure function returned inconsistent shapes: {e}") from e
        if A.shape != (n, n):
            raise DataError(f"A must be square, got shape {A.shape}")
        return {"A": A, "B": B, "C": C, "D": D, "K": K, "x0": x0}

    def matrices(self, values: Any = None, dt: float | None = None
                 ) -> dict[str, np.ndarray | None]:
        """``{"A", "B", "C", "D", "K", "x0"}`` as ``fn`` returns them (not sampled)."""
        vals = self._values(values)
        return self._call(vals, dt if dt is not None else self.dt)

    def _values(self, values: Any) -> dict[str, float]:
        if values is None:
            return {k: v.value for k, v in self.params.items()}
        if isinstance(values, Mapping):
            return {k: float(values.get(k, v.value)) for k, v in self.params.items()}
        return dict(zip(self.names, np.asarray(values, dtype=float)))

    def sampled(self, values: Any, dt: float) -> dict[str, np.ndarray | None]:
        """The sampled matrices at ``dt`` (a discrete structure's own, a continuous one's by
        ZOH/FOH)."""
        mats = self._call(self._values(values), dt)
        if not self.continuous:
            return mats
        A, B, C, D = mats["A"], mats["B"], mats["C"], mats["D"]
        assert A is not None and B is not None and C is not None and D is not None
        n, m = B.shape
        E = expm(hold_blocks(A, B, dt, self.hold), [])[0]
        Ad, Bd, dD = from_blocks(E, C, D, n, m, self.hold)
        return {**mats, "A": Ad, "B": Bd, "D": D + dD}

    def sampled_derivatives(self, values: Any, dt: float, names: list[str]
                            ) -> tuple[dict[str, Any], list[dict[str, np.ndarray | None]]]:
        """Sampled matrices and their derivatives with respect to each parameter in ``names``
        (Fréchet derivative of the exponential for continuous structures)."""
        _, _, base, ders = self._sampled_all(self._values(values), dt, names)
        return base, ders

    def _sampled_all(self, vals: dict[str, float], dt: float, names: list[str]
                     ) -> tuple[dict[str, Any], list[dict[str, Any]], dict[str, Any],
                                list[dict[str, Any]]]:
        """``(raw, raw derivatives, sampled, sampled derivatives)``."""
        base = self._call(vals, dt)
        raw = self._raw_derivatives(vals, dt, names, base)
        if not self.continuous:
            return base, raw, base, raw
        A, B, C, D = base["A"], base["B"], base["C"], base["D"]
        assert A is not None and B is not None and C is not None and D is not None
        n, m = B.shape
        M = hold_blocks(A, B, dt, self.hold)
        dMs = []
        for d in raw:
            dM = hold_blocks(d["A"], d["B"], dt, self.hold)
            if self.hold == "foh":
                dM[n:n + m, n + m:] = 0.0
            dMs.append(dM)
        E, dEs = expm(M, dMs)
        Ad, Bd, dD0 = from_blocks(E, C, D, n, m, self.hold)
        out = []
        for d, dE in zip(raw, dEs):
            if self.hold == "zoh":
                dAd, dBd, ddD = dE[:n, :n], dE[:n, n:n + m], np.zeros_like(D)
            else:
                G2, dG1, dG2 = E[:n, n + m:], dE[:n, n:n + m], dE[:n, n + m:]
                dAd = dE[:n, :n]
                dBd = dG1 + dAd @ G2 + (Ad - np.eye(n)) @ dG2
                ddD = d["C"] @ G2 + C @ dG2
            out.append({**d, "A": dAd, "B": dBd, "D": d["D"] + ddD})
        return base, raw, {**base, "A": Ad, "B": Bd, "D": D + dD0}, out

    def input_taps(self, dt: float) -> list[tuple[int, int]]:
        """The sampled model's input columns ``(input, shift in samples)``: one per input
        whose delay is a whole number of samples, two (``l`` and ``l + 1`` samples) for a
        fractional delay ``l dt + r`` (see :mod:`sysid.greybox.delays`)."""
        check_fraction(self.input_delay, dt, self.continuous, self.hold)
        return input_taps(self.input_delay, dt, self.hold)

    def sampled_taps(self, values: Any, dt: float, names: list[str] | None = None
                     ) -> tuple[dict[str, Any], list[dict[str, Any]]]:
        """The sampled matrices with ``B`` and ``D`` over :meth:`input_taps` (exact for
        fractional input delays under ZOH), and their derivatives with respect to ``names``."""
        taps = self.input_taps(dt)
        vals = self._values(values)
        names = list(names or [])
        raw, raw_d, base, ders = self._sampled_all(vals, dt, names)
        if len(taps) == self.ninputs:  # whole-sample delays: the plain columns
            return base, ders
        Bt, Dt, dt_ders = delayed_blocks(raw, raw_d, base, ders, dt, self.input_delay,
                                         self.hold)
        return ({**base, "B": Bt, "D": Dt},
                [{**d, "B": db, "D": dd} for d, (db, dd) in zip(ders, dt_ders)])

    def _raw_derivatives(self, vals: dict[str, float], dt: float | None, names: list[str],
                         base: dict[str, Any]) -> list[dict[str, np.ndarray | None]]:
        keys = ("A", "B", "C", "D", "K", "x0")
        if self.jacobian_fn is not None:
            p = Parameters(vals)
            given = self.jacobian_fn(p, dt=dt) if _takes_dt(self.jacobian_fn) else \
                self.jacobian_fn(p)
            out = []
            for k in names:
                d = list(given[k]) + [None] * (6 - len(given[k]))
                out.append({key: (np.zeros_like(base[key]) if d[i] is None else
                                  np.asarray(d[i], dtype=float).reshape(base[key].shape))
                            if base[key] is not None else None for i, key in enumerate(keys)})
            return out
        out = []
        for k in names:
            h = np.finfo(float).eps ** (1 / 3) * max(abs(vals[k]), self.params[k].typical)
            up, dn = dict(vals), dict(vals)
            up[k] += h
            dn[k] -= h
            mu, md = self._call(up, dt), self._call(dn, dt)
            out.append({key: None if base[key] is None else
                        (np.asarray(mu[key]) - np.asarray(md[key])) / (2 * h) for key in keys})
        return out

    # -- models -------------------------------------------------------------------------
    def model(self, values: Any = None, dt: float | None = None) -> Any:
        """The structure at ``values`` as a model: :class:`sysid.ContinuousStateSpace` for a
        continuous structure without ``dt`` (and without delays), otherwise the sampled
        :class:`sysid.StateSpaceModel` (input delays as extra states)."""
        from ..models.continuous import ContinuousStateSpace
        from ..models.statespace import StateSpaceModel

        dt = dt if dt is not None else self.dt
        if dt is None:
            if not self.continuous:
                raise DataError("a discrete structure needs dt")
            mats = self.matrices(values)
            if np.any(self.input_delay > 0):
                raise DataError("a structure with input delays is returned sampled: give dt")
            return ContinuousStateSpace(mats["A"], mats["B"], mats["C"], mats["D"],
                                        hold=self.hold, input_names=self.input_names,
                                        output_names=self.output_names)
        mats, _ = self.sampled_taps(values, dt)
        A, B, C, D, K = tap_states(mats, self.input_taps(dt), self.ninputs)
        return StateSpaceModel(A, B, C, D, K, dt=dt, input_names=self.input_names,
                               output_names=self.output_names)

    def delay_samples(self, dt: float) -> np.ndarray:
        """Input delays in whole samples, rounded down (the fraction is in
        :meth:`input_taps`)."""
        return split_delays(self.input_delay, dt)[0]

    @classmethod
    def from_structure(cls, A: Any, B: Any, C: Any, D: Any = None, K: Any = None, *,
                       free: Mapping[str, Any] | None = None, continuous: bool = False,
                       dt: float | None = None, bounds: Mapping[str, Any] | None = None,
                       **kwargs: Any) -> GreyBox:
        """MATLAB's structured ``idss``: the given matrices, with the entries marked in
        ``free`` (boolean masks per matrix, e.g. ``{"A": mask}``) estimated, the others fixed.

        Parameters are named ``A_i_j`` (zero-based). ``bounds`` maps a matrix name to
        ``(lower, upper)`` arrays (or scalars) for its free entries.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> s = sysid.GreyBox.from_structure([[0.5, 0.0], [0.1, 0.3]], [[1.0], [0.0]],
        ...                                  [[0.0, 1.0]], free={"A": [[1, 0], [1, 1]]})
        >>> s.free_names
        ['A_0_0', 'A_1_0', 'A_1_1']
        """
        base: dict[str, np.ndarray] = {"A": np.atleast_2d(np.asarray(A, dtype=float))}
        n = base["A"].shape[0]
        base["B"] = np.asarray(B, dtype=float).reshape(n, -1)
        base["C"] = np.atleast_2d(np.asarray(C, dtype=float)).reshape(-1, n)
        m, l = base["B"].shape[1], base["C"].shape[0]
        base["D"] = np.zeros((l, m)) if D is None else np.asarray(D, dtype=float).reshape(l, m)
        if K is not None:
            base["K"] = np.asarray(K, dtype=float).reshape(n, l)
        free = dict(free or {})
        bounds = dict(bounds or {})
        params: dict[str, Param] = {}
        where: dict[str, tuple[str, int, int]] = {}
        for key, mat in base.items():
            mask = np.zeros(mat.shape, bool) if key not in free else \
                np.broadcast_to(np.asarray(free[key], dtype=bool), mat.shape)
            lo, hi = bounds.get(key, (-np.inf, np.inf))
            lo = np.broadcast_to(np.asarray(lo, dtype=float), mat.shape)
            hi = np.broadcast_to(np.asarray(hi, dtype=float), mat.shape)
            for i, j in zip(*np.nonzero(mask)):
                name = f"{key}_{i}_{j}"
                params[name] = param(mat[i, j], bounds=(lo[i, j], hi[i, j]))
                where[name] = (key, int(i), int(j))
        unknown = set(free) - set(base)
        if unknown:
            raise DataError(f"free has masks for {sorted(unknown)}; use A, B, C, D, K")
        if not params:
            raise DataError("no entry is free: mark entries in free={'A': mask, ...}")

        def fn(p: Parameters) -> tuple[Any, ...]:
            mats = {k: v.copy() for k, v in base.items()}
            for name, (key, i, j) in where.items():
                mats[key][i, j] = p[name]
            return (mats["A"], mats["B"], mats["C"], mats["D"], mats.get("K"))

        return cls(fn, params, continuous=continuous, dt=dt, **kwargs)

    def _repr_html_(self) -> str:
        """Notebook display: facts, parameters, poles (see :mod:`sysid._display`)."""
        from .._display import greybox_html

        return greybox_html(self)

    def __repr__(self) -> str:
        p = len(self.params)
        kind = "continuous" if self.continuous else "discrete"
        s = lambda k, w: f"{k} {w}{'s' if k != 1 else ''}"  # noqa: E731
        return (f"GreyBox({s(p, 'parameter')} ({len(self.free_names)} free), "
                f"{s(self.nstates, 'state')}, {s(self.ninputs, 'input')}, "
                f"{s(self.noutputs, 'output')}, {kind})")
