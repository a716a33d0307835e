"""Grey-box estimation: :func:`greyest` (MATLAB's ``greyest`` and ``nlgreyest``).

A linear structure (:class:`sysid.GreyBox`) is fitted by the prediction-error method of
:func:`sysid.pem`: the Rust predictor accumulates, over the samples, the Gauss-Newton matrix
in the entries of the sampled ``(A, B, C, D, K, x0)``, and the one optimiser of the core
(``sysid_core::optim``) searches the physical parameters through the chain rule
``J_p = J_theta dtheta/dp``, with ``dtheta/dp`` formed here once per iteration (central
differences of the structure function, Fréchet derivative of the matrix exponential). A
nonlinear structure (:class:`sysid.NonlinearGreyBox`) is integrated in the Rust core with all
finite-difference perturbations at once. Both report the parameters with standard deviations
from the same Gauss-Newton covariance (the inverse-covariance-weighted criterion, maximum
likelihood for Gaussian errors); where a fit's errors are coloured (simulation errors, a
nonlinear fit's always, or prediction errors of a noise model that cannot take the
disturbance's shape) the sandwich of :mod:`sysid.greybox.coloured` replaces it (a nonlinear
fit's when first used).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_int, experiment_arrays, require_inputs_vary, warn_if_capped
from .._progress import iteration_printer
from .._threads import one_blas_thread
from ..data.iodata import IOData
from ..errors import DataError
from ..models.discretisation import expm, hold_blocks
from ..models.frd import FRD
from ..pem.records import _experiments
from ..validation.output_error import output_error
from .delays import _aug_foh as foh_block
from .delays import shift_taps, split_delays
from .greybox import GreyBox
from .outer import OuterParameters, model_of
from .results import GreyEstimate, _costs, _criterion

__all__ = ["greyest", "GreyEstimate"]


def _no_noise_model(a: dict[str, Any]) -> bool:
    """A linear structure fitted without a noise model (the simulation focus, or no ``K``):
    the output-error fits :mod:`sysid.validation.output_error` checks for feedback (a
    nonlinear structure is left out: the test reads its distortions as feedback)."""
    return isinstance(a["structure"], GreyBox) and (a["focus"] == "simulation"
                                                    or a["noise"] == "none")


_FOCUS = ("prediction", "simulation")
#: Most random starts ``multistart`` may ask for: each is a whole search, and 10000 is far
#: beyond what tells a global minimum from local ones.
MAX_STARTS = 10_000


def _progress(progress: Any, criterion: str) -> Any:
    if progress is True:
        return iteration_printer("greyest", criterion)
    if progress is False or progress is None:
        return None
    if callable(progress):
        return progress
    raise DataError(f"progress must be True, False or a callable, got {progress!r}")


def _x0_modes(x0: Any, count: int, n: int, has_model_x0: bool) -> list[Any]:
    if isinstance(x0, str):
        if x0 not in ("estimate", "zero", "model"):
            raise DataError(f"x0 must be 'estimate', 'zero', 'model' or an array, got {x0!r}")
        if x0 == "model" and not has_model_x0:
            raise DataError("x0='model' needs a structure function that returns x0")
        return [x0] * count
    if isinstance(x0, (list, tuple)) and len(x0) == count and count > 1:
        return [m for it in x0 for m in _x0_modes(it, 1, n, has_model_x0)]
    arr = np.asarray(x0, dtype=float).ravel()
    if arr.size != n:
        raise DataError(f"x0 has {arr.size} entries but the structure has {n} states")
    return [arr] * count


@output_error("greyest", when=_no_noise_model)
@one_blas_thread
def greyest(
    data: Any,
    structure: Any,
    *,
    focus: str = "prediction",
    x0: Any = None,
    noise: str = "model",
    weighting: str = "noise",
    multistart: int = 0,
    rng: Any = None,
    max_iter: int = 100,
    tol: float = 1e-10,
    progress: bool | Callable[..., Any] = False,
    periods: int | str | None = None,
    transient: int | None = None,
) -> GreyEstimate:
    """Estimate the free parameters of a grey-box structure by prediction-error minimisation.

    Parameters
    ----------
    data : IOData, (u, y) or FRD
        Estimation data; every experiment is used (with its own initial state). An
        :class:`sysid.FRD` with ``std`` (for example from :func:`sysid.bla`) is fitted in
        the frequency domain, as with ``periods``.
    structure : GreyBox or NonlinearGreyBox
        The model structure with initial values, fixed parameters and bounds.
    focus : {"prediction", "simulation"}
        One-step prediction errors (with the structure's ``K``) or simulation errors (``K = 0``).
        A nonlinear structure always uses simulation errors.
    x0 : "estimate", "zero", "model", array, or a list per experiment
        Initial states: estimated, zero, the structure's own (a linear ``fn`` returning x0,
        possibly a function of the parameters; a nonlinear structure's ``x0`` and
        ``x0_free``), or given. Default: "estimate" for linear, "model" for nonlinear
        structures. Given, zero and reported (``initial_states``) states are the
        structure's own, also under ``hold="foh"``, whose sampled model runs in the states
        ``x - G u`` (``info["x0_values"]``; zero is rest, ``x(0) = 0``).
    noise : {"model", "none", "estimate"}
        ``K`` as the structure returns it (zero when it returns none), no ``K``, or every entry
        of ``K`` estimated freely (innovation gain of the sampled model). Prediction focus only.
    weighting : {"noise", "identity"}
        Weight the errors by the inverse of their covariance, re-estimated between iterations
        (maximum likelihood, default), or the plain sum of squares.
    multistart : int
        Extra searches from random initial values within the bounds (a fixed seed ``rng``);
        the lowest loss wins. Against local minima. At most ``MAX_STARTS`` (10000); more
        raises a DataError.
    rng : seed or numpy Generator, optional
    max_iter : int
    tol : float
        Relative cost decrease below which the search stops (positive, finite).
    progress : bool or callable
        ``True`` prints one line per iteration; a callable gets
        ``(iteration, cost, step_norm, gradient_norm, damping)`` and may return ``False``.
    periods : int or "auto", optional
        The data are periodic (linear structures): every experiment holds this many whole
        periods in steady state, or ``"auto"`` detects the period of the input
        (:func:`sysid.detect_period`; when there is none, or fewer than 2 periods remain
        after the transient, the estimation runs in the time domain and
        ``info["periodicity"]["reason"]`` says why). The structure's sampled response is
        then fitted on the excited lines only (:mod:`sysid.greybox.greyest_lines`): the
        response averaged over the periods (:func:`sysid.bla`), each entry weighted by the
        inverse of its noise variance from the periods; no initial state, no noise model
        (``x0``, ``noise``, ``focus`` do not apply: ``x0`` or ``noise="estimate"`` raise),
        ``weighting="noise"`` only. The covariance is scaled by ``info["residual_scale"]``
        (about 1 when the structure explains the lines) and by ``(P-2)/(P-3)`` for the
        variances estimated from ``P`` periods (``info["sample_variance_factor"]``; with 3
        or fewer an ``UncertaintyWarning`` says the std is too small).
    transient : int, optional
        Leading periods dropped (default 0 with a declared ``periods``, 1 with ``"auto"``).

    Returns
    -------
    GreyEstimate
        ``.parameters`` (table with std and 95 % intervals), ``.correlation``, ``.model``
        (with ``uncertainty``), ``.info``. Warns with :class:`sysid.IdentifiabilityWarning`
        naming the parameters the data cannot determine separately.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> def motor(p, dt=None):
    ...     return [[-1 / p.tau]], [[p.K / p.tau]], [[1.0]], [[0.0]]
    >>> u = np.sign(np.sin(np.arange(400) * 0.05))
    >>> y = sysid.GreyBox(motor, {"K": 2.0, "tau": 0.3}).model(dt=0.05).simulate(u)
    >>> s = sysid.GreyBox(motor, params={"K": 1.0, "tau": sysid.param(1.0, bounds=(0.01, 10))})
    >>> fit = sysid.greyest(sysid.IOData(u=u, y=y, dt=0.05), s, x0="zero")
    >>> np.round(fit.parameters.value, 6)
    array([2. , 0.3])

    Periodic data in steady state, fitted on the excited lines:

    >>> up = sysid.multisine(128, band=(0, 0.5), periods=4, seed=0)
    >>> g = sysid.GreyBox(motor, {"K": 2.0, "tau": 0.3}).model(dt=0.05)
    >>> yp = g.simulate(np.vstack([np.tile(up[:128], (4, 1)), up]))[512:]
    >>> fit = sysid.greyest(sysid.IOData(u=up, y=yp, dt=0.05), s, periods=4)
    >>> np.round(fit.parameters.value, 6), fit.info["domain"]
    (array([2. , 0.3]), 'frequency')
    """
    from ..tf.options import search_limits
    from .nlgreybox import NonlinearGreyBox
    from .nlgreyest import nlgreyest

    multistart = as_int(multistart, "multistart", 0)
    if multistart > MAX_STARTS:
        raise DataError(f"multistart = {multistart} random starts is too many (each is a whole "
                        f"search; at most {MAX_STARTS}): pass a few (10 to 100) and tighten "
                        "the parameters' bounds instead")
    max_iter, tol = search_limits(max_iter, tol, None)  # the checks of procest and tfest
    periodicity = None
    if isinstance(data, FRD) or periods is not None or transient is not None:
        out, periodicity = _periodic(data, structure, periods, transient, x0, noise, weighting,
                                     multistart, rng, max_iter, tol, progress)
        if out is not None:
            return out
    data = _experiments(data)
    if focus not in _FOCUS:
        raise DataError(f"focus must be 'prediction' or 'simulation', got {focus!r}")
    if weighting not in ("noise", "identity"):
        raise DataError(f"weighting must be 'noise' or 'identity', got {weighting!r}")
    max_iter = as_int(max_iter, "max_iter", 0)
    cb = _progress(progress, _criterion(weighting))
    if isinstance(structure, NonlinearGreyBox):
        out = nlgreyest(data, structure, x0=x0, weighting=weighting, multistart=multistart,
                        rng=rng, max_iter=max_iter, tol=float(tol), progress=cb)
        warn_if_capped(out.info, "the greyest search", max_iter)
        return out
    if not isinstance(structure, GreyBox):
        raise DataError("structure must be a sysid.GreyBox or sysid.NonlinearGreyBox, got "
                        f"{type(structure).__name__}")
    if noise not in ("model", "none", "estimate"):
        raise DataError(f"noise must be 'model', 'none' or 'estimate', got {noise!r}")
    if (data.n_inputs, data.n_outputs) != (structure.ninputs, structure.noutputs):
        raise DataError(f"the structure has {structure.ninputs} input(s) and "
                        f"{structure.noutputs} output(s), the data {data.n_inputs} and "
                        f"{data.n_outputs}")
    require_inputs_vary(experiment_arrays(data), "greyest", data.input_names)
    dt = float(data.dt)
    if structure.dt is not None and not structure.continuous and \
            abs(structure.dt - dt) > 1e-9 * dt:
        raise DataError(f"the structure's dt={structure.dt} differs from the data's dt={dt}: "
                        "resample the data or give the structure the data's sample time")
    longest = max(e[0].shape[0] for e in data.experiments)
    shift = max((t[1] for t in structure.input_taps(dt)), default=0)
    if shift >= longest:
        raise DataError(f"the structure's input_delay {structure.input_delay.tolist()} s is "
                        f"{shift} samples of dt={dt:g}, longer than the record ({longest} "
                        "samples): the output would not see the input; input_delay is in "
                        "seconds: check its value and the data's dt")
    fit = _LinearFit(data, structure, dt, focus, "estimate" if x0 is None else x0, noise,
                     weighting == "noise")
    best, starts = fit.best_of_starts(max_iter, float(tol), cb, multistart, rng, "loss")
    est = fit.result(best, starts)
    if not fit.with_k:  # no noise model (either focus): the errors are the disturbance
        from .coloured import coloured_covariance

        coloured_covariance(fit, best, est)
    else:  # a noise model K, which may not take the disturbance's shape
        from .coloured import prediction_covariance

        prediction_covariance(fit, best, est)
    if periodicity is not None:  # periods="auto" found none: why the time domain
        est.info["periodicity"] = periodicity
    warn_if_capped(est.info, "the greyest search", max_iter)
    return est


def _periodic(data: Any, structure: Any, periods: Any, transient: Any, x0: Any, noise: str,
              weighting: str, multistart: Any, rng: Any, max_iter: Any, tol: Any,
              progress: Any) -> tuple[GreyEstimate | None, dict[str, Any] | None]:
    """:func:`greyest` on the excited lines (an FRD, or periodic data) and what was found
    of the periodicity; no estimate when ``periods="auto"`` finds no usable period (the
    caller then fits in the time domain)."""
    from ..pem.periodic import CRITERION, resolve_periods
    from .greyest_lines import greyest_lines

    if not isinstance(structure, GreyBox):
        raise DataError("the frequency-domain path (periods= or an FRD) fits linear "
                        "structures (sysid.GreyBox); a nonlinear structure is fitted in the "
                        "time domain: leave periods out")
    if x0 is not None or noise == "estimate":
        raise DataError("the frequency-domain path fits the steady-state response on the "
                        "excited lines: there is no initial state and no noise model to "
                        "estimate; leave x0 and noise out, or fit in the time domain (no "
                        "periods=)")
    if weighting != "noise":
        raise DataError("the frequency-domain path weights each line by its noise variance "
                        "from the periods: leave weighting out, or fit in the time domain")
    extra: dict[str, Any] = {"periodicity": None}
    frd: FRD | None = data if isinstance(data, FRD) else None
    if frd is not None:
        if periods is not None or transient is not None:
            raise DataError("periods= and transient= describe a time record; an FRD is "
                            "already on its lines: leave them out")
    else:
        frd, extra["periodicity"] = resolve_periods(_experiments(data), periods, transient)
        if frd is None:
            return None, extra["periodicity"]
    extra["periods"] = frd.info.get("periods")
    max_iter = as_int(max_iter, "max_iter", 0)
    cb = _progress(progress, CRITERION)
    return greyest_lines(frd, structure, multistart=as_int(multistart, "multistart", 0),
                         rng=rng, max_iter=max_iter, tol=float(tol), progress=cb,
                         extra=extra), extra["periodicity"]


class _LinearFit(OuterParameters):
    """The bookkeeping of one linear grey-box estimation (outer vector z, map to theta)."""

    def __init__(self, data: IOData, s: GreyBox, dt: float, focus: str, x0: Any, noise: str,
                 reweight: bool) -> None:
        super().__init__(s)
        self.data, self.dt, self.focus, self.reweight = data, dt, focus, reweight
        self.taps = s.input_taps(dt)
        self.foh = s.continuous and s.hold == "foh"
        base = s.sampled_taps(None, dt)[0]
        self.n, self.m = base["B"].shape  # m: one input column per tap (delayed input)
        self.l = base["C"].shape[0]
        n, l = self.n, self.l
        self.exps = [(shift_taps(np.asarray(u, dtype=float), self.taps),
                      np.ascontiguousarray(y))
                     for u, y in data.experiments]
        self.noise = noise if focus == "prediction" else "none"
        self.k_model = self.noise == "model" and base["K"] is not None
        self.k_free = self.noise == "estimate"
        self.with_k = self.k_model or self.k_free
        self.modes = _x0_modes(x0, len(self.exps), n, base["x0"] is not None)
        z0 = list(self.z0)
        if self.k_free:
            k0 = base["K"] if base["K"] is not None else np.zeros((n, l))
            z0 += list(k0.ravel())
            self.names += [f"K[{i},{j}]" for i in range(n) for j in range(l)]
        self.x0_params: list[int] = []
        for e, mode in enumerate(self.modes):
            if isinstance(mode, str) and mode == "estimate":
                self.x0_params += list(range(len(z0), len(z0) + n))
                self.names += [f"x0[{e}][{i}]" for i in range(n)]
                z0 += [0.0] * n
        extra = len(z0) - self.nf
        self.lower = np.concatenate([self.lower, np.full(extra, -np.inf)])
        self.upper = np.concatenate([self.upper, np.full(extra, np.inf)])
        self.z0 = np.array(z0, dtype=float)

    def theta(self, z: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
        n, l, nf = self.n, self.l, self.nf
        vals = self.values(z)
        base, ders = self.s.sampled_taps(vals, self.dt, self.free if jac else None)

        def pack(mats: dict[str, Any], xs: list[np.ndarray], with_k: Any) -> list[np.ndarray]:
            parts = [mats["A"].ravel(), mats["B"].ravel(), mats["C"].ravel(), mats["D"].ravel()]
            if self.with_k:
                parts.append(with_k)
            return parts + xs

        o = nf + (n * l if self.k_free else 0)
        k_now = (z[nf:o] if self.k_free else
                 (base["K"].ravel() if self.k_model else np.zeros(0)))
        xs = []
        for mode in self.modes:
            if isinstance(mode, str) and mode == "estimate":
                xs.append(z[o:o + n])
                o += n
            elif isinstance(mode, str) and mode == "model":
                xs.append(np.asarray(base["x0"]).ravel())
            elif isinstance(mode, str):
                xs.append(np.zeros(n))
            else:
                xs.append(mode)
        # a zero, given or model x0 is the physical state: the sampled model's is x - G u(0)
        fixed = [not (isinstance(md, str) and md == "estimate") for md in self.modes]
        offs, doffs = (self._hold_offsets(vals, jac) if any(fixed) and self.foh
                       else (None, None))
        if offs is not None:
            xs = [x - g if f else x for x, g, f in zip(xs, offs, fixed)]
        th = np.concatenate(pack(base, xs, k_now))
        if not jac:
            return th, None
        M = np.zeros((th.size, z.size))
        for j, d in enumerate(ders):
            dk = d["K"].ravel() if (self.k_model and d["K"] is not None) else \
                np.zeros(n * l if self.with_k else 0)
            dx = [np.asarray(d["x0"]).ravel() if (isinstance(md, str) and md == "model"
                                                   and d["x0"] is not None) else np.zeros(n)
                  for md in self.modes]
            if doffs is not None:
                dx = [x - g if f else x for x, g, f in zip(dx, doffs[j], fixed)]
            M[:, j] = np.concatenate(pack(d, dx, dk)) * self.scale[j]
        # the freely estimated K entries and initial states enter theta directly
        off_k = n * n + n * self.m + l * n + l * self.m
        if self.k_free:
            M[off_k:off_k + n * l, nf:nf + n * l] = np.eye(n * l)
        o = nf + (n * l if self.k_free else 0)
        row = off_k + (n * l if self.with_k else 0)
        for mode in self.modes:
            if isinstance(mode, str) and mode == "estimate":
                M[row:row + n, o:o + n] = np.eye(n)
                o += n
            row += n
        return th, M

    def run(self, z0: np.ndarray, max_iter: int, tol: float, cb: Any) -> dict[str, Any]:
        res = _sysid.greybox_linear(
            (self.n, self.m, self.l), self.exps, lambda z, jac: self.theta(z, jac),
            list(map(float, z0)), focus=self.focus, with_k=self.with_k,
            reweight=self.reweight, x0_params=self.x0_params,
            search={"lower": list(self.lower), "upper": list(self.upper), "max_iter": max_iter,
                    "tol_cost": tol}, progress=cb)
        res["loss"] = float(np.linalg.det(res["innovation_covariance"]))
        res["start"] = z0
        return res

    def result(self, res: dict[str, Any], starts: list[float | None]) -> GreyEstimate:
        n = self.n
        z = np.asarray(res["p"])
        th = np.asarray(res["theta"])
        off = n * n + n * self.m + self.l * n + self.l * self.m
        K = th[off:off + n * self.l].reshape(n, self.l) if self.with_k else None
        row = off + (n * self.l if self.with_k else 0)
        xis = [th[row + e * n: row + (e + 1) * n] for e in range(len(self.exps))]
        # initial_states are the structure's (physical) states; a first-order hold samples
        # the model in the states xi = x - G u (info["x0_values"], a sampled model's x0)
        x0s = ([x + g for x, g in zip(xis, self._hold_offsets(self.values(z))[0])]
               if self.foh else xis)
        lam = np.asarray(res["innovation_covariance"])
        d = self.data
        names = {"input_names": d.input_names, "output_names": d.output_names}
        info = {
            "method": "greyest", "domain": "time", "iterations": res["iterations"],
            "evaluations": res["evaluations"], **_costs(res, self.reweight),
            "stop": res["stop"], "remaining_decrease": float(res["remaining_decrease"]),
            "condition": res["condition"], "rank": int(res["rank"]), "n_free": int(z.size),
            "n_samples": int(res["n_samples"]), "focus": self.focus, "noise": self.noise,
            "x0_values": xis, "multistart": starts, "loss": res["loss"],
        }
        table, cov, est, model = self.estimate(
            res, lambda s, v, inf: model_of(s, v, self.dt, K, names, lam, inf), info)
        delayed = bool(np.any(self.s.input_delay > 0))
        if len(xis) == 1 and not delayed and hasattr(model, "K"):
            model.x0 = xis[0]
        return GreyEstimate(table, cov, list(self.free), model, est, x0s, info)

    def _hold_offsets(self, vals: dict[str, float], jac: bool = False
                      ) -> tuple[list[np.ndarray], list[list[np.ndarray]] | None]:
        """Per experiment, ``G u(0)``, what a first-order hold moves out of the state (and
        its derivatives along each free parameter when ``jac``): the sampled model's state is
        ``xi = x - G u`` with ``G`` the ``G2`` of
        :func:`~sysid.models.discretisation.from_blocks` for an input delayed by whole samples,
        the weight of ``u[k+1]`` of :func:`~sysid.greybox.delays.foh_columns` for a delay of
        a fraction of one sample (nothing for longer fractional delays), and ``u(0)`` the
        first row of the experiment's tap columns (zero for a delayed tap)."""
        n, m, h, s = self.n, self.s.ninputs, self.dt, self.s
        base = s.matrices(vals, h)
        A, B = np.asarray(base["A"], float), np.asarray(base["B"], float)
        raw = s._raw_derivatives(vals, h, self.free, base) if jac else []

        def blocks(A: np.ndarray, B: np.ndarray, unit: float) -> np.ndarray:
            M = hold_blocks(A, B, h, "foh")
            M[n:n + m, n + m:] *= unit  # the ramp's identity block has no derivative
            return M

        E, dE = expm(blocks(A, B, 1.0), [blocks(d["A"], d["B"], 0.0) for d in raw])
        lo, r = split_delays(s.input_delay, h)
        cols = [E[:n, n + m:]] + [d[:n, n + m:] for d in dE]  # G2 and its derivatives
        G = [np.zeros((n, len(self.taps))) for _ in cols]
        for c, (j, shift) in enumerate(self.taps):
            if r[j] == 0:
                for g, g2 in zip(G, cols):
                    g[:, c] = g2[:, j]
            elif lo[j] == 0 and shift == 0:
                t = h - float(r[j])
                E2, dE2 = expm(foh_block(A, B[:, j], t, 1.0),
                               [foh_block(d["A"], d["B"][:, j], t, 0.0) for d in raw])
                for g, e2 in zip(G, [E2, *dE2]):
                    g[:, c] = e2[:n, n + 1] / h
        u0 = [u[0] if u.shape[0] else np.zeros(len(self.taps)) for u, _ in self.exps]
        offs = [G[0] @ u for u in u0]
        return offs, ([[g @ u for u in u0] for g in G[1:]] if jac else None)
