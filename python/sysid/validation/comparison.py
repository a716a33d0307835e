"""Several models compared on one record: ``sysid.compare(data, m1, m2, ...)`` (MATLAB's
``compare(z, m1, m2)``) returns a :class:`CompareSet`, one
:class:`~sysid.validation.compare.CompareResult` per model, with a table of their fits, the
best model, and one plot with the measured outputs and every model's. A model that diverges
on the record is in the table with a fit of ``-inf`` and flagged, not raised.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import DataError, is_frd, several_records_hint
from ..models.checks import inner_model

__all__ = ["CompareSet", "split_arguments"]


def _is_data(x: Any) -> bool:
    """A record, a ``(u, y)`` pair or frequency-response data (an FRD)."""
    return isinstance(x, IOData) or (isinstance(x, tuple) and len(x) == 2) or is_frd(x)


def _is_horizon(a: Any) -> bool:
    """An integer (not a bool) or ``inf`` in the models' place: MATLAB's prediction horizon
    ``K`` of ``compare(data, sys, K)``."""
    if isinstance(a, (bool, np.bool_)):
        return False
    return isinstance(a, (int, np.integer)) or (isinstance(a, float) and a == np.inf)


def split_arguments(args: tuple[Any, ...], horizon: Any) -> tuple[Any, list[Any], Any]:
    """``(data, models, horizon)`` from ``compare``'s positional arguments: ``data, m1, m2,
    ...[, horizon]`` (MATLAB's ``compare(data, sys, K)``) or ``model, data[, horizon]``."""
    if not args:
        raise DataError("compare needs data and at least one model: compare(data, m1, m2, ...)")
    if _is_data(args[0]):
        data, models = args[0], list(args[1:])
        if len(models) > 1 and _is_horizon(models[-1]):  # MATLAB's compare(data, m1, .., K)
            if horizon is not None:
                raise DataError("horizon given twice (positionally and by keyword)")
            horizon = models.pop()
    elif len(args) in (2, 3) and _is_data(args[1]):
        data, models = args[1], [args[0]]
        if len(args) == 3:
            if horizon is not None:
                raise DataError("horizon given twice (positionally and by keyword)")
            horizon = args[2]
    else:
        raise DataError(
            "compare takes compare(data, m1, m2, ...) or compare(model, data): data is a "
            "sysid.IOData, a pair (u, y) or a sysid.FRD, got "
            + ", ".join(type(a).__name__ for a in args) + several_records_hint(args[0]))
    if not models:
        raise DataError("compare needs at least one model after the data")
    models = [inner_model(m) for m in models]
    if any(_is_data(m) for m in models):
        if is_frd(data) or any(is_frd(m) for m in models):
            raise DataError("an FRD has no time response to compare with a record: compare "
                            "models with frequency-response data, compare(frd, m1, m2, ...), "
                            "or with a record, compare(data, m1, m2, ...)")
        raise DataError("compare takes one record: compare(data, m1, m2, ...)")
    return data, models, horizon


class CompareSet:
    """The comparison of several models with one record.

    Attributes
    ----------
    results : list of CompareResult
        One per model, in the order given.
    fit : ndarray
        ``(n_models, n_experiments, n_outputs)`` NRMSE fit in % (``-inf`` where a model
        diverged).
    diverged : ndarray of bool
        Per model: it diverged on some experiment.
    names : list of str
        A label per model (``info["method"]`` and order where known).
    """

    def __init__(self, results: list[Any]) -> None:
        self.results = results
        self.fit = np.array([r.fit for r in results])
        self.diverged = np.array([bool(r.diverged.any()) for r in results])
        self.names = [_label(r.model, k) for k, r in enumerate(results)]
        self.output_names = list(results[0].output_names)
        self.kind = results[0].kind

    def __len__(self) -> int:
        return len(self.results)

    def __getitem__(self, k: int) -> Any:
        return self.results[k]

    @property
    def mean_fit(self) -> np.ndarray:
        """Fit averaged over outputs and experiments, one per model (``-inf`` if diverged)."""
        return np.array([r.mean_fit for r in self.results])

    @property
    def best(self) -> int:
        """Index of the model with the highest mean fit."""
        return int(np.argmax(self.mean_fit))

    def to_pandas(self) -> Any:
        """One row per (model, experiment, output): fit, VAF, RMSE and divergence."""
        import pandas as pd

        frames = []
        for name, r in zip(self.names, self.results):
            df = r.to_pandas()
            df.insert(0, "model", name)
            frames.append(df)
        return pd.concat(frames, ignore_index=True)

    def summary(self) -> str:
        """A text table: one row per model, its fit per output, and divergence."""
        w = [max(10, min(24, len(n))) for n in self.output_names]
        head = f"{'model':<28}" + "".join(f" {n[:k]:>{k}}" for n, k in zip(self.output_names, w))
        lines = [f"{self.kind} fit % of {len(self)} models", head]
        for k, (name, r) in enumerate(zip(self.names, self.results)):
            fits = "".join(f" {f:{c}.2f}" for f, c in zip(r.fit.mean(axis=0), w))
            flag = "  diverged (unstable on this record)" if self.diverged[k] else ""
            best = "  best" if k == self.best else ""
            lines.append(f"{name[:28]:<28}{fits}{flag}{best}")
        flat = sorted({r.output_names[j] for r in self.results for _, j in r.flat})
        if flat:  # the measure is each result's (a model's operating point moves the level)
            many = len(flat) != 1
            lines.append(f"note: output{'s' * many} {', '.join(flat)} barely "
                         f"move{'' if many else 's'} on this record: the NRMSE fits there are "
                         "not a meaningful "
                         "measure (each result's .notes says why)")
        return "\n".join(lines)

    def plot(self, experiment: int = 0, fig: Any = None) -> Any:
        """Measured outputs and every model's (diverged ones listed, not drawn)."""
        from ..plot.validation import plot_compare_set

        return plot_compare_set(self, experiment=experiment, fig=fig)

    def __repr__(self) -> str:
        parts = ", ".join(f"{n}: {'diverged' if d else f'{f:.1f}'}"
                          for n, f, d in zip(self.names, self.mean_fit, self.diverged))
        return f"CompareSet({self.kind}, fit % [{parts}])"


def _label(model: Any, k: int) -> str:
    info = getattr(model, "info", None) or {}
    method = info.get("method") if isinstance(info, dict) else None
    order = getattr(model, "nstates", None)
    base = f"{k + 1}: {method or type(model).__name__}"
    return base + (f" (order {order})" if isinstance(order, (int, np.integer)) else "")


#: a pole counts as unstable in :func:`compare` when its mode grows by more than this factor
#: over the record compared (an integrator, or an estimate a hair outside the unit circle,
#: does not)
GROWTH = 10.0


def unstable_pole(model: Any, samples: int = 1, dt: float = 1.0) -> str | None:
    """A phrase naming ``model``'s most unstable pole, when its mode grows more than
    :data:`GROWTH` times over ``samples`` samples of ``dt`` seconds (modulus above 1 in
    discrete time, real part above 0 in continuous time), or ``None`` when it has none or
    no poles to read. A nonlinear model's poles are those of a linearisation (a NARX model's
    at zero, a nonlinear grey-box model's at a point): they say nothing of its simulation's
    growth (a NARX model ``y(t) = 1.2 y(t-1) - 0.2 y(t-1)^3 + u(t-1)`` has a pole at 1.2 and
    a bounded simulation), whose divergence, if any, shows in the simulation itself: None."""
    if callable(getattr(model, "linearize", None)) or hasattr(model, "narx"):
        return None
    try:
        p = np.asarray(model.poles(), dtype=complex).ravel()
    except Exception:  # noqa: BLE001 - no poles to read (a nonlinear model): divergence says
        return None
    p = p[np.isfinite(p)]
    if not p.size:
        return None
    if getattr(model, "dt", None):  # discrete time
        worst = p[np.argmax(np.abs(p))]
        if abs(worst) > 1.0 and samples * np.log(abs(worst)) > np.log(GROWTH):
            return f"a pole of modulus {abs(worst):.4g}"
        return None
    worst = p[np.argmax(p.real)]
    if worst.real > 0 and worst.real * samples * dt > np.log(GROWTH):
        return f"a pole at s = {worst.real:.4g}{worst.imag:+.4g}j (in the right half-plane)"
    return None


def warn_diverging(results: list[Any]) -> None:
    """One :class:`~sysid.StabilityWarning` per model of a :func:`~sysid.compare` that
    diverged on the record (fit ``-inf``, ``diverged`` set) or, simulated, is unstable (a
    mode that grows more than :data:`GROWTH` times over the record): its
    fit may hold only because the fitted initial state holds the unstable mode back on this
    record. Every model kind alike (a continuous model is read as given, not as sampled); a
    prediction (whose predictor may be stable) is warned about only when it diverged."""
    import warnings

    from .._checks import user_stacklevel
    from ..errors import StabilityWarning

    many = len(results) > 1
    for k, r in enumerate(results):
        model = getattr(r.model, "continuous", r.model)  # a continuous model, as sampled
        name = f"model {_label(model, k)}" if many else f"the {type(model).__name__}"
        samples = max((len(y) for y in r.y), default=1)
        pole = unstable_pole(model, samples, float(r.dt or 1.0)) if r.horizon is None else None
        if r.diverged.any():
            where = (f" on experiment(s) {np.flatnonzero(r.diverged).tolist()}"
                     if r.diverged.size > 1 else "")
            msg = (f"{name} diverged{where}: its output grew without bound (fit -inf, "
                   f"diverged flagged)" + (f"; it is unstable, {pole}" if pole else ""))
        elif pole:
            msg = (f"{name} is unstable ({pole}): its simulation grows without bound, on a "
                   "longer record or from another initial state if not on this one (a "
                   "fitted initial state can hold the unstable mode back), so its fit here "
                   "says little")
        else:
            continue
        warnings.warn(msg + "; re-estimate it with stability enforced (e.g. sysid.ssest(..., "
                      "enforce_stability=True)), or check the signs of its coefficients and "
                      "time constants", StabilityWarning, stacklevel=user_stacklevel())
