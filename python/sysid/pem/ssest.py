"""The one-call state-space estimator :func:`ssest`: the best subspace start (several
weightings, with and without ``x0``), refined by :func:`sysid.pem`."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from .._checks import as_int, as_nonnegative, recorded, reissue
from .._threads import one_blas_thread
from ..errors import DataError, OffsetWarning, SysidError
from ..models.frd import FRD
from ..models.statespace import StateSpaceModel
from ..subspace.estimator import CLOSED_LOOP, METHODS, SubspaceEstimator, horizon_for_order
from ..subspace.feedthrough import (
    check_feedthrough,
    choose_feedthrough,
    default_feedthrough,
    warn_if_left_out,
)
from ..validation.output_error import output_error
from .pem import _experiments, pem, pem_loss
from .ssform import StateSpaceStructure

__all__ = ["ssest"]


@output_error("ssest", when=lambda a: a["focus"] == "simulation" or a["noise"] == "none")
@one_blas_thread
def ssest(
    data: Any,
    order: Any = "auto",
    *,
    focus: str = "prediction",
    feedthrough: Any = None,
    x0: Any = "estimate",
    noise: str = "estimate",
    horizon: int | None = None,
    methods: tuple[str, ...] = ("moesp", "n4sid", "cva"),
    method: str | None = None,
    max_iter: int = 50,
    tol: float = 1e-6,
    regularization: dict[str, Any] | None = None,
    progress: bool | None | Callable[..., Any] = None,
    enforce_stability: bool | None = None,
    periods: int | str | None = None,
    transient: int | None = None,
    input_delay: Any = None,
    form: str | None = None,
) -> StateSpaceModel:
    """Estimate a state-space model: the best subspace start, refined by :func:`pem`.

    The candidates are the subspace weightings in ``methods``, each with ``B, D`` from the
    regression on the compressed data and (single-experiment records) from least squares on
    the data jointly with ``x0``; the one with the lowest cost that :func:`pem` will minimise
    (the determinant of the error covariance, initial states fitted) is refined.

    Parameters
    ----------
    data : IOData, (u, y) or FRD
    order : int, "auto", sequence of int, StateSpaceModel or StateSpaceStructure
        Model order. A model (MATLAB's ``ssest(data, init_sys)``) is the start, refined by
        :func:`pem` with these options; a :func:`sysid.ssform` structure (fixed entries, a
        canonical form) has its free parameters estimated (:mod:`sysid.pem.structured`).
        ``"auto"`` (default): the order whose subspace models best simulate
        parts of the record held out (:meth:`SubspaceEstimator.order_selection`); a sequence
        (``range(1, 11)``): each order refined on the whole record, the one with the lowest
        BIC of its simulation errors wins (:func:`sysid.identify.structure.refined_order`).
        Table and reason in ``info["order_selection"]``.
    feedthrough : bool or "auto", optional
        Estimate ``D``. Default: ``D = 0`` at a given order (MATLAB's ``ssest`` default, and
        the same for every sysid state-space estimator), chosen with the order (as
        ``"auto"``) when the order is ``"auto"`` or a sequence. ``True`` estimates ``D``;
        ``False``: ``D = 0``; ``"auto"`` decides from the data: ``D`` only when it raises the
        held-out simulation fit of the subspace models by more than 0.5 points
        (:func:`sysid.subspace.feedthrough.choose_feedthrough`, recorded in
        ``info["feedthrough_selection"]``), then refined with that choice. Left out at a
        given order, ``D`` is checked for: a :class:`~sysid.errors.FeedthroughWarning` when
        the record shows a direct term (:func:`sysid.subspace.feedthrough.warn_if_left_out`).
    focus, x0, noise, max_iter, tol, regularization, progress, enforce_stability
        As for :func:`pem` (the candidates are scored by :func:`pem_loss`).
    horizon : int, optional
        Subspace horizon (default :func:`sysid.default_horizon`, raised to the smallest
        that allows ``order`` when it does not and the data do:
        :func:`~sysid.subspace.estimator.horizon_for_order`).
    methods : tuple of str
        Subspace weightings tried for the start. When the input repeats (2 or more whole
        periods, :func:`sysid.detect_period`), the subspace fit of the averaged response on
        the excited lines (:func:`periodic_start`) is one more candidate, scored by the
        same loss (``info["start"]["method"] == "frd_subspace"`` when it wins).
    method : str, optional
        One subspace method for the start (overrides ``methods``, and no start from the
        averaged lines is tried); ``"pbsid"`` or
        ``"ssarx"`` for closed-loop data (their start is consistent under feedback, and the
        start's ``B, D`` are then not re-fitted on the data with ``x0``, which would be an
        output-error fit).
    periods : int or "auto", optional
        Periodic data (at least 2 whole periods after the ``transient`` ones): the
        candidates (the subspace weightings, and the frequency-domain subspace fit of the
        averaged response, :func:`sysid.frd_subspace`) are scored on the excited lines and
        the best is refined there (:func:`pem` with ``periods``; ``focus``, ``x0`` and
        ``noise`` do not apply). ``"auto"``: the period detected from the input
        (:func:`sysid.detect_period`); not periodic: the time-domain estimate, with the
        reason in ``info["pem"]["periodicity"]``.
    transient : int, optional
        Leading periods dropped: default 1 with ``periods="auto"``, 0 with a declared
        ``periods`` (as :func:`pem`).
    form : {"canonical", "companion", "modal"}, optional
        MATLAB's ``ssest(..., 'Form', f)``: the model fitted as without it, then its
        parameters estimated again in that form (:func:`sysid.ssform`; ``D`` and ``K`` free
        as fitted): the same model class with an identifiable parameter vector, its table in
        ``info["parameters"]`` and ``info["structure"]``.
    input_delay : int, sequence of int or "auto", optional
        Known input delays in samples (MATLAB's ``InputDelay``; one for all inputs or one
        each; ``"auto"``: from :func:`sysid.delayest`): the model is fitted to the shifted
        inputs and returned with the delays absorbed as states
        (:mod:`sysid.models.input_delay`; ``info["delay_free"]``, ``info["input_delay"]``).

    Frequency-response data (an :class:`sysid.FRD`, MATLAB's ``ssest(idfrd, n)``): the
    frequency-domain subspace fits (:func:`sysid.frd_subspace`, weighted by the lines' std
    and unweighted) are scored on the lines and the best stable one is refined there
    (:func:`pem` on the FRD: by its ``std``, or uniformly without one); ``order`` an integer
    or ``"auto"`` (:func:`sysid.frd_subspace`'s), ``feedthrough`` ``True`` or ``False``
    (default), and ``focus``, ``x0``, ``noise`` do not apply (an output-error fit of the
    response).

    Returns
    -------
    StateSpaceModel
        With ``info["pem"]`` and ``info["start"]`` (the chosen candidate and every
        candidate's loss).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> true = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], K=[[0.5]])
    >>> u = rng.standard_normal(500)
    >>> e = 0.1 * rng.standard_normal((500, 1))
    >>> y = true.simulate(u) + 0.0
    >>> m = sysid.ssest(sysid.IOData(u=u, y=y + e), order=1)
    >>> bool(abs(m.poles()[0] - 0.8) < 0.05)
    True
    """
    as_int(max_iter, "max_iter", 0), as_nonnegative(tol, "tol")  # before any fit
    if input_delay is not None:  # MATLAB's InputDelay: fitted on the shifted inputs
        from ..models.input_delay import delayed_fit

        if isinstance(data, FRD) or hasattr(order, "nstates"):
            raise DataError("input_delay applies to a time record and an order: leave it out "
                            "for an FRD or a start model")
        return delayed_fit(_experiments(data), input_delay, feedthrough, lambda shifted: ssest(
            shifted, order, focus=focus, feedthrough=feedthrough, x0=x0, noise=noise,
            horizon=horizon, methods=methods, method=method, max_iter=max_iter, tol=tol,
            regularization=regularization, progress=progress,
            enforce_stability=enforce_stability, periods=periods, transient=transient,
            form=form))
    if form is not None:  # MATLAB's 'Form': the free fit, then estimated in the form
        from .ssform import ssform
        from .structured import pem_structured

        free_fit = ssest(data, order, focus=focus, feedthrough=feedthrough, x0=x0, noise=noise,
                         horizon=horizon, methods=methods, method=method, max_iter=max_iter,
                         tol=tol, regularization=regularization, progress=progress,
                         enforce_stability=enforce_stability, periods=periods,
                         transient=transient)
        s = ssform(free_fit, form, feedthrough=bool(np.any(free_fit.D)),
                   noise="estimate" if free_fit.K is not None and focus == "prediction"
                   else "none")
        return pem_structured(data, s, focus=focus, x0=x0, max_iter=max_iter, tol=tol,
                              progress=progress, caller="ssest")
    if isinstance(order, StateSpaceStructure):  # MATLAB's ssest(data, init_sys)
        from .structured import pem_structured

        given = [k for k, v, d in (("feedthrough", feedthrough, None), ("noise", noise,
                 "estimate"), ("horizon", horizon, None), ("regularization", regularization,
                 None), ("enforce_stability", enforce_stability, None), ("periods", periods,
                 None), ("transient", transient, None)) if v is not d and v != d]
        return pem_structured(data, order, focus=focus, x0=x0, max_iter=max_iter, tol=tol,
                              progress=progress, caller="ssest", given=given, refine=pem)
    if isinstance(order, StateSpaceModel):  # MATLAB's ssest(data, init_sys): refined by pem
        if horizon is not None or method is not None:
            raise DataError("ssest refines a start model without a subspace step: leave "
                            "horizon and method out")
        return pem(data, order, focus=focus, feedthrough=feedthrough, x0=x0, noise=noise,
                   max_iter=max_iter, tol=tol, regularization=regularization,
                   progress=progress, enforce_stability=enforce_stability, periods=periods,
                   transient=transient)
    if hasattr(order, "nstates"):  # another model (its repr may not print)
        raise DataError(f"ssest takes an order, a sysid.StateSpaceModel or a sysid.ssform "
                        f"structure, got a {type(order).__name__}")
    if isinstance(data, FRD):
        return _ssest_frd(data, order, feedthrough, horizon, max_iter, tol, progress,
                          regularization, periods, transient)
    data = _experiments(data)
    if not isinstance(order, str) and np.ndim(order) == 0:
        order = as_int(order, "order", 1)  # inf, nan, 2.5: before any data are compressed
    if isinstance(methods, str):
        methods = (methods,)  # one method named alone
    unknown = [m for m in ((method,) if method is not None else tuple(methods))
               if m not in METHODS]
    if unknown:
        raise DataError(f"unknown subspace method(s) {unknown}: choose from {list(METHODS)}")
    ft_default = feedthrough is None  # D left out by default at a given order: checked below
    feedthrough = default_feedthrough(feedthrough, order)
    if periods is not None or transient is not None:
        from .periodic import resolve_periods

        frd, periodicity = resolve_periods(data, periods, transient)
        if frd is not None:
            model = _ssest_periodic(data, order, frd, feedthrough, horizon, methods, method,
                                    max_iter, tol, progress, regularization)
        else:
            model = ssest(data, order, focus=focus, feedthrough=feedthrough, x0=x0,
                          noise=noise, horizon=horizon, methods=methods, method=method,
                          max_iter=max_iter, tol=tol, regularization=regularization,
                          progress=progress, enforce_stability=enforce_stability)
        model.info.setdefault("pem", {})["periodicity"] = periodicity
        return model
    if check_feedthrough(feedthrough) == "auto":
        # decided once from the data (the rule every estimator shares), then a fixed choice
        with warnings.catch_warnings():  # the fit below says it (once, re-emitted)
            warnings.simplefilter("ignore", OffsetWarning)
            chooser = SubspaceEstimator(data, horizon_for_order(data, order, horizon),
                                        method=method or "moesp")
        use, why = choose_feedthrough(chooser, order)
        kw = dict(focus=focus, x0=x0, noise=noise, horizon=horizon, methods=methods,
                  method=method, max_iter=max_iter, tol=tol, regularization=regularization,
                  progress=progress, enforce_stability=enforce_stability)
        model, said = recorded(lambda: ssest(data, order, feedthrough=use, **kw))
        if use:
            kept, why, said_without = _confirm_feedthrough(data, order, model, why, kw)
            said = said if kept is model else said_without
            model = kept
        # the warnings of the model returned, once, at the caller's line (not those of the
        # fit the choice of D left out: two "stopped at max_iter" for one call)
        reissue(said)
        model.info["feedthrough_selection"] = why
        return model
    if isinstance(order, str) or np.ndim(order):
        # order="auto" or a range of orders: chosen from the data
        from ..identify.structure import ssest_select

        return ssest_select(data, order, focus=focus, feedthrough=feedthrough, x0=x0,
                            noise=noise, horizon=horizon, methods=methods, method=method,
                            max_iter=max_iter, tol=tol, regularization=regularization,
                            progress=progress, enforce_stability=enforce_stability)
    order = as_int(order, "order", 1)
    est = SubspaceEstimator(data, horizon_for_order(data, order, horizon))
    candidates = []
    why: list[Exception] = []  # why the weightings failed (the order error names the bound)

    names = methods if method is None else (method,)
    for name in names:
        x0_options = (False, True) if data.n_experiments == 1 else (False,)
        if name in CLOSED_LOOP:
            x0_options = (False,)
        for use_x0 in x0_options:
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    cand = est.fit(order, method=name, feedthrough=feedthrough, x0=use_x0)
            except Exception as e:  # noqa: BLE001 - a failing weighting is just not a candidate
                if method is not None:
                    raise
                why.append(e)
                continue
            try:
                loss = pem_loss(data, cand, focus=focus, feedthrough=feedthrough, x0=x0,
                                noise=noise, enforce_stability=enforce_stability)
            except SysidError:
                loss = float("inf")
            candidates.append((loss, name, use_x0, cand))
    periodic = periodic_start(data, order, feedthrough) if method is None else None
    if periodic is not None:
        try:
            loss = pem_loss(data, periodic, focus=focus, feedthrough=feedthrough, x0=x0,
                            noise=noise, enforce_stability=enforce_stability)
        except SysidError:
            loss = float("inf")
        candidates.append((loss, "frd_subspace", False, periodic))
    if not candidates:
        _no_start(why)
    candidates.sort(key=lambda c: c[0])
    best = candidates[0]
    # the direct-term check compares subspace fits of one weighting with and without D: the
    # best time-domain weighting's (the frequency-domain start has no time-domain twin)
    td = next((c for c in candidates if c[1] != "frd_subspace"), None)
    check = (warn_if_left_out(est, order, td[1], td[3], "ssest", x0=td[2])
             if ft_default and td is not None else None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OffsetWarning)  # said once, by the subspace start
        model = pem(data, best[3], focus=focus, feedthrough=feedthrough, x0=x0, noise=noise,
                    max_iter=max_iter, tol=tol, regularization=regularization,
                    progress=progress, enforce_stability=enforce_stability)
    model.info["start"] = {
        "method": best[1],
        "bd_x0": best[2],
        "losses": {f"{c[1]}{'+x0' if c[2] else ''}": c[0] for c in candidates},
    }
    if check is not None:
        model.info["feedthrough_check"] = check
    return model


def periodic_start(data: Any, order: int, feedthrough: Any) -> StateSpaceModel | None:
    """The frequency-domain subspace fit of the averaged response on the excited lines
    (:func:`sysid.frd_subspace`) when the input repeats (:func:`sysid.detect_period`: 2 or
    more whole periods), else ``None``.

    One more start candidate for :func:`ssest`'s time-domain search, scored by the same loss
    as the subspace weightings: with a periodic input the averaged lines hold the response
    at the excited frequencies with the noise averaged out, and a model fitted to them has
    the lightly damped modes a time-domain subspace fit of the same order can miss (the
    F-16 ground vibration record: 3 of its 6 structural modes at the default horizon). The
    first period is dropped as a transient when 3 or more are whole. The lines are weighted
    by their inverse noise variance when it has more than 4 real degrees of freedom (4 or
    more periods): from fewer, its inverse has no finite variance (no finite mean from 2)
    and a few lines would take all the weight; uniform weights then. The detection costs
    about 0.1 s per 10^5 samples of three inputs, once per order ``ssest`` fits.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.pem.ssest import periodic_start
    >>> u = sysid.multisine(256, band=(0, 0.4), periods=4, seed=1)
    >>> g = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0], [0.0]], [[1.0, 0.0]])
    >>> m = periodic_start(sysid.IOData(u=u, y=g.simulate(u)), 2, False)
    >>> bool(np.allclose(np.sort_complex(m.poles()), np.sort_complex(g.poles()), atol=1e-6))
    True
    >>> periodic_start(sysid.IOData(u=np.random.default_rng(0).standard_normal(512),
    ...                             y=np.zeros(512)), 2, False) is None
    True
    """
    from ..data.periodicity import detect, whole_periods
    from ..subspace.frd_subspace import frd_subspace
    from .periodic import frequency_weights, periodic_lines

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            found, _ = detect(data)
            if found is None or found.periods < 2:
                return None
            frd = periodic_lines(whole_periods(data, found), found.periods,
                                 1 if found.periods >= 3 else 0)
            weights = frequency_weights(frd) if frd.dof is not None and frd.dof > 4 else None
            return frd_subspace(frd, order, weights=weights, feedthrough=bool(feedthrough))
    except SysidError:
        return None


def _ssest_frd(frd: FRD, order: Any, feedthrough: Any, horizon: int | None, max_iter: int,
               tol: float, progress: Any, regularization: Any, periods: Any,
               transient: Any) -> StateSpaceModel:
    """:func:`ssest` on frequency-response data: the frequency-domain subspace fits (weighted
    by the lines' std, and unweighted) scored on the lines, the best stable one refined
    there by :func:`pem`."""
    from ..subspace.frd_subspace import frd_subspace
    from .periodic import frequency_weights, lines_cost, with_line_weights

    if regularization is not None or periods is not None or transient is not None:
        raise DataError("an FRD is fitted on its lines: regularization, periods= and "
                        "transient= do not apply; leave them out")
    if not (isinstance(order, str) and order == "auto") and np.ndim(order) != 0:
        raise DataError("with frequency-response data give the order as an integer or "
                        "'auto' (frd_subspace's gap of the singular values); for an order "
                        "search estimate from the time record")
    ft = False if feedthrough is None else feedthrough
    ft_why = None
    if frd.dt is not None and check_feedthrough(ft) == "auto":  # on held-out lines
        from ..subspace.feedthrough_frd import choose_feedthrough_frd

        ft, ft_why = choose_feedthrough_frd(frd, order, lambda g, n, d: frd_subspace(
            g, n, feedthrough=d))
    ft = bool(ft)
    if frd.dt is None:
        raise DataError("ssest fits a discrete model and needs the FRD's sample time: "
                        "pass dt= to sysid.FRD (for a continuous model use sysid.tfest or "
                        "sysid.frd_subspace(frd, order, continuous=True))")
    scored_on, how = with_line_weights(frd)
    weights = frequency_weights(scored_on) if how == "noise" else None
    why: list[Exception] = []
    candidates = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, wts in (("frd_subspace weighted", weights), ("frd_subspace", None)):
            if name.endswith("weighted") and wts is None:
                continue
            try:
                cand = frd_subspace(frd, order, horizon=horizon, weights=wts, feedthrough=ft)
            except SysidError as e:
                why.append(e)
                continue
            order = cand.nstates  # "auto" decided once, by the first fit
            stable = np.max(np.abs(cand.poles()), initial=0.0) < 1
            candidates.append((lines_cost(scored_on, cand) if stable else np.inf, name, cand))
    if not candidates:
        _no_start(why)
    candidates.sort(key=lambda c: c[0])
    model = pem(frd, candidates[0][2], feedthrough=ft, max_iter=max_iter, tol=tol,
                progress=progress)
    model.info["start"] = {"method": candidates[0][1], "bd_x0": False,
                           "losses": {c[1]: c[0] for c in candidates}}
    if ft_why is not None:
        model.info["feedthrough_selection"] = ft_why
    if feedthrough is None:  # the default, no D: checked against the subspace fit with D
        from ..subspace.feedthrough_frd import warn_if_left_out_frd

        warn_if_left_out_frd(frd, model, lambda d: frd_subspace(
            frd, order, horizon=horizon, weights=weights, feedthrough=d), "ssest")
    return model


def _no_start(why: list[Exception]) -> None:
    """No subspace weighting gave a start: the order error when there is one (it names the
    largest order the horizon allows), else a plain one."""
    from ..errors import OrderError

    for e in why:
        if isinstance(e, OrderError):
            raise OrderError(f"no subspace start for ssest: {e}") from e
    raise DataError("no subspace start could be computed for this order; lower the order"
                    + (f" ({type(why[0]).__name__}: {why[0]})" if why else ""))


def _confirm_feedthrough(data: Any, order: Any, model: StateSpaceModel, why: dict[str, Any],
                         kw: dict[str, Any]
                         ) -> tuple[StateSpaceModel, dict[str, Any], list[Any]]:
    """The refined model with ``D`` (chosen by the subspace models' held-out fits) against
    the refined model without it, by the BIC of their simulation errors on the record
    (:func:`sysid.identify.board.bic`, ``D`` counted): ``D`` is kept only when the refined
    models confirm it. The refinement can spend a direct term on what the subspace models
    left (a prediction-focus fit has no reason to keep a simulation-friendly ``D``), and
    then simulates new data worse than the model without it."""
    from ..identify.board import bic

    try:
        without, said = recorded(lambda: ssest(data, order, feedthrough=False, **kw))
        b_with, b_without = bic(model, data), bic(without, data)
    except SysidError:
        return model, why, []
    keep = bool(b_with < b_without)
    why = dict(why, feedthrough=keep, refined_bic={"with D": b_with, "without D": b_without},
               reason=why["reason"] + f"; refined models: BIC {b_with:.4g} with D, "
               f"{b_without:.4g} without: " + ("D kept" if keep else "D = 0"))
    return (model if keep else without), why, said


def _ssest_periodic(data: Any, order: Any, frd: Any, feedthrough: Any,
                    horizon: int | None, methods: tuple[str, ...], method: str | None,
                    max_iter: int, tol: float, progress: Any,
                    regularization: Any) -> StateSpaceModel:
    """:func:`ssest` on the excited lines of periodic data: the stable candidate with the
    lowest weighted misfit on the lines, refined there."""
    from ..subspace.frd_subspace import frd_subspace
    from .periodic import frequency_weights, lines_cost

    if regularization is not None:
        raise DataError("regularization does not apply to the frequency-domain refinement of "
                        "periodic data; leave it out, or call ssest without periods=")
    if isinstance(order, str) or np.ndim(order):
        raise DataError("with periods= give the order as an integer (the order search runs "
                        "in the time domain: call ssest without periods= to choose it)")
    order = as_int(order, "order", 1)
    ft = check_feedthrough(feedthrough)
    if ft == "auto":
        ft, _ = choose_feedthrough(SubspaceEstimator(data, horizon), order)
    est = SubspaceEstimator(data, horizon)
    candidates = []
    why: list[Exception] = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name in methods if method is None else (method,):
            try:
                candidates.append((name, est.fit(order, method=name, feedthrough=ft)))
            except SysidError as e:
                why.append(e)
                continue
        try:
            candidates.append(("frd_subspace", frd_subspace(
                frd, order, weights=frequency_weights(frd), feedthrough=bool(ft))))
        except SysidError:
            pass
    scored = [(lines_cost(frd, c) if np.max(np.abs(c.poles()), initial=0.0) < 1 else np.inf,
               name, c) for name, c in candidates]
    if not scored:
        _no_start(why)
    scored.sort(key=lambda c: c[0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OffsetWarning)
        model = pem(frd, scored[0][2], feedthrough=bool(ft), max_iter=max_iter, tol=tol,
                    progress=progress)
    model.info["start"] = {"method": scored[0][1], "bd_x0": False,
                           "losses": {c[1]: c[0] for c in scored}}
    return model

