"""Validation: compare a model with measured data, and test its residuals.

:func:`compare`
    Simulation (``horizon=None``) or ``k``-step-ahead Kalman prediction against the
    measured outputs, per output NRMSE fit (MATLAB's ``compare`` definition), VAF and RMSE.
:func:`residuals` (in :mod:`sysid.validation.residuals`)
    Auto-correlation of the one-step prediction errors and their cross-correlation with the
    inputs, with confidence bounds, a Ljung-Box portmanteau test of whiteness per output and
    Ljung's test of independence from past inputs (an exact regression F test).
:func:`error_spectrum`
    Power spectrum of the simulation error beside that of the output: the frequencies at
    which a model is wrong stand out.

The initial state is estimated by default (``x0="estimate"``): the model's response is linear
in ``x0``, so its free response from each unit state forms a regressor and ``x0`` follows by
least squares on the record. ``x0="zero"``, ``"model"`` (the state stored with the model) or
an array are the alternatives.

Data may be an :class:`~sysid.IOData` (several experiments allowed: each gets its own
initial state and its own row of fit numbers) or a pair ``(u, y)``.

Any model satisfying :class:`sysid.Model` is accepted. The initial state is estimated for
state-space models (those with ``A, B, C, D`` and ``nstates``, and nonlinear ones whose
simulation takes any initial state, ``initial_state_fits``: PNLSS, neural state space and
Hammerstein-Wiener, by Gauss-Newton), and for the simulation of a
model with ``to_statespace()`` when its state-space form simulates the same map (not a
nonlinear model's linear part or linearisation), and for every horizon of a model whose
state-space form also predicts as it does (``statespace_predicts``: polynomial models, their
noise model included; transfer functions, whose predictions are their simulation); other
models start from rest, and ``x0`` may then only be ``"estimate"`` or ``"zero"``. A continuous-time
model (``dt == 0``) meets the data at their sample time with its ``hold`` (ZOH or FOH, exact;
its initial state is the continuous state), so the data must be an :class:`~sysid.IOData`.
"""

from __future__ import annotations

from typing import Any, Union

import numpy as np

from .._checks import as_2d, as_int
from .._display import HTMLResult
from .._threads import one_blas_thread
from ..data.iodata import IOData
from ..errors import DataError, NumericalError, ShapeError, SysidWarning, several_records_hint
from ..models.checks import check_model, inner_model
from ..models.trended import TrendedModel

__all__ = [
    "CompareResult",
    "compare",
    "fit_metrics",
    "estimate_x0",
]

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


def output_weights(y: np.ndarray) -> np.ndarray:
    """``1 / std`` of each output over the record (1 for one that stands still): the initial
    state is fitted to the errors relative to each output's spread, as the fit % weighs them,
    not to whichever output has the largest numbers in its units."""
    s = _unit(y)
    sd = np.std(y / s, axis=0) * s
    return 1.0 / np.where(sd > 0, sd, 1.0)


def _unit(y: np.ndarray) -> np.ndarray:
    """Per output, the power of two nearest its largest deviation from its mean (1 for one
    that stands still): norms and variances are taken of ``y / unit`` and scaled back, since
    the squares of outputs near 1e-200 underflow (a fit of nan) and near 1e200 overflow
    (-inf). Dividing by a power of two is exact: outputs of ordinary size give the same
    numbers to the last bit."""
    with np.errstate(over="ignore", invalid="ignore"):
        spread = np.max(np.abs(y - y.mean(0)), axis=0, initial=0.0)
    ok = (spread > 0) & np.isfinite(spread)
    return np.where(ok, np.ldexp(1.0, np.frexp(np.where(ok, spread, 1.0))[1]), 1.0)


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
    >>> from sysid.validation.compare import given_start
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


def fit_metrics(y: Any, yhat: Any) -> dict[str, np.ndarray]:
    """NRMSE fit, VAF (both %) and RMSE per output column.

    ``fit = 100 (1 - ||y - yhat|| / ||y - mean(y)||)`` (MATLAB's ``compare``; 100 is
    perfect, 0 is no better than the mean, negative is worse), ``vaf = 100 (1 - var(y - yhat)
    / var(y))`` and ``rmse = sqrt(mean((y - yhat)^2))``. Fit and VAF are undefined for a
    constant output channel: it raises a :class:`~sysid.errors.DataError` (as
    :func:`compare` does). The measurement comes first; MATLAB's ``goodnessOfFit(x, xref)``
    takes the reference second: :func:`sysid.goodness_of_fit` has its order and costs.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> y = np.array([0.0, 1.0, 2.0, 3.0])
    >>> sysid.fit_metrics(y, y + 0.1)["fit"]
    array([91.05572809])
    """
    y = as_2d(y, "y")
    yhat = as_2d(yhat, "yhat", ncols=y.shape[1])
    if yhat.shape != y.shape:
        raise ShapeError(f"yhat has shape {yhat.shape} but y has {y.shape}")
    require_outputs_vary([y])
    return _metrics(y, yhat)


def _metrics(y: np.ndarray, yhat: np.ndarray) -> dict[str, np.ndarray]:
    s = _unit(y)
    # an unstable model's simulation may overflow: its fit is then -inf, not a warning
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        y, err = y / s, (y - yhat) / s
        dev = np.linalg.norm(y - y.mean(0), axis=0)
        fit = 100.0 * (1.0 - np.linalg.norm(err, axis=0) / dev)
        vaf = 100.0 * (1.0 - err.var(0) / y.var(0))
        rmse = np.sqrt(np.mean(err**2, axis=0)) * s
    fit = np.where(np.isnan(fit) & ~np.isfinite(rmse), -np.inf, fit)
    fit = np.where(dev == 0, np.nan, fit)  # undefined for a constant channel (documented)
    return {"fit": fit, "vaf": vaf, "rmse": rmse}


# -- compare ----------------------------------------------------------------------------
def diverged(y: np.ndarray, yhat: np.ndarray) -> bool:
    """A model output that overflowed or grew beyond ``1e8`` times the measured range (the
    rule of :func:`compare`'s ``diverged``, shared by the fits' own free-run checks).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.validation.compare import diverged
    >>> diverged(np.ones(3), np.array([1.0, 2.0, 3e9])), diverged(np.ones(3), np.ones(3))
    (True, False)
    """
    if not np.all(np.isfinite(yhat)):
        return True
    scale = float(np.max(np.abs(y))) if y.size else 0.0
    return bool(yhat.size and np.max(np.abs(yhat)) > 1e8 * max(scale, 1e-300))


class CompareResult(HTMLResult):
    """Measured versus model outputs, with fit numbers per experiment and output.

    Attributes
    ----------
    horizon : int or None
        ``None`` for simulation, else the prediction horizon.
    y, yhat : list of ndarray
        Measured and model outputs per experiment, ``(n_samples, noutputs)``.
    u : list of ndarray
        Inputs per experiment.
    x0 : list of ndarray or None
        Initial state used per experiment.
    start : int
        Samples at the start of each experiment that the model's run copies rather than
        predicts (:func:`given_start`: a NARX model's first ``max_lag`` outputs, its initial
        condition; 0 for other models): kept in ``yhat``, left out of the fit numbers.
    fit, vaf, rmse : ndarray
        Shape ``(n_experiments, noutputs)`` over the samples after ``start``; see
        :func:`fit_metrics`.
    diverged : ndarray of bool
        Per experiment: the model's output diverged on it (not finite, or beyond ``1e8``
        times the measured range: an unstable model on a long record); its fit is ``-inf``
        and the comparison is reported, not raised.
    """

    def __init__(self, model: Any, horizon: int | None, u: list[np.ndarray],
                 y: list[np.ndarray], yhat: list[np.ndarray], x0: list[Any],
                 start: int = 0) -> None:
        self.model, self.horizon = model, horizon
        self.u, self.y, self.yhat, self.x0 = u, y, yhat, x0
        self.start = int(start)
        #: start time of each experiment (the record's clock; ``None``: from 0)
        self.t0: list[float] | None = None
        self.output_names = list(model.output_names)
        self.dt = model.dt
        metrics = [_metrics(a[start:], b[start:]) for a, b in zip(y, yhat)]
        self.fit = np.array([d["fit"] for d in metrics])
        self.vaf = np.array([d["vaf"] for d in metrics])
        self.rmse = np.array([d["rmse"] for d in metrics])
        #: per experiment: the model's output diverged (not finite, or grew beyond 1e8 times
        #: the measured range); its fit is -inf
        self.diverged = np.array([diverged(a, b) for a, b in zip(y, yhat)])
        self.fit[self.diverged] = -np.inf

    @property
    def kind(self) -> str:
        """``"simulation"`` or ``"k-step prediction"``."""
        return "simulation" if self.horizon is None else f"{self.horizon}-step prediction"

    @property
    def mean_fit(self) -> float:
        """Fit averaged over outputs and experiments (a single score)."""
        return float(np.mean(self.fit))

    def to_pandas(self) -> Any:
        """One row per (experiment, output) with fit, VAF and RMSE."""
        import pandas as pd

        rows = []
        for e in range(self.fit.shape[0]):
            for j, name in enumerate(self.output_names):
                rows.append({"experiment": e, "output": name, "fit %": self.fit[e, j],
                             "VAF %": self.vaf[e, j], "RMSE": self.rmse[e, j],
                             "diverged": bool(self.diverged[e])})
        return pd.DataFrame(rows)

    def summary(self) -> str:
        """A text table of the fit numbers."""
        w = max([20] + [len(str(n)) for n in self.output_names])  # names whole
        lines = [f"{self.kind} of {self.model!r}",
                 f"{'exp':>4} {'output':<{w}} {'fit %':>9} {'VAF %':>9} {'RMSE':>11}"]
        for e in range(self.fit.shape[0]):
            for j, name in enumerate(self.output_names):
                lines.append(f"{e:>4} {name:<{w}} {self.fit[e, j]:9.2f} {self.vaf[e, j]:9.2f} "
                             f"{self.rmse[e, j]:11.4g}"
                             + ("  diverged (unstable on this record)" if self.diverged[e]
                                else ""))
        return "\n".join(lines)

    def plot(self, experiment: int = 0, fig: Any = None) -> Any:
        """Measured and model outputs over time, one axis per output; returns the figure."""
        from ..plot.validation import plot_compare

        return plot_compare(self, experiment=experiment, fig=fig)

    def __repr__(self) -> str:
        fits = ", ".join(f"{n}: {f:.1f}" for n, f in zip(self.output_names, self.fit.mean(0)))
        ne = len(self.y)
        div = ", diverged" if self.diverged.any() else ""
        return (f"CompareResult({self.kind}, {ne} experiment{'s' * (ne != 1)}, fit % "
                f"[{fits}]{div})")


@one_blas_thread
def compare(*args: Any, horizon: int | None = None, x0: X0 = "estimate") -> Any:
    """Compare models' simulations or ``horizon``-step predictions with measured outputs.

    ``compare(data, m1, m2, ...)`` (MATLAB's order) compares several models on the same
    record and returns a :class:`~sysid.validation.comparison.CompareSet`; ``compare(model,
    data)`` (or ``compare(data, model)``) one model, a :class:`CompareResult`. Frequency-
    response data (an :class:`sysid.FRD`) compare the models' responses on its lines (fit of
    the complex response per output/input pair): a
    :class:`~sysid.validation.compare_frd.FRDCompareSet`. A model that
    diverges on the data (an unstable model on a long record) is reported with a fit of
    ``-inf`` and ``diverged`` set, never raised, and a :class:`~sysid.StabilityWarning`
    (so is a simulated model with an unstable pole whose fitted initial state kept it
    bounded on the record).

    Parameters
    ----------
    *args
        ``data, model, ...`` or ``model, data[, horizon]``. ``data`` is an
        :class:`~sysid.IOData` (validation data, ideally not used for estimation) or a pair
        ``(u, y)``; each model any :class:`sysid.Model` (state-space, continuous,
        polynomial, a :class:`~sysid.models.trended.TrendedModel` for raw data, your own).
    horizon : int or None
        ``None`` (default) simulates from the inputs alone; ``k`` predicts ``k`` steps
        ahead with the Kalman predictor (needs ``model.K``; without it the predictor never
        looks at the measured outputs and prediction equals simulation).
    x0 : "estimate", "zero", "model" or array
        Initial state: least squares on each experiment (default), zero, the model's own, or
        given (one array, or a list with one per experiment). A nonlinear state-space
        model's is fitted by Gauss-Newton on the record (never worse than zero); a NARX
        model's simulation starts from the measured first ``max_lag`` outputs
        (``"estimate"``), from zero outputs, or from the outputs given. Those first
        ``max_lag`` samples (its initial condition, in prediction too) stay in ``yhat`` but
        not in the fit numbers, which score the samples the model predicts
        (:attr:`CompareResult.start`).

    Returns
    -------
    CompareResult or CompareSet

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]])
    >>> u = rng.standard_normal(200)
    >>> y = m.simulate(u, x0=[5.0]) + 0.1 * rng.standard_normal((200, 1))
    >>> r = sysid.compare(m, (u, y))
    >>> bool(r.fit[0, 0] > 90)
    True
    >>> bool(sysid.compare(m, (u, y), x0="zero").fit[0, 0] < r.fit[0, 0])
    True
    >>> bad = sysid.StateSpaceModel([[1.5]], [[1.0]], [[1.0]])     # diverges
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as said:
    ...     warnings.simplefilter("always")
    ...     both = sysid.compare((u, y), m, bad)
    >>> both.fit[:, 0, 0].round(1).tolist(), both.diverged.tolist()
    ([95.5, -inf], [False, True])
    >>> print(said[0].message)          # doctest: +ELLIPSIS
    model 2: StateSpaceModel (order 1) diverged: its output grew without bound (fit -inf, ...
    """
    from .comparison import warn_diverging

    out = compare_quiet(*args, horizon=horizon, x0=x0)
    if not hasattr(out, "responses"):  # a frequency response does not diverge
        warn_diverging(getattr(out, "results", [out]))
    return out


def compare_quiet(*args: Any, horizon: int | None = None, x0: X0 = "estimate") -> Any:
    """:func:`compare` without its :class:`~sysid.StabilityWarning`: for the estimators and
    reports that compare candidate models and show the divergence in their own tables."""
    from .comparison import split_arguments

    data, models, horizon = split_arguments(args, horizon)
    if not isinstance(data, (IOData, tuple)):  # an FRD: the responses on its lines
        from .compare_frd import compare_frd

        return compare_frd(data, models, horizon, x0)
    results = [compare_one(m, data, horizon, x0) for m in models]
    if isinstance(data, IOData):  # the record's own clock, for plots
        for r in results:
            r.t0 = [float(t[0]) if t.size else 0.0 for t in data.times]
    if len(models) > 1:
        from .comparison import CompareSet

        return CompareSet(results)
    return results[0]


def compare_one(model: Any, data: Any, horizon: int | None, x0: X0) -> CompareResult:
    """:func:`compare` for one model."""
    if isinstance(model, TrendedModel):  # compare the inner model on the detrended record
        if not isinstance(data, IOData):
            data = IOData(u=data[0], y=data[1], dt=model.dt)
        inner = compare_one(model.model, model.trend.apply(data), horizon, x0)
        raw = data.experiments
        # the record's sample time: a continuous inner model has none (dt = 0 put every
        # sample of a linear trend at its start, and error_spectrum divided by it)
        yh = [model.trend.restore_outputs(b, inner.dt, model.trend.start_of(t[0]))
              for b, t in zip(inner.yhat, data.times)]
        out = CompareResult(model, inner.horizon, [u for u, _ in raw], [y for _, y in raw],
                            yh, inner.x0, inner.start)
        out.dt = inner.dt
        return out
    if _operating_point(model):  # the model of the deviations, its offsets added back
        raw = data if isinstance(data, IOData) else IOData(u=data[0], y=data[1], dt=model.dt)
        inner = compare_one(model.statespace, model.remove_offsets(raw), horizon, x0)
        out = CompareResult(model, inner.horizon, [u for u, _ in raw.experiments],
                            [y for _, y in raw.experiments],
                            [yh + model.y_offset for yh in inner.yhat], inner.x0,
                            inner.start)
        out.dt = inner.dt
        return out
    model, recs = _records(model, data)
    h = _horizon(horizon)
    runner = _simulator(model, x0, h, recs[0][0] if recs else None)
    start = given_start(runner)
    require_scored(recs, start, model)
    us, ys, yh, x0s = [], [], [], []
    for i, (u, y) in enumerate(recs):
        x = _x0_for(runner, x0, u, y, h, i, len(recs))
        if isinstance(x0, str) and x0 == "estimate" and x is not None and y.size <= 2 * x.size:
            import warnings

            from .._checks import user_stacklevel

            warnings.warn(f"the record{f' (experiment {i})' if len(recs) > 1 else ''} has "
                          f"{y.shape[0]} samples of {y.shape[1]} output(s) for {x.size} "
                          "fitted initial values: its fit says little about the model "
                          "(the initial state takes up the record); compare on a longer "
                          "record, or with x0='zero'", SysidWarning,
                          stacklevel=user_stacklevel())
        us.append(u)
        ys.append(y)
        yh.append(_run(runner, u, y, h, x))
        x0s.append(x)
    require_outputs_vary([y[start:] for _, y in recs], getattr(model, "output_names", None))
    return CompareResult(model, h, us, ys, yh, x0s, start)


def require_outputs_vary(ys: list[np.ndarray], names: Any = None) -> None:
    """Refuse records with an output that is constant in an experiment: a fit against it
    (NRMSE against the mean) is undefined (:func:`compare`, and ``identify``'s validation
    data before its search)."""
    for i, y in enumerate(ys):
        flat = np.ptp(y, axis=0) == 0
        if flat.any():
            names = names or [f"y{j}" for j in range(y.shape[1])]
            which = ", ".join(str(names[j]) for j in np.flatnonzero(flat))
            raise DataError(
                f"output {which} is constant"
                + (f" in experiment {i}" if len(ys) > 1 else "")
                + ": the fit (NRMSE against the mean) is undefined for a constant signal; "
                "compare on a record where the output varies, or look at the residuals"
            )


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
