"""``nlhw_ss``: MIMO Hammerstein-Wiener estimation around a state-space linear block.

Starts from a linear subspace fit (:func:`sysid.n4sid`) of the record and near-identity
nonlinearities, then minimises the simulation error of every output over all parameters
with the shared Gauss-Newton / Levenberg-Marquardt search (``sysid-core`` ``optim/``), the
sensitivities run sample by sample in Rust (``hw/mimo.rs``). The admissible set is a stable
``A``.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import (
    as_int,
    as_nonnegative,
    check_magnitudes,
    experiment_arrays,
    require_inputs_vary,
    warn_if_capped,
)
from .._progress import iteration_callback, iteration_printer
from .._threads import one_blas_thread
from ..data.iodata import require_record
from ..data.levels import warn_two_levels
from ..data.offsets import check_offsets
from ..errors import DataError
from .hw_initial import check_initial, free_response_ss, least_squares_states
from .hw_model import (
    Nonlinearity,
    UserFunction,
    check_search_size,
    fit_amplitudes,
    fitted_curve,
)
from .hw_ss_model import HammersteinWienerSSModel
from .hw_uncertainty import attach
from .operating_point import better_of_both, centred, record_means, undecided, use_offsets

__all__ = ["nlhw_ss"]


def _per_channel(nl: Any, n: int, name: str) -> list[Nonlinearity]:
    items = list(nl) if isinstance(nl, (list, tuple)) else [nl] * n
    if len(items) != n:
        raise DataError(f"{name} needs one nonlinearity per channel ({n}), got {len(items)}")
    out = []
    for f in items:
        if f is None:
            out.append(Nonlinearity())
        elif isinstance(f, Nonlinearity):
            out.append(copy.deepcopy(f))
        else:
            raise DataError(f"{name} entries must be sysid nonlinearities (Saturation, "
                            f"DeadZone, PolynomialNonlinearity, PiecewiseLinear, "
                            f"SigmoidNetwork, UserFunction) or None (the whole side may "
                            f"be \"auto\"), got {f!r}")
    return out


@one_blas_thread
def nlhw_ss(
    data: Any,
    order: int,
    *,
    input_nl: Any = "auto",
    output_nl: Any = "auto",
    feedthrough: bool = False,
    max_iter: int = 200,
    tol: float = 1e-10,
    progress: bool | None | Callable[..., Any] = None,
    linear: Any = None,
    offsets: bool | str = "auto",
    initial_condition: str = "zero",
) -> HammersteinWienerSSModel:
    """Hammerstein-Wiener model with per-channel static nonlinearities around a MIMO
    state-space linear block: ``w_j = f_j(u_j)``, ``x(t+1) = A x + B w``, ``v = C x + D w``,
    ``y_i = g_i(v_i) + e_i``.

    Parameters
    ----------
    data : IOData or (u, y)
        Estimation record (any numbers of inputs and outputs; several experiments are used
        together).
    order : int
        State dimension of the linear block.
    input_nl, output_nl : Nonlinearity, list, "auto" or None
        One nonlinearity for every channel, or a list with one per input / output (``None``
        entries: identity). ``output_nl=None``: Hammerstein; ``input_nl=None``: Wiener.
        ``"auto"`` (default): the identity or a 3-unit sigmoid network on every channel of
        that side, as the record's held-out blocks insist (as for :func:`sysid.nlhw`;
        ``info["nonlinearity_choice"]``).
    feedthrough : bool
        Estimate a direct term ``D`` (default ``D = 0``).
    max_iter, tol : int, float
        Optimiser iterations and step/gradient tolerance.
    progress : bool or callable, optional
        As for :func:`sysid.nlhw` (a bar, silence, or a callable getting ``(iteration, cost,
        step_norm, gradient_norm, damping)``; ``False`` returned stops).
    linear : StateSpaceModel, optional
        The linear block's start (stable, ``order`` states; the record's units). Default: a
        subspace fit (:func:`sysid.n4sid`) of the record, with a stable ``A`` enforced when
        it is unstable (``info["linear_start"]`` then says so).
    offsets : "auto", True or False
        As for :func:`sysid.nlhw`: fit about the record's means and keep them in the model
        (``"auto"``: a channel's mean farther from zero than its standard deviation, and
        every nonlinearity a sigmoid network or the identity; with levels in the data's units
        on such a record, the better of both fits); about the means the outputs' levels
        (``y_offset``) are estimated with the other parameters.
    initial_condition : "zero" or "estimate"
        MATLAB's ``InitialCondition``: every experiment from rest (default), or its linear
        block's initial state ``x(0)`` estimated with the other parameters (for a record that
        starts mid-response; :mod:`sysid.nonlinear.hw_initial`). ``info["initial_condition"]``
        says which, ``info["initial_state"]`` holds one ``x(0)`` per experiment (zeros from
        rest; in the fitted model's state basis, as its ``simulate(u, x0)`` takes it).

    Returns
    -------
    HammersteinWienerSSModel
        With ``info``: ``iterations``, ``cost`` (``1/2 sum |e|^2`` at the start and after each
        iteration of the chosen start's search), ``criterion``, ``stop`` (reason), the start,
        and the Gauss-Newton parameter covariance in ``info["covariance"]`` (over ``theta``,
        then the outputs' levels when estimated; the pseudo-inverse's, zero along the
        similarity directions of ``A, B, C``; with estimated initial states, the marginal
        one). ``model.uncertainty`` carries it as for :func:`sysid.nlhw` (the sandwich for
        coloured simulation errors when first used, :mod:`sysid.nonlinear.hw_uncertainty`):
        ``model.poles(std=True)``, ``model.uncertainty.propagate(fn)`` for anything else.

    Warns
    -----
    IterationLimitWarning
        When the chosen start's search stopped at ``max_iter`` while its last
        iteration still lowered the cost by more than 1e-5 of its value and by more
        than 0.01 residual variances: raise ``max_iter``. (The search itself also
        stops at statistical convergence, ``info["stop"]`` says which.)

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> u = rng.uniform(-1, 1, (600, 2)); w = np.clip(u, -0.5, 0.5); x = np.zeros(2)
    >>> y = np.zeros((600, 2))
    >>> for t in range(600):
    ...     y[t] = x; x = np.array([[0.8, 0.0], [0.1, 0.5]]) @ x + w[t]
    >>> m = sysid.nlhw_ss(sysid.IOData(u, y, 1.0), 2, input_nl=sysid.Saturation(),
    ...                   output_nl=None)  # None: the identity (a Hammerstein model)
    >>> np.round(np.sort(m.poles().real), 6).tolist()
    [0.5, 0.8]
    >>> [np.round(f.params, 6).tolist() for f in m.input_nls]
    [[-0.5, 0.5], [-0.5, 0.5]]
    """
    from ..data.iodata import IOData
    from ..models.statespace import StateSpaceModel
    from ..subspace.estimator import SubspaceEstimator, horizon_for_order
    from .choice import auto_fit, is_auto

    data = require_record(data, "nlhw_ss")
    ic = check_initial(initial_condition, "nlhw_ss")
    if is_auto(input_nl) or is_auto(output_nl):
        u0, y0 = experiment_arrays(data)[0]
        return auto_fit(data, lambda d, fi, fo, prog: nlhw_ss(
            d, order, input_nl=fi, output_nl=fo, feedthrough=feedthrough, max_iter=max_iter,
            tol=tol, progress=prog, linear=linear, offsets=offsets, initial_condition=ic),
            input_nl, output_nl,
            (u0.shape[1], y0.shape[1]), progress, "nlhw_ss")
    exps = experiment_arrays(data)
    check_magnitudes(data, "nlhw_ss")
    m, p = exps[0][0].shape[1], exps[0][1].shape[1]
    if m == 0:
        raise DataError("nlhw_ss needs at least one input (a Hammerstein-Wiener model maps "
                        "inputs to outputs); for a time series use sysid.ar or sysid.n4sid")
    if int(order) != order or order < 1:
        raise DataError(f"order must be a positive integer, got {order!r}")
    fin = _per_channel(input_nl, m, "input_nl")
    fout = _per_channel(output_nl, p, "output_nl")
    if any(isinstance(g, UserFunction) for g in fout):
        raise DataError("a UserFunction can only be an input nonlinearity")
    check_search_size(fin + fout, sum(y.size for _, y in exps), "nlhw_ss")
    require_inputs_vary(exps, "nlhw_ss", getattr(data, "input_names", None))
    # before centring (a constant output is then 0) and the linear start (named otherwise)
    require_inputs_vary(exps, "nlhw_ss", getattr(data, "output_names", None), side=1)
    # before the Rust core, which takes max_iter unsigned (OverflowError on a negative)
    max_iter, tol = as_int(max_iter, "max_iter", 0), as_nonnegative(tol, "tol")
    if undecided(offsets, fin + fout, exps):
        import copy

        return better_of_both(lambda o: nlhw_ss(
            data, order, input_nl=copy.deepcopy(input_nl), output_nl=copy.deepcopy(output_nl),
            feedthrough=feedthrough, max_iter=max_iter, tol=tol, progress=progress,
            linear=linear, offsets=o, initial_condition=ic))
    # a static curve fitted through two input levels is any curve
    warn_two_levels([u for u, _ in exps], [j for j, f in enumerate(fin) if fitted_curve(f)],
                    list(getattr(data, "input_names", [f"u{j}" for j in range(m)])), "nlhw_ss")
    shift = use_offsets(offsets, fin + fout, exps)
    raw = exps  # the record in its own units: the covariance's simulation errors
    u0, y0 = record_means(exps) if shift else (np.zeros(m), np.zeros(p))
    if shift:
        exps = centred(exps, u0, y0)
    else:  # the start's own check is silenced below with its other warnings
        check_offsets(data if isinstance(data, IOData) else
                      IOData([u for u, _ in exps], [y for _, y in exps], 1.0))
    fit_amplitudes(fout, np.vstack([y for _, y in exps]))
    records = []
    for u, y in exps:
        uu = u.copy()
        for j, f in enumerate(fin):
            if isinstance(f, UserFunction):
                uu[:, j] = f(uu[:, j])
        records.append((np.ascontiguousarray(uu), np.ascontiguousarray(y)))
    dt = float(getattr(data, "dt", 1.0) or 1.0)
    # linear start: subspace fit on the (transformed) inputs
    import warnings

    start_note = None
    if linear is None:
        lin_data = IOData([r[0] for r in records], [r[1] for r in records], dt)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            est = SubspaceEstimator(lin_data, horizon_for_order(lin_data, int(order), None),
                                    method="n4sid")
            lin = est.fit(int(order), feedthrough=bool(feedthrough))
            rho = float(np.max(np.abs(lin.poles())))
            if rho >= 1:
                # the simulation errors of an unstable block grow without bound: start from
                # the subspace fit with a stable A enforced (Maciejowski's shift) instead
                lin = est.fit(int(order), feedthrough=bool(feedthrough), stable=True)
                start_note = (f"n4sid's model of order {int(order)} was unstable (largest "
                              f"|pole| {rho:.4g}); started from it with a stable A enforced")
    else:
        lin = linear.to_statespace() if hasattr(linear, "to_statespace") else linear
        if not isinstance(lin, StateSpaceModel) or (lin.nstates, lin.ninputs, lin.noutputs) \
                != (int(order), m, p):
            raise DataError(f"linear must be a sysid.StateSpaceModel with {int(order)} states, "
                            f"{m} inputs and {p} outputs, got {linear!r}")
    A, B, C = np.asarray(lin.A), np.asarray(lin.B).copy(), np.asarray(lin.C)
    D = np.asarray(lin.D).copy() if feedthrough else None
    if np.max(np.abs(np.linalg.eigvals(A))) >= 1:
        raise DataError("the linear start (n4sid, or linear=) is unstable; try another order "
                        "or give a stable linear start")
    u_all = np.vstack([r[0] for r in records])
    fit_amplitudes(fin, u_all)
    n = int(order)
    estimate_x0 = ic == "estimate"
    x0s: list[np.ndarray] = [np.zeros(n) for _ in records]
    frees = [np.zeros_like(r[1]) for r in records]
    if estimate_x0:  # the states whose free responses fit the linear start's errors
        lin0 = HammersteinWienerSSModel([Nonlinearity()] * m, [Nonlinearity()] * p, A, B, C,
                                        D, dt)
        cols = [free_response_ss(A, C, r[1].shape[0]) for r in records]
        x0s = least_squares_states(cols, [r[1] - lin0.simulate(r[0]) for r in records])
        frees = [(o @ x).reshape(r[1].shape) for o, x, r in zip(cols, x0s, records)]
    in_starts = [f.starts(u_all[:, j]) for j, f in enumerate(fin)]
    res, th0, v_all = None, None, np.zeros((0, p))
    # start k: every channel's k-th starting point (the last one when it has fewer)
    cb, close_bar = iteration_callback(progress, "nlhw_ss", int(max_iter),
                                       iteration_printer("nlhw_ss", "sum of squares"))
    # and (when a channel's first start is not the identity) every channel near the
    # identity: the linear start itself, so that the search ends no worse than it
    lin_in = [None if isinstance(f, UserFunction) else f.linear_start(u_all[:, j])
              for j, f in enumerate(fin)]
    linear_pass = any(v is not None for v in lin_in) or any(
        type(g).linear_start is not Nonlinearity.linear_start for g in fout)
    passes = list(range(max(len(s_) for s_ in in_starts))) + ([-1] if linear_pass else [])
    try:
        for k in passes:
            if res is not None and res["stop"] == "cancelled":
                break
            Bk, Dk = B.copy(), None if D is None else D.copy()
            for j, f in enumerate(fin):  # B's column absorbs the starting nonlinearity's gain
                f.params = (in_starts[j][min(k, len(in_starts[j]) - 1)] if k >= 0
                            else in_starts[j][0] if lin_in[j] is None else lin_in[j])
                fu = f(u_all[:, j])
                if not isinstance(f, UserFunction) and float(fu @ fu) > 0 and float(
                        fu @ u_all[:, j]):
                    g = float(fu @ u_all[:, j]) / float(fu @ fu)
                    Bk[:, j] *= g
                    if Dk is not None:
                        Dk[:, j] *= g
            start = HammersteinWienerSSModel(fin, [Nonlinearity()] * p, A, Bk, C, Dk, dt)
            vs = np.vstack([start.simulate(r[0]) + e for r, e in zip(records, frees)])
            out_starts = [g.starts(vs[:, i]) if k >= 0 else
                          [g.initial(vs[:, i]) if g.linear_start(vs[:, i]) is None
                           else g.linear_start(vs[:, i])] for i, g in enumerate(fout)]
            for q in range(max(len(s_) for s_ in out_starts)):
                for i, g in enumerate(fout):
                    g.params = out_starts[i][min(q, len(out_starts[i]) - 1)]
                start = HammersteinWienerSSModel(fin, fout, A, Bk, C, Dk, dt)
                fi, fo = start.specs()
                try:
                    # about the means, the output levels are estimated with the rest
                    r = _sysid.hw_mimo_estimate(
                        records, fi, fo, int(order), bool(feedthrough),
                        start.theta.tolist() + [0.0] * (p * shift)
                        + (np.concatenate(x0s).tolist() if estimate_x0 else []),
                        int(max_iter), float(tol), cb, offsets=shift,
                        initial_state=estimate_x0)
                except DataError:
                    continue  # an inadmissible start: try the next one
                if res is None or r["cost"] < res["cost"] or r["stop"] == "cancelled":
                    res, th0, v_all = r, start.theta, vs
                if r["stop"] == "cancelled":
                    break
    finally:
        close_bar()
    if res is None:
        raise DataError("no admissible start for the Hammerstein-Wiener search; check the "
                        "order against a linear fit (sysid.n4sid)")
    th = np.asarray(res["theta"], float)
    k = 0
    for f in fin:
        f.params, k = th[k:k + np.size(f.params)], k + np.size(f.params)
    A, k = th[k:k + n * n].reshape(n, n), k + n * n
    B, k = th[k:k + n * m].reshape(n, m), k + n * m
    C, k = th[k:k + p * n].reshape(p, n), k + p * n
    if feedthrough:
        D, k = th[k:k + p * m].reshape(p, m), k + p * m
    for g in fout:
        g.params, k = th[k:k + np.size(g.params)], k + np.size(g.params)
    y0 = y0 + th[k:k + p] if shift else y0  # the operating point's levels, estimated
    k += p * shift
    states = th[k:].reshape(len(records), n) if estimate_x0 else np.zeros((len(records), n))
    info = {"method": "nlhw_ss", "iterations": int(res["iterations"]), "stop": res["stop"],
            "remaining_decrease": float(res["remaining_decrease"]),
            "n_starts": len(passes),
            "cost": list(res["history"]), "criterion": "sum of squares", "theta0": th0,
            "u_ranges": [(float(c.min()), float(c.max())) for c in u_all.T],
            "v_ranges": [(float(c.min()), float(c.max())) for c in v_all.T],
            "offsets": {"removed": shift, "u": u0.tolist(), "y": y0.tolist(),
                        "y_estimated": shift},
            "initial_condition": ic, "initial_state": [x.copy() for x in states],
            "covariance": None if res["covariance"] is None else np.asarray(res["covariance"])}
    if start_note:
        info["linear_start"] = start_note
    n_res = sum(y.size for _, y in exps)
    warn_if_capped(info, "the nlhw_ss search", int(max_iter), n_residuals=n_res)
    model = HammersteinWienerSSModel(fin, fout, A, B, C, D, dt, u_offset=u0, y_offset=y0,
                                     noise_variance=float(res["noise_variance"]), info=info,
                                     input_names=getattr(data, "input_names", None),
                                     output_names=getattr(data, "output_names", None))
    attach(model, res["covariance"], raw, list(states) if estimate_x0 else None)
    return model
