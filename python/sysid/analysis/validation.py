"""Validation: compare a model with measured data, and test its residuals.

:func:`compare`
    Simulation (``horizon=None``) or ``k``-step-ahead Kalman prediction against the
    measured outputs, per output NRMSE fit (MATLAB's ``compare`` definition), VAF and RMSE.
:func:`residuals`
    Auto-correlation of the one-step prediction errors and their cross-correlation with the
    inputs, with confidence bounds, a Ljung-Box portmanteau test of whiteness per output and
    Ljung's chi-square test of independence from past inputs.
:func:`error_spectrum`
    Power spectrum of the simulation error beside that of the output: the frequencies at
    which a model is wrong stand out.

The initial state is estimated by default (``x0="estimate"``): the model's response is linear
in ``x0``, so its free response from each unit state forms a regressor and ``x0`` follows by
least squares on the record. ``x0="zero"``, ``"model"`` (the state stored with the model) or
an array are the alternatives.

Data may be an :class:`~sysid.IOData` (several experiments allowed: each gets its own
initial state and its own row of fit numbers) or a pair ``(u, y)``.
"""

from __future__ import annotations

from typing import Any, Union

import numpy as np

from .._checks import as_2d, as_int
from ..data.iodata import IOData
from ..errors import DataError, ShapeError
from ..models.statespace import StateSpaceModel

__all__ = [
    "CompareResult",
    "ResidualAnalysis",
    "ErrorSpectrum",
    "compare",
    "residuals",
    "error_spectrum",
    "fit_metrics",
    "estimate_x0",
]

X0 = Union[str, np.ndarray, None]


# -- argument handling ------------------------------------------------------------------
def _records(model: StateSpaceModel, data: Any) -> list[tuple[np.ndarray, np.ndarray]]:
    """The experiments of ``data`` as (u, y) pairs, checked against the model's channels."""
    if not isinstance(model, StateSpaceModel):
        raise DataError(f"model must be a sysid.StateSpaceModel, got {type(model).__name__}")
    if isinstance(data, IOData):
        recs = data.experiments
    elif isinstance(data, tuple) and len(data) == 2:
        u, y = data
        y = as_2d(y, "y")
        u = np.zeros((y.shape[0], 0)) if u is None else as_2d(u, "u")
        recs = [(u, y)]
    else:
        raise DataError(
            f"data must be a sysid.IOData or a pair (u, y), got {type(data).__name__}"
        )
    m, l = model.ninputs, model.noutputs
    for u, y in recs:
        if u.shape[1] != m or y.shape[1] != l:
            raise ShapeError(
                f"the model has {m} input(s) and {l} output(s) but the data have "
                f"{u.shape[1]} input(s) and {y.shape[1]} output(s); select the same channels "
                "the model was identified on"
            )
        if u.shape[0] != y.shape[0]:
            raise ShapeError(f"u has {u.shape[0]} samples but y has {y.shape[0]}")
    if isinstance(data, IOData) and not np.isclose(data.dt, model.dt, rtol=1e-9):
        raise DataError(
            f"the data are sampled every {data.dt:g} s but the model every {model.dt:g} s; "
            "resample the data or use a model of the same sample time"
        )
    return recs


def _horizon(horizon: Any) -> int | None:
    if horizon is None or (isinstance(horizon, float) and np.isinf(horizon)):
        return None
    return as_int(horizon, "horizon", alt="None (simulation)")


def _run(model: StateSpaceModel, u: np.ndarray, y: np.ndarray, horizon: int | None,
         x0: np.ndarray | None) -> np.ndarray:
    if horizon is None:
        return model.simulate(u, x0)
    return model.predict(u, y, horizon, x0)


def estimate_x0(model: StateSpaceModel, u: Any, y: Any, horizon: int | None = None) -> np.ndarray:
    """Least-squares initial state for simulation (``horizon=None``) or prediction.

    The output is ``yhat(x0) = yhat(0) + Phi x0`` where column ``i`` of ``Phi`` is the free
    response from the ``i``-th unit state (computed with the same simulator or predictor, so
    the estimate is exact for whatever is being compared). ``x0`` minimises
    ``||y - yhat(x0)||``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]])
    >>> u = np.ones(20)
    >>> y = m.simulate(u, x0=[3.0])
    >>> np.round(sysid.estimate_x0(m, u, y), 10)
    array([3.])
    """
    u = as_2d(u, "u", ncols=model.ninputs, allow_empty=model.ninputs == 0)
    y = as_2d(y, "y", ncols=model.noutputs)
    if u.shape[0] != y.shape[0]:
        raise ShapeError(f"u has {u.shape[0]} samples but y has {y.shape[0]}")
    n = model.nstates
    if n == 0:
        return np.zeros(0)
    h = _horizon(horizon)
    W = _window(model, h, y.shape[0])
    base = _run(model, u[:W], y[:W], h, None)
    u0, y0 = np.zeros((W, u.shape[1])), np.zeros((W, y.shape[1]))
    phi = np.empty((W * y.shape[1], n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = 1.0
        phi[:, i] = _run(model, u0, y0, h, e).ravel()
    x0, *_ = np.linalg.lstsq(phi, (y[:W] - base).ravel(), rcond=None)
    return x0


def _window(model: StateSpaceModel, horizon: int | None, N: int) -> int:
    """Samples over which the free response from x0 is above 1e-13 of its start.

    The state is seen through ``A`` (simulation) or the predictor ``A - K C``; past the
    window its influence is below round-off, so the regression ignores those samples (this
    keeps the estimate O(n^2 W) instead of O(n^2 N) on long records).
    """
    F = model.A
    if horizon is not None and model.K is not None:
        F = model.A - model.K @ model.C
    rho = float(np.max(np.abs(np.linalg.eigvals(F)))) if F.size else 0.0
    if rho >= 0.9999:
        return N
    decay = 1 if rho == 0 else int(np.ceil(np.log(1e-13) / np.log(rho)))
    # transient growth of non-normal matrices: leave generous room
    W = 4 * decay + 10 * model.nstates + (horizon or 0)
    return int(min(N, max(W, 50)))


def _x0_for(model: StateSpaceModel, x0: Any, u: np.ndarray, y: np.ndarray, horizon: int | None,
            index: int, count: int) -> np.ndarray | None:
    if isinstance(x0, str):
        if x0 == "estimate":
            return estimate_x0(model, u, y, horizon)
        if x0 == "zero":
            return None
        if x0 == "model":
            if model.x0 is None:
                raise DataError("x0='model' but the model carries no initial state")
            return model.x0
        raise DataError(f"x0 must be 'estimate', 'zero', 'model' or an array, got {x0!r}")
    if x0 is None:
        return None
    if (isinstance(x0, (list, tuple)) and count > 1 and len(x0) == count
            and np.ndim(x0[0]) >= 1):  # one state vector per experiment
        x0 = x0[index]
    arr = np.asarray(x0, dtype=float).ravel()
    if arr.size != model.nstates:
        raise ShapeError(f"x0 has {arr.size} entries but the model has {model.nstates} states")
    return arr


def fit_metrics(y: Any, yhat: Any) -> dict[str, np.ndarray]:
    """NRMSE fit, VAF (both %) and RMSE per output column.

    ``fit = 100 (1 - ||y - yhat|| / ||y - mean(y)||)`` (MATLAB's ``compare``; 100 is
    perfect, 0 is no better than the mean, negative is worse), ``vaf = 100 (1 - var(y - yhat)
    / var(y))`` and ``rmse = sqrt(mean((y - yhat)^2))``. Fit and VAF are undefined (NaN)
    for a constant output channel.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> y = np.array([0.0, 1.0, 2.0, 3.0])
    >>> sysid.fit_metrics(y, y + 0.1)["fit"]
    array([91.05572809])
    """
    y = as_2d(y, "y")
    yhat = as_2d(yhat, "yhat", ncols=y.shape[1])
    if yhat.shape != y.shape:
        raise ShapeError(f"yhat has shape {yhat.shape} but y has {y.shape}")
    return _metrics(y, yhat)


def _metrics(y: np.ndarray, yhat: np.ndarray) -> dict[str, np.ndarray]:
    err = y - yhat
    # an unstable model's simulation may overflow: its fit is then -inf, not a warning
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        dev = np.linalg.norm(y - y.mean(0), axis=0)
        fit = 100.0 * (1.0 - np.linalg.norm(err, axis=0) / dev)
        vaf = 100.0 * (1.0 - err.var(0) / y.var(0))
        rmse = np.sqrt(np.mean(err**2, axis=0))
    fit = np.where(np.isnan(fit) & ~np.isfinite(rmse), -np.inf, fit)
    return {"fit": fit, "vaf": vaf, "rmse": rmse}


# -- compare ----------------------------------------------------------------------------
class CompareResult:
    """Measured versus model outputs, with fit numbers per experiment and output.

    Attributes
    ----------
    horizon : int or None
        ``None`` for simulation, else the prediction horizon.
    y, yhat : list of ndarray
        Measured and model outputs per experiment, ``(n_samples, noutputs)``.
    u : list of ndarray
        Inputs per experiment.
    x0 : list of ndarray or None
        Initial state used per experiment.
    fit, vaf, rmse : ndarray
        Shape ``(n_experiments, noutputs)``; see :func:`fit_metrics`.
    """

    def __init__(self, model: StateSpaceModel, horizon: int | None, u: list[np.ndarray],
                 y: list[np.ndarray], yhat: list[np.ndarray], x0: list[Any]) -> None:
        self.model, self.horizon = model, horizon
        self.u, self.y, self.yhat, self.x0 = u, y, yhat, x0
        self.output_names = list(model.output_names)
        self.dt = model.dt
        metrics = [_metrics(a, b) for a, b in zip(y, yhat)]
        self.fit = np.array([d["fit"] for d in metrics])
        self.vaf = np.array([d["vaf"] for d in metrics])
        self.rmse = np.array([d["rmse"] for d in metrics])

    @property
    def kind(self) -> str:
        """``"simulation"`` or ``"k-step prediction"``."""
        return "simulation" if self.horizon is None else f"{self.horizon}-step prediction"

    @property
    def mean_fit(self) -> float:
        """Fit averaged over outputs and experiments (a single score)."""
        return float(np.mean(self.fit))

    def to_pandas(self) -> Any:
        """One row per (experiment, output) with fit, VAF and RMSE."""
        import pandas as pd

        rows = []
        for e in range(self.fit.shape[0]):
            for j, name in enumerate(self.output_names):
                rows.append({"experiment": e, "output": name, "fit %": self.fit[e, j],
                             "VAF %": self.vaf[e, j], "RMSE": self.rmse[e, j]})
        return pd.DataFrame(rows)

    def summary(self) -> str:
        """A text table of the fit numbers."""
        lines = [f"{self.kind} of {self.model!r}",
                 f"{'exp':>4} {'output':<20} {'fit %':>9} {'VAF %':>9} {'RMSE':>11}"]
        for e in range(self.fit.shape[0]):
            for j, name in enumerate(self.output_names):
                lines.append(f"{e:>4} {name[:20]:<20} {self.fit[e, j]:9.2f} {self.vaf[e, j]:9.2f} "
                             f"{self.rmse[e, j]:11.4g}")
        return "\n".join(lines)

    def plot(self, experiment: int = 0, fig: Any = None) -> Any:
        """Measured and model outputs over time, one axis per output; returns the figure."""
        from ..plot.validation import plot_compare

        return plot_compare(self, experiment=experiment, fig=fig)

    def __repr__(self) -> str:
        fits = ", ".join(f"{n}: {f:.1f}" for n, f in zip(self.output_names, self.fit.mean(0)))
        ne = len(self.y)
        return f"CompareResult({self.kind}, {ne} experiment{'s' * (ne != 1)}, fit % [{fits}])"


def compare(model: StateSpaceModel, data: Any, horizon: int | None = None, *,
            x0: X0 = "estimate") -> CompareResult:
    """Compare a model's simulation or ``horizon``-step prediction with measured outputs.

    Parameters
    ----------
    model : StateSpaceModel
    data : IOData or (u, y)
        Validation data, ideally not used for estimation.
    horizon : int or None
        ``None`` (default) simulates from the inputs alone; ``k`` predicts ``k`` steps
        ahead with the Kalman predictor (needs ``model.K``; without it the predictor never
        looks at the measured outputs and prediction equals simulation).
    x0 : "estimate", "zero", "model" or array
        Initial state: least squares on each experiment (default), zero, the model's own, or
        given (one array, or a list with one per experiment).

    Returns
    -------
    CompareResult

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]])
    >>> u = rng.standard_normal(200)
    >>> y = m.simulate(u, x0=[5.0]) + 0.1 * rng.standard_normal((200, 1))
    >>> r = sysid.compare(m, (u, y))
    >>> bool(r.fit[0, 0] > 90)
    True
    >>> bool(sysid.compare(m, (u, y), x0="zero").fit[0, 0] < r.fit[0, 0])
    True
    """
    recs = _records(model, data)
    h = _horizon(horizon)
    us, ys, yh, x0s = [], [], [], []
    for i, (u, y) in enumerate(recs):
        x = _x0_for(model, x0, u, y, h, i, len(recs))
        us.append(u)
        ys.append(y)
        yh.append(_run(model, u, y, h, x))
        x0s.append(x)
    return CompareResult(model, h, us, ys, yh, x0s)


# -- residual analysis ------------------------------------------------------------------
def _xcorr_sums(a: np.ndarray, b: np.ndarray, lags: np.ndarray) -> np.ndarray:
    """``sum_t a(t) b(t - tau)^T`` for each lag, shape (len(lags), a.cols, b.cols)."""
    N = a.shape[0]
    out = np.zeros((lags.size, a.shape[1], b.shape[1]))
    for k, tau in enumerate(lags):
        if abs(tau) >= N:
            continue
        if tau >= 0:
            out[k] = a[tau:].T @ b[: N - tau]
        else:
            out[k] = a[: N + tau].T @ b[-tau:]
    return out


class ResidualAnalysis:
    """Correlation tests of the one-step prediction errors (innovations).

    Attributes
    ----------
    e : list of ndarray
        One-step prediction errors per experiment, ``(n_samples, noutputs)``.
    lags : ndarray
        ``0 .. max_lag`` for :attr:`autocorr`.
    autocorr : ndarray
        ``(max_lag + 1, l, l)`` normalised correlations ``r_ij(tau) = E[e_i(t) e_j(t - tau)]``.
    xlags : ndarray
        ``-max_lag .. max_lag`` for :attr:`crosscorr`.
    crosscorr : ndarray
        ``(2 max_lag + 1, l, m)`` normalised ``E[e_i(t) u_j(t - tau)]``; positive lags look at
        past inputs (missing dynamics), negative ones at future inputs (feedback).
    bound : float
        ``z_{1 - alpha/2} / sqrt(N)``: the band a white, input-independent residual stays in
        with probability ``1 - alpha`` at each lag.
    ljung_box, ljung_box_pvalue : ndarray
        Portmanteau statistic ``Q = N (N + 2) sum_{tau=1}^{M} r_ii(tau)^2 / (N - tau)`` per
        output and its p-value under ``chi2(M)``.
    whiteness : ndarray of bool
        ``p >= alpha`` per output: whiteness is not rejected.
    independence_stat, independence_pvalue : ndarray
        Ljung's (1999, eq. 16.62) test per output: ``S = N r^T R_phi^{-1} r / lambda`` with
        ``r`` the covariances of the residual with ``phi(t) = [u(t); ...; u(t - M)]``,
        ``R_phi`` the covariance of ``phi``; ``chi2(m (M + 1))`` under independence.
    independence : ndarray of bool
        ``p >= alpha`` per output.
    """

    def __init__(self, model: StateSpaceModel, e: list[np.ndarray], u: list[np.ndarray],
                 max_lag: int, alpha: float) -> None:
        self.model, self.e, self.max_lag, self.alpha = model, e, max_lag, alpha
        self.output_names, self.input_names = list(model.output_names), list(model.input_names)
        M = max_lag
        ec = [x - x.mean(0) for x in e]
        uc = [x - x.mean(0) for x in u]
        N = sum(x.shape[0] for x in e)
        self.n_samples = N
        self.lags = np.arange(M + 1)
        self.xlags = np.arange(-M, M + 1)
        ree = sum(_xcorr_sums(x, x, self.lags) for x in ec) / N
        se = np.sqrt(np.maximum(np.diag(ree[0]), 1e-300))
        self.autocorr = ree / np.outer(se, se)[None]
        m = model.ninputs
        if m:
            reu = sum(_xcorr_sums(a, b, self.xlags) for a, b in zip(ec, uc)) / N
            su = np.sqrt(np.maximum(np.diag(sum(b.T @ b for b in uc) / N), 1e-300))
            self.crosscorr = reu / np.outer(se, su)[None]
        else:
            self.crosscorr = np.zeros((2 * M + 1, len(se), 0))
        import scipy.stats

        z = scipy.stats.norm.ppf(1 - alpha / 2)
        self.bound = float(z / np.sqrt(N))
        r = np.array([self.autocorr[1:, i, i] for i in range(len(se))])  # (l, M)
        self.ljung_box = N * (N + 2) * np.sum(r**2 / (N - self.lags[1:]), axis=1)
        self.ljung_box_pvalue = scipy.stats.chi2.sf(self.ljung_box, M)
        self.whiteness = self.ljung_box_pvalue >= alpha
        self.independence_stat = np.full(len(se), np.nan)
        self.independence_pvalue = np.full(len(se), np.nan)
        if m:
            # phi(t) = [u(t); u(t-1); ...; u(t-M)], over samples with a full past
            rows_phi, rows_e = [], []
            for a, b in zip(ec, uc):
                if b.shape[0] <= M:
                    continue
                rows_phi.append(np.hstack([b[M - k: b.shape[0] - k] for k in range(M + 1)]))
                rows_e.append(a[M:])
            if rows_phi:
                phi, ee = np.vstack(rows_phi), np.vstack(rows_e)
                n_eff = phi.shape[0]
                Rphi = phi.T @ phi / n_eff
                rr = ee.T @ phi / n_eff  # (l, m (M + 1))
                lam = np.mean(ee**2, axis=0)
                sol = np.linalg.lstsq(Rphi, rr.T, rcond=1e-12)[0]  # (m(M+1), l)
                self.independence_stat = n_eff * np.einsum("ij,ji->i", rr, sol) / lam
                self.independence_pvalue = scipy.stats.chi2.sf(self.independence_stat,
                                                               m * (M + 1))
        self.independence = self.independence_pvalue >= alpha

    @property
    def is_white(self) -> bool:
        """Whiteness accepted for every output."""
        return bool(np.all(self.whiteness))

    def to_pandas(self) -> Any:
        """One row per output: Ljung-Box and independence statistics with their verdicts."""
        import pandas as pd

        return pd.DataFrame({
            "output": self.output_names, "ljung_box": self.ljung_box,
            "ljung_box_p": self.ljung_box_pvalue, "white": self.whiteness,
            "independence": self.independence_stat,
            "independence_p": self.independence_pvalue, "independent": self.independence,
        })

    def summary(self) -> str:
        """A text table of the tests."""
        M = self.max_lag
        lines = [f"residual analysis of {self.model!r}",
                 f"{self.n_samples} samples, lags 1..{M}, alpha = {self.alpha:g}, "
                 f"bound +-{self.bound:.4f}",
                 f"{'output':<20} {'Ljung-Box Q':>12} {'p':>8} {'white':>6} "
                 f"{'indep. S':>10} {'p':>8} {'indep.':>7}"]
        for i, name in enumerate(self.output_names):
            lines.append(
                f"{name[:20]:<20} {self.ljung_box[i]:12.2f} {self.ljung_box_pvalue[i]:8.3g} "
                f"{'yes' if self.whiteness[i] else 'NO':>6} {self.independence_stat[i]:10.2f} "
                f"{self.independence_pvalue[i]:8.3g} {'yes' if self.independence[i] else 'NO':>7}"
            )
        return "\n".join(lines)

    def plot(self, fig: Any = None) -> Any:
        """Auto-correlation per output and cross-correlation per (output, input) with bounds."""
        from ..plot.validation import plot_residuals

        return plot_residuals(self, fig=fig)

    def __repr__(self) -> str:
        w = ", ".join(f"{n}: {'white' if ok else 'NOT white'} (p={p:.2g})" for n, ok, p in
                      zip(self.output_names, self.whiteness, self.ljung_box_pvalue))
        return f"ResidualAnalysis({self.n_samples} samples, max_lag={self.max_lag}, {w})"


def residuals(model: StateSpaceModel, data: Any, max_lag: int = 25, *, x0: X0 = "estimate",
              alpha: float = 0.01) -> ResidualAnalysis:
    """Whiteness and independence tests of the one-step prediction errors.

    A model that captures the dynamics and the noise leaves innovations that are white and
    uncorrelated with past inputs. Means are removed before correlating.

    Parameters
    ----------
    model : StateSpaceModel
        Needs ``K`` for a meaningful test of the noise model (without it the errors are
        simulation errors, coloured whenever there is process noise).
    data : IOData or (u, y)
    max_lag : int
        Largest lag ``M`` tested.
    x0 : "estimate", "zero", "model" or array
        Initial predictor state (see :func:`compare`).
    alpha : float
        Significance level of the tests and of the plotted bounds.

    Returns
    -------
    ResidualAnalysis

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]], K=[[0.5]])
    >>> u, e = rng.standard_normal((2, 2000, 1))
    >>> x, y = 0.0, np.empty((2000, 1))
    >>> for t in range(2000):
    ...     y[t] = x + e[t]
    ...     x = 0.9 * x + u[t, 0] + 0.5 * e[t, 0]
    >>> sysid.residuals(m, (u, y)).is_white
    True
    >>> sysid.residuals(m.__class__([[0.5]], [[1.0]], [[1.0]], K=[[0.0]]), (u, y)).is_white
    False
    """
    recs = _records(model, data)
    max_lag = as_int(max_lag, "max_lag")
    if not 0 < float(alpha) < 1:
        raise DataError(f"alpha must lie strictly between 0 and 1, got {alpha!r}")
    N = min(y.shape[0] for _, y in recs)
    if max_lag >= N:
        raise DataError(f"max_lag={max_lag} needs more than {max_lag} samples per experiment; "
                        f"the shortest has {N}")
    es, us = [], []
    for i, (u, y) in enumerate(recs):
        x = _x0_for(model, x0, u, y, 1, i, len(recs))
        es.append(y - model.predict(u, y, 1, x))
        us.append(u)
    return ResidualAnalysis(model, es, us, int(max_lag), float(alpha))


# -- spectrum of the simulation error ---------------------------------------------------
class ErrorSpectrum:
    """Welch power spectra of the simulation error and of the measured output.

    Attributes
    ----------
    freq : ndarray
        Frequencies in Hz.
    error_psd, output_psd : ndarray
        ``(len(freq), noutputs)`` one-sided power spectral densities (units^2 / Hz).
    """

    def __init__(self, model: StateSpaceModel, freq: np.ndarray, err: np.ndarray,
                 out: np.ndarray) -> None:
        self.model, self.freq, self.error_psd, self.output_psd = model, freq, err, out
        self.output_names = list(model.output_names)

    def worst_frequency(self) -> np.ndarray:
        """Frequency (Hz, above zero) of the largest simulation-error power, per output."""
        return self.freq[np.argmax(self.error_psd[1:], axis=0) + 1]

    def relative_error(self) -> np.ndarray:
        """Error-to-output power ratio per frequency, ``(len(freq), noutputs)``."""
        return self.error_psd / np.maximum(self.output_psd, 1e-300)

    def plot(self, fig: Any = None) -> Any:
        """Both spectra on a log scale, one axis per output."""
        from ..plot.validation import plot_error_spectrum

        return plot_error_spectrum(self, fig=fig)

    def __repr__(self) -> str:
        return (f"ErrorSpectrum({len(self.freq)} frequencies up to {self.freq[-1]:g} Hz, "
                f"{len(self.output_names)} output(s))")


def error_spectrum(model: StateSpaceModel, data: Any, *, x0: X0 = "estimate",
                   nperseg: int | None = None) -> ErrorSpectrum:
    """Power spectrum of the simulation error ``y - yhat`` beside the output's (Welch).

    Where the error spectrum approaches the output spectrum the model explains nothing;
    a peak in the error marks a mode the model misses or misplaces.

    Parameters
    ----------
    model : StateSpaceModel
    data : IOData or (u, y)
    x0 : "estimate", "zero", "model" or array
        Initial state of the simulation.
    nperseg : int, optional
        Welch segment length (default ``min(256, shortest experiment)``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]])
    >>> u = np.random.default_rng(0).standard_normal(512)
    >>> s = sysid.error_spectrum(m, (u, m.simulate(u) + np.sin(0.5 * np.arange(512))[:, None]))
    >>> bool(abs(s.worst_frequency()[0] - 0.5 / (2 * np.pi)) < 0.01)
    True
    """
    cmp = compare(model, data, None, x0=x0)
    shortest = min(y.shape[0] for y in cmp.y)
    if nperseg is None:
        nperseg = min(256, shortest)
    else:
        nperseg = as_int(nperseg, "nperseg", 4, shortest)
    fs = 1.0 / model.dt
    err_sum, out_sum, weight = 0.0, 0.0, 0
    freq = np.zeros(0)
    for y, yh in zip(cmp.y, cmp.yhat):
        import scipy.signal

        freq, pe = scipy.signal.welch(y - yh, fs=fs, nperseg=int(nperseg), axis=0)
        _, py = scipy.signal.welch(y, fs=fs, nperseg=int(nperseg), axis=0)
        err_sum = err_sum + pe * y.shape[0]
        out_sum = out_sum + py * y.shape[0]
        weight += y.shape[0]
    return ErrorSpectrum(model, freq, np.asarray(err_sum) / weight, np.asarray(out_sum) / weight)
