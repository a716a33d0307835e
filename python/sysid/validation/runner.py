"""Running a model on a record for :func:`~sysid.validation.compare.compare` and the
residual tests: the arguments (a model and a record in either order), the model that is run
(its exact state-space form when that lets the initial state be fitted), its initial state
(:func:`estimate_x0`, least squares on the record) and its simulation or ``k``-step
prediction.
"""

from __future__ import annotations

import warnings
from typing import Any, Union

import numpy as np

from .. import _sysid
from .._checks import as_2d, as_int
from ..data.iodata import IOData
from ..errors import DataError, NumericalError, ShapeError, several_records_hint
from ..models.checks import check_model, inner_model
from ..models.trended import TrendedModel
from .fit import output_weights

__all__ = ["X0", "estimate_x0", "fitted_simulation_errors", "given_start"]

X0 = Union[str, np.ndarray, None]


# -- argument handling ------------------------------------------------------------------
def _model_first(model: Any, data: Any) -> tuple[Any, Any]:
    """``(model, data)``, also when given in MATLAB's order (``resid(data, sys)``): a
    record (an :class:`IOData` or a ``(u, y)`` pair) followed by a model."""
    model, data = inner_model(model), inner_model(data)
    is_record = isinstance(model, IOData) or (isinstance(model, tuple) and len(model) == 2)
    if is_record and callable(getattr(data, "simulate", None)):
        return data, model
    return model, data


def _records(model: Any, data: Any) -> tuple[Any, list[tuple[np.ndarray, np.ndarray]]]:
    """The model at the data's rate and the experiments of ``data`` as (u, y) pairs,
    checked against the model's channels.

    A :class:`~sysid.models.trended.TrendedModel` is replaced by its inner model and the
    data by ``trend.apply(data)`` (the trend at the record's own instants), so residuals and
    criteria are those of the model on the detrended record, its initial state estimated
    there.

    A continuous-time model (``dt == 0``) is replaced by the model at the data's sample
    time: :meth:`~sysid.ContinuousStateSpace.sampled` (exact hold, continuous initial
    state), or ``c2d(dt)`` for another continuous class.

    The arguments in MATLAB's order (``resid(data, sys)``: the record first, then a model)
    are taken as such: a record and a model cannot be mistaken for each other.
    """
    model, data = _model_first(model, data)
    model = check_model(model)
    if isinstance(model, TrendedModel):  # the inner model on the record less the trend
        if isinstance(data, tuple) and len(data) == 2:
            data = IOData(u=data[0], y=data[1], dt=model.dt)
        if isinstance(data, IOData):
            data, model = model.trend.apply(data), model.model
    if _operating_point(model):  # residuals are the same about the offsets: use its inside
        data, model = model.remove_offsets(data), model.statespace
    if isinstance(data, IOData):
        recs = data.experiments
    elif isinstance(data, tuple) and len(data) == 2:
        u, y = data
        y = as_2d(y, "y")
        u = np.zeros((y.shape[0], 0)) if u is None else as_2d(u, "u")
        recs = [(u, y)]
    else:
        raise DataError(
            f"data must be a sysid.IOData or a pair (u, y), got {type(data).__name__}"
            + several_records_hint(data))
    m, l = model.ninputs, model.noutputs
    for u, y in recs:
        if u.shape[1] != m or y.shape[1] != l:
            raise ShapeError(
                f"the model has {m} input(s) and {l} output(s) but the data have "
                f"{u.shape[1]} input(s) and {y.shape[1]} output(s); select the same channels "
                "the model was identified on"
            )
        if u.shape[0] != y.shape[0]:
            raise ShapeError(f"u has {u.shape[0]} samples but y has {y.shape[0]}")
    if not model.dt:
        if not isinstance(data, IOData):
            raise DataError("a continuous-time model needs the data's sample time: pass the "
                            "data as a sysid.IOData (with dt), or discretise with model.c2d(dt)")
        for name in ("sampled", "c2d"):
            if hasattr(model, name):
                try:
                    return getattr(model, name)(data.dt), recs
                except NumericalError as e:  # unstable within one sample: reported diverged
                    return _Unsampled(model, data.dt, e), recs
        raise DataError(f"{type(model).__name__} is continuous-time (dt == 0) but has no "
                        "sampled(dt) or c2d(dt) method to meet sampled data")
    if isinstance(data, IOData) and not np.isclose(data.dt, model.dt, rtol=1e-9):
        raise DataError(
            f"the data are sampled every {data.dt:.10g} s but the model every {model.dt:.10g} s; "
            "resample the data or use a model of the same sample time"
        )
    return model, recs


def _operating_point(model: Any) -> bool:
    """A model of deviations about offsets (:class:`sysid.IdentifiedModel`): its
    ``statespace`` on ``remove_offsets(data)``."""
    return hasattr(model, "statespace") and hasattr(model, "remove_offsets")


def _stateful(model: Any) -> bool:
    """A state-space model: its initial state can be estimated and given."""
    return all(hasattr(model, k) for k in ("A", "B", "C", "D", "nstates"))


def _has_state(model: Any) -> bool:
    """A model whose simulation takes any initial state of ``nstates`` entries: a linear
    state-space model, or a nonlinear one that says so (``initial_state_fits``: neural state
    space, Hammerstein-Wiener); :func:`compare` fits its initial state."""
    return _stateful(model) or bool(getattr(model, "initial_state_fits", False))


class _Unsampled:
    """A continuous model that cannot be sampled at the data's ``dt`` (a pole so unstable
    that ``exp(A dt)`` overflows): every run raises the sampling's error, so that the model
    is reported as diverged (fit ``-inf``) like any other that overflows."""

    def __init__(self, model: Any, dt: float, error: NumericalError) -> None:
        self.continuous, self.dt, self.error = model, dt, error
        self.ninputs, self.noutputs = model.ninputs, model.noutputs
        self.input_names, self.output_names = model.input_names, model.output_names

    def simulate(self, *args: Any, **kw: Any) -> np.ndarray:
        raise self.error

    predict = simulate


def _horizon(horizon: Any) -> int | None:
    if horizon is None or (isinstance(horizon, float) and np.isinf(horizon)):
        return None
    return as_int(horizon, "horizon", alt="None (simulation)")


def _run(model: Any, u: np.ndarray, y: np.ndarray, horizon: int | None,
         x0: np.ndarray | None) -> np.ndarray:
    """The model's simulation or prediction of ``y``; a run that overflows (a model that
    diverges on this record) gives ``inf`` outputs, reported as a fit of ``-inf``."""
    try:
        return _run_raw(model, u, y, horizon, x0)
    except NumericalError:
        return np.full(y.shape, np.inf)


def _run_raw(model: Any, u: np.ndarray, y: np.ndarray, horizon: int | None,
             x0: np.ndarray | None) -> np.ndarray:
    if horizon is None:
        out = model.simulate(u, x0=x0) if x0 is not None else model.simulate(u)
    elif x0 is not None:
        out = model.predict(u, y, horizon, x0=x0)
    else:
        out = model.predict(u, y, horizon)
    out = np.asarray(out, dtype=float)
    if out.size != y.size:
        raise ShapeError(f"{type(model).__name__} returned {out.shape} outputs for data of "
                         f"shape {y.shape}")
    return out.reshape(y.shape)


def _one_record(data: Any) -> tuple[Any, Any]:
    """``(u, y)`` of ``estimate_x0``'s record given alone: an IOData of one experiment or a
    ``(u, y)`` pair."""
    if isinstance(data, tuple) and len(data) == 2:
        return data
    exps = getattr(data, "experiments", None)
    if exps is None:
        raise DataError(f"estimate_x0 needs the outputs too: pass estimate_x0(model, u, y) or "
                        f"estimate_x0(model, data) with a sysid.IOData, got "
                        f"{type(data).__name__} alone")
    if len(exps) != 1:
        raise DataError(f"estimate_x0 fits one initial state, but the data hold {len(exps)} "
                        "experiments: pass one (data.experiment(i) or its u, y)")
    return exps[0]


def estimate_x0(model: Any, u: Any, y: Any = None, horizon: int | None = None) -> np.ndarray:
    """Least-squares initial state for simulation (``horizon=None``) or prediction.

    ``u, y`` are the record's arrays, or ``u`` is the record itself (an
    :class:`~sysid.IOData` of one experiment, or a ``(u, y)`` pair) and ``y`` is left out,
    as in MATLAB's ``findstates(sys, data)``.

    The output is ``yhat(x0) = yhat(0) + Phi x0`` where column ``i`` of ``Phi`` is the free
    response from the ``i``-th unit state (computed with the same simulator or predictor, so
    the estimate is exact for whatever is being compared). ``x0`` minimises the errors of
    every output relative to its spread, ``sum_k ||y_k - yhat_k(x0)||^2 / std(y_k)^2`` (as
    the fit % counts them: the same model in other units gets the same fits). Needs a
    state-space model (``A, B, C, D``); use ``model.to_statespace()`` for others.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]])
    >>> u = np.ones(20)
    >>> y = m.simulate(u, x0=[3.0])
    >>> np.round(sysid.estimate_x0(m, u, y), 10)
    array([3.])
    >>> np.round(sysid.estimate_x0(m, sysid.IOData(u=u, y=y)), 10)
    array([3.])
    """
    if y is None:
        u, y = _one_record(u)
    if not _has_state(model):
        raise DataError(f"estimate_x0 needs a state-space model; {type(model).__name__} has no "
                        "A, B, C, D (pass model.to_statespace())")
    u = as_2d(u, "u", ncols=model.ninputs, allow_empty=model.ninputs == 0)
    y = as_2d(y, "y", ncols=model.noutputs)
    if u.shape[0] != y.shape[0]:
        raise ShapeError(f"u has {u.shape[0]} samples but y has {y.shape[0]}")
    n = model.nstates
    if n == 0:
        return np.zeros(0)
    h = _horizon(horizon)
    if not getattr(model, "statespace_is_exact", True):
        return _estimate_x0_nonlinear(model, u, y, h)
    W = _window(model, h, y.shape[0])
    base = _run(model, u[:W], y[:W], h, None)
    u0, y0 = np.zeros((W, u.shape[1])), np.zeros((W, y.shape[1]))
    phi = np.empty((W * y.shape[1], n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = 1.0
        phi[:, i] = _run(model, u0, y0, h, e).ravel()
    target = (y[:W] - base).ravel()
    if not (np.all(np.isfinite(phi)) and np.all(np.isfinite(target))):
        return np.zeros(n)  # the model diverges on this record: no state fits it
    w = np.tile(output_weights(y), W)  # rows t l + k: output k's weight
    with np.errstate(over="ignore", invalid="ignore"):
        x0, *_ = np.linalg.lstsq(phi * w[:, None], target * w, rcond=None)
    return x0 if np.all(np.isfinite(x0)) else np.zeros(n)


def fitted_simulation_errors(model: Any, u: np.ndarray, y: np.ndarray,
                             simulated: np.ndarray | None = None) -> np.ndarray:
    """``y`` minus the linear state-space ``model``'s simulation of ``u`` from the initial
    state that fits ``y`` best (least squares, each output relative to its spread, as
    :func:`estimate_x0`; in the core, blockwise, no ``(N l, n)`` array, by QR where a growing
    mode needs it); the model may be unstable (then keep ``N`` short enough for its growth).

    Parameters
    ----------
    model : StateSpaceModel
        A linear model (``A``, ``C`` and ``simulate``).
    u, y : ndarray, shape (N, m) and (N, l)
        One record.
    simulated : ndarray, shape (N, l), optional
        ``model``'s simulation of ``u`` from rest, when the caller has it already.

    Returns
    -------
    ndarray, shape (N, l)
        The errors (``inf`` everywhere when the model's run diverges).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.runner import fitted_simulation_errors
    >>> m = sysid.StateSpaceModel([[1.02]], [[1.0]], [[1.0]], [[0.0]], dt=1.0)
    >>> u = np.random.default_rng(0).standard_normal((300, 1))
    >>> bool(np.abs(fitted_simulation_errors(m, u, m.simulate(u, x0=[3.0]))).max() < 1e-6)
    True
    """
    y = np.asarray(y, float)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")  # an unstable model's own warnings
        ys = np.asarray(model.simulate(u) if simulated is None else simulated,
                        float).reshape(y.shape)
        if model.nstates == 0:
            return y - ys
        e = _sysid.fitted_errors(np.asarray(model.A, float), np.asarray(model.C, float), y, ys,
                                 False, None)
    return np.full(y.shape, np.inf) if e is None else np.asarray(e).reshape(y.shape)


def _estimate_x0_nonlinear(model: Any, u: np.ndarray, y: np.ndarray,
                           horizon: int | None, iterations: int = 8) -> np.ndarray:
    """Least-squares initial state of a nonlinear state-space model (PNLSS, neural: its
    output is not affine in ``x0``, and its response to a unit state on a zero input holds
    its offsets and nonlinear terms): Gauss-Newton from ``x0 = 0`` on the record's own input,
    the columns by forward differences, each step halved until the error falls. Never worse
    than ``x0 = 0`` over the record, which it returns when no step helps."""
    n = model.nstates
    W = min(y.shape[0], 2 * _window(model, horizon, y.shape[0]))
    uw, yw = u[:W], y[:W]
    w = output_weights(y)

    def err(x: np.ndarray) -> np.ndarray:
        return ((yw - _run(model, uw, yw, horizon, x)) * w).ravel()

    x = np.zeros(n)
    r = err(x)
    cost = float(r @ r) if np.all(np.isfinite(r)) else np.inf
    if not np.isfinite(cost):
        return x
    for _ in range(iterations):
        J = np.empty((r.size, n))
        for i in range(n):
            d = 1e-6 * (1.0 + abs(x[i]))
            xi = x.copy()
            xi[i] += d
            J[:, i] = (r - err(xi)) / d  # d yhat / d x_i
        if not np.all(np.isfinite(J)):
            break
        step, *_ = np.linalg.lstsq(J, r, rcond=None)
        for _half in range(20):
            rt = err(x + step)
            ct = float(rt @ rt) if np.all(np.isfinite(rt)) else np.inf
            if ct < cost:
                break
            step = step / 2
        else:
            break
        done = cost - ct <= 1e-10 * cost
        x, r, cost = x + step, rt, ct
        if done:
            break
    if W < y.shape[0]:  # the window's fit must not cost the rest of the record
        full = [float(np.sum(((y - _run(model, u, y, horizon, v)) * w) ** 2))
                for v in (np.zeros(n), x)]
        if not full[1] < full[0]:
            return np.zeros(n)
    return x


def _window(model: Any, horizon: int | None, N: int) -> int:
    """Samples over which the free response from x0 is above 1e-13 of its start.

    The state is seen through ``A`` (simulation) or the predictor ``A - K C``; past the
    window its influence is below round-off, so the regression ignores those samples (this
    keeps the estimate O(n^2 W) instead of O(n^2 N) on long records).
    """
    F = model.A if hasattr(model, "A") else _linear_part(model).A
    if horizon is not None and getattr(model, "K", None) is not None:
        F = model.A - model.K @ model.C
    rho = float(np.max(np.abs(np.linalg.eigvals(F)))) if F.size else 0.0
    if rho >= 0.9999:
        return N
    decay = 1 if rho == 0 else int(np.ceil(np.log(1e-13) / np.log(rho)))
    # transient growth of non-normal matrices: leave generous room
    W = 4 * decay + 10 * model.nstates + (horizon or 0)
    return int(min(N, max(W, 50)))


def _linear_part(model: Any) -> Any:
    """A nonlinear model's linear part in state-space form (its dynamics)."""
    lin = model.linear()
    return lin if hasattr(lin, "A") else lin.to_statespace()


def given_start(model: Any) -> int:
    """Samples at the start of each experiment that a run of ``model`` copies rather than
    predicts: a NARX model's first ``max_lag`` outputs are its initial condition (the
    measured outputs, or the ``x0`` given) in its simulation and its prediction alike; 0 for
    other models. The one rule by which :func:`compare`'s fit numbers, :func:`residuals`'
    tests and ``nlarx``'s own free-run checks leave them out (as MATLAB's ``compare`` scores a
    nonlinear ARX model whose initial condition comes from the data).

    Examples
    --------
    >>> import sysid
    >>> from sysid.validation.runner import given_start
    >>> m = sysid.NARXModel([2], [1], [1], sysid.PolynomialBasis(1), [[[0]]], [[0.5]], dt=1.0)
    >>> given_start(m), given_start(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]))
    (2, 0)
    """
    if _has_state(model):
        return 0
    lag = getattr(model, "max_lag", None)
    return int(lag) if isinstance(lag, (int, np.integer)) and lag > 0 else 0


def require_scored(recs: list[tuple[np.ndarray, np.ndarray]], start: int, model: Any) -> None:
    """Refuse experiments with no sample after the ``start`` a model's run copies
    (:func:`given_start`): nothing of theirs would be the model's."""
    for i, (_, y) in enumerate(recs):
        if start and y.shape[0] <= start:
            raise DataError(
                f"{type(model).__name__} copies its first {start} outputs (max_lag, its initial "
                f"condition) and predicts the rest, but "
                + (f"experiment {i}" if len(recs) > 1 else "the record")
                + f" has {y.shape[0]} samples: nothing is left to score; give a longer record")


def _x0_for(model: Any, x0: Any, u: np.ndarray, y: np.ndarray, horizon: int | None,
            index: int, count: int) -> np.ndarray | None:
    if not _has_state(model):
        lag = given_start(model)
        if horizon is None and lag > 0:
            # a NARX model's "state" is its first max_lag outputs: the measured ones (as
            # nlarx's own validation criterion runs it), or those given
            if isinstance(x0, str) and x0 == "estimate":
                return y[:lag].copy()
            if x0 is not None and not isinstance(x0, str):
                if (isinstance(x0, (list, tuple)) and count > 1 and len(x0) == count
                        and np.ndim(x0[0]) >= 1):  # one start per experiment
                    x0 = x0[index]
                return np.asarray(x0, dtype=float)
        if x0 is None or (isinstance(x0, str) and x0 in ("estimate", "zero")):
            return None  # no state to estimate: the model starts from rest
        raise DataError(f"{type(model).__name__} has no state-space form here: x0 must be "
                        "'estimate' or 'zero' (it starts from rest)")
    if isinstance(x0, str):
        if x0 == "estimate":
            return estimate_x0(model, u, y, horizon)
        if x0 == "zero":
            return None
        if x0 == "model":
            if getattr(model, "x0", None) is None:
                raise DataError("x0='model' but the model carries no initial state")
            return model.x0
        raise DataError(f"x0 must be 'estimate', 'zero', 'model' or an array, got {x0!r}")
    if x0 is None:
        return None
    if (isinstance(x0, (list, tuple)) and count > 1 and len(x0) == count
            and np.ndim(x0[0]) >= 1):  # one state vector per experiment
        x0 = x0[index]
    arr = np.asarray(x0, dtype=float).ravel()
    if arr.size != model.nstates:
        raise ShapeError(f"x0 has {arr.size} entries but the model has {model.nstates} states")
    return arr



def _simulator(model: Any, x0: Any, horizon: int | None, u: np.ndarray | None = None) -> Any:
    """For a simulation with ``x0="estimate"`` of a model without a state (polynomial, ...),
    or a prediction of one whose state-space form predicts as it does (``statespace_predicts``),
    its ``to_statespace()`` when that is the same input-output map, whose initial state can
    be fitted. A nonlinear model's ``to_statespace()`` is its linear part or linearisation
    (``statespace_is_exact = False`` on the class, or a simulation of the first samples of
    ``u`` that differs): it is simulated itself (from rest unless its initial state fits,
    :func:`_has_state`); its linear part would be compared in its place."""
    if horizon is not None and not getattr(model, "statespace_predicts", False):
        return model
    if (_stateful(model) or not isinstance(x0, str)
            or x0 != "estimate" or not hasattr(model, "to_statespace")
            or not getattr(model, "statespace_is_exact", True)):
        return model
    try:
        ss = model.to_statespace()
    except DataError:  # e.g. a coupled MIMO ARX model: simulate from rest
        return model
    except NumericalError:  # unstable within one sample: its simulation says it diverged
        return model
    if not _stateful(ss):
        return model
    if getattr(model, "statespace_up_to_x0", False) or (
            horizon is not None and getattr(model, "statespace_predicts", False)):
        # the same map but for the initial state (a first-order hold's start from the first
        # input), which the fitted x0 takes up
        return ss
    if u is not None and getattr(model, "dt", 0) and getattr(ss, "dt", 0):
        k = min(len(u), 200)
        try:
            a = np.asarray(model.simulate(u[:k]), float).reshape(k, -1)
            b = np.asarray(ss.simulate(u[:k]), float).reshape(k, -1)
        except Exception:  # noqa: BLE001 - the check cannot run: the class's word stands
            return ss
        if not np.allclose(a, b, rtol=1e-6, atol=1e-9 * max(1.0, float(np.max(np.abs(a)))
                                                            if a.size else 1.0)):
            return model
    return ss
