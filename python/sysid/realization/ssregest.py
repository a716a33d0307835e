"""A state-space model from a reduced regularised ARX model (MATLAB's ``ssregest``).

A high-order ARX model ``A(q) y = B(q) u + e`` is estimated with a kernel prior tuned by
empirical Bayes (:func:`sysid.arxregul`: stable impulse responses without the variance of a
plain high-order fit), realised in innovations form (:meth:`PolynomialModel.to_statespace`)
and reduced by balanced truncation (:func:`sysid.balanced_truncation`) of the system from
``[u, e]`` to ``y``, the inputs scaled by their standard deviations and ``e`` by the
innovations' so that both paths are weighed by the output they cause. The reduced model
keeps the noise path (``K``); where truncation leaves its one-step predictor ``A - K C``
unstable, ``K`` becomes the stabilising Kalman gain of the same noise spectrum (its
minimum-phase factor, ``info["ssregest"]["predictor_stabilized"]``). Orders that cannot
be balanced (fewer states than the ARX model's unstable poles, or more than its non-zero
Hankel singular values) are left out of the candidates. On noise-free data of a system of
order ``n`` the ARX model holds the system exactly (its extra roots cancel) and the
reduction returns it to round-off.

``order="auto"`` (or a sequence of orders) chooses as the other automatic orders do
(:mod:`sysid.validation.crossval`): the whole procedure fitted on parts of the record, scored
by the simulation fit on the blocks held out, among orders whose model on the whole record
is stable unless the data insist.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .._checks import as_int, experiment_arrays, require_inputs_vary
from ..data.iodata import require_record
from ..data.offsets import check_offsets
from ..errors import DataError, InsufficientDataError, NumericalError
from ..models.checks import warn_unstable
from ..models.statespace import StateSpaceModel
from ..subspace.feedthrough import check_feedthrough, default_feedthrough, held_out_decision

__all__ = ["ssregest"]


def _orders(order: Any) -> list[int] | None:
    """The candidate orders: ``None`` for ``"auto"``, else a sorted list."""
    if isinstance(order, str):
        if order != "auto":
            raise DataError(f"order must be a whole number, a sequence of them or 'auto', "
                            f"got {order!r}")
        return None
    if isinstance(order, (int, np.integer)) and not isinstance(order, (bool, np.bool_)):
        return [as_int(order, "order")]
    try:
        vals = list(order)
    except TypeError:
        raise DataError(f"order must be a whole number, a sequence of them or 'auto', "
                        f"got {order!r}") from None
    if not vals:
        raise DataError("order is an empty sequence: pass at least one order, or 'auto'")
    return sorted({as_int(v, "every order") for v in vals})


def _arx_order(n_samples: int, nu: int, ny: int, arx_orders: Any) -> int:
    if arx_orders is not None:
        return as_int(arx_orders, "arx_orders")
    # about a tenth of the record per equation's parameters, at most 30 lags
    return int(np.clip(n_samples // (10 * (nu + ny)), 1, 30))


def _big_model(data: Any, na: int, kernel: str, nk: int, reg: Any = None
               ) -> tuple[StateSpaceModel, Any]:
    """The regularised ARX model's innovations form and its regularisation (tuned on
    ``data`` by empirical Bayes unless ``reg`` is given)."""
    from ..polynomial.arx import arx
    from ..polynomial.arxregul import arxregul
    from ..validation.free_run import skipped

    ny, nu = data.n_outputs, data.n_inputs
    grid_a = np.full((ny, ny), na) if ny > 1 else na
    grid_b, grid_k = np.full((ny, nu), na), np.full((ny, nu), nk)
    with warnings.catch_warnings(), skipped():  # the quick fit's simulation is not the model
        warnings.simplefilter("ignore")  # the offset check was made once, on the whole record
        if reg is None:
            reg = arxregul(data, grid_a, grid_b, grid_k, kernel)
        poly = arx(data, grid_a, grid_b, grid_k, regularization=reg)
    return poly.to_statespace(), reg


def _reduce(big: StateSpaceModel, su: np.ndarray, ysd: np.ndarray, orders: list[int],
            why: list[str] | None = None) -> dict[int, StateSpaceModel]:
    """Balanced truncation of ``[u, e] -> y`` (scaled) to each order; ``K`` from ``e``'s
    columns. ``why`` collects, per order left out, balanced truncation's reason."""
    from ..analysis.reduction import _truncations

    nu, ny = big.B.shape[1], big.C.shape[0]
    sv = np.sqrt(np.clip(np.diag(big.noise_cov), 0.0, None)) if big.noise_cov is not None \
        else np.zeros(ny)
    se = np.maximum(sv, 1e-6 * ysd)  # noise-free data: the deterministic part decides
    K = big.K if big.K is not None else np.zeros((big.nstates, ny))
    g = StateSpaceModel(big.A, np.hstack([big.B * su, K * se]), big.C,
                        np.hstack([big.D * su, np.diag(se)]), dt=big.dt)
    out = {}
    # one balancing for every order
    for n, r in _truncations(g, [n for n in orders if n <= big.nstates]).items():
        if isinstance(r, DataError):  # fewer states than unstable poles, or more than minimal
            if why is not None:
                why.append(f"order {n}: {r}")
            continue
        out[n] = StateSpaceModel(r.A, r.B[:, :nu] / su, r.C, big.D, K=r.B[:, nu:] / se,
                                 dt=big.dt, input_names=big.input_names,
                                 output_names=big.output_names)
    return out


def _unstable_arx(big: StateSpaceModel) -> DataError | None:
    """The error to raise when no order could be chosen because the ARX model itself is
    unstable (every reduced model keeps its unstable poles, so none simulates a held-out
    block), or None when that is not the cause."""
    rho = np.abs(big.poles())
    unstable = int(np.sum(rho >= 1.0))
    if not unstable:
        return None
    return DataError(
        f"no order could be chosen: the regularised ARX model ({big.nstates} states) has "
        f"{unstable} poles outside the unit circle (largest modulus {rho.max():.4g}), which "
        f"balanced truncation keeps in every reduced model, so none simulates the held-out "
        f"blocks. Unless the process itself is unstable, the ARX structure does not "
        f"suit this record (under feedback or with an integrator an ARX fit can be "
        f"unstable where the plant is not): use sysid.ssest(data, focus='simulation') or "
        f"sysid.oe, or pass an order >= {unstable} for the unstable model")


def _stable_predictor(model: StateSpaceModel, lam: np.ndarray) -> dict[str, Any] | None:
    """Make the one-step predictor ``A - K C`` stable where truncation left it unstable (a
    noise model with zeros outside the unit circle): ``K`` becomes the stabilising Kalman
    gain of the same noise spectrum (``Q = K L K^T``, ``S = K L``, ``R = L``, its
    minimum-phase factor), as the closed-loop subspace fits do; what changed is returned."""
    from ..subspace.kalman import kalman_gain

    A, C, K = model.A, model.C, model.K
    before = float(np.max(np.abs(np.linalg.eigvals(A - K @ C)))) if A.size else 0.0
    model.noise_cov = lam
    if before < 1.0:
        return None
    q = K @ lam @ K.T
    # Q - S R^-1 S^T is 0 here (one noise source): a round-off floor lets the Riccati
    # iteration reach the stabilising solution
    q = q + 1e-10 * max(float(np.trace(q)) / len(q), np.finfo(float).tiny) * np.eye(len(q))
    try:
        k_new, re = kalman_gain(A, C, q, lam, K @ lam)
    except Exception:  # noqa: BLE001 - no stabilising solution: a model without noise path
        model.K = None
        return {"before": before, "after": None,
                "why": "the reduced noise model has an unstable predictor and no stabilising "
                       "Kalman gain: the model is returned without K (output error)"}
    model.K, model.noise_cov = np.asarray(k_new), np.asarray(re)
    after = float(np.max(np.abs(np.linalg.eigvals(A - model.K @ C))))
    return {"before": before, "after": after,
            "why": "truncation left the one-step predictor unstable; K is the stabilising "
                   "Kalman gain of the same noise spectrum (its minimum-phase factor)"}


def _fits(data: Any, orders: list[int], na: int, kernel: str, nk: int,
          why: list[str] | None = None, reg: Any = None
          ) -> tuple[dict[int, StateSpaceModel], StateSpaceModel, Any]:
    """The reduced models of each order, the realised ARX model they come from and its
    regularisation (``why``: see :func:`_reduce`; ``reg``: see :func:`_big_model`)."""
    exps = experiment_arrays(data)
    su = np.concatenate([u for u, _ in exps]).std(axis=0)
    ysd = np.concatenate([y for _, y in exps]).std(axis=0)
    big, reg = _big_model(data, na, kernel, nk, reg)
    return _reduce(big, su, np.maximum(ysd, np.finfo(float).tiny), orders, why), big, reg


def _held_out(data: Any, orders: list[int], na: int, kernel: str, nk: int, reg: Any
              ) -> dict[int, list[float]]:
    """Simulation fits on the record's held-out blocks, per order, of the procedure fitted on
    the rest with the whole record's regularisation ``reg`` (its few hyper-parameters are
    not tuned again per block: the empirical-Bayes search is most of the cost)."""
    from ..validation.crossval import record_folds, simulation_fit

    table: dict[int, list[float]] = {n: [] for n in orders}
    for part, held in record_folds(data):
        try:
            models, _, _ = _fits(part, orders, na, kernel, nk, reg=reg)
        except (DataError, NumericalError):
            models = {}
        for n in orders:
            try:
                table[n].append(simulation_fit(models[n], held) if n in models else -np.inf)
            except (DataError, NumericalError):
                table[n].append(-np.inf)
    return table


def _median(table: dict[int, list[float]]) -> dict[int, float]:
    return {n: float(np.median(v)) if v else -np.inf for n, v in table.items()}


def _choose(whole: dict[int, StateSpaceModel], table: dict[int, list[float]], data: Any
            ) -> tuple[int, dict[str, Any]]:
    from ..validation.crossval import choose, simulation_fit
    from ..validation.stable_orders import stable_first

    med = _median(table)
    unstable = {n for n, m in whole.items() if not m.is_stable()}
    allowed, note = stable_first(med, table, unstable,
                                 lambda n: simulation_fit(whole[n], data))
    n, why = choose({o: f for o, f in med.items() if o in allowed})
    return n, {"order": n, "criterion": "cross-validated simulation fit",
               "reason": why + note, "table": med}


def _decide_feedthrough(data: Any, pool: list[int], na: int, kernel: str
                        ) -> tuple[bool, dict[str, Any], dict[int, list[float]], Any]:
    """``feedthrough="auto"``: the rule of every estimator
    (:func:`sysid.subspace.feedthrough.held_out_decision`) on the best held-out simulation
    fits over ``pool``; also the winning side's held-out table and regularisation."""
    regs = {ft: _big_model(data, na, kernel, 0 if ft else 1)[1] for ft in (False, True)}
    tables = {ft: _held_out(data, pool, na, kernel, 0 if ft else 1, regs[ft])
              for ft in (False, True)}
    best = {ft: max(_median(t).values(), default=-np.inf) for ft, t in tables.items()}
    use, record = held_out_decision(best[True], best[False])
    return use, record, tables[use], regs[use]


def _left_out(data: Any, model: StateSpaceModel, na: int, kernel: str, order: int
              ) -> dict[str, Any] | None:
    """The default ``D = 0`` at a given order: warn when the same procedure with a direct
    term predicts the record one step ahead at least ``LEFT_OUT_RATIO`` times better at this
    order (:func:`sysid.subspace.feedthrough.record_left_out`; the subspace estimators
    compare their fits at the order the same way)."""
    from ..subspace.feedthrough import _prediction_error, record_left_out

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with_d = _fits(data, [order], na, kernel, 0)[0].get(order)
            if with_d is None:
                return None
            without, with_ = (_prediction_error(m, data) for m in (model, with_d))
    except (DataError, NumericalError):  # a check that cannot be made says nothing
        return None
    ratio = without / with_ if with_ > 0 else np.inf
    return record_left_out(ratio, "reduced regularised ARX model", order, "ssregest")


def ssregest(
    data: Any,
    order: Any = "auto",
    *,
    arx_orders: int | None = None,
    kernel: str = "tc",
    feedthrough: bool | str | None = None,
) -> StateSpaceModel:
    """A state-space model by reducing a regularised ARX model (MATLAB's ``ssregest``).

    Parameters
    ----------
    data : IOData or (u, y)
        Estimation record with inputs (several experiments are used together). Remove
        offsets first (a large mean warns, as in every estimator).
    order : int, sequence of int or "auto"
        States of the model; a sequence or ``"auto"`` (orders ``1 .. 20`` the ARX model
        can hold) chooses by simulation fit on blocks of the record held out
        (``info["ssregest"]["order_selection"]``).
    arx_orders : int, optional
        Lags of every ``A`` and ``B`` polynomial of the ARX model (MATLAB's ``ARXOrders``);
        default about a tenth of the samples per equation parameter, at most 30, and at
        least the lags the largest given order needs (or else the smallest) while each
        equation keeps two samples per parameter.
    kernel : {"tc", "ss", "dc", "ridge"}
        The prior of :func:`sysid.arxregul` (MATLAB's ``RegularizationKernel``, default TC).
    feedthrough : bool or "auto", optional
        Estimate ``D`` (the ARX model then has no input delay). Default, as every estimator
        of the package (:mod:`sysid.subspace.feedthrough`): ``"auto"`` when the order is
        chosen too (``D`` when it raises the held-out simulation fit by more than half a
        point, ``info["feedthrough_selection"]``), else ``D = 0`` (MATLAB's default), with a
        :class:`~sysid.FeedthroughWarning` when the record shows a direct term
        (``info["feedthrough_check"]``; not with ``feedthrough=False`` given).

    Returns
    -------
    StateSpaceModel
        In innovations form (``K``, ``noise_cov`` from the one-step prediction errors on the
        data); ``info["ssregest"]``: the ARX orders, the kernel, the Hankel singular values
        of the realised ARX model, for an automatic order the choice, and
        ``predictor_stabilized`` when ``K`` was replaced (module docstring). No parameter
        covariance: refine with ``sysid.pem(data, model)`` for one.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> true = sysid.StateSpaceModel([[0.9, 0.3], [-0.3, 0.9]], [[1.0], [0.5]], [[1.0, 0.0]])
    >>> u = rng.standard_normal((1000, 1))
    >>> y = true.simulate(u) + 0.05 * rng.standard_normal((1000, 1))
    >>> m = sysid.ssregest(sysid.IOData(u, y, 1.0), 2)
    >>> np.round(np.sort(np.abs(m.poles())), 2).tolist()
    [0.95, 0.95]
    >>> m.info["ssregest"]["hankel_singular_values"][:3].round(2).tolist()  # of the ARX model
    [6.31, 4.82, 0.01]
    """
    data = require_record(data, "ssregest")
    if data.n_inputs == 0:
        raise DataError("ssregest estimates an input-output model and the data have no "
                        "inputs: for a time series use sysid.n4sid(data, order) or "
                        "sysid.ssest(data, order)")
    exps = experiment_arrays(data)
    require_inputs_vary(exps, "ssregest", getattr(data, "input_names", None))
    require_inputs_vary(exps, "ssregest", getattr(data, "output_names", None), side=1)
    check_offsets(data)
    candidates = _orders(order)
    n_samples = int(sum(y.shape[0] for _, y in exps))
    na = _arx_order(n_samples, data.n_inputs, data.n_outputs, arx_orders)
    if arx_orders is None and candidates is not None and candidates[-1] > na * data.n_outputs:
        # the default lags hold fewer states than asked for: enough lags for the largest
        # order (else the smallest), as long as each equation keeps two samples per
        # parameter (the prior does the rest)
        for order_ in (candidates[-1], candidates[0]):
            need = -(-order_ // data.n_outputs)
            if na < need and 2 * need * (data.n_inputs + data.n_outputs) <= n_samples:
                na = need
                break
    top = na * data.n_outputs
    pool = candidates if candidates is not None else list(range(1, min(20, top) + 1))
    if pool[0] > top:
        raise DataError(f"order {pool[0]} exceeds the {top} states of the ARX model "
                        f"({na} lags x {data.n_outputs} output(s)): pass a larger "
                        "arx_orders or a smaller order")
    given = feedthrough is not None
    feedthrough = check_feedthrough(default_feedthrough(feedthrough, order))
    selection = table = reg = None
    if feedthrough == "auto":
        feedthrough, selection, table, reg = _decide_feedthrough(data, pool, na, kernel)
    nk = 0 if feedthrough else 1
    why: list[str] = []
    models, big, reg = _fits(data, pool, na, kernel, nk, why, reg)
    if not models:
        raise DataError(f"no order of {pool} could be reduced from the {big.nstates}-state "
                        f"ARX model ({'; '.join(why[:2])}): pass another order or "
                        "arx_orders")
    choice = None
    if len(models) > 1:
        try:
            if table is None:
                table = _held_out(data, sorted(models), na, kernel, nk, reg)
            n, choice = _choose(models, {o: table[o] for o in models}, data)
        except InsufficientDataError as e:
            raise _unstable_arx(big) or e from None
    else:
        n = next(iter(models))
    model = models[n]
    lam = big.noise_cov if big.noise_cov is not None else np.eye(data.n_outputs)
    stabilized = _stable_predictor(model, lam)
    try:
        e = np.concatenate([y - model.predict(u, y, 1) for u, y in exps])
        model.noise_cov = e.T @ e / e.shape[0]
    except NumericalError:  # a predictor on the stability boundary: the Riccati covariance
        pass
    from ..analysis.reduction import hankel_singular_values

    info: dict[str, Any] = {"arx_orders": (na, na, nk), "kernel": kernel,
                            "arx_states": big.nstates}
    try:
        info["hankel_singular_values"] = hankel_singular_values(big)
    except (DataError, NumericalError):  # an unstable ARX model: its stable part's only
        info["hankel_singular_values"] = None
    if choice is not None:
        info["order_selection"] = choice
    if stabilized is not None:
        info["predictor_stabilized"] = stabilized
    model.info = {"method": "ssregest", "ssregest": info}
    if selection is not None:
        model.info["feedthrough_selection"] = selection
    elif not given:  # D left out by default: say so when the record shows a direct term
        check = _left_out(data, model, na, kernel, n)
        if check is not None:
            model.info["feedthrough_check"] = check
    warn_unstable(model, "ssregest", advice=(
        "Unless the process itself is unstable, try another order, a larger arx_orders, or "
        "refine with sysid.pem(data, model, focus='simulation'), which keeps the "
        "simulation stable."))
    return model
