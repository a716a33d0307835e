"""Polynomial nonlinear state-space models (PNLSS): the model and its estimator.

.. code-block:: text

    x(t+1) = A x(t) + B u(t) + E zeta(x(t), u(t))
      y(t) = C x(t) + D u(t) + F eta(x(t), u(t))

in scaled channels (offsets removed, unit standard deviations; the model converts), with
``zeta``, ``eta`` all monomials of the chosen total degrees in the states and/or inputs
(Paduart, Lauwers, Swevers, Smolders, Schoukens & Pintelon, Automatica 46, 2010). The fit
starts from a linear model (the BLA's for periodic data) and minimises the simulation error
with the shared optimiser; the Jacobian comes from forward sensitivities in the Rust core.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_int, as_nonnegative, as_seed
from .._display import modulus
from .._progress import iteration_callback, iteration_printer
from .._threads import one_blas_thread
from ..data.iodata import IOData, require_record
from ..data.levels import input_levels
from ..errors import DataError, SysidWarning
from ..models.protocol import ModelMixin
from ..models.serialize import register_model
from ..models.statespace import StateSpaceModel
from .common import (
    LinearPart,
    Scaling,
    balanced,
    channels,
    check_order,
    check_parameters,
    clamp_box,
    envelope,
    fit_summary,
    held_stable,
    linear_start,
    linear_states,
    scaled_data,
    settle_samples,
    signal,
)
from .freqweight import averaged_periods, cost_weights, experiment_periods
from .memory import check_memory
from .monomials import TERMS, equation_terms, output_basis, warn_undetermined
from .selection import ValidationRecords, select_iterate, validation_records
from .startup import StartUp
from .startup import failing as startup_failing

__all__ = ["PNLSSModel", "pnlss"]


@register_model
class PNLSSModel(LinearPart, ModelMixin):
    """A polynomial nonlinear state-space model (see the module documentation).

    Parameters
    ----------
    A, B, C, D, E, F : array_like
        Coefficients in scaled channels (``E``: ``nstates x len(zeta)``, ``F``:
        ``noutputs x len(eta)``).
    zeta, eta : list of list of int
        Monomials as index lists into ``z = [x; u]`` (``[0, 0, 2]`` is ``x0^2 u0`` for two
        states; ``[]`` is the constant 1).
    scaling : dict
        ``u_offset, u_scale, y_offset, y_scale`` of the channels.
    clamp : tuple of array_like, optional
        ``(lo, hi)``: the box (scaled coordinates, states then inputs) the monomials'
        arguments are clamped to, so that outside the region the model was fitted on the
        nonlinear terms stay at their boundary values (``None``: plain polynomials).
    dt : float
    input_names, output_names : list of str, optional
    info : dict, optional

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.PNLSSModel([[0.5]], [[1.0]], [[1.0]], [[0.0]], [[-0.1]], np.zeros((1, 0)),
    ...                      zeta=[[0, 0]], eta=[])
    >>> m.simulate([1.0, 1.0, 0.0])[:, 0]
    array([0. , 1. , 1.4])
    >>> m
    PNLSSModel(nstates=1, ninputs=1, noutputs=1, 1 state monomial(s), 0 output monomial(s), dt=1)
    """

    def __init__(self, A: Any, B: Any, C: Any, D: Any, E: Any, F: Any, *,
                 zeta: Any, eta: Any, scaling: dict[str, Any] | None = None,
                 clamp: Any = None, dt: float = 1.0,
                 input_names: Any = None, output_names: Any = None,
                 info: dict[str, Any] | None = None) -> None:
        self.A, self.B = np.atleast_2d(np.asarray(A, float)), np.atleast_2d(np.asarray(B, float))
        self.C, self.D = np.atleast_2d(np.asarray(C, float)), np.atleast_2d(np.asarray(D, float))
        self.zeta = [[int(v) for v in t] for t in zeta]
        self.eta = [[int(v) for v in t] for t in eta]
        n, m, l_ = self.A.shape[0], self.B.shape[1], self.C.shape[0]
        self.E = np.asarray(E, float).reshape(n, len(self.zeta))
        self.F = np.asarray(F, float).reshape(l_, len(self.eta))
        if self.A.shape != (n, n) or self.B.shape[0] != n or self.C.shape[1] != n \
                or self.D.shape != (l_, m):
            raise DataError(f"A {self.A.shape}, B {self.B.shape}, C {self.C.shape} and D "
                            f"{self.D.shape} do not fit together")
        self.scaling, self.input_names, self.output_names = channels(
            scaling, m, l_, input_names, output_names)
        self.clamp = None if clamp is None else clamp_box(clamp, n + m, " (states then inputs)")
        self.dt = float(dt)
        self.info = dict(info or {"method": "pnlss"})

    nstates = property(lambda self: self.A.shape[0])
    ninputs = property(lambda self: self.B.shape[1])
    noutputs = property(lambda self: self.C.shape[0])

    @property
    def n_parameters(self) -> int:
        """Number of coefficients (the state basis makes ``nstates^2`` of them redundant)."""
        return int(self.theta.size - self.nstates ** 2)

    @property
    def theta(self) -> np.ndarray:
        """All coefficients ``[A, B, C, D, E, F]`` row-major (the core's parameter vector)."""
        return np.concatenate([a.ravel() for a in (self.A, self.B, self.C, self.D, self.E,
                                                   self.F)])

    def _struct(self) -> dict[str, Any]:
        rng = None if self.clamp is None else (list(self.clamp[0]), list(self.clamp[1]))
        return {"nx": self.nstates, "nu": self.ninputs, "ny": self.noutputs, "zeta": self.zeta,
                "eta": self.eta, "range": rng}

    def _u(self, u: Any) -> np.ndarray:
        return self.scaling.u(signal(u, self.ninputs, "u"))

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        """Output ``(n_samples, noutputs)`` from ``x0`` (scaled-state coordinates; zero by
        default). Raises :class:`~sysid.NumericalError` when the state diverges."""
        us = self._u(u)
        x = None if x0 is None else [float(v) for v in np.ravel(x0)]
        y, _ = _sysid.pnlss_simulate(self._struct(), self.theta, us, x)
        return self.scaling.y_back(np.asarray(y).reshape(-1, self.noutputs))

    def states(self, u: Any, x0: Any = None) -> np.ndarray:
        """Simulated states ``(n_samples, nstates)`` (scaled coordinates)."""
        x = None if x0 is None else [float(v) for v in np.ravel(x0)]
        _, xs = _sysid.pnlss_simulate(self._struct(), self.theta, self._u(u), x)
        return np.asarray(xs).reshape(-1, self.nstates)

    def linear(self) -> StateSpaceModel:
        """The linear part ``(A, B, C, D)`` in engineering units."""
        return self.scaling.to_units(self.A, self.B, self.C, self.D, self)

    def to_dict(self) -> dict[str, Any]:
        return {"A": self.A, "B": self.B, "C": self.C, "D": self.D, "E": self.E, "F": self.F,
                "zeta": self.zeta, "eta": self.eta, "scaling": self.scaling.to_dict(),
                "clamp": None if self.clamp is None else [self.clamp[0], self.clamp[1]],
                "dt": self.dt, "input_names": self.input_names,
                "output_names": self.output_names, "info": self.info}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> PNLSSModel:
        return cls(d["A"], d["B"], d["C"], d["D"], d["E"], d["F"], zeta=d["zeta"],
                   eta=d["eta"], scaling=d["scaling"], clamp=d.get("clamp"), dt=d["dt"],
                   input_names=d["input_names"], output_names=d["output_names"],
                   info=d.get("info"))

    def summary(self) -> str:
        return fit_summary(self)

    def __repr__(self) -> str:
        return (f"PNLSSModel(nstates={self.nstates}, ninputs={self.ninputs}, "
                f"noutputs={self.noutputs}, {len(self.zeta)} state monomial(s), "
                f"{len(self.eta)} output monomial(s), dt={self.dt:g})")


def _degrees(degree: Any) -> list[int]:
    ds = [degree] if np.ndim(degree) == 0 else list(degree)
    try:  # int(2.5) == 2 would silently drop the fraction: a fraction is refused
        out = sorted({int(d) for d in ds})
        exact = all(int(d) == d for d in ds)
    except (TypeError, ValueError, OverflowError):
        exact = False
    if not exact:
        raise DataError(f"degree must be an integer or a list of integers, got {degree!r}")
    if not out:
        raise DataError("degree needs at least one value")
    if max(out) < 2:
        raise DataError(f"degree must be at least 2 (1 is the linear part), got {degree!r}")
    return list(range(2, out[0] + 1)) if np.ndim(degree) == 0 else [d for d in out if d >= 2]


@one_blas_thread
def pnlss(
    data: IOData | tuple[Any, Any],
    order: int,
    *,
    degree: Any = "auto",
    terms: str = "full",
    output_terms: str | None = None,
    periods: Any = None,
    average: bool = False,
    init: Any = None,
    transient: int | None = None,
    extrapolation: str = "clamp",
    branches: int | None = None,
    weighting: str = "none",
    seed: int = 0,
    max_iter: int = 100,
    tol: float = 1e-8,
    significance: float = 1.0,
    validation: Any = None,
    progress: bool | None | Callable[..., Any] = None,
) -> PNLSSModel:
    """Polynomial nonlinear state-space model fitted on the simulation error.

    Parameters
    ----------
    data : IOData or (u, y)
        Estimation record(s).
    order : int
        Number of states.
    degree : "auto", int or list of int
        Monomial degrees: an integer ``d`` means all degrees ``2..d``, a list exactly those
        (``[3]``: cubic terms only). ``"auto"`` (default): degrees 2, or 2-3 where blocks of
        the estimation record held out of the fit insist on the cubic terms by their
        simulation fit (:mod:`sysid.nlss.degree`: cubic terms that fit the record can run away
        on data in other ranges; degrees 2-3 are not tried where the record gives fewer than
        ten residuals per parameter); it costs two fits per block (five blocks on most
        records) and ``info["degree_choice"]`` holds the table and the reason. Give the
        degree to fit once.
    terms : {"full", "states", "inputs", "outputs"}
        Variables of the state-equation monomials ``zeta``: states and inputs, states only,
        inputs only, or ``"outputs"``: the inputs and the ``noutputs`` states that the
        linear start's outputs span (the start is put in the state basis whose first states
        are the rows of ``C x``), so that a model of many states keeps few monomials: with
        10 states, 3 outputs, 1 input and degrees 2-3, 30 monomials instead of 352 (a state
        nonlinearity seen through the measured outputs; on the F-16 records it validated at
        0.108 against 0.202 for the input monomials, ``benches/results/nonlinear.md``).
    output_terms : {"full", "states", "inputs", "outputs", "none"}, optional
        Variables of the output-equation monomials ``eta`` (default: as ``terms``);
        ``"none"`` keeps the output equation linear (fewer parameters).
    periods : int or list of int, optional
        Periods in each experiment (one number for all, or one per experiment), for periodic
        excitation: the linear start is then the BLA's parametric model
        (:func:`sysid.bla_model`; with one number for equal-length experiments) and the
        first period of each experiment is left out of the cost as the transient.
    average : bool
        With ``periods``: fit on each experiment's average over its periods after the first
        (noise down by the square root of their number, the record as many times shorter),
        simulated over two averaged periods with the first as the transient (the steady
        state of a periodic input).
    init : StateSpaceModel, optional
        Linear start of ``order`` states (engineering units). Default: the BLA's model for
        ``periods`` (above), else the model ``sysid.ssest(data, order, focus="simulation")``
        gives on the scaled channels, at its own iteration cap (a start capped at 30
        iterations validated at 0.1095 on the F-16 level 2 against 0.1015 from the
        converged one, ``benches/results/nonlinear.md``).
    transient : int, optional
        Leading samples of each experiment left out of the cost (default: one period for
        periodic data, else the settling time of the linear start, at most a quarter).
    extrapolation : {"clamp", "polynomial"}
        ``"clamp"`` (default) evaluates the monomials at ``[x; u]`` clamped to a box: during
        the fit the range of the linear start's states and of the inputs, widened by half
        its span on each side (a bounded simulation: the polynomial cannot blow the state
        up), and in the returned model the range the fitted model's states and the inputs
        cover on the estimation data, widened by a tenth of its span (inside the fit's box,
        so the fit's simulation is unchanged). Beyond it the nonlinear terms keep their
        boundary values instead of growing as powers: records that leave the estimation
        range stay bounded, the linear part held stable for that (a free search that ends
        with an unstable ``A`` is continued from its latest stable iterate with ``A`` kept
        stable; ``info["fit"]["held_stable"]``). ``"polynomial"``: plain monomials
        everywhere.
    branches : int, optional
        Fit the decoupled variant instead (:class:`~sysid.DecoupledPNLSSModel`): the state
        equation's polynomial is ``W g(V [x; u])``, ``branches`` univariate polynomials of
        the chosen degrees of linear forms of the states and inputs (``terms`` and
        ``output_terms`` do not apply; the output equation is linear plus a constant).
        Far fewer parameters than all monomials when there are many states.
    weighting : {"none", "bla"}
        ``"none"`` (default): the time-domain simulation error of every sample after the
        transient. ``"bla"``: with ``periods``, the classic frequency-domain PNLSS cost: the
        simulation error of the steady state, averaged over the periods after the transient,
        on the mean and the excited DFT lines, each weighted by the inverse noise variance of
        the measured output's averaged spectrum (estimated over the periods; see
        :mod:`sysid.nlss.freqweight`); needs at least two periods after a transient of whole
        periods in every experiment and ``average=False``; applies to the coupled and the
        decoupled (``branches=``) model alike. It is not the default: on the F-16 records the
        coupled fit validated worse with it than with the time-domain cost
        (``benches/results/nonlinear.md``).
    seed : int
        Seeds the decoupled variant's initial branch directions.
    max_iter, tol : int, float
        Iterations and the relative cost/step tolerance of the search.
    significance : float
        The search (time-domain cost) steps only along directions the data support: in the
        eigenbasis of its scaled Gauss-Newton matrix, a direction whose own predicted
        decrease of the cost is below ``significance`` residual variances is left out of
        the step (``1``, the default: the Akaike criterion's price of one parameter; ``0``:
        every direction, the plain Levenberg-Marquardt step). Not with ``weighting="bla"``.
        On the F-16 records the decoupled fit validated at 0.0990 / 0.1038 / 0.0928 with it
        (seeds 0-2) against 0.1019 / 0.1091 / 7.10 without (``benches/results/nonlinear.md``).
    validation : float, IOData or (u, y), optional
        Choose the returned model on validation data, as the PNLSS literature does: every
        iterate of the search (the linear start first) simulates the validation data from
        rest and the one with the lowest mean squared error of the scaled outputs is
        returned (never one that validates worse than the start; the search itself is
        unchanged). A fraction in ``(0, 0.9]``: that share of each experiment's end is
        held out of the fit (each experiment simulated whole, its end scored; not with
        ``periods``); records: each scored after ``transient`` samples (default: the
        linear start's settling time, at most a quarter). ``info["fit"]["validation"]``
        holds every iterate's error, the one returned and the first sample scored in each
        record. Default: the search's last iterate (see Warns).
    progress : bool or callable, optional
        The shared progress machinery (a bar on a terminal; a callable receives
        ``(iteration, cost, step, gradient, damping)`` and may return ``False`` to stop).

    Returns
    -------
    PNLSSModel or DecoupledPNLSSModel
        ``info["fit"]``: iterations (those of the path returned, one per entry of
        ``cost`` after the first; ``iterations_all_trials`` adds the decoupled fit's other
        random starts), costs, stop reason, parameters, transient, and
        ``"returned"`` when the model is an earlier iterate than the search's last (below,
        and ``validation``);
        ``info["memory"]``: the check that the model forgets its initial state
        (:mod:`sysid.nlss.memory`); ``info["startup"]``: the check that its start from
        rest over each transient stays within what the record explains
        (:mod:`sysid.nlss.startup`; not with ``average=True``).

    Warns
    -----
    StabilityWarning
        When the linear part is unstable, or when the model, simulated from rest at the
        middle of a training experiment, does not return to its simulation of the whole
        experiment (a second stable equilibrium or orbit: its simulation of other data
        depends on where it starts), or when, simulated from rest, it misses a training
        experiment's transient by far more than a start from rest explains. When the
        search's last model fails either check but an earlier iterate passes both, the
        latest such iterate is returned instead, with this warning (its iteration and cost
        in ``info["fit"]["returned"]``).
    IterationLimitWarning
        When the search stopped at ``max_iter``.
    ExcitationWarning
        When an input takes fewer levels than a monomial's power of it (a step test or a
        binary PRBS: two): such monomials equal combinations of others on the record and are
        left out (:mod:`sysid.nlss.monomials`; ``info["undetermined_monomials"]``).

    Raises
    ------
    DataError
        Among others, when the model has at least as many parameters as the record gives
        residuals after the transient (checked before the search is sized).

    Examples
    --------
    A Wiener-type system (first-order filter, then a cubic output map), four random-phase
    multisines of two periods:

    >>> import numpy as np, sysid
    >>> truth = sysid.PNLSSModel([[0.8]], [[0.5]], [[1.0]], [[0.0]], np.zeros((1, 0)),
    ...                          [[0.3]], zeta=[], eta=[[0, 0, 0]])
    >>> u = sysid.multisine(200, band=(0, 0.5), phases="random", seed=1, periods=2)
    >>> d = sysid.IOData(u, truth.simulate(u), 1.0)
    >>> m = sysid.pnlss(d, 1, degree=[3], terms="states", output_terms="states",
    ...                 periods=2, progress=False)
    >>> bool(sysid.compare(m, d, x0="zero").fit[0, 0] > 99.9)
    True
    """
    data = require_record(data, "pnlss")
    n = check_order(order)
    if isinstance(degree, str) and degree != "auto":
        raise DataError(f"degree must be 'auto', an integer or a list of integers, got "
                        f"{degree!r}")
    degs = [] if isinstance(degree, str) else _degrees(degree)
    # before the Rust core, which takes them unsigned (OverflowError on a negative)
    max_iter, tol, seed = as_int(max_iter, "max_iter", 0), as_nonnegative(tol, "tol"), \
        as_seed(seed)
    significance = as_nonnegative(significance, "significance")
    if transient is not None:
        transient = as_int(transient, "transient", 0)
    if branches is not None:
        branches = as_int(branches, "branches", 1)
    if data.n_inputs == 0:
        raise DataError("pnlss needs inputs; for output-only records use sysid.ar/arma")
    val_recs = None
    if validation is not None:
        data, val_recs = validation_records(data, validation, periods is not None)
        short = [u.shape[0] for u, _, s in val_recs if s is None and transient is not None
                 and u.shape[0] <= transient]
        if short:  # said before the search, not after it
            raise DataError(f"a validation record of {short[0]} samples has none left after "
                            f"transient={transient}; give longer validation records or a "
                            f"shorter transient")
    sc = Scaling.of(data)
    sd = scaled_data(data, sc)
    pers = experiment_periods(periods, len(sd.experiments))
    one = periods if pers is not None and np.ndim(periods) == 0 else None
    if terms not in TERMS or (output_terms is not None and output_terms not in TERMS
                                 + ("none",)):
        raise DataError(f"terms must be one of {', '.join(TERMS)} and output_terms one of "
                        f"those or 'none', got {terms!r} and {output_terms!r}")
    if extrapolation not in ("clamp", "polynomial"):
        raise DataError(f"extrapolation must be 'clamp' or 'polynomial', got {extrapolation!r}")
    if weighting not in ("bla", "none"):
        raise DataError(f"weighting must be 'none' or 'bla', got {weighting!r}")
    lin = linear_start(data, sd, sc, n, init, one)
    if "outputs" in (terms, output_terms):
        lin = output_basis(lin)
    lin = balanced(lin, [u for u, _ in sd.experiments])
    if np.max(np.abs(lin.poles())) >= 1:
        raise DataError("the linear start is unstable: its simulation cannot seed a "
                        "simulation-error fit; give a stable init= or another order")
    choice = None  # after the record's own start: what it refuses is said of the record
    if isinstance(degree, str):
        choice = _auto_degree(data, n, dict(terms=terms, output_terms=output_terms, init=init,
                                            extrapolation=extrapolation, branches=branches,
                                            seed=seed, max_iter=max_iter, tol=tol,
                                            significance=significance), progress)
        degs = _degrees(choice.degree)
    us = [u for u, _ in sd.experiments]
    recs = []
    for k, (u, y) in enumerate(sd.experiments):
        N = u.shape[0]
        skip = transient if transient is not None else (
            N // pers[k] if pers and pers[k] > 1 else settle_samples(lin, N))
        recs.append((u, y, int(skip)))
    weights = cost_weights(weighting, sd, pers, recs, average)
    # the start from rest over each transient, judged on the records as measured
    startup = None if average else StartUp.of(lin, recs, data)
    if average:
        recs = averaged_periods(sd, pers)
        us = [r[0] for r in recs]
    cb, close = iteration_callback(progress, "pnlss", max_iter,
                                   iteration_printer("pnlss", "sum of squares"))
    common = {"scaling": sc.to_dict(), "dt": data.dt, "input_names": data.input_names,
              "output_names": data.output_names}
    info: dict[str, Any] = {"degree": degs, "extrapolation": extrapolation,
                            "weighting": "none" if weights is None else "bla",
                            "significance": significance if weights is None else 0.0,
                            "start": lin.info.get("method") if lin.info else "linear"}
    if choice is not None:
        info["degree_choice"] = choice.as_dict()
    try:
        if branches is not None:
            from .decoupled import DecoupledPNLSSModel, fit_decoupled

            kw_of, res = fit_decoupled(lin, us, recs, degs, branches, extrapolation == "clamp",
                                       max_iter, tol, cb if cb is not None else _tick, seed,
                                       weights, significance)
            info.update(method="pnlss (decoupled)", branches=int(branches))
            cls: Any = DecoupledPNLSSModel
        else:
            kw_of, res = _fit_coupled(lin, us, recs, terms, output_terms, degs, extrapolation,
                                      max_iter, tol, cb if cb is not None else _tick, weights,
                                      significance)
            info.update(method="pnlss", terms=terms,
                        output_terms=terms if output_terms is None else output_terms)
            cls = PNLSSModel
    finally:
        close()
    info["fit"] = _report(res, recs)
    if "left_out" in res:
        info["undetermined_monomials"] = lo = res["left_out"]
        warn_undetermined(data.input_names, lo["levels"], degs, lo["monomials"], lo["kept"])
    _said_held(res)
    build = lambda th: cls(**kw_of(th), **common,  # noqa: E731
                           info={**info, "fit": dict(info["fit"])})
    if val_recs is not None:
        val = ValidationRecords(val_recs, sc.y_scale, lambda N: (
            transient if transient is not None else settle_samples(lin, N)))
        return _validated(build, res, data, val, max_iter, startup)
    _warn_short(res, max_iter)
    return _forgetting(build, res, data, startup)


def _validated(build: Callable[[np.ndarray], Any], res: dict[str, Any], data: IOData,
               val: ValidationRecords, max_iter: int, startup: StartUp | None) -> Any:
    """The iterate that simulates the validation records best
    (:func:`~sysid.nlss.selection.select_iterate`), checked for fading memory and its start
    from rest (said, not replaced: the choice is the validation data's); the cap
    warning only when that is the search's last iterate (an earlier one was chosen on
    data the later ones simulate worse)."""
    k, model, errors = select_iterate(build, res["iterates"], val)
    last = len(errors) - 1
    hist = res["history"]
    model.info["fit"]["validation"] = {"errors": [float(e) for e in errors],
                                       "returned": int(k),
                                       "scored_from": [r[2] for r in val.records]}
    if k < last:
        model.info["fit"]["returned"] = {
            "iteration": int(k), "cost": float(hist[k]),
            "last_cost": float(hist[-1]), "reason": "lowest validation error"}
    else:
        _warn_short(res, max_iter)
    return check_memory(_warn_unstable(_startup_said(startup, model)), data, "pnlss")


def _forgetting(build: Callable[[np.ndarray], Any], res: dict[str, Any], data: IOData,
                startup: StartUp | None = None) -> Any:
    """The model of the search's result, checked for fading memory
    (:func:`~sysid.nlss.memory.check_memory`) and for its start from rest over the transients
    (:mod:`sysid.nlss.startup`); when it fails either, the model of the latest iterate that
    passes both (:func:`~sysid.nlss.memory.latest_forgetting`), with a
    :class:`~sysid.StabilityWarning` that says which and at what cost. A search can walk into
    such a model late, after iterates that passed; an earlier iterate is a better model to
    return than the last one with a warning (pH, the bench's split: the decoupled fit tested
    at 8.34 from its last iterate, at 1.02 from its iteration 3;
    ``benches/results/nonlinear.md``)."""
    import warnings

    from .._checks import user_stacklevel
    from ..errors import StabilityWarning
    from .memory import differences, failing, latest_forgetting

    model = build(np.asarray(res["theta"]))
    measured = differences(model, data)
    its = res["iterates"]
    failed = failing(measured[0])
    ratios = [] if startup is None else startup.excess(model)
    wild = startup_failing(ratios)
    found = None if not (failed or wild) or len(its) < 2 else \
        latest_forgetting(build, its[:-1], data, failed,
                          None if startup is None else startup.passes)
    if found is None:
        return check_memory(_warn_unstable(_startup_said(startup, model, ratios)), data,
                            "pnlss", measured)
    k, earlier, kept = found
    hist = res["history"]
    returned: dict[str, Any] = {"iteration": int(k), "cost": float(hist[k]),
                                "last_cost": float(hist[-1])}
    if startup is not None:
        returned["last_startup_excess"] = ratios
    if failed:
        worst = max(d for d in measured[0] if d is not None)
        returned["last_difference"] = float(worst)
        what = ("diverges" if not np.isfinite(worst) else
                f"stays {worst:.3g} output standard deviations away from its simulation of "
                "the whole experiment")
        why = (f"does not forget its initial state (simulated from rest at the middle of a "
               f"training experiment it {what})")
        passing, avoid = "does", "the second behaviour"
    else:
        why = f"does not start from rest as its data do ({startup.describe(model, ratios)})"
        passing, avoid = "starts within what the start from rest explains", "the swing"
    earlier.info["fit"]["returned"] = returned
    warnings.warn(
        f"pnlss: the search's last model (iteration {len(its) - 1}, cost {hist[-1]:.6g}) "
        f"{why}: returned the model of iteration {k} (cost {hist[k]:.6g}), the latest found "
        f"that {passing}; info['fit']['returned']. Check it on validation data "
        f"(sysid.compare); fewer iterations, a lower degree or fewer terms avoid {avoid}",
        StabilityWarning, stacklevel=user_stacklevel())
    return check_memory(_warn_unstable(_startup_said(startup, earlier)), data, "pnlss", kept)


def _startup_said(startup: StartUp | None, model: Any,
                  ratios: list[float | None] | None = None) -> Any:
    """``model`` with its start-up check recorded (``info["startup"]``) and, when it swings
    away from its data over a transient, a :class:`~sysid.StabilityWarning` saying so."""
    import warnings

    from .._checks import user_stacklevel
    from ..errors import StabilityWarning

    if startup is None:
        return model
    ratios = startup.excess(model) if ratios is None else ratios
    if startup_failing(ratios):
        warnings.warn(f"pnlss returned a model that does not start from rest as its data do: "
                      f"{startup.describe(model, ratios)}. Its simulations from rest "
                      f"(validation data, sysid.compare) start with that error; give them a "
                      f"warm-up or an initial state, or try fewer iterations, a lower degree "
                      f"or fewer terms", StabilityWarning, stacklevel=user_stacklevel())
    return startup.note(model, ratios)


def _auto_degree(data: IOData, n: int, kw: dict[str, Any], progress: Any) -> Any:
    """:func:`sysid.nlss.degree.choose_degree` with ``pnlss``'s settings ``kw`` on each
    fold (time-domain cost, no periods: the blocks cut them), the folds' linear starts scored
    beside them; warns when those insist over the chosen degree on the held-out blocks
    (:func:`~sysid.validation.crossval.insists`; how often that was right:
    :mod:`sysid.nlss.degree`)."""
    import functools
    import warnings

    from .._checks import user_stacklevel
    from ..validation.crossval import fold_count
    from .decoupled import n_parameters
    from .degree import CANDIDATES, caution, choose_degree, too_large

    def linear(part: IOData) -> PNLSSModel:
        """The part's linear start (as ``pnlss`` fits it), a model without monomials."""
        sc = Scaling.of(part)
        lin = linear_start(part, scaled_data(part, sc), sc, n, kw["init"], None)
        return PNLSSModel(lin.A, lin.B, lin.C, lin.D, np.zeros((n, 0)),
                          np.zeros((lin.noutputs, 0)), zeta=[], eta=[], scaling=sc.to_dict(),
                          dt=part.dt)

    def fit(part: IOData, k: int, start: PNLSSModel | None) -> Any:
        # from the part's linear start, fitted once for both degrees
        init = kw["init"] if start is None else start.linear()
        return pnlss(part, n, degree=k, progress=False, **{**kw, "init": init})

    @functools.cache
    def size(k: int) -> int:  # the parameters of degree k's model, as its fit counts them
        m_, l_, degs = data.n_inputs, data.n_outputs, _degrees(k)
        if kw["branches"] is not None:
            return n_parameters(n, m_, l_, kw["branches"], len(degs))
        zeta, eta, _ = equation_terms(n, m_, l_, kw["terms"], kw["output_terms"], degs,
                                      input_levels([u for u, _ in data.experiments]))
        return (n + l_) * (n + m_) + n * len(zeta) + l_ * len(eta)

    # a bar over the fold fits (a progress callable follows the final fit's iterations)
    total = fold_count(data) * (len(CANDIDATES) + 1 - len(too_large(data, size)))
    cb, close = iteration_callback(False if callable(progress) else progress,
                                   "pnlss degree choice", total, _fold_line, unit="fit",
                                   postfix=lambda i, f, *a: {"held-out fit": f"{f:.1f} %"})
    try:
        choice = choose_degree(data, fit, linear,
                               None if cb is None else (lambda i, f: cb(i, f, 0.0, 0.0, 0.0)),
                               size)
    finally:
        close()
    if (note := caution(choice)) is not None:
        warnings.warn(f"pnlss: {note}", SysidWarning, stacklevel=user_stacklevel())
    return choice


def _fold_line(i: int, fit: float, *_: Any) -> None:
    print(f"pnlss degree choice: fold fit {i}: held-out simulation fit {fit:.1f} %")


def _fit_coupled(lin: StateSpaceModel, us: list[np.ndarray], recs: list[Any], terms: str,
                 output_terms: str | None, degs: list[int], extrapolation: str, max_iter: int,
                 tol: float, cb: Any, weights: Any = None,
                 significance: float = 0.0) -> tuple[Callable[[np.ndarray], dict[str, Any]],
                                                     dict[str, Any]]:
    """The coupled fit from the linear start ``lin`` (scaled channels). Returns the model's
    keyword arguments (without scaling and names) as a function of the parameters (for the
    search's result or any of its ``iterates``) and the optimiser's report."""
    n, m_, l_ = lin.nstates, lin.ninputs, lin.noutputs
    fit_box = None if extrapolation == "polynomial" else envelope(linear_states(lin, us), us,
                                                                  0.5)
    rng = None if fit_box is None else (list(fit_box[0]), list(fit_box[1]))
    levels = input_levels(us)
    zeta, eta, left_out = equation_terms(n, m_, l_, terms, output_terms, degs, levels)
    theta0 = np.concatenate([lin.A.ravel(), lin.B.ravel(), lin.C.ravel(), lin.D.ravel(),
                             np.zeros(n * len(zeta) + l_ * len(eta))])
    struct = {"nx": n, "nu": m_, "ny": l_, "zeta": zeta, "eta": eta, "range": rng}
    check_parameters(theta0.size, recs, "the degree, the terms or the order")

    def search(st: dict[str, Any], th0: np.ndarray, it: int) -> dict[str, Any]:
        if weights is None:
            return _sysid.pnlss_estimate(st, recs, th0, max_iter=it, tol=tol, progress=cb,
                                         iterates=True, significance=significance)
        return _sysid.pnlss_estimate_weighted(st, recs, weights, th0, max_iter=it, tol=tol,
                                              progress=cb, iterates=True)

    res = search(struct, theta0, max_iter)
    res["iterates"] = np.vstack([theta0[None, :], np.asarray(res["iterates"])])
    if fit_box is not None and res["stop"] != "cancelled":  # clamped: an unstable A runs away
        res = held_stable(res, n, lambda th0, it: search({**struct, "stable": True}, th0, it),
                          max_iter, max(r[0].shape[0] for r in recs))
    if left_out:  # said by pnlss (an input of too few levels)
        res["left_out"] = {"levels": levels.tolist(), "monomials": left_out,
                           "kept": len(zeta) + len(eta) - 2}

    def kw_of(th: np.ndarray) -> dict[str, Any]:
        box = None
        if fit_box is not None:
            xs = [np.asarray(_sysid.pnlss_simulate(struct, list(th), u)[1]).reshape(-1, n)
                  for u in us]
            env = envelope(xs, us, 0.1)
            box = (np.maximum(env[0], fit_box[0]), np.minimum(env[1], fit_box[1]))
        o = np.cumsum([0, n * n, n * m_, l_ * n, l_ * m_, n * len(zeta), l_ * len(eta)])
        p = [th[o[i]:o[i + 1]] for i in range(6)]
        return {"A": p[0].reshape(n, n), "B": p[1].reshape(n, m_), "C": p[2].reshape(l_, n),
                "D": p[3].reshape(l_, m_), "E": p[4], "F": p[5], "zeta": zeta, "eta": eta,
                "clamp": box}

    return kw_of, res


def _report(res: dict[str, Any], recs: list[Any]) -> dict[str, Any]:
    return {"iterations": res["iterations"], "evaluations": res["evaluations"],
            # the decoupled fit's random starts, the ones not returned too
            "iterations_all_trials": res.get("iterations_all_trials", res["iterations"]),
            "evaluations_all_trials": res.get("evaluations_all_trials", res["evaluations"]),
            "cost": list(res["history"]), "stop": res["stop"],
            "remaining_decrease": float(res["remaining_decrease"]),
            "n_parameters": int(np.asarray(res["theta"]).size),
            "transient": [r[2] for r in recs],
            **({"held_stable": res["held_stable"]} if "held_stable" in res else {})}


def _said_held(res: dict[str, Any]) -> None:
    """A :class:`StabilityWarning` when the search held the linear part stable
    (:func:`~sysid.nlss.common.held_stable`): the free search's pole, its growth over the
    record, both costs and the option that returns the free model."""
    import warnings

    from .._checks import user_stacklevel
    from ..errors import StabilityWarning

    if "held_stable" not in res:
        return
    h, cost = res["held_stable"], res["history"][-1]
    warnings.warn(f"pnlss: the free search's linear part reached a pole of modulus "
                  f"{modulus(h['free_radius'])}, a mode that grows "
                  f"{h['free_growth']:.2g}-fold over the record, which the clamped "
                  f"monomials cannot hold once the state leaves the range they were fitted "
                  f"on; returned the search continued from iteration {h['from_iteration']} "
                  f"with the linear part held stable (cost {cost:.6g} against the free "
                  f"{h['free_cost']:.6g}; info['fit']['held_stable']). For a process that "
                  f"is itself unstable or bistable, extrapolation='polynomial' returns the "
                  f"free model", StabilityWarning, stacklevel=user_stacklevel())


def _warn_unstable(model: Any) -> Any:
    """Warn (:class:`StabilityWarning`) when the fitted model's linear part is unstable: its
    simulation stays bounded on the training record but can run away on other inputs (an
    evaporator record: a pole of modulus 1.08, divergence after 1046 validation samples)."""
    import warnings

    from .._checks import user_stacklevel
    from ..errors import StabilityWarning

    poles = model.linear().poles()
    rho = float(np.max(np.abs(poles))) if len(poles) else 0.0
    if rho >= 1.0:
        model.info["unstable_linear_part"] = rho
        warnings.warn(f"pnlss returned a model whose linear part is unstable (largest pole "
                      f"modulus {modulus(rho)}): it simulates the training record, but other "
                      f"inputs can make its state run away; try a lower order or degree, "
                      f"terms='states', or check it on validation data (sysid.compare)",
                      StabilityWarning, stacklevel=user_stacklevel())
    return model


def _warn_short(res: dict[str, Any], max_iter: int) -> None:
    """The search stopped short: at its cap ``max_iter`` (an :class:`IterationLimitWarning`,
    as every iterative estimator's, with how much the last iteration still gained) or
    cancelled (after the iterations of every start of a decoupled fit)."""
    import warnings

    from .._checks import user_stacklevel, warn_iteration_limit

    if res["stop"] == "maximum iterations":
        warn_iteration_limit("pnlss", int(max_iter), res["history"],
                             remaining=res["remaining_decrease"])
    elif res["stop"] == "cancelled":
        done = res.get("iterations_all_trials", res["iterations"])
        warnings.warn(f"pnlss was cancelled after {done} iterations; the model is "
                      "the best iterate", SysidWarning, stacklevel=user_stacklevel())


def _tick(*_: Any) -> None:
    """Runs Python once per iteration, so that Ctrl-C interrupts the search."""
