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

from typing import Any

from .._threads import one_blas_thread
from ..data.iodata import IOData
from ..errors import SysidWarning
from ..models.trended import TrendedModel
from .compare_result import CompareResult
from .fit import diverged, fit_metrics, require_outputs_vary
from .runner import (
    X0,
    _horizon,
    _operating_point,
    _records,
    _run,
    _simulator,
    _x0_for,
    estimate_x0,
    given_start,
    require_scored,
)

__all__ = [
    "CompareResult",
    "compare",
    "fit_metrics",
    "estimate_x0",
    # the parts of compare in their own modules, importable from here as before
    "diverged",
    "given_start",
    "require_outputs_vary",
    "X0",
]


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
        _warn_flat(getattr(out, "results", [out]))
    return out


def _warn_flat(results: list[CompareResult]) -> None:
    """One :class:`~sysid.errors.SysidWarning` with the notes of the flat outputs and of the
    level errors whose fit reads below zero (there the number misleads; above it the note in
    the summary is enough)."""
    said = []
    for r in results:
        # the notes list the flat outputs' first, then those of the level errors
        for (e, j), note in zip(r.flat + r.levels, r.notes):
            if not r.diverged[e] and r.fit[e, j] < 0 and note not in said:
                said.append(note)
    if said:
        import warnings

        from .._checks import user_stacklevel

        warnings.warn("; ".join(said[:3]) + (f" (and {len(said) - 3} more)" if len(said) > 3
                                             else ""), SysidWarning, stacklevel=user_stacklevel())


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
        return _flat_as(out, inner)
    if _operating_point(model):  # the model of the deviations, its offsets added back
        raw = data if isinstance(data, IOData) else IOData(u=data[0], y=data[1], dt=model.dt)
        inner = compare_one(model.statespace, model.remove_offsets(raw), horizon, x0)
        out = CompareResult(model, inner.horizon, [u for u, _ in raw.experiments],
                            [y for _, y in raw.experiments],
                            [yh + model.y_offset for yh in inner.yhat], inner.x0,
                            inner.start)
        out.dt = inner.dt
        return _flat_as(out, inner)
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


def _flat_as(out: CompareResult, inner: CompareResult) -> CompareResult:
    """``out`` (a comparison on the raw record) with the flat outputs of ``inner`` (the same
    on the model's deviations from its operating point or trend): an output's level is
    measured from where the model puts it, not from zero."""
    out.flat, out.notes, out._why, out.levels = [], [], [], []
    for (e, j), why in zip(inner.flat, inner._why):
        out.add_flat(e, j, why)
    out.add_levels()
    return out
