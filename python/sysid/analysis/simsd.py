"""Simulation with the model's uncertainty (MATLAB's ``simsd``).

``simsd(model, u, n)`` simulates the estimate and ``n`` models drawn from the Gaussian
approximation of its parameter covariance (:meth:`ParameterUncertainty.sample`), and gives
the standard deviation of the simulated output at every sample: first order by default
(``J P J^T`` along the covariance's eigen-directions, :meth:`ParameterUncertainty.
scaled_jacobian`; only the diagonal is kept, never an ``N x N`` matrix), or the sample one of
Monte Carlo draws. ``noise=True`` adds to each drawn response a realisation of the model's
noise (its innovations through ``K`` or the noise polynomials, covariance ``noise_cov``), as
MATLAB's ``AddNoise``: the spread of what a new experiment would measure.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_int, check_elements, real_array
from .._display import HTMLResult
from ..errors import DataError
from ..models.uncertainty import require

__all__ = ["SimulationSpread", "simsd"]

_METHODS = ("linear", "monte-carlo")


class SimulationSpread(HTMLResult):
    """The estimate's simulation, ``n`` drawn models' simulations and the output's standard
    deviation per sample.

    Attributes
    ----------
    t : ndarray (N,)
    y : ndarray (N, n_outputs)
        The estimate's simulation.
    std : ndarray (N, n_outputs)
        Standard deviation of the simulated output (``method``; with ``noise``, the variance
        at each sample of the noise path started at rest added, as the samples draw it).
    samples : ndarray (n, N, n_outputs)
        The drawn models' responses (with a noise realisation each when ``noise``).
    method : str
    noise : bool
    """

    def __init__(self, t: np.ndarray, y: np.ndarray, std: np.ndarray, samples: np.ndarray,
                 method: str, noise: bool, output_names: list[str]) -> None:
        self.t, self.y, self.std, self.samples = t, y, std, samples
        self.method, self.noise, self.output_names = method, noise, output_names

    def to_pandas(self) -> Any:
        """One row per sample: time, then each output's simulation and standard deviation."""
        import pandas as pd

        cols: dict[str, Any] = {"t": self.t}
        for i, name in enumerate(self.output_names):
            cols[name] = self.y[:, i]
            cols[f"{name} std"] = self.std[:, i]
        return pd.DataFrame(cols)

    def summary(self) -> str:
        """Per output: the largest and the mean standard deviation against the response's."""
        lines = [repr(self)]
        for i, name in enumerate(self.output_names):
            lines.append(f"  {name}: std mean {np.mean(self.std[:, i]):.4g}, max "
                         f"{np.max(self.std[:, i]):.4g} (response std "
                         f"{np.std(self.y[:, i]):.4g})")
        return "\n".join(lines)

    def plot(self, ax: Any = None, confidence: float = 0.99) -> Any:
        """The drawn responses (thin), the estimate and its ``confidence`` band; one axis
        per output. Returns the axes."""
        import matplotlib.pyplot as plt
        from scipy import stats

        k = float(stats.norm.ppf(0.5 + confidence / 2))
        ny = self.y.shape[1]
        if ax is None:
            _, ax = plt.subplots(ny, 1, sharex=True, squeeze=False)
            ax = ax[:, 0]
        axes = np.atleast_1d(ax)
        for i in range(ny):
            a = axes[i]
            for s in self.samples:
                a.plot(self.t, s[:, i], color="0.7", lw=0.6)
            a.plot(self.t, self.y[:, i], color="C0", lw=1.2, label="estimate")
            a.fill_between(self.t, self.y[:, i] - k * self.std[:, i],
                           self.y[:, i] + k * self.std[:, i], color="C0", alpha=0.2,
                           label=f"{confidence:.0%} band")
            a.set_ylabel(self.output_names[i])
        axes[-1].set_xlabel("time")
        axes[0].legend(loc="best")
        return ax

    def __repr__(self) -> str:
        return (f"SimulationSpread({self.y.shape[0]} samples, {self.y.shape[1]} output(s), "
                f"{len(self.samples)} drawn models, std: {self.method}"
                + (", with noise)" if self.noise else ")"))


def _noise_path(model: Any, e: np.ndarray) -> np.ndarray:
    """The output the model's noise part makes from innovations ``e`` (zero input)."""
    ss = model.to_statespace() if hasattr(model, "to_statespace") else model
    K = getattr(ss, "K", None)
    if K is None:  # an output-error model: white measurement noise
        return e
    n, ny = ss.A.shape[0], ss.C.shape[0]
    from ..models.statespace import StateSpaceModel

    h = StateSpaceModel(ss.A, K, ss.C, np.eye(ny), dt=ss.dt)
    return np.asarray(h.simulate(e)).reshape(e.shape[0], ny) if n else e


def _noise_cov(model: Any) -> np.ndarray:
    cov = getattr(model, "noise_cov", None)
    var = getattr(model, "noise_variance", None)  # polynomial models: one per output
    if cov is None and var is not None:
        cov = np.diag(np.atleast_1d(np.asarray(var, dtype=float)).ravel())
    if cov is None:
        ss = model.to_statespace() if hasattr(model, "to_statespace") else None
        cov = getattr(ss, "noise_cov", None)
    if cov is None:
        raise DataError("noise=True needs the model's noise covariance (noise_cov), and this "
                        "model has none: estimate it from data (ssest, pem, a polynomial "
                        "estimator), or pass noise=False")
    return np.atleast_2d(np.asarray(cov, dtype=float))


def _noise_std(model: Any, L: np.ndarray, n_samples: int) -> np.ndarray:
    """Standard deviation at every sample, ``(n_samples, ny)``, of the noise path started at
    rest (as :func:`_noise_path` draws it): ``sum_{k <= t} g_k^2`` of its impulse response
    ``g`` for innovations of covariance ``L L^T``, growing to the stationary value."""
    ny = L.shape[0]
    var = np.zeros((n_samples, ny))
    for j in range(ny):
        e = np.zeros((n_samples, ny))
        e[0] = L[:, j]
        g = _noise_path(model, e)
        var += np.cumsum(g * g, axis=0)
    return np.sqrt(var)


def _sample_time(model: Any, dt: Any, record_dt: Any) -> float:
    """The sample time of the simulation: the model's (discrete), else ``dt`` or the
    record's (continuous), which must agree when both are given."""
    own = float(getattr(model, "dt", 1.0) or 0.0)
    given = None if dt is None else float(dt)
    if given is not None and not (np.isfinite(given) and given > 0):
        raise DataError(f"dt must be a positive sample time in seconds, got {dt!r}")
    if own > 0:
        return own
    if given is not None and record_dt is not None and abs(given - float(record_dt)) > 1e-12 * \
            given:
        raise DataError(f"dt = {given:g} s disagrees with the record's dt = "
                        f"{float(record_dt):g} s; pass one of them")
    step = given if given is not None else record_dt
    if step is None:
        raise DataError("this continuous-time model needs the sample time of u: pass dt= (or "
                        "u as an IOData, whose dt is used)")
    return float(step)


def simsd(
    model: Any,
    u: Any,
    n: int = 10,
    *,
    method: str = "linear",
    x0: Any = None,
    noise: bool = False,
    seed: Any = None,
    dt: float | None = None,
) -> SimulationSpread:
    """Simulate a model with its uncertainty (MATLAB's ``simsd``).

    Parameters
    ----------
    model : Model
        A model with a parameter covariance (``model.uncertainty``: from ``ssest``/``pem``,
        the polynomial estimators, ``greyest``, or a bootstrap subspace fit).
    u : array_like (N, n_inputs) or IOData
        The input (an :class:`~sysid.IOData`: its inputs).
    n : int
        Models drawn from ``N(theta, P)`` and simulated (MATLAB's ``N``, default 10; 0:
        the standard deviation only).
    method : {"linear", "monte-carlo"}
        The standard deviation: first order (default; ``2 p`` simulations for ``p``
        identifiable directions), or the sample one of the ``n`` drawn responses (take
        ``n`` in the hundreds).
    x0 : array_like, optional
        Initial state of every simulation (default zero).
    noise : bool
        Add a realisation of the model's noise to each drawn response, and its variance to
        ``std`` (MATLAB's ``AddNoise``). The noise model starts at rest, as the simulation
        does from its zero initial state (MATLAB's ``sim`` default): the variance added is
        that of the path at each sample, ``lambda`` at the first for an innovation model,
        growing to the stationary one over the noise model's settling time.
    seed : int or numpy.random.Generator, optional
    dt : float, optional
        Sample time of ``u`` for a continuous-time model (``tfest``, ``procest``, ``greyest``
        in continuous time); taken from ``u`` when it is an :class:`~sysid.IOData`.

    Returns
    -------
    SimulationSpread
        ``.y``, ``.std``, ``.samples``; ``.plot()``, ``.to_pandas()``, ``.summary()``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((400, 1))
    >>> true = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]])
    >>> y = true.simulate(u) + 0.1 * rng.standard_normal((400, 1))
    >>> m = sysid.oe(sysid.IOData(u, y, 1.0), 1, 1, 1)
    >>> s = sysid.simsd(m, np.ones((30, 1)), n=5, seed=1)
    >>> s
    SimulationSpread(30 samples, 1 output(s), 5 drawn models, std: linear)
    >>> bool(0 < s.std[-1, 0] < 0.1), s.samples.shape
    (True, (5, 30, 1))
    """
    if method not in _METHODS:
        raise DataError(f"method must be 'linear' or 'monte-carlo', got {method!r}")
    unc = require(model)
    record = hasattr(u, "u") and hasattr(u, "y")
    step = _sample_time(model, dt, getattr(u, "dt", None) if record else None)
    uu = real_array(u.u if record else u, "u")
    if uu.ndim == 1:
        uu = uu[:, None]
    if uu.ndim != 2 or uu.shape[1] != model.ninputs:
        raise DataError(f"u must be (samples, {model.ninputs}) for this model's "
                        f"{model.ninputs} input(s), got shape {np.shape(uu)}")
    if not np.all(np.isfinite(uu)):
        raise DataError("u holds NaN or infinite values: repair them (sysid.repair_nan) first")
    n = as_int(n, "n", 0)
    N, ny = uu.shape[0], model.noutputs
    check_elements((n + 1) * N * ny + N * ny * unc.n_parameters,
                   f"simsd of {N} samples with {n} drawn models and {unc.n_parameters} "
                   "parameters", "simulate a shorter input, or fewer models")
    rng = np.random.default_rng(seed)

    def sim(m: Any) -> np.ndarray:
        kw = {} if x0 is None else {"x0": x0}
        out = m.simulate(uu, dt=step, **kw) if continuous else m.simulate(uu, **kw)
        return np.asarray(out, dtype=float).reshape(N, ny)

    continuous = float(getattr(model, "dt", 1.0) or 0.0) == 0.0

    y = sim(model)
    draws = unc.sample(n, rng) if n else []
    samples = np.stack([sim(m) for m in draws]) if n else np.empty((0, N, ny))
    if method == "linear":
        _, G = unc.scaled_jacobian(lambda m: sim(m).ravel())
        var = np.sum(np.abs(G) ** 2, axis=1).reshape(N, ny)
    else:
        if n < 2:
            raise DataError("method='monte-carlo' needs n >= 2 drawn models (hundreds for a "
                            "stable estimate)")
        var = samples.var(axis=0, ddof=1)
    if noise:
        L = np.linalg.cholesky(_noise_cov(model) + 1e-300 * np.eye(ny))
        for k, m in enumerate(draws):
            samples[k] += _noise_path(m, rng.standard_normal((N, ny)) @ L.T)
        var = var + _noise_std(model, L, N) ** 2
    t = np.arange(N) * step
    return SimulationSpread(t, y, np.sqrt(var), samples, method, bool(noise),
                            list(model.output_names))
