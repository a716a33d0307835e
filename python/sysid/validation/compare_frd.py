"""Models against frequency-response data: ``sysid.compare(frd, m1, m2, ...)`` (MATLAB's
``compare`` with ``idfrd`` data).

Each model's response on the FRD's frequencies is compared with the measured one, per output
and input pair, by the NRMSE fit of the complex response over the frequencies,

    fit = 100 (1 - ||G - G_model|| / ||G - mean(G)||),

MATLAB's definition applied to the complex values (100 % is exact; below 0 worse than the
mean response). With the FRD's ``std`` the share of lines whose model response lies inside
the confidence band is reported too. A model has a frequency response whether or not it is
stable; one that is infinite on a line (a pole on the unit circle there) gets a fit of
``-inf``. A continuous model meets sampled data (an FRD with ``dt``) sampled with its hold,
as :func:`sysid.compare` meets a record. A nonlinear model is refused: its ``freqresp`` is
its linear part's, whose gain the nonlinearities share (pass ``model.linear()`` to compare
that part).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError
from ..models.checks import require_freqresp

__all__ = ["FRDCompareSet", "compare_frd"]


def _nrmse_fit(g: np.ndarray, gm: np.ndarray) -> np.ndarray:
    """Fit in % per (output, input) of ``gm`` against ``g``, both ``(n_freq, l, m)``."""
    if not np.all(np.isfinite(gm)):
        bad = ~np.all(np.isfinite(gm), axis=0)
        gm = np.where(np.isfinite(gm), gm, 0.0)
    else:
        bad = np.zeros(g.shape[1:], bool)
    num = np.linalg.norm(g - gm, axis=0)
    den = np.linalg.norm(g - g.mean(axis=0), axis=0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        fit = 100.0 * (1.0 - num / den)
    # a constant measured response: 100 % only for an exact model
    fit = np.where(den > 0, fit, np.where(num == 0, 100.0, -np.inf))
    return np.where(bad, -np.inf, fit)


def _on_lines(frd: Any, model: Any) -> np.ndarray:
    """``model``'s response on ``frd``'s lines: another FRD only on the same grid, a
    continuous model against sampled data (``frd.dt``) sampled with its hold first (the
    response such data measure, as :func:`sysid.compare` samples it for a record); inf where
    it cannot be sampled (unstable within one sample)."""
    from ..errors import NumericalError

    if frd.dt and getattr(model, "dt", None) == 0:
        for name in ("sampled", "c2d"):
            if hasattr(model, name):
                try:
                    model = getattr(model, name)(float(frd.dt))
                except NumericalError:
                    return np.full(frd.response.shape, np.inf + 0j)
                break
    return np.asarray(frd._other(model), dtype=complex)


class FRDCompareSet:
    """Models compared with frequency-response data (from :func:`sysid.compare` given an FRD).

    Attributes
    ----------
    frd : FRD
        The measured response.
    models : list
        The models, in the order given.
    names : list of str
        A label per model.
    responses : list of ndarray
        Each model's response on ``frd.omega``, ``(n_freq, n_outputs, n_inputs)``.
    fit : ndarray
        ``(n_models, n_outputs, n_inputs)`` NRMSE fit of the complex response in %.
    within_band : ndarray or None
        ``(n_models,)`` share of the entries inside the FRD's confidence band (with ``std``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> g = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]])
    >>> w = np.linspace(0.05, 3.0, 50)
    >>> frd = sysid.FRD(w, g.freqresp(w), dt=1.0)
    >>> c = sysid.compare(frd, g, sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]]))
    >>> c.fit[:, 0, 0].round(1).tolist(), c.best
    ([100.0, 68.9], 0)
    """

    def __init__(self, frd: Any, models: list[Any]) -> None:
        from .comparison import _label

        self.frd = frd
        self.models = models
        self.names = [_label(m, k) for k, m in enumerate(models)]
        self.responses = [_on_lines(frd, m) for m in models]
        self.fit = np.array([_nrmse_fit(frd.response, g) for g in self.responses])
        rad = frd.radius
        self.within_band = (None if rad is None else np.array(
            [float(np.mean(np.abs(g - frd.response) <= rad)) for g in self.responses]))
        self.output_names = list(frd.output_names)
        self.input_names = list(frd.input_names)

    def __len__(self) -> int:
        return len(self.models)

    @property
    def mean_fit(self) -> np.ndarray:
        """Fit averaged over the output/input pairs, one per model."""
        return self.fit.reshape(len(self.models), -1).mean(axis=1)

    @property
    def best(self) -> int:
        """Index of the model with the highest mean fit."""
        return int(np.argmax(self.mean_fit))

    def to_pandas(self) -> Any:
        """One row per (model, output, input): the fit and, with ``std``, the share of lines
        inside the band."""
        import pandas as pd

        rows = []
        for k, name in enumerate(self.names):
            for i, yo in enumerate(self.output_names):
                for j, ui in enumerate(self.input_names):
                    row = {"model": name, "output": yo, "input": ui,
                           "fit": float(self.fit[k, i, j])}
                    if self.within_band is not None:
                        row["within_band"] = float(self.within_band[k])
                    rows.append(row)
        return pd.DataFrame(rows)

    def summary(self) -> str:
        """A text table: one row per model, its fit per output/input pair."""
        pairs = [f"{u}->{y}" for y in self.output_names for u in self.input_names]
        w = [max(10, min(24, len(p))) for p in pairs]
        head = f"{'model':<28}" + "".join(f" {p[:k]:>{k}}" for p, k in zip(pairs, w))
        if self.within_band is not None:
            head += "  in band"
        lines = [f"frequency-response fit % of {len(self)} model(s) on "
                 f"{self.frd.omega.size} frequencies", head]
        for k, name in enumerate(self.names):
            fits = "".join(f" {f:{c}.2f}" for f, c in zip(self.fit[k].ravel(), w))
            band = "" if self.within_band is None else f"  {self.within_band[k]:7.1%}"
            best = "  best" if k == self.best else ""
            lines.append(f"{name[:28]:<28}{fits}{band}{best}")
        return "\n".join(lines)

    def plot(self, fig: Any = None) -> Any:
        """Bode plot of the data (with its band) and every model, labelled with its fit."""
        from ..models.frd import FRD
        from ..plot.frequency import plot_frd

        # the responses compared (a continuous model's sampled one), on the FRD's lines
        models = {f"{n} ({f:.1f} %)": FRD(self.frd.omega, g, dt=self.frd.dt)
                  for n, f, g in zip(self.names, self.mean_fit, self.responses)
                  if np.all(np.isfinite(g))}
        return plot_frd(self.frd, models=models, fig=fig)

    def __repr__(self) -> str:
        parts = ", ".join(f"{n}: {f:.1f}" for n, f in zip(self.names, self.mean_fit))
        return f"FRDCompareSet(frequency response, fit % [{parts}])"


def compare_frd(frd: Any, models: list[Any], horizon: Any, x0: Any) -> FRDCompareSet:
    """:func:`sysid.compare` with frequency-response data (internal: the dispatch)."""
    if horizon is not None:
        raise DataError("horizon= predicts a time record; frequency-response data are "
                        "compared by their response: leave horizon out")
    if not (isinstance(x0, str) and x0 == "estimate"):
        raise DataError("x0= is the initial state of a time record; frequency-response data "
                        "have none: leave x0 out")
    for k, m in enumerate(models):
        require_freqresp(m, "model" if len(models) == 1 else f"model {k + 1}")
        part = next((f for f in ("linear", "linearize") if callable(getattr(m, f, None))), None)
        if part is not None:  # its freqresp is a linear part's, whose gain it shares
            raise DataError(f"model {k + 1} ({type(m).__name__}) is nonlinear: its frequency "
                            f"response is its linear part's (model.{part}()), whose gain the "
                            "nonlinearities share; compare the model on a record, or pass "
                            f"model.{part}() to compare that part on purpose")
        shape = (getattr(m, "noutputs", None), getattr(m, "ninputs", None))
        if None not in shape and shape != (frd.n_outputs, frd.n_inputs):
            raise DataError(f"model {k + 1} has {shape[1]} input(s) and {shape[0]} output(s) "
                            f"but the FRD has {frd.n_inputs} and {frd.n_outputs}")
        dt = getattr(m, "dt", None)
        if dt and frd.dt and not np.isclose(float(dt), float(frd.dt), rtol=1e-9):
            raise DataError(f"model {k + 1} has sample time {dt} but the FRD {frd.dt}: "
                            "resample the model (sysid.d2c / sysid.c2d) or compare on the "
                            "FRD of its own sample time")
    return FRDCompareSet(frd, models)
