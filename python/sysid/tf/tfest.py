"""``sysid.tfest``: transfer-function models from time-domain or frequency-response data."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from .._checks import require_inputs_vary, user_stacklevel
from .._threads import one_blas_thread
from ..errors import DataError, NumericalError, is_frd, several_records_hint
from ..models.paramtable import ParameterTable
from ..models.uncertainty import ParameterUncertainty
from ..validation.output_error import output_error
from .feedthrough import lag_check, say_discrete
from .free import arx_start, free_fit, reflected, unstable_uncertainty
from .model import TransferFunction
from .options import (
    blockdiag,
    delays,
    fit_percent,
    pole_zero_orders,
    progress_callback,
    search_limits,
)
from .refine import PairStructure, check_experiments, free_test, refine
from .srivc import srivc

__all__ = ["tfest"]

_HOLDS = ("zoh", "foh")


@output_error("tfest")
@one_blas_thread
def tfest(data: Any, n_poles: Any, n_zeros: Any = None, *, iodelay: Any = None,
          dt: float | None = None, hold: str = "zoh", initial_state: str = "zero",
          init: TransferFunction | None = None,
          max_delay: float | None = None, max_iter: int = 100, tol: float = 1e-10,
          progress: bool | None | Callable[..., Any] = None,
          periods: int | str | None = None, transient: int | None = None,
          enforce_stability: bool = True, feedthrough: bool = False) -> TransferFunction:
    """Estimate a transfer-function model (MATLAB's ``tfest``).

    .. math::

        y_i(t) = \\sum_j \\frac{B_{ij}(s)}{A_{ij}(s)} e^{-s \\tau_{ij}} u_j(t) + e_i(t)

    From sampled data (an :class:`~sysid.IOData`): refined instrumental variables for
    continuous-time models (SRIVC) give the start, then the simulation error is minimised on
    the shared Gauss-Newton search, the model sampled exactly with the input's ``hold``
    (fractional delays included). From frequency-response data (an :class:`~sysid.FRD`):
    Sanathanan-Koerner iterations, then weighted nonlinear least squares (weights ``1/std``
    when the FRD has a confidence band). Several outputs: one model per output, each a sum of
    single-input rational functions with their own poles. With several inputs each output's
    continuous-time search also runs from the poles of its subspace model (numerators by
    least squares, :mod:`sysid.tf.starts`) and the lower criterion is kept
    (``info["start"]`` names the start per output).

    Parameters
    ----------
    data : IOData or FRD
    n_poles : int or array_like (noutputs, ninputs)
        Number of poles of each pair.
    n_zeros : int or array_like, optional
        Number of zeros (default ``n_poles - 1``; at most ``n_poles``).
    iodelay : None, float, array_like or "auto"
        Input-output delays, fixed: in seconds for a continuous-time model (any value, not
        only whole samples), in whole samples for a discrete-time one (``dt`` given; MATLAB's
        ``IODelay``, the model's ``iodelay``); ``"auto"`` estimates them. ``None``: no
        delay.
    dt : float, optional
        ``None`` for a continuous-time model; the data's sample time for a discrete-time
        model (output error ``B(q)/F(q)``, delays in whole samples).
    hold : {"zoh", "foh"}
        How the input behaves between samples (time-domain data).
    initial_state : {"zero", "estimate"}
        Start from rest, or estimate the initial state of each experiment (the model's
        state; the input before the record, which a delay would still deliver, is taken as
        zero). A discrete-time fit passes it to :func:`sysid.oe` as ``initial_condition``
        (there the delayed inputs before the record are estimated too).
    init : TransferFunction, optional
        Start the refinement from this model (continuous, same orders) instead of SRIVC.
    max_delay : float, optional
        Upper bound on estimated delays (seconds; default a tenth of the record).
    max_iter, tol : int, float
        Search limits.
    progress : bool or callable, optional
        Progress display (see :mod:`sysid._progress`).
    periods : int or "auto", optional
        The data are periodic (discrete-time models, ``dt=data.dt``): every experiment holds
        this many whole periods in steady state, or ``"auto"`` detects the period of the
        input (:func:`sysid.detect_period`). The model is then fitted in the frequency
        domain on the excited lines: the response averaged over the periods
        (:func:`sysid.bla`), each entry weighted by ``1/std`` from the spread over the
        periods, as for an FRD; the covariance is scaled by the residual scale
        ``info["residual_scale"]`` and by ``(P-2)/(P-3)`` for the variances estimated from
        the ``P`` periods (``info["sample_variance_factor"]``; as in ``pem``/``greyest``:
        taking them as exact would report too small a std; with 3 periods or fewer no
        calibrated std exists and an ``UncertaintyWarning`` says so; see
        :mod:`sysid.tf.frequency`). When ``"auto"`` finds no period, or fewer than 2 after the
        transient, the time-domain fit runs and ``info["periodicity"]["reason"]`` says why.
    transient : int, optional
        Leading periods dropped (default 0 with a declared ``periods``, 1 with ``"auto"``).

    enforce_stability : bool
        Keep the poles stable (MATLAB's ``EnforceStability``) in the fits on frequency-response
        data and on the excited lines of periodic data, where a free fit can place poles in
        the right half-plane (outside the unit circle) to match the data: the start's
        unstable poles are reflected and every step stays stable (the free search from the
        start itself also runs, and its result is kept when it ends stable and lower). Default
        ``True``, as :func:`sysid.ssest` and :func:`sysid.pem` on frequency data (MATLAB's
        default is ``False``): on 17 real records' :func:`sysid.spa` estimates, the free fits
        of 2 and 3 poles were unstable in 22 of 34 cases, 20 of them diverging on the
        validation data. ``False`` for an unstable plant's response (measured in closed
        loop). Continuous-time fits of time records keep the simulation stable too; there,
        from the stable fit and from the least-squares ARX fit when its ``A`` grows over
        the record, the search is run again free of the bound (``False``: the lower
        result is returned when it improves on the stable fit), and with the default a
        :class:`sysid.StabilityWarning` names the pole when the data insist on an unstable
        model (likelihood-ratio test at 1 %, as :func:`sysid.ssest`'s prediction focus;
        ``info["insisting"]``). A discrete-time fit is :func:`sysid.oe`'s, which keeps
        ``F`` stable and warns likewise.
    feedthrough : bool
        Discrete-time models: ``False`` (default, MATLAB's) lags every numerator one sample
        behind the input (no direct term, ``B(z) = b_0 z^(n-1) + ...``); ``True`` lets the
        output answer the input at the same sample (``B(z) = b_0 z^n + ...``, a biproper
        pair). A continuous model has a direct term when ``n_zeros == n_poles``.

    Returns
    -------
    TransferFunction
        With ``parameters`` (a :class:`~sysid.models.paramtable.ParameterTable` with std),
        ``uncertainty`` (:class:`~sysid.models.uncertainty.ParameterUncertainty`) and
        ``info`` (method, iterations, stop reason, cost, fit per output). From an FRD or on
        periodic data the covariance is ``c s (J^T W J)^-1`` with the residual scale
        ``s = info["residual_scale"]`` per pair (about 1 when the FRD's std is right and
        the model explains it; unweighted, the residual variance) and ``c =
        info["sample_variance_factor"]`` (``(P-2)/(P-3)`` on periodic data or a
        :func:`sysid.bla`, else 1). A discrete model from a
        time record (``dt`` given) carries :func:`sysid.oe`'s covariance: on one record
        the sandwich for the errors' colour, formed when first used (by ``uncertainty`` or
        the table's std), with ``info["covariance"]`` saying which.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> true = sysid.TransferFunction([0.5, 2.0], [1.0, 0.8, 4.0], iodelay=0.13)
    >>> u = np.random.default_rng(0).standard_normal(600)
    >>> data = sysid.IOData(u, true.simulate(u, dt=0.05), dt=0.05)
    >>> G = sysid.tfest(data, 2, 1, iodelay="auto")
    >>> np.round(G.den[0][0], 6), np.round(G.num[0][0], 6), round(float(G.iodelay[0, 0]), 6)
    (array([1. , 0.8, 4. ]), array([0.5, 2. ]), 0.13)

    Periodic data (4 periods of a multisine in steady state), a discrete model on the lines:

    >>> g = sysid.TransferFunction([0.0, 0.5, 0.2], [1.0, -1.2, 0.5], dt=1.0)
    >>> up = sysid.multisine(128, band=(0, 0.5), periods=4, seed=0)
    >>> yp = g.simulate(np.vstack([np.tile(up, (5, 1)), up]))[-512:]
    >>> Gp = sysid.tfest(sysid.IOData(up, yp, dt=1.0), 2, 1, dt=1.0, periods=4)
    >>> np.round(Gp.den[0][0], 8), np.round(Gp.num[0][0], 8), Gp.info["domain"]
    (array([ 1. , -1.2,  0.5]), array([0.5, 0.2]), 'frequency')
    """
    if hold not in _HOLDS:
        raise DataError(f"hold must be 'zoh' or 'foh', got {hold!r}")
    max_iter, tol = search_limits(max_iter, tol, max_delay)
    if initial_state not in ("zero", "estimate"):
        raise DataError(f"initial_state must be 'zero' or 'estimate', got {initial_state!r}")
    if not isinstance(feedthrough, (bool, np.bool_)):
        raise DataError(f"feedthrough must be True or False, got {feedthrough!r}")
    ft = bool(feedthrough)
    if ft and dt is None:
        raise DataError("feedthrough= applies to discrete-time models (dt=); a continuous "
                        "transfer function has a direct term when n_zeros == n_poles")
    if is_frd(data):
        from .frequency import tfest_frd

        if periods is not None or transient is not None:
            raise DataError("periods= and transient= describe a time record; an FRD is "
                            "already on its lines: leave them out")
        # what only a time record has, refused rather than dropped silently
        for name, given, default in (("init", init, None), ("hold", hold, "zoh"),
                                     ("initial_state", initial_state, "zero")):
            if given is not default and given != default:
                raise DataError(
                    f"{name}= applies to time-domain data; tfest on an FRD starts from its "
                    "own Sanathanan-Koerner fit of the lines, on which a continuous model "
                    "is its response at j omega and a discrete one at exp(j omega dt): "
                    f"leave {name} out")
        return _checked(tfest_frd(data, n_poles, n_zeros, iodelay=iodelay, dt=dt,
                                  max_iter=max_iter, tol=tol, progress=progress,
                                  stable=bool(enforce_stability), max_delay=max_delay,
                                  feedthrough=ft))
    if not hasattr(data, "experiments") or not hasattr(data, "dt"):
        raise DataError(f"tfest needs a sysid.IOData or sysid.FRD, got {type(data).__name__}"
                        + (several_records_hint(data)
                           or "; wrap arrays as sysid.IOData(u, y, dt=...)"))
    l, m = data.n_outputs, data.n_inputs
    if m == 0:
        raise DataError("tfest needs at least one input; for a time series use sysid.ar")
    from ..data.offsets import check_offsets

    # a transfer function has no constant term (as every estimator); from rest, no state
    check_offsets(data, from_rest=initial_state == "zero")
    npo, nze = pole_zero_orders(n_poles, n_zeros, l, m)
    from ..data.input_design import check_model_excitation

    # the numerator and denominator coefficients of the largest channel: n_poles + n_zeros + 1
    k = int(np.argmax(npo + nze))
    p_k, z_k = int(npo.flat[k]), int(nze.flat[k])
    check_model_excitation(data, p_k + z_k + 1, "tfest",
                           f"n_poles + n_zeros + 1 = {p_k} + {z_k} + 1", "fewer poles and zeros")
    fixed_delays, auto = delays(iodelay, l, m)
    span = max(len(y) for _, y in data.experiments) * data.dt  # the longest experiment, s
    if np.any(fixed_delays >= span):
        raise DataError(
            f"iodelay = {float(np.max(fixed_delays)):g} s exceeds what the record allows: its "
            f"longest experiment lasts {span:g} s, so the input would never reach the output; "
            "give a delay shorter than the record (in seconds, not samples), or "
            "iodelay='auto' to estimate it")
    periodicity = None
    if periods is not None or transient is not None:
        unused = [k for k, v in (("init", init), ("max_delay", max_delay)) if v is not None]
        unused += ["initial_state"] if initial_state != "zero" else []
        if unused:
            raise DataError(f"{' and '.join(unused)} cannot be used with periods=: the lines are "
                            "the steady state (no initial state) and the fit starts from its "
                            "own linear least squares; leave them out, or leave periods out "
                            "for the time-domain fit")
        G, periodicity = _periodic(data, npo, nze, fixed_delays, auto, dt, periods, transient,
                                   max_iter, tol, progress, bool(enforce_stability), ft)
        if G is not None:
            return _checked(G, lag_check(data, npo, nze, dt, ft, iodelay))
    if dt is not None:
        G = _discrete(data, npo, nze, fixed_delays, auto, dt, max_iter, progress, ft,
                      initial_state)
        if periodicity is not None:  # periods="auto" found none: why the time domain
            G.info["periodicity"] = periodicity
        if iodelay is None:  # the oe inside checked the one-sample lag (feedthrough=False)
            say_discrete(G.info.get("feedthrough_check"))
        return _checked(G)
    cb, close = progress_callback(progress, max_iter)
    try:
        G = _continuous(data, npo, nze, fixed_delays, auto, hold, initial_state, max_delay,
                        max_iter, tol, cb, _init(init, npo, nze), bool(enforce_stability))
        return _checked(G, lag_check(data, npo, nze, dt, ft, iodelay))
    finally:
        close()


def _checked(G: TransferFunction, ft_check: dict[str, Any] | None = None) -> TransferFunction:
    """``G``, with a :class:`sysid.StabilityWarning` when it is unstable (and ``ft_check``,
    the lag check's record, in its ``info``)."""
    from ..models.checks import warn_unstable

    if ft_check is not None:
        G.info["feedthrough_check"] = ft_check
    warn_unstable(G, "tfest", advice=(
        "Unless the process itself is unstable, leave enforce_stability at its default "
        "(True), try fewer poles, a start from a stable model (init=), or "
        "sysid.ssest(data, order, focus='simulation') (which keeps the simulation stable)."))
    return G


def _continuous(data: Any, npo: np.ndarray, nze: np.ndarray, delays: np.ndarray, auto: bool,
                hold: str, initial_state: str, max_delay: float | None, max_iter: int,
                tol: float, cb: Any, init: Any, stable: bool = True) -> TransferFunction:
    l, m = data.n_outputs, data.n_inputs
    insisted = []
    exps_all = [(np.asarray(u, float), np.asarray(y, float)) for u, y in data.experiments]
    N = sum(u.shape[0] for u, _ in exps_all)
    dmax = max_delay if max_delay is not None else 0.1 * N * data.dt / len(exps_all)
    rows_num, rows_den, tables, covs, info_out = [], [], [], [], []
    est_delays = np.zeros((l, m))
    for i in range(l):
        exps = [(u, y[:, i]) for u, y in exps_all]
        check_experiments(exps, int(np.sum(npo[i] + nze[i] + 1)))
        if i == 0:  # an input that never changes shows no response (0 / (s^2 + ...) before)
            require_inputs_vary(exps_all, "tfest", data.input_names)
        # a constant output has no dynamics to fit (its fit is undefined): refused as by arx
        # (the discrete-time fit is oe's, which refuses it itself)
        require_inputs_vary([(u, y[:, None]) for u, y in exps], "tfest",
                            [data.output_names[i]], side=1)
        starts = _starts(exps, data.dt, npo[i], nze[i], delays[i], auto, hold, dmax) \
            if init is None else [(init.den[i][j], init.num[i][j],
                                   float(init.iodelay[i, j]) if auto else float(delays[i, j]))
                                  for j in range(m)]
        # a fixed delay longer than the default bound on estimated ones is the user's
        pairs = [_pair(a, b, t, auto, dmax if auto else max(dmax, t), data.output_names[i],
                       data.input_names[j]) for j, (a, b, t) in enumerate(starts)]
        res, said = _refined(pairs, exps, data.dt, hold, initial_state, max_iter, tol, cb)
        res["start"] = "SRIVC" if init is None else "init"
        if init is None and m > 1 and res["stop"] != "cancelled":
            res, pairs, said = _second_start(res, said, pairs, exps, data, npo[i], nze[i],
                                             starts, auto, dmax, hold, initial_state,
                                             max_iter, tol, cb, i)
        if not stable and res["stop"] != "cancelled":  # free, from the stable fit (or ARX)
            got = free_fit(res, pairs, exps, data.dt, npo[i], nze[i], hold, initial_state,
                           max_iter, tol)
            if got is not None:
                got[0]["start"] = res["start"]
                res, said = got
        said = unstable_uncertainty(res, said, pairs, exps, data.dt, hold, initial_state)
        for w in said:  # the kept search's warnings, at the user's line
            warnings.warn(w.message, w.category, stacklevel=user_stacklevel())
        if stable and res["stop"] != "cancelled":  # held at the bound: do the data insist?
            got = free_test(res, pairs, exps, data.dt, hold, initial_state, max_iter, tol,
                            reflected, arx_start(res, pairs, exps, data.dt, npo[i], nze[i],
                                                 hold))
            if got is not None:
                insisted.append((f"{data.output_names[i]}<-{data.input_names[got[0]]}",
                                 *got[1:]))
        nums, dens = [], []
        for j, p in enumerate(res["p"]):
            n = int(npo[i, j])
            dens.append(np.concatenate([[1.0], p[:n]]))
            nums.append(p[n:])
        est_delays[i] = res["delays"]
        rows_num.append(nums)
        rows_den.append(dens)
        names = [nm for p in pairs for nm in p.names] + [
            f"{data.output_names[i]}<-{data.input_names[j]}:iodelay" for j in res["delay_index"]]
        tables.append((names, res))
        covs.append(res["covariance"])
        info_out.append(res)
    info = _info(info_out, auto, hold, initial_state)
    info["n_delays_estimated"] = int(l * m) if auto else 0
    G = TransferFunction(rows_num, rows_den, iodelay=est_delays, hold=hold,
                         input_names=data.input_names, output_names=data.output_names,
                         info=info)
    _attach(G, tables, covs, auto)
    if insisted:
        from ..pem.boundary import warn_insisted

        pair, pole, lr = max(insisted, key=lambda x: x[2])
        warn_insisted("tfest's model", pair, pole, 0.0, lr,
                      "pass enforce_stability=False for the unstable model (its simulation "
                      "grows as the plant's does)")
        G.info["insisting"] = [{"pair": a, "pole": b, "statistic": c} for a, b, c in insisted]
    if auto:
        warn_delay_at_bound(est_delays, dmax, max_delay is not None, data)
    coloured_uncertainty(G, data, [len(nm) for nm, _ in tables], hold, initial_state)
    if initial_state == "zero":  # the fit of a simulation from rest, as the model was fitted
        fit_percent(G, data)
    return G


def _refined(pairs: list[PairStructure], exps: list[tuple[np.ndarray, np.ndarray]],
             dt: float, hold: str, initial_state: str, max_iter: int, tol: float, cb: Any
             ) -> tuple[dict[str, Any], list[Any]]:
    """:func:`.refine.refine` of one output, and the warnings it gave (held back: a
    search from another start may replace it)."""
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        res = refine(pairs, exps, dt, hold, x0_mode=initial_state, max_iter=max_iter,
                     tol=tol, progress=cb)
    return res, list(said)


def _second_start(res: dict[str, Any], said: list[Any], pairs: list[PairStructure],
                  exps: list[tuple[np.ndarray, np.ndarray]], data: Any, npo: np.ndarray,
                  nze: np.ndarray, starts: list[Any], auto: bool, dmax: float, hold: str,
                  initial_state: str, max_iter: int, tol: float, cb: Any, i: int
                  ) -> tuple[dict[str, Any], list[PairStructure], list[Any]]:
    """Output ``i``'s search also from the poles of its subspace model
    (:func:`sysid.tf.starts.subspace_pairs`, the delays of the default start): the result
    with the lower criterion is kept (``res["start"]`` names its start), its warnings only
    (the other search's are dropped, as its model is). On the warning audit's clean 2 x 2
    records the SRIVC sweeps left one output's pairs far from the truth (a criterion 10 and
    90 times the subspace start's search's, an IdentifiabilityWarning from a degenerate
    point)."""
    from ..polynomial.starts import RESTART_GAIN
    from .starts import subspace_pairs

    alt = subspace_pairs(exps, data.dt, npo, nze, [float(t) for _, _, t in starts], hold)
    if alt is None:
        return res, pairs, said
    pairs2 = [_pair(a, b, t, auto, dmax if auto else max(dmax, t), data.output_names[i],
                    data.input_names[j]) for j, (a, b, t) in enumerate(alt)]
    try:
        res2, said2 = _refined(pairs2, exps, data.dt, hold, initial_state, max_iter, tol, cb)
    except (DataError, NumericalError):
        return res, pairs, said
    if not res2["cost_history"][-1] < res["cost_history"][-1] * (1 - RESTART_GAIN):
        return res, pairs, said
    res2["start"] = "subspace (n4sid)"
    return res2, pairs2, said2


def warn_delay_at_bound(delays: np.ndarray, dmax: float, given: bool, data: Any) -> None:
    """A :class:`~sysid.DelayWarning` when an estimated dead time (``delays``, outputs x
    inputs of ``data``) ended on the search's upper bound ``dmax`` (``given``: the user's
    ``max_delay``, else a tenth of the record): the fit may improve beyond it."""
    from ..polynomial.delayest import DelayWarning

    names = [f"{o}<-{i}" for o in data.output_names for i in data.input_names]
    at = [n for n, d in zip(names, np.ravel(delays)) if d >= dmax * (1 - 1e-9)]
    if at:
        bound = "max_delay" if given else "the default max_delay (a tenth of the record)"
        warnings.warn(f"the dead time of {', '.join(at)} ended on {bound}, {dmax:g} s: the "
                      "fit may improve beyond it; pass a larger max_delay (or fix the dead "
                      "time if it is known)", DelayWarning, stacklevel=user_stacklevel())


def coloured_uncertainty(model: Any, data: Any, sizes: list[int], hold: str,
                         initial_state: str, limits: tuple[Any, Any] | None = None) -> None:
    """A continuous fit's (``tfest``'s, ``procest``'s) uncertainty for coloured errors, as
    ``oe``'s: the sandwich of :mod:`sysid.pem.sandwich`, per output (``sizes``: its
    parameters, in order), on every record's errors of the simulation the search minimised
    (from rest, or from the initial state it estimated: fitted again for every model, so
    the covariance is the model parameters' own, the initial state's profiled out);
    ``limits``: the parameters' bounds, where the table's intervals stay cut.
    On white errors it is the Gauss-Newton covariance; with coloured ones that was 2-4
    times too small (Monte Carlo in ``tests/test_oe_coloured.py``)."""
    from ..pem.sandwich import defer_sandwich, free_response, with_fitted_state

    records = [(np.asarray(u, float), np.asarray(y, float)) for u, y in data.experiments]
    ys = [y.reshape(len(y), -1) for _, y in records]

    def sim(g: Any) -> list[np.ndarray]:
        out = [g.simulate(u, dt=data.dt, hold=hold) for u, _ in records]
        if initial_state != "estimate":
            return out
        Ad, _, Cd = g.sampled_taps(data.dt, hold)[:3]
        return [with_fitted_state(s, y, free_response(Ad, Cd, len(y)))
                for s, y in zip(out, ys)]

    starts = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
    blocks = [(list(range(starts[i], starts[i + 1])), [i]) for i in range(len(sizes))]
    defer_sandwich(model, sim, ys, blocks, limits)


def _init(init: Any, npo: np.ndarray, nze: np.ndarray) -> Any:
    if init is None:
        return None
    if not isinstance(init, TransferFunction) or init.dt > 0:
        raise DataError("init must be a continuous sysid.TransferFunction")
    for i, j in init.pairs():
        p = np.roots(init.den[i][j])
        if np.any(p.real > 0):  # an integrator (a pole at 0) is admitted by the search
            raise DataError(f"init pair ({i}, {j}) is unstable (pole {p[np.argmax(p.real)]:.4g}"
                            "): tfest fits the simulation error, which diverges there; give a "
                            "stable init (poles in the left half plane)")
    if (init.noutputs, init.ninputs) != npo.shape:
        raise DataError(f"init has {init.noutputs} x {init.ninputs} pairs, the data "
                        f"{npo.shape[0]} x {npo.shape[1]}")
    for i, j in init.pairs():
        if init.den[i][j].size - 1 != npo[i, j] or init.num[i][j].size - 1 > nze[i, j]:
            raise DataError(f"init pair ({i}, {j}) has {init.den[i][j].size - 1} poles and "
                            f"{init.num[i][j].size - 1} zeros; tfest was asked for "
                            f"{npo[i, j]} and {nze[i, j]}")
    nums = [[np.concatenate([np.zeros(nze[i, j] + 1 - init.num[i][j].size), init.num[i][j]])
             for j in range(init.ninputs)] for i in range(init.noutputs)]
    out = TransferFunction(nums, init.den, iodelay=init.iodelay, hold=init.hold)
    out.num = nums  # keep the requested number of numerator coefficients
    return out


def _start_filter(n: int, lam: float) -> np.ndarray:
    return np.real(np.poly(-lam * np.ones(n))) if n else np.ones(1)


def _oe_cost(exps: list[tuple[np.ndarray, np.ndarray]], j: int, a: np.ndarray,
             b: np.ndarray, tau: float, dt: float, hold: str) -> float:
    g = TransferFunction(b, a, iodelay=tau, hold=hold)
    return float(sum(np.sum((y - g.simulate(u[:, j], dt=dt)[:, 0]) ** 2) for u, y in exps))


def _siso_start(exps: list[tuple[np.ndarray, np.ndarray]], j: int, dt: float, n: int, nz: int,
                tau: float, hold: str, lams: Any = None, max_iter: int = 30
                ) -> tuple[np.ndarray, np.ndarray, float, float]:
    """The best SRIVC start over a few initial filters ``(s + lam)^n`` (by the simulation
    error): ``(a, b, cost, lam)``; ``max_iter`` SRIVC iterations at most."""
    wn = np.pi / dt
    best: tuple[float, np.ndarray, np.ndarray, float] | None = None
    for lam in (lams if lams is not None else (wn / 100, wn / 20, wn / 5)):
        a_list, b_list = [], []
        for u, y in exps:
            a, b, _ = srivc(np.ascontiguousarray(u[:, j]), np.ascontiguousarray(y), dt, n, nz,
                            tau, hold, _start_filter(n, lam), max_iter=max_iter)
            a_list.append(a)
            b_list.append(b)
        a, b = np.mean(a_list, axis=0), np.mean(b_list, axis=0)
        if not np.all(np.isfinite(a)) or not np.all(np.isfinite(b)):
            continue
        c = _oe_cost(exps, j, a, b, tau, dt, hold)
        if best is None or c < best[0]:
            best = (c, a, b, lam)
    if best is None:
        raise DataError("the instrumental-variable start failed (no finite estimate): check "
                        "that the input excites the system, or lower n_poles")
    return best[1], best[2], best[0], best[3]


def _delay_grid(exps: list[tuple[np.ndarray, np.ndarray]], j: int, dt: float, dmax: float
                ) -> list[float]:
    """Candidate delays (whole samples) of input ``j``: every one up to ``DELAY_SCAN`` samples
    (within ``dmax`` and a quarter of the record) and those around the ARX delay estimate.
    The ARX estimate alone (second-order ARX) misses the delay of slow, lagging processes
    (a heating system: 1 sample where 6 fit best), and the output-error cost is not unimodal
    in the delay, so the SRIVC starts scan them all (about 8 ms each)."""
    from ..data.iodata import IOData
    from ..polynomial.delayest import DelayWarning, delayest

    u = np.concatenate([u[:, j] for u, _ in exps])
    y = np.concatenate([y for _, y in exps])
    kmax = max(int(min(dmax, 0.25 * u.size * dt) / dt), 1)
    try:
        with warnings.catch_warnings():  # a start: its range is not the user's to widen
            warnings.simplefilter("ignore", DelayWarning)
            nk = delayest(IOData(u[:, None], y[:, None], dt), 2, 2, 0, min(kmax + 1, 60))
    except Exception:  # the grid below still covers the start
        nk = 1
    # a strictly proper ZOH-sampled system without delay has nk = 1
    near = set(range(max(nk - 2, 0), min(nk + 1, kmax) + 1))
    return [k * dt for k in sorted(near | set(range(min(DELAY_SCAN, kmax) + 1)))
            if k * dt <= dmax]


#: whole-sample delays every SRIVC start scans (:func:`_delay_grid`)
DELAY_SCAN = 40
#: SRIVC iterations per delay of the scan, and the delays of the lowest costs then iterated
#: to convergence: the scan ranks 41 delays by the simulation error of a few iterations
#: (most of SRIVC's fall there) instead of iterating every one out (0.9 s on 2000 samples)
SCAN_ITER, SCAN_KEEP = 4, 3


def _starts(exps: list[tuple[np.ndarray, np.ndarray]], dt: float, npo: np.ndarray,
            nze: np.ndarray, delays: np.ndarray, auto: bool, hold: str, dmax: float
            ) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """Per input ``(a, b, delay)``: SRIVC, inputs fitted in turn on what the others leave
    (three sweeps when there are several); ``auto`` delays from the whole-sample candidates
    of :func:`_delay_grid` in the first sweep, then from the chosen one's neighbours."""
    m = npo.size
    cur = [(np.ones(1), np.zeros(1), float(delays[j])) for j in range(m)]
    grids = [_delay_grid(exps, j, dt, dmax) if auto else [float(delays[j])] for j in range(m)]
    lams: list[Any] = [None] * m
    for _ in range(1 if m == 1 else 3):
        for j in range(m):
            rest = [(u, y - sum(TransferFunction(cur[k][1], cur[k][0], iodelay=cur[k][2],
                                                 hold=hold).simulate(u[:, k], dt=dt)[:, 0]
                                for k in range(m) if k != j))
                    for u, y in exps]
            n_j, z_j = int(npo[j]), int(nze[j])
            grid = grids[j]
            if len(grid) > SCAN_KEEP:  # ranked by a few iterations, the best few iterated out
                ranked = []
                for tau in grid:
                    _, _, c, lam = _siso_start(rest, j, dt, n_j, z_j, tau, hold, lams[j],
                                               SCAN_ITER)
                    lams[j] = [lam]
                    ranked.append((c, tau))
                grid = [t for _, t in sorted(ranked, key=lambda r: r[0] if np.isfinite(r[0])
                                             else np.inf)[:SCAN_KEEP]]
            best = None
            for tau in grid:
                a, b, c, lam = _siso_start(rest, j, dt, n_j, z_j, tau, hold, lams[j])
                lams[j] = [lam]
                if best is None or c < best[3]:
                    best = (a, b, tau, c)
            assert best is not None
            cur[j] = best[:3]
            if auto:  # later sweeps: the chosen delay and its neighbours
                grids[j] = [t for t in (best[2] - dt, best[2], best[2] + dt)
                            if -1e-9 <= t <= dmax]
    return cur


def _pair(a: np.ndarray, b: np.ndarray, tau: float, auto: bool, dmax: float, yname: str,
          uname: str) -> PairStructure:
    n = a.size - 1

    def coef(p: np.ndarray, n: int = n) -> tuple[np.ndarray, np.ndarray]:
        return p[n:], np.concatenate([[1.0], p[:n]])

    p0 = np.concatenate([a[1:], b])
    k = p0.size
    names = [f"{yname}<-{uname}:a{i + 1}" for i in range(n)] + \
        [f"{yname}<-{uname}:b{i}" for i in range(b.size)]
    return PairStructure(coef, p0, np.zeros(k, bool), np.full(k, -np.inf), np.full(k, np.inf),
                         tau, auto, dmax, names)


def _info(results: list[dict[str, Any]], auto: bool, hold: str, x0: str) -> dict[str, Any]:
    return {"method": "tfest (SRIVC + output error)",
            "iterations": [r["iterations"] for r in results],
            "stop": [r["stop"] for r in results],
            "cost": [float(r["cost_history"][-1]) for r in results],
            "cost_start": [float(r["cost_history"][0]) for r in results],
            "start": [r.get("start", "SRIVC") for r in results],
            "noise_variance": [r["noise_variance"] for r in results],
            "n_samples": results[0]["n_samples"], "hold": hold, "initial_state": x0,
            "delays": "estimated" if auto else "fixed"}


def _attach(G: TransferFunction, tables: list[Any], covs: list[np.ndarray], auto: bool) -> None:
    names, values, stds, undetermined = [], [], [], []
    for (nm, res), cov in zip(tables, covs):
        undetermined += [len(names) + int(i) for i in res.get("unidentifiable", [])]
        v = np.concatenate([np.concatenate(res["p"]),
                            [res["delays"][j] for j in res["delay_index"]]])
        names += nm
        values.append(v)
        sd = np.sqrt(np.clip(np.diag(cov), 0, None))
        sd[res.get("unidentifiable", [])] = np.inf
        stds.append(sd)
    theta = np.concatenate(values)
    fixed = np.array(["iodelay" in n and not auto for n in names])
    G.parameters = ParameterTable(names, theta, np.concatenate(stds), fixed)
    P = blockdiag(covs)
    shapes = [(len(nm), res) for nm, res in tables]
    proto = G

    def build(t: np.ndarray) -> TransferFunction:
        t = np.asarray(t, dtype=float)
        nums, dens, dl = [], [], proto.iodelay.copy()
        o = 0
        for i, (_k, res) in enumerate(shapes):
            row_n, row_d = [], []
            for j, p in enumerate(res["p"]):
                n = proto.den[i][j].size - 1
                q = t[o:o + p.size]
                row_d.append(np.concatenate([[1.0], q[:n]]))
                row_n.append(q[n:])
                o += p.size
            for j in res["delay_index"]:
                dl[i, j] = t[o]
                o += 1
            nums.append(row_n)
            dens.append(row_d)
        return TransferFunction(nums, dens, iodelay=np.maximum(dl, 0), hold=proto.hold,
                                input_names=proto.input_names,
                                output_names=proto.output_names)

    G.uncertainty = ParameterUncertainty(theta, P, build, names=names,
                                         undetermined=undetermined)


def _periodic(data: Any, npo: np.ndarray, nze: np.ndarray, delays: np.ndarray, auto: bool,
              dt: float | None, periods: Any, transient: Any, max_iter: int, tol: float,
              progress: Any, stable: bool = False, ft: bool = False
              ) -> tuple[TransferFunction | None, dict[str, Any]]:
    """The discrete model fitted on the excited lines of periodic data (the FRD branch on
    :func:`sysid.bla` of the record), and what was found of the periodicity; no model when
    ``periods="auto"`` finds no usable period (the caller then fits in the time domain)."""
    from .frequency import record_lines, tfest_frd

    if dt is None:
        raise DataError("periods= fits a discrete-time model on the excited lines of the "
                        "sampled record: pass dt=data.dt, or leave periods out for a "
                        "continuous-time model")
    lines, periodicity = record_lines(data, periods, transient)
    if lines is None:
        return None, periodicity
    nk = _whole_delays(data, delays, auto, dt, ft)
    G = tfest_frd(lines, npo, nze, iodelay=nk, dt=dt, max_iter=max_iter, tol=tol,
                  progress=progress, stable=stable, feedthrough=ft)
    G.info.update(method="tfest (periodic data: weighted NLS on the excited lines)",
                  domain="frequency", lines=int(lines.omega.size),
                  periods=lines.info.get("periods"), periodicity=periodicity,
                  n_delays_estimated=int(nk.size) if auto else 0)
    return G, periodicity


def _whole_delays(data: Any, delays: np.ndarray, auto: bool, dt: float,
                  ft: bool = False) -> np.ndarray:
    """A discrete model's delays in whole samples: estimated (``auto``) or checked."""
    if abs(float(dt) - data.dt) > 1e-9 * data.dt:
        raise DataError(f"dt={dt} differs from the data's sample time {data.dt}: resample the "
                        "data first (sysid.resample) or pass dt=data.dt")
    if auto:  # delayest counts the model's one-sample lag too (none with feedthrough)
        lag0 = 0 if ft else 1
        return np.array([[max(_delayest_one(data, i, j) - lag0, 0)
                          for j in range(data.n_inputs)] for i in range(data.n_outputs)],
                        dtype=float)
    if np.any(np.abs(delays - np.round(delays)) > 1e-9):
        raise DataError("a discrete model's iodelay counts whole samples; round it")
    return np.round(delays)


def _discrete(data: Any, npo: np.ndarray, nze: np.ndarray, delays: np.ndarray, auto: bool,
              dt: float, max_iter: int, progress: Any, ft: bool = False,
              initial_state: str = "zero") -> TransferFunction:
    """Discrete-time variant: output error ``B(q)/F(q) q^-nk`` per output (``sysid.oe``, its
    ``initial_condition`` the ``initial_state``),
    with the parameter table, uncertainty and ``info`` of the continuous fit (per pair
    ``[a_1.., b_0..]``; ``info["cost"]`` the final cost per output)."""
    import sysid

    from .frequency import descending

    nk = _whole_delays(data, delays, auto, dt, ft)
    l, m = data.n_outputs, data.n_inputs
    lag0 = 0 if ft else 1  # a one-sample lag as MATLAB's discrete tfest (none: feedthrough)
    lag = lag0 + np.round(nk).astype(int)
    with warnings.catch_warnings():  # tfest checks its own lag (tf.feedthrough), in its words
        warnings.filterwarnings("ignore", category=sysid.FeedthroughWarning)
        poly = sysid.oe(data, nze + 1, npo, lag, max_iter=max_iter, progress=progress,
                        initial_condition=initial_state)
    nb = [[poly.b[i][j].size for j in range(m)] for i in range(l)]
    nf = [[poly.f[i][j].size for j in range(m)] for i in range(l)]

    def from_pairs(b: list[list[np.ndarray]], f: list[list[np.ndarray]]) -> TransferFunction:
        # the one-sample lag in B, the delay as the model's iodelay (MATLAB's IODelay in
        # samples), not as powers of z folded into the denominator
        pairs = [[descending(b[i][j], np.concatenate([[1.0], f[i][j]]), lag0)
                  for j in range(m)] for i in range(l)]
        return TransferFunction([[p[0] for p in r] for r in pairs],
                                [[p[1] for p in r] for r in pairs], dt=data.dt, iodelay=nk,
                                input_names=data.input_names, output_names=data.output_names)

    G = from_pairs(poly.b, poly.f)
    hist = poly.info["cost"]
    G.info = {**poly.info, "method": "tfest (discrete, output error)",
              "cost": [float(h[-1]) for h in hist], "cost_start": [float(h[0]) for h in hist],
              "noise_variance": [float(v) for v in np.ravel(poly.noise_variance)],
              "n_samples": int(sum(u.shape[0] for u, _ in data.experiments)),
              "delays": "estimated" if auto else "fixed"}
    from ..pem.sandwich import gauss_newton

    deferred = getattr(poly, "uncertainty", None)
    unc = gauss_newton(deferred)  # oe's sandwich, if it has one, waits for its first use
    if unc is not None:
        # oe's parameters per output are [b_i1.., f_i1..]; the table's per pair [a.., b..]
        names, order, o = [], [], 0
        for i in range(l):
            b_at = o + np.cumsum([0, *nb[i]])[:-1]
            f_at = o + sum(nb[i]) + np.cumsum([0, *nf[i]])[:-1]
            for j in range(m):
                pre = f"{data.output_names[i]}<-{data.input_names[j]}:"
                names += [f"{pre}a{k + 1}" for k in range(nf[i][j])] + \
                    [f"{pre}b{k}" for k in range(nb[i][j])]
                order += list(range(f_at[j], f_at[j] + nf[i][j]))
                order += list(range(b_at[j], b_at[j] + nb[i][j]))
            o += sum(nb[i]) + sum(nf[i])
        theta, P = unc.theta[order], unc.covariance[np.ix_(order, order)]
        G.parameters = ParameterTable(names, theta, np.sqrt(np.clip(np.diag(P), 0, None)),
                                      np.zeros(theta.size, bool))

        def build(t: np.ndarray) -> TransferFunction:
            t, at = np.asarray(t, dtype=float), 0
            b: list[list[np.ndarray]] = [[] for _ in range(l)]
            f: list[list[np.ndarray]] = [[] for _ in range(l)]
            for i in range(l):
                for j in range(m):
                    f[i].append(t[at:at + nf[i][j]])
                    b[i].append(t[at + nf[i][j]:at + nf[i][j] + nb[i][j]])
                    at += nf[i][j] + nb[i][j]
            return from_pairs(b, f)

        G.uncertainty = ParameterUncertainty(theta, P, build, names=names, method=unc.method)
        if deferred is not unc:
            _defer(G, poly, order)
    fit_percent(G, data)
    return G


def _defer(G: TransferFunction, poly: Any, order: list[int]) -> None:
    """``G``'s uncertainty and parameter table wait, as ``oe``'s (``poly``), for their first
    use to become the sandwich for coloured errors (:mod:`sysid.pem.sandwich`), in the
    table's order; ``info["covariance"]`` follows ``oe``'s."""
    from ..pem.sandwich import DeferredSandwich, DeferredTable

    base = G.uncertainty
    ix = np.ix_(order, order)

    def form() -> tuple[ParameterUncertainty | None, str]:
        pu = poly.uncertainty
        P = pu.covariance  # forms oe's, which says which it is
        return (ParameterUncertainty(base.theta, P[ix], base.build, names=base.names,
                                     dof=pu.dof, method=pu.method),
                poly.info["covariance"])

    def then(note: str) -> None:
        G.info["covariance"] = note
    G.uncertainty = DeferredSandwich(base, form, then)
    G.parameters = DeferredTable(G.parameters, G.uncertainty)


def _delayest_one(data: Any, i: int, j: int) -> int:
    from ..polynomial.delayest import delayest

    sub = data.select(outputs=[i], inputs=[j]) if hasattr(data, "select") else data
    return delayest(sub)
