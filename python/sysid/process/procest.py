"""``sysid.procest``: low-order continuous-time process models (MATLAB's ``procest``)."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from .._checks import require_inputs_vary
from .._threads import one_blas_thread
from ..errors import DataError, NumericalError
from ..models.paramtable import ParameterTable
from ..models.uncertainty import ParameterUncertainty
from ..validation.output_error import output_error
from .model import ProcessModel
from .structure import ProcessType

__all__ = ["procest"]


@output_error("procest")
@one_blas_thread
def procest(data: Any, type_code: Any, *, init: Mapping[str, float] | None = None,
            fixed: Mapping[str, float] | None = None,
            bounds: Mapping[str, tuple[float, float]] | None = None, hold: str = "zoh",
            initial_state: str = "zero", max_delay: float | None = None,
            max_iter: int = 100, tol: float = 1e-10,
            progress: bool | None | Callable[..., Any] = None) -> ProcessModel:
    """Estimate a process model such as first order plus dead time (MATLAB's ``procest``).

    .. math::

        G(s) = K_p \\frac{1 + T_z s}{(1 + T_{p1} s)(1 + T_{p2} s)(1 + T_{p3} s)}
        \\frac{1}{s^{[I]}} e^{-T_d s}

    The continuous-time model is fitted to the sampled record with the input's inter-sample
    behaviour (``hold``), the dead time sampled exactly (any value, not only whole samples),
    by minimising the simulation error on the shared Gauss-Newton search; the start comes
    from refined instrumental variables (SRIVC). Each parameter gets its standard deviation.
    A free parameter the search leaves on a bound (an undamped pair, a time constant run to
    zero), and a time constant whose pole acts within one sample (the model is then in effect
    a simpler type, :meth:`ProcessModel.collapsed`), are named in a
    :class:`~sysid.BoundWarning` with what to change.

    Parameters
    ----------
    data : IOData
        Sampled record (one model per output/input pair; several inputs add up).
    type_code : str
        MATLAB type code: ``P`` + poles (0-3) + any of ``D`` (dead time), ``Z`` (zero),
        ``I`` (integrator), ``U`` (underdamped), e.g. ``"P1D"``, ``"P2DU"``, ``"P1DI"``.
    init : dict, optional
        Starting values by name (``Kp``, ``Tp1``, ``Tp2``, ``Tp3``, ``Tw``, ``Zeta``,
        ``Tz``, ``Td``) instead of the automatic start. Equal time constants to estimate
        (``Tp1 == Tp2``, to 1e-6) start spread apart as the automatic start's are (ratio
        1.25, their product kept, the first named the slower): the fit is symmetric in
        them, so a search started equal could not separate them.
    fixed : dict, optional
        Parameters held at the given values.
    bounds : dict, optional
        ``{name: (lower, upper)}``; time constants and damping are positive by default.
    hold : {"zoh", "foh"}
        Inter-sample behaviour of the input.
    initial_state : {"zero", "estimate"}
        Start from rest, or estimate the initial state of each experiment (the model's
        state; the input before the record, which the dead time would still deliver, is taken
        as zero).
    max_delay : float, optional
        Upper bound on the dead time (default a tenth of the record).
    max_iter, tol, progress
        Search limits and progress display.

    Returns
    -------
    ProcessModel

    Examples
    --------
    >>> import numpy as np, sysid
    >>> true = sysid.ProcessModel("P1D", Kp=2.0, Tp1=1.5, Td=0.37)
    >>> u = np.repeat(np.random.default_rng(1).choice([-1.0, 1.0], 60), 10)
    >>> data = sysid.IOData(u, true.simulate(u, dt=0.1), dt=0.1)
    >>> m = sysid.procest(data, "P1D")
    >>> {k: round(v, 6) for k, v in m.values.items()}
    {'Kp': 2.0, 'Tp1': 1.5, 'Td': 0.37}
    """
    from ..tf.options import fit_percent, progress_callback, search_limits
    from ..tf.refine import check_experiments, refine
    from ..tf.tfest import coloured_uncertainty, warn_delay_at_bound

    t = ProcessType.parse(type_code)
    max_iter, tol = search_limits(max_iter, tol, max_delay)
    if not hasattr(data, "experiments") or not hasattr(data, "dt"):
        from ..errors import is_frd

        raise DataError(
            f"procest needs a sysid.IOData, got {type(data).__name__}; " + (
                "procest fits time-domain records: for frequency-response data use "
                "sysid.tfest(frd, n_poles, n_zeros, iodelay='auto') (a process model is a "
                "transfer function with a delay)" if is_frd(data) else
                "wrap arrays as sysid.IOData(u, y, dt=...)"))
    if hold not in ("zoh", "foh"):
        raise DataError(f"hold must be 'zoh' or 'foh', got {hold!r}")
    if initial_state not in ("zero", "estimate"):
        raise DataError(f"initial_state must be 'zero' or 'estimate', got {initial_state!r}")
    if data.n_inputs == 0:
        raise DataError("procest needs at least one input")
    from ..data.offsets import check_offsets

    # a process model has no constant term (as every estimator); from rest, no state
    check_offsets(data, from_rest=initial_state == "zero")
    if t.poles == 0 and not t.integrator:
        raise DataError(f"{t.code} (a pure gain and dead time) is not supported: the sampled "
                        "response of a pure delay is not smooth in the dead time; fit 'P1D' "
                        "(a small Tp1) instead")
    init, fixed, bounds = _options(t, init, fixed, bounds)
    exps_all = [(np.asarray(u, float), np.asarray(y, float)) for u, y in data.experiments]
    require_inputs_vary(exps_all, "procest", data.input_names)
    # a constant output has no response to fit (its gain came out 1.5e7)
    require_inputs_vary(exps_all, "procest", data.output_names, side=1)
    N = sum(u.shape[0] for u, _ in exps_all)
    dmax = max_delay if max_delay is not None else 0.1 * N * data.dt / len(exps_all)
    given = {**init, **fixed}.get("Td")
    if given is not None and given > dmax:
        if max_delay is not None:
            raise DataError(f"the dead time given ({given:g} s) is beyond max_delay = "
                            f"{max_delay:g} s: raise max_delay or give a shorter Td")
        # the default bound (a tenth of the record) takes the user's value: a fixed one as
        # it is, a start with the default's room beyond it
        dmax = given + (0.0 if "Td" in fixed else dmax)
    names = [n for n in t.names if n != "Td"]
    # an integrator is fitted through the integrated input: under a zero-order hold its
    # integral is piecewise linear through dt * cumsum(u), exactly a first-order hold
    fit_t, fit_hold = t, hold
    if t.integrator:
        if hold != "zoh":
            raise DataError(f"{t.code} with hold='foh' is not supported (the integrated input "
                            "would need a second-order hold); use hold='zoh'")
        fit_t = ProcessType(t.poles, t.delay, t.zero, False, t.underdamped)
        exps_all = [(np.vstack([np.zeros((1, u.shape[1])), np.cumsum(u, axis=0)[:-1]
                                * data.dt]), y) for u, y in exps_all]
        fit_hold = "foh"
    l, m = data.n_outputs, data.n_inputs
    cb, close = progress_callback(progress, max_iter)
    values, covs, infos, weak = [], [], [], []
    try:
        for i in range(l):
            exps = [(u, y[:, i]) for u, y in exps_all]
            check_experiments(exps, len(t.names) * m)
            pairs = []
            for j in range(m):
                start = _start(fit_t, exps, j, data.dt, fit_hold, dmax, init, fixed)
                pairs.append(_pair(fit_t, names, start, fixed, bounds, dmax,
                                   f"{data.output_names[i]}<-{data.input_names[j]}"))
            fix = (f"Fix one of them (fixed={{...}}), fit a simpler type than {t.code} or "
                   "use more informative data")
            try:
                with warnings.catch_warnings(record=True) as said:
                    warnings.simplefilter("always")
                    res = refine(pairs, exps, data.dt, fit_hold, x0_mode=initial_state,
                                 max_iter=max_iter, tol=tol, progress=cb, fix=fix)
            except NumericalError as e:
                raise _diverged(e, t, data) from e
            nested = _nested_pairs(fit_t, exps, data, fit_hold, dmax, init, fixed, bounds,
                                   names, i)
            if nested is not None:  # also from the one-pole fit embedded: keep the lower
                try:
                    with warnings.catch_warnings(record=True) as said_alt:
                        warnings.simplefilter("always")
                        alt = refine(nested, exps, data.dt, fit_hold, x0_mode=initial_state,
                                     max_iter=max_iter, tol=tol, progress=cb, fix=fix)
                    if alt["cost_history"][-1] < res["cost_history"][-1]:
                        res, said = alt, said_alt
                except NumericalError:
                    pass
            for w in said:  # the kept search's warnings
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
            vals = []
            for j in range(m):
                v = dict(zip(names, map(float, res["p"][j])))
                if t.delay:
                    v["Td"] = float(res["delays"][j])
                vals.append(v)
            values.append(vals)
            covs.append(_full_cov(res, t, names, m))
            weak.append(_weak(res, t, names, m))
            infos.append(res)
    finally:
        close()
    model = ProcessModel(t.code, values=values, hold=hold, input_names=data.input_names,
                         output_names=data.output_names)
    model.info.update({
        "method": "procest (SRIVC start + output error)",
        "iterations": [r["iterations"] for r in infos], "stop": [r["stop"] for r in infos],
        "cost": [float(r["cost_history"][-1]) for r in infos],
        "cost_start": [float(r["cost_history"][0]) for r in infos],
        "noise_variance": [r["noise_variance"] for r in infos],
        "n_samples": infos[0]["n_samples"], "initial_state": initial_state,
        "fixed": sorted(fixed)})
    limits = _attach(model, covs, fixed, weak,
                     {k: bounds.get(k, (max(bounds.get("Td", (0.0, dmax))[0], 0.0),
                                        min(bounds.get("Td", (0.0, dmax))[1], dmax))
                                    if k == "Td" else t.default_bounds(k)) for k in t.names})
    if t.delay and "Td" not in fixed and not ("Td" in bounds and bounds["Td"][1] <= dmax):
        warn_delay_at_bound(np.array([[v["Td"] for v in row] for row in values]), dmax,
                            max_delay is not None, data)
    model.info["sample_time"] = float(data.dt)
    _warn_bounds(model, t, fixed, bounds, limits)
    coloured_uncertainty(model, data, [c.shape[0] for c in covs], hold, initial_state, limits)
    if initial_state == "zero":  # the fit of a simulation from rest, as the model was fitted
        fit_percent(model, data)
    return model


def _warn_bounds(model: ProcessModel, t: ProcessType, fixed: dict[str, float],
                 bounds: dict[str, tuple[float, float]], limits: tuple[Any, Any]) -> None:
    """A :class:`~sysid.BoundWarning` naming every free parameter the search left on one of
    its ``limits`` (what that means: a time constant run to zero, an undamped pair) and the
    options to change, and what a pair with a pole that acts within one sample is in effect
    (:meth:`ProcessModel.collapsed`): the wing flutter's ``P2DU`` ended at ``Zeta = 1e-9``
    (validation -131 %) and ``P2`` on the ball and beam at ``Tp2 = 1e-9`` (coefficients
    1e9 .. 1e18), said nowhere. A dead time of 0 on its default bound is an answer (no dead
    time), and one on the default ``max_delay`` has its own :class:`~sysid.DelayWarning`:
    neither is listed here."""
    from .._checks import user_stacklevel
    from ..errors import BoundWarning

    gone = model.collapsed()
    table, (lo, hi) = model.parameters, limits
    said, names, c, values, fasts = [], [], 0, {}, {}
    structural = bool(gone)  # a pole run to zero or an undamped pair, not a user's bound
    for i, j in model.pairs():
        pair = f"{model.output_names[i]}<-{model.input_names[j]}"
        vals = values[pair] = model._values[i][j]
        fast = fasts[pair] = t.fast(vals, model.info["sample_time"]) if pair in gone else {}
        for k in t.names:
            side, full, c = table.bound[c], table.names[c], c + 1
            if not side or k in fixed or (k == "Td" and "Td" not in bounds):
                continue
            if side == "lower" and (k in fast or ("pair" in fast and k in ("Tw", "Zeta"))):
                names.append(k)
                continue  # said with the pair's collapse below
            edge = lo[c - 1] if side == "lower" else hi[c - 1]
            what = ""
            if side == "lower" and k == "Zeta" and edge <= 1e-6:
                what = (f": an undamped pair, an oscillation at {1.0 / abs(vals['Tw']):.4g} "
                        "rad/s that never decays")
            elif side == "lower" and k in ("Tp1", "Tp2", "Tp3", "Tw") and edge <= 1e-9:
                what = ": a time constant run to zero"
            structural |= bool(what)
            said.append(f"{full} = {vals[k]:.4g} on its {side} bound ({edge:.4g}){what}")
            names.append(k)
    dt = model.info["sample_time"]
    for pair, (code, text) in gone.items():
        vals, fast = values[pair], fasts[pair]
        which = [f"{k} = {vals[k]:.4g}" for k in fast if k != "pair"]
        names += [k for k in fast if k != "pair"]
        if "pair" in fast:
            which.append(f"Tw = {vals['Tw']:.4g}, Zeta = {vals['Zeta']:.4g} ("
                         + ("one pole" if fast["pair"] == "one" else "both poles")
                         + " of the pair)")
            names.append("Tw")
        said.append(f"{pair}: {', '.join(which)}: a pole that acts within one sample "
                    f"(dt = {dt:g}): in effect "
                    + (f"{code}, {text}" if code[1] != "0" or "I" in code else
                       f"a static gain, {text}"))
    if not said:
        return
    k = names[0] if names else next((n for n in t.names if n.startswith("T")), "Kp")
    # a static gain (no pole left) is fitted as 'P1D' with a small Tp1: not a type to name
    simpler = sorted({code for code, _ in gone.values() if code[1] != "0" or "I" in code})
    fix = (f"a start (init={{{k!r}: ...}}) or the bounds (bounds={{{k!r}: (lower, "
           "upper)})")
    if structural:
        fix = ("the data do not support that structure: fit " + "".join(
            f"{x!r} or " for x in simpler) + "another type (a zero 'Z', fewer or more "
            "poles), or change the search: " + fix)
    else:
        fix = "the fit may improve beyond it: widen the bounds or start elsewhere, " + fix
    warnings.warn(f"procest({t.code!r}): " + "; ".join(said) + ". " + fix[0].upper()
                  + fix[1:], BoundWarning, stacklevel=user_stacklevel())


def _nested_pairs(t: ProcessType, exps: list[tuple[np.ndarray, np.ndarray]], data: Any,
                  hold: str, dmax: float, init: dict[str, float], fixed: dict[str, float],
                  bounds: dict[str, tuple[float, float]], names: list[str], i: int
                  ) -> list[Any] | None:
    """Starts for a type of several poles from the one-pole fit's start embedded in it (the
    other time constants a twentieth of ``Tp1``, a zero near the second pole, the one-pole
    start's delay): a type that holds the one-pole model can then fit no worse than it
    (``P2DZ`` on the ball and beam and the robot arm ended above ``P1D`` from the SRIVC start
    alone: 1.0096 against 0.5646, 32.45 against 31.60). An underdamped type (``U``) holds it
    too, its pair overdamped: the pair of real time constants ``Ta, Tb`` is ``Tw = sqrt(Ta
    Tb)``, ``Zeta = (Ta + Tb) / (2 Tw)`` (``P2U``'s the two slowest, ``P3U``'s the two
    fastest beside ``Tp3 = Tp1``); from the SRIVC start alone ``P2DU`` ended at
    ``Tw = Zeta = 1e-9`` and 18 times ``P1D``'s cost on the DaISy heating system. ``None``
    when the type has one pole, the user set parameters, or the output has several inputs
    (there the second search's delay moves took procest(winding, "P2D") from 67 to 186 s:
    left out)."""
    if data.n_inputs > 1 or t.poles < 2 or init or fixed:
        return None
    s1 = _start(ProcessType(1, t.delay, False, False, False), exps, 0, data.dt, hold, dmax,
                {}, {})
    start = {"Kp": s1["Kp"], "Tp1": s1["Tp1"], "Td": s1.get("Td", 0.0)}
    for k in range(2, t.poles + 1):
        start[f"Tp{k}"] = s1["Tp1"] / 20.0 ** (k - 1)
    if t.zero:
        start["Tz"] = start["Tp2"] * 1.5
    if t.underdamped:
        ta, tb = (start["Tp1"], start["Tp2"]) if t.poles == 2 else (start["Tp2"],
                                                                      start["Tp3"])
        start["Tp3"] = start["Tp1"]
        start["Tw"] = float(np.sqrt(ta * tb))
        start["Zeta"] = (ta + tb) / (2.0 * start["Tw"])
    return [_pair(t, names, {k: start[k] for k in t.names}, fixed, bounds, dmax,
                  f"{data.output_names[i]}<-{data.input_names[0]}")]


def _diverged(e: NumericalError, t: ProcessType, data: Any) -> NumericalError:
    """The error of a search that ran to where the model's sensitivities overflow: on data
    with offsets the core's advice (remove them) stands; without any, the structure itself
    does not fit the data (two real poles for an oscillating response: the time constants
    run to 0 or infinity), which the core's message cannot know."""
    u = np.vstack([np.asarray(e[0], float) for e in data.experiments])
    y = np.vstack([np.asarray(e[1], float) for e in data.experiments])
    # an offset beside the variation (not only one that dwarfs it, as the offset warning's):
    # then it may be what drove the search, and the core's advice to remove it stands
    level = np.abs(np.r_[u.mean(0), y.mean(0)]) > np.r_[u.std(0), y.std(0)]
    if "sensitivities overflow" not in str(e) or level.any():
        return e
    hint = ("'P2U' (complex poles) if the response oscillates, " if t.poles == 2
            and not t.underdamped else "")
    return NumericalError(
        f"procest({t.code!r}): the output-error search ran to parameters where the model's "
        f"sensitivities overflow (a time constant driven towards 0 or infinity) on data "
        f"without offsets: the {t.code} structure does not fit them. Try another type "
        f"({hint}fewer or more poles, a zero 'Z', a delay 'D') or give a start "
        f"(init={{...}}) near what a step or frequency response of the data suggests")


def _options(t: ProcessType, init: Any, fixed: Any, bounds: Any
             ) -> tuple[dict[str, float], dict[str, float], dict[str, tuple[float, float]]]:
    out = []
    for what, d in (("init", init), ("fixed", fixed), ("bounds", bounds)):
        d = dict(d or {})
        bad = sorted(set(d) - set(t.names))
        if bad:
            raise DataError(f"{what}: {bad} are not parameters of {t.code}; its parameters "
                            f"are {t.names}")
        out.append(d)
    init, fixed, bounds = out
    for k, v in {**init, **fixed}.items():
        if not np.isfinite(float(v)):
            raise DataError(f"{k} must be finite, got {v}")
    for k, b in bounds.items():
        try:
            lo, hi = float(b[0]), float(b[1])
        except (TypeError, ValueError, IndexError):
            raise DataError(f"bounds[{k!r}] must be a pair (lower, upper), got {b!r}") from None
        if not lo < hi:
            raise DataError(f"bounds[{k!r}] = ({lo}, {hi}): lower must be below upper")
        bounds[k] = (lo, hi)
    for what, d in (("init", init), ("fixed", fixed)):
        for k, v in d.items():
            lo, hi = bounds.get(k, t.default_bounds(k))
            if not lo <= float(v) <= hi:
                why = ("time constants and damping are positive" if k not in bounds and k != "Td"
                       else "a dead time is not negative" if k not in bounds else
                       f"bounds[{k!r}] = ({lo:g}, {hi:g})")
                raise DataError(f"{what}[{k!r}] = {float(v):g} is outside the range of {k} "
                                f"({why}): give a value inside it")
    return ({k: float(v) for k, v in init.items()}, {k: float(v) for k, v in fixed.items()},
            bounds)


def _start(t: ProcessType, exps: list[tuple[np.ndarray, np.ndarray]], j: int, dt: float,
           hold: str, dmax: float, init: dict[str, float], fixed: dict[str, float]
           ) -> dict[str, float]:
    """Starting values: SRIVC for the pole/zero structure (the integrator through the
    integrated input, exact under FOH), then the process parameters read off it."""
    from ..tf.tfest import _starts

    given = {**init, **fixed}
    if set(t.names) <= set(given):
        return _apart(t, dict(given), fixed)
    tau = given.get("Td", 0.0)
    auto = t.delay and "Td" not in given
    use, h = exps, hold
    n = t.poles
    if n == 0:
        v = _gain_only(use, j, dt)
        out = {"Kp": v, "Tz": 0.0, "Td": tau}
    else:
        one = [(u[:, [j]], y) for u, y in use]
        (a, b, d), = _starts(one, dt, np.array([n]), np.array([int(t.zero)]),
                             np.array([tau]), auto, h, dmax)
        out = _from_tf(t, a, b)
        out["Td"] = d
    out.update(given)
    return _apart(t, {k: out[k] for k in t.names}, fixed)


def _apart(t: ProcessType, start: dict[str, float], fixed: dict[str, float]
           ) -> dict[str, float]:
    """``start`` with its equal free time constants (a user's ``init``) spread as
    :func:`_distinct` spreads the automatic start's, the first named the slower; distinct
    ones and fixed ones are kept."""
    if t.underdamped:
        return start
    free = [k for k in (f"Tp{i + 1}" for i in range(t.poles)) if k not in fixed and k in start]
    vals = [start[k] for k in free]
    spread = _distinct(vals)  # slowest first
    if sorted(spread) == sorted(vals):
        return start
    order = sorted(range(len(free)), key=lambda i: -vals[i])  # stable: equal ones by name
    for rank, i in enumerate(order):
        start[free[i]] = spread[rank]
    return start


def _gain_only(exps: list[tuple[np.ndarray, np.ndarray]], j: int, dt: float) -> float:
    num = sum(float(u[:, j] @ y) for u, y in exps)
    den = sum(float(u[:, j] @ u[:, j]) for u, _ in exps)
    return num / den if den > 0 else 1.0


def _from_tf(t: ProcessType, a: np.ndarray, b: np.ndarray) -> dict[str, float]:
    p = np.roots(a)
    out: dict[str, float] = {"Kp": float(b[-1] / a[-1]) if a[-1] != 0 else 1.0}
    order = np.argsort(np.abs(p))                       # slowest first
    p = p[order]
    if t.underdamped:
        cpx = [k for k in range(p.size) if abs(p[k].imag) > 0]
        pair = cpx[:2] if len(cpx) >= 2 else [0, 1]
        prod = float(np.real(p[pair[0]] * p[pair[1]]))
        s = float(np.real(p[pair[0]] + p[pair[1]]))
        w = np.sqrt(abs(prod)) if prod != 0 else 1.0
        out["Tw"] = 1.0 / w
        out["Zeta"] = float(np.clip(-s / (2 * w), 0.05, 5.0))
        rest = [k for k in range(p.size) if k not in pair]
        if t.poles == 3:
            out["Tp3"] = 1.0 / max(abs(p[rest[0]]), 1e-9) if rest else 1.0
    else:
        tps = _distinct([1.0 / max(abs(p[k]), 1e-9) for k in range(t.poles)])
        for k in range(t.poles):
            out[f"Tp{k + 1}"] = tps[k]
    if t.zero:
        out["Tz"] = float(b[0] / b[1]) if b.size > 1 and b[1] != 0 else 0.0
    return out


_SPLIT = 1.25


def _distinct(tps: list[float]) -> list[float]:
    """Real time constants to start from (slowest first), no two of them equal.

    A complex pair read as two real poles (``1 / |p|`` each: SRIVC found an oscillating
    response for a structure without ``U``) gives ``Tp1 == Tp2``. The output-error cost is
    symmetric in the two, so its gradient never separates them: every step keeps them
    equal, and the sampled model there is a double pole, a defective ``A`` on which the
    search's sensitivities lose all accuracy (the Gauss-Newton matrix overflows and the fit
    raised, whatever ``max_iter``). Equal time constants (to 1e-6) are spread geometrically
    about their value (ratio ``_SPLIT``, the product kept), so the search starts off the
    symmetric set; distinct ones are kept.

    Examples
    --------
    >>> from sysid.process.procest import _distinct
    >>> [round(x, 4) for x in _distinct([0.5, 0.5, 3.0])]
    [3.0, 0.559, 0.4472]
    """
    out = sorted(float(x) for x in tps)
    k = 0
    while k < len(out):
        j = k + 1
        while j < len(out) and out[j] <= out[j - 1] * (1 + 1e-6):
            j += 1
        if j - k > 1:  # equal ones: spread evenly in log about their geometric mean
            g = float(np.exp(np.mean(np.log(out[k:j]))))
            mid = (j - k - 1) / 2
            out[k:j] = [g * _SPLIT ** (i - mid) for i in range(j - k)]
        k = j
    return out[::-1]


def _pair(t: ProcessType, names: list[str], start: dict[str, float], fixed: dict[str, float],
          bounds: dict[str, tuple[float, float]], dmax: float, label: str = "") -> Any:
    from ..tf.refine import PairStructure

    def coef(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return t.coefficients(dict(zip(names, p)))

    lo = np.array([bounds.get(k, t.default_bounds(k))[0] for k in names])
    hi = np.array([bounds.get(k, t.default_bounds(k))[1] for k in names])
    p0 = np.clip(np.array([start[k] for k in names]), lo, hi)
    fx = np.array([k in fixed for k in names])
    dlo, dhi = bounds.get("Td", (0.0, dmax))
    td = float(np.clip(start.get("Td", 0.0), max(dlo, 0.0), min(dhi, dmax))) if t.delay else 0.0
    return PairStructure(coef, p0, fx, lo, hi, td, t.delay and "Td" not in fixed,
                         min(dhi, dmax), [f"{label}:{k}" if label else k for k in names])


def _full_cov(res: dict[str, Any], t: ProcessType, names: list[str], m: int) -> np.ndarray:
    """Covariance ordered as the model's parameter table (per input: names, then Td)."""
    k = len(names)
    P = np.asarray(res["covariance"])
    idx: list[int] = []
    for j in range(m):
        idx += list(range(j * k, (j + 1) * k))
        if t.delay:
            idx.append(m * k + res["delay_index"].index(j) if j in res["delay_index"] else -1)
    out = np.zeros((len(idx), len(idx)))
    for a, ia in enumerate(idx):
        for b, ib in enumerate(idx):
            if ia >= 0 and ib >= 0:
                out[a, b] = P[ia, ib]
    return out


def _weak(res: dict[str, Any], t: ProcessType, names: list[str], m: int) -> list[int]:
    """The unidentifiable entries in the table order of one output (see ``_full_cov``)."""
    k = len(names)
    order: list[int] = []
    for j in range(m):
        order += list(range(j * k, (j + 1) * k))
        if t.delay:
            order.append(m * k + res["delay_index"].index(j) if j in res["delay_index"] else -1)
    return [a for a, i in enumerate(order) if i in set(res.get("unidentifiable", []))]


def _attach(model: ProcessModel, covs: list[np.ndarray], fixed: dict[str, float],
            weak: list[list[int]], limits: dict[str, tuple[float, float]]
            ) -> tuple[np.ndarray, np.ndarray]:
    """The parameter table and uncertainty. A parameter the search left on one of its
    ``limits`` is marked ``bound`` and its 95 % interval is cut at the bound (its std is
    that of the unconstrained curvature: a dead time of 0 is not -1.2 .. 1.2 s). Returns
    the lower and upper limits per parameter."""
    from ..tf.options import blockdiag

    names, theta = model.parameter_names(), model.parameter_vector()
    P = blockdiag(covs)
    short = [n.split(":")[-1] for n in names]
    is_fixed = np.array([k in fixed for k in short])
    sd = np.sqrt(np.clip(np.diag(P), 0, None))
    o = 0
    for c, w in zip(covs, weak):
        sd[[o + a for a in w]] = np.inf
        o += c.shape[0]
    lo = np.array([limits.get(k, (-np.inf, np.inf))[0] for k in short], float)
    hi = np.array([limits.get(k, (-np.inf, np.inf))[1] for k in short], float)
    tol = 1e-9 * np.maximum(1.0, np.abs(theta))
    on = np.where(~is_fixed & (np.abs(theta - lo) <= tol), "lower",
                  np.where(~is_fixed & (np.abs(theta - hi) <= tol), "upper", ""))
    model.parameters = ParameterTable(names, theta, sd, is_fixed,
                                      bound=[str(b) for b in on]).cut_at_bounds(lo, hi)
    model.uncertainty = ParameterUncertainty(theta, P, model.with_parameter_vector,
                                             names=names)
    return lo, hi
