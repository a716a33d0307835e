"""``nlarx``: NARX / NARMAX estimation with FROLS term selection (Rust core, streaming).

The candidate terms are generated and orthogonalised block by block in ``sysid-core``
(``narx/frols.rs``): the full regressor matrix is never built. Each output gets its own
selection from the shared candidates; the number of terms is chosen by an information
criterion on the exact least-squares residuals of each prefix of the selection order, or by
free-run validation error.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import (
    as_between,
    as_int,
    check_magnitudes,
    experiment_arrays,
    require_independent_inputs,
    user_stacklevel,
)
from .._threads import one_blas_thread
from ..data.iodata import require_record
from ..errors import (
    DataError,
    ExcitationWarning,
    InsufficientDataError,
    NumericalError,
    StabilityWarning,
)
from ..polynomial.orders import matlab_orders
from ..validation.fit import diverged
from ..validation.free_run import warn_poor_simulation
from ..validation.records import validation_record
from ..validation.runner import given_start
from .choice import is_auto
from .customreg import CustomRegressor
from .hw_model import SigmoidNetwork, check_search_size
from .narx_model import NARXModel, PolynomialBasis, RBFBasis
from .narx_network import is_network, nlarx_network
from .narx_network_model import NetworkNARXModel

__all__ = ["nlarx"]

CRITERIA = ("aic", "bic", "fpe", "validation", None)


def _per(v: Any, n: int, name: str) -> list[int]:
    a = np.atleast_1d(np.asarray(v))
    if a.size == 1:
        a = np.full(n, a[0])  # as given: 2.5 is refused below, not read as 2
    if a.dtype.kind not in "iuf" or a.shape != (n,) or np.any(a < 0) \
            or not np.all(np.equal(np.mod(a, 1), 0)):
        raise DataError(f"{name} must be a non-negative integer or {n} of them, got {v!r}")
    return [int(x) for x in a]


def _lag_matrix(u: np.ndarray, y: np.ndarray, na: list[int], nb: list[int], nk: list[int]
                ) -> np.ndarray:
    """Lagged variables ``(n - L, nv)`` of one record (for fitting an RBF basis)."""
    L = max([*na, *[b + k - 1 for b, k in zip(nb, nk) if b], 1])
    n = y.shape[0]
    cols = [y[L - lag:n - lag, k] for k in range(len(na)) for lag in range(1, na[k] + 1)]
    cols += [u[L - lag:n - lag, j] for j in range(len(nb)) for lag in range(nk[j], nk[j] + nb[j])]
    return np.column_stack(cols)


def _structure(orders: Any, degree: int | None, rbf: Any, cust: dict[str, Any]) -> dict[str, Any]:
    """The model structure the NARX bindings share (orders, basis, custom regressors)."""
    return {"orders": orders, "degree": degree, "rbf": rbf,
            "custom_args": cust.get("custom_args", [])}


def _values(cust: dict[str, Any]) -> dict[str, Any]:
    """The custom regressors' values over the records, as keyword arguments."""
    return {"custom_values": cust["custom_values"]} if "custom_values" in cust else {}


def _custom(custom: list[Any], exps: list[tuple[np.ndarray, np.ndarray]], orders: Any,
            ne: int, names: dict[str, Any]) -> dict[str, Any]:
    """Arguments and values (one ``(N, n_custom)`` array per experiment) of the custom
    regressors for ``_sysid.narx_frols``; empty without custom regressors."""
    if not custom:
        return {}
    if not all(isinstance(c, CustomRegressor) for c in custom):
        raise DataError("custom must be a list of sysid.CustomRegressor")
    na_, nb_, nk_, _ = orders
    ny, nu = len(na_), len(nb_)
    outs = names["output_names"] or [f"y{i}" for i in range(ny)]
    ins = names["input_names"] or [f"u{j}" for j in range(nu)]
    args = [c.resolve(list(outs), list(ins)) for c in custom]
    L = max([*na_, *[b + k - 1 for b, k in zip(nb_, nk_) if b], ne, 1,
             *[lag for a in args for _, _, lag in a]])
    vals = []
    for u, y in exps:
        if y.shape[0] <= L:
            raise DataError(f"a record of {y.shape[0]} samples is too short for lags up to {L}")
        vals.append(np.ascontiguousarray(np.column_stack(
            [c.values(u, y, L, list(outs), list(ins)) for c in custom])))
    return {"custom_args": args, "custom_values": vals}


def _prefix(r: np.ndarray, k: int) -> tuple[np.ndarray, float]:
    """Least squares of the first ``k`` terms from the factor of ``[Phi_S, y]``."""
    K = r.shape[1] - 1
    rss = float(np.sum(r[k:, K] ** 2))
    if k == 0:
        return np.zeros(0), rss
    from scipy.linalg import solve_triangular

    return solve_triangular(r[:k, :k], r[:k, K]), rss


def _score(rss: float, n: int, k: int, criterion: str) -> float:
    v = max(rss / n, 1e-300)
    if criterion == "aic":
        return n * np.log(v) + 2 * k
    if criterion == "bic":
        return n * np.log(v) + k * np.log(n)
    return n * np.log(v) + n * np.log((n + k) / max(n - k, 1))  # fpe


def _free_run(model: Any, exps: list[tuple[np.ndarray, np.ndarray]]
              ) -> tuple[np.ndarray, np.ndarray, int] | tuple[None, str, int]:
    """The model run free on each experiment from its measured first ``max_lag`` outputs:
    ``(sum of squared errors, sum of squared deviations from the mean, count)`` per output
    after those samples (:func:`~sysid.validation.runner.given_start`, as ``compare``
    scores them), or ``(None, why, experiment)`` when a run diverges."""
    sse, var, count = 0.0, 0.0, 0
    k = given_start(model)
    for i, (u, y) in enumerate(exps):
        try:
            ys = np.asarray(model.simulate(u, x0=y[:model.max_lag])).reshape(y.shape)
            if not np.all(np.isfinite(ys)):
                raise NumericalError("the simulated output is not finite")
            if diverged(y, ys):  # finite, but grown far beyond the record (F-16: 1e37 x)
                big = float(np.max(np.abs(ys)) / max(float(np.max(np.abs(y))), 1e-300))
                raise NumericalError(f"the simulated output grows to {big:.2g} times the "
                                     "measured one")
        except NumericalError as e:
            return None, str(e), i
        sse = sse + np.sum((ys - y)[k:] ** 2, axis=0)
        var = var + np.sum((y[k:] - y[k:].mean(axis=0)) ** 2, axis=0)
        count += y[k:].size
    return np.atleast_1d(sse), np.atleast_1d(var), count


def _free_run_rmse(model: NARXModel, exps: list[tuple[np.ndarray, np.ndarray]]) -> float:
    sse, _, count = _free_run(model, exps)
    return np.inf if sse is None else float(np.sqrt(np.sum(sse) / max(count, 1)))


#: what to do when a NARX model's free run fails on its own estimation data
_SIMULATE = ("keep fewer terms (criterion='bic'), a lower degree or shorter lags, or fit for "
             "simulation (nlarx with a SigmoidNetwork and focus='simulation', nlhw, pnlss)")


def free_run_check(model: Any, exps: list[tuple[np.ndarray, np.ndarray]]) -> None:
    """Simulate the fitted model on its estimation record (free run from the measured first
    ``max_lag`` outputs of each experiment) and record it in ``model.info["free_run"]``;
    warn (:class:`~sysid.StabilityWarning`) when the simulation diverges, and
    (:func:`sysid.validation.free_run.warn_poor_simulation`) when it simulates an output
    worse than its mean. A NARX model is fitted one step ahead, where the measured outputs
    hold it; run on its own outputs it can blow up even on the data it was fitted to (a
    degree-3 polynomial model on the pH record did, and said nothing until ``compare``
    reported ``-inf``), or just miss (the flutter record's degree-2 model: -1986 %)."""
    sse, var, i = _free_run(model, exps)
    if sse is None:
        model.info["free_run"] = {"diverged": True, "experiment": i, "reason": var}
        warnings.warn(StabilityWarning(
            f"nlarx: the model's free-run simulation diverges on its own estimation data "
            f"(experiment {i}: {var}). It is fitted for one-step prediction, which it still "
            "does; to simulate, " + _SIMULATE), stacklevel=user_stacklevel())
        return
    fit = 100.0 * (1.0 - np.sqrt(sse / np.maximum(var, 1e-300)))
    model.info["free_run"] = {"diverged": False, "fit": fit.tolist()}
    # a model without input terms has its own warning (its simulation is a constant)
    if getattr(model, "ninputs", 0) and (not hasattr(model, "terms") or _uses_input(model)):
        warn_poor_simulation("nlarx", fit, list(model.output_names),
                             "To simulate, " + _SIMULATE + ".")


@one_blas_thread
def nlarx(
    data: Any,
    na: Any,
    nb: Any = None,
    nk: Any = None,
    *,
    basis: Any = "auto",
    max_terms: int = 10,
    criterion: str | None = "aic",
    validation: Any = None,
    noise_terms: int = 0,
    n_iterations: int = 5,
    err_tol: float = 1e-10,
    custom: Any = None,
    focus: str = "prediction",
    max_iter: int = 100,
    progress: Any = None,
) -> NARXModel | NetworkNARXModel:
    """NARX / NARMAX model with terms chosen by FROLS (forward-regression orthogonal least
    squares with the error reduction ratio).

    Parameters
    ----------
    data : IOData or (u, y)
        Estimation record; several experiments are used together.
    na : int or list (n_outputs)
        Output lags ``1..na`` of each output (shared by every output's equation); or all the
        lags as MATLAB's one vector ``[na, nb, nk]`` (``na`` one per output, ``nb`` and
        ``nk`` one per input) with ``nb`` and ``nk`` left out.
    nb, nk : int or list (n_inputs)
        Input lags ``nk..nk + nb - 1`` (``nk`` default 1).
    basis : "auto", PolynomialBasis, RBFBasis, SigmoidNetwork, WaveletNetwork or TreePartition
        Candidate terms (``None``: ``PolynomialBasis(2)``). ``"auto"`` (default): the
        degree-2 polynomial terms (selected as the other arguments say) where the record's
        held-out blocks insist on them, else the linear ARX model of the same lags (degree
        1: every lag and custom regressor, least squares): FROLS picks terms by their
        one-step error, and run free they can simulate far worse than that linear model
        (:mod:`sysid.nonlinear.choice`; about ten FROLS fits: give the basis to fit once);
        ``info["basis_choice"]`` holds the table and the reason; with ``focus="simulation"``
        a sigmoid network (``SigmoidNetwork()``), as FROLS selects terms for the one-step
        prediction. Or a network nonlinearity of all
        lagged variables (MATLAB's ``idSigmoidNetwork``, ``idWaveletNetwork``,
        ``idTreePartition``): then the result is a :class:`~sysid.NetworkNARXModel`, trained
        by separable least squares (the term-selection arguments do not apply). A
        :class:`~sysid.NetworkNARXModel` (a sigmoid or wavelet network) is refined from its
        parameters (MATLAB's ``nlarx(data, sys0)``).
    max_terms : int
        Term budget per output (process terms).
    criterion : "aic", "bic", "fpe", "validation" or None
        How many of the selected terms to keep: the prefix minimising the criterion on the
        estimation residuals, the smallest free-run RMSE on ``validation`` data, or all
        (``None``; selection still stops when the residual is below ``err_tol``). With
        ``basis="auto"`` and ``"validation"``, the validation record also chooses between
        the polynomial and the linear model (the lower free-run RMSE on it), in place of
        the estimation record's held-out blocks.
    validation : IOData or (u, y), optional
        Validation record for ``criterion="validation"``: the estimation data's channels
        and sample time (a ``(u, y)`` pair takes the latter), refused otherwise.
    noise_terms : int
        NARMAX: residual lags ``1..noise_terms``; up to ``max_terms`` noise terms are chosen
        after the process terms by the extended-least-squares iteration (``n_iterations``
        rounds of residuals, selection and refit).
    n_iterations : int
        Extended-least-squares rounds (NARMAX only).
    err_tol : float
        Stop selecting when the unexplained fraction ``1 - sum ERR`` falls below this.
    custom : list of CustomRegressor, optional
        User-supplied regressors (MATLAB's ``customreg``), candidates beside the basis's
        terms; each enters linearly if chosen.

    focus : "prediction" or "simulation"
        Network nonlinearities only: train for one-step prediction, or refine every
        parameter afterwards for free-run simulation (MATLAB's ``Focus``).
    max_iter : int
        Network nonlinearities only: iteration cap of each search.
    progress : bool or callable, optional
        Network nonlinearities only: a progress bar over the iterations (by default on a
        terminal), or ``callable(iteration, cost, step_norm, gradient_norm, damping)``
        (``False`` returned stops the search).

    Returns
    -------
    NARXModel or NetworkNARXModel
        With ``err`` per term and ``info`` (criterion values, candidates, rows); a network
        model's ``info`` holds each search's iterations, cost history and stop reason.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> u = rng.uniform(-1, 1, (400, 1)); y = np.zeros((400, 1))
    >>> for t in range(2, 400):
    ...     y[t] = -0.605 * y[t-1] - 0.163 * y[t-2]**2 + 0.588 * u[t-1] - 0.24 * u[t-2]
    >>> m = sysid.nlarx(sysid.IOData(u, y, 1.0), 2, 2, basis=sysid.PolynomialBasis(2))
    >>> print(m.terms_table())
    y0 = -0.605 y0(t-1) + 0.588 u0(t-1) - 0.24 u0(t-2) - 0.163 y0(t-2)^2
    """
    data = require_record(data, "nlarx")
    exps = experiment_arrays(data)
    check_magnitudes(data, "nlarx")
    ny, nu = exps[0][1].shape[1], exps[0][0].shape[1]
    # inputs recorded twice: no model can tell them apart (constant ones are checked below)
    require_independent_inputs(exps, "nlarx", getattr(data, "input_names", None))
    na, nb, nk = matlab_orders("nlarx", data, na, nb=nb, nk=nk)
    na_, nb_, nk_ = _per(na, ny, "na"), _per(nb, nu, "nb"), _per(nk, nu, "nk")
    shortest = min(len(y) for _, y in exps)
    lag = max([*na_, *(k + b - 1 for b, k in zip(nb_, nk_) if b > 0), 0])
    if lag >= shortest:  # before the regressors are allocated
        raise InsufficientDataError(f"the largest lag ({lag}) must be below the samples of the "
                                    f"shortest experiment ({shortest}); lower na, nb or nk")
    if criterion not in CRITERIA:
        raise DataError(f"criterion must be one of {CRITERIA}, got {criterion!r}")
    if focus not in ("prediction", "simulation"):
        raise DataError(f"focus must be 'prediction' or 'simulation', got {focus!r}")
    if criterion == "validation" and validation is None:
        raise DataError("criterion='validation' needs validation data (validation=IOData)")
    # channels, sample time, length and varying outputs: the check pnlss and nlssest make
    validation = validation_record(validation, data)
    max_terms, noise_terms = as_int(max_terms, "max_terms"), as_int(noise_terms, "noise_terms", 0)
    n_iterations, max_iter = as_int(n_iterations, "n_iterations"), as_int(max_iter, "max_iter", 0)
    # the unexplained fraction at which the selection stops: NaN stopped it never, a value
    # of 1 or more before the first term
    err_tol = as_between(err_tol, "err_tol", 0.0, 1.0, closed="left")
    auto_network = is_auto(basis) and focus != "prediction"
    if auto_network:  # FROLS selects for prediction: the automatic basis is then a network
        if noise_terms or custom:
            raise DataError("focus='simulation' trains a sigmoid network (the polynomial "
                            "terms are selected for prediction), which takes no noise_terms "
                            "or custom regressors: leave them out, or use focus='prediction'")
        basis = SigmoidNetwork()
    elif is_auto(basis):
        return _auto_basis(data, dict(
            na=na, nb=nb, nk=nk, max_terms=max_terms, criterion=criterion,
            validation=validation, noise_terms=noise_terms, n_iterations=n_iterations,
            err_tol=err_tol, custom=custom, focus=focus, max_iter=max_iter, progress=progress),
            int(sum(na_)) + int(sum(nb_)) + len(custom or []) + 1)
    basis = PolynomialBasis(2) if basis is None else basis
    if is_network(basis):
        if noise_terms or custom:
            raise DataError("noise_terms and custom regressors need a PolynomialBasis or "
                            "RBFBasis; a network nonlinearity takes the lagged inputs and outputs")
        check_search_size([basis] * ny, sum(y.size for _, y in exps), "nlarx",
                          int(sum(na_)) + int(sum(nb_)))
        net = nlarx_network(exps, na_, nb_, nk_,
                            np.vstack([_lag_matrix(u, y, na_, nb_, nk_) for u, y in exps]),
                            basis, dt=float(getattr(data, "dt", 1.0) or 1.0),
                            names=dict(input_names=getattr(data, "input_names", None),
                                       output_names=getattr(data, "output_names", None)),
                            focus=focus, max_iter=max_iter, tol=1e-4, progress=progress)
        if net.info.get("refine", {}).get("stop") != "failed to start":  # that one warned
            free_run_check(net, exps)
        if auto_network:
            net.info["basis_choice"] = {
                "choice": repr(basis),
                "reason": "basis='auto' with focus='simulation': a sigmoid network trained on "
                          "the simulation error (the polynomial terms are selected for the "
                          "one-step prediction)"}
        return net
    if focus != "prediction":
        raise DataError("focus='simulation' needs a network nonlinearity (SigmoidNetwork, "
                        "WaveletNetwork, TreePartition); FROLS selects for prediction")
    if not isinstance(basis, (PolynomialBasis, RBFBasis)):
        raise DataError(f"basis must be a PolynomialBasis, an RBFBasis or a network "
                        f"(SigmoidNetwork, WaveletNetwork, TreePartition), got {basis!r}")
    if isinstance(basis, RBFBasis):
        if noise_terms:
            raise DataError("noise_terms (NARMAX) needs a PolynomialBasis")
        basis = basis.fitted([_lag_matrix(u, y, na_, nb_, nk_) for u, y in exps])
    degree, rbf = basis.rust_args()
    orders = (na_, nb_, nk_, [0] * ny)
    names = dict(input_names=getattr(data, "input_names", None),
                 output_names=getattr(data, "output_names", None))
    custom = list(custom or [])
    cust = _custom(custom, exps, orders, noise_terms, names)
    structure = _structure(orders, degree, rbf, cust)
    sel, n_cands = _sysid.narx_frols([(u, y, None) for u, y in exps], structure,
                                     int(max_terms), [[] for _ in range(ny)], float(err_tol),
                                     **_values(cust))
    n_rows = int(sel[0]["n_rows"])
    if n_rows < 2:
        raise DataError(f"the record gives {n_rows} regression row(s) for these lags: too "
                        "short to fit a NARX model; give a longer record or shorter lags")
    may = min(int(max_terms), int(n_cands))  # the terms FROLS may select per output
    if n_rows < may:  # it would interpolate the rows exactly (3 rows for 35 candidates)
        raise InsufficientDataError(
            f"nlarx: the record gives {n_rows} regression rows for {int(n_cands)} candidate "
            f"terms, of which FROLS may select {may} (max_terms={int(max_terms)}): fewer "
            f"rows than terms fit the record exactly and say nothing of the system; give a "
            f"longer record (at least {may} rows, {2 * may} to keep them all), a lower "
            "degree or shorter lags (na, nb), or fewer candidate terms (a smaller max_terms, "
            "fewer custom regressors)")
    keep, scores = [], []
    for s in sel:
        # at least as many residual degrees of freedom as terms: on a short record FROLS
        # would otherwise keep one term per row, an exact interpolation of the noise
        K = min(len(s["terms"]), n_rows // 2)
        if criterion in ("aic", "bic", "fpe"):
            sc = [_score(_prefix(s["r"], k)[1], n_rows, k, criterion) for k in range(K + 1)]
            keep.append(int(np.argmin(sc)))
            scores.append(sc)
        else:
            keep.append(K)
    dt = float(getattr(data, "dt", 1.0) or 1.0)

    def build(ks: list[int]) -> NARXModel:
        terms, coefs, errs, var = [], [], [], []
        for s, k in zip(sel, ks):
            th, rss = _prefix(s["r"], k)
            terms.append(s["terms"][:k])
            coefs.append(th)
            errs.append(np.asarray(s["err"])[:k])
            var.append(rss / n_rows)
        return NARXModel(na_, nb_, nk_, basis, terms, coefs, dt, err=errs,
                         noise_variance=var, custom=custom, **names)

    if criterion == "validation":
        vexps = experiment_arrays(validation)
        for i, s in enumerate(sel):
            best = (np.inf, keep[i])
            for k in range(1, len(s["terms"]) + 1):
                trial = list(keep)
                trial[i] = k
                rmse = _free_run_rmse(build(trial), vexps)
                if rmse < best[0]:
                    best = (rmse, k)
            keep[i] = best[1]
            scores.append([best[0]])
    model = build(keep)
    info: dict[str, Any] = {"method": "nlarx", "selection": "FROLS", "criterion": criterion,
                            "n_candidates": int(n_cands), "n_rows": n_rows,
                            "max_terms": int(max_terms), "criterion_values": scores}
    if noise_terms:
        model = _narmax(model, exps, orders, degree, rbf, int(noise_terms), int(max_terms),
                        int(n_iterations), float(err_tol), names, info, criterion, cust)
    model.info.update(info)
    free_run_check(model, exps)
    if nu and not _uses_input(model):
        left = ", ".join(f"{1.0 - float(np.sum(e)):.1e}" for e in model.err)
        model.info["uses_input"] = False
        warnings.warn(ExcitationWarning(
            f"nlarx: no selected term involves an input, so the model's simulation does not "
            f"depend on the input (a constant). The output lags alone left {left} of the "
            f"output's variation unexplained one step ahead (the selection stops below "
            f"err_tol={err_tol:g}; criterion={criterion!r} keeps a prefix of the terms chosen)"
            ". A fast-sampled or integrating output does "
            "this: decimate the record (sysid.decimate), lower err_tol, or fit for simulation "
            "(nlarx with a SigmoidNetwork and focus='simulation', nlhw, pnlss)"),
            stacklevel=user_stacklevel())
    return model


def _auto_basis(data: Any, kw: dict[str, Any], n_linear: int) -> NARXModel:
    """``nlarx`` with ``basis="auto"``: the degree-2 polynomial (``kw`` as given) where the
    record's held-out blocks insist on it over the linear ARX model of the same lags (all
    ``n_linear`` candidate terms by least squares: a selection that stops at ``err_tol``
    or ``max_terms`` can leave out every input, as on a smooth servo record), chosen by
    :func:`sysid.nonlinear.choice.choose_structure`; the choice in ``info["basis_choice"]``."""
    from .choice import choose_structure

    def fit(part: Any, kind: str) -> NARXModel:
        if kind == "polynomial":
            return nlarx(part, basis=PolynomialBasis(2), **kw)
        return nlarx(part, basis=PolynomialBasis(1), **{
            **kw, "criterion": None, "max_terms": max(n_linear, int(kw["max_terms"])),
            "err_tol": 0.0})

    if kw["criterion"] == "validation":  # the record the user gave decides, as it decides
        return _basis_by_validation(data, fit, kw["validation"])  # the terms
    choice = choose_structure(data, fit, ("linear", "polynomial"),
                              {"linear": "the linear ARX model of the same lags",
                               "polynomial": "degree-2 polynomial terms"}, "")
    model = fit(data, choice.kind)
    model.info["basis_choice"] = choice.as_dict()
    return model


def _basis_by_validation(data: Any, fit: Any, validation: Any) -> NARXModel:
    """``basis="auto"`` with ``criterion="validation"``: both candidates fitted on the whole
    record (the polynomial's terms kept by their free-run RMSE on ``validation``), and the
    one of lower free-run RMSE on ``validation`` kept (the linear one on a tie)."""
    vexps = experiment_arrays(validation)
    models = {kind: fit(data, kind) for kind in ("linear", "polynomial")}
    rmse = {kind: _free_run_rmse(m, vexps) for kind, m in models.items()}
    kind = "polynomial" if rmse["polynomial"] < rmse["linear"] else "linear"
    model = models[kind]
    model.info["basis_choice"] = {
        "kind": kind, "table": rmse, "criterion": "validation",
        "reason": (f"criterion='validation': the {kind} candidate has the lower free-run RMSE "
                   f"on the validation record ({rmse[kind]:.4g} against "
                   f"{rmse['linear' if kind == 'polynomial' else 'polynomial']:.4g})")}
    return model


def _uses_input(model: NARXModel) -> bool:
    """Whether any equation has a term in a lagged input (or a radial-basis or custom term,
    which may): without one the free-run simulation ignores the input."""
    lo = int(sum(model.na))
    hi = lo + int(sum(model.nb))
    for eq in model.terms:
        for t in eq:
            if (len(t) == 2 and t[0] == -1) or (len(t) == 1 and t[0] < 0):
                return True
            if any(lo <= k < hi for k in t):
                return True
    return False


def _narmax(model: NARXModel, exps: list[tuple[np.ndarray, np.ndarray]], orders: Any,
            degree: int | None, rbf: Any, ne: int, max_noise: int, n_iterations: int,
            err_tol: float, names: dict[str, Any], info: dict[str, Any],
            criterion: str | None, cust: dict[str, Any]) -> NARXModel:
    """Extended least squares: residuals of the current model, noise terms chosen after the
    (forced) process terms, refit; repeated ``n_iterations`` times."""
    na_, nb_, nk_, _ = orders
    ny = len(na_)
    process = [list(t) for t in model.terms]
    ne_ = [ne] * ny
    history = []
    current = model
    for _ in range(max(n_iterations, 1)):
        recs = [(u, y, np.ascontiguousarray(y - current.predict(u, y, 1))) for u, y in exps]
        sel, _ = _sysid.narx_frols(recs, _structure((na_, nb_, nk_, ne_), degree, rbf, cust),
                                   max(len(p) for p in process) + max_noise, process, err_tol,
                                   **_values(cust))
        terms, coefs, errs, var = [], [], [], []
        for s, p in zip(sel, process):
            k = len(s["terms"])
            if criterion in ("aic", "bic", "fpe"):  # noise terms kept by the same criterion
                n = int(s["n_rows"])
                sc = [_score(_prefix(s["r"], j)[1], n, j, criterion)
                      for j in range(len(p), k + 1)]
                k = len(p) + int(np.argmin(sc))
            th, rss = _prefix(s["r"], k)
            terms.append(s["terms"][:k])
            coefs.append(th)
            errs.append(np.asarray(s["err"])[:k])
            var.append(rss / s["n_rows"])
        new = NARXModel(na_, nb_, nk_, current.basis, terms, coefs, current.dt, ne=ne_,
                        err=errs, noise_variance=var, custom=current.custom, **names)
        history.append(float(np.sum(var)))
        same = [t for t in new.terms] == [t for t in current.terms] and all(
            np.allclose(a, b, rtol=1e-8, atol=1e-12) for a, b in zip(new.coefs, current.coefs))
        current = new
        if same:
            break
    info["els_residual_variance"] = history
    return current
