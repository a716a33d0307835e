"""Does a fitted nonlinear state-space model forget its initial state?

A linear model with stable poles does: two simulations of it on the same input from
different initial states approach each other at the rate of its slowest pole. A nonlinear
model need not: a polynomial or network state equation can have several stable equilibria
or orbits (attractors) for the same input, and which one the simulation follows depends on
where it started. A simulation-error fit only ever simulates each training experiment from
its start, so it can return such a model with a good training fit; started anywhere else (a
validation record, ``compare`` with an estimated initial state, the same record joined
mid-way) it may follow another attractor and miss the data by far more than its fit says.
Seen on a DaISy CD-player record: ``pnlss(data, 3, degree=2)`` fits its training record
from rest, but started from rest at the record's middle it settles on another orbit, 25
output standard deviations away, and validates at -2000 %.

:func:`check_memory` tests this on the training data themselves: each experiment is
simulated from rest twice, whole and from its middle; once the linear part's slowest mode has
decayed to 1 %, the two must agree (to :data:`MEMORY_TOLERANCE` of the output's standard
deviation). An experiment whose second half is shorter than that settling time (a short
record, a slow mode) is simulated repeated end to end, as long as both runs need to settle
and be compared over a half record (at most :data:`MAX_SAMPLES` samples): the question is
the same (do two starts on one input meet?), only the input is longer. A settling time
beyond that, or a linear part with a pole on or outside the unit circle, is not judged. When
the two runs do not agree, or the second diverges, a :class:`~sysid.StabilityWarning` says
so; ``info["memory"]`` records the differences and how often each experiment was repeated.
A search can walk into such a model late: :func:`latest_forgetting` finds the latest of its
iterates that passes, which ``pnlss`` returns (with a warning) when its last one does not.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from .._checks import user_stacklevel
from ..data.iodata import IOData
from ..errors import NumericalError, StabilityWarning
from .common import decay_samples

__all__ = ["MEMORY_TOLERANCE", "check_memory", "differences", "failing", "forgets",
           "latest_forgetting"]

#: The largest difference (a fraction of each output's standard deviation) between the two
#: simulations of an experiment after the settling time that still counts as forgotten.
#: Fading-memory fits measured at 1e-9 .. 0.01 (Bouc-Wen, F-16, pH's nlssest, a heat
#: exchanger); a DaISy CD-player PNLSS fit that followed another orbit at 25.
MEMORY_TOLERANCE = 0.1
#: The longest input (samples) the check simulates when it repeats a short experiment: two
#: simulations of this length cost milliseconds for a PNLSS model, a fraction of a second for
#: a neural one; a slower mode (a pole within about 2e-5 of the unit circle) is not judged.
MAX_SAMPLES = 200_000


def differences(model: Any, data: IOData, order: list[int] | None = None,
                quick: bool = False) -> tuple[list[float | None], list[int]]:
    """Per experiment of ``data``, the largest difference (a fraction of the output's
    standard deviation) between ``model``'s simulation of the whole experiment and its
    simulation from rest at the middle, after the settling time (``inf``: a run diverged;
    ``None``: too slow a pole to tell), and how many copies of the experiment's input were
    simulated; see :func:`check_memory`. ``order``: the experiments' indices in the order to
    check them; ``quick``: stop at the first that fails (the rest stay ``None``, 0), for a
    verdict alone.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.nlss.memory import differences
    >>> m = sysid.PNLSSModel([[0.5]], [[1.0]], [[1.0]], [[0.0]], [[-0.1]], np.zeros((1, 0)),
    ...                      zeta=[[0, 0]], eta=[])
    >>> u = np.random.default_rng(0).uniform(-1, 1, (400, 1))
    >>> d, repeats = differences(m, sysid.IOData(u, m.simulate(u)))
    >>> bool(d[0] < 1e-2), repeats   # the two runs meet (what is left after settling)
    (True, [1])
    """
    # samples for the slowest pole to decay to 1 % (what is left of the two runs' initial
    # difference, a few output standard deviations, is then well under the tolerance; an
    # unstable linear part never settles: it is warned about on its own)
    settle = decay_samples(model.linear(), 1e-2)
    exps = data.experiments
    diffs: list[float | None] = [None] * len(exps)
    repeats = [0] * len(exps)
    for k in range(len(exps)) if order is None else order:
        diffs[k], repeats[k] = _difference(model, exps[k][0], settle)
        if quick and diffs[k] is not None and diffs[k] > MEMORY_TOLERANCE:
            break  # the verdict is known: the experiments after stay unchecked (None, 0)
    return diffs, repeats


def _difference(model: Any, u: np.ndarray, settle: float) -> tuple[float | None, int]:
    """One experiment's entry of :func:`differences`: the difference and the copies of ``u``
    simulated (``None, 0``: too slow a pole to tell)."""
    n = u.shape[0]
    half = n // 2
    # the runs settle, then are compared over the second half's length (10 samples at
    # least): the record itself when long enough, else the record repeated end to end
    need = half + settle + max(n - half, 10)
    long_enough = n - half - settle >= 10
    if not long_enough and need > MAX_SAMPLES:  # too slow a pole (or an unstable one)
        return None, 0
    copies = 1 if long_enough else int(np.ceil(need / n))
    if copies > 1:
        u = np.tile(u, (copies, 1))[:int(need)]
    s = int(settle)
    with np.errstate(all="ignore"):
        try:  # (the whole run of a repeated input is longer than the record: it may diverge)
            whole = np.asarray(model.simulate(u))
            second = np.asarray(model.simulate(u[half:]))
        except NumericalError:
            return float("inf"), copies
    a, b = whole[half + s:], second[s:]
    ref = np.std(whole[s:], axis=0)
    d = np.sqrt(np.mean((a - b) ** 2, axis=0)) / np.where(ref > 0, ref, 1.0)
    return (float(np.max(d)) if np.all(np.isfinite(d)) else float("inf")), copies


def check_memory(model: Any, data: IOData, name: str,
                 measured: tuple[list[float | None], list[int]] | None = None) -> Any:
    """Warn when ``model``, started from rest at the middle of a training experiment, does not
    return to its own simulation of the whole experiment (see the module documentation).

    Parameters
    ----------
    model : model with ``simulate(u)`` (from rest) and ``linear()``
        A fitted nonlinear state-space model.
    data : IOData
        Its training data (engineering units).
    name : str
        The estimator, named in the warning.
    measured : tuple, optional
        :func:`differences` of ``model`` on ``data``, when already measured.

    Returns
    -------
    model
        The same model, ``info["memory"]`` set: ``"difference"``, per experiment the largest
        difference over the outputs (a fraction of the output's standard deviation; ``inf``
        when the second simulation diverged, ``None`` when the settling time is too long to
        tell), and ``"repeats"``, how many copies of each experiment's input were simulated
        (1: the record itself).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.nlss.memory import check_memory
    >>> m = sysid.PNLSSModel([[0.5]], [[1.0]], [[1.0]], [[0.0]], [[-0.1]], np.zeros((1, 0)),
    ...                      zeta=[[0, 0]], eta=[])
    >>> u = np.random.default_rng(0).uniform(-1, 1, (400, 1))
    >>> d = check_memory(m, sysid.IOData(u, m.simulate(u)), "pnlss").info["memory"]
    >>> bool(d["difference"][0] < d["tolerance"])   # it forgets: no warning
    True
    """
    diffs, repeats = differences(model, data) if measured is None else measured
    model.info["memory"] = {"difference": diffs, "tolerance": MEMORY_TOLERANCE,
                            "repeats": repeats}
    bad = [(k, diffs[k]) for k in failing(diffs)]
    if bad:
        k, d = max(bad, key=lambda kd: kd[1])
        where = f"experiment {k}" if len(diffs) > 1 else "the record"
        if repeats[k] > 1:  # too short for the runs to settle within it
            where += f", its input repeated {repeats[k]} times end to end,"
        what = ("diverges" if not np.isfinite(d) else
                f"stays {d:.3g} output standard deviations away from its simulation of the "
                "whole record")
        warnings.warn(
            f"{name} returned a model that does not forget its initial state: simulated from "
            f"rest at the middle of {where} and past its linear part's settling time, it "
            f"{what}."
            f" The model has another stable behaviour for the same input (a second "
            f"equilibrium or orbit), so its simulation of other data depends on where it "
            f"starts; check it with sysid.compare on validation data, and try a lower degree "
            f"or order, or fewer monomials", StabilityWarning, stacklevel=user_stacklevel())
    return model


def failing(diffs: list[float | None]) -> list[int]:
    """The experiments whose :func:`differences` ``diffs`` exceed the tolerance (one that
    cannot be judged counts as forgotten, as :func:`check_memory` does)."""
    return [k for k, d in enumerate(diffs) if d is not None and d > MEMORY_TOLERANCE]


def forgets(diffs: list[float | None]) -> bool:
    """Whether :func:`differences` ``diffs`` say the model forgets its initial state."""
    return not failing(diffs)


def latest_forgetting(build: Callable[[np.ndarray], Any], iterates: np.ndarray,
                      data: IOData, first: list[int] | None = None,
                      also: Callable[[Any], bool] | None = None
                      ) -> tuple[int, Any, tuple[list[float | None], list[int]]] | None:
    """The latest of a search's iterates whose model forgets its initial state (and passes
    ``also``, when given).

    Used when the search's last iterate does not: the iterates (rows of ``iterates``, in
    search order, the last one excluded by the caller) are checked from the end on a grid of
    about ten, then between the latest on the grid that forgets and the next one (which does
    not) by bisection, about fourteen checks of two simulations each in all. Whether an
    iterate forgets need not be monotone along the search; the one returned forgets, and no
    later grid point does.

    Parameters
    ----------
    build : callable
        The model of one row of ``iterates``.
    iterates : ndarray, shape (k, p)
        The iterates, earliest first.
    data : IOData
        The training data (engineering units), as for :func:`check_memory`.
    first : list of int, optional
        Experiments to check first (those the last iterate failed on): an iterate that fails
        there is judged without simulating the others.
    also : callable, optional
        A second test a model must pass (``also(model)`` true), judged after the memory
        check: ``pnlss``'s start-up check (:mod:`sysid.nlss.startup`).

    Returns
    -------
    (index, model, differences) or None
        The row found, its model and its :func:`differences`; ``None`` when no grid point
        forgets.

    Examples
    --------
    A first-order model ``x(t+1) = 0.5 x + u + s (0.75 x^3 - 0.25 x^5)`` whose nonlinear
    terms grow along a made-up "search" ``s = 0, 0.1, ..., 1``: at ``s = 1`` it has a second
    stable equilibrium (``x = sqrt(2)``), where a short input pulse leaves the whole
    record's simulation while the simulation from its middle rests at zero.

    >>> import numpy as np, sysid
    >>> from sysid.nlss.memory import latest_forgetting
    >>> u = np.zeros((400, 1)); u[:5] = 0.6
    >>> def build(th):
    ...     return sysid.PNLSSModel([[0.5]], [[1.0]], [[1.0]], [[0.0]],
    ...                             [[0.75 * th[0], -0.25 * th[0]]], np.zeros((1, 0)),
    ...                             zeta=[[0, 0, 0], [0, 0, 0, 0, 0]], eta=[])
    >>> its = np.linspace(0.0, 1.0, 11)[:, None]
    >>> k, m, d = latest_forgetting(build, its, sysid.IOData(u, build(its[0]).simulate(u)))
    >>> float(its[k, 0])
    0.9
    """
    rows = len(iterates)
    if rows == 0:
        return None
    stride = max(1, int(np.ceil(rows / 10)))
    grid = list(range(rows - 1, -1, -stride))
    if grid[-1] != 0:
        grid.append(0)
    first = list(first or [])
    order = first + [e for e in range(len(data.experiments)) if e not in first]
    found = None
    failed = None
    def passes(i: int) -> tuple[bool, Any, Any]:
        m = build(iterates[i])
        d = differences(m, data, order, quick=True)
        return forgets(d[0]) and (also is None or also(m)), m, d

    for i in grid:
        ok, m, d = passes(i)
        if ok:
            found = (i, m, d)
            break
        failed = i
    if found is None:
        return None
    lo, hi = found[0], failed  # lo passes, hi does not (None: lo is the last row)
    while hi is not None and hi - lo > 1:
        mid = (lo + hi) // 2
        ok, m, d = passes(mid)
        if ok:
            lo, found = mid, (mid, m, d)
        else:
            hi = mid
    return found
