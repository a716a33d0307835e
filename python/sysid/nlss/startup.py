"""Does a fitted nonlinear state-space model start from rest as its data do?

A simulation-error fit leaves each experiment's first samples out of its cost (the transient:
one period of periodic data, else the linear start's settling time), because the state the
record starts in is unknown. What the model does over those samples is then not seen by the
fit: a nonlinear state equation can swing far from the data after a start from rest and join
the record's behaviour only later. Such a model fits its training record after the transient
but misses the first samples of every simulation from rest (validation data, ``compare``,
``simulate``) by far more than its fit says. Seen on a Wiener-Hammerstein record: over the last
25 of 50 iterations of a decoupled PNLSS fit the cost fell by 4 % while the model's error over
the transient grew from 0.5 to 9 output standard deviations; simulated from rest on a test
input the model missed it by 3.1 standard deviations (root mean square), 0.13 after its first
500 samples.

:func:`excess` judges this on the training data. Each experiment is simulated from rest; its
error over the transient is set against what a start from rest explains there: the model's own
error after the transient, and the part of the linear start's error over the transient that
an initial state fitted to the record removes (the record's unknown initial state: the
linear start, too, starts from rest). An experiment whose root-mean-square error over the
transient (per output, in the output's standard deviations) exceeds :data:`STARTUP_FACTOR`
(3) times that allowance, and one output standard deviation (:data:`FLOOR`), fails.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..errors import NumericalError
from ..validation.runner import fitted_simulation_errors

__all__ = ["FLOOR", "MIN_WINDOW", "STARTUP_FACTOR", "StartUp", "excess", "failing", "initial_part"]

#: How many times the allowance (see the module documentation) an experiment's error over
#: the transient may reach: a gross swing, not a start-up a little off. On simulated Duffing
#: and Wiener-Hammerstein records (32 PNLSS fits of 50 iterations, coupled and decoupled, two
#: training amplitudes) the last iterates missed their transients by 0.06-0.6 output standard
#: deviations, except one that swings away: 8.8 and 5.5, 3.2 and 5.4 times what it allows. The
#: fold fits of EMPS's automatic degree (a position record, not shipped: an integrator whose
#: initial offset stays in the whole record) pass only because the linear start's part is
#: the one a fitted initial state removes; measured against its error after the transient
#: instead, they failed and the degree choice moved (``benches/results/nonlinear.md``).
STARTUP_FACTOR = 3.0
#: Transients shorter than this (samples) are not judged: too few errors to compare.
MIN_WINDOW = 10
#: An error over the transient within this many output standard deviations never fails: a
#: start-up within the record's own range is not a swing away from it (a model whose error
#: after the transient is tiny may still start up a little off).
FLOOR = 1.0


def _split_rms(e: np.ndarray, skip: int, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Root-mean-square errors over the first ``skip`` samples and after them, per output,
    in units of ``scale``."""
    w = np.sqrt(np.mean(e[:skip] ** 2, axis=0)) / scale
    a = np.sqrt(np.mean(e[skip:] ** 2, axis=0)) / scale
    return w, a


def _judged(u: np.ndarray, skip: int) -> bool:
    return skip >= MIN_WINDOW and u.shape[0] - skip >= MIN_WINDOW


def _scale(y: np.ndarray) -> np.ndarray:
    s = np.std(y, axis=0)
    return np.where(s > 0, s, 1.0)


def initial_part(linear: Any, experiments: list[tuple[np.ndarray, np.ndarray]],
                 skips: list[int]) -> list[np.ndarray | None]:
    """Per experiment and output, the squared part of the linear start's error over the
    transient (simulated from rest) that a fitted initial state removes (in squared output
    standard deviations): what the record's unknown initial state adds there. A fitted state
    rather than the error after the transient: an integrating plant's initial offset stays
    in the whole record.

    Parameters
    ----------
    linear : StateSpaceModel
        The fit's linear start, in the units of ``experiments``.
    experiments : list of (u, y)
        The training experiments.
    skips : list of int
        Each experiment's transient (samples).

    Returns
    -------
    list
        One array per experiment (``None``: a transient too short to judge).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.nlss.startup import initial_part
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]], [[0.0]], dt=1.0)
    >>> u = np.random.default_rng(0).standard_normal((500, 1))
    >>> y = m.simulate(u, x0=[20.0])   # the record starts away from rest
    >>> bool(initial_part(m, [(u, y)], [100])[0][0] > 0.5)
    True
    """
    out: list[np.ndarray | None] = []
    for (u, y), skip in zip(experiments, skips):
        if not _judged(u, skip):
            out.append(None)
            continue
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            ys = np.asarray(linear.simulate(u), float).reshape(y.shape)
        rest = y - ys
        fitted = fitted_simulation_errors(linear, u, y, ys)  # the state fitted over the record
        if not np.all(np.isfinite(fitted)):  # the linear start diverges: nothing explained
            out.append(np.zeros(y.shape[1]))
            continue
        scale = _scale(y)
        w_rest = _split_rms(rest, skip, scale)[0]
        w_fit = _split_rms(fitted, skip, scale)[0]
        out.append(np.maximum(w_rest ** 2 - w_fit ** 2, 0.0))
    return out


def excess(model: Any, experiments: list[tuple[np.ndarray, np.ndarray]], skips: list[int],
           initial: list[np.ndarray | None]) -> list[float | None]:
    """Per experiment, the model's root-mean-square error over the transient when simulated
    from rest, divided by what the start from rest allows there (:data:`STARTUP_FACTOR`
    times the allowance of the module documentation, at least :data:`FLOOR` output standard
    deviations); the largest over the outputs. Above 1 fails; ``inf``: the simulation
    diverged; ``None``: not judged (a short transient).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.nlss.startup import excess
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]], [[0.0]], dt=1.0)
    >>> u = np.random.default_rng(0).standard_normal((500, 1))
    >>> bool(excess(m, [(u, m.simulate(u))], [100], [np.zeros(1)])[0] < 1)
    True
    """
    out: list[float | None] = []
    for (u, y), skip, init in zip(experiments, skips, initial):
        if init is None or not _judged(u, skip):
            out.append(None)
            continue
        try:
            with np.errstate(all="ignore"):
                yh = np.asarray(model.simulate(u)).reshape(y.shape)
        except NumericalError:
            out.append(float("inf"))
            continue
        w, a = _split_rms(y - yh, skip, _scale(y))
        allow = np.maximum(STARTUP_FACTOR * np.sqrt(a ** 2 + init), FLOOR)
        r = w / allow
        out.append(float(np.max(r)) if np.all(np.isfinite(r)) else float("inf"))
    return out


def failing(ratios: list[float | None]) -> list[int]:
    """The experiments whose :func:`excess` ``ratios`` exceed 1."""
    return [k for k, r in enumerate(ratios) if r is not None and r > 1.0]


class StartUp:
    """The start-up check of one fit: its training experiments (the units its models
    simulate in), their transients and the linear start's initial-state parts
    (:func:`initial_part`).

    Examples
    --------
    A model whose constant terms (state 5, output -50) cancel once it has settled, but which
    starts from rest 50 away from its data (and its linear start):

    >>> import numpy as np, sysid
    >>> from sysid.nlss.startup import StartUp
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]], [[0.0]], dt=1.0)
    >>> u = np.random.default_rng(0).standard_normal((500, 1))
    >>> y = m.simulate(u)
    >>> swing = sysid.PNLSSModel([[0.9]], [[1.0]], [[1.0]], [[0.0]], [[5.0]], [[-50.0]],
    ...                          zeta=[[]], eta=[[]])
    >>> check = StartUp.of(m, [(u, y, 100)], sysid.IOData(u, y))
    >>> check.passes(m), check.passes(swing)
    (True, False)
    """

    def __init__(self, experiments: list[tuple[np.ndarray, np.ndarray]], skips: list[int],
                 initial: list[np.ndarray | None]) -> None:
        self.experiments, self.skips, self.initial = experiments, skips, initial

    @classmethod
    def of(cls, linear: Any, scaled: list[tuple[Any, ...]], data: Any) -> StartUp:
        """From the fit's linear start and its records ``(u, y, transient)`` (both in the
        search's scaled units) and the training data ``data`` (the returned models' units:
        the experiments of ``data`` are the records' in the same order)."""
        skips = [int(r[2]) for r in scaled]
        return cls(list(data.experiments), skips,
                   initial_part(linear, [(r[0], r[1]) for r in scaled], skips))

    def excess(self, model: Any) -> list[float | None]:
        """:func:`excess` of ``model`` on the training experiments."""
        return excess(model, self.experiments, self.skips, self.initial)

    def passes(self, model: Any) -> bool:
        """Whether ``model`` starts from rest within the allowance on every experiment."""
        return not failing(self.excess(model))

    def note(self, model: Any, ratios: list[float | None]) -> Any:
        """``model`` with ``info["startup"]`` set (the ratios, the factor, the transients)."""
        model.info["startup"] = {"excess": ratios, "factor": STARTUP_FACTOR,
                                 "transient": list(self.skips)}
        return model

    def describe(self, model: Any, ratios: list[float | None]) -> str:
        """How ``model`` misses the transient of its worst experiment, for a warning."""
        k = max(failing(ratios), key=lambda j: float(ratios[j] or 0.0))
        u, y = self.experiments[k]
        where = f"training experiment {k}" if len(self.experiments) > 1 else "its training record"
        try:
            with np.errstate(all="ignore"):
                e = y - np.asarray(model.simulate(u)).reshape(y.shape)
            w = float(np.max(_split_rms(e, self.skips[k], _scale(y))[0]))
        except NumericalError:
            w = float("inf")
        size = ("it diverges" if not np.isfinite(w) else
                f"it misses the data by {w:.3g} output standard deviations (root mean "
                f"square), {ratios[k]:.3g} times what a start from rest explains there")
        return (f"simulated from rest, over the first {self.skips[k]} samples of {where} "
                f"(left out of the cost as the transient) {size}")
