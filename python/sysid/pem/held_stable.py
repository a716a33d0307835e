"""Does the record insist on an unstable model where the simulation focus holds it stable?

``pem``/``ssest`` with ``focus="simulation"`` keep ``A`` stable: the focus promises a model
whose simulation follows the plant, and an unstable model's simulation grows without bound.
An unstable plant's record cannot be followed by such a model: its output grows, and the
stable model's simulation misses it by about its own size. Started from an unstable subspace
fit (its unstable poles reflected into the unit circle before the search), the search then
returned a stable model without saying so: on the warning audit's unstable plants (a real
pole at 1.01-1.03, outputs growing 1e5 to 6e8-fold over 800 samples) 14 of 40 such models
came without a StabilityWarning (7 without any warning; the five scored validate at -14 to
-5 %, where ``focus="prediction"`` validates at 100 %).

:func:`check_held_stable` says so. When the search's start was unstable, it compares the
refined stable model with the start as given on one simulation criterion (each output's
errors relative to its variance, every experiment's initial state fitted by least squares)
over each experiment's leading samples in which the start's fastest mode grows at most
:data:`GROWTH`-fold; the likelihood-ratio test of :func:`~sysid.pem.boundary.insists` (1 %
level) decides. The start is not refined: what a free search would reach fits at least as
well, so the statistic is a lower bound of the free fit's.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .._checks import user_stacklevel
from .._display import modulus
from ..errors import StabilityWarning
from ..models.statespace import StateSpaceModel
from ..validation.runner import fitted_simulation_errors
from .boundary import insists, spectral_radius

__all__ = ["GROWTH", "check_held_stable"]

#: The largest growth of the start's fastest mode over the samples compared: beyond it the
#: free responses' columns span more than the double precision of a least-squares fit keeps.
GROWTH = 1e8
#: Fewer samples than this many per state are not compared.
MIN_PER_STATE = 10


def check_held_stable(res: Any, start: StateSpaceModel, data: Any) -> dict[str, Any] | None:
    """After a simulation-focus search from the unstable ``start`` (as given, before its
    poles were reflected) ended at the stable model of ``res`` (the core's result: ``a``,
    ``b``, ``c``, ``d``; or a model), both in the units of the record ``data``
    (experiments of ``(u, y)``; the test does not depend on the channels' scales): a
    :class:`~sysid.StabilityWarning` when the record insists on an unstable model (see the
    module documentation). Returns the test (``info["pem"]["held_stable"]``), ``None`` when
    it is not made (a stable start).

    Examples
    --------
    An unstable plant's growing record, a stable model of it and the unstable start:

    >>> import warnings
    >>> import numpy as np, sysid
    >>> from sysid.pem.held_stable import check_held_stable
    >>> plant = sysid.StateSpaceModel([[1.02]], [[1.0]], [[1.0]], [[0.0]], dt=1.0)
    >>> u = np.random.default_rng(0).standard_normal((400, 1))
    >>> data = sysid.IOData(u, plant.simulate(u))
    >>> held = sysid.StateSpaceModel([[0.99]], [[1.0]], [[1.0]], [[0.0]], dt=1.0)
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     test = check_held_stable(held, plant, data)
    >>> test["insists"], w[0].category.__name__
    (True, 'StabilityWarning')
    """
    out = res if isinstance(res, StateSpaceModel) else StateSpaceModel(
        res["a"], res["b"], res["c"], res["d"], dt=start.dt)
    rho = spectral_radius(start.A)
    if rho < 1.0 or spectral_radius(out.A) >= 1.0:
        return None
    grow = np.inf if rho == 1.0 else np.log(GROWTH) / np.log(rho)
    exps = [(np.asarray(u, float), np.asarray(y, float)) for u, y in data.experiments]
    exps = [(u[:int(min(u.shape[0], grow))], y[:int(min(u.shape[0], grow))]) for u, y in exps]
    exps = [(u, y) for u, y in exps if u.shape[0] >= MIN_PER_STATE * max(out.nstates, 1)]
    if not exps:
        return None
    scale = np.std(np.vstack([y for _, y in exps]), axis=0)
    scale = np.where(scale > 0, scale, 1.0)

    def cost(m: StateSpaceModel) -> float:
        return sum(float(np.sum((fitted_simulation_errors(m, u, y) / scale) ** 2))
                   for u, y in exps)

    kept, free = cost(out), cost(start)
    n = sum(u.shape[0] for u, _ in exps)
    # an exact start (noise-free data): infinitely more likely
    lr, yes = insists(kept, free, n, out.noutputs) if free > 0 else (float("inf"), kept > 0)
    test = {"likelihood_ratio": lr, "insists": yes, "start_radius": rho, "samples": n,
            "error_ratio": float(np.sqrt(kept / free)) if free > 0 else float("inf")}
    if yes:
        warnings.warn(
            f"the simulation focus held the model stable (largest pole modulus "
            f"{modulus(spectral_radius(out.A))}), but the data insist on an unstable "
            f"one: the search's start as given (largest pole modulus {modulus(rho)}) "
            f"simulates the record's first {n} samples with errors {test['error_ratio']:.3g} "
            f"times smaller (initial states fitted; likelihood ratio {lr:.3g} > 6.63, the 1 % "
            f"level of chi-square(1)). If the plant is unstable, use focus='prediction' (it "
            f"keeps the predictor stable, not the model); if not, look for a drift or an "
            f"offset left in the data (sysid.detrend(data, 'linear') removes both)",
            StabilityWarning, stacklevel=user_stacklevel())
    return test
