"""What pre-processing removed from a record (:class:`Trend`), so that it can be added back."""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_2d
from ..errors import ShapeError

__all__ = ["Trend"]


class Trend:
    """What pre-processing removed from a record, so that it can be added back.

    Per channel, ``original = scale * processed + trend``, with the trend a value per sample
    of every experiment (offsets, lines, piecewise lines) and one scale per channel.
    Obtained from :attr:`IOData.trend`.

    Attributes
    ----------
    u_trend, y_trend : list of ndarray
        Per experiment, shaped like its ``u`` and ``y``.
    u_scale, y_scale : ndarray
        One factor per input and output channel.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.ones(4), y=np.full(4, 3.0))
    >>> tr = sysid.detrend(d, "mean").trend
    >>> tr.add_outputs(np.zeros((4, 1))).ravel()
    array([3., 3., 3., 3.])
    """

    def __init__(
        self,
        u_trend: list[np.ndarray],
        y_trend: list[np.ndarray],
        u_scale: np.ndarray,
        y_scale: np.ndarray,
    ) -> None:
        self.u_trend = u_trend
        self.y_trend = y_trend
        self.u_scale = u_scale
        self.y_scale = y_scale

    def add_outputs(self, y: Any, experiment: int = 0, start: int = 0) -> np.ndarray:
        """Map model outputs (in processed units) of one experiment back to original units.

        Parameters
        ----------
        y : array_like
            ``(n, n_outputs)``, e.g. a model's simulation of experiment ``experiment``.
        experiment : int
            Which experiment's trend to add.
        start : int
            Sample of the experiment where ``y`` begins.
        """
        arr = as_2d(y, "y", ncols=len(self.y_scale))
        tr = self.y_trend[experiment]
        if start < 0 or start + arr.shape[0] > tr.shape[0]:
            raise ShapeError(
                f"y covers samples {start}..{start + arr.shape[0] - 1} but experiment "
                f"{experiment} has {tr.shape[0]}"
            )
        return arr * self.y_scale + tr[start : start + arr.shape[0]]

    def add_inputs(self, u: Any, experiment: int = 0, start: int = 0) -> np.ndarray:
        """Map inputs in processed units back to original units (as :meth:`add_outputs`)."""
        arr = as_2d(u, "u", ncols=len(self.u_scale))
        tr = self.u_trend[experiment]
        if start < 0 or start + arr.shape[0] > tr.shape[0]:
            raise ShapeError(f"u does not fit inside experiment {experiment}")
        return arr * self.u_scale + tr[start : start + arr.shape[0]]

    def __repr__(self) -> str:
        return (
            f"Trend({len(self.y_trend)} experiment(s), input scale {np.round(self.u_scale, 6)}, "
            f"output scale {np.round(self.y_scale, 6)})"
        )
