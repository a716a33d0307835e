"""``nlhw``: Hammerstein-Wiener estimation by prediction error with the shared optimiser.

Starts from a linear output-error fit (:func:`sysid.oe`) and near-identity nonlinearities,
then minimises the simulation error over every parameter with the Gauss-Newton /
Levenberg-Marquardt search of ``sysid-core`` (``optim/``), the admissible set being a stable
``F``. The sensitivities are run sample by sample in Rust (``hw/``).
"""

from __future__ import annotations

import copy
import time
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import (
    as_int,
    as_int_grid,
    as_nonnegative,
    check_magnitudes,
    experiment_arrays,
    require_inputs_vary,
    user_stacklevel,
    warn_if_capped,
)
from .._progress import iteration_callback, iteration_printer
from .._threads import one_blas_thread
from ..data.iodata import require_record
from ..data.levels import warn_two_levels
from ..errors import DataError, StabilityWarning
from ..polynomial.orders import matlab_orders
from ..validation.output_error import feedback_checked
from .hw_initial import check_initial, free_response_bf, least_squares_states
from .hw_model import (
    HammersteinWienerModel,
    Nonlinearity,
    UserFunction,
    check_search_size,
    fit_amplitudes,
    fitted_curve,
)
from .hw_uncertainty import attach
from .operating_point import better_of_both, centred, record_means, undecided, use_offsets

__all__ = ["nlhw"]


def _check_nl(nl: Any, name: str) -> Nonlinearity:
    if nl is None:
        return Nonlinearity()
    if not isinstance(nl, Nonlinearity):
        raise DataError(f"{name} must be a sysid nonlinearity (Saturation, DeadZone, "
                        f"PolynomialNonlinearity, PiecewiseLinear, SigmoidNetwork, "
                        f"UserFunction), \"auto\" or None, got {nl!r}")
    return copy.deepcopy(nl)


@feedback_checked()  # a nonlinear plant looks fed back to the test: its oe start says nothing
@one_blas_thread
def nlhw(
    data: Any,
    nb: Any,
    nf: int | None = None,
    nk: int | None = None,
    *,
    input_nl: Nonlinearity | str | None = "auto",
    output_nl: Nonlinearity | str | None = "auto",
    max_iter: int = 100,
    tol: float = 1e-10,
    progress: bool | None | Callable[..., Any] = None,
    offsets: bool | str = "auto",
    initial_condition: str = "zero",
) -> HammersteinWienerModel:
    """Hammerstein-Wiener model ``y = g(B/F f(u(t - nk))) + e`` (one input, one output).

    Parameters
    ----------
    data : IOData or (u, y)
        Estimation record (one input, one output; several experiments are used together).
    nb, nf, nk : int
        Orders of ``B`` and ``F`` and the input delay of the linear block (``nk`` default 1);
        or MATLAB's one vector ``[nb, nf, nk]`` as ``nb``.
    input_nl, output_nl : Nonlinearity, "auto" or None
        :class:`~sysid.Saturation`, :class:`~sysid.DeadZone`,
        :class:`~sysid.PolynomialNonlinearity`, :class:`~sysid.PiecewiseLinear`,
        :class:`~sysid.SigmoidNetwork`, or (input only) a fixed :class:`~sysid.UserFunction`;
        ``None`` is the identity (``output_nl=None``: Hammerstein, ``input_nl=None``: Wiener).
        ``"auto"`` (default): the identity or a 3-unit sigmoid network, whichever the
        record's held-out blocks insist on (:mod:`sysid.nonlinear.choice`: the networks
        only where they simulate the blocks better beyond their scatter; every candidate is
        fitted on the record less each block, so this costs about ten fits: give the
        nonlinearities to fit once); ``info["nonlinearity_choice"]`` holds the table and the
        reason.
    max_iter, tol : int, float
        Optimiser iterations and step/gradient tolerance.
    progress : bool or callable, optional
        As for :func:`sysid.pem`: a bar (``None``: on a terminal only; ``True``: also one
        line per iteration in a log), ``False`` for silence, or a callable getting
        ``(iteration, cost, step_norm, gradient_norm, damping)`` after every accepted step of
        every start's search (``False`` returned stops the search and skips the remaining
        starts).
    offsets : "auto", True or False
        Fit about the record's means and keep them in the model (its operating point,
        :mod:`sysid.nonlinear.operating_point`): ``"auto"`` when a channel's mean is farther
        from zero than its standard deviation and both nonlinearities are sigmoid networks or
        the identity; with a nonlinearity whose levels are in the data's units (a saturation,
        dead zone, polynomial, ...) on such a record, both ways are fitted and the lower sum
        of squares kept (``info["offsets"]["auto"]`` says which). About the means, the
        output level of the operating point (``y_offset``) is estimated with the other
        parameters (the input's is the mean: a shift of it is a shift of the nonlinearity).
    initial_condition : "zero" or "estimate"
        MATLAB's ``InitialCondition``: every experiment from rest (default), or its linear
        block's initial state estimated with the other parameters (for a record that starts
        mid-response; :mod:`sysid.nonlinear.hw_initial`): ``h`` with ``max(nf, nk + nb - 1)``
        entries, SciPy's ``lfilter(r_[zeros(nk), b], r_[1, f], w, zi=h)`` state.
        ``info["initial_condition"]`` says which, ``info["initial_state"]`` holds one ``h``
        per experiment (zeros from rest).

    Returns
    -------
    HammersteinWienerModel
        With ``info``: ``iterations``, ``cost`` (``1/2 sum e^2`` at the start and after each
        iteration of the chosen start's search), ``criterion``, ``stop`` (reason), the start,
        and the Gauss-Newton parameter covariance in ``info["covariance"]`` (over ``theta``,
        then the output level when it is estimated; with estimated initial states, the
        marginal one). ``model.uncertainty`` (a :class:`~sysid.ParameterUncertainty` over the
        same parameters, ``build(theta)`` the model) carries it, becoming the sandwich
        covariance for coloured simulation errors when first used
        (:mod:`sysid.nonlinear.hw_uncertainty`; ``info["covariance_method"]`` says which):
        ``model.poles(std=True)``, ``model.uncertainty.propagate(fn)`` for anything else.
        ``info["seconds"]``: the linear start's, each start's search and the chosen start's.

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
    >>> u = rng.uniform(-1, 1, 600)
    >>> w = np.clip(u, -0.4, 0.4); y = np.zeros(600)
    >>> for t in range(1, 600): y[t] = 0.8 * y[t - 1] + 0.5 * w[t - 1]
    >>> m = sysid.nlhw(sysid.IOData(u, y, 1.0), 1, 1, 1, input_nl=sysid.Saturation(),
    ...                output_nl=None)  # None: the identity (a Hammerstein model)
    >>> np.round(m.input_nl.params, 6).tolist(), np.round(m.poles().real, 6).tolist()
    ([-0.4, 0.4], [0.8])
    """
    from ..polynomial.estimators import oe
    from .choice import auto_fit, is_auto

    data = require_record(data, "nlhw")
    ic = check_initial(initial_condition, "nlhw")
    exps = experiment_arrays(data)
    if exps[0][0].shape[1] != 1 or exps[0][1].shape[1] != 1:
        raise DataError(f"nlhw handles one input and one output (the record has "
                        f"{exps[0][0].shape[1]} and {exps[0][1].shape[1]}); for several use "
                        "sysid.nlhw_ss (a state-space linear block), or select channels with "
                        "data.select(...)")
    nb, nf, nk = matlab_orders("nlhw", data, nb, nf=nf, nk=nk)
    if is_auto(input_nl) or is_auto(output_nl):
        return auto_fit(data, lambda d, fi, fo, prog: nlhw(
            d, nb, nf, nk, input_nl=fi, output_nl=fo, max_iter=max_iter, tol=tol,
            progress=prog, offsets=offsets, initial_condition=ic), input_nl, output_nl, (0, 0),
            progress, "nlhw")
    check_magnitudes(data, "nlhw")
    require_inputs_vary(exps, "nlhw", getattr(data, "input_names", None))
    # before centring (a constant output is then 0) and the linear start (named oe)
    require_inputs_vary(exps, "nlhw", getattr(data, "output_names", None), side=1)
    # the orders as arx and oe take them: a scalar or a (1, 1) array of integers
    nb, nf, nk = (as_int_grid(v, (1, 1), name)[0][0] for v, name in
                  ((nb, "nb"), (nf, "nf"), (nk, "nk")))
    if nb < 1:
        raise DataError(f"nb must be a positive integer, got {nb!r}")
    max_iter, tol = as_int(max_iter, "max_iter", 0), as_nonnegative(tol, "tol")
    fin, fout = _check_nl(input_nl, "input_nl"), _check_nl(output_nl, "output_nl")
    check_search_size([fin, fout], sum(y.size for _, y in exps), "nlhw")
    if undecided(offsets, [fin, fout], exps):
        import copy

        return better_of_both(lambda o: nlhw(
            data, nb, nf, nk, input_nl=copy.deepcopy(input_nl),
            output_nl=copy.deepcopy(output_nl), max_iter=max_iter, tol=tol, progress=progress,
            offsets=o, initial_condition=ic))
    # a static curve fitted through two input levels is any curve
    warn_two_levels([u for u, _ in exps], [0] if fitted_curve(fin) else [],
                    list(getattr(data, "input_names", ["u0"])), "nlhw")
    shift = use_offsets(offsets, [fin, fout], exps)
    raw = exps  # the record in its own units: the covariance's simulation errors
    u0, y0 = record_means(exps) if shift else (np.zeros(1), np.zeros(1))
    if shift:
        exps = centred(exps, u0, y0)
    fit_amplitudes([fout], np.concatenate([y for _, y in exps]))
    estimate_x0 = ic == "estimate"
    nh = max(int(nf), int(nk) + int(nb) - 1)  # the linear block's initial state (h)
    n_par = int(nb) + int(nf) + sum(np.size(getattr(f, "params", ())) for f in (fin, fout)
                                     if not isinstance(f, UserFunction))
    n_par += nh * len(exps) * estimate_x0
    n_samples = sum(len(y) for _, y in exps)
    if n_par >= n_samples:  # before any regressor is allocated
        raise DataError(f"nlhw with these orders and nonlinearities has {n_par} parameters "
                        f"but the record has {n_samples} samples; lower the orders or the "
                        "nonlinearities' sizes (degree, units, breakpoints)")
    if isinstance(fout, UserFunction):
        raise DataError("a UserFunction can only be the input nonlinearity")
    records = []
    for u, y in exps:
        uu = fin(u[:, 0]) if isinstance(fin, UserFunction) else u[:, 0]
        records.append((np.ascontiguousarray(uu), np.ascontiguousarray(y[:, 0])))
    dt = float(getattr(data, "dt", 1.0) or 1.0)
    # linear start: output error on the (transformed) input
    from ..data.iodata import IOData

    t_lin = time.perf_counter()
    with warnings.catch_warnings(record=True) as said:  # a start: where its F sits is the
        warnings.simplefilter("always")  # search's to move; the rest is said as nlhw's
        lin = oe(IOData([r[0][:, None] for r in records], [r[1][:, None] for r in records],
                        dt), int(nb), int(nf), int(nk), initial_condition="zero")
    for w in said:
        if not issubclass(w.category, StabilityWarning):
            text = str(w.message)
            text = text[4:] if text.startswith("oe: ") else text
            warnings.warn(w.category(f"nlhw (its linear start, an output-error fit of the same "
                                     f"orders): {text}"), stacklevel=user_stacklevel())
    t_lin = time.perf_counter() - t_lin
    b0, f0 = np.asarray(lin.b[0][0], float), np.asarray(lin.f[0][0], float)
    u_all = np.concatenate([r[0] for r in records])
    fit_amplitudes([fin], u_all[:, None])
    h0: list[np.ndarray] = [np.zeros(nh) for _ in records]
    if estimate_x0:  # the states whose free responses fit the linear start's errors
        frees = [free_response_bf(f0, nh, r[1].size) for r in records]
        h0 = least_squares_states(frees, [r[1] - np.asarray(lin.simulate(r[0][:, None]),
                                                            float)[:, 0] for r in records])
        free = np.concatenate([o @ h for o, h in zip(frees, h0)])
    else:
        free = np.zeros(u_all.size)
    lin_b = b0
    res, theta0, x_all = None, None, np.zeros(0)
    searches: list[float] = []  # each start's search, seconds (the chosen one's: t_chosen)
    t_chosen = 0.0
    cb, close_bar = iteration_callback(progress, "nlhw", int(max_iter),
                                       iteration_printer("nlhw", "sum of squares"))
    # every start of the input nonlinearity with every start of the output one, and (when
    # either's first start is not the identity) both near the identity: the linear model
    lin_in = None if isinstance(fin, UserFunction) else fin.linear_start(u_all)
    pairs: list[tuple[np.ndarray, Any]] = [(a, None) for a in fin.starts(u_all)]
    linear_pair = lin_in is not None or type(fout).linear_start is not Nonlinearity.linear_start
    if linear_pair:
        pairs.append((fin.initial(u_all) if lin_in is None else lin_in, "linear"))
    try:
        for start_in, kind in pairs:
            if res is not None and res["stop"] == "cancelled":
                break
            fin.params = start_in
            # B absorbs the gain of the starting nonlinearity: B f(u) ~ B_linear u
            fu = fin(u_all)
            b0 = lin_b
            if not isinstance(fin, UserFunction) and float(fu @ fu) > 0 and float(fu @ u_all):
                b0 = lin_b * float(fu @ u_all) / float(fu @ fu)
            start = HammersteinWienerModel(fin, Nonlinearity(), b0, f0, int(nk), dt)
            xs = np.concatenate([start.signals(r[0])[2] for r in records]) + free
            lin_out = fout.linear_start(xs) if kind else None
            for start_out in ([fout.initial(xs) if lin_out is None else lin_out] if kind
                              else fout.starts(xs)):
                # about the means, the output level is estimated with the rest (from 0)
                th0 = np.concatenate([start_in, b0, f0, start_out, np.zeros(int(shift)),
                                      *(h0 if estimate_x0 else [])])
                t_search = time.perf_counter()
                try:
                    r = _sysid.hw_estimate(records, fin.spec(), fout.spec(), int(nb), int(nf),
                                           int(nk), th0.tolist(), int(max_iter), float(tol), cb,
                                           offset=shift, initial_state=estimate_x0)
                except DataError:
                    continue  # an inadmissible start (unstable F): try the next one
                searches.append(time.perf_counter() - t_search)
                if res is None or r["cost"] < res["cost"] or r["stop"] == "cancelled":
                    res, theta0, x_all, t_chosen = r, th0, xs, searches[-1]
                if r["stop"] == "cancelled":
                    break
    finally:
        close_bar()
    if res is None:
        raise DataError("no admissible start for the Hammerstein-Wiener search; check nb, nf "
                        "and nk against a linear fit (sysid.oe)")
    th = np.asarray(res["theta"], float)
    na, nbeta = fin.params.size, fout.params.size
    n_model = na + int(nb) + int(nf) + nbeta + int(shift)
    states = th[n_model:].reshape(len(records), nh) if estimate_x0 else \
        np.zeros((len(records), nh))
    th = th[:n_model]
    fin.params = th[:na]
    b, f = th[na:na + int(nb)], th[na + int(nb):na + int(nb) + int(nf)]
    fout.params = th[na + int(nb) + int(nf):na + int(nb) + int(nf) + nbeta]
    level = float(th[-1]) if shift else 0.0  # the operating point's level, estimated
    info = {"method": "nlhw", "iterations": int(res["iterations"]), "stop": res["stop"],
            "remaining_decrease": float(res["remaining_decrease"]),
            "cost": list(res["history"]), "criterion": "sum of squares", "theta0": theta0,
            "n_starts": len(fin.starts(u_all)) * len(fout.starts(x_all)) + int(linear_pair),
            "covariance": None if res["covariance"] is None else np.asarray(res["covariance"]),
            "u_range": (float(u_all.min()), float(u_all.max())),
            "x_range": (float(x_all.min()), float(x_all.max())), "n_output_params": nbeta,
            "offsets": {"removed": shift, "u": float(u0[0]), "y": float(y0[0] + level),
                        "y_estimated": shift},
            "initial_condition": ic, "initial_state": [h.copy() for h in states],
            "seconds": {"linear_start": t_lin, "searches": searches,
                        "chosen_start_search": t_chosen}}
    warn_if_capped(info, "the nlhw search", int(max_iter), n_residuals=n_samples)
    model = HammersteinWienerModel(fin, fout, b, f, int(nk), dt,
                                   u_offset=float(u0[0]), y_offset=float(y0[0] + level),
                                   noise_variance=float(res["noise_variance"]), info=info,
                                   input_names=getattr(data, "input_names", None),
                                   output_names=getattr(data, "output_names", None))
    attach(model, res["covariance"], raw, list(states) if estimate_x0 else None)
    return model
