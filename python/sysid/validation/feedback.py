"""Detection of feedback in a record: do past outputs help predict the input?

In open loop the input is generated independently of the noise, so the noise in past outputs
carries no information about the next input. Under feedback ``u(t) = r(t) - F y(t)`` it does.
:func:`check_feedback` tests this with the regression of ``u(t)`` on ``p`` lags of ``u`` and
on the *innovations* of the past outputs: each ``y(t - k)`` less its least-squares prediction
from ``p / 2`` lags of ``y`` and ``u`` (an ARX model fitted inside the window), for
``k = 1 .. p - p / 2`` (an F test of those coefficients per input channel,
Bonferroni-combined over inputs; Granger 1969, Caines & Chan 1975). The regressions run on
the triangular factor of the compressed record, so the test costs one compression pass;
:class:`sysid.SubspaceEstimator` runs the same test on its own factor (no extra pass) and
warns (:class:`sysid.FeedbackWarning`) when an open-loop method is used on data with feedback.

Why innovations and not the outputs themselves: in open loop the outputs also carry the inputs
older than the window (through the state). An input with a long memory, a band-limited
multisine above all, is predicted by its own ``p`` lags to 1e-6 but not exactly, and the older
inputs in the outputs then "predict" it further: with the outputs as regressors, an open-loop
multisine record of a few thousand samples was declared fed back (p < 1e-14). The ARX
innovations are free of the inputs' past; the input depends on them only through a
controller. A noise-free loop is not flagged: its innovations vanish (and without noise the
open-loop methods are not biased either). A *nonlinear* system looks fed back: the
nonlinear distortions in its outputs are functions of the input's past that a linear ARX
model leaves in the innovations (the F-16 record with the shaker voltage as input: p = 1e-37
on 8192 samples, 1e-89 before). Where the input is periodic (two whole periods or more) the
test runs on what changes from one period to the next (:func:`non_periodic_parts`): the
distortions, periodic as the input, cancel there, and a loop still feeds the output's noise
into the input.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_between, as_int
from .._display import HTMLResult, pvalue
from ..data.iodata import IOData, require_record
from ..errors import DataError, InsufficientDataError

__all__ = ["FEEDBACK_WARNING_LEVEL", "FeedbackTest", "check_feedback", "default_lags",
           "feedback_pvalues", "feedback_statistics", "non_periodic_parts"]

#: combined p-value below which the estimators that feedback biases warn of it
#: (:class:`sysid.FeedbackWarning`: the open-loop subspace methods, the output-error fits of
#: :mod:`sysid.validation.output_error`); strict, so that it does not fire by chance on
#: open-loop data
FEEDBACK_WARNING_LEVEL = 1e-6


def f_sf(F: float, d1: float, d2: float) -> float:
    """Survival function ``P(X > F)`` of the F distribution with ``(d1, d2)`` degrees of freedom.

    ``I_x(d2 / 2, d1 / 2)`` at ``x = d2 / (d2 + d1 F)``, the regularised incomplete beta by its
    continued fraction (modified Lentz): within 1e-8 relative of SciPy, far in the tail too.
    Written here because importing ``scipy.stats`` (or ``scipy.special``) costs 0.3-2 s, which
    every open-loop fit would pay for its feedback check.

    Examples
    --------
    >>> from sysid.validation.feedback import f_sf
    >>> round(f_sf(3.2, 4, 100), 6)
    0.016178
    """
    if not F > 0.0:
        return 1.0
    if not math.isfinite(F):
        return 0.0
    return _betai(0.5 * d2, 0.5 * d1, d2 / (d2 + d1 * F))


def _betai(a: float, b: float, x: float) -> float:
    """Regularised incomplete beta ``I_x(a, b)``."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    front = math.exp(math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x)
                     + b * math.log1p(-x))
    if x < (a + 1.0) / (a + b + 2.0):
        return front * _betacf(a, b, x) / a
    return 1.0 - front * _betacf(b, a, 1.0 - x) / b


def _betacf(a: float, b: float, x: float) -> float:
    """Continued fraction of the incomplete beta (modified Lentz)."""
    tiny = 1e-300

    def guard(v: float) -> float:
        return tiny if abs(v) < tiny else v

    c, d = 1.0, 1.0 / guard(1.0 - (a + b) * x / (a + 1.0))
    h = d
    for k in range(1, 100_000):
        for num in (k * (b - k) * x / ((a + 2 * k - 1) * (a + 2 * k)),
                    -(a + k) * (a + b + k) * x / ((a + 2 * k) * (a + 2 * k + 1))):
            d = 1.0 / guard(1.0 + num * d)
            c = guard(1.0 + num / c)
            h *= d * c
        if abs(d * c - 1.0) < 1e-15:
            break
    return h


def feedback_pvalues(factor: Any) -> tuple[np.ndarray, np.ndarray, int, int]:
    """Per-input F statistics and p-values of "past output innovations predict u(t)" on a
    Hankel factor.

    Returns ``(F, p_values, df_num, df_den)``; an input that its own past predicts exactly
    (a sum of sinusoids, a step) cannot be tested and gets ``F = 0, p = 1``.
    """
    F, p, _, q, df2, _ = feedback_statistics(factor)
    return F, p, q, df2


def feedback_statistics(factor: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, int,
                                            np.ndarray]:
    """:func:`feedback_pvalues` and the effect sizes beside them: ``(F, p_values, explained,
    df_num, df_den, explained_new)``, ``explained`` per input the share (0-1) of the input's
    variance that the past output innovations explain beyond its own past (``(RSS_r - RSS_f)
    / |u|^2``).

    The p-value says whether the dependence is there, the share how large it is. On a long
    record of a smooth, nearly deterministic input (a chirp, whose own past predicts it to
    0.1 % of its variance) a dependence of 0.004 % of the input's variance is significant at
    p = 1e-232 (the servo-hydraulic actuator's chirp, ``benches/results/chirp_feedback.md``):
    a measured input and output that share a coloured interference do this as a controller
    would, and so does a linear model's misfit of a nonlinear plant. The bias such a
    dependence puts in an open-loop fit grows with the share.

    ``explained_new``: per input the share (0-1) of what the input's own past leaves unexplained
    that the past output innovations explain (``(RSS_r - RSS_f) / RSS_r``). An integrating
    controller's output (a PI loop's) is predicted by its own past almost wholly, so the first
    share is tiny however closed the loop; this one says how much of the input's new movement
    the outputs drive (3-20 % on a four-tank rig under PI control, where the first share is
    0.002-0.02 %).
    """
    m, l, p = factor.n_inputs, factor.n_outputs, factor.past
    n_cols = int(factor.n_columns)
    Fs, ps, shares, news = np.zeros(m), np.ones(m), np.zeros(m), np.zeros(m)
    # the regressions of u(t) on U_p (restricted) and on U_p, Y_p (full), on the rows of the
    # triangular factor, in the Rust core on the calling thread (a threaded LAPACK call here
    # cost a loaded machine seconds on the first fit): one Householder QR per regressor set
    # for all inputs, singular values below 1e-9 of the largest dropped (rows scaled to unit
    # norm) as LAPACK gelsd's rule
    rss_rs, rss_fs, r_r, r_f, totals = _sysid.feedback_regressions(factor, 1e-9)
    q, df2 = p * l, n_cols - p * (m + l)
    for i in range(m):
        total = float(totals[i])
        rss_r, rss_f = float(rss_rs[i]), float(rss_fs[i])
        q, df2 = r_f - r_r, n_cols - r_f
        if q <= 0 or df2 <= 0 or total <= 0 or rss_r <= 1e-10 * total:
            continue  # deterministic input or no new regressor: no power, no claim
        rss_f = max(rss_f, 1e-300)
        F = max(rss_r - rss_f, 0.0) / q / (rss_f / df2)
        Fs[i], ps[i] = F, f_sf(F, q, df2)
        shares[i] = max(rss_r - rss_f, 0.0) / total
        news[i] = max(rss_r - rss_f, 0.0) / rss_r
    return Fs, ps, shares, q, df2, news


class FeedbackTest(HTMLResult):
    """Result of :func:`check_feedback`.

    Attributes
    ----------
    statistic : ndarray
        F statistic per input channel.
    p_values : ndarray
        Per input channel.
    p_value : float
        Bonferroni-combined over inputs: ``min(1, m * min(p_values))``.
    lags : int
    df : tuple of int
        Degrees of freedom of each F test: the rank the innovations add, and ``N_eff`` less
        the rank of all regressors.
    alpha : float
        Level at which :attr:`detected` is decided.
    detected : bool
        ``p_value < alpha``.
    explained : ndarray
        Per input channel, the share (0-1) of the input's variance that the past output
        innovations explain beyond the input's own past: the size of the dependence the
        p-value finds (on a long record a tiny share is significant; the bias of open-loop
        fits grows with it). Zeros when not given.
    explained_new : ndarray
        Per input channel, the share (0-1) of what the input's own past leaves unexplained
        that the past output innovations explain: under an integrating controller (PI) the
        input's own past predicts it almost wholly and :attr:`explained` is tiny, while this
        share says how much of its new movement the outputs drive. Zeros when not given.
    """

    def __init__(self, statistic: np.ndarray, p_values: np.ndarray, lags: int,
                 df: tuple[int, int], alpha: float, input_names: list[str],
                 explained: np.ndarray | None = None,
                 explained_new: np.ndarray | None = None) -> None:
        self.statistic = statistic
        self.p_values = p_values
        self.p_value = float(min(1.0, len(p_values) * float(np.min(p_values))))
        self.lags = lags
        self.df = df
        self.alpha = alpha
        self.detected = bool(self.p_value < alpha)
        self.input_names = input_names
        self.explained = (np.zeros(len(p_values)) if explained is None
                          else np.asarray(explained, float))
        self.explained_new = (np.zeros(len(p_values)) if explained_new is None
                              else np.asarray(explained_new, float))
        #: ``(period, periods)`` when the input is periodic and the test ran on what changes
        #: from period to period (:func:`non_periodic_parts`), else ``None``
        self.periodic: tuple[int, int] | None = None

    @property
    def explained_share(self) -> float:
        """The largest :attr:`explained` over the inputs."""
        return float(np.max(self.explained)) if self.explained.size else 0.0

    @property
    def explained_new_share(self) -> float:
        """The largest :attr:`explained_new` over the inputs."""
        return float(np.max(self.explained_new)) if self.explained_new.size else 0.0

    def size_text(self) -> str:
        """How much of the input the past outputs explain, in words: its variance beyond its
        own past and, when given, the part of it its own past does not predict.

        Examples
        --------
        >>> import numpy as np
        >>> from sysid.validation.feedback import FeedbackTest
        >>> t = FeedbackTest(np.ones(1), np.full(1, 1e-9), 10, (10, 900), 0.01, ["u"],
        ...                  np.full(1, 2e-4), np.full(1, 0.09))
        >>> t.size_text()
        "past outputs explain 0.02 % of the input's variance beyond its own past (9 % of the part its own past does not predict)"
        """  # noqa: E501
        text = (f"past outputs explain {100 * self.explained_share:.2g} % of the input's "
                "variance beyond its own past")
        if self.explained_new.size and np.any(self.explained_new > 0):
            text += (f" ({100 * self.explained_new_share:.2g} % of the part its own past does "
                     "not predict)")
        return text

    def __repr__(self) -> str:
        verdict = "feedback detected" if self.detected else "no feedback detected"
        return (f"FeedbackTest({verdict}: {pvalue(self.p_value, 3)} at alpha = {self.alpha}, "
                f"lags = {self.lags})")

    def summary(self) -> str:
        """A table of the per-input statistics and the verdict."""
        lines = [
            "Feedback test: do past outputs predict the input beyond its own past?",
            f"lags = {self.lags}, F({self.df[0]}, {self.df[1]}) per input",
            f"{'input':<12}{'F':>12}{'p-value':>14}{'explained %':>14}",
        ]
        for name, F, p, e in zip(self.input_names, self.statistic, self.p_values,
                                 self.explained):
            lines.append(f"{name:<12}{F:>12.4g}{p:>14.3g}{100 * e:>14.3g}")
        lines.append("explained: the share of the input's variance the past output innovations "
                     "explain beyond its own past")
        if self.periodic is not None:
            lines.append(f"periodic input ({self.periodic[0]} samples, {self.periodic[1]} "
                         f"periods): tested on what changes from one period to the next")
        lines.append(repr(self))
        if self.detected:
            lines.append("open-loop subspace methods are biased here: use sysid.pbsid or "
                         "sysid.ssarx (or PEM with a noise model)")
        return "\n".join(lines)

    def to_pandas(self) -> Any:
        """One row per input: ``F``, ``p_value``, ``explained``."""
        import pandas as pd

        return pd.DataFrame({"F": self.statistic, "p_value": self.p_values,
                             "explained": self.explained},
                            index=pd.Index(self.input_names, name="input"))

    def plot(self, ax: Any = None) -> Any:
        """Bar chart of ``-log10 p`` per input with the level ``alpha``."""
        from ..plot import _pyplot

        plt = _pyplot()
        if ax is None:
            _, ax = plt.subplots()
        vals = -np.log10(np.maximum(self.p_values, 1e-300))
        ax.bar(self.input_names, vals)
        ax.axhline(-np.log10(self.alpha), color="k", ls="--", label=f"alpha = {self.alpha}")
        ax.set_ylabel("-log10 p")
        ax.set_title("Feedback test per input")
        ax.legend()
        return ax


def default_lags(data: IOData) -> int:
    """:func:`check_feedback`'s default number of lags: ``min(20, max(2, N // (20 (m +
    l))))``, ``N`` the shortest experiment's length.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> default_lags(sysid.IOData(u=np.zeros(683), y=np.zeros(683)))
    17
    """
    shortest = min(y.shape[0] for _, y in data.experiments)
    return int(min(20, max(2, shortest // (20 * (data.n_inputs + data.n_outputs)))))


def check_feedback(data: IOData | tuple[Any, Any], lags: int | None = None, *, alpha: float = 0.01
                   ) -> FeedbackTest:
    """Test whether the input depends on past outputs (a feedback loop).

    Regresses each ``u_i(t)`` on ``lags`` past inputs and on the innovations of the past
    outputs (see the module notes) and tests, with an F test, whether the innovations improve
    the prediction (means removed per experiment first). Band-limited inputs (multisines)
    are tested correctly: only the noise in the outputs can reveal a loop. A periodic input
    (two whole periods or more) is tested on what changes from one period to the next
    (:func:`non_periodic_parts`; :attr:`FeedbackTest.periodic` says so): a loop feeds the
    output's noise back there, while the excitation and a nonlinear plant's distortions,
    periodic as the input, cancel.

    Parameters
    ----------
    data : IOData or (u, y)
        With at least one input.
    lags : int, optional
        Past samples used (default ``min(20, max(2, N // (20 (m + l))))``).
    alpha : float
        Level of the verdict :attr:`FeedbackTest.detected`.

    Returns
    -------
    FeedbackTest

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> n = 2000; r = rng.standard_normal(n); e = 0.5 * rng.standard_normal(n)
    >>> u, y = np.zeros(n), np.zeros(n)
    >>> for t in range(1, n):
    ...     y[t] = 0.8 * y[t - 1] + u[t - 1] + e[t]
    ...     u[t] = r[t] - 0.3 * y[t]
    >>> sysid.check_feedback(sysid.IOData(u=u, y=y)).detected
    True
    >>> sysid.check_feedback(sysid.IOData(u=r, y=y)).detected
    False
    """
    data = require_record(data, "check_feedback")
    if data.n_inputs == 0:
        raise DataError("check_feedback needs at least one input channel")
    alpha = as_between(alpha, "alpha", 0.0, 1.0)
    shortest = min(y.shape[0] for _, y in data.experiments)
    if lags is None:
        lags = default_lags(data)
    lags = as_int(lags, "lags", 1)
    if shortest < 2 * lags + 2:
        raise InsufficientDataError(f"lags = {lags} needs experiments of at least "
                                    f"{2 * lags + 2} samples; use fewer lags")
    periodic = non_periodic_parts(data, lags)
    if periodic is not None:  # the test on what changes from period to period
        exps, period, periods, scale = periodic
    else:
        exps = [(u - u.mean(axis=0), y - y.mean(axis=0)) for u, y in data.experiments]
    factor = _sysid.compress(exps, lags, 1, None, "qr")
    F, p, shares, q, df2, news = feedback_statistics(factor)
    if factor.n_columns <= lags * (data.n_inputs + data.n_outputs):
        raise InsufficientDataError(f"lags = {lags} leaves no degrees of freedom; use a "
                                    "longer record or fewer lags")
    if periodic is not None:  # shares of the whole input's variance, as on any record
        shares = shares * scale
    test = FeedbackTest(F, p, lags, (q, df2), float(alpha), list(data.input_names), shares,
                        news)
    if periodic is not None:
        test.periodic = (period, periods)
    return test


def non_periodic_parts(data: IOData, lags: int) -> tuple[list[Any], int, int, np.ndarray
                                                       ] | None:
    """The record's non-periodic parts, when its input is periodic (:func:`sysid.
    detect_period`, at least two whole periods in every experiment, each period at least
    ``2 lags + 2`` samples): ``(experiments, period, periods, scale)``, else ``None``.

    Under feedback ``u = r - F y`` from a periodic reference ``r``, what the input does
    differently from one period to the next is ``-F`` applied to what the output does
    differently: the output's noise. In open loop it is the input's own noise, independent
    of the output's. Everything periodic cancels there: the excitation itself, the plant's
    transient-free response and a nonlinear plant's distortions, which a linear ARX model
    leaves in the output innovations and which then "predict" a deterministic input on the
    whole record (a piezo mirror's open-loop multisine: p < 1e-300, past outputs explaining
    21 % of the input's variance). The ``K`` whole periods of each experiment give ``K - 1``
    orthonormal contrasts (Helmert's: period ``j + 1`` against the mean of the ``j`` before
    it, times ``sqrt(j / (j + 1))``), each an experiment of one period; the periodic mean is
    the one combination left out. ``scale`` per input: the contrasts' share of the input's
    variance (about its mean), by which the explained shares are rescaled to the whole
    input's.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.feedback import non_periodic_parts
    >>> rng = np.random.default_rng(0)
    >>> u = np.tile(rng.standard_normal(200), 3) + 0.01 * rng.standard_normal(600)
    >>> exps, period, periods, scale = non_periodic_parts(sysid.IOData(u=u, y=u), 10)
    >>> len(exps), period, periods, bool(scale[0] < 1e-3)
    (2, 200, 3, True)
    """
    from ..data.periodicity import detect

    found, _ = detect(data)
    if found is None or found.periods < 2 or found.period < 2 * lags + 2:
        return None
    per, k = found.period, found.periods
    out, np_energy, total = [], 0.0, 0.0
    for u, y in data.experiments:
        u, y = u[:per * k], y[:per * k]
        total = total + np.sum((u - u.mean(axis=0)) ** 2, axis=0)
        us, ys = u.reshape(k, per, -1), y.reshape(k, per, -1)
        su, sy = np.cumsum(us, axis=0), np.cumsum(ys, axis=0)  # running sums of the periods
        for j in range(1, k):
            w = np.sqrt(j / (j + 1.0))
            cu = w * (su[j - 1] / j - us[j])
            cy = w * (sy[j - 1] / j - ys[j])
            np_energy = np_energy + np.sum(cu ** 2, axis=0)
            out.append((cu - cu.mean(axis=0), cy - cy.mean(axis=0)))
    scale = np.where(total > 0, np_energy / np.where(total > 0, total, 1.0), 0.0)
    return out, per, k, scale
