"""Recursive subspace identification: update the compressed factor chunk by chunk.

:class:`RecursiveSubspace` keeps the triangular factor ``R`` of the block-Hankel Gram matrix
``G = sum_t lambda^{age(t)} h(t) h(t)^T`` (exponential forgetting ``lambda``) and folds each
new chunk in by a blocked QR update in the Rust core, so the cost of an update depends on
the chunk and the horizon, never on how much data came before. After each update the
current model is the subspace fit on that factor (the same weighted SVD and least squares as
:class:`sysid.SubspaceEstimator`); without forgetting it equals the batch estimate on all
data so far, to round-off.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_dt, as_int
from ..errors import DataError, InsufficientDataError, ShapeError
from ..models.statespace import StateSpaceModel
from .feedthrough import check_feedthrough
from .streaming import as_chunk

__all__ = ["RecursiveSubspace"]


class RecursiveSubspace:
    """Subspace identification that follows the data, with optional forgetting.

    Parameters
    ----------
    order : int
        Model order fitted after each update.
    horizon : int
        Past and future horizon of the data matrix.
    forgetting : float
        ``lambda`` in (0, 1]: a column's weight decays by ``lambda`` per new column (memory
        about ``1 / (1 - lambda)`` samples); 1 keeps all data.
    method : str
        Weighting (``"moesp"``, ``"n4sid"``, ``"cva"``, ``"pbsid"``, ``"ssarx"``, ...).
    feedthrough, kalman : bool
        As in :meth:`sysid.SubspaceEstimator.fit` (``feedthrough`` default ``False``:
        ``D = 0``, as every sysid state-space estimator; ``"auto"`` is not taken, the data
        arrive after the choice).
    dt : float
        Sample time of the models.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> true = sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]])
    >>> u = rng.standard_normal(600)
    >>> y = true.simulate(u)
    >>> rs = sysid.RecursiveSubspace(order=1, horizon=4)
    >>> for k in range(0, 600, 200):
    ...     model = rs.update(u[k:k + 200], y[k:k + 200])
    >>> bool(abs(model.poles()[0] - 0.7) < 1e-9)
    True
    """

    def __init__(self, order: int, horizon: int, *, forgetting: float = 1.0,
                 method: str = "moesp", feedthrough: bool = False, kalman: bool = False,
                 dt: float = 1.0) -> None:
        from .estimator import _method

        self.order = as_int(order, "order", 1)
        self.horizon = as_int(horizon, "horizon", 2)
        forgetting = float(forgetting)
        if not 0.0 < forgetting <= 1.0:
            raise DataError(f"forgetting must lie in (0, 1], got {forgetting}")
        self.forgetting = forgetting
        self.method = _method(method)
        self.feedthrough = check_feedthrough(feedthrough, auto=False)
        self.kalman = bool(kalman)
        self.dt = as_dt(dt)
        self._rec: Any = None
        self.model: StateSpaceModel | None = None
        self.n_samples = 0

    def update(self, u: Any, y: Any) -> StateSpaceModel | None:
        """Fold a chunk in and return the current model (``None`` until the factor has more
        columns than rows, i.e. about ``2 horizon (m + l)`` samples).

        Parameters
        ----------
        u : array_like
            ``(samples, m)`` or 1-D; ``None`` or empty for output-only data.
        y : array_like
            ``(samples, l)`` or 1-D.
        """
        uu, yy = as_chunk(u, y, allow_empty=True)  # whole, before the first sizes the factor
        if self._rec is None:
            _refuse_transposed(uu, yy)
            self._rec = _sysid.RecursiveFactor(uu.shape[1], yy.shape[1], self.horizon,
                                               self.horizon, self.forgetting)
            self._m, self._l = uu.shape[1], yy.shape[1]
        elif uu.shape[1] != self._m or yy.shape[1] != self._l:
            flipped = (uu.shape[0] == self._m or self._m == 0) and yy.shape[0] == self._l
            raise ShapeError(
                f"this chunk has {uu.shape[1]} input(s) and {yy.shape[1]} output(s), the "
                f"estimator {self._m} and {self._l}: chunks must keep the channels of the "
                "first" + ("; it looks transposed (chunks are (samples, channels)): pass "
                           "u.T, y.T" if flipped else ""))
        self._rec.update(uu, yy)
        self.n_samples += yy.shape[0]
        k = 2 * self.horizon * (self._m + self._l)
        if self._rec.n_columns < k:
            return None
        self.model = self._fit()
        return self.model

    def _fit(self) -> StateSpaceModel:
        from .estimator import SubspaceEstimator

        est = SubspaceEstimator.from_factor(self._rec.factor(), dt=self.dt, method=self.method)
        model = est.fit(self.order, feedthrough=self.feedthrough, kalman=self.kalman)
        model.info.update({"recursive": True, "forgetting": self.forgetting,
                           "n_samples": self.n_samples,
                           "effective_columns": self._rec.effective_columns})
        return model

    @property
    def factor(self) -> Any:
        """The current :class:`~sysid._sysid.HankelFactor`."""
        if self._rec is None or self._rec.n_columns == 0:
            raise InsufficientDataError("no Hankel column yet: update with more samples")
        return self._rec.factor()

    def __repr__(self) -> str:
        return (f"RecursiveSubspace(order={self.order}, horizon={self.horizon}, "
                f"forgetting={self.forgetting}, method={self.method!r}, "
                f"{self.n_samples} samples)")


#: a first chunk with more channels than this and than samples is taken as transposed
_MAX_WIDE_CHANNELS = 16


def _refuse_transposed(u: np.ndarray, y: np.ndarray) -> None:
    """Refuse a first chunk that looks ``(channels, samples)``: more channels than samples
    and than :data:`_MAX_WIDE_CHANNELS` (it would size the estimator for them, and return
    ``None`` for want of samples)."""
    n, channels = y.shape[0], u.shape[1] + y.shape[1]
    if channels > max(n, _MAX_WIDE_CHANNELS):
        raise ShapeError(f"the first chunk has {u.shape[1]} input(s) and {y.shape[1]} "
                         f"output(s) but only {n} sample(s): it looks transposed (chunks are "
                         "(samples, channels)): pass u.T, y.T")
