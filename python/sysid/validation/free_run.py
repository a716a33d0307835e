"""A one-step-ahead fit run free on its own estimation data.

``arx`` and ``nlarx`` fit their models one step ahead, where the measured outputs hold
them. Run on their own outputs (simulated, as ``compare`` and every simulation use them)
they can be far worse, even on the data they were fitted to: equation-error fits of
output-error data are biased. Measured: ``arx(data, 4, 4, 1)`` on the shipped F-16 levels
simulates its own estimation record at -94 to -166 % (level 1) and -21 to -69 % (level 3),
and ``nlarx(data, 3, 3, basis=PolynomialBasis(2))`` the flutter record at -1986 % and F-16
level 3 at -39 to -99 %, each without a word; their validation fits were as poor. On the
warning audit's 120 clean and closed-loop records (seed 55) one ``arx`` fit simulated its own
data below zero (-35 %, a 6-state plant under 25 dB output noise; validation -35 %).

The rule is that fit below zero: the simulation misses the output by more than the output
varies about its mean, so a constant would simulate it better. It says so; the model is
returned as fitted (its one-step predictions are what it was fitted for).
"""

from __future__ import annotations

import contextlib
import contextvars
import warnings
from collections.abc import Iterator
from typing import Any

import numpy as np

from .._checks import user_stacklevel
from ..errors import SysidWarning

__all__ = ["linear_free_run", "skipped", "warn_poor_simulation"]

_SKIP: contextvars.ContextVar[bool] = contextvars.ContextVar("sysid_free_run_skip",
                                                             default=False)


@contextlib.contextmanager
def skipped() -> Iterator[None]:
    """Within it, :func:`linear_free_run` does nothing: for fits made as a step of another
    method, whose simulation is not the user's model's (``arxstruc``'s rows, scored one step
    ahead; the quick ARX fits of ``advice`` and ``ssregest``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.free_run import linear_free_run, skipped
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], [[0.0]], dt=1.0)
    >>> m.info = {}
    >>> u = np.ones((50, 1))
    >>> with skipped():
    ...     linear_free_run(m, [(u, m.simulate(u))], "arx")
    >>> "free_run" in m.info
    False
    """
    token = _SKIP.set(True)
    try:
        yield
    finally:
        _SKIP.reset(token)


def warn_poor_simulation(method: str, fit: Any, names: list[str], advice: str) -> bool:
    """A :class:`~sysid.SysidWarning` when a one-step-ahead fit, run free on its own
    estimation data, simulates an output worse than that output's mean (NRMSE fit ``fit``,
    per output, below 0 %); ``advice`` says what to fit for simulation. True if it warned.

    Examples
    --------
    >>> import warnings
    >>> from sysid.validation.free_run import warn_poor_simulation
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     warn_poor_simulation("arx", [80.0, -23.0], ["y0", "y1"], "use sysid.oe")
    True
    >>> "y1 worse than its mean (fit -23.0 %)" in str(w[0].message)
    True
    """
    f = np.asarray(fit, float).ravel()
    bad = [i for i in range(f.size) if np.isfinite(f[i]) and f[i] < 0.0]
    if not bad:
        return False
    worst = min(bad, key=lambda i: f[i])
    more = f" (and {len(bad) - 1} more output(s))" if len(bad) > 1 else ""
    warnings.warn(
        f"{method}: run free on its own estimation data, the model simulates "
        f"{names[worst]} worse than its mean (fit {f[worst]:.1f} %){more}. It is fitted "
        f"one step ahead, where the measured outputs hold it; run on its own outputs "
        f"(compare, simulate) it is not held. Either the one-step fit is biased for "
        f"simulation (an equation-error fit of output-error data) or the output is mostly "
        f"a disturbance the input does not explain (a drift: integrate_noise=True or "
        f"sysid.detrend). {advice}", SysidWarning, stacklevel=user_stacklevel())
    return True


#: what a one-step-ahead linear fit's warning advises
LINEAR_ADVICE = ("For simulation fit sysid.oe or sysid.ssest(data, order, focus='simulation'), "
                 "which minimise the simulation error.")


def linear_free_run(model: Any, exps: list[tuple[np.ndarray, np.ndarray]], method: str,
                    advice: str = LINEAR_ADVICE) -> None:
    """For a stable linear one-step-ahead fit with inputs (``arx``): its simulation of each
    estimation experiment from the initial state that fits it best (least squares,
    :func:`sysid.validation.runner.fitted_simulation_errors`), the NRMSE fit per output
    pooled over the experiments in ``model.info["free_run"]``, and
    :func:`warn_poor_simulation` (``advice``: what to fit instead). The errors' mean is
    taken out (an offset left in the record has its own warning). An unstable model (its
    own warning), a time series, a model without states or a fit within :func:`skipped`
    is left alone.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.free_run import linear_free_run
    >>> u = np.random.default_rng(0).standard_normal((300, 1))
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], [[0.0]], dt=1.0)
    >>> m.info = {}
    >>> linear_free_run(m, [(u, m.simulate(u))], "arx", "")
    >>> np.round(m.info["free_run"]["fit"], 6).tolist()
    [100.0]
    """
    from ..pem.boundary import spectral_radius
    from .runner import fitted_simulation_errors

    if _SKIP.get() or not exps or exps[0][0].shape[1] == 0:
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ss = model.to_statespace() if hasattr(model, "to_statespace") else model
    A = np.asarray(ss.A, float)
    if ss.nstates == 0 or not np.all(np.isfinite(A)) or spectral_radius(A) >= 1.0:
        return
    sse, var = 0.0, 0.0
    for u, y in exps:
        e = fitted_simulation_errors(ss, u, y)
        # with the best constant added: an offset left in the record has its own warning
        sse = sse + np.sum((e - e.mean(axis=0)) ** 2, axis=0)
        var = var + np.sum((y - y.mean(axis=0)) ** 2, axis=0)
    fit = 100.0 * (1.0 - np.sqrt(sse / np.maximum(var, 1e-300)))
    if not np.all(np.isfinite(fit)):
        return
    model.info["free_run"] = {"fit": fit.tolist()}
    warn_poor_simulation(method, fit, list(model.output_names), advice)
