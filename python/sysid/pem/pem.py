"""Prediction-error refinement of state-space models: :func:`pem` (the one-call estimator
:func:`sysid.ssest` is in :mod:`sysid.pem.ssest`).

The model ``x(t+1) = A x + B u + K e``, ``y = C x + D u + e`` is refined by minimising the
prediction errors of its Kalman predictor (``focus="prediction"``) or its simulation errors
(``focus="simulation"``, ``K = 0``) over all experiments of the record, weighted by the inverse
of their covariance (re-estimated between iterations: the determinant criterion). The search is
the one Gauss-Newton / Levenberg-Marquardt optimiser of the Rust core (``sysid_core::optim``),
in data-driven local coordinates, with analytic sensitivities accumulated blockwise (memory
independent of the record length), and never leaves the set of stable predictors.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_int, as_nonnegative, check_magnitudes, record_stats, user_stacklevel
from .._progress import iteration_callback, iteration_printer
from .._threads import one_blas_thread
from ..data.iodata import IOData
from ..data.offsets import check_offsets
from ..errors import DataError, SysidWarning
from ..models.checks import check_start
from ..models.frd import FRD
from ..models.statespace import StateSpaceModel
from ..models.uncertainty import ParameterUncertainty
from ..polynomial.model import PolynomialModel
from ..subspace.feedthrough import check_feedthrough, choose_feedthrough
from ..validation.output_error import output_error
from .boundary import spectral_radius
from .diagnostics import lines_record_length, warn_refinement, warn_undetermined
from .records import _experiments
from .ssform import StateSpaceStructure
from .units import SearchUnits, search_units

__all__ = ["pem", "pem_loss", "PemUncertainty"]

_NOISE = ("estimate", "none", "fixed")


#: The interim name of :class:`sysid.ParameterUncertainty` (kept for compatibility).
PemUncertainty = ParameterUncertainty


def _stabilize(A: np.ndarray) -> np.ndarray:
    """Reflect eigenvalues outside the unit circle to ``0.99 / conj(z)`` (a real matrix;
    the core's ``reflect_unstable_poles``)."""
    return _sysid.reflect_unstable_poles(np.ascontiguousarray(A, dtype=float), 0.99)


def _x0_modes(x0: Any, count: int, n: int) -> list[Any]:
    if isinstance(x0, str):
        if x0 not in ("estimate", "zero"):
            raise DataError(f"x0 must be 'estimate', 'zero' or an array, got {x0!r}")
        return [x0] * count
    if x0 is None:
        return ["zero"] * count
    if isinstance(x0, (list, tuple)) and len(x0) == count and count > 1 and (
            isinstance(x0[0], str) or np.ndim(x0[0]) == 1):
        items = list(x0)
    else:
        items = [x0] * count
    out: list[Any] = []
    for it in items:
        if isinstance(it, str):
            out.extend(_x0_modes(it, 1, n))
        else:
            arr = np.asarray(it, dtype=float).ravel()
            if arr.size != n:
                raise DataError(f"x0 has {arr.size} entries but the model has {n} states")
            out.append(arr)
    return out


def _regularization(reg: Any, p_start: np.ndarray | None) -> tuple[float, Any, Any]:
    if reg is None:
        return 0.0, None, None
    if not isinstance(reg, dict) or "lambda" not in reg:
        raise DataError("regularization must be a dict with 'lambda' and optionally 'R' and "
                        "'nominal' ('zero', 'model' or an array)")
    lam = float(reg["lambda"])
    if not np.isfinite(lam) or lam < 0:
        raise DataError(f"regularization lambda must be finite and >= 0, got {lam}")
    R = reg.get("R")
    R = None if R is None else np.asarray(R, dtype=float)
    nom = reg.get("nominal", "zero")
    if isinstance(nom, str):
        if nom == "zero":
            nom = None
        elif nom == "model":
            nom = p_start
        else:
            raise DataError(f"regularization nominal must be 'zero', 'model' or an array, "
                            f"got {nom!r}")
    else:
        nom = np.asarray(nom, dtype=float).ravel()
    return lam, R, nom


@dataclass
class _Setup:
    """The start's matrices and the options as the core takes them (see :func:`_setup`)."""

    data: IOData
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    K: np.ndarray | None
    feedthrough: bool
    estimate_k: bool
    weighting: str
    modes: list[Any]
    focus: str
    enforce_stability: bool | None
    stabilized: str | None
    dropped_d: bool = False
    #: the channels' scales (:mod:`.units`): ``data``, ``B``, ``C``, ``D``, ``K`` are scaled
    units: SearchUnits | None = None
    #: the record in its own units
    record: IOData | None = None
    #: the state scaled by this factor (``B, K, x0`` times it, ``C`` divided; :func:`_balance`)
    xscale: float = 1.0
    stats: dict[int, Any] | None = None  #: the record's :func:`~sysid._checks.record_stats`

    def kwargs(self) -> dict[str, Any]:
        return {"focus": self.focus, "estimate_d": self.feedthrough,
                "estimate_k": self.estimate_k, "reweight": self.weighting == "noise",
                "enforce_stability": self.enforce_stability,
                "x0": [m if isinstance(m, str) else np.ascontiguousarray(m) for m in self.modes]}


def _setup(data: Any, model: StateSpaceModel, focus: str, feedthrough: Any, x0: Any,
           noise: str, weighting: str | None, enforce_stability: bool | None,
           balance: bool = True) -> _Setup:
    """Checks the arguments and prepares the start (``focus`` itself is parsed by the core);
    ``balance``: search on channels of unit scale (:mod:`.units`; else in the record's
    units, only the outputs scaled for ``weighting="output"``) in a state basis of balanced
    scale (:func:`_balance`)."""
    data = _experiments(data)
    stats = record_stats(data)
    check_magnitudes(data, "pem", stats)  # before the start is balanced on the record's scale
    if not isinstance(model, StateSpaceModel):
        raise DataError(f"model must be a sysid.StateSpaceModel, got {type(model).__name__}")
    if not isinstance(focus, str) or focus not in ("prediction", "simulation"):
        raise DataError(f"focus must be 'prediction' or 'simulation', got {focus!r}")
    if weighting is None:  # simulation: one output's plain sum; several: each to its scale
        weighting = ("noise" if focus == "prediction" else
                     "output" if data.n_outputs > 1 else "identity")
    if weighting not in ("noise", "identity", "output"):
        raise DataError(f"weighting must be 'noise', 'identity' or 'output', got {weighting!r}")
    if noise not in _NOISE:
        raise DataError(f"noise must be 'estimate', 'none' or 'fixed', got {noise!r}")
    if enforce_stability is not None and not isinstance(enforce_stability, (bool, np.bool_)):
        raise DataError(f"enforce_stability must be True, False or None, got "
                        f"{enforce_stability!r}")
    if data.n_inputs != model.ninputs or data.n_outputs != model.noutputs:
        raise DataError(
            f"the model has {model.ninputs} input(s) and {model.noutputs} output(s) but the "
            f"data have {data.n_inputs} and {data.n_outputs}")
    n, l = model.nstates, model.noutputs
    A, B, C, D = model.A.copy(), model.B.copy(), model.C.copy(), model.D.copy()
    feedthrough = check_feedthrough(feedthrough, auto=False)  # "auto": decided by the caller
    dropped_d = not feedthrough and bool(np.any(D != 0))
    if not feedthrough:
        D = np.zeros_like(D)
    K = None
    if focus == "prediction" and noise != "none":
        K = model.K.copy() if model.K is not None else np.zeros((n, l))
    # an unstable start: stabilise first and record it
    stabilized = None
    if focus != "prediction" or K is None or enforce_stability:
        if spectral_radius(A) >= 1.0:
            A = _stabilize(A)
            stabilized = "unstable poles of A reflected into the unit circle"
    if K is not None and spectral_radius(A - K @ C) >= 1.0:
        if noise == "fixed":
            raise DataError("the start's predictor A - K C is unstable and noise='fixed' keeps "
                            "K: give a stabilising K or use noise='estimate'")
        if spectral_radius(A) >= 1.0:
            A = _stabilize(A)
            stabilized = "unstable poles of A reflected and K = 0"
        else:
            stabilized = "unstable predictor: started from K = 0"
        K = np.zeros((n, l))
    record, units = data, search_units(data, weighting, balance)
    data = units.data(data)
    B, C, D, K = units.start(B, C, D, K)
    modes = _x0_modes(x0, data.n_experiments, n)
    xs = _balance(B, C, K) if balance else 1.0
    if xs != 1.0:
        B, C = B * xs, C / xs
        K = K * xs if K is not None else None
        modes = [m if isinstance(m, str) else m * xs for m in modes]
    return _Setup(data, A, B, C, D, K, bool(feedthrough),
                  focus == "prediction" and noise == "estimate", weighting, modes, focus,
                  enforce_stability, stabilized, dropped_d, units, record, xs, stats)


#: state factors of a start left as they are (:func:`_balance`)
BALANCE_RANGE = (1e-2, 1e2)


def _balance(B: np.ndarray, C: np.ndarray, K: np.ndarray | None) -> float:
    """The factor ``c`` that makes the state's scale match the signals': with ``x -> c x``
    the entries of ``c [B K]`` and ``C / c`` are of one size. A subspace basis carries the
    units of the data (``C`` in output units, ``B`` in their inverse: in megapascal-volt
    units ``|C| ~ 1e7``, ``|B| ~ 1e-8``), and the search's step test, relative to the
    parameter vector's norm, then stopped it after one iteration. 1 (no change) when ``c``
    is within :data:`BALANCE_RANGE`: only such badly scaled starts are balanced. :func:`pem`
    takes ``B``, ``C``, ``K`` on channels of unit root mean square (:mod:`.units`), where
    ``c``, and so the decision, do not depend on the record's units."""
    nb = float(np.linalg.norm(B)) + (float(np.linalg.norm(K)) if K is not None else 0.0)
    nc = float(np.linalg.norm(C))
    if not (nb > 0 and nc > 0 and np.isfinite(nb) and np.isfinite(nc)):
        return 1.0
    c = float(np.sqrt(nc / nb))
    # as LAPACK's equilibration (xLAQGE), only a badly scaled start is rescaled: within
    # BALANCE_RANGE the entries of [B K] and C differ by less than 1e4, the relative step
    # test sees both, and the search keeps the start's own basis (a subspace start's, on
    # unit-free channels, is well scaled: balancing it anyway ended 2 of 72 synthetic
    # searches in a worse local minimum, 8 % and 214 % above the best found)
    return c if not BALANCE_RANGE[0] <= c <= BALANCE_RANGE[1] else 1.0


def _unbalanced(model: StateSpaceModel, xs: float) -> StateSpaceModel:
    """A model found in the state basis scaled by ``xs`` (:func:`_balance`), in the start's."""
    if xs == 1.0:
        return model
    return StateSpaceModel(
        model.A, model.B / xs, model.C * xs, model.D,
        None if model.K is None else model.K / xs, dt=model.dt, noise_cov=model.noise_cov,
        x0=None if model.x0 is None else model.x0 / xs, input_names=model.input_names,
        output_names=model.output_names, info=model.info)


def _as_start(feedthrough: Any, model: Any) -> Any:
    """``feedthrough=None``: as the start model (its ``D`` estimated when non-zero)."""
    if feedthrough is None:
        D = getattr(model, "D", None)
        return bool(D is not None and np.any(np.asarray(D) != 0))
    return feedthrough


def _warn_dropped_d() -> None:
    """A start with a non-zero ``D`` refined with ``feedthrough=False``: say its D goes."""
    warnings.warn("the start model has a non-zero D but feedthrough=False: it is refined "
                  "with D = 0; leave feedthrough out (or pass True) to refine its D as well",
                  SysidWarning, stacklevel=user_stacklevel())


def pem_loss(
    data: Any,
    model: StateSpaceModel,
    *,
    focus: str = "prediction",
    feedthrough: bool | None = None,
    x0: Any = "estimate",
    noise: str = "estimate",
    weighting: str | None = None,
    enforce_stability: bool | None = None,
) -> float:
    """The criterion :func:`pem` would start from for ``model``, without refining it.

    One pass over the data fits the estimated initial states by least squares, one more
    gives the criterion: ``det(E^T E / N)`` of the prediction (or simulation) errors for
    ``weighting="noise"`` (default for prediction), ``1/2 sum |e|^2`` for
    ``weighting="identity"`` (default for simulation with one output; with several the
    default ``"output"`` sums each output's errors relative to its scale, as :func:`pem`).
    Cheap enough to score many candidate
    models (orders, structures, starts) before refining the best.

    Parameters
    ----------
    data, model, focus, x0, noise, weighting, enforce_stability
        As for :func:`pem`.
    feedthrough : bool, optional
        As for :func:`pem` (``"auto"`` is not taken: score each choice); default as the
        start model (its ``D`` when non-zero).

    Returns
    -------
    float
        The criterion, or ``inf`` when the model is not admissible for that focus (an
        unstable predictor, or for simulation an unstable ``A``): :func:`pem` would have to
        stabilise it first.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> true = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]])
    >>> u = rng.standard_normal(300)
    >>> data = sysid.IOData(u=u, y=true.simulate(u) + 0.1 * rng.standard_normal((300, 1)))
    >>> worse = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    >>> sysid.pem_loss(data, true, focus="simulation") < sysid.pem_loss(data, worse,
    ...                                                                  focus="simulation")
    True
    """
    check_start(model, data, "pem_loss", role="model")
    st = _setup(data, model, focus, _as_start(feedthrough, model), x0, noise, weighting,
                enforce_stability)
    if st.stabilized:
        return float("inf")
    try:
        loss = float(_sysid.pem_criterion(st.A, st.B, st.C, st.D, st.K, st.data.experiments,
                                          **st.kwargs()))
    except DataError as e:
        if "start model" in str(e):
            return float("inf")
        raise
    return loss * st.units.cost_factor  # in the record's units (:mod:`.units`)



def _start_noise(info: dict[str, Any]) -> None:
    """The start's noise covariances (a subspace fit's ``Q``, ``R``, ``S``) under
    ``info["start_noise"]``: at the top level they read as the refined model's (``R`` 0.09
    beside its ``noise_cov`` of 0.19)."""
    moved = {k: info.pop(k) for k in ("Q", "R", "S") if k in info}
    if moved:
        info["start_noise"] = moved


@output_error("pem", when=lambda a: a["focus"] == "simulation" or a["noise"] == "none")
@one_blas_thread
def pem(
    data: Any,
    model: StateSpaceModel | StateSpaceStructure | PolynomialModel,
    *,
    focus: str = "prediction",
    feedthrough: bool | str | None = None,
    x0: Any = "estimate",
    noise: str = "estimate",
    max_iter: int = 50,
    tol: float = 1e-6,
    regularization: dict[str, Any] | None = None,
    progress: bool | None | Callable[..., Any] = None,
    local_coordinates: bool = True,
    weighting: str | None = None,
    enforce_stability: bool | None = None,
    periods: int | str | None = None,
    transient: int | None = None,
    geodesic: bool = False,
    initial_condition: str = "auto",
) -> StateSpaceModel:
    """Refine a state-space model by minimising its prediction (or simulation) errors.

    Parameters
    ----------
    data : IOData or (u, y)
        Estimation data (every experiment is used; remove means first).
    model : StateSpaceModel, StateSpaceStructure or PolynomialModel
        The start (for example a subspace estimate). A polynomial model (``arx``,
        ``armax``, ``oe``, ``bj``, ``polyest``; MATLAB's ``pem(data, idpoly)``) is refined in
        its own structure by the polynomial estimators' prediction-error search
        (:func:`sysid.polynomial.polyest.pem_polynomial`: ``max_iter`` and ``progress``
        apply; a state-space option given is an error that names it). A
        :func:`sysid.ssform` structure (fixed entries, a canonical form) is refined in its
        free parameters (:mod:`sysid.pem.structured`: ``focus``, ``x0``, ``max_iter``,
        ``tol`` and ``progress`` apply).
    focus : {"prediction", "simulation"}
        One-step prediction errors of the innovation form, or simulation errors (``K = 0``).
    feedthrough : bool or "auto", optional
        Estimate ``D`` (``True``) or force ``D = 0`` (``False``; a start with a non-zero
        ``D`` then warns that its ``D`` is dropped). Default: as the start model, the
        structure being refined (MATLAB's ``pem`` keeps its initial model's): ``D``
        estimated when the start's is non-zero, else ``D = 0`` (the default of every sysid
        state-space estimator at a given order). ``"auto"``: decided from the data by the
        rule every estimator shares (:func:`sysid.subspace.feedthrough.choose_feedthrough`,
        at the start's order; recorded in ``info["feedthrough_selection"]``).
    x0 : "estimate", "zero", array, or a list with one per experiment
        Initial states: estimated with the model (default), zero, or given.
    noise : {"estimate", "none", "fixed"}
        Estimate ``K``; no noise model (``K = 0``, an output-error model); or keep the start's
        ``K``. Ignored for ``focus="simulation"``.
    max_iter : int
        Iteration cap.
    tol : float
        Stop when an iteration lowers the cost by less than this fraction.
    regularization : dict, optional
        ``{"lambda": float, "R": (p, p) array, "nominal": "zero" | "model" | array}``: adds
        ``lambda/2 (theta - nominal)^T R (theta - nominal)`` to the cost (MATLAB's
        ``Regularization``).
    progress : bool or callable, optional
        A progress bar over the iterations with the cost (sysid's one progress machinery,
        :mod:`sysid._progress`): by default only on a terminal; ``True`` asks for it (when
        stderr is not a terminal, one line per iteration on stdout instead, for logs);
        ``False`` silences it; a callable gets ``(iteration, cost, step_norm,
        gradient_norm, damping)`` (``cost``: the criterion of ``info["pem"]["cost"]``) and may
        return ``False`` to stop.
    local_coordinates : bool
        Search in data-driven local coordinates (default); ``False`` searches all entries in
        the start's state basis. Without a noise model (``focus="simulation"`` or
        ``noise="none"``) and an order well above the number of inputs (the chart must remove at
        least half of the state sensitivities) the local coordinates are the modal chart: ``A``
        is held in its real block-diagonal (modal) form, the entries outside its 1x1 and 2x2
        blocks at zero, so each iteration costs a fraction of a full one; the refined model
        and its covariance are mapped back to the start's state basis.
    weighting : {"noise", "identity", "output"}, optional
        ``"noise"``: weight the errors by the inverse of their covariance, re-estimated between
        iterations (the determinant criterion, maximum likelihood for Gaussian innovations);
        ``"identity"``: plain sum of squares. ``"output"``: the plain sum of squares of each
        output's errors divided by that output's mean square (the fit % of every output
        counts alike, whatever its units; ``info["pem"]["output_scale"]``, the criterion in
        those units); the same as ``"identity"`` for one output. Default ``"noise"`` for
        prediction focus; for simulation focus (simulation errors are not white, and on the
        shipped records a plain sum gives the better validation fit; see docs/pem.md)
        ``"identity"`` for one output and ``"output"`` for several, so that the result does
        not depend on the outputs' units (with ``"identity"``, a second output in units 1000
        times smaller was ignored: validation fit -1411 % instead of 77 %).
    enforce_stability : bool, optional
        Keep ``A`` stable (MATLAB's ``EnforceStability``). ``focus="simulation"`` always
        does (from an unstable start, a :class:`sysid.StabilityWarning` says when the record
        insists on an unstable model: ``info["pem"]["held_stable"]``). ``None`` (default):
        with ``focus="prediction"`` the predictor ``A - K C`` is always stable and ``A`` is
        kept stable unless an unstable model fits significantly
        better (likelihood-ratio test at the 1 % level, made only once the stable search has
        converged: one stopped at ``max_iter`` keeps ``A`` stable); then a
        :class:`sysid.StabilityWarning` names the largest pole modulus. ``False``: only the
        predictor is kept stable (a warning still says when the model is unstable). Where A
        is kept stable, a pole whose mode keeps over 99 % over the record (where the bound
        held it: an integrating plant, or an undamped pair fitted to noise) is named in a
        ``StabilityWarning`` too.
    periods : int or "auto", optional
        The data are periodic: every experiment holds this many whole periods (at least 2
        after the ``transient`` ones). ``"auto"``: detected from the input
        (:func:`sysid.detect_period`, exact repetition; a trailing partial period is
        dropped); when the input is not periodic, or fewer than 2 periods remain after the
        transient, the refinement runs in the time domain as without ``periods`` and
        ``info["pem"]["periodicity"]`` says why. The model is then fitted in the
        frequency domain on the excited lines only (:mod:`sysid.pem.periodic`): the response
        averaged over the periods (:func:`sysid.bla`), each entry weighted by the inverse of
        its noise variance from the periods, ``A`` held in its real modal form, no initial
        state and no noise model (``K = 0``: ``focus``, ``x0`` and ``noise`` do not apply;
        ``weighting`` may only be ``"noise"``). The model is stable and in the modal basis.
        ``data`` may also be an :class:`sysid.FRD` (for example from :func:`sysid.bla`,
        :func:`sysid.spa` or :func:`sysid.etfe`), fitted the same way: weighted by its
        ``std``, or without one uniformly (MATLAB's default for frequency-response data;
        ``info["pem"]["weighting"] == "uniform"``, the covariance then assumes one noise
        level for every line, scaled by the residuals).
    transient : int, optional
        Leading periods dropped because the output's response to the start of the
        excitation has not settled. Default: 1 with ``periods="auto"`` (the usual practice
        with a multisine applied from rest), 0 with a declared ``periods`` (its periods are
        in steady state, as before). ``info["pem"]["periodicity"]`` records the period, the
        whole periods, the transient and (``"auto"``) the detection.
    geodesic : bool
        Levenberg-Marquardt with geodesic acceleration (Transtrum & Sethna 2012) in the
        time-domain search: each damped step gets a second-order correction from the
        errors' second difference along it (two extra simulations and a gradient pass per
        step); the step is refused when the correction exceeds 0.75 of its size.
        ``info["pem"]["geodesic"]`` counts the corrections formed, carried by accepted steps
        and refused. Default ``False``: at equal CPU time it did not pay on the F-16 at
        ``max_iter=100`` nor on the smaller records; it does on long searches of lightly
        damped large records (benches/results/pem_speed.md). Not used with ``periods``.
    initial_condition : {"auto", "zero", "estimate"}
        A polynomial model's only (a state-space model's initial state is ``x0``): MATLAB's
        ``InitialCondition``, ``"auto"`` (default), ``"zero"`` or ``"estimate"``
        (:mod:`sysid.polynomial.initial`).

    Returns
    -------
    StateSpaceModel
        ``info["pem"]`` holds iterations, ``"cost"``: the criterion the search decreases at
        the start and after each iteration (the values the progress callback gets), named by
        ``"criterion"``: ``"det"``, the determinant of the error covariance
        ``det(E^T E / N)`` (not its log; the maximum-likelihood loss, MATLAB's "loss
        function") for ``weighting="noise"``, ``"sum of squares"``, ``1/2 sum |e|^2``, for
        ``weighting="identity"`` (and ``"output"``, of the scaled errors); ``"loss_history"``:
        the determinant under either weighting;
        ``"weighted_cost"``: ``1/2 sum e^T W e`` with the weighting of each iterate (``N l / 2``
        throughout with the noise weighting); the stop reason (``"statistical convergence"``
        when the expected further decrease is below a hundredth of a residual variance, or a
        tolerance, the cap, or no further decrease) and the condition number;
        ``"spectral_radius"``, the largest pole modulus of the result. The result's
        criterion is never above its start's. The search runs on channels of unit root mean
        square (:mod:`sysid.pem.units`; ``"channel_scaling"``, the input and output scales,
        and ``"state_scale"``, the state basis factor), so that its path and the model do not
        depend on the channels' units; the criterion is reported in the record's units.
        Stopping at ``max_iter`` warns (:class:`sysid.IterationLimitWarning`) unless
        ``"remaining_decrease"`` (the Gauss-Newton predicted decrease at the result in
        residual variances; NaN for other stops) is below 1/8, half a standard deviation of
        the estimate; ``"shortened"`` counts the accepted steps the stability bound
        shortened, and when it is most of them the warning says more iterations creep there.
        ``"metric_switched_at"``: the iteration at which the search's local coordinates
        turned to a basis orthonormal in its own (Marquardt) metric because its steps crawled
        while the parameters' effects spanned more than six orders of magnitude (an unstable
        plant; ``None``: they did not).
        ``uncertainty`` holds the parameter covariance (:class:`sysid.ParameterUncertainty`), so
        that ``poles(std=True)``, ``freqresp(w, std=True)``, ``damp(std=True)`` and Bode bands
        work: the Gauss-Newton one, and with ``focus="simulation"`` (no noise model) on one
        record the sandwich for the errors' own colour (:mod:`sysid.pem.sandwich`; the
        Gauss-Newton one holds for white errors only); ``info["pem"]["covariance"]`` says
        which.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> true = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0], [0.0]], [[1.0, 0.5]])
    >>> u = rng.standard_normal(400)
    >>> data = sysid.IOData(u=u, y=true.simulate(u) + 0.05 * rng.standard_normal((400, 1)))
    >>> start = sysid.moesp(data, order=2, horizon=5, feedthrough=False)
    >>> m = sysid.pem(data, start, focus="simulation")
    >>> m.info["pem"]["stop"] in ("statistical convergence", "cost tolerance", "step tolerance",
    ...                           "gradient tolerance", "no further decrease")
    True
    >>> bool(np.allclose(np.sort_complex(m.poles()), np.sort_complex(true.poles()), atol=0.02))
    True
    """
    given = [k for k, v, d in (
        ("focus", focus, "prediction"), ("feedthrough", feedthrough, None),
        ("x0", x0, "estimate"), ("noise", noise, "estimate"), ("tol", tol, 1e-6),
        ("regularization", regularization, None), ("weighting", weighting, None),
        ("enforce_stability", enforce_stability, None), ("periods", periods, None),
        ("transient", transient, None), ("geodesic", geodesic, False),
        ("local_coordinates", local_coordinates, True))
        if not (v is d or (isinstance(v, (str, bool, float, int)) and v == d))]
    if isinstance(model, PolynomialModel):  # MATLAB's pem(data, idpoly)
        from ..polynomial.polyest import pem_polynomial

        if given:
            raise DataError(f"pem refines a polynomial model in its own structure (one-step "
                            f"prediction errors, its noise model included) and takes "
                            f"max_iter and progress only, got {', '.join(given)}: for a "
                            "simulation fit refine sysid.oe(data, nb, nf, nk, init=model), "
                            "or a state-space form, sysid.pem(data, model.to_statespace())")
        return pem_polynomial(_experiments(data), model, max_iter=max_iter, progress=progress,
                              initial_condition=initial_condition)
    if not (isinstance(initial_condition, str) and initial_condition == "auto"):
        raise DataError(f"initial_condition={initial_condition!r} is a polynomial model's "
                        "option (MATLAB's InitialCondition); a state-space model's initial "
                        "state is x0: 'estimate' (default), 'zero' or given")
    if isinstance(model, StateSpaceStructure):  # MATLAB's pem(data, init_sys) with Structure
        from .structured import pem_structured

        return pem_structured(data, model, focus=focus, x0=x0, max_iter=max_iter, tol=tol,
                              progress=progress, given=given, refine=pem)
    check_start(model, data, "pem")  # NaN matrices, another sample time: before any work
    max_iter, tol = as_int(max_iter, "max_iter", 0), as_nonnegative(tol, "tol")
    periodicity = None
    feedthrough = _as_start(feedthrough, model)
    if isinstance(data, FRD):
        return _pem_periodic(data, model, data, feedthrough, max_iter, tol, progress,
                             weighting, regularization)
    if periods is not None or transient is not None:
        from .periodic import resolve_periods

        frd, periodicity = resolve_periods(_experiments(data), periods, transient)
        if frd is not None:
            out = _pem_periodic(data, model, frd, feedthrough, max_iter, tol, progress,
                                weighting, regularization)
            out.info["pem"]["periodicity"] = periodicity
            return out
    ft_selection = None
    if check_feedthrough(feedthrough) == "auto":
        from ..subspace.estimator import SubspaceEstimator

        feedthrough, ft_selection = choose_feedthrough(SubspaceEstimator(_experiments(data)),
                                                       model.nstates)
    # on channels of unit scale (:mod:`.units`); a nominal parameter vector of the user's is
    # in the start's basis and the record's units: search in them
    st = _setup(data, model, focus, feedthrough, x0, noise, weighting, enforce_stability,
                balance=regularization is None)
    if st.dropped_d:
        _warn_dropped_d()
    check_offsets(st.record, who="pem", stats=st.stats)  # issue 26: the one offset check
    data, A, B, C, D, K = st.data, st.A, st.B, st.C, st.D, st.K
    n, l = model.nstates, model.noutputs
    feedthrough, estimate_k, weighting, modes = (st.feedthrough, st.estimate_k, st.weighting,
                                                 st.modes)
    start_theta = np.concatenate([A.ravel(), B.ravel(), C.ravel()]
                                 + ([D.ravel()] if feedthrough else [])
                                 + ([K.ravel()] if estimate_k and K is not None else []))
    lam, R, nom = _regularization(regularization, None)
    if regularization is not None and isinstance(regularization.get("nominal"), str) \
            and regularization["nominal"] == "model":
        nom = np.concatenate([start_theta] + [np.zeros(n) for m in modes if
                                              isinstance(m, str) and m == "estimate"])
    cb, close_bar = iteration_callback(progress, "pem", max_iter, iteration_printer(
        "pem", "det" if weighting == "noise" else "sum of squares"))
    units = st.units
    try:
        res = _sysid.pem_refine(
            A, B, C, D, K, data.experiments, **st.kwargs(),
            local_coordinates=bool(local_coordinates), max_iter=max_iter, tol_cost=tol,
            reg_lambda=lam, reg_r=R, reg_nominal=nom, progress=units.progress(cb),
            geodesic=bool(geodesic))
    finally:
        close_bar()
    units.report(res)  # the criterion in the record's units
    # a bound held A: the simulation focus, enforce_stability=True, or the default from a
    # stable start (the core's rule)
    held = (focus == "simulation" or bool(enforce_stability)
            or (enforce_stability is None and spectral_radius(A) < 1.0))
    insist = None  # the simulation focus held an unstable start stable: does the record insist?
    if focus == "simulation" and st.stabilized:
        from .held_stable import check_held_stable
        insist = check_held_stable(res, StateSpaceModel(model.A, B, C, D, dt=data.dt), data)
    warn_refinement(res, focus, max_iter, enforce_stability, max(data.lengths), held,
                    boundary=not (insist or {}).get("insists", False))
    stabilized = st.stabilized
    Kres = res["k"] if K is not None else None
    x0s = [x / st.xscale for x in res["x0"]]
    est_x0 = [i for i, m in enumerate(modes) if isinstance(m, str) and m == "estimate"]

    def build(theta: np.ndarray) -> StateSpaceModel:
        theta = np.asarray(theta, dtype=float)
        m_, o = model.ninputs, 0

        def take(r: int, c: int) -> np.ndarray:
            nonlocal o
            out = theta[o:o + r * c].reshape(r, c)
            o += r * c
            return out
        a, b, c = take(n, n), take(n, m_), take(l, n)
        d = take(l, m_) if feedthrough else res["d"]
        k = take(n, l) if estimate_k else Kres
        return units.record_units(_unbalanced(StateSpaceModel(a, b, c, d, k, dt=data.dt),
                                              st.xscale))

    info = dict(model.info) if model.info else {}
    info["method"] = "pem"
    info["start_method"] = model.info.get("method") if model.info else None
    info.pop("integrating", None)  # a start's pinned integrator (identify's) is free here
    if "settings" in info:  # the start's estimator settings (its kalman=True, ...), not ours
        info["start_settings"] = info.pop("settings")
    _start_noise(info)
    info["pem"] = {
        "domain": "time",
        "iterations": res["iterations"],
        "evaluations": res["evaluations"],
        "cost": list(res["history"]),
        "criterion": "det" if weighting == "noise" else "sum of squares",
        "output_scale": units.sy.tolist() if weighting == "output" else None,
        "channel_scaling": units.info(),
        "state_scale": st.xscale,
        "weighted_cost": list(res["weighted_history"]),
        "loss_history": list(res["loss_history"]),
        "stop": res["stop"],
        "geodesic": dict(res["geodesic"], on=bool(geodesic)),
        "shortened": int(res["shortened"]), "remaining_decrease": float(res["remaining_decrease"]),
        "metric_switched_at": res.get("metric_switched_at"),
        "condition": res["condition"],
        "focus": focus,
        "weighting": weighting,
        "feedthrough": bool(feedthrough),
        "start_d_dropped": st.dropped_d,
        "noise": noise if focus == "prediction" else "none",
        "x0": ["estimate" if isinstance(m, str) and m == "estimate" else
               ("zero" if isinstance(m, str) else "given") for m in modes],
        "stabilized": stabilized, "held_stable": insist,
        "spectral_radius": float(res["spectral_radius"]),
        "enforce_stability": enforce_stability,
        "n_parameters": int(res["theta"].size),
        "rank": int(res["rank"]),
        "n_samples": int(res["n_samples"]),
        "x0_values": x0s,
        "estimated_x0": est_x0,
    }
    ys = [np.asarray(y, float) for _, y in data.experiments]  # scaled, as the covariance
    quiet = float(np.trace(np.atleast_2d(res["innovation_covariance"]))) <= 1e-20 * max(
        float(sum(np.sum(np.var(y, axis=0)) for y in ys)) / len(ys), 1e-300)
    # noise-free data leave the noise model (K) undetermined, not the order: no warning
    info["pem"]["undetermined"] = 0 if quiet else warn_undetermined(res, n)
    if periodicity is not None:
        info["pem"]["periodicity"] = periodicity
    if ft_selection is not None:
        info["feedthrough_selection"] = ft_selection
    out = StateSpaceModel(
        res["a"], res["b"], res["c"], res["d"], Kres, dt=data.dt,
        noise_cov=res["innovation_covariance"],
        x0=res["x0"][0] if len(x0s) == 1 else None,  # in the searched basis: unbalanced below
        input_names=data.input_names, output_names=data.output_names, info=info)
    out = units.record_units(_unbalanced(out, st.xscale))
    if K is not None and not estimate_k and model.K is not None:
        out.K = model.K.copy()  # noise="fixed": the start's own, not its round trip
    out.uncertainty = _uncertainty(
        res["theta"], res["covariance"], build, int(res["rank"]),
        _names(n, model.ninputs, l, bool(feedthrough), estimate_k and K is not None, len(est_x0)))
    if focus == "simulation" and out.K is None:
        from .sandwich import defer_state_space

        fixed = [None if isinstance(md, str) and md == "estimate" else x
                 for md, x in zip(modes, x0s)]  # the estimated refitted for every draw
        defer_state_space(out, list(_experiments(st.record).experiments), weighting,
                          units.sy, fixed)
    elif focus == "prediction":  # the sandwich where K cannot take the errors' shape
        from .prediction_sandwich import defer_prediction

        defer_prediction(out, res, list(data.experiments), est_x0, bool(feedthrough),
                         estimate_k and K is not None, weighting)
    return out


def _pem_periodic(data: Any, model: StateSpaceModel, frd: FRD, feedthrough: Any,
                  max_iter: int, tol: float, progress: Any, weighting: str | None,
                  regularization: Any) -> StateSpaceModel:
    """:func:`pem` on the excited lines of periodic data, or on an FRD (weighted by its std,
    uniformly without one)."""
    from .periodic import CRITERION, pem_lines, with_line_weights

    if not isinstance(model, StateSpaceModel):
        raise DataError(f"model must be a sysid.StateSpaceModel, got {type(model).__name__}")
    max_iter, tol = as_int(max_iter, "max_iter", 0), as_nonnegative(tol, "tol")
    if weighting not in (None, "noise") or regularization is not None:
        raise DataError("the frequency-domain refinement of periodic data weights each line "
                        "by its noise variance and takes no regularization: leave weighting "
                        "and regularization out, or refine in the time domain (no periods=)")
    ft = check_feedthrough(feedthrough)
    if ft == "auto":
        if isinstance(data, FRD):  # on lines held out of frequency-subspace fits
            from ..subspace.feedthrough_frd import choose_feedthrough_frd
            from ..subspace.frd_subspace import frd_subspace

            ft, _ = choose_feedthrough_frd(data, model.nstates, lambda g, n, d: frd_subspace(
                g, n, continuous=g.dt is None, feedthrough=d))
        else:
            from ..subspace.estimator import SubspaceEstimator

            ft, _ = choose_feedthrough(SubspaceEstimator(_experiments(data)), model.nstates)
    if not ft and np.any(model.D != 0):
        _warn_dropped_d()
    how = "noise"
    if isinstance(data, FRD):
        frd, how = with_line_weights(frd)
    res, extra = pem_lines(frd, model, feedthrough=bool(ft), max_iter=max_iter, tol=tol,
                           progress=progress, stabilize=_stabilize)
    warn_refinement(res, "frequency-domain", max_iter, True, lines_record_length(frd))
    n, m_, l = model.nstates, model.ninputs, model.noutputs
    d_fixed = res["d"]
    dt = float(frd.dt) if frd.dt is not None else 1.0  # pem_lines refused an FRD without dt

    def build(theta: np.ndarray) -> StateSpaceModel:
        th = np.asarray(theta, dtype=float)
        o = [0, n * n, n * n + n * m_, n * (n + m_ + l)]
        d = th[o[3]:o[3] + l * m_].reshape(l, m_) if ft else d_fixed
        return StateSpaceModel(th[:o[1]].reshape(n, n), th[o[1]:o[2]].reshape(n, m_),
                               th[o[2]:o[3]].reshape(l, n), d, dt=dt)

    info = dict(model.info) if model.info else {}
    info["method"] = "pem"
    info["start_method"] = model.info.get("method") if model.info else None
    info.pop("integrating", None)  # a start's pinned integrator (identify's) is free here
    if "settings" in info:  # the start's estimator settings (its kalman=True, ...), not ours
        info["start_settings"] = info.pop("settings")
    _start_noise(info)
    info["pem"] = {
        "iterations": res["iterations"], "evaluations": res["evaluations"],
        "cost": list(res["history"]), "criterion": CRITERION,
        "weighted_cost": list(res["weighted_history"]), "stop": res["stop"],
        "condition": res["condition"], "focus": "simulation", "weighting": how,
        "feedthrough": bool(ft), "noise": "none", "x0": [],
        "spectral_radius": float(res["spectral_radius"]), "enforce_stability": True,
        "n_parameters": int(res["theta"].size), "rank": int(res["rank"]), **extra,
        "undetermined": warn_undetermined(res, n),
    }
    out = StateSpaceModel(res["a"], res["b"], res["c"], res["d"], None, dt=dt,
                          input_names=frd.input_names, output_names=frd.output_names,
                          info=info)
    out.uncertainty = _uncertainty(res["theta"], res["covariance"], build, int(res["rank"]),
                                   _names(n, m_, l, bool(ft), False, 0))
    return out


def _uncertainty(theta: np.ndarray, cov: np.ndarray, build: Callable[[np.ndarray], Any],
                 rank: int, names: list[str]) -> ParameterUncertainty:
    return ParameterUncertainty(theta, cov, build, names=names[:len(theta)]
                                + [f"theta{i}" for i in range(len(names), len(theta))],
                                dof=rank, method="gauss-newton")


def _names(n: int, m: int, l: int, feedthrough: bool, estimate_k: bool,
           n_x0: int) -> list[str]:
    out = []
    for name, r, c, on in (("A", n, n, True), ("B", n, m, True), ("C", l, n, True),
                           ("D", l, m, feedthrough), ("K", n, l, estimate_k)):
        if on:
            out += [f"{name}[{i},{j}]" for i in range(r) for j in range(c)]
    for e in range(n_x0):
        out += [f"x0[{e}][{i}]" for i in range(n)]
    return out
