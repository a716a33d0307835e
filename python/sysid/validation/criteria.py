"""Information criteria and order selection.

Parameter count
---------------
An innovation-form model ``(A, B, C, D, K)`` of order ``n`` with ``m`` inputs and ``l``
outputs has ``n^2 + n m + l n + n l`` entries in ``A, B, C, K`` (plus ``l m`` in ``D``), but
any similarity transform ``T`` gives the same input-output behaviour, so ``n^2`` of them are
not identifiable. The count used here is the dimension of the identifiable (pseudo-canonical)
parameterisation (Ljung 1999, *System Identification*, 2nd ed., Sec. 4.3 on state-space model
structures; McKelvey 1995, PhD thesis, Linkoping, on fully parameterised forms):

.. math::

    d = n (2 l + m) + [D]\\, l m + [x_0]\\, n \\cdot n_{exp}

``K`` contributes ``n l`` only when a noise model is estimated (without it ``d = n (l + m)
+ [D] l m``), and estimated initial states count ``n`` per experiment. Known input delays
add nothing: ``n`` leaves out the unit delays a state-space model absorbed
(``input_delay=``) or a polynomial model's ``nk`` beyond one sample realises, as MATLAB
counts no ``InputDelay``. The noise covariance
``l (l + 1) / 2`` is the same for every order and is left out (it cancels in comparisons).

Criteria (Ljung 1999, Sec. 16.4), with ``V = det(Lambda)``, ``Lambda = (1/N) sum e e^T`` the
covariance of the one-step prediction errors on the estimation data and ``N`` the number of
samples:

- ``AIC = N log V + 2 d`` (Akaike 1974),
- ``AICc = AIC + 2 d (d + 1) / (N - d - 1)`` (small-sample correction, Hurvich & Tsai 1989),
- ``BIC = N log V + d log N`` (Schwarz 1978; Rissanen's MDL),
- ``FPE = V (1 + d / N) / (1 - d / N)`` (Akaike's final prediction error).

Constants common to all orders (``N l (log 2 pi + 1)``) are omitted, so values differ from
MATLAB's by a constant; the minimising order is the same. :func:`sysid.aic` and
:func:`sysid.fpe` give MATLAB's numbers under MATLAB's names (``nAIC`` included).

Noise-free data drive ``V`` to round-off, where its value is meaningless and would reward
fitting rounding noise. ``V`` is therefore regularised: ``Lambda + diag(resolution^2 *
mean(y_j^2))`` with ``resolution = 1e-8`` (about ``sqrt(eps)``, the accuracy of a
least-squares estimate), which changes nothing on noisy data.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable, Iterator, Sequence
from typing import Any

import numpy as np

from .._checks import as_int, as_nonnegative, check_magnitudes, user_stacklevel
from .._display import HTMLResult
from .._progress import Bar, show
from ..data.iodata import IOData
from ..errors import DataError, InsufficientDataError, NumericalError, SysidError
from ..models.checks import _optional, check_model
from ..models.statespace import StateSpaceModel, ss_parameter_count
from .compare import compare_quiet as compare
from .runner import _has_state, _records, _run, _simulator, _x0_for

__all__ = ["n_parameters", "Criteria", "criteria", "OrderSelection", "select_order"]

CRITERIA = ("aic", "aicc", "bic", "fpe")
_NAMES = {"aic": "AIC", "aicc": "AICc", "bic": "BIC", "fpe": "FPE"}


def n_parameters(n: Any, m: int | None = None, l: int | None = None, *,
                 feedthrough: bool = True, noise_model: bool = True, x0: bool = False,
                 n_experiments: int = 1) -> int:
    """Identifiable parameters of an innovation-form state-space model (see module docs):
    from its sizes ``n, m, l``, or of a model given alone (its ``n_parameters``).

    Examples
    --------
    >>> import sysid
    >>> from sysid.validation.criteria import n_parameters
    >>> n_parameters(4, 1, 1)        # 4 (2 + 1) + 1
    13
    >>> n_parameters(4, 1, 1, feedthrough=False, noise_model=False)
    8
    >>> n_parameters(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]))
    2
    """
    if m is None and l is None and hasattr(n, "n_parameters"):
        return int(n.n_parameters)
    if m is None or l is None:
        raise DataError("n_parameters takes a model, or its order n with m inputs and l "
                        "outputs: n_parameters(n, m, l)")
    n, m, l = as_int(n, "n", 0), as_int(m, "m", 0), as_int(l, "l", 0)
    n_experiments = as_int(n_experiments, "n_experiments")
    return ss_parameter_count(n, m, l, feedthrough=feedthrough, noise_model=noise_model, x0=x0,
                              n_experiments=n_experiments)


class Criteria(HTMLResult):
    """AIC, AICc, BIC and FPE of one model on one record.

    Attributes
    ----------
    loss, log_loss : float
        ``V = det(Lambda)`` (regularised, see module docs) and its logarithm.
    n_params, n_samples : int
    aic, aicc, bic, fpe : float
    """

    def __init__(self, log_loss: float, n_params: int, n_samples: int) -> None:
        self.log_loss, self.n_params = float(log_loss), int(n_params)
        self.n_samples = int(n_samples)
        self.loss = float(np.exp(self.log_loss))
        N, d = float(n_samples), float(n_params)
        logv = self.log_loss
        self.aic = N * logv + 2 * d
        self.aicc = self.aic + (2 * d * (d + 1) / (N - d - 1) if N - d - 1 > 0 else np.inf)
        self.bic = N * logv + d * np.log(N)
        self.fpe = self.loss * (1 + d / N) / (1 - d / N) if d < N else np.inf

    def as_dict(self) -> dict[str, float]:
        """``{"loss", "n_params", "aic", "aicc", "bic", "fpe"}``."""
        return {"loss": self.loss, "n_params": self.n_params, "aic": self.aic,
                "aicc": self.aicc, "bic": self.bic, "fpe": self.fpe}

    def __repr__(self) -> str:
        return (f"Criteria(d={self.n_params}, N={self.n_samples}, V={self.loss:.4g}, "
                f"AIC={self.aic:.2f}, AICc={self.aicc:.2f}, BIC={self.bic:.2f}, "
                f"FPE={self.fpe:.4g})")


def criteria(model: Any, data: Any, *, x0: Any = "estimate",
             n_params: int | None = None, resolution: float = 1e-8) -> Criteria:
    """Information criteria of a model on (its estimation) data.

    Parameters
    ----------
    model : sysid.Model
        Any model; its ``n_parameters`` is the parameter count.
    data : IOData or (u, y)
        The data the model was estimated on.
    x0 : "estimate", "zero", "model" or array
        Initial predictor state; an estimated one counts ``n`` parameters per experiment,
        ``n`` the states of the model whose state is fitted (as :func:`sysid.compare` does:
        a state-space model's own, a polynomial or transfer-function model's through its
        state-space form, hold states included) less the delay lines of known input delays
        (a state-space model's absorbed ``input_delay``, a polynomial model's ``nk`` beyond
        one sample: their start is the unrecorded past input); models without one start
        from rest and count none.
    n_params : int, optional
        Override the parameter count (default ``model.n_parameters``, for a state-space
        model :func:`n_parameters` from its shape, its ``D`` and ``K``); a count of at
        least the number of samples minus 1 raises :class:`~sysid.errors.InsufficientDataError`
        (AICc and FPE would be infinite).
    resolution : float
        Relative floor of the prediction-error covariance (see module docs), finite and
        ``>= 0``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]], K=[[0.0]])
    >>> u = rng.standard_normal(400)
    >>> y = m.simulate(u) + 0.1 * rng.standard_normal((400, 1))
    >>> c = sysid.criteria(m, (u, y))
    >>> c.n_params   # n (2 l + m) + n for x0; D = 0 counts as no feed-through
    4
    """
    if n_params is not None:
        n_params = as_int(n_params, "n_params", 0)
    resolution = as_nonnegative(resolution, "resolution")
    c = _criteria(model, data, x0, n_params, resolution)
    if c.n_params >= c.n_samples - 1:
        raise InsufficientDataError(
            f"the model counts {c.n_params} parameters but the data have only "
            f"{c.n_samples} samples: AICc and FPE need fewer parameters than samples minus 1 "
            "(they would be infinite); use a longer record or a smaller model")
    return c


def _criteria(model: Any, data: Any, x0: Any, n_params: int | None,
              resolution: float) -> Criteria:
    """:func:`criteria` without its argument checks (infinite AICc/FPE for ``d >= N - 1``,
    which the order sweeps rank last)."""
    given = model
    model, recs = _records(model, data)
    # the range check the estimators apply: |y| near 1e200 gave a NaN Ljung-Box statistic
    check_magnitudes(recs, "criteria")
    es, ys = [], []
    runner = _simulator(model, x0, 1, recs[0][0] if recs else None)  # x0 fitted as compare
    for i, (u, y) in enumerate(recs):
        x = _x0_for(runner, x0, u, y, 1, i, len(recs))
        es.append(y - _run(runner, u, y, 1, x))
        ys.append(y)
    e, y = np.vstack(es), np.vstack(ys)
    N = e.shape[0]
    lam = e.T @ e / N + np.diag(resolution**2 * np.mean(y**2, axis=0) + 1e-300)
    _, logdet = np.linalg.slogdet(lam)  # lam is positive definite by construction
    if n_params is None:
        n_params = int(given.n_parameters)
        if _has_state(runner) and isinstance(x0, str) and x0 == "estimate":
            def realise(m: Any) -> Any:  # another model's runner, made as ``runner`` was
                return _simulator(_records(m, data)[0], x0, 1, recs[0][0] if recs else None)

            # the fitted initial states
            n_params += _x0_states(given, runner, realise) * len(recs)
    return Criteria(logdet, n_params, N)


def _x0_states(model: Any, runner: Any, realise: Any = None) -> int:
    """The initial states an estimated ``x0`` counts: those of the state-space form
    ``runner`` less the unit delays of known input delays (their start is the unrecorded
    past input, not a parameter of the model: a state-space model's absorbed
    ``input_delay``, a polynomial model's ``nk`` beyond one sample, a transfer-function or
    process model's ``iodelay``: the order of the runner ``realise`` makes of the model
    without it; MATLAB counts no state of an ``IODelay`` either)."""
    from ..models.statespace import delay_states

    n = int(runner.nstates)
    if runner is model or isinstance(runner, StateSpaceModel) and "input_delay" in getattr(
            runner, "info", {}):
        return n - delay_states(runner)
    from ..tf.model import TransferFunction

    if (realise is not None and isinstance(model, TransferFunction)
            and np.any(np.asarray(model.iodelay) != 0)):
        try:  # the same transfer functions without their delays: their runner's order
            d = TransferFunction.to_dict(model)  # a process model's too (its Td)
            free = realise(TransferFunction.from_dict({**d, "iodelay": 0.0 * np.asarray(
                d["iodelay"], float)}))
            return min(n, int(free.nstates)) if _has_state(free) else n
        except SysidError:
            return n
    nk = getattr(model, "nk", None)
    if isinstance(nk, np.ndarray) and np.any(nk > 1) and hasattr(model, "to_dict"):
        try:  # the same model with at most one sample of delay: its realisation's order
            free = type(model).from_dict({**model.to_dict(), "nk": np.minimum(nk, 1)})
            return min(n, int(free.to_statespace().nstates))
        except SysidError:
            return n
    return n


# -- order selection ----------------------------------------------------------------------
class OrderSelection(HTMLResult):
    """Results of an order (and weighting) sweep on one compression.

    Attributes
    ----------
    rows : list of dict
        One per (method, order): ``method, order, singular_value, n_params, loss, aic,
        aicc, bic, fpe, fit_estimation, fit_validation, stable, max_abs_pole, error``.
    singular_values : dict
        Method -> singular values.
    picks : dict
        Order chosen by each rule: ``"svd"`` (largest log-gap), ``"aic"``, ``"aicc"``,
        ``"bic"``, ``"fpe"`` (minimum), ``"validation"`` (smallest order within
        ``fit_tol`` of the best validation fit, stable models only), ``"cv"`` (when it was
        computed: the order ``order="auto"`` takes, by simulation fit on blocks of the
        estimation record held out; each swept row of its method has it as ``fit_held_out``).
    order, method : int, str
        The recommendation: the validation pick when validation data were given, else the
        cross-validated pick (BIC for given models, the singular-value gap for an estimator
        without data), or the rule named by ``criterion``.
    reason : str
        Why, in one paragraph.
    """

    def __init__(self, rows: list[dict[str, Any]], singular_values: dict[str, np.ndarray],
                 models: dict[tuple[str, int], Any], svd_picks: dict[str, int],
                 has_validation: bool, criterion: str | None, fit_tol: float,
                 cv: dict[str, Any] | None = None) -> None:
        self.rows, self.singular_values, self._models = rows, singular_values, models
        self._cv = cv
        self.has_validation, self.fit_tol = has_validation, fit_tol
        ok = [r for r in rows if r["error"] is None]
        if not ok:
            raise SysidError("no order could be fitted; see the errors: "
                             + "; ".join(str(r["error"]) for r in rows[:3]))
        self.picks: dict[str, int] = {}
        self.pick_methods: dict[str, str] = {}
        for crit in CRITERIA:
            vals = [r for r in ok if np.isfinite(r[crit])]
            if vals:
                best = min(vals, key=lambda r: (r[crit], r["order"]))
                self.picks[crit], self.pick_methods[crit] = best["order"], best["method"]
        first = rows[0]["method"]
        if first in svd_picks:
            self.picks["svd"], self.pick_methods["svd"] = svd_picks[first], first
        self._top: float | None = None
        if has_validation:
            cand = [r for r in ok if r["stable"] and np.isfinite(r["fit_validation"])]
            cand = cand or [r for r in ok if np.isfinite(r["fit_validation"])]
            if cand:
                top = max(r["fit_validation"] for r in cand)
                self._top = top
                good = [r for r in cand if r["fit_validation"] >= top - fit_tol]
                best = min(good, key=lambda r: (r["order"], -r["fit_validation"]))
                self.picks["validation"], self.pick_methods["validation"] = (
                    best["order"], best["method"])
        if cv is not None and cv.get("method"):
            self.picks["cv"], self.pick_methods["cv"] = int(cv["order"]), cv["method"]
        rule = criterion or next((r for r in ("validation", "cv", "bic", "svd")
                                  if r in self.picks), "")
        if rule == "cv" and "cv" not in self.picks and cv is not None:
            # the record could not be cross-validated: the rule that applies otherwise
            rule = next((r for r in ("validation", "bic", "svd") if r in self.picks), "")
        if rule not in self.picks:
            raise DataError(f"criterion {rule!r} is not available; choose one of "
                            f"{', '.join(self.picks)}")
        self.criterion = rule
        self.order, self.method = self.picks[rule], self.pick_methods[rule]
        self.reason = self._reason()

    def _row(self, method: str, order: int) -> dict[str, Any]:
        for r in self.rows:
            if r["method"] == method and r["order"] == order:
                return r
        raise DataError(f"order {order} with method {method!r} was not part of the sweep")

    def _reason(self) -> str:
        r = self._row(self.method, self.order)
        votes = ", ".join(f"{_NAMES.get(k, k)} -> {v}" for k, v in self.picks.items())
        parts = [f"order {self.order} ({self.method}) chosen by {self.criterion}"]
        if self.criterion == "validation":
            top = self._top if self._top is not None else r["fit_validation"]
            parts.append(
                f": validation fit {r['fit_validation']:.1f} % is within {self.fit_tol:g} "
                f"points of the best stable order's ({top:.1f} %), and no smaller stable "
                "order is")
            excluded = self._excluded()
            if excluded:
                parts.append(f" ({excluded})")
        elif self.criterion == "cv":
            parts.append(f" ({self._cv['criterion']} on the estimation record): "
                         f"{self._cv['reason']}")
            if self.has_validation:
                parts.append("; the validation data were only reported on")
        elif self.criterion in CRITERIA:
            parts.append(f": smallest {_NAMES[self.criterion]} = {r[self.criterion]:.4g}")
        else:
            parts.append(": largest gap of the log singular values")
        if self._cv is not None and not self._cv.get("method") and self.criterion != "given":
            parts.append(f" ({self._cv['reason']})")
        sv = self.singular_values.get(self.method, np.zeros(0))
        if 0 < self.order < sv.size:
            parts.append(f"; singular values {sv[self.order - 1]:.4g} -> {sv[self.order]:.4g} "
                         f"(ratio {sv[self.order - 1] / max(sv[self.order], 1e-300):.3g})")
        parts.append(f"; {'stable' if r['stable'] else 'UNSTABLE'} model. Votes: {votes}.")
        return "".join(parts)

    def _excluded(self) -> str:
        """Which orders the choice left out and why (unstable, failed)."""
        def orders(rows: list[dict[str, Any]]) -> str:
            return ", ".join(str(x["order"]) for x in rows)

        unstable = [x for x in self.rows if x["error"] is None and not x["stable"]]
        failed = [x for x in self.rows if x["error"] is not None]
        out = []
        if unstable:
            best = max(unstable, key=lambda x: x["fit_validation"]
                       if np.isfinite(x["fit_validation"]) else -np.inf)
            fit = (f", the best of them {best['fit_validation']:.1f} % at order "
                   f"{best['order']}" if np.isfinite(best["fit_validation"]) else "")
            out.append(f"excluded as unstable: order(s) {orders(unstable)}{fit}")
        if failed:
            out.append(f"not fitted: order(s) {orders(failed)} ({failed[0]['error']})")
        return "; ".join(out)

    def given(self, order: int) -> OrderSelection:
        """This sweep with ``order`` fixed by the user (``criterion == "given"``): its
        ``order`` and ``reason`` say so, and the reason keeps the sweep's own choice.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> rng = np.random.default_rng(0)
        >>> u = rng.standard_normal((400, 1))
        >>> y = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]]).simulate(u)
        >>> y = y + 0.1 * rng.standard_normal((400, 1))
        >>> sel = sysid.select_order(sysid.SubspaceEstimator(sysid.IOData(u, y), 10), range(1, 4))
        >>> sel.given(3).order, sel.given(3).reason.startswith("order 3 (moesp) given")
        (3, True)
        """
        import copy

        out = copy.copy(self)
        row = self._row(self.method, int(order))
        out.criterion, out.order = "given", int(order)
        out.reason = (f"order {order} ({self.method}) given, not chosen; "
                      f"{'stable' if row['stable'] else 'UNSTABLE'} model. The sweep's own "
                      f"choice would be: {self.reason}")
        return out

    def model(self, order: int | None = None, method: str | None = None) -> Any:
        """The fitted model of the sweep (default: the recommended one)."""
        key = (method or self.method, self.order if order is None else order)
        if key not in self._models:
            raise DataError(f"no model for method {key[0]!r}, order {key[1]} in this sweep")
        return self._models[key]

    def damping(self, method: str | None = None) -> Iterator[tuple[int, Any]]:
        """``(order, DampingTable)`` for each fitted order of ``method``."""
        from ..analysis.lti import damp

        meth = method or self.method
        for (mm, order), mod in sorted(self._models.items(), key=lambda kv: kv[0][1]):
            if mm == meth:
                try:
                    table = damp(mod)
                except DataError:  # a model without poles() or to_statespace()
                    continue
                yield order, table

    def to_pandas(self) -> Any:
        """The table as a :class:`pandas.DataFrame`."""
        import pandas as pd

        return pd.DataFrame(self.rows)

    def summary(self) -> str:
        """The table and the reason for the recommendation, as text."""
        return repr(self)

    def plot(self, fig: Any = None) -> Any:
        """Singular values, criteria and fit versus order."""
        from ..plot.validation import plot_order_selection

        return plot_order_selection(self, fig=fig)

    def stabilization_plot(self, ax: Any = None, hz: bool = True) -> Any:
        """Stabilisation diagram of the pole frequencies versus order."""
        from ..plot.validation import plot_stabilization

        return plot_stabilization(self, ax=ax, hz=hz)

    def __repr__(self) -> str:
        head = (f"{'method':<15} {'n':>3} {'sv':>10} {'d':>4} {'AIC':>11} {'AICc':>11} "
                f"{'BIC':>11} {'FPE':>10} {'fit est':>8} {'fit val':>8} {'stable':>6}")
        held = any("fit_held_out" in r for r in self.rows)
        if held:  # the cross-validated fits the "cv" rule reads
            head = head.replace(" fit val", " held out  fit val")
        lines = ["OrderSelection", head]
        for r in self.rows:
            if r["error"] is not None:
                lines.append(f"{r['method']:<15} {r['order']:>3} failed: {r['error']}")
                continue
            star = " *" if (r["method"], r["order"]) == (self.method, self.order) else ""
            lines.append(
                f"{r.get('model', r['method'])[:15]:<15} {r['order']:>3} "
                f"{r['singular_value']:10.4g} "
                f"{r['n_params']:>4} {r['aic']:11.2f} {r['aicc']:11.2f} {r['bic']:11.2f} "
                f"{r['fpe']:10.4g} {_pct(r['fit_estimation'])} "
                + (f"{_pct(r.get('fit_held_out', np.nan))} " if held else "")
                + f"{_pct(r['fit_validation'])} {'yes' if r['stable'] else 'NO':>6}{star}"
            )
        lines.append(self.reason)
        return "\n".join(lines)


def _pct(x: float) -> str:
    """A fit percentage in 8 characters (diverging fits of unstable models as -inf)."""
    if not np.isfinite(x):
        return f"{'-':>8}" if np.isnan(x) else f"{'-inf':>8}"
    return f"{x:8.2f}" if x > -1e4 else f"{'< -1e4':>8}"


def _check_orders(orders: Iterable[int] | None, max_order: int) -> list[int]:
    if orders is None:
        return list(range(1, min(max_order, 15) + 1))
    out = []
    for o in orders:
        o = as_int(o, "every entry of orders")
        if o > max_order:
            raise DataError(f"order {o} is larger than the horizon allows ({max_order}); "
                            "increase the horizon or lower the order")
        out.append(int(o))
    if not out:
        raise DataError("orders is empty")
    return sorted(set(out))


def _fit(est: Any, n: int, meth: str, feedthrough: bool, kalman: bool) -> StateSpaceModel:
    try:
        return est.fit(n, method=meth, feedthrough=feedthrough, kalman=kalman)
    except NumericalError as e:
        if not kalman:
            raise
        # no stabilising Kalman gain (e.g. noise-free data): keep an output-error model
        mod = est.fit(n, method=meth, feedthrough=feedthrough, kalman=False)
        mod.info["kalman_failed"] = str(e)
        return mod


def _failed(row: dict[str, Any], e: Exception) -> dict[str, Any]:
    row.update({"error": str(e), "stable": False, "max_abs_pole": np.nan, "n_params": 0,
                "loss": np.nan, "fit_estimation": np.nan, "fit_validation": np.nan,
                **{k: np.nan for k in CRITERIA}})
    return row


def _check_validation(validation: Any, m: int, l: int, dt: float) -> None:
    if validation is None:
        return
    probe = StateSpaceModel(np.zeros((1, 1)), np.zeros((1, m)), np.zeros((l, 1)), dt=dt)
    _records(probe, validation)  # raises a ShapeError naming the channel counts


def select_order(
    data: Any,
    orders: Iterable[int] | None = None,
    *,
    methods: Sequence[str] | None = None,
    horizon: int | None = None,
    validation: Any = None,
    x0: str = "estimate",
    criterion: str | None = None,
    fit_tol: float = 0.5,
    feedthrough: bool | str = False,
    kalman: bool = True,
    models: Sequence[Any] | None = None,
    progress: bool | None = None,
) -> OrderSelection:
    """Sweep orders (and weightings) on one compression, or rank given models; tabulate
    criteria and fits.

    Parameters
    ----------
    data : IOData, (u, y) or SubspaceEstimator
        Estimation data (compressed once), or an estimator to reuse. With ``models``, the
        data the models were estimated on (an IOData or a pair).
    orders : iterable of int, optional
        Orders to fit (default ``1 .. min(max_order, 15)``).
    methods : sequence of str, optional
        Weightings to sweep (default: the estimator's method).
    horizon : int, optional
        Horizon of the estimator built from ``data``; default the data's, or the smallest
        that allows the largest of ``orders`` when the data support it (as ``n4sid``).
    validation : IOData or (u, y), optional
        Fresh data for the validation fit (simulation, NRMSE %; for a time series, without
        inputs, the one-step prediction).
    x0 : "estimate" or "zero"
        Initial states in the criteria and fits.
    criterion : str, optional
        Rule for the recommended order: ``"validation"``, ``"cv"``, ``"aic"``, ``"aicc"``,
        ``"bic"``, ``"fpe"`` or ``"svd"``. Default: validation if given; else ``"cv"``, the
        rule of ``order="auto"`` (:meth:`SubspaceEstimator.order_selection`: simulation fit
        on blocks of the estimation record held out, for the first of ``methods``; its
        held-out fits are the rows' ``fit_held_out``), which keeps the validation data
        for an honest report when both are wanted (the command line's choice). On a record
        too short to split, ``"cv"`` falls back to the rule that applies otherwise and the
        reason says so. Given models: BIC (they cannot be re-fitted on blocks).
    fit_tol : float
        Percentage points of validation fit a smaller order may give up and still win.
    feedthrough, kalman : bool
        Passed to :meth:`SubspaceEstimator.fit` (``feedthrough`` default ``False``: no ``D``,
        as every sysid state-space estimator; ``"auto"``: one decision from the data for the
        whole sweep, :func:`sysid.subspace.feedthrough.choose_feedthrough`).
    models : sequence of sysid.Model, optional
        Candidate models of any family (state-space, polynomial, your own) to rank instead of
        a subspace sweep; the "order" of each is its ``nstates`` or else its
        ``n_parameters``, and must differ between candidates. ``orders``, ``methods``,
        ``horizon``, ``feedthrough`` and ``kalman`` do not apply.
    progress : bool, optional
        A progress bar over the fits (default: only when stderr is a terminal).

    Returns
    -------
    OrderSelection

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> true = sysid.StateSpaceModel([[0.8, 0.3], [-0.3, 0.8]], [[1.0], [0.0]], [[1.0, 0.5]])
    >>> u = rng.standard_normal(400)
    >>> y = true.simulate(u) + 0.05 * rng.standard_normal((400, 1))
    >>> low = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]])
    >>> sysid.select_order((u, y), models=[low, true], criterion="bic").order
    2
    """
    fit_tol = as_nonnegative(fit_tol, "fit_tol")
    if models is not None:
        return _rank_models(data, list(models), validation, x0, criterion, fit_tol)
    if orders is not None and (np.ndim(orders) == 0 or isinstance(orders, (str, bytes))):
        raise DataError(f"orders must be a sequence of model orders (e.g. range(1, 6) or "
                        f"[{orders!r}]), got {orders!r}")
    from ..subspace.estimator import SubspaceEstimator, horizon_for_order

    est = data if isinstance(data, SubspaceEstimator) else None
    if est is None:
        if not isinstance(data, IOData):
            raise DataError(f"data must be a sysid.IOData or SubspaceEstimator, got "
                            f"{type(data).__name__}")
        if orders is not None:  # the horizon follows the largest order asked for
            orders = list(orders)
            whole = [int(o) for o in orders if isinstance(o, (int, np.integer))]
            horizon = horizon_for_order(data, max(whole, default=None), horizon)
        est = SubspaceEstimator(data, horizon)
    if x0 not in ("estimate", "zero"):
        raise DataError(f"x0 must be 'estimate' or 'zero', got {x0!r}")
    meths = [est.method] if methods is None else list(methods)
    if not meths:
        raise DataError("methods is empty")
    from ..subspace.estimator import _method

    meths = [_method(m) for m in meths]
    orders_ = _check_orders(orders, est.max_order)
    from ..subspace.feedthrough import check_feedthrough, choose_feedthrough

    if check_feedthrough(feedthrough) == "auto":  # one decision for the whole sweep
        feedthrough = choose_feedthrough(est, orders_, method=meths[0])[0]
    _check_validation(validation, est.data.n_inputs, est.data.n_outputs, est.data.dt)
    est_data = None if getattr(est, "_from_factor", False) else est.data
    rows, fitted, svs, svd_picks = [], {}, {}, {}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with Bar(len(meths) * len(orders_), "order sweep", unit="fits",
                 enabled=show(progress)) as bar:
            _sweep(est, est_data, meths, orders_, validation, x0, feedthrough, kalman, rows,
                   fitted, svs, svd_picks, bar)
    _warn_once(caught)
    cv = None
    if criterion == "cv" or (criterion is None and validation is None):
        cv = _cross_validated(est, est_data, meths[0], bool(feedthrough), orders_, rows)
    return OrderSelection(rows, svs, fitted, svd_picks, validation is not None, criterion,
                          float(fit_tol), cv)


def _cross_validated(est: Any, est_data: Any, method: str, feedthrough: bool,
                     orders: list[int], rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The order ``order="auto"`` takes among ``orders`` (``{"order", "method", "reason"}``;
    without ``"method"`` when the record could not be cross-validated, and then why), its
    held-out fits written into ``rows`` as ``fit_held_out``."""
    if est_data is None:
        return {"reason": "not cross-validated: the estimator holds no data (built from a "
                          "factor)"}
    choice = est.order_selection(method, feedthrough, orders)
    if not choice["table"]:  # the singular-value rule: the record could not be split
        return {"reason": f"the record could not be cross-validated: {choice['failure']}"
                if choice.get("failure") else f"not cross-validated: {choice['reason']}"}
    for r in rows:
        if r["method"] == method:
            r["fit_held_out"] = float(choice["table"].get(r["order"], np.nan))
    return {"order": choice["order"], "method": method, "reason": choice["reason"],
            "criterion": choice["criterion"]}


def _warn_once(caught: list[Any]) -> None:
    """Re-emit the warnings of a sweep: each distinct one once, and the excitation warning
    only for the lowest order that raised it (it would repeat for every higher order)."""
    from ..errors import ExcitationWarning, StabilityWarning

    seen: set[tuple[type, str]] = set()
    excitation = [w for w in caught if issubclass(w.category, ExcitationWarning)]
    for w in caught:
        if issubclass(w.category, ExcitationWarning):
            if w is not excitation[0]:
                continue
            msg = str(w.message)
            if len(excitation) > 1:
                msg += " (the same holds for every higher order of the sweep)"
            warnings.warn(msg, w.category, stacklevel=user_stacklevel())
            continue
        if issubclass(w.category, StabilityWarning):
            continue  # a sweep's unstable candidates: the table shows them, the pick warns
        key = (w.category, str(w.message))
        if key not in seen:
            seen.add(key)
            warnings.warn(w.message, w.category, stacklevel=user_stacklevel())


def _sweep(est: Any, est_data: Any, meths: list[str], orders_: list[int], validation: Any,
           x0: str, feedthrough: bool, kalman: bool, rows: list[dict[str, Any]],
           fitted: dict[Any, Any], svs: dict[str, Any], svd_picks: dict[str, int],
           bar: Bar) -> None:
    for meth in meths:
        sv = np.asarray(est.singular_values_for(meth))
        svs[meth] = sv
        svd_picks[meth] = int(est._subspace(meth).auto_order())
        for n in orders_:
            bar.update(1)
            row: dict[str, Any] = {"method": meth, "order": n,
                                   "singular_value": float(sv[n - 1]) if n <= sv.size else np.nan,
                                   "error": None}
            try:
                mod = _fit(est, n, meth, feedthrough, kalman)
            except SysidError as e:
                rows.append(_failed(row, e))
                continue
            fitted[(meth, n)] = mod
            row["stable"] = mod.is_stable()
            row["max_abs_pole"] = float(np.max(np.abs(mod.poles())))
            d = n_parameters(n, mod.ninputs, mod.noutputs, feedthrough=feedthrough,
                             noise_model=mod.K is not None, x0=x0 == "estimate",
                             n_experiments=est_data.n_experiments if est_data else 1)
            row["n_params"] = d
            # a time series has nothing to simulate from: its fits are one-step predictions
            h = 1 if mod.ninputs == 0 and getattr(mod, "K", None) is not None else None
            try:
                if est_data is not None:
                    c = _criteria(mod, est_data, x0, d, 1e-8)
                    row.update({k: getattr(c, k) for k in ("loss",) + CRITERIA})
                    row["fit_estimation"] = compare(mod, est_data, h, x0=x0).mean_fit
                else:
                    row.update({k: np.nan for k in ("loss", "fit_estimation") + CRITERIA})
                row["fit_validation"] = (compare(mod, validation, h, x0=x0).mean_fit
                                         if validation is not None else np.nan)
            except NumericalError as e:  # e.g. an unstable predictor overflowing
                rows.append(_failed(row, e))
                continue
            rows.append(row)


def _order_of(model: Any) -> int:
    return int(getattr(model, "nstates", model.n_parameters))


def _stability(model: Any) -> tuple[bool, float]:
    """``(stable, max |pole|)``; a model without poles counts as stable (FIR-like)."""
    try:
        p = np.asarray(_optional(model, "poles", "stability"))
    except DataError:
        return True, np.nan
    if not p.size:
        return True, 0.0
    if not model.dt:
        return bool(np.max(p.real) < 0), float(np.max(np.abs(p)))
    rho = float(np.max(np.abs(p)))
    return rho < 1.0, rho


def _rank_models(data: Any, models: list[Any], validation: Any, x0: str,
                 criterion: str | None, fit_tol: float) -> OrderSelection:
    """:func:`select_order` over given candidate models (any :class:`sysid.Model`)."""
    if not models:
        raise DataError("models is empty; pass at least one candidate model")
    if x0 not in ("estimate", "zero"):
        raise DataError(f"x0 must be 'estimate' or 'zero', got {x0!r}")
    seen: dict[int, Any] = {}
    rows, fitted = [], {}
    for mod in models:
        check_model(mod, "every candidate in models")
        order = _order_of(mod)
        if order in seen:
            raise DataError(f"two candidate models have order {order} ({seen[order]!r} and "
                            f"{mod!r}); rank models of different orders, or compare them "
                            "one by one with sysid.criteria")
        seen[order] = mod
        label = str(mod.info.get("method", type(mod).__name__))
        row: dict[str, Any] = {"method": "models", "order": order, "model": label,
                               "singular_value": np.nan, "error": None}
        try:
            c = _criteria(mod, data, x0, None, 1e-8)
            row["stable"], row["max_abs_pole"] = _stability(mod)
            row["n_params"] = c.n_params
            row.update({k: getattr(c, k) for k in ("loss",) + CRITERIA})
            # a time series has nothing to simulate from: its fits are one-step predictions
            # (as the sweep's; simulated, every AR order fitted about 0 %)
            h = 1 if getattr(mod, "ninputs", 1) == 0 else None
            row["fit_estimation"] = compare(mod, data, x0=x0, horizon=h).mean_fit
            row["fit_validation"] = (compare(mod, validation, x0=x0, horizon=h).mean_fit
                                     if validation is not None else np.nan)
        except NumericalError as e:
            rows.append(_failed(row, e))
            continue
        fitted[("models", order)] = mod
        rows.append(row)
    rows.sort(key=lambda r: r["order"])
    return OrderSelection(rows, {}, fitted, {}, validation is not None, criterion, fit_tol)
