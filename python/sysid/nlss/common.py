"""What the nonlinear state-space models and estimators share: data scaling, channel names,
input checks, the linear start, the state-basis balancing and the transient left out of the
cost."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import (
    DataError,
    ExcitationError,
    InsufficientDataError,
    IterationLimitWarning,
    OrderError,
    StabilityWarning,
    SysidError,
)
from ..models.statespace import StateSpaceModel
from ..validation.output_error import feedback_checked


class Scaling:
    """Affine channel scaling ``u_s = (u - u_offset) / u_scale`` (and likewise ``y``)."""

    def __init__(self, u_offset: Any, u_scale: Any, y_offset: Any, y_scale: Any) -> None:
        self.u_offset, self.u_scale = np.asarray(u_offset, float), np.asarray(u_scale, float)
        self.y_offset, self.y_scale = np.asarray(y_offset, float), np.asarray(y_scale, float)

    @classmethod
    def of(cls, data: IOData) -> Scaling:
        from .._checks import check_magnitudes, require_samples

        # outputs near 1e200 overflowed the std and were called "constant (0)"
        check_magnitudes(data, "the nonlinear state-space fits")
        require_samples(data.lengths, "a nonlinear state-space model")  # else "constant"
        u = np.vstack([e[0] for e in data.experiments])
        y = np.vstack([e[1] for e in data.experiments])
        su, sy = u.std(axis=0), y.std(axis=0)
        for name, s, names in (("input", su, data.input_names), ("output", sy, data.output_names)):
            if np.any(s == 0):
                bad = [names[j] for j in np.flatnonzero(s == 0)]
                raise DataError(f"{name} {', '.join(map(str, bad))} is constant: a nonlinear "
                                "state-space model needs every channel to vary; drop it")
        return cls(u.mean(axis=0), su, y.mean(axis=0), sy)

    def u(self, u: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray((u - self.u_offset) / self.u_scale)

    def y(self, y: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray((y - self.y_offset) / self.y_scale)

    def y_back(self, ys: np.ndarray) -> np.ndarray:
        return ys * self.y_scale + self.y_offset

    def to_dict(self) -> dict[str, Any]:
        return {"u_offset": self.u_offset, "u_scale": self.u_scale,
                "y_offset": self.y_offset, "y_scale": self.y_scale}

    def to_scaled(self, m: StateSpaceModel) -> StateSpaceModel:
        """A linear model in engineering units, shown in the scaled channels."""
        su, sy = np.diag(self.u_scale), np.diag(1.0 / self.y_scale)
        return StateSpaceModel(m.A, m.B @ su, sy @ m.C, sy @ m.D @ su, dt=m.dt)

    def to_units(self, A: Any, B: Any, C: Any, D: Any, model: Any) -> StateSpaceModel:
        """The scaled-channel linear part ``(A, B, C, D)`` in engineering units (the inverse
        of :meth:`to_scaled`), with ``model``'s sample time and channel names."""
        ys = self.y_scale[:, None]
        return StateSpaceModel(A, B / self.u_scale, ys * C, ys * D / self.u_scale, dt=model.dt,
                               input_names=model.input_names, output_names=model.output_names)


def channels(scaling: dict[str, Any] | None, m: int, l_: int, input_names: Any,
             output_names: Any) -> tuple[Scaling, list[str], list[str]]:
    """A model's channel scaling (none when ``scaling`` is ``None``) and its input and output
    names (``u0, u1, ...`` and ``y0, y1, ...`` when not given), for ``m`` inputs and ``l_``
    outputs."""
    sc = scaling or {"u_offset": np.zeros(m), "u_scale": np.ones(m),
                     "y_offset": np.zeros(l_), "y_scale": np.ones(l_)}
    ins = list(input_names) if input_names is not None else [f"u{j}" for j in range(m)]
    outs = list(output_names) if output_names is not None else [f"y{j}" for j in range(l_)]
    return Scaling(sc["u_offset"], sc["u_scale"], sc["y_offset"], sc["y_scale"]), ins, outs


def clamp_box(clamp: Any, size: int, of: str = "") -> tuple[np.ndarray, np.ndarray]:
    """``clamp = (lo, hi)`` as two arrays of ``size`` bounds with ``lo <= hi`` (``of`` says
    what they bound, in the message)."""
    try:
        lo, hi = (np.asarray(v, dtype=float).ravel() for v in clamp)
    except (TypeError, ValueError):
        raise DataError("clamp must be a pair (lo, hi) of arrays") from None
    if lo.size != size or hi.size != size or np.isnan(lo).any() or np.isnan(hi).any() \
            or np.any(lo > hi):
        raise DataError(f"clamp needs {size} lower and upper bounds{of} with lo <= hi")
    return lo, hi


def signal(a: Any, width: int, name: str) -> np.ndarray:
    """``a`` as a finite, real ``(n_samples, width)`` float array (1-D: one channel) with at
    least one sample: the check every model family applies (:func:`sysid._checks.as_2d`;
    complex values are refused, not cast to their real parts)."""
    from .._checks import as_2d

    return as_2d(a, name, ncols=width)


def fit_summary(model: Any) -> str:
    """``summary()`` of a model fitted by the shared optimiser (``info["fit"]``)."""
    fit = model.info.get("fit", {})
    cost = fit.get("cost", [float("nan")])
    return (f"{model!r}\n  parameters: {model.theta.size}\n  iterations: "
            f"{fit.get('iterations', '-')}, stop: {fit.get('stop', '-')}\n  cost: "
            f"{cost[0]:.6g} -> {cost[-1]:.6g}")


class LinearPart:
    """``to_statespace`` and ``freqresp`` of a nonlinear state-space model: those of its
    linear part (the host defines ``linear()``); ``predict``: its simulation (the host
    defines ``simulate()``)."""

    #: ``to_statespace()`` is the linear part, not the model: :func:`sysid.compare` simulates
    #: the model itself
    statespace_is_exact = False
    #: ``simulate`` takes any initial state of ``nstates`` entries: :func:`sysid.compare`
    #: fits it (``x0="estimate"``) as it does a linear model's
    initial_state_fits = True

    def linear(self) -> StateSpaceModel:  # pragma: no cover - defined by the host
        raise NotImplementedError

    def to_statespace(self) -> StateSpaceModel:
        """The linear part (poles, zeros and frequency response are those of it)."""
        return self.linear()

    def freqresp(self, omega: Any) -> np.ndarray:
        """Frequency response of the linear part."""
        return np.asarray(self.linear().freqresp(omega))

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:  # pragma: no cover - the host's
        raise NotImplementedError

    def predict(self, u: Any, y: Any = None, horizon: int = 1, x0: Any = None) -> np.ndarray:
        """An output-error model has no noise model: its prediction is its simulation
        (from ``x0``, as :meth:`simulate`). ``u``, ``y`` and ``horizon`` (a positive
        integer, or ``np.inf``) are checked as every model's ``predict`` checks them."""
        from .._measured import as_horizon, as_measured, predict_args

        as_horizon(horizon)
        u, _ = as_measured(*predict_args(u, y), self.ninputs, self.noutputs)
        return self.simulate(u) if x0 is None else self.simulate(u, x0=x0)


def scaled_data(data: IOData, sc: Scaling) -> IOData:
    """The record in scaled channels (offsets removed, unit standard deviations)."""
    return IOData([sc.u(u) for u, _ in data.experiments], [sc.y(y) for _, y in data.experiments],
                  data.dt)


def linear_start(data: IOData, sd: IOData, sc: Scaling, order: int, init: Any,
                 periods: int | None, max_iter: int | None = None) -> StateSpaceModel:
    """The linear model the nonlinear fit starts from, in scaled channels: ``init`` (in
    engineering units), the BLA's parametric model for periodic data with equal-length
    experiments, else an output-error refinement (``ssest``) of a subspace model, with
    ``ssest``'s own iteration cap unless ``max_iter`` is given (the model a user gets from
    ``sysid.ssest(data, order, focus="simulation")``)."""
    import sysid

    if init is not None:
        ss = init.to_statespace() if hasattr(init, "to_statespace") else init
        if not isinstance(ss, StateSpaceModel):
            raise DataError("init must be a sysid.StateSpaceModel (or have to_statespace())")
        if (ss.ninputs, ss.noutputs, ss.nstates) != (data.n_inputs, data.n_outputs, order):
            raise DataError(f"init has {ss.nstates} states, {ss.ninputs} inputs and "
                            f"{ss.noutputs} outputs; the data and order need {order}, "
                            f"{data.n_inputs} and {data.n_outputs}")
        return sc.to_scaled(ss)
    lens = {u.shape[0] for u, _ in sd.experiments}
    if periods is not None and len(lens) == 1 and lens.pop() % periods == 0:
        f = sysid.bla(sd, periods=periods, transient=1 if periods > 2 else 0)
        return sysid.bla_model(f, order)
    # a start: the nonlinear search goes on from it, so its own cap is not the user's concern
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IterationLimitWarning)
        # a pole the bound holds at the unit circle: the nonlinear search goes on from it
        warnings.simplefilter("ignore", StabilityWarning)
        try:
            kw = {} if max_iter is None else {"max_iter": max_iter}
            with feedback_checked():  # a nonlinear model's start (see nlhw)
                return sysid.ssest(sd, order, focus="simulation", feedthrough=False,
                                   progress=False, **kw)
        except ExcitationError as e:
            raise _oversampled(e, data) from None
        except (OrderError, InsufficientDataError) as e:
            # a record too short for the order, in the nonlinear fit's words (the subspace
            # start's horizons are not the user's settings), its own after
            n = sum(u.shape[0] for u, _ in sd.experiments)
            raise type(e)(f"the record ({n} training samples) is too short for the linear "
                          f"start of order {order} (a subspace fit refined by ssest): give a "
                          f"longer record or a lower order, or a linear start (init=); the "
                          f"subspace fit said: {e}") from e


def _oversampled(err: ExcitationError, data: IOData) -> SysidError:
    """The linear start's refusal of a record as not persistently exciting, with the
    decimation that helps when the user's whole record (``data``) is oversampled: the start
    sees only the training part, often too short for the subspace estimators' own note (a
    reaction-wheel pendulum's chirp of 1 001 samples, twice oversampled: decimated by 2, both
    nonlinear fits run); ``err`` itself otherwise, or when it names the decimation already."""
    from ..data.oversampling import oversampled_note

    note = None if "sysid.decimate" in str(err) else oversampled_note(data)
    return err if note is None else err.with_remedy(note)


def linear_states(m: StateSpaceModel, us: list[np.ndarray]) -> list[np.ndarray]:
    """The states of the linear model ``m`` simulated from rest over each input record."""
    n = m.nstates
    probe = StateSpaceModel(m.A, m.B, np.eye(n), np.zeros((n, m.ninputs)), dt=m.dt)
    return [np.asarray(probe.simulate(u)) for u in us]


def balanced(m: StateSpaceModel, us: list[np.ndarray]) -> StateSpaceModel:
    """The linear model in the basis where its simulated states have unit variance, so that
    monomials and network weights of the states are well scaled."""
    xs = np.vstack(linear_states(m, us))
    s = xs.std(axis=0)
    s = np.where(s > 1e-12 * max(s.max(), 1e-300), s, 1.0)
    T, Ti = np.diag(s), np.diag(1.0 / s)
    return StateSpaceModel(Ti @ m.A @ T, Ti @ m.B, m.C @ T, m.D, dt=m.dt)


def envelope(xs: list[np.ndarray], us: list[np.ndarray],
              widen: float) -> tuple[np.ndarray, np.ndarray]:
    """The range of ``[x; u]`` over the records, widened by ``widen`` times its span on
    each side (a span of zero counts as one)."""
    z = np.hstack([np.vstack(xs), np.vstack(us)])
    lo, hi = z.min(axis=0), z.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    return lo - widen * span, hi + widen * span


def decay_samples(m: Any, level: float) -> float:
    """Samples for the slowest pole of ``m``'s linear part (``m.poles()``) to decay to
    ``level`` of its mode; ``inf`` for a pole on or outside the unit circle."""
    poles = m.poles()
    rho = float(np.max(np.abs(poles))) if len(poles) else 0.0
    if rho >= 1:
        return float("inf")
    return 0.0 if rho == 0 else float(np.ceil(np.log(level) / np.log(rho)))


def settle_samples(m: StateSpaceModel, n: int) -> int:
    """Samples for the slowest pole to decay to 0.1 %, at most a quarter of the record."""
    return int(min(max(decay_samples(m, 1e-3), 0.0), n // 4))


def check_parameters(n_par: int, recs: list[Any], fix: str) -> None:
    """Refuses a simulation-error fit of ``n_par`` parameters on records ``(u, y, transient)``
    that give no more residuals than that, before the optimiser sizes anything by the
    parameter count; ``fix`` says what to lower."""
    n_res = sum(max(y.shape[0] - int(skip), 0) * y.shape[1] for _, y, skip in recs)
    if n_par >= n_res:
        raise DataError(f"the model has {n_par} parameters but the record gives {n_res} "
                        f"residuals (after the transient); lower {fix}, or give more data")


def check_order(order: Any) -> int:
    from .._checks import as_int

    return as_int(order, "order", 1)  # MATLAB's orders are doubles: 2.0 is 2


#: a linear part whose largest mode grows at most this much over the longest record is kept
#: as the free search left it (an integrator, as :data:`sysid.polynomial.stability.NOISE_GROWTH`
#: judges the noise model's roots)
RUNAWAY_GROWTH = 10.0


def held_stable(res: dict[str, Any], n: int, refit: Any, max_iter: int,
                samples: int) -> dict[str, Any]:
    """The search's report ``res`` (``iterates`` from its start, ``history`` with the start's
    cost first) when the linear part's ``A`` (the first ``n * n`` parameters) of its last
    point is stable, or its largest mode grows at most :data:`RUNAWAY_GROWTH`-fold over
    ``samples`` (the longest record: an integrator); otherwise the search continued from its
    latest iterate whose ``A`` is stable by ``refit(theta0, iterations)``, a search that
    keeps ``A`` stable (the structure's ``stable``), for the iterations left of
    ``max_iter``, and its report joined to that iterate's path (``res["held_stable"]``: the
    iteration it continued from, the free search's cost, largest pole modulus and that
    mode's growth over ``samples``).

    With clamped monomials an unstable ``A`` runs away as soon as the state leaves the box
    the polynomial was fitted in, whatever the nonlinear terms do inside it: a free search
    on a lightly damped five-storey test tower (``pnlss(data, 3)``, 10 240 samples, 5 outputs)
    took ``A`` to a pole of modulus 1.0017 (a 5e7-fold growth over the record) and simulated
    its validation record at -8.9e8 %; its last iterate with a stable ``A`` (iteration 3 of
    100) at 15.6 %. The EMPS servo's free search (position from force: an integrator) ends
    at 1 + 6.5e-6, a 1.18-fold growth over its 24 841 samples, and tests at 0.0121 (the
    stable start: 0.144): it is kept.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.nlss.common import held_stable
    >>> res = {"iterates": np.array([[0.5], [0.9], [1.1]]), "history": [3.0, 2.0, 1.0],
    ...        "theta": np.array([1.1]), "iterations": 2, "evaluations": 4}
    >>> def refit(th0, it):  # a search that stops at the boundary
    ...     return {"iterates": np.array([[0.99]]), "history": [2.0, 1.5], "iterations": 1,
    ...             "evaluations": 3, "theta": np.array([0.99]), "cost": 1.5}
    >>> out = held_stable(res, 1, refit, 10, 100)
    >>> out["theta"].tolist(), out["history"], out["held_stable"]["from_iteration"]
    ([0.99], [3.0, 2.0, 1.5], 1)
    >>> held_stable(res, 1, refit, 10, 20) is res  # 1.1 ** 20 = 6.7: kept
    True
    """
    from ..pem.boundary import spectral_radius

    its = np.asarray(res["iterates"])

    def radius(th: np.ndarray) -> float:
        return spectral_radius(np.asarray(th[:n * n]).reshape(n, n))

    rho = radius(np.asarray(res["theta"]))
    growth = samples * np.log(rho) if rho > 0 else -np.inf  # log of the mode's growth
    if n == 0 or rho < 1.0 or len(its) < 2 or growth <= np.log(RUNAWAY_GROWTH):
        return res
    # the latest stable iterate (the start is stable: pnlss refuses an unstable one)
    k = next((k for k in range(len(its) - 1, -1, -1) if radius(its[k]) < 1.0), None)
    if k is None:
        return res
    more = refit(np.asarray(its[k]), max(max_iter - k, 1))
    hist = list(res["history"])
    out = dict(more)
    tail = np.asarray(more["iterates"]).reshape(-1, its.shape[1])
    out["iterates"] = np.vstack([its[:k + 1], tail])
    out["history"] = hist[:k + 1] + list(more["history"])[1:]
    out["iterations"] = k + more["iterations"]
    out["evaluations"] = res["evaluations"] + more["evaluations"]
    out["iterations_all_trials"] = res.get("iterations_all_trials", res["iterations"]) \
        + more["iterations"]
    out["evaluations_all_trials"] = res.get("evaluations_all_trials", res["evaluations"]) \
        + more["evaluations"]
    out["held_stable"] = {"from_iteration": int(k), "free_cost": float(hist[-1]),
                          "free_radius": rho,
                          "free_growth": float(np.exp(min(growth, 700.0)))}
    return out
