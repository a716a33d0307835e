"""Polynomial estimators: ``armax``, ``oe``, ``bj`` and ``iv4`` (the iterative structures
through the shared Gauss-Newton optimiser of ``sysid-core``, IV by streaming QR in Rust), and
the helpers they share with ``arx`` (:mod:`sysid.polynomial.arx`); ``arxstruc``,
``selstruc`` and ``struc`` are in :mod:`sysid.polynomial.structure`, ``delayest`` in
:mod:`sysid.polynomial.delayest`."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import (
    as_2d,
    as_int,
    as_int_grid,
    experiment_arrays,
    mode_kept,
    require_inputs_vary,
    user_stacklevel,
    warn_if_capped,
)
from .._progress import iteration_callback, iteration_printer
from .._threads import one_blas_thread
from ..data.input_design import check_polynomial_excitation
from ..data.iodata import IOData, as_record
from ..data.offsets import check_offsets
from ..errors import DataError, InsufficientDataError, ShapeError, is_frd
from ..validation.output_error import output_error
from .cancellation import cancellation, warn_cancellations
from .feedthrough import check_polynomial_feedthrough
from .initial import check as _check_initial
from .initial import record as _record_initial
from .initial import simulator as _initial_simulator
from .model import PolynomialModel
from .orders import matlab_orders
from .stability import warn_growing_noise, warn_insisting_f
from .starts import init_parameters, second_start
from .uncertainty import attach_uncertainty as _attach_uncertainty
from .uncertainty import defer_coloured


def _grid(v: Any, ny: int, ncol: int, name: str) -> list[list[int]]:
    return as_int_grid(v, (ny, ncol), name)


def _col(v: Any, ny: int, name: str) -> list[int]:
    """One order per output (``na``, ``nc``, ``nd`` of armax/bj/arma): a scalar, ``(ny,)`` or
    ``(ny, 1)``; another shape is refused as given (it was reshaped first: a (6, 6) ``na``
    was reported as (36, 1))."""
    try:
        a = np.array(v, dtype=object)
    except (TypeError, ValueError):
        a = None  # as_int_grid says what is wrong with it
    if a is not None and a.ndim and a.shape not in ((ny,), (ny, 1)):
        poly = name[1].upper()
        coupled = (f"; a ({ny}, {ny}) na, an A coupling the outputs, is sysid.arx's"
                   if poly == "A" else "")
        raise ShapeError(f"{name} has shape {a.shape} but should be ({ny},) or ({ny}, 1) or a "
                         f"scalar: armax, bj and arma use one {poly} polynomial per output"
                         f"{coupled}")
    return [r[0] for r in as_int_grid(a.reshape(-1, 1) if a is not None and a.ndim else v,
                                      (ny, 1), name)]


def _differenced(data: Any, integrate_noise: Any) -> IOData:
    """The record differenced per experiment (each one's first sample dropped), for a fit
    with an integrated disturbance (MATLAB's ``IntegrateNoise``)."""
    if not isinstance(integrate_noise, (bool, np.bool_)):
        raise DataError(f"integrate_noise must be True or False (every output alike), got "
                        f"{integrate_noise!r}")
    exps = experiment_arrays(data)
    if min(u.shape[0] for u, _ in exps) < 3:
        raise DataError("integrate_noise differences the record: every experiment needs at "
                        "least 3 samples")
    du = [np.diff(u, axis=0) for u, _ in exps]
    dy = [np.diff(y, axis=0) for _, y in exps]
    return IOData(u=du if len(du) > 1 else du[0], y=dy if len(dy) > 1 else dy[0],
                  dt=data.dt, input_names=getattr(data, "input_names", None),
                  output_names=getattr(data, "output_names", None))


def _integrated(m: PolynomialModel) -> PolynomialModel:
    """A model fitted on the differenced record as the model of the record: ``D(q) = 1 -
    q^-1`` on every output (its uncertainty's models get the same ``D``)."""
    unc, m.uncertainty = m.uncertainty, None  # replaced by its own with D below

    def with_d(b: PolynomialModel) -> PolynomialModel:
        b.d = [np.array([-1.0]) for _ in range(b.noutputs)]
        return b

    with_d(m)
    if unc is not None:
        m.uncertainty = unc.through(with_d)
    m.info = {**m.info, "integrate_noise": True}
    return m


def _warn_diverging(m: PolynomialModel, method: str, exps: Any = None) -> PolynomialModel:
    """``m``, with a :class:`sysid.StabilityWarning` when ``A`` has a pole on or outside the
    unit circle: its one-step predictor is stable, its simulation diverges (on the unshipped
    EMPS servo record ``arx(data, 2, 2, 1)`` returned a pole at 1 + 5e-5 silently, where
    ``n4sid`` warned); a stable one that simulates ``exps`` poorly too (``free_run``)."""
    from ..models.checks import warn_unstable
    from ..validation.free_run import linear_free_run

    warn_unstable(m, method, advice=(
        "Its one-step predictor is stable. Unless the process itself integrates or is "
        "unstable, use a model whose simulation is kept stable: sysid.oe, or "
        "sysid.ssest(data, order, focus='simulation')."))
    linear_free_run(m, exps or [], method)
    return m


def _names_of(model: PolynomialModel, data: Any) -> None:
    """The data's channel names on the model (they were u0, y0 whatever the data said)."""
    if getattr(data, "input_names", None) is not None and model.n_inputs:
        model.input_names = data.input_names
    if getattr(data, "output_names", None) is not None:
        model.output_names = data.output_names


def _require_samples(exps: Any, method: str, i: int, na: int, nb: list[int], nc: int,
                     nd: int, nf: list[int], nk: list[int]) -> None:
    """The sample count :func:`arx` requires (``N - max lag >= n_params + 1``) for output
    ``i``'s search: a delay that leaves a handful of samples gave numbers without a
    warning (``armax`` on 100 samples with ``nk = 98``: ``b = [-7.19, -19.68]``)."""
    lags = [(na, f"na = {na}"), (nc, f"nc = {nc}"), (nd, f"nd = {nd}")]
    lags += [(n, f"nf = {n}") for n in nf]
    lags += [(k + n - 1, f"nk + nb - 1 = {k} + {n} - 1") for n, k in zip(nb, nk) if n > 0]
    lag, which = max(lags, key=lambda t: t[0])
    p = na + sum(nb) + nc + nd + sum(nf)
    rows = sum(max(y.shape[0] - lag, 0) for _, y in exps)
    if rows < p + 1:
        raise InsufficientDataError(
            f"too few samples: the {method} fit of output {i} with {p} parameters and lags up "
            f"to {lag} ({which}) needs at least {p + 1} samples past its largest lag but got "
            f"{rows}; use a longer record or smaller orders and delays")


def _pem(
    data: Any,
    na: Any,
    nb: Any,
    nc: Any,
    nd: Any,
    nf: Any,
    nk: Any,
    method: str,
    max_iter: int,
    progress: bool | None | Callable[..., Any],
    init: PolynomialModel | None = None,
    second: bool = False,
    initial_condition: str = "zero",
) -> PolynomialModel:
    """The prediction-error search of ``armax``/``oe``/``bj``, per output, from the default
    start (ARX; Steiglitz-McBride for ``B/F``) or ``init``; with ``second``, each output
    also from a subspace fit (:func:`.starts.subspace_starts`), the lower criterion kept
    (``info["start"]``); the initial conditions by ``initial_condition``
    (:mod:`sysid.polynomial.initial`; the second start takes the first's choice)."""
    data = as_record(data)  # a (u, y) pair, as ssest and compare take
    iters = as_int(max_iter, "max_iter", 0)
    ic = _check_initial(initial_condition)
    exps = experiment_arrays(data)
    check_offsets(data)
    require_inputs_vary(exps, method, getattr(data, "input_names", None))
    require_inputs_vary(exps, method, getattr(data, "output_names", None), side=1)
    ny, nu = exps[0][1].shape[1], exps[0][0].shape[1]
    nb_g, nf_g, nk_g = _grid(nb, ny, nu, "nb"), _grid(nf, ny, nu, "nf"), _grid(nk, ny, nu, "nk")
    na_v, nc_v, nd_v = _col(na, ny, "na"), _col(nc, ny, "nc"), _col(nd, ny, "nd")
    for i, row in enumerate(nb_g):
        if method in ("oe", "bj") and not any(row):
            raise DataError(f"nb is 0 for every input of output {i}: the {method} model would "
                            "have no input path (B = 0); give nb >= 1 (nb = 0 leaves one "
                            "input out)")
    if min(na_v + nc_v + nd_v, default=0) < 0:
        raise DataError("na, nc and nd must be non-negative integers")
    for i in range(ny):
        _require_samples(exps, method, i, na_v[i], nb_g[i], nc_v[i], nd_v[i], nf_g[i], nk_g[i])
    check_polynomial_excitation(exps, method, na_v, nb_g, nf_g)
    ft_check = check_polynomial_feedthrough(
        exps, method, [max(na_v[i], nc_v[i], nd_v[i], *nb_g[i], *nf_g[i]) for i in range(ny)],
        nb_g, nk_g, data)
    parts: dict[str, list[Any]] = {k: [] for k in "abcdf"}
    info: dict[str, Any] = {"method": method, "iterations": [], "cost": [],
                            "criterion": "sum of squares", "stop": [],
                            "remaining_decrease": []}
    if ft_check is not None:
        info["feedthrough_check"] = ft_check
    cov, var = [], []
    cb, close_bar = iteration_callback(progress, method, iters * ny,
                                       iteration_printer(method, "sum of squares"))
    starts = [None if init is None else init_parameters(init, i, na_v[i], nb_g[i], nc_v[i],
                                                        nd_v[i], nf_g[i]) for i in range(ny)]
    if init is not None:
        info["start_stabilized"] = [bool(s[1]) for s in starts]  # type: ignore[index]

    def search(i: int, theta0: Any, callback: Any, how: str = ic) -> dict[str, Any]:
        return _sysid.polynomial_pem(
            [(np.ascontiguousarray(y[:, i]), u) for u, y in exps], na_v[i], nb_g[i], nc_v[i],
            nd_v[i], nf_g[i], nk_g[i], theta0, iters, 1e-9, callback, how)
    try:
        rs = [search(i, None if starts[i] is None else starts[i][0], cb) for i in range(ny)]
    finally:
        close_bar()
    if second:
        second_start(data, rs, search, nb_g, nf_g, nk_g, na_v, nc_v, nd_v, progress, info)
    for i in range(ny):
        r = rs[i]
        th = np.asarray(r["theta"])
        cuts = np.cumsum([na_v[i], *nb_g[i], nc_v[i], nd_v[i], *nf_g[i]])
        pieces = np.split(th, cuts[:-1])
        it = iter(pieces)

        def take(_n: int, it: Any = it) -> np.ndarray:
            return np.asarray(next(it))

        a = take(na_v[i])
        parts["a"].append([a if k == i else np.zeros(0) for k in range(ny)])
        parts["b"].append([take(n) for n in nb_g[i]])
        parts["c"].append(take(nc_v[i]))
        parts["d"].append(take(nd_v[i]))
        parts["f"].append([take(n) for n in nf_g[i]])
        info["iterations"].append(r["iterations"])
        info["cost"].append(list(r["history"]))
        info["stop"].append(r["stop"])
        info["remaining_decrease"].append(float(r["remaining_decrease"]))
        cov.append(r["covariance"])
        var.append(r["noise_variance"])
    m = PolynomialModel(parts["a"], parts["b"], nk_g, data.dt, c=parts["c"], d=parts["d"],
                        f=parts["f"], noise_variance=var)
    _names_of(m, data)
    _record_initial(info, rs)
    m.info = info
    warn_if_capped(info, f"the {method} search", iters)
    m.covariance = cov  # type: ignore[attr-defined]
    _attach_uncertainty(m, cov, "pem", "gauss-newton")
    # no noise model (oe, or bj / polyest with C = D = 1 and A = 1): the errors are the
    # output disturbance, coloured as it is
    if method == "oe" or not any(np.any(np.asarray(v) != 0) for v in (na_v, nc_v, nd_v)):
        chosen = [r["initial_condition"] for r in rs]
        sim = None if len(exps) != 1 or "estimate" not in chosen else _initial_simulator(
            m, *exps[0], [(na_v[i], nb_g[i], nc_v[i], nd_v[i], nf_g[i], nk_g[i])
                          for i in range(ny)], chosen)
        defer_coloured(m, exps, sim)
    found = []
    for i in range(ny):
        at = na_v[i] + sum(nb_g[i]) + nc_v[i] + nd_v[i]
        for j, nf in enumerate(nf_g[i]):
            P = np.asarray(cov[i], float)
            said = cancellation(parts["b"][i][j], parts["f"][i][j], P[at:at + nf, at:at + nf]) \
                if nf and P.shape[0] >= at + nf else None
            if said:
                found.append((f"{m.output_names[i]} <- {m.input_names[j]}", said))
            at += nf
    insisting = method in ("oe", "bj", "polyest") and m.is_stable() and (warn_insisting_f(
        m, exps, rs, na_v, nb_g, nc_v, nd_v, nf_g, nk_g, iters, method)
        or warn_growing_noise(m, parts["d"], method, max(len(y) for _, y in exps)))
    if insisting:  # a stable fit of a plant the data say is unstable: its pole-zero pairs
        m.info["cancellations"] = found  # are the bound's doing; "lower nb, nf" misleads
    else:
        warn_cancellations(method, found)
        _warn_held_f(m, parts["f"], method, max(u.shape[0] for u, _ in exps))
    _warn_returned_unstable(m, parts["f"], method)
    return m



def _warn_returned_unstable(m: PolynomialModel, f: list[list[np.ndarray]], method: str) -> None:
    """A :class:`~sysid.StabilityWarning` when the returned model is unstable, as ``arx``
    says: the search keeps F stable, yet rounding can leave a pole on the unit circle (a
    detrended step record: ``oe(data, 2, 2, 1)`` ended with F = (1 - q^-1)(1 - 0.9989 q^-1)
    silently, its simulation a ramp), and A (``arma``, ``polyest``) is not held stable (on
    seven raw records ``arma(y, 2, 1)`` returned a pole at or beyond 1 without a word).
    ``armax``, ``polyest`` and the polynomial ``pem`` say it themselves
    (:func:`_warn_diverging`): one warning, not two."""
    if m.is_stable() or method in ("armax", "polyest", "pem"):
        return
    from ..models.checks import warn_unstable

    def outside(c: np.ndarray) -> bool:
        return len(c) > 0 and bool(np.abs(np.roots(np.r_[1.0, np.asarray(c, float)])).max()
                                   >= 1.0)
    if any(outside(fj) for row in f for fj in row):
        advice = ("The search keeps F stable, but a pole ended on the unit circle: unless the "
                  "process itself integrates, try a smaller nf or a detrended record; for an "
                  "integrating process fit the differenced output, or arx/armax (whose A is "
                  "not held stable).")
    else:
        advice = ("A is not held stable: unless the "
                  + ("series" if method == "arma" else "process") + " itself integrates or "
                  "grows, remove its offsets and trends first (sysid.detrend), or model the "
                  "differenced " + ("series" if method == "arma" else "output") + ".")
    warn_unstable(m, method, advice=advice)


def _warn_held_f(m: PolynomialModel, f: list[list[np.ndarray]], method: str, n: int) -> None:
    """The search keeps every ``F`` stable: a :class:`~sysid.StabilityWarning` when that
    bound holds a pole at the unit circle (:func:`sysid.pem.boundary.warn_poles_at_bound`),
    naming the channel whose pole keeps most of its mode over the record (``n`` samples).
    On unshipped DaISy records ``oe(data, 2, 2, 1)`` ended at 1 - 1.5e-11 (dryer),
    1 - 5e-9 (power plant) and 1 - 9e-11 (EMPS) without a word."""
    from ..pem.boundary import warn_poles_at_bound

    best: tuple[float, str, np.ndarray] | None = None
    for i, row in enumerate(f):
        for j, fj in enumerate(row):
            if len(fj) == 0:
                continue
            r = np.roots(np.concatenate([[1.0], np.asarray(fj, float)]))
            if r.size and np.all(np.isfinite(r)) and np.abs(r).max() < 1.0:
                kept = mode_kept(float(np.abs(r).max()), n)
                if best is None or kept > best[0]:
                    best = (kept, f"{m.output_names[i]} <- {m.input_names[j]}", r)
    if best is not None:
        warn_poles_at_bound(
            best[2], n, f"the {method} model's F of {best[1]}", "the search keeps F stable",
            integrating="fit the differenced output, or arx/armax (whose A is not held "
            "stable)", lower="a smaller nf", stacklevel=user_stacklevel())


@one_blas_thread
def armax(
    data: Any,
    na: Any,
    nb: Any = None,
    nc: Any = None,
    nk: Any = None,
    *,
    max_iter: int = 100,
    progress: bool | None | Callable[..., Any] = None,
    init: PolynomialModel | None = None,
    integrate_noise: bool = False,
    initial_condition: str = "auto",
) -> PolynomialModel:
    """ARMAX ``A y = B u(t-nk) + C e`` by prediction-error minimisation (per output). The
    orders may be given as MATLAB's one vector, ``armax(data, [na, nb, nc, nk])``
    (:func:`~sysid.polynomial.orders.matlab_orders`); ``nk`` defaults to 1.
    ``integrate_noise=True`` (MATLAB's ``IntegrateNoise``, ARIMAX): ``A y = B u + C e / (1 -
    q^-1)``, fitted on the differenced record, as :func:`arx`'s.

    The search starts from an ARX fit, or from ``init`` (a polynomial model with the data's
    channel counts, e.g. an earlier ``armax`` or an ``arx`` fit: its ``A``, ``B`` and ``C``
    cut or padded with zeros to ``na``, ``nb``, ``nc``; an unstable ``C`` has its roots
    reflected into the unit circle and ``info["start_stabilized"]`` says so), as MATLAB's
    ``armax(data, init_sys)``.

    ``initial_condition``: MATLAB's ``InitialCondition``, ``"auto"`` (default), ``"zero"``
    or ``"estimate"`` (:mod:`sysid.polynomial.initial`).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(1)
    >>> u = rng.standard_normal((2000, 1)); e = 0.1 * rng.standard_normal(2000)
    >>> y = np.zeros((2000, 1))
    >>> for t in range(1, 2000): y[t] = 0.7 * y[t-1] + u[t-1, 0] + e[t] + 0.5 * e[t-1]
    >>> m = sysid.polynomial.estimators.armax(sysid.IOData(u, y, 1.0), 1, 1, 1)
    >>> bool(abs(m.c[0][0] - 0.5) < 0.1)
    True
    >>> again = sysid.polynomial.estimators.armax(sysid.IOData(u, y, 1.0), 1, 1, 1, init=m)
    >>> again.info["start"], bool(abs(again.c[0][0] - m.c[0][0]) < 1e-6)
    ('init', True)

    A record that starts mid-response (here at sample 200 of a noise-free run):

    >>> y0 = np.zeros((2200, 1)); u0 = rng.standard_normal((2200, 1))
    >>> for t in range(1, 2200): y0[t] = 0.7 * y0[t-1] + u0[t-1, 0]
    >>> d = sysid.IOData(u0[200:], y0[200:], 1.0)
    >>> m = sysid.armax(d, 1, 1, 1, 1)
    >>> m.info["initial_condition"], np.round([m.a[0][0][0], m.b[0][0][0], m.c[0][0]], 8)
    ('estimate', array([-0.7,  1. ,  0. ]))
    """
    data = as_record(data)
    _check_initial(initial_condition)
    if integrate_noise is not False:  # ARIMAX: the fit of the differenced record
        m = armax(_differenced(data, integrate_noise), na, nb, nc, nk, max_iter=max_iter,
                  progress=progress, init=init, initial_condition=initial_condition)
        return _integrated(m)
    na, nb, nc, nk = matlab_orders("armax", data, na, nb=nb, nc=nc, nk=nk)
    m = _pem(data, na, nb, nc, 0, 0, nk, "armax", max_iter, progress, init,
             initial_condition=initial_condition)
    if init is not None:
        m.info["start"] = "init"
    return _warn_diverging(m, "armax")


@output_error("oe")
@one_blas_thread
def oe(
    data: Any,
    nb: Any,
    nf: Any = None,
    nk: Any = None,
    *,
    max_iter: int = 100,
    progress: bool | None | Callable[..., Any] = None,
    init: PolynomialModel | None = None,
    periods: int | str | None = None,
    transient: int | None = None,
    initial_condition: str = "auto",
) -> PolynomialModel:
    """Output error ``y = B/F u(t-nk) + e``. The orders may be given as MATLAB's one vector,
    ``oe(data, [nb, nf, nk])`` (:func:`~sysid.polynomial.orders.matlab_orders`); ``nk``
    defaults to 1.

    Starts from Steiglitz-McBride (one input) or from ``init`` (an ARX model's ``A`` becomes
    ``F``; unstable roots of the start are reflected into the unit circle, and
    ``info["start_stabilized"]`` says so), then Gauss-Newton on the simulation error; ``F``
    is kept stable. Without ``init``, every output is also fitted from a subspace start
    (:func:`sysid.n4sid` of order ``max(nf)`` on that output, as ``B/F``) and, per output,
    the fit with the lower criterion is returned, ``info["start"]`` naming its start (a list
    per output for several): the Steiglitz-McBride iterates can stay far from the minimum
    on a slow, nearly integrating plant. On a time record it warns when the record shows
    feedback, which biases an output-error fit (:mod:`sysid.validation.output_error`).

    With ``periods=P`` (whole periods of a periodic input in steady state in every
    experiment) or ``"auto"`` (:func:`sysid.detect_period`), ``B/F`` is fitted on the
    excited lines instead: the response averaged over the periods (:func:`sysid.bla`), each
    entry weighted by ``1/std`` from their spread, by ``tfest``'s frequency-response fit
    (``info["domain"] == "frequency"``; the covariance scaled by the residual scale
    ``info["residual_scale"]`` and by ``(P-2)/(P-3)`` for the variances estimated from the
    ``P`` periods, ``info["sample_variance_factor"]``, as in ``pem``/``greyest``; with 3
    periods or fewer an ``UncertaintyWarning`` says the std is too small). ``transient``
    drops leading periods (default 0 declared, 1 with ``"auto"``). ``"auto"`` without a
    usable period fits in the time domain with the reason in ``info["periodicity"]``.
    Frequency-response data (an :class:`sysid.FRD` with ``dt``, MATLAB's ``oe(idfrd, [nb nf
    nk])``) are fitted the same way on their lines, weighted by the ``std`` or uniformly
    without one (``info["weighting"]``); no output noise variance is estimated from a
    response (``noise_variance`` zero, ``info["noise_variance"]`` says so).

    The errors of the time-domain fit are the output disturbance itself, coloured on nearly
    every real record, where the Gauss-Newton covariance ``sigma^2 (J^T J)^-1`` (kept as
    ``covariance``, per output) is too small. On one record ``uncertainty`` is therefore the
    sandwich for the errors' own colour (:mod:`sysid.pem.sandwich`; per output, the
    Gauss-Newton one when the errors are white), formed when first used;
    ``info["covariance"]`` says which covariance the model carries. With several
    experiments it stays the Gauss-Newton one, and ``info["covariance"]`` says so.

    ``initial_condition``: MATLAB's ``InitialCondition``, ``"auto"`` (default), ``"zero"``
    or ``"estimate"`` (:mod:`sysid.polynomial.initial`).
    A fit on lines (``periods``, an FRD) has no transient: there ``"estimate"`` is refused.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> g = sysid.TransferFunction([0.5, 0.2], [1.0, -1.2, 0.5], dt=1.0)
    >>> up = sysid.multisine(128, band=(0, 0.5), periods=4, seed=0)
    >>> yp = g.simulate(np.vstack([np.tile(up, (5, 1)), up]))[-512:]
    >>> m = sysid.oe(sysid.IOData(up, yp, dt=1.0), 2, 2, 1, periods=4)
    >>> np.round(m.b[0][0], 8), np.round(m.f[0][0], 8), m.info["domain"]
    (array([0.5, 0.2]), array([-1.2,  0.5]), 'frequency')

    The same plant from a record that starts mid-response (the transient estimated):

    >>> u = np.random.default_rng(0).standard_normal((600, 1))
    >>> m = sysid.oe(sysid.IOData(u[100:], g.simulate(u)[100:], 1.0), 2, 2, 1)
    >>> np.round(m.f[0][0], 8), m.info["initial_condition"]
    (array([-1.2,  0.5]), 'estimate')
    """
    periodicity = None
    on_lines = is_frd(data) or (periods is not None and periods != "auto")
    _check_initial(initial_condition, lines=on_lines)
    if is_frd(data):  # its lines
        from .oe_lines import oe_frd

        if periods is not None or transient is not None:
            raise DataError("an FRD is already on its lines: leave periods= and transient= "
                            "out")
        nb, nf, nk = matlab_orders("oe", data, nb, nf=nf, nk=nk)
        return oe_frd(data, nb, nf, nk, max_iter=max_iter, progress=progress, init=init)
    data = as_record(data)
    nb, nf, nk = matlab_orders("oe", data, nb, nf=nf, nk=nk)
    if periods is not None or transient is not None:
        from .oe_lines import oe_lines

        m, periodicity = oe_lines(data, nb, nf, nk, periods=periods, transient=transient,
                                  max_iter=max_iter, progress=progress, init=init)
        if m is not None:
            return m
    if init is not None:
        m = _pem(data, 0, nb, 0, 0, nf, nk, "oe", max_iter, progress, init,
                 initial_condition=initial_condition)
        m.info["start"] = "init"
    else:
        m = _pem(data, 0, nb, 0, 0, nf, nk, "oe", max_iter, progress, second=True,
                 initial_condition=initial_condition)
    if periodicity is not None:  # periods="auto" found none: why the time domain
        m.info["periodicity"] = periodicity
    return m


@one_blas_thread
def bj(
    data: Any,
    nb: Any,
    nc: Any = None,
    nd: Any = None,
    nf: Any = None,
    nk: Any = None,
    *,
    max_iter: int = 100,
    progress: bool | None | Callable[..., Any] = None,
    init: PolynomialModel | None = None,
    initial_condition: str = "auto",
) -> PolynomialModel:
    """Box-Jenkins ``y = B/F u(t-nk) + C/D e``. The orders may be given as MATLAB's one
    vector, ``bj(data, [nb, nc, nd, nf, nk])`` (:func:`~sysid.polynomial.orders.matlab_orders`);
    ``nk`` defaults to 1.

    ``B/F`` starts from Steiglitz-McBride and also, per output, from a subspace fit (as
    :func:`oe`; ``C = D = 1``), and the fit with the lower prediction-error criterion is
    returned (``info["start"]``). With ``init`` (a polynomial model with the data's channel counts:
    an earlier ``bj``, an ``oe`` fit, or an ``arx`` one whose ``A`` becomes ``F``; cut or
    padded with zeros to the orders given) the search starts there alone, as MATLAB's
    ``bj(data, init_sys)``; unstable ``C``, ``D`` or ``F`` roots are reflected into the unit
    circle and ``info["start_stabilized"]`` says so.

    ``initial_condition``: MATLAB's ``InitialCondition``, ``"auto"`` (default), ``"zero"``
    or ``"estimate"`` (:mod:`sysid.polynomial.initial`).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(3000); e = 0.1 * rng.standard_normal(3000)
    >>> g = sysid.TransferFunction([0.0, 1.0], [1.0, -0.8], dt=1.0)
    >>> h = sysid.TransferFunction([1.0, 0.0], [1.0, -0.9], dt=1.0)
    >>> y = g.simulate(u)[:, 0] + h.simulate(e)[:, 0]
    >>> m = sysid.bj(sysid.IOData(u, y, 1.0), 1, 0, 1, 1, 1)
    >>> np.round([m.f[0][0][0], m.d[0][0]], 1).tolist()
    [-0.8, -0.9]
    >>> sysid.bj(sysid.IOData(u, y, 1.0), 1, 0, 1, 1, 1, init=m).info["start"]
    'init'
    >>> sysid.bj(sysid.IOData(u, y, 1.0), 1, 0, 1, 1, 1).info["initial_condition"]  # at rest
    'zero'
    """
    data = as_record(data)
    _check_initial(initial_condition)
    nb, nc, nd, nf, nk = matlab_orders("bj", data, nb, nc=nc, nd=nd, nf=nf, nk=nk)
    if init is not None:
        m = _pem(data, 0, nb, nc, nd, nf, nk, "bj", max_iter, progress, init,
                 initial_condition=initial_condition)
        m.info["start"] = "init"
        return m
    return _pem(data, 0, nb, nc, nd, nf, nk, "bj", max_iter, progress, second=True,
                initial_condition=initial_condition)


def _references(reference: Any, exps: list[tuple[np.ndarray, np.ndarray]]) -> list[Any]:
    """One instrument-input array per experiment (``None`` entries: the input itself)."""
    if reference is None:
        return [None] * len(exps)
    refs = list(reference) if isinstance(reference, (list, tuple)) else [reference]
    if len(refs) != len(exps):
        raise DataError(f"reference: give one array per experiment ({len(exps)}), got "
                        f"{len(refs)}")
    out = []
    for r, (u, _) in zip(refs, exps):
        if isinstance(r, (str, bytes)) or np.asarray(r).dtype.kind not in "biuf":
            raise DataError(f"reference must be the reference signal: a real array "
                            f"(n_samples, n_ref), or a list with one per experiment; got "
                            f"{type(r).__name__} {r!r:.40}")
        a = as_2d(r, "reference")
        if a.ndim != 2 or a.shape[0] != u.shape[0] or a.shape[1] == 0:
            raise DataError(f"reference must have the input's {u.shape[0]} rows (one column "
                            f"per reference channel), got shape {a.shape}")
        out.append(np.ascontiguousarray(a))
    return out


def iv4(data: Any, na: Any, nb: Any = None, nk: Any = None, *, reference: Any = None
        ) -> PolynomialModel:
    """Four-stage instrumental-variable estimate of ``A(q) y = B(q) u(t-nk) + v``.

    Consistent for coloured noise ``v`` where least squares (:func:`arx`) is biased. MIMO
    with the orders of :func:`arx` (``na`` outputs x outputs, ``nb``/``nk`` outputs x
    inputs; or MATLAB's one vector ``[na, nb, nk]``, ``nk`` default 1); several experiments
    are used together (each filtered from rest; the prefiltered stage's sums start after its
    prefilter's start-up in each, so that a record that does not start at rest is fitted
    without bias). For
    closed-loop data pass the reference signal (``(N, n_ref)``, a list with one array per
    experiment) as ``reference``: the instruments are then the parts of ``y`` and ``u``
    explained by the reference (a least-squares FIR projection on its lags), which the
    feedback cannot correlate with the noise, instead of the (noise-correlated) input.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from scipy import signal
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(3000)
    >>> v = signal.lfilter([1], [1, -0.9], rng.standard_normal(3000))
    >>> y = signal.lfilter([0, 1.0], [1, -0.5], u) + 0.5 * v
    >>> m = sysid.iv4(sysid.IOData(u[:, None], y[:, None], 1.0), 1, 1, 1)
    >>> bool(abs(m.a[0][0][0] + 0.5) < 0.05)
    True
    """
    data, exps, (na_g, nb_g, nk_g) = iv_setup("iv4", data, na, nb, nk)
    refs = _references(reference, exps)
    fits = _sysid.iv4([(u, y, r) for (u, y), r in zip(exps, refs)], na_g, nb_g, nk_g)
    return _iv_model(data, fits, na_g, nb_g, nk_g, "iv4", reference is not None)


def iv_setup(method: str, data: Any, na: Any, nb: Any, nk: Any
             ) -> tuple[Any, list[Any], tuple[Any, Any, Any]]:
    """The record, its experiments and the order grids of an IV estimator (``iv4``, ``ivx``):
    MATLAB's order vector read, offsets checked, an input required."""
    data = as_record(data)  # a (u, y) pair, as ssest and compare take
    exps = experiment_arrays(data)
    na, nb, nk = matlab_orders(method, data, na, nb=nb, nk=nk)
    check_offsets(data)
    ny, nu = exps[0][1].shape[1], exps[0][0].shape[1]
    if nu == 0:
        raise DataError(f"{method} needs an input signal (use ar/arma for time series)")
    return data, exps, (_grid(na, ny, ny, "na"), _grid(nb, ny, nu, "nb"),
                        _grid(nk, ny, nu, "nk"))


def _iv_model(data: Any, fits: list[Any], na_g: Any, nb_g: Any, nk_g: Any, method: str,
              closed_loop: bool) -> PolynomialModel:
    """The polynomial model of an IV fit (per output ``theta = [a.., b..]``)."""
    ny = len(fits)
    a, b = [], []
    for i, f in enumerate(fits):
        th = np.asarray(f["theta"])
        pieces = np.split(th, np.cumsum([*na_g[i], *nb_g[i]])[:-1])
        a.append([np.asarray(x) for x in pieces[:ny]])
        b.append([np.asarray(x) for x in pieces[ny:]])
    m = PolynomialModel(a, b, nk_g, data.dt)
    _names_of(m, data)
    m.info = {"method": method, "closed_loop": closed_loop}
    cov = [np.asarray(f["covariance"]) for f in fits]
    m.noise_variance = np.array([f["noise_variance"] for f in fits])
    m.covariance = cov  # type: ignore[attr-defined]
    m.parameters = [np.asarray(f["theta"]) for f in fits]  # type: ignore[attr-defined]
    _attach_uncertainty(m, cov, "arx", "instrumental-variable")
    from ..models.checks import warn_unstable

    warn_unstable(m, method, advice=(
        "Unless the process itself is unstable, the instruments did not pin A down: try "
        "lower orders, sysid.oe (whose simulation is stable) or "
        "sysid.ssest(data, order, focus='simulation')."))
    return m
