"""The result of :func:`~sysid.validation.compare.compare` for one model:
:class:`CompareResult` (measured and model outputs, fit numbers, summary, plot)."""

from __future__ import annotations

from typing import Any

import numpy as np

from .._display import HTMLResult
from .fit import _metrics, diverged, flat_outputs, level_errors

__all__ = ["CompareResult"]


class CompareResult(HTMLResult):
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
    start : int
        Samples at the start of each experiment that the model's run copies rather than
        predicts (:func:`given_start`: a NARX model's first ``max_lag`` outputs, its initial
        condition; 0 for other models): kept in ``yhat``, left out of the fit numbers.
    fit, vaf, rmse : ndarray
        Shape ``(n_experiments, noutputs)`` over the samples after ``start``; see
        :func:`fit_metrics`.
    diverged : ndarray of bool
        Per experiment: the model's output diverged on it (not finite, or beyond ``1e8``
        times the measured range: an unstable model on a long record); its fit is ``-inf``
        and the comparison is reported, not raised.
    flat : list of (int, int)
        ``(experiment, output)`` pairs whose output barely moves on the record
        (:func:`~sysid.validation.fit.flat_outputs`: a step test's settled end): their
        NRMSE fit is not a meaningful measure; :attr:`notes` says why.
    levels : list of (int, int)
        ``(experiment, output)`` pairs (not flat) whose simulation error is mostly a constant
        level (:func:`~sysid.validation.fit.level_errors`): the fit measures the level the
        model puts the output at, not its response; :attr:`notes` says how large.
    notes : list of str
        What the fit numbers cannot say (shown by :meth:`summary`).
    """

    def __init__(self, model: Any, horizon: int | None, u: list[np.ndarray],
                 y: list[np.ndarray], yhat: list[np.ndarray], x0: list[Any],
                 start: int = 0) -> None:
        self.model, self.horizon = model, horizon
        self.u, self.y, self.yhat, self.x0 = u, y, yhat, x0
        self.start = int(start)
        #: start time of each experiment (the record's clock; ``None``: from 0)
        self.t0: list[float] | None = None
        self.output_names = list(model.output_names)
        self.dt = model.dt
        metrics = [_metrics(a[start:], b[start:]) for a, b in zip(y, yhat)]
        self.fit = np.array([d["fit"] for d in metrics])
        self.vaf = np.array([d["vaf"] for d in metrics])
        self.rmse = np.array([d["rmse"] for d in metrics])
        #: per experiment: the model's output diverged (not finite, or grew beyond 1e8 times
        #: the measured range); its fit is -inf
        self.diverged = np.array([diverged(a, b) for a, b in zip(y, yhat)])
        self.fit[self.diverged] = -np.inf
        self.flat: list[tuple[int, int]] = []
        self.notes: list[str] = []
        self._why: list[str] = []  # per flat output: its measure (flat_outputs)
        for e, (a, b) in enumerate(zip(u, y)):
            for j, why in flat_outputs(a[start:] if a is not None else None, b[start:]):
                self.add_flat(e, j, why)
        self.levels: list[tuple[int, int]] = []
        self.add_levels()

    def add_levels(self) -> None:
        """Note the outputs (not flat, not diverged) whose error is mostly a constant level
        (:func:`~sysid.validation.fit.level_errors`)."""
        for e, (a, b) in enumerate(zip(self.y, self.yhat)):
            if self.diverged[e]:
                continue
            where = f" in experiment {e}" if len(self.y) > 1 else ""
            for j, level, k, fit in level_errors(a[self.start:], b[self.start:]):
                if (e, j) in self.flat:
                    continue
                self.levels.append((e, j))
                self.notes.append(
                    f"output {self.output_names[j]}{where}: the error is mostly a constant "
                    f"level ({level:.3g}, {k:.1f} times the output's standard deviation on "
                    f"this record): the fit ({self.fit[e, j]:.1f} %) measures where the model "
                    f"puts the output's level; without that level it would be {fit:.1f} %. "
                    "Either the model's static gain is wrong at this record's input level, or "
                    "the level is not the input's doing (a sensor offset or drift that differs "
                    "between records: then judge the response by the fit without it)")

    def add_flat(self, e: int, j: int, why: str) -> None:
        """Record that output ``j`` of experiment ``e`` is flat (``why``: the measure)."""
        where = f" in experiment {e}" if len(self.y) > 1 else ""
        self.flat.append((e, j))
        self._why.append(why)
        self.notes.append(
            f"output {self.output_names[j]}{where}: the NRMSE fit ({self.fit[e, j]:.1f} %) is "
            f"not a meaningful measure on this record: {why}, so any error in the level is "
            "weighed against that small variation; validate on a segment where the output "
            f"changes (a step inside it), or judge by the RMSE ({self.rmse[e, j]:.3g})")

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
                             "VAF %": self.vaf[e, j], "RMSE": self.rmse[e, j],
                             "diverged": bool(self.diverged[e])})
        return pd.DataFrame(rows)

    def summary(self) -> str:
        """A text table of the fit numbers."""
        w = max([20] + [len(str(n)) for n in self.output_names])  # names whole
        lines = [f"{self.kind} of {self.model!r}",
                 f"{'exp':>4} {'output':<{w}} {'fit %':>9} {'VAF %':>9} {'RMSE':>11}"]
        for e in range(self.fit.shape[0]):
            for j, name in enumerate(self.output_names):
                lines.append(f"{e:>4} {name:<{w}} {self.fit[e, j]:9.2f} {self.vaf[e, j]:9.2f} "
                             f"{self.rmse[e, j]:11.4g}"
                             + ("  diverged (unstable on this record)" if self.diverged[e]
                                else "")
                             + ("  flat output: see the note" if (e, j) in self.flat else ""))
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)

    def plot(self, experiment: int = 0, fig: Any = None) -> Any:
        """Measured and model outputs over time, one axis per output; returns the figure."""
        from ..plot.validation import plot_compare

        return plot_compare(self, experiment=experiment, fig=fig)

    def __repr__(self) -> str:
        fits = ", ".join(f"{n}: {f:.1f}" for n, f in zip(self.output_names, self.fit.mean(0)))
        ne = len(self.y)
        div = ", diverged" if self.diverged.any() else ""
        flat = sorted({self.output_names[j] for _, j in self.flat})
        note = (f", fit not meaningful on flat output{'s' * (len(flat) != 1)} "
                f"{', '.join(flat)} (see .notes)") if flat else ""
        return (f"CompareResult({self.kind}, {ne} experiment{'s' * (ne != 1)}, fit % "
                f"[{fits}]{div}{note})")

