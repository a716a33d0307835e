"""Auto and cross correlation of every channel pair, with confidence bounds.

The lag covariances ``R[tau] = (1/N) sum_t z(t + tau) z(t)^T`` are the core's lagged sums
over all experiments (no lag spans two); :func:`sysid.spa` smooths the same covariances with a lag
window.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import stats

from .. import _sysid
from .._checks import as_between, as_int
from ..data.iodata import IOData
from ..errors import DataError, InsufficientDataError
from .spectra import _names, _need_data, _need_varying, _z_scaled

__all__ = ["Correlation", "correlation"]


def _lag_covariances(
    zs: list[np.ndarray], max_lag: int, remove_mean: bool
) -> tuple[np.ndarray, int]:
    """``R[tau] = (1/N) sum_t z(t + tau) z(t)^T`` for tau = 0..max_lag, over experiments
    (the core's lagged sums, read in place)."""
    xs = [np.ascontiguousarray(z - z.mean(axis=0) if remove_mean else z, dtype=float)
          for z in zs]
    total = sum(x.shape[0] for x in xs)
    return _sysid.lagged_products(xs, int(max_lag)) / total, total


class Correlation:
    """Auto and cross correlation coefficients of every channel pair with confidence bounds.

    Attributes
    ----------
    lags : ndarray
        ``-max_lag .. max_lag`` (samples).
    values : ndarray
        ``(n_lags, nc, nc)``: ``values[k, a, b] = r_ab(lags[k])``, the correlation of
        ``z_a(t + tau)`` with ``z_b(t)`` normalised by ``sqrt(R_aa(0) R_bb(0))``.
    bound : float
        ``z_{(1+p)/2} / sqrt(N)``: under the hypothesis of white, mutually uncorrelated
        channels, a coefficient lies within +- bound with probability ``confidence``.
    names : list of str
    """

    def __init__(self, lags: np.ndarray, values: np.ndarray, bound: float, confidence: float,
                 names: list[str], dt: float) -> None:
        self.lags = lags
        self.values = values
        self.bound = bound
        self.confidence = confidence
        self.names = names
        self.dt = dt

    def pair(self, a: str, b: str) -> np.ndarray:
        """``r_ab(tau)`` for all lags."""
        for n in (a, b):
            if n not in self.names:
                raise DataError(f"no channel {n!r}; channels are {self.names}")
        return self.values[:, self.names.index(a), self.names.index(b)]

    def significant(self, a: str, b: str) -> np.ndarray:
        """Lags where ``|r_ab|`` exceeds the bound (auto-correlations: lag 0 excluded)."""
        r = self.pair(a, b)
        out = np.abs(r) > self.bound
        if a == b:
            out &= self.lags != 0
        return self.lags[out]

    def to_pandas(self) -> Any:
        """A long-format DataFrame: one row per lag and channel pair with ``lag``, ``time``
        (``lag * dt``, seconds), ``a``, ``b``, ``r`` (``r_ab(lag)``) and ``significant``
        (``|r| > bound``).

        Examples
        --------
        >>> import numpy as np, sysid
        >>> u = np.random.default_rng(0).standard_normal(500)
        >>> sysid.correlation(sysid.IOData(u, u), 3).to_pandas().shape
        (28, 6)
        """
        from ..data.formats import _pandas

        nl, nc, _ = self.values.shape
        idx = np.indices((nl, nc, nc)).reshape(3, -1)
        names = np.array(self.names, dtype=object)
        r = self.values.reshape(-1)
        return _pandas().DataFrame({
            "lag": self.lags[idx[0]], "time": self.lags[idx[0]] * self.dt,
            "a": names[idx[1]], "b": names[idx[2]], "r": r,
            "significant": np.abs(r) > self.bound})

    def plot(self, a: str | None = None, b: str | None = None, *, ax: Any = None) -> Any:
        """Stem plot of ``r_ab`` with the confidence bounds; by default the last channel
        (the record's last output) against the first (its first input, when it has one;
        ``plot()`` raised a ``TypeError`` without the pair)."""
        from ..plot.data import plot_correlation

        return plot_correlation(self, self.names[-1] if a is None else a,
                                self.names[0] if b is None else b, ax=ax)

    def __repr__(self) -> str:
        return (f"Correlation: lags {self.lags[0]}..{self.lags[-1]}, channels {self.names}, "
                f"{self.confidence:.0%} bound +-{self.bound:.3g}")


def correlation(
    data: IOData, max_lag: int = 25, *, confidence: float = 0.99, remove_mean: bool = True
) -> Correlation:
    """Auto and cross correlations of all channels (inputs then outputs) up to ``max_lag``.

    A channel without variation (constant within every experiment, with ``remove_mean``;
    zero in every sample, without) has a correlation of 0 / 0 with any channel, undefined:
    such an input raises an :class:`~sysid.ExcitationError`, such an output a
    :class:`~sysid.DataError`, naming it (the coefficients were reported as 0).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = np.random.default_rng(0).standard_normal(2000)
    >>> y = np.concatenate([[0.0, 0.0, 0.0], u[:-3]])        # a pure delay of 3 samples
    >>> c = sysid.correlation(sysid.IOData(u=u, y=y), 10)
    >>> c.significant("y0", "u0").tolist()
    [3]
    """
    data = _need_data(data, inputs=False, who="correlation")
    L = as_int(max_lag, "max_lag", 0)
    if L >= min(data.lengths):
        raise InsufficientDataError(f"max_lag = {L} needs experiments longer than {L} samples")
    confidence = as_between(confidence, "confidence", 0.0, 1.0)
    _need_varying(data, "correlation", "correlation", centred=bool(remove_mean))
    # coefficients are unitless: channels near 1e300 (whose squares overflow) are scaled
    R, total = _lag_covariances(_z_scaled(data, per_channel=True)[0], L, remove_mean)
    d = np.sqrt(np.maximum(np.einsum("aa->a", R[0]), np.finfo(float).tiny))
    Rn = R / np.outer(d, d)[None]
    # negative lags: r_ab(-tau) = r_ba(tau)
    vals = np.concatenate([np.swapaxes(Rn[1:][::-1], 1, 2), Rn], axis=0)
    bound = float(stats.norm.ppf(0.5 + confidence / 2) / np.sqrt(total))
    return Correlation(np.arange(-L, L + 1), vals, bound, confidence, _names(data), data.dt)
