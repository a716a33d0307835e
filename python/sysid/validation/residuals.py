"""Residual analysis: are the one-step prediction errors white and independent of the input?

:func:`residuals` correlates the innovations of any :class:`sysid.Model` with themselves and
with the inputs, with confidence bounds, a Ljung-Box portmanteau test of whiteness per output
and Ljung's test of independence from past inputs (as an exact regression F test).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .._checks import as_between, as_int, check_magnitudes, user_stacklevel
from .._display import HTMLResult
from ..errors import DataError, SysidWarning
from .runner import X0, _records, _run, _simulator, _x0_for, given_start, require_scored

__all__ = ["ResidualAnalysis", "default_max_lag", "no_noise_model", "residuals"]

# fewest residual degrees of freedom (samples with a full past minus regressors) for which
# the independence test is reported; below, the regression is (nearly) exact and says nothing
_MIN_RESIDUAL_DOF = 5
_BLOCK = 16384  # rows of the independence regression accumulated at a time


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


def _pooled_centred(x: list[np.ndarray]) -> list[np.ndarray]:
    """The experiments less their pooled mean (one mean over all samples)."""
    mean = sum(a.sum(0) for a in x) / max(sum(a.shape[0] for a in x), 1)
    return [a - mean for a in x]


def _lag_products(lengths: list[int], lags: np.ndarray) -> np.ndarray:
    """``N_tau = sum_k max(N_k - |tau|, 0)``: products at each lag within the experiments."""
    n = np.asarray(lengths, float)
    return np.maximum(n[None, :] - np.abs(lags)[:, None], 0.0).sum(1)


def _largest_testable_lag(lengths: list[int], m: int, below: int) -> int:
    """The largest ``M < below`` for which experiments of ``lengths`` samples leave at least
    ``_MIN_RESIDUAL_DOF`` rows beyond the ``m (M + 1)`` regressors; 0 if none."""
    for M in range(below - 1, 0, -1):
        if sum(max(n - M, 0) for n in lengths) - m * (M + 1) >= _MIN_RESIDUAL_DOF:
            return M
    return 0


def _whitening_filter(r: np.ndarray, n: int, M: int, lengths: list[int],
                      p: int) -> np.ndarray:
    """``[1, a_1, ..., a_q]``: the residual's autoregressive whitening filter ``A(q)`` from
    its autocorrelations ``r[0..M]`` (Levinson-Durbin), the order ``q <= M`` by AIC
    (``n log sigma_q^2 + 2 q``), and small enough that the filtered regression keeps
    ``_MIN_RESIDUAL_DOF`` degrees of freedom. ``[1]`` (no filter) for a white residual.

    Why: the F test's level needs the residual white. A model without a noise model (an
    output-error fit, ``ssest(..., focus="simulation")``) leaves the disturbance itself,
    coloured on nearly every record; its correlations with a coloured input's lags are then
    correlated with each other, and the test rejected the true model 10-25 % of the time at
    ``alpha = 0.01`` (a first-order plant, AR(1) 0.9 disturbance, white or AR(1) 0.9 input).
    Filtering the residual and the inputs by the same ``A(q)`` keeps the hypothesis (``A e``
    is independent of ``A u`` exactly when ``e`` is of ``u``) and whitens the residual, as
    the classic prewhitening of cross-correlation checks does (Box & Jenkins)."""
    a, E = np.ones(1), float(r[0])
    if not (np.isfinite(E) and E > 0.0):
        return a
    best = (n * np.log(E), a)
    for k in range(1, M + 1):
        if sum(max(x - M - k, 0) for x in lengths) - p < _MIN_RESIDUAL_DOF:
            break
        refl = -float(np.dot(a, r[k:0:-1])) / E
        if not abs(refl) < 1.0:
            break
        a = np.concatenate([a, [0.0]])
        a = a + refl * a[::-1]
        E *= 1.0 - refl * refl
        if not E > 0.0:
            break
        aic = n * np.log(E) + 2 * k
        if aic < best[0]:
            best = (aic, a.copy())
    return best[1]


def _regression_statistic(es: list[np.ndarray], us: list[np.ndarray], M: int,
                          a: np.ndarray) -> tuple[float, int, int]:
    """``(S, rank, n)``: ``n R^2`` of the least-squares regression of the residual ``es``
    (one output, per experiment) on ``phi(t) = [u(t); ...; u(t - M)]``, both filtered by
    ``a`` (its first ``len(a) - 1`` samples per experiment dropped), over the samples with
    a full past; ``rank`` is that of ``phi``."""
    from scipy.signal import lfilter

    q = a.size - 1
    Rphi, rr, ee, n = 0.0, 0.0, 0.0, 0
    for e, u in zip(es, us):
        if u.shape[0] <= M + q:
            continue
        ew = lfilter(a, 1.0, e)[q:] if q else e
        uw = lfilter(a, 1.0, u, axis=0)[q:] if q else u
        for t0 in range(M, uw.shape[0], _BLOCK):  # blocks of rows: no N x p array
            t1 = min(t0 + _BLOCK, uw.shape[0])
            phi = np.hstack([uw[t0 - k: t1 - k] for k in range(M + 1)])
            Rphi = Rphi + phi.T @ phi
            rr = rr + phi.T @ ew[t0:t1]
        ee = ee + float(ew[M:] @ ew[M:])
        n += uw.shape[0] - M
    Rphi, rr = np.asarray(Rphi) / n, np.asarray(rr) / n
    sol, _, rank, _ = np.linalg.lstsq(Rphi, rr, rcond=1e-12)
    return float(n * (rr @ sol) / max(ee / n, 1e-300)), int(rank), n


def no_noise_model(model: Any) -> bool:
    """Whether ``model`` has no noise model: its one-step prediction is its simulation (an
    output-error polynomial, a transfer-function or process model, a state-space model
    without a Kalman gain or with a zero one, as a simulation-focus ``ssest``; an
    :class:`~sysid.IdentifiedModel` by its state-space model). False where that cannot be
    told (a nonlinear model's state-space form is its linear part).

    Examples
    --------
    >>> import sysid
    >>> from sysid.validation.residuals import no_noise_model
    >>> no_noise_model(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]))
    True
    >>> no_noise_model(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], K=[[0.2]]))
    False
    """
    if getattr(model, "prediction_is_simulation", False):
        return True
    model = getattr(model, "statespace", model)
    if not hasattr(model, "to_statespace") or not getattr(model, "statespace_is_exact", True):
        return False
    try:
        ss = model if hasattr(model, "K") and hasattr(model, "A") else model.to_statespace()
    except Exception:  # noqa: BLE001 - no state-space form: nothing to say
        return False
    K = getattr(ss, "K", None)
    return K is None or not np.any(np.asarray(K) != 0)


def default_max_lag(data: Any) -> int:
    """The largest residual lag the command line and the report use: ``min(25, N / 5)`` for
    the shortest experiment, lowered to the largest for which the independence test can be
    made with the record's inputs (their lags must leave rows to spare).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.residuals import default_max_lag
    >>> default_max_lag(sysid.IOData(u=np.zeros((1000, 1)), y=np.zeros((1000, 1))))
    25
    >>> default_max_lag(sysid.IOData(u=np.zeros((67, 5)), y=np.zeros((67, 3))))  # 5 inputs
    9
    """
    lengths = [y.shape[0] for _, y in data.experiments]
    lag = min(25, max(1, min(lengths) // 5))
    m = data.n_inputs
    if m:
        fit = _largest_testable_lag(lengths, m, lag + 1)
        lag = max(1, min(lag, fit)) if fit > 0 else lag
    return lag


class ResidualAnalysis(HTMLResult):
    """Correlation tests of the one-step prediction errors (innovations).

    Attributes
    ----------
    e : list of ndarray
        One-step prediction errors per experiment, ``(n_samples, noutputs)`` (a NARX
        model's: after its first ``max_lag`` samples, which it copies).
    lags : ndarray
        ``0 .. max_lag`` for :attr:`autocorr`.
    autocorr : ndarray
        ``(max_lag + 1, l, l)`` normalised correlations ``r_ij(tau) = E[e_i(t) e_j(t - tau)]``:
        the lag products within each experiment, summed over the experiments and divided by
        the pooled ``N`` (and the lag-0 scales), after removing the pooled mean (MATLAB's
        ``resid`` joins experiments' correlations this way).
    xlags : ndarray
        ``-max_lag .. max_lag`` for :attr:`crosscorr`.
    crosscorr : ndarray
        ``(2 max_lag + 1, l, m)`` normalised ``E[e_i(t) u_j(t - tau)]``; positive lags look at
        past inputs (missing dynamics), negative ones at future inputs (feedback).
    bound : float
        ``z_{1 - alpha/2} / sqrt(N)``: the band a white, input-independent residual stays in
        with probability ``1 - alpha`` at each lag of one experiment.
    bounds, xbounds : ndarray
        The band per lag of :attr:`lags` and :attr:`xlags`: :attr:`bound` times
        ``sqrt(N_tau / (N - |tau|))``, with ``N_tau = sum_k max(N_k - |tau|, 0)`` the lag
        products the experiments hold (``N - n_exp |tau|`` for equal lengths, not the
        ``N - |tau|`` of one record); equal to :attr:`bound` for one experiment.
    ljung_box, ljung_box_pvalue : ndarray
        Portmanteau statistic ``Q = N (N + 2) sum_{tau=1}^{M} r_ii(tau)^2 / N_tau`` per
        output (``N_tau = N - tau`` for one experiment) and its p-value under ``chi2(M)``.
    whiteness : ndarray of bool
        ``p >= alpha`` per output: whiteness is not rejected.
    independence_stat, independence_pvalue : ndarray
        Ljung's (1999, eq. 16.62) test per output: ``S = N r^T R_phi^{-1} r / lambda`` with
        ``r`` the covariances of the residual with ``phi(t) = [u(t); ...; u(t - M)]`` over
        the ``n`` samples with a full past, ``R_phi`` the covariance of ``phi``, both filtered
        by the residual's whitening filter (:attr:`whitening_order`). ``S / n`` is
        the ``R^2`` of the least-squares regression of the residual on ``phi``; the p-value
        is that of the exact regression F test, ``F = (R^2/p) / ((1 - R^2)/(n - p))``
        against ``F(p, n - p)``, ``p = m (M + 1)`` (the rank of ``phi``). Its large-sample
        limit ``chi2(p)`` for ``S`` holds its size only for ``p`` small next to ``n``.
        NaN where the test is not made (no inputs, or fewer than ``p + 5`` samples with a
        full past: the regression then fits any residual; see :attr:`independence_note`).
    independence_dof : tuple of int
        ``(p, n - p)`` of the F test, ``(0, 0)`` when not made.
    independence : ndarray of object
        Per output ``True`` (``p >= alpha``: independence not rejected), ``False``, or
        ``None`` where the test is not made.
    independence_note : str
        Why the independence test is not made (empty when it is).
    whiteness_note : str
        Set by :func:`residuals` when whiteness is rejected for a model without a noise
        model (its errors are the disturbance: the test then says nothing about the model).
    whitening_order : ndarray of int
        Per output, the order ``q`` of the residual's autoregressive whitening filter
        ``A(q)`` (AIC, at most ``M``) by which the residual and the inputs are filtered
        before the independence regression, so that a coloured residual (a model without a
        noise model) keeps the test's level; 0 where the residual is white. The plotted
        cross-correlations and their band are of the unfiltered signals, as MATLAB's.
    """

    def __init__(self, model: Any, e: list[np.ndarray], u: list[np.ndarray],
                 max_lag: int, alpha: float) -> None:
        self.model, self.e, self.max_lag, self.alpha = model, e, max_lag, alpha
        self.output_names, self.input_names = list(model.output_names), list(model.input_names)
        M = max_lag
        # one mean over all experiments: a mean per experiment biases every lag by about
        # -1 / N_k, which the Ljung-Box sum of squares turns into rejections of a true model
        ec, uc = _pooled_centred(e), _pooled_centred(u)
        N = sum(x.shape[0] for x in e)
        self.n_samples = N
        self.lags = np.arange(M + 1)
        self.xlags = np.arange(-M, M + 1)
        counts = _lag_products([x.shape[0] for x in e], self.xlags)  # N_tau per xlag
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
        # a white residual's r(tau) has variance N_tau / N^2: the one-record band scaled by
        # the share of lag products the experiments' breaks leave
        self.xbounds = self.bound * np.sqrt(counts / np.maximum(N - np.abs(self.xlags), 1))
        self.bounds = self.xbounds[M:]
        r = np.array([self.autocorr[1:, i, i] for i in range(len(se))])  # (l, M)
        n_tau = np.maximum(counts[M + 1:], 1)
        self.ljung_box = N * (N + 2) * np.sum(r**2 / n_tau, axis=1)
        self.ljung_box_pvalue = scipy.stats.chi2.sf(self.ljung_box, M)
        self.whiteness = self.ljung_box_pvalue >= alpha
        self.independence_stat = np.full(len(se), np.nan)
        self.independence_pvalue = np.full(len(se), np.nan)
        self.independence_dof = (0, 0)
        self.independence_note = ("" if m else
                                  "independence not tested: the model has no inputs")
        self.whitening_order = np.zeros(len(se), dtype=int)
        self.whiteness_note = ""
        if m:
            self._independence(ec, uc, M, m)
        self.independence = np.array(
            [None if np.isnan(p) else bool(p >= alpha) for p in self.independence_pvalue],
            dtype=object)

    def _independence(self, ec: list[np.ndarray], uc: list[np.ndarray], M: int,
                      m: int) -> None:
        """Ljung's test as the exact regression F test of the residual on ``phi``, after both
        are filtered by the residual's own whitening filter (:func:`_whitening_filter`)."""
        import scipy.stats

        n_eff, p = sum(max(b.shape[0] - M, 0) for b in uc), m * (M + 1)
        if n_eff - p < _MIN_RESIDUAL_DOF or not any(np.ptp(b, axis=0).any() for b in uc):
            fit = _largest_testable_lag([x.shape[0] for x in ec], m, M)
            self.independence_note = (
                f"independence not tested: {n_eff} samples with a full past for "
                f"{p} regressors ({m} input(s) x {M + 1} lags); "
                + ("the input does not vary" if n_eff - p >= _MIN_RESIDUAL_DOF else
                   f"use max_lag <= {fit}" if fit > 0 else "the record is too short"))
            return
        l = ec[0].shape[1]
        self.whitening_order = np.zeros(l, dtype=int)
        dof = []
        for i in range(l):
            a = _whitening_filter(self.autocorr[:, i, i], self.n_samples, M,
                                  [b.shape[0] for b in uc], p)
            self.whitening_order[i] = a.size - 1
            S, rank, n = _regression_statistic([x[:, i] for x in ec], uc, M, a)
            self.independence_stat[i] = S
            # S / n is the R^2 of the regression of the residual on phi: under independence
            # (Gaussian residuals) it is Beta(p/2, (n - p)/2), i.e. F = (R^2/p)/((1-R^2)/(n-p))
            # follows F(p, n - p); chi2(p) is its large-sample limit and too lenient when p
            # is not small next to n
            self.independence_pvalue[i] = scipy.stats.beta.sf(min(max(S / n, 0.0), 1.0),
                                                              rank / 2, (n - rank) / 2)
            dof.append((int(rank), int(n - rank)))
        self.independence_dof = min(dof, key=lambda d: d[1])

    @property
    def is_white(self) -> bool:
        """Whiteness accepted for every output."""
        return bool(np.all(self.whiteness))

    def to_pandas(self) -> Any:
        """One row per output: Ljung-Box and independence statistics with their verdicts
        (``independent`` is ``<NA>`` where independence is not tested)."""
        import pandas as pd

        return pd.DataFrame({
            "output": self.output_names, "ljung_box": self.ljung_box,
            "ljung_box_p": self.ljung_box_pvalue, "white": self.whiteness,
            "independence": self.independence_stat,
            "independence_p": self.independence_pvalue,
            "independent": pd.array(self.independence, dtype="boolean"),
        })

    def summary(self) -> str:
        """A text table of the tests."""
        M = self.max_lag
        w = max([20] + [len(str(n)) for n in self.output_names])  # names whole
        lines = [f"residual analysis of {self.model!r}",
                 f"{self.n_samples} samples, lags 1..{M}, alpha = {self.alpha:g}, "
                 f"bound +-{self.bound:.4f}",
                 f"{'output':<{w}} {'Ljung-Box Q':>12} {'p':>8} {'white':>6} "
                 f"{'indep. S':>10} {'p':>8} {'indep.':>7}"]
        for i, name in enumerate(self.output_names):
            ind = self.independence[i]
            lines.append(
                f"{name:<{w}} {self.ljung_box[i]:12.2f} {self.ljung_box_pvalue[i]:8.3g} "
                f"{'yes' if self.whiteness[i] else 'NO':>6} {self.independence_stat[i]:10.2f} "
                f"{self.independence_pvalue[i]:8.3g} "
                f"{'n/a' if ind is None else 'yes' if ind else 'NO':>7}"
            )
        if self.independence_note:
            lines.append(self.independence_note)
        if self.whiteness_note:
            lines.append(self.whiteness_note)
        return "\n".join(lines)

    def plot(self, fig: Any = None) -> Any:
        """Auto-correlation per output and cross-correlation per (output, input) with bounds."""
        from ..plot.validation import plot_residuals

        return plot_residuals(self, fig=fig)

    def __repr__(self) -> str:
        w = ", ".join(f"{n}: {'white' if ok else 'NOT white'} (p={p:.2g})" for n, ok, p in
                      zip(self.output_names, self.whiteness, self.ljung_box_pvalue))
        return f"ResidualAnalysis({self.n_samples} samples, max_lag={self.max_lag}, {w})"


def residuals(model: Any, data: Any, max_lag: int = 25, *, x0: X0 = "estimate",
              alpha: float = 0.01) -> ResidualAnalysis:
    """Whiteness and independence tests of the one-step prediction errors.

    A model that captures the dynamics and the noise leaves innovations that are white and
    uncorrelated with past inputs. The mean over all experiments is removed before
    correlating; lags run within experiments, never across their joins. A NARX model's first
    ``max_lag`` samples of each experiment are its initial condition, copies of the measured
    outputs (errors of zero): they are left out, errors and inputs alike
    (:func:`~sysid.validation.runner.given_start`).

    The tests hold their level ``alpha`` for the true model; the independence test also for
    a model without a noise model (an output-error fit, ``focus="simulation"``), whose errors
    are the coloured disturbance itself: both the errors and the inputs are first filtered by
    the errors' own autoregressive whitening filter (``whitening_order``; without it the true
    model was rejected 10-25 % of the time at ``alpha = 0.01`` under an AR(1) 0.9
    disturbance). MATLAB's advice for output-error models: judge them by this test, not by
    whiteness. An estimated model's errors also
    hold its own estimation error, ``(G - G_hat) u`` and the noise model's, which the tests
    are built to see once the record is long enough: on a validation record as long as the
    estimation one, ``ssest(data, n)`` models at the true order are rejected at ``alpha =
    0.01`` about 8 % of the time for whiteness and 13 % for independence
    (``benches/results/warning_audit.md``). A rejection says the model can still be improved
    on this record, not that its structure is wrong.

    Parameters
    ----------
    model : sysid.Model
        Any model; a state-space model needs ``K`` for a meaningful test of the noise
        model (without it the errors are simulation errors, coloured whenever there is
        process noise).
    data : IOData or (u, y)
        The record (MATLAB's order, ``residuals(data, model)``, is accepted too).
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
    model, recs = _records(model, data)
    max_lag = as_int(max_lag, "max_lag")
    # the range check the estimators apply: |y| near 1e200 gave a NaN Ljung-Box statistic
    check_magnitudes(recs, "residuals")
    alpha = as_between(alpha, "alpha", 0.0, 1.0)
    runner = _simulator(model, x0, 1, recs[0][0] if recs else None)  # x0 fitted as compare
    start = given_start(runner)  # a NARX model's first max_lag errors are zero by construction
    require_scored(recs, start, model)
    N = min(y.shape[0] for _, y in recs) - start
    if max_lag >= N:
        raise DataError(f"max_lag={max_lag} needs more than {max_lag} samples per experiment"
                        + (f" after the first {start} (the model's initial condition)"
                           if start else "") + f"; the shortest has {N}")
    es, us = [], []
    for i, (u, y) in enumerate(recs):
        x = _x0_for(runner, x0, u, y, 1, i, len(recs))
        es.append((y - _run(runner, u, y, 1, x))[start:])
        us.append(u[start:])
    res = ResidualAnalysis(model, es, us, int(max_lag), float(alpha))
    if not res.is_white and model.ninputs and no_noise_model(model):
        res.whiteness_note = (
            "whiteness: the model has no noise model (its one-step prediction is its "
            "simulation), so its errors are the disturbance itself and the whiteness test "
            "judges the disturbance, not the model; judge its dynamics by the independence "
            "test (MATLAB's advice for output-error models), or fit a noise model (focus="
            "'prediction', armax, bj) for predictions")
    if model.ninputs and res.independence_note:
        warnings.warn(res.independence_note + " (the whiteness test stands)", SysidWarning,
                      stacklevel=user_stacklevel())
    return res
