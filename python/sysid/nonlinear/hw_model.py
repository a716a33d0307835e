"""Hammerstein-Wiener models: static nonlinearities around a linear output-error block.

``w(t) = f(u(t))``, ``x(t) = B(q)/F(q) w(t - nk)``, ``y(t) = g(x(t)) + e(t)`` (one input, one
output). The nonlinearities are normalised to unit gain (unit slope, unit linear term, or a
fixed value at the last breakpoint) so that the gain lives in ``B``. Simulation runs in Rust
(``sysid-core``, ``hw/``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_2d, as_count, as_matrix, check_elements
from .._measured import as_horizon, as_measured, predict_args
from ..errors import DataError, ShapeError
from ..models.protocol import ModelMixin

__all__ = ["Nonlinearity", "Saturation", "DeadZone", "PolynomialNonlinearity",
           "PiecewiseLinear", "SigmoidNetwork", "UserFunction", "HammersteinWienerModel"]


class Nonlinearity:
    """A static nonlinearity with free parameters ``params`` (see the subclasses)."""

    kind = "identity"

    def __init__(self) -> None:
        self.params = np.zeros(0)

    def spec(self) -> tuple[str, int, list[float]]:
        """``(kind, n, breakpoints)`` for the Rust core."""
        return self.kind, 0, []

    def initial(self, x: np.ndarray) -> np.ndarray:
        """Starting parameters from the signal the nonlinearity sees (near identity)."""
        return np.zeros(0)

    def starts(self, x: np.ndarray) -> list[np.ndarray]:
        """Starting points tried by :func:`sysid.nlhw` (the best final cost is kept)."""
        return [self.initial(x)]

    def linear_start(self, x: np.ndarray) -> np.ndarray | None:
        """Parameters that make it the identity over the range of ``x`` to within round-off,
        where :meth:`initial` is not (``None``: it is). With them on every channel the
        Hammerstein-Wiener search starts from its linear model itself, so it ends no worse
        than that model."""
        return None

    def __call__(self, x: Any) -> np.ndarray:
        """Evaluate at ``x`` with the current ``params``."""
        return np.asarray(x, float)

    def to_dict(self) -> dict[str, Any]:
        """For saving."""
        return {"kind": self.kind, "params": self.params}

    def __repr__(self) -> str:
        p = np.array2string(np.asarray(self.params), precision=4, separator=", ")
        return f"{type(self).__name__}({p})"


_MAX_DEGREE = 100


def _bounds(lower: Any, upper: Any, who: str) -> tuple[float | None, float | None]:
    """Start values of a two-sided nonlinearity: finite numbers, lower < upper."""
    out = []
    for name, v in (("lower", lower), ("upper", upper)):
        if v is not None:
            try:
                v = float(v)
            except (TypeError, ValueError):
                raise DataError(f"{who}: {name} must be a number or None, got {v!r}") from None
            if not np.isfinite(v):
                raise DataError(f"{who}: {name} must be finite, got {v!r}")
        out.append(v)
    if out[0] is not None and out[1] is not None and not out[0] < out[1]:
        raise DataError(f"{who}: lower ({out[0]:g}) must be below upper ({out[1]:g}); swap them")
    return out[0], out[1]


class Saturation(Nonlinearity):
    """``clip(x, lower, upper)`` (unit slope); ``lower``/``upper`` start values (default: the
    1 % and 99 % quantiles of the signal).

    Examples
    --------
    >>> import sysid
    >>> s = sysid.Saturation(-0.5, 0.5); s.params = s.initial(None)
    >>> s([-2.0, 0.1, 3.0]).tolist()
    [-0.5, 0.1, 0.5]
    """

    kind = "saturation"

    def __init__(self, lower: float | None = None, upper: float | None = None) -> None:
        self.lower, self.upper = _bounds(lower, upper, type(self).__name__)
        self.params = np.array([np.nan, np.nan])

    def initial(self, x: Any) -> np.ndarray:
        lo = self.lower if self.lower is not None else float(np.quantile(x, 0.01))
        hi = self.upper if self.upper is not None else float(np.quantile(x, 0.99))
        return np.array([lo, hi], float)

    def starts(self, x: Any) -> list[np.ndarray]:
        if self.lower is not None and self.upper is not None:
            return [self.initial(x)]
        out = []
        for q in (0.01, 0.1, 0.25):
            lo = self.lower if self.lower is not None else float(np.quantile(x, q))
            hi = self.upper if self.upper is not None else float(np.quantile(x, 1 - q))
            out.append(np.array([lo, hi], float))
        return out

    def __call__(self, x: Any) -> np.ndarray:
        return np.clip(np.asarray(x, float), self.params[0], self.params[1])


class DeadZone(Nonlinearity):
    """Zero between ``lower`` and ``upper``, unit slope outside (default start: +-5 % of the
    signal's standard deviation).

    Examples
    --------
    >>> import sysid
    >>> d = sysid.DeadZone(-0.2, 0.2); d.params = d.initial(None)
    >>> d([-1.0, 0.1, 1.0]).tolist()
    [-0.8, 0.0, 0.8]
    """

    kind = "deadzone"

    def __init__(self, lower: float | None = None, upper: float | None = None) -> None:
        self.lower, self.upper = _bounds(lower, upper, type(self).__name__)
        self.params = np.array([np.nan, np.nan])

    def initial(self, x: Any) -> np.ndarray:
        s = 0.05 * float(np.std(x)) if x is not None else 0.05
        return np.array([self.lower if self.lower is not None else -s,
                         self.upper if self.upper is not None else s], float)

    def starts(self, x: Any) -> list[np.ndarray]:
        if self.lower is not None and self.upper is not None:
            return [self.initial(x)]
        s = float(np.std(x))
        return [self.initial(x), np.array([self.lower if self.lower is not None else -0.3 * s,
                                           self.upper if self.upper is not None else 0.3 * s])]

    def __call__(self, x: Any) -> np.ndarray:
        x = np.asarray(x, float)
        lo, hi = self.params
        return np.where(x > hi, x - hi, np.where(x < lo, x - lo, 0.0))


class PolynomialNonlinearity(Nonlinearity):
    """``x + c_2 x^2 + ... + c_d x^d`` (unit linear term).

    Examples
    --------
    >>> import sysid
    >>> p = sysid.PolynomialNonlinearity(3); p.params = [0.0, 0.5]
    >>> p([2.0]).tolist()
    [6.0]
    """

    kind = "polynomial"

    def __init__(self, degree: int = 3) -> None:
        if int(degree) != degree or degree < 2:
            raise DataError(f"degree must be an integer >= 2, got {degree!r}")
        if degree > _MAX_DEGREE:  # x**degree overflows double precision for |x| > 2
            raise DataError(f"degree must be at most {_MAX_DEGREE}, got {degree!r}: powers that "
                            "high overflow double precision; use PiecewiseLinear or "
                            "SigmoidNetwork for a flexible curve")
        self.degree = int(degree)
        self.params = np.zeros(self.degree - 1)

    def spec(self) -> tuple[str, int, list[float]]:
        return self.kind, self.degree, []

    def initial(self, x: Any) -> np.ndarray:
        return np.zeros(self.degree - 1)

    def __call__(self, x: Any) -> np.ndarray:
        x = np.asarray(x, float)
        return x + sum(c * x ** (k + 2) for k, c in enumerate(np.asarray(self.params, float)))

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "params": self.params, "degree": self.degree}


class PiecewiseLinear(Nonlinearity):
    """Linear interpolation between values at chosen ``breakpoints`` (end segments
    extended); the value at the last breakpoint is held at the breakpoint (gain
    normalisation), the others are free.

    ``breakpoints`` are the values themselves, or their number (MATLAB's
    ``idPiecewiseLinear`` with ``NumberOfUnits``; default 10): that many are then placed
    evenly over the range of the signal the nonlinearity sees when the fit starts (its
    :meth:`initial`), the input for an input nonlinearity, the linear model's output for an
    output one.

    Examples
    --------
    >>> import sysid
    >>> p = sysid.PiecewiseLinear([-1.0, 0.0, 1.0]); p.params = p.initial(None)
    >>> p([-2.0, 0.5]).tolist()
    [-2.0, 0.5]
    >>> q = sysid.PiecewiseLinear(5); q.params = q.initial([-2.0, 0.0, 2.0])
    >>> q.breakpoints.tolist()
    [-2.0, -1.0, 0.0, 1.0, 2.0]
    """

    kind = "pwl"

    def __init__(self, breakpoints: Any = 10) -> None:
        self.count: int | None = None
        self.breakpoints: Any = None
        self.params = np.zeros(0)
        if np.ndim(breakpoints) == 0 and not isinstance(breakpoints, str):
            self.count = as_count(breakpoints, "the number of breakpoints", 8, lo=2)
            return
        self.breakpoints = np.asarray(breakpoints, float).ravel()
        if self.breakpoints.size < 2 or np.any(np.diff(self.breakpoints) <= 0):
            raise DataError("breakpoints must be an array of at least two strictly increasing "
                            f"values, or their number (at least 2); got {breakpoints!r}")
        self.params = self.breakpoints[:-1].copy()

    def _placed(self, x: Any) -> np.ndarray:
        """The breakpoints, placed over the range of ``x`` first when only their number was
        given."""
        if self.breakpoints is None:
            v = np.asarray(x, float).ravel() if x is not None else np.zeros(0)
            v = v[np.isfinite(v)]
            if v.size == 0 or not np.max(v) > np.min(v):
                raise DataError(f"PiecewiseLinear({self.count}) places its breakpoints over "
                                "the range of the signal it sees, and that signal is constant "
                                "(or missing): give the breakpoints themselves")
            self.breakpoints = np.linspace(np.min(v), np.max(v), self.count)
            self.params = self.breakpoints[:-1].copy()
        return np.asarray(self.breakpoints)

    def spec(self) -> tuple[str, int, list[float]]:
        if self.breakpoints is None:
            raise DataError(f"PiecewiseLinear({self.count}) has no breakpoints yet: they are "
                            "placed by initial(x) over the range of the signal x it sees (a "
                            "fit does this), or give them")
        return self.kind, 0, self.breakpoints.tolist()

    def initial(self, x: Any) -> np.ndarray:
        return self._placed(x)[:-1].copy()

    def linear_start(self, x: Any) -> np.ndarray | None:
        self._placed(x)  # the identity: initial(x) already is
        return None

    def __call__(self, x: Any) -> np.ndarray:
        self.spec()  # refuses breakpoints not yet placed
        z = np.asarray(self.breakpoints)
        v = np.append(np.asarray(self.params, float), z[-1])
        x = np.asarray(x, float)
        s = np.clip(np.searchsorted(z, x, side="right") - 1, 0, z.size - 2)
        lam = (x - z[s]) / (z[s + 1] - z[s])
        return (1 - lam) * v[s] + lam * v[s + 1]

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "params": self.params,
                "breakpoints": self.breakpoints if self.breakpoints is not None else self.count}


class SigmoidNetwork(Nonlinearity):
    """``c x + sum_k a_k tanh(b_k x + d_k)`` with ``units`` units and the first amplitude
    fixed, ``a_1 = amplitude``; ``params = [c, b_1, d_1, a_2, b_2, d_2, ...]``.

    The fixed amplitude is in the units of the signal the network takes (an input network,
    whose output then lives in ``B``) or models (an output network), so :func:`sysid.nlhw`
    and :func:`sysid.nlhw_ss` set it to that channel's standard deviation in the training
    record (a unit amplitude would be a different curve in volts and in millivolts: the
    fitted model would depend on the units the channel was recorded in).

    Examples
    --------
    >>> import sysid
    >>> s = sysid.SigmoidNetwork(2); s.params = s.initial([-1.0, 1.0])
    >>> s.params.shape
    (6,)
    >>> g = sysid.SigmoidNetwork(1, amplitude=3.0); g.params = [0.5, 2.0, 0.0]
    >>> round(float(g(0.25)), 6)  # 0.5 * 0.25 + 3 tanh(2 * 0.25)
    1.511351
    """

    kind = "sigmoid"

    def __init__(self, units: int = 3, amplitude: float = 1.0) -> None:
        # three parameters a unit: a count beyond memory is refused before they are made
        self.units = as_count(units, "units", 3 * 8)
        self.params = np.zeros(3 * self.units)
        try:
            self.amplitude = float(amplitude)
        except (TypeError, ValueError):
            self.amplitude = float("nan")
        if not (np.isfinite(self.amplitude) and self.amplitude != 0.0):
            raise DataError(f"SigmoidNetwork: amplitude must be a finite nonzero number, got "
                            f"{amplitude!r}")

    def spec(self) -> tuple[str, int, list[float]]:
        return self.kind, self.units, [] if self.amplitude == 1.0 else [self.amplitude]

    def table(self) -> tuple[float, np.ndarray]:
        """The linear coefficient ``c`` and one row ``(a_k, b_k, d_k)`` per unit, ``a_1``
        filled in.

        Examples
        --------
        >>> import sysid
        >>> g = sysid.SigmoidNetwork(1, amplitude=3.0); g.params = [0.5, 2.0, -1.0]
        >>> c, rows = g.table(); c, rows.tolist()
        (0.5, [[3.0, 2.0, -1.0]])
        """
        rows = np.asarray(self.params, float).reshape(-1, 3).copy()
        c = float(rows[0, 0])
        rows[0, 0] = self.amplitude
        return c, rows

    def initial(self, x: Any) -> np.ndarray:
        s = float(np.std(x)) or 1.0
        centres = np.linspace(-1, 1, self.units) * s if self.units > 1 else np.zeros(1)
        a = 0.5 * self.amplitude  # amplitudes (and c) in the units of the fixed one
        p = np.column_stack([np.full(self.units, a), np.full(self.units, 1.0 / s),
                             -1.0 / s * centres]).ravel()
        p[0] = a / s  # the linear coefficient c
        return p

    def linear_start(self, x: Any) -> np.ndarray:
        """``c x + a_1 tanh(b_1 x)`` with ``b_1 = 1e-3 / std(x)``, ``c = 1 - a_1 b_1`` (the
        fixed unit in its linear range: ``|a_1| |b_1 x|^3 / 3`` at most ``1e-8 |a_1|`` over
        3 standard deviations), the other units' amplitudes zero and their slopes and
        centres as in :meth:`initial` (the search can grow them).

        Examples
        --------
        >>> import numpy as np, sysid
        >>> s = sysid.SigmoidNetwork(3); x = np.linspace(-3.0, 3.0, 7)
        >>> s.params = s.linear_start(x)
        >>> bool(np.max(np.abs(s(x) - x)) < 1e-8)
        True
        """
        p = self.initial(x).reshape(-1, 3)
        b1 = 1e-3 / (float(np.std(x)) or 1.0)
        p[0] = [1.0 - self.amplitude * b1, b1, 0.0]
        p[1:, 0] = 0.0
        return p.ravel()

    def __call__(self, x: Any) -> np.ndarray:
        x = np.asarray(x, float)
        c, rows = self.table()
        return c * x + sum(a * np.tanh(b * x + d) for a, b, d in rows)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "params": self.params, "units": self.units,
                "amplitude": self.amplitude}


class UserFunction(Nonlinearity):
    """A fixed, user-supplied input nonlinearity ``w = func(u)`` (no free parameters; the
    linear block and the output nonlinearity are estimated on ``func(u)``). Not saved by
    :func:`sysid.save_model` (a Python function is not data).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> sysid.UserFunction(np.sign)([-2.0, 3.0]).tolist()
    [-1.0, 1.0]
    """

    kind = "user"

    def __init__(self, func: Callable[[np.ndarray], Any]) -> None:
        if not callable(func):
            raise DataError("UserFunction needs a callable func(u) -> array")
        self.func = func
        self.params = np.zeros(0)

    def spec(self) -> tuple[str, int, list[float]]:
        return "identity", 0, []

    def __call__(self, x: Any) -> np.ndarray:
        x = np.asarray(x, float)
        out = np.asarray(self.func(x), float)
        if out.shape != x.shape or not np.all(np.isfinite(out)):
            raise DataError("UserFunction must return finite values of the input's shape")
        return out


def fit_amplitudes(nls: list[Any], x: np.ndarray) -> None:
    """Fix the first amplitude of every :class:`SigmoidNetwork` in ``nls`` at the standard
    deviation of its column of ``x`` (samples x channels, the training record as fitted):
    for an input network the input it takes, for an output network the output it models,
    so that the model class scales with the channel's units (a fit of the record in other
    units is the same model, scaled) and a network's linear start (the identity) is on
    the scale of its fixed unit."""
    for g, col in zip(nls, np.asarray(x, float).reshape(len(x), -1).T):
        if isinstance(g, SigmoidNetwork):
            sd = float(np.std(col))
            g.amplitude = sd if np.isfinite(sd) and sd > 0 else 1.0


def with_linear_uncertainty(model: Any, linear: Any) -> Any:
    """``linear`` (``model.linear()``'s block) carrying ``model``'s uncertainty seen
    through ``linear()`` (a deferred sandwich stays deferred); itself when there is none."""
    unc = model.__dict__.get("uncertainty")
    if unc is not None:
        from ..pem.sandwich import through_deferred

        linear.uncertainty = through_deferred(unc, lambda m: m.linear())
    return linear


def linear_with_std(model: Any) -> Any:
    """``model.linear()`` with the uncertainty of ``model`` formed first (a clear error
    without one): for ``poles(std=True)`` and ``freqresp(omega, std=True)``."""
    from ..models.uncertainty import form_deferred, require

    info = getattr(model, "info", None) or {}
    if getattr(model, "uncertainty", None) is None and not isinstance(
            info.get("uncertainty"), dict):
        raise DataError(f"{type(model).__name__}: std=True needs the parameter uncertainty "
                        "that sysid.nlhw and sysid.nlhw_ss attach (model.uncertainty); this "
                        "model carries none (built by hand, or saved without it)")
    require(model)  # names why the fit attached none
    form_deferred(model)
    return model.linear()


def uncertainty_lines(model: Any) -> list[str]:
    """The parameter table with standard deviations for ``summary()`` (none without an
    uncertainty)."""
    unc = model.__dict__.get("uncertainty")
    return [] if unc is None else ["  parameters:", unc.summary(max_rows=20)]


_KINDS = {c.kind: c for c in (Nonlinearity, Saturation, DeadZone, PolynomialNonlinearity,
                              PiecewiseLinear, SigmoidNetwork)}


def nonlinearity_from_dict(d: dict[str, Any]) -> Nonlinearity:
    """Inverse of ``Nonlinearity.to_dict``."""
    kind = str(d["kind"])
    if kind == "user":
        raise DataError("a model with a UserFunction cannot be loaded: the function is not "
                        "saved")
    if kind == "polynomial":
        nl: Nonlinearity = PolynomialNonlinearity(int(d["degree"]))
    elif kind == "pwl":
        nl = PiecewiseLinear(d["breakpoints"])
    elif kind == "sigmoid":  # saved before the amplitude was kept: one
        nl = SigmoidNetwork(int(d["units"]), amplitude=float(d.get("amplitude", 1.0)))
    else:
        nl = _KINDS[kind]()
    nl.params = np.asarray(d["params"], float).ravel()
    return nl


def fitted_curve(f: Nonlinearity) -> bool:
    """Whether ``f`` is a static curve the search fits (not the identity, not a fixed
    :class:`UserFunction`).

    Examples
    --------
    >>> import sysid
    >>> from sysid.nonlinear.hw_model import Nonlinearity, fitted_curve
    >>> fitted_curve(Nonlinearity()), fitted_curve(sysid.SigmoidNetwork(3))
    (False, True)
    """
    return type(f) is not Nonlinearity and not isinstance(f, UserFunction)


def check_search_size(nls: list[Any], residuals: int, who: str, regressors: int = 1) -> None:
    """Refuse, before the search allocates its Jacobian (one row per residual, one column
    per parameter), nonlinearities whose parameters make it too large: a
    ``SigmoidNetwork(10**6)`` took minutes and gigabytes before failing. A network's unit
    has ``regressors + 2`` parameters (a slope per regressor, a centre, an amplitude)."""
    def units(f: Any) -> int:
        return int(getattr(f, "units", 0)) + int(getattr(f, "scaling_units", 0))

    n_par = sum(units(f) * (regressors + 2) if units(f) else
                int(np.size(getattr(f, "params", ()))) for f in nls)
    most = max((f for f in nls), key=units, default=None)
    what = (f"{who} with a {type(most).__name__} of {units(most)} units ({n_par} "
            f"nonlinearity parameters) on {residuals} residuals" if most and units(most) else
            f"{who} with {n_par} nonlinearity parameters on {residuals} residuals")
    check_elements(residuals * n_par, what, "use far fewer units (3 to 30 are usual) or a "
                   "shorter record")


class HammersteinWienerModel(ModelMixin):
    """A Hammerstein-Wiener model (see the module docstring).

    Parameters
    ----------
    input_nl, output_nl : Nonlinearity
        With their fitted ``params``.
    b, f : array_like
        ``B`` coefficients ``b_0..`` and free ``F`` coefficients ``f_1..``.
    nk : int
        Input delay.
    dt : float
        Sample time.
    u_offset, y_offset : float
        The operating point: the model is ``y = y_offset + g(B/F f(u - u_offset))``
        (:mod:`sysid.nonlinear.operating_point`; zero by default).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> sat = sysid.Saturation(); sat.params = np.array([-0.5, 0.5])
    >>> m = sysid.HammersteinWienerModel(sat, sysid.Nonlinearity(), [1.0], [-0.5], 1, 1.0)
    >>> m.simulate(np.full(4, 2.0)).ravel().tolist()
    [0.0, 0.5, 0.75, 0.875]
    >>> m.poles()
    array([0.5+0.j])
    """

    def __init__(self, input_nl: Nonlinearity, output_nl: Nonlinearity, b: Any, f: Any,
                 nk: int, dt: float, *, noise_variance: float = 1.0,
                 info: dict[str, Any] | None = None, input_names: Any = None,
                 output_names: Any = None, u_offset: float = 0.0,
                 y_offset: float = 0.0) -> None:
        for name, g in (("input_nl", input_nl), ("output_nl", output_nl)):
            if g is not None and not isinstance(g, Nonlinearity):
                raise DataError(f"{name} must be a sysid nonlinearity (Saturation, DeadZone, "
                                f"PolynomialNonlinearity, PiecewiseLinear, SigmoidNetwork, "
                                f"UserFunction) or None (none on that side), got {g!r}")
        # None: no nonlinearity on that side (as nlhw takes it)
        self.input_nl = Nonlinearity() if input_nl is None else input_nl
        self.output_nl = Nonlinearity() if output_nl is None else output_nl
        for name, g in (("input_nl", self.input_nl), ("output_nl", self.output_nl)):
            if not np.all(np.isfinite(np.asarray(g.params, float))):
                raise DataError(f"{name} ({g!r}) has parameters not set (NaN): give them, "
                                f"e.g. nl.params = nl.initial(x) for the signal x it sees, or "
                                f"fit the model with sysid.nlhw")
        self.u_offset, self.y_offset = float(u_offset), float(y_offset)
        if not (np.isfinite(self.u_offset) and np.isfinite(self.y_offset)):
            raise DataError("u_offset and y_offset must be finite")
        self.b = np.asarray(b, float).ravel()
        self.f = np.asarray(f, float).ravel()
        self.nk, self.dt = int(nk), float(dt)
        self.noise_variance = float(noise_variance)
        self.info: dict[str, Any] = dict(info or {})
        self.input_names = ["u0"] if input_names is None else [str(n) for n in input_names]
        self.output_names = ["y0"] if output_names is None else [str(n) for n in output_names]
        if self.b.size < 1:
            raise DataError("b needs at least one coefficient")

    ninputs = property(lambda self: 1, doc="Number of inputs (1).")
    noutputs = property(lambda self: 1, doc="Number of outputs (1).")
    nstates = property(lambda self: int(self.f.size),
                       doc="The linear block's state: its last ``nf`` outputs before the record.")
    #: ``simulate`` takes the linear block's state: :func:`sysid.compare` fits it
    #: (``x0="estimate"``), by Gauss-Newton since the output is not affine in it
    initial_state_fits = True
    statespace_is_exact = False

    @property
    def theta(self) -> np.ndarray:
        """Parameters ``[input_nl, b, f, output_nl]`` in the estimator's order."""
        return np.concatenate([self.input_nl.params, self.b, self.f, self.output_nl.params])

    @property
    def n_parameters(self) -> int:
        """Number of free parameters, the output level included when estimated."""
        return int(self.theta.size) + bool(dict(self.info.get("offsets") or {}).get(
            "y_estimated"))

    def _level_estimated(self) -> bool:
        return bool(dict(self.info.get("offsets") or {}).get("y_estimated"))

    def _searched(self) -> np.ndarray:
        """The parameters the search estimated: ``theta``, then ``y_offset`` when the output
        level was estimated (:mod:`sysid.nonlinear.hw_uncertainty`)."""
        return np.concatenate([self.theta, [self.y_offset] * self._level_estimated()])

    def _searched_names(self) -> list[str]:
        return self._names() + ["y_offset"] * self._level_estimated()

    def _names(self) -> list[str]:
        return ([f"input[{k}]" for k in range(self.input_nl.params.size)]
                + [f"b{k}" for k in range(self.b.size)]
                + [f"f{k + 1}" for k in range(self.f.size)]
                + [f"output[{k}]" for k in range(self.output_nl.params.size)])

    def _rebuilt(self, theta: Any) -> HammersteinWienerModel:
        """The model with the searched parameters ``theta`` (:meth:`_searched`'s order): the
        ``build`` of its uncertainty."""
        import copy

        t = np.asarray(theta, float).ravel()
        fin, fout = copy.deepcopy(self.input_nl), copy.deepcopy(self.output_nl)
        cuts = np.cumsum([fin.params.size, self.b.size, self.f.size, fout.params.size])
        fin.params, b, f, fout.params = (t[:cuts[0]], t[cuts[0]:cuts[1]], t[cuts[1]:cuts[2]],
                                         t[cuts[2]:cuts[3]])
        return HammersteinWienerModel(
            fin, fout, b, f, self.nk, self.dt, noise_variance=self.noise_variance,
            info={"offsets": self.info.get("offsets")}, input_names=self.input_names,
            output_names=self.output_names, u_offset=self.u_offset,
            y_offset=float(t[-1]) if self._level_estimated() else self.y_offset)

    def _from_state(self, u: Any, h: Any) -> np.ndarray:
        """``(n, 1)``: the output from the estimator's initial state ``h`` (``max(nf, nk + nb
        - 1)`` coefficients acting on the first samples, ``info["initial_state"]``)."""
        from .hw_initial import free_response_bf

        _, _, x = self.signals(u)
        h = np.asarray(h, float).ravel()
        free = free_response_bf(self.f, h.size, x.size) @ h
        return (np.asarray(self.output_nl(x + free), float) + self.y_offset)[:, None]

    def _u(self, u: Any) -> np.ndarray:
        # complex, NaN or Inf, a wrong shape: an error naming u, not NaN outputs
        u = as_2d(u, "u", ncols=1)[:, 0]
        if self.u_offset:
            u = u - self.u_offset
        if isinstance(self.input_nl, UserFunction):
            u = self.input_nl(u)
        return np.ascontiguousarray(u)

    def signals(self, u: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(y, w, x)``: output (with ``y_offset``), input-nonlinearity output and
        linear-block output."""
        y, w, x = _sysid.hw_simulate(self.input_nl.spec(), self.output_nl.spec(), self.b.size,
                                     self.f.size, self.nk, self.theta.tolist(), self._u(u))
        return np.asarray(y) + self.y_offset, np.asarray(w), np.asarray(x)

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        """Noise-free output ``(n, 1)`` from rest, or from the linear block's state ``x0``:
        its outputs ``x(-1), ..., x(-nf)`` before the record (their free response through
        ``1/F`` is added to the block's output before the output nonlinearity)."""
        y, _, x = self.signals(u)
        if x0 is None or (isinstance(x0, str) and x0 == "zero"):
            return y[:, None]
        past = as_matrix(np.ravel(x0) if not isinstance(x0, str) else x0, "x0", (1, None))[0]
        if past.size != self.nstates:
            raise ShapeError(f"x0 has {past.size} entries but the linear block has "
                             f"{self.nstates} states (the F coefficients)")
        if not past.any():
            return y[:, None]
        from scipy.signal import lfilter, lfiltic

        a = np.concatenate([[1.0], self.f])
        free = lfilter([1.0], a, np.zeros(x.size), zi=lfiltic([1.0], a, past))[0]
        return (np.asarray(self.output_nl(x + free), float) + self.y_offset)[:, None]

    def predict(self, u: Any, y: Any = None, horizon: int = 1, x0: Any = None) -> np.ndarray:
        """The output-error predictor does not use measured outputs: equals ``simulate``
        (from ``x0``; ``u``, ``y`` and ``horizon`` are checked all the same, as every
        model's are)."""
        as_horizon(horizon)
        u, _ = as_measured(*predict_args(u, y), 1, 1)
        return self.simulate(u, x0)

    def linear(self) -> Any:
        """The linear block ``B/F`` as a :class:`~sysid.PolynomialModel` (with the
        uncertainty of its coefficients when the model carries one)."""
        from ..polynomial.model import PolynomialModel

        out = PolynomialModel([[np.zeros(0)]], [[self.b]], [[self.nk]], self.dt, f=[[self.f]])
        return with_linear_uncertainty(self, out)

    def freqresp(self, omega: Any, std: bool = False) -> Any:
        """Frequency response of the linear block (between the nonlinearities); with
        ``std=True`` (needs ``uncertainty``) the pair ``(H, sd)`` as for
        :meth:`sysid.PolynomialModel.freqresp`."""
        if std:
            return linear_with_std(self).freqresp(omega, std=True)
        return np.asarray(self.linear().freqresp(omega))

    def poles(self, std: bool = False) -> Any:
        """Poles of the linear block (roots of ``F``); with ``std=True`` (needs
        ``uncertainty``) the pair ``(poles, sd)`` as for :meth:`sysid.PolynomialModel.poles`."""
        if std:
            return linear_with_std(self).poles(std=True)
        return np.roots(np.concatenate([[1.0], self.f])).astype(complex) if self.f.size \
            else np.zeros(0, complex)

    def summary(self) -> str:
        """Nonlinearities, linear block and fit."""
        return "\n".join([repr(self), f"  input:  {self.input_nl!r}",
                          f"  B: {np.array2string(self.b, precision=5)}",
                          f"  F: 1 {np.array2string(self.f, precision=5)}",
                          f"  output: {self.output_nl!r}",
                          f"  operating point: u0 = {self.u_offset:.6g}, "
                          f"y0 = {self.y_offset:.6g}",
                          f"  residual variance {self.noise_variance:.4g}, "
                          f"{self.info.get('iterations', '-')} iterations "
                          f"({self.info.get('stop', '-')})"] + uncertainty_lines(self))

    def __repr__(self) -> str:
        ident_in, ident_out = (type(f) is Nonlinearity for f in (self.input_nl, self.output_nl))
        kind = ("linear: no nonlinearity" if ident_in and ident_out else
                "Hammerstein-Wiener" if not (ident_in or ident_out) else
                "Wiener" if ident_in else "Hammerstein")
        return (f"HammersteinWienerModel({kind}, nb={self.b.size}, nf={self.f.size}, "
                f"nk={self.nk}, dt={self.dt:g})")

    def to_pandas(self) -> Any:
        """Parameters as a table (with their standard deviations when the model carries an
        uncertainty; the estimated output level is the uncertainty's last row)."""
        import pandas as pd

        out = pd.DataFrame({"parameter": self._names(), "value": self.theta})
        unc = getattr(self, "uncertainty", None)
        if unc is not None:
            out["std"] = unc.std[:self.theta.size]
        return out

    def plot(self, fig: Any = None) -> Any:
        """The two nonlinearities over the range seen in estimation; returns the figure."""
        import matplotlib.pyplot as plt

        fig = fig or plt.figure(figsize=(8, 3))
        for k, (nl, key, name) in enumerate([(self.input_nl, "u_range", "input"),
                                             (self.output_nl, "x_range", "output")]):
            lo, hi = self.info.get(key, (-1.0, 1.0))
            x = np.linspace(lo, hi, 200)
            ax = fig.add_subplot(1, 2, k + 1)
            ax.plot(x, nl(x))
            ax.set_title(f"{name} nonlinearity")
        fig.tight_layout()
        return fig

    def to_dict(self) -> dict[str, Any]:
        """For :func:`sysid.save_model` (not with a :class:`UserFunction`)."""
        if isinstance(self.input_nl, UserFunction):
            raise DataError("a model with a UserFunction input cannot be saved")
        return {"input_nl": self.input_nl.to_dict(), "output_nl": self.output_nl.to_dict(),
                "b": self.b, "f": self.f, "nk": self.nk, "dt": self.dt,
                "noise_variance": self.noise_variance, "info": self.info,
                "input_names": self.input_names, "output_names": self.output_names,
                "u_offset": self.u_offset, "y_offset": self.y_offset}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> HammersteinWienerModel:
        """Inverse of :meth:`to_dict`."""
        return cls(nonlinearity_from_dict(dict(d["input_nl"])),
                   nonlinearity_from_dict(dict(d["output_nl"])), d["b"], d["f"], int(d["nk"]),
                   float(d["dt"]), noise_variance=float(d.get("noise_variance", 1.0)),
                   info=d.get("info"), input_names=d.get("input_names"),
                   output_names=d.get("output_names"), u_offset=float(d.get("u_offset", 0.0)),
                   y_offset=float(d.get("y_offset", 0.0)))
