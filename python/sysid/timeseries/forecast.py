r"""Forecasts of time-series models with confidence bands.

Any model is put in innovation form ``x(t+1) = A x + B u + K e``, ``y = C x + D u + e``
(``cov e = Lambda``): a state-space model as it is, a polynomial time-series model
``y = C(q)/(A(q) D(q)) e`` through the realisation of ``H - 1``. The Kalman predictor runs
over the past record to ``xhat(N | N-1)``; the forecast ``j`` steps on is
``C A^j xhat`` (plus the response to given future inputs), with the error covariance of the
``j+1``-step predictor

.. math:: \Sigma_j = \sum_{i=0}^{j} M_i \Lambda M_i^T, \quad M_0 = I, \; M_i = C A^{i-1} K,

which grows from ``Lambda`` toward the covariance of the output. The bands are
``mean +- z sqrt(diag Sigma_j)`` for Gaussian innovations; parameter uncertainty is not
included (it is of order ``1/N`` against the innovations).

The predictor's initial state is estimated by default (MATLAB's ``forecastOptions``
``InitialCondition = 'e'``): with ``Ap = A - K C``, the one-step errors from rest are
``e_0(t) = e(t) + C Ap^t x0``, so ``x0`` is their weighted least-squares fit
(weight ``Lambda^{-1}``), with covariance ``P0 = (sum_t Ap^tT C^T Lambda^{-1} C Ap^t)^{-1}``.
Its error reaches the state after the record as ``Ap^N (x0_hat - x0)``, which adds
``C A^j Ap^N P0 Ap^NT A^jT C^T`` to ``Sigma_j`` (vanishing as the record outgrows the
predictor's memory). ``initial_condition="zero"`` starts from rest, as earlier versions
did, and its bands leave out the error of that start.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_2d, as_int, check_elements
from ..errors import DataError, InsufficientDataError, ShapeError
from ..models.trended import TrendedModel


class Forecast:
    """What :func:`forecast` returns.

    Attributes
    ----------
    t : ndarray (horizon,)
        Times of the forecast samples (continuing the past record's).
    mean : ndarray (horizon, noutputs)
        The forecast.
    std : ndarray (horizon, noutputs)
        Standard deviation of the forecast error.
    covariance : ndarray (horizon, noutputs, noutputs)
        Forecast error covariance per step.
    level : float
        Confidence level of :attr:`lower` / :attr:`upper`.
    """

    def __init__(self, t: np.ndarray, mean: np.ndarray, cov: np.ndarray, level: float,
                 output_names: list[str], past: np.ndarray, past_t: np.ndarray) -> None:
        from scipy.stats import norm

        self.t, self.mean, self.covariance, self.level = t, mean, cov, level
        self.std = np.sqrt(np.einsum("kii->ki", cov))
        self._z = float(norm.ppf(0.5 + level / 2))
        self.output_names, self._past, self._past_t = output_names, past, past_t

    @property
    def lower(self) -> np.ndarray:
        """Lower band ``mean - z std`` at :attr:`level`."""
        return self.mean - self._z * self.std

    @property
    def upper(self) -> np.ndarray:
        """Upper band ``mean + z std`` at :attr:`level`."""
        return self.mean + self._z * self.std

    def to_pandas(self) -> Any:
        """A DataFrame indexed by time: mean, std, lower, upper per output."""
        import pandas as pd

        cols = {}
        for i, n in enumerate(self.output_names):
            cols.update({f"{n}": self.mean[:, i], f"{n} std": self.std[:, i],
                         f"{n} lower": self.lower[:, i], f"{n} upper": self.upper[:, i]})
        return pd.DataFrame(cols, index=self.t)

    def plot(self, fig: Any = None, n_past: int = 200) -> Any:
        """The last ``n_past`` samples, the forecast and its band, one axis per output."""
        import matplotlib.pyplot as plt

        fig = fig or plt.figure()
        axes = np.atleast_1d(fig.subplots(len(self.output_names), 1, sharex=True, squeeze=False)
                             [:, 0])
        for i, ax in enumerate(axes):
            ax.plot(self._past_t[-n_past:], self._past[-n_past:, i], "k", lw=0.8, label="past")
            ax.plot(self.t, self.mean[:, i], "C0", label="forecast")
            ax.fill_between(self.t, self.lower[:, i], self.upper[:, i], color="C0", alpha=0.25,
                            label=f"{self.level:.0%} band")
            ax.set_ylabel(self.output_names[i])
        axes[0].legend(fontsize="small")
        axes[-1].set_xlabel("time")
        return fig

    def summary(self) -> str:
        """Per output: the first and last forecast with their bands."""
        lines = [repr(self)]
        for i, n in enumerate(self.output_names):
            for k in sorted({0, self.mean.shape[0] - 1}):
                lines.append(f"  {n} at t = {self.t[k]:.4g}: {self.mean[k, i]:.4g} "
                             f"[{self.lower[k, i]:.4g}, {self.upper[k, i]:.4g}]")
        return "\n".join(lines)

    def __repr__(self) -> str:
        return (f"Forecast({self.mean.shape[0]} steps, {self.mean.shape[1]} output(s), "
                f"{self.level:.0%} bands)")


def _innovation_form(model: Any) -> tuple[np.ndarray, ...]:
    """``(A, B, C, D, K, Lambda)`` of the model's innovation form."""
    from ..models.statespace import StateSpaceModel

    if isinstance(model, StateSpaceModel):
        n, l = model.A.shape[0], model.C.shape[0]
        K = model.K if model.K is not None else np.zeros((n, l))
        lam = model.noise_cov
        return model.A, model.B, model.C, model.D, K, (None if lam is None else
                                                       np.asarray(lam, float))
    from ..polynomial.model import PolynomialModel

    if not isinstance(model, PolynomialModel) or model.n_inputs != 0 or model.n_outputs != 1:
        conv = getattr(model, "to_statespace", None)
        ss = None
        if conv is not None and getattr(model, "statespace_is_exact", True):
            try:
                ss = conv()
            except DataError:
                ss = None
        if not isinstance(ss, StateSpaceModel):
            raise DataError(
                f"forecast needs a linear model with an innovations form (a StateSpaceModel, "
                f"a polynomial model, or a model whose to_statespace() gives one); "
                f"{type(model).__name__} has none: fit a linear model (ssest, n4sid, armax) "
                "to forecast")
        return _innovation_form(ss)
    num = np.r_[1.0, model.c[0]]
    den = np.convolve(np.r_[1.0, model.a[0][0]], np.r_[1.0, model.d[0]])
    n = max(num.size, den.size)
    num, den = np.pad(num, (0, n - num.size)), np.pad(den, (0, n - den.size))
    r = n - 1  # H = 1 + (num - den) / den: its strictly proper part in observer form
    A = np.zeros((r, r))
    A[:, 0] = -den[1:]
    A[: r - 1, 1:] = np.eye(r - 1)
    K = (num[1:] - den[1:]).reshape(r, 1)
    C = np.zeros((1, r))
    if r:
        C[0, 0] = 1.0
    lam = np.atleast_2d(float(np.asarray(model.noise_variance).ravel()[0]))
    return A, np.zeros((A.shape[0], 0)), C, np.zeros((1, 0)), K, lam


def _predictor_states(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
                      K: np.ndarray, u: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``xhat(t | t-1)`` for ``t = 0..N`` (from rest): the Kalman predictor
    ``x(t+1) = (A - K C) x + (B - K D) u + K y`` run by the Rust core, its output chosen as
    the next state."""
    from .. import _sysid

    n = A.shape[0]
    Ap = A - K @ C
    Bp = np.hstack([B - K @ D, K])
    if n == 0:
        return np.zeros((y.shape[0] + 1, 0))
    nxt = _sysid.simulate(np.ascontiguousarray(Ap), np.ascontiguousarray(Bp),
                          np.ascontiguousarray(Ap), np.ascontiguousarray(Bp),
                          np.ascontiguousarray(np.hstack([u, y])))
    return np.vstack([np.zeros((1, n)), np.asarray(nxt)])


def _initial_state(Ap: np.ndarray, C: np.ndarray, e0: np.ndarray,
                   lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(x0, P0)``: the predictor's initial state fitted to the one-step errors ``e0`` of
    the predictor from rest, ``e0(t) = e(t) + C Ap^t x0``, weighted by ``Lambda^{-1}``, and
    the covariance of that fit (module docs)."""
    from .. import _sysid

    N, l = e0.shape
    n = Ap.shape[0]
    c = np.ascontiguousarray
    w = np.linalg.cholesky(np.linalg.inv(lam + 1e-12 * np.trace(lam) / l * np.eye(l)))
    # normal equations summed block by block of samples (no (N l, n) regressor on long
    # records), until the free responses C Ap^t fall below round-off
    G, b = np.zeros((n, n)), np.zeros(n)
    M = np.eye(n)  # Ap^t0
    for t0 in range(0, N, _BLOCK):
        k = min(_BLOCK, N - t0)
        quiet = np.zeros((k, 0))
        # C Ap^(t0 + j) e_i for the block's samples j and every state direction i: (k, l, n)
        phi = np.stack([np.asarray(_sysid.simulate(c(Ap), np.zeros((n, 0)), c(C),
                                                   np.zeros((l, 0)), quiet, c(M[:, i])))
                        for i in range(n)], axis=2)
        Phi = np.einsum("ab,kbn->kan", w.T, phi).reshape(k * l, n)
        G += Phi.T @ Phi
        b += Phi.T @ (e0[t0:t0 + k] @ w).reshape(k * l)
        M = np.linalg.matrix_power(Ap, k) @ M
        if not np.all(np.isfinite(M)) or np.max(np.abs(M)) < 1e-17:
            break
    P0 = np.linalg.pinv(G, rcond=1e-12, hermitian=True)
    return P0 @ b, P0


#: samples per block of the initial state's normal equations
_BLOCK = 4096


def _free_response(Ap: np.ndarray, x0: np.ndarray, count: int) -> np.ndarray:
    """``Ap^t x0`` for ``t = 0..count-1``, ``(count, n)`` (the Rust core's recursion)."""
    from .. import _sysid

    n = Ap.shape[0]
    c = np.ascontiguousarray
    return np.asarray(_sysid.simulate(c(Ap), np.zeros((n, 0)), np.eye(n), np.zeros((n, 0)),
                                      np.zeros((count, 0)), c(x0))).reshape(count, n)


def _start_spread(A: np.ndarray, C: np.ndarray, S: np.ndarray, h: int) -> np.ndarray:
    """``C A^j S A^jT C^T`` for ``j = 0..h-1``: a state error of covariance ``S`` after the
    record, carried over the horizon."""
    from .. import _sysid

    n, l = A.shape[0], C.shape[0]
    c = np.ascontiguousarray
    G = np.stack([np.asarray(_sysid.simulate(c(A), np.zeros((n, 0)), c(C), np.zeros((l, 0)),
                                             np.zeros((h, 0)), c(np.eye(n)[i])))
                  for i in range(n)], axis=2)  # (h, l, n): C A^j e_i
    return np.einsum("kan,nm,kbm->kab", G, S, G)


def _propagate(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray, K: np.ndarray,
               lam: np.ndarray, x: np.ndarray, uf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The forecast's mean ``C x(j) + D u(j)`` from the state ``x`` after the record and its
    covariance ``Sigma_j = Lambda + sum_{k<j} M_k Lambda M_k^T``, ``M_k = C A^k K`` (the
    innovations' Markov parameters), for ``j = 0..h-1``: both recursions over the horizon run
    in the Rust core (:func:`sysid._sysid.simulate`; ``M_k`` column by column, the response
    to an initial state ``K e_i``), the sums accumulated in order."""
    from .. import _sysid

    h, n, l = uf.shape[0], A.shape[0], C.shape[0]
    c = np.ascontiguousarray
    if n == 0:
        mean = uf @ D.T
        markov = np.zeros((max(h - 1, 0), l, l))
    else:
        mean = np.asarray(_sysid.simulate(c(A), c(B), c(C), c(D), c(uf), c(x)))
        quiet = np.zeros((max(h - 1, 0), 0))
        cols = [np.asarray(_sysid.simulate(c(A), np.zeros((n, 0)), c(C), np.zeros((l, 0)),
                                           quiet, c(K[:, i]))) for i in range(l)]
        markov = np.stack(cols, axis=2) if h > 1 else np.zeros((0, l, l))
    steps = np.einsum("kab,bc,kdc->kad", markov, lam, markov)
    cov = np.empty((h, l, l))
    cov[0] = lam
    if h > 1:
        cov[1:] = lam + np.cumsum(steps, axis=0)
    return mean.reshape(h, l), cov


def forecast(model: Any, past: Any, horizon: int, *, future_inputs: Any = None,
             level: float = 0.95, initial_condition: str = "estimate") -> Forecast:
    """Forecast ``horizon`` samples beyond a record, with confidence bands
    (MATLAB's ``forecast``).

    Parameters
    ----------
    model : StateSpaceModel, PolynomialModel, TrendedModel or identify's model
        A model with a noise model: ``ar``/``arma`` results, or a state-space model in
        innovation form (``n4sid``/``ssest`` of time series or of input/output data). A
        :class:`~sysid.models.trended.TrendedModel` (``trend.attach(model)``) or the model
        of :func:`sysid.identify` forecasts raw data: the trend (offsets) is removed from
        the record and added back to the forecast at its own instants.
    past : IOData, (u, y) pair or array_like (n_samples, noutputs)
        The record the forecast continues (its last sample is the last one known). A model
        with inputs needs the past inputs too: an IOData or a pair ``(u, y)``. The forecast
        continues an IOData's clock (its start time and sample time); an array or a pair
        starts at ``t = 0`` with the model's sample time.
    horizon : int
        Number of samples to forecast.
    future_inputs : array_like (horizon, ninputs), optional
        Inputs over the forecast, for models with inputs.
    level : float
        Confidence level of the bands (default 0.95).
    initial_condition : {"estimate", "zero"}
        The predictor's state at the record's start: fitted to the record (default, as
        MATLAB's ``forecast``; its uncertainty widens the bands, module docs), or zero (from
        rest; the bands leave that start's error out).

    Returns
    -------
    Forecast
        ``t``, ``mean``, ``std``, ``covariance``, ``lower``/``upper``, ``plot()``,
        ``to_pandas()``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.PolynomialModel([[[-0.8]]], [[]], np.zeros((1, 0)), 1.0)
    >>> f = sysid.forecast(m, [0.0, 0.0, 1.0], 3)     # y(t) = 0.8 y(t-1) + e(t), var e = 1
    >>> f.mean[:, 0]
    array([0.8  , 0.64 , 0.512])
    >>> np.round(f.std[:, 0] ** 2, 4)                 # 1, 1 + 0.8^2, 1 + 0.8^2 + 0.8^4
    array([1.    , 1.64  , 2.0496])
    >>> f.t                                           # the samples after t = 0, 1, 2
    array([3., 4., 5.])
    """
    h = as_int(horizon, "horizon", 1)
    if initial_condition not in ("estimate", "zero"):
        raise DataError(f"initial_condition must be 'estimate' or 'zero' (MATLAB's 'e' and "
                        f"'z'), got {initial_condition!r}")
    if not (isinstance(level, (int, float)) and 0 < level < 1):
        raise DataError(f"level must be a number in (0, 1), e.g. 0.95; got {level!r}")
    inner, trend, offsets = _unwrap(model)
    A, B, C, D, K, lam = _innovation_form(inner)
    m, l = B.shape[1], C.shape[0]
    # per step: the time, mean, std, covariance and future inputs
    check_elements(h * (1 + 4 * l + l * l + m), f"forecast with horizon = {h}",
                   "forecast fewer steps (the forecast settles to the mean, and its band "
                   "to the output's spread, within a few time constants of the model)")
    u, y, t, dt = _past(model, past, l, m, h, future_inputs)
    if y.shape[0] < A.shape[0]:
        raise InsufficientDataError(
            f"the past holds {y.shape[0]} sample(s), fewer than the model's order "
            f"{A.shape[0]}: it does not determine the state the forecast starts from; give at "
            "least that many past samples (to forecast from rest, pad the past with zeros)")
    if m and future_inputs is None:
        raise DataError(f"the model has {m} input(s): give future_inputs of shape ({h}, {m})")
    uf = np.zeros((h, 0)) if not m else as_2d(future_inputs, "future_inputs", ncols=m)
    if uf.shape[0] != h:
        raise ShapeError(f"future_inputs has {uf.shape[0]} rows but horizon is {h}")
    y_raw, tf = y, t[-1] + dt * np.arange(1, h + 1)
    scale, add = np.ones(l), np.zeros((h, l))
    if trend is not None:  # on the trend's clock: the record's and the forecast's instants
        start, N = trend.start_of(t[0]), y.shape[0]
        u = (u - trend.values(N, "u", dt, start)) / trend.u_scale
        y = (y - trend.values(N, "y", dt, start)) / trend.y_scale
        uf = (uf - trend.values(h, "u", dt, start + N * dt)) / trend.u_scale
        scale, add = np.asarray(trend.y_scale, float), trend.values(h, "y", dt, start + N * dt)
    if offsets is not None:  # identify's model: the deviations about its operating point
        u, y, uf = u - offsets[0], y - offsets[1], uf - offsets[0]
        add = add + scale * offsets[1]
    xs = _predictor_states(A, B, C, D, K, u, y)
    e = y - xs[:-1] @ C.T - u @ D.T
    given = lam
    if lam is None:  # no stored innovation covariance: the sample one of the past
        lam = np.atleast_2d(e.T @ e / max(y.shape[0], 1))
    spread = None
    if initial_condition == "estimate" and A.shape[0]:
        Ap = A - K @ C
        x0, P0 = _initial_state(Ap, C, e, lam)
        xs = xs + _free_response(Ap, x0, xs.shape[0])  # Ap^t x0 added to the run from rest
        e = y - xs[:-1] @ C.T - u @ D.T
        carry = np.linalg.matrix_power(Ap, y.shape[0])  # x0's reach to the record's end
        if given is None:
            lam = np.atleast_2d(e.T @ e / max(y.shape[0], 1))
        spread = _start_spread(A, C, carry @ P0 @ carry.T, h)
    mean, cov = _propagate(A, B, C, D, K, lam, xs[-1], uf)
    if spread is not None:
        cov = cov + spread
    names = list(getattr(model, "output_names", [f"y{i}" for i in range(l)]))
    return Forecast(tf, mean * scale + add, cov * np.outer(scale, scale)[None], float(level),
                    names, y_raw, t)


def _unwrap(model: Any) -> tuple[Any, Any, tuple[np.ndarray, np.ndarray] | None]:
    """The linear model inside ``model``, the trend a :class:`TrendedModel` removes and
    the ``(u, y)`` offsets of identify's model (None where there are none)."""
    trend = offsets = None
    if isinstance(model, TrendedModel):
        model, trend = model.model, model.trend
    if hasattr(model, "remove_offsets") and hasattr(model, "statespace"):
        offsets = (np.asarray(model.u_offset, float).ravel(),
                   np.asarray(model.y_offset, float).ravel())
        model = model.statespace
    return model, trend, offsets


def _past(model: Any, past: Any, l: int, m: int, h: int,
          future_inputs: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """``(u, y, t, dt)`` of the past record: an IOData's own, or of an array or a ``(u, y)``
    pair from ``t = 0`` at the model's sample time."""
    from ..data.iodata import IOData

    if isinstance(past, IOData):
        if len(past.experiments) > 1:
            raise DataError("forecast continues one record: pass one experiment "
                            "(data.experiment(i)) as past")
        u, y, t, dt = past.u, past.y, past.time, float(past.dt)
    else:
        dt = float(getattr(model, "dt", 1.0) or 1.0)
        if (isinstance(past, tuple) and len(past) == 2
                and all(a is None or np.ndim(a) >= 1 for a in past)):
            u, y = past
        elif m:
            raise DataError(
                f"the model has {m} input(s): forecast needs the past inputs as well as the "
                "past outputs; pass past as a sysid.IOData or a pair (u, y)"
                + ("" if future_inputs is not None else
                   f", and give future_inputs of shape ({h}, {m})"))
        else:
            u, y = None, past
        y = as_2d(y, "past", ncols=l)
        t = dt * np.arange(y.shape[0])
    y = as_2d(y, "past", ncols=l)
    u = np.zeros((y.shape[0], 0)) if u is None else as_2d(u, "past inputs", ncols=m,
                                                            allow_empty=True)
    if u.shape[0] != y.shape[0]:
        raise ShapeError(f"the past inputs have {u.shape[0]} samples but the past outputs "
                         f"{y.shape[0]}")
    return u, y, np.asarray(t, float), dt
