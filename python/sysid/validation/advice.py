"""What to do with a record before fitting it (MATLAB's ``advice(data)``).

``advice(data)`` runs the package's data checks and says, per topic, what was found and what
to do: offsets (the rule every estimator applies, :mod:`sysid.data.offsets`), drifts,
excitation (:func:`sysid.persistent_excitation_order`), feedback
(:func:`sysid.check_feedback`), periodic excitation (:func:`sysid.detect_period`),
isolated spikes (:func:`sysid.data.preprocessing.spike_report`), input delays
(:func:`sysid.delayest`) and nonlinearity.

The nonlinearity check fits a linear ARX model (``na = nb = 2`` at the estimated delays) and
asks whether second-degree products of its regressors explain its residuals: an F-test of
the residuals on those products, flagged when significant at 0.1 % *and* explaining at least
2 % of the residual variance (on long records any small curvature is significant; what
matters is whether a nonlinear model could fit noticeably better). A linear system with
coloured noise explains no share of an ARX model's residuals with products of its own
regressors, so the noise alone does not trigger it.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._display import HTMLResult, pvalue
from .._threads import one_blas_thread
from ..data.iodata import require_record
from ..data.preprocessing import line_share
from ..errors import DataError, InsufficientDataError

__all__ = ["Advice", "Finding", "advice"]

#: a drift is noted when a straight line in time explains this share of an output's variance
TREND_SHARE = 0.5
#: the nonlinearity check's significance level and the residual share it must explain
NONLINEAR_ALPHA, NONLINEAR_SHARE = 1e-3, 0.02


@dataclass
class Finding:
    """One topic's check: ``verdict`` is ``"ok"``, ``"note"`` (worth knowing) or ``"act"``
    (fix it before fitting)."""

    topic: str
    verdict: str
    finding: str
    action: str = ""


class Advice(HTMLResult):
    """The findings of :func:`advice`, one per topic; ``advice["feedback"]`` gets one.

    Attributes
    ----------
    findings : list of Finding
    """

    def __init__(self, findings: list[Finding]) -> None:
        self.findings = findings

    def __getitem__(self, topic: str) -> Finding:
        for f in self.findings:
            if f.topic == topic:
                return f
        raise KeyError(f"no finding on {topic!r}; topics: "
                       f"{', '.join(f.topic for f in self.findings)}")

    @property
    def to_act_on(self) -> list[str]:
        """The topics to fix before fitting."""
        return [f.topic for f in self.findings if f.verdict == "act"]

    def summary(self) -> str:
        """One line per topic, and what to do."""
        lines = [repr(self)]
        for f in self.findings:
            lines.append(f"  [{f.verdict:>4}] {f.topic}: {f.finding}")
            if f.action:
                lines.append(f"         -> {f.action}")
        return "\n".join(lines)

    def to_pandas(self) -> Any:
        """One row per topic: topic, verdict, finding, action."""
        import pandas as pd

        return pd.DataFrame([vars(f) for f in self.findings])

    def __repr__(self) -> str:
        act = self.to_act_on
        notes = [f.topic for f in self.findings if f.verdict == "note"]
        return (f"Advice({len(self.findings)} checks; to act on: "
                f"{', '.join(act) if act else 'none'}; notes: "
                f"{', '.join(notes) if notes else 'none'})")


def _stack(data: Any, idx: int) -> np.ndarray:
    return np.vstack([e[idx] for e in data.experiments])


def _offsets(data: Any) -> Finding:
    from ..data.offsets import OFFSET_RATIO, offsets

    big = offsets(data)
    if big:
        names = ", ".join(f"{k} {n} (mean {m:.4g}, std {s:.3g})" for k, n, m, s in big[:4])
        return Finding("offsets", "act", f"offsets that cost a linear fit: {names}",
                       "sysid.detrend(data, 'constant', return_trend=True), then "
                       "trend.apply(validation); or sysid.identify(data), which removes "
                       "and restores them")
    chans = [("input", j, n) for j, n in enumerate(data.input_names)] + \
        [("output", j, n) for j, n in enumerate(data.output_names)]
    small = []
    for kind, j, name in chans:
        x = _stack(data, 0 if kind == "input" else 1)[:, j]
        if x.std() > 0 and abs(x.mean()) > 0.1 * x.std():
            small.append(f"{kind} {name}")
    if small and not getattr(data, "has_trend", False):
        return Finding("offsets", "note",
                       f"non-zero means ({', '.join(small[:4])}; below what every estimator "
                       f"warns at: {OFFSET_RATIO:g} standard deviations, or a quick ARX fit "
                       "losing fit to them)",
                       "linear models have no constant term: remove the means "
                       "(sysid.detrend(data, 'constant', return_trend=True))")
    return Finding("offsets", "ok", "means removed or negligible")


def _trends(data: Any) -> Finding:
    shares = []
    for j, name in enumerate(data.output_names):
        r2 = [float(line_share(e[1][:, j])[0]) for e in data.experiments]
        if r2 and max(r2) > TREND_SHARE:
            shares.append(f"{name} ({100 * max(r2):.0f} %)")
    if shares:
        return Finding("trends", "note",
                       f"a straight line in time explains most of the variance of "
                       f"{', '.join(shares)}",
                       "if the drift is not the input's doing (an integrating process is), "
                       "remove it: sysid.detrend(data, 'linear', return_trend=True)")
    return Finding("trends", "ok", "no drift dominates an output")


def _flat_inputs(data: Any) -> list[str]:
    """The inputs that hold one value in every sample."""
    if data.n_inputs == 0:
        return []
    u = _stack(data, 0)
    return [n for j, n in enumerate(data.input_names) if np.ptp(u[:, j]) == 0]


def _excitation(data: Any, flat: list[str]) -> Finding:
    from ..data.input_design import persistent_excitation_order
    from ..subspace.steptest import step_changes, stepped_inputs

    if data.n_inputs == 0:
        return Finding("excitation", "ok", "no inputs: a time series (sysid.ar, sysid.n4sid)")
    u = _stack(data, 0)
    if flat:
        return Finding("excitation", "act", f"input(s) {', '.join(flat)} never change",
                       "drop them (data.select(inputs=...)) or record with them excited")
    steps = step_changes(data.experiments)
    if steps is not None:
        # the spectral count assumes a stationary input: that of a step test is its edges'
        # (an irrigation canal's gate step at sample 1 read "order >= 40"); the subspace
        # fits refuse it only when every change precedes their data matrix's future rows (a
        # pulse in mid-record passed n4sid's rank test and gave a 22-state model)
        return Finding("excitation", "note",
                       f"the input changes at sample(s) {', '.join(map(str, steps))} only: a "
                       f"step test, not a stationary input whose spectrum counts its "
                       f"excitation; the subspace fits see only the few windows around its "
                       f"changes (and refuse it when they all come before their data "
                       f"matrix's rows of future inputs)",
                       "fit models simulated from rest: sysid.identify(data) (process "
                       "models by BIC), sysid.procest, sysid.tfest or sysid.oe")
    # one input of several switched a few times (a pulse beside a ramped input): its
    # spectrum is its edges', and the joint count spoke for it as for the others
    stepped = stepped_inputs(data)
    if stepped and len(stepped) < data.n_inputs:
        rest = [j for j in range(data.n_inputs) if data.input_names[j] not in stepped]
        pe = persistent_excitation_order(
            [e[0][:, rest] for e in data.experiments] if data.n_experiments > 1
            else u[:, rest], 40)
        said = "; ".join(f"{n} at sample(s) {', '.join(map(str, c))}"
                         for n, c in stepped.items())
        return Finding("excitation", "note",
                       f"input(s) {', '.join(stepped)} change only a few times ({said}): "
                       f"steps or pulses, whose responses alone determine their paths, not a "
                       f"stationary excitation a spectrum counts; the other input(s) "
                       f"persistently exciting of order {'>= ' if pe == 40 else ''}{pe}",
                       "judge the model of those paths by simulation on a record holding "
                       "other steps (identify(..., validation=...)), or excite them richly "
                       "(sysid.idinput)")
    pe = persistent_excitation_order(
        [e[0] for e in data.experiments] if data.n_experiments > 1 else u, 40)
    if pe < 4:
        what = f"the input is persistently exciting of order {pe} only"
        if data.n_inputs > 1:  # name the input that limits it (rain beside a climatology)
            per = [persistent_excitation_order(
                [e[0][:, [j]] for e in data.experiments] if data.n_experiments > 1
                else u[:, [j]], 40) for j in range(data.n_inputs)]
            low = [n for n, p in zip(data.input_names, per) if p < 4]
            what = (f"the inputs together are persistently exciting of order {pe} only, "
                    f"limited by {', '.join(low)} (alone: order "
                    f"{', '.join(str(p) for p in per if p < 4)}; "
                    + "; ".join(f"{n} alone: order {'>= ' if p == 40 else ''}{p}"
                                for n, p in zip(data.input_names, per) if p >= 4) + ")"
                    if low and len(low) < data.n_inputs else
                    f"the inputs together are persistently exciting of order {pe} only")
        return Finding("excitation", "act",
                       f"{what}: models of order above {pe // 2} are not determined by the "
                       "data",
                       "excite more frequencies (sysid.idinput, sysid.multisine) or keep "
                       f"the order at most {max(pe // 2, 1)}")
    return Finding("excitation", "ok",
                   f"input persistently exciting of order >= {pe} (models up to order "
                   f"{pe // 2} determined)")


def _feedback(data: Any) -> Finding:
    from .feedback import check_feedback

    if data.n_inputs == 0:
        return Finding("feedback", "ok", "no inputs")
    try:
        fb = check_feedback(data)
    except InsufficientDataError as e:  # a short record of many channels: reported
        return Finding("feedback", "note", f"not tested ({e})")
    if fb.detected:
        return Finding("feedback", "act",
                       f"the input depends on past outputs ({pvalue(fb.p_value)}; "
                       f"{fb.size_text()}): a closed "
                       "loop, unless the plant is nonlinear (its distortions, which a linear "
                       "model leaves in its residuals, look like feedback: a periodic input "
                       "to a nonlinear structure does this)",
                       "open-loop subspace fits are biased there: use "
                       "sysid.pbsid(data, order) or sysid.ssarx, or "
                       "sysid.ssest(data, order, method='pbsid') (prediction error)")
    return Finding("feedback", "ok", f"no feedback found ({pvalue(fb.p_value)})")


def _periodic(data: Any) -> Finding:
    from ..data.periodicity import detect_period

    try:
        per = detect_period(data)
    except Exception:  # noqa: BLE001 - a record it cannot read has no period to report
        per = None
    if per is None:
        return Finding("periodic", "ok", "the input does not repeat")
    return Finding("periodic", "note",
                   f"the input repeats every {per.period} samples ({per.periods} periods)",
                   "average the periods and fit the excited lines (sysid.ssest(data, order, "
                   "periods='auto')); the best linear approximation and its nonlinear "
                   "distortions: sysid.bla(data, periods=...)")


def _outliers(data: Any) -> Finding:
    from ..data.preprocessing import spike_report

    rep = spike_report(data)
    if rep:
        return Finding("outliers", "act", rep, "sysid.despike(data), or cut them out")
    return Finding("outliers", "ok", "no isolated spikes in the outputs")


def _delays(data: Any) -> tuple[Finding, np.ndarray | None]:
    from ..polynomial.delayest import delays

    if data.n_inputs == 0:
        return Finding("delays", "ok", "no inputs"), None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            nk, weak, _, _ = delays(data)
    except Exception as e:  # noqa: BLE001 - reported, not raised
        return Finding("delays", "note", f"not estimated ({e})"), None
    # a pair whose input explains nothing at any delay searched has no delay to give (its
    # loss is flat, the least anywhere: delayest warns so, which this finding swallowed)
    blind = {(i, j): ("the input does not excite its lags independently" if np.isnan(p)
                      else "no delay searched makes the input explain it")
             for i, j, p in weak}
    pairs = [f"{data.input_names[j]} -> {data.output_names[i]}: "
             + (f"not determined ({blind[i, j]})" if (i, j) in blind else str(nk[i, j]))
             for i in range(nk.shape[0]) for j in range(nk.shape[1])]
    if all(nk[i, j] <= 1 or (i, j) in blind
           for i in range(nk.shape[0]) for j in range(nk.shape[1])):
        return Finding("delays", "ok", "no dead time beyond one sample (" + "; ".join(
            pairs[:6]) + ")"), nk
    return Finding("delays", "note", "input delays in samples: " + "; ".join(pairs[:6]),
                   "give them to the polynomial estimators (nk) or as input delays; "
                   "state-space fits need extra states for them otherwise"), nk


def _monomials(x: np.ndarray) -> np.ndarray:
    k = x.shape[1]
    cols = [x[:, i] * x[:, j] for i in range(k) for j in range(i, k)]
    return np.column_stack(cols)


def _nonlinearity(data: Any, nk: np.ndarray | None) -> Finding:
    from scipy import stats

    from ..polynomial.arx import arx
    from .free_run import skipped

    if data.n_inputs == 0:
        return Finding("nonlinearity", "ok", "not checked: no inputs")
    ny, nu = data.n_outputs, data.n_inputs
    k = np.ones((ny, nu), int) if nk is None else np.maximum(nk, 0)
    try:
        with warnings.catch_warnings(), skipped():
            warnings.simplefilter("ignore")
            m = arx(data, 2, np.full((ny, nu), 2), k)
    except Exception as e:  # noqa: BLE001 - reported, not raised
        return Finding("nonlinearity", "note", f"not checked ({e})")
    flagged = []
    lag = int(max(2, k.max() + 1))
    for i, name in enumerate(data.output_names):
        rows, res = [], []
        for u, y in data.experiments:
            if y.shape[0] <= lag + 2:
                continue
            e = (y - m.predict(u, y, 1))[lag:, i]
            reg = [y[lag - 1:-1, i], y[lag - 2:-2, i]]
            for j in range(nu):
                reg += [u[lag - k[i, j]:u.shape[0] - k[i, j], j],
                        u[lag - k[i, j] - 1:u.shape[0] - k[i, j] - 1, j]]
            rows.append(np.column_stack(reg))
            res.append(e)
        if not rows:
            continue
        X, e = np.vstack(rows), np.concatenate(res)
        X = (X - X.mean(0)) / np.where(X.std(0) > 0, X.std(0), 1.0)
        Z = np.column_stack([np.ones(len(e)), X, _monomials(X)])
        p0, q = 1 + X.shape[1], Z.shape[1] - 1 - X.shape[1]
        if len(e) <= Z.shape[1] + 10:
            continue
        rss0 = float(np.sum((e - e.mean()) ** 2))
        coef = np.linalg.lstsq(Z, e, rcond=None)[0]
        rss1 = float(np.sum((e - Z @ coef) ** 2))
        if rss0 <= 0:
            continue
        f = ((rss0 - rss1) / q) / (rss1 / (len(e) - p0 - q)) if rss1 > 0 else np.inf
        p = float(stats.f.sf(f, q, len(e) - p0 - q))
        share = 1 - rss1 / rss0
        if p < NONLINEAR_ALPHA and share >= NONLINEAR_SHARE:
            flagged.append(f"{name} ({100 * share:.0f} % of its residual variance, "
                           f"{pvalue(p, 1)})")
    if flagged:
        return Finding("nonlinearity", "note",
                       "products of past inputs and outputs explain a linear model's "
                       "residuals: " + ", ".join(flagged),
                       "a nonlinear model may fit better: sysid.nlarx, sysid.nlhw, or "
                       "sysid.pnlss on periodic data")
    return Finding("nonlinearity", "ok", "no sign that a nonlinear model would fit better")


@one_blas_thread
def advice(data: Any) -> Advice:
    """Check a record before fitting it and say what to do (MATLAB's ``advice(data)``).

    Parameters
    ----------
    data : IOData or (u, y)

    Returns
    -------
    Advice
        A :class:`Finding` per topic (``offsets``, ``trends``, ``excitation``,
        ``feedback``, ``periodic``, ``outliers``, ``delays``, ``nonlinearity``): verdict
        ``"ok"``, ``"note"`` or ``"act"``, what was found and what to do;
        ``.summary()``, ``.to_pandas()``, ``advice["feedback"]``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((1000, 1))
    >>> y = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]]).simulate(u)
    >>> a = sysid.advice(sysid.IOData(u, y + 20.0 + 0.1 * rng.standard_normal((1000, 1))))
    >>> a.to_act_on
    ['offsets']
    >>> a["nonlinearity"].verdict, a["delays"].verdict
    ('ok', 'ok')
    """
    data = require_record(data, "advice")
    if not data.output_names:
        raise DataError("advice needs a record with outputs")
    from ..data.offsets import remove_means

    centred = remove_means(data)[0]  # the model-based checks see the record as a fit would
    flat = _flat_inputs(data)
    excitation = _excitation(data, flat)
    if flat:
        # centred, a constant input reads as "0 in every sample" to the model-based checks
        why = f"not checked: {excitation.finding} (see excitation)"
        delays, nk = Finding("delays", "note", why), None
        nonlinear = Finding("nonlinearity", "note", why)
    else:
        delays, nk = _delays(centred)
        nonlinear = _nonlinearity(centred, nk)
    feedback = _feedback(centred)
    if feedback.verdict == "act" and nonlinear.verdict == "note":
        # check_feedback's documented limit: a nonlinear system's distortions, functions of
        # the input's past that a linear model leaves in its residuals, look like feedback
        feedback = Finding("feedback", "note", feedback.finding.split(": ")[0]
                           + ": closed loop, or the nonlinearity below (distortions a linear "
                           "model leaves in its residuals look like feedback)",
                           "if the record was taken in closed loop: " + feedback.action)
    return Advice([_offsets(data), _trends(data), excitation, feedback,
                   _periodic(data), _outliers(data), delays, nonlinear])
