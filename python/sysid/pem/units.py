"""The units of the prediction-error search: :func:`sysid.pem` searches on channels of unit
root mean square, so that its path, and the model it returns in the record's units, do not
depend on the units the inputs and outputs were recorded in.

The search's step and stopping tests are relative to the norm of the parameter vector, whose
``B`` entries carry the inverse of the inputs' units and ``C`` entries the outputs' units:
searched in the record's units, an input recorded 100 times smaller moved a held-out fit from
72.9 % to 73.0 %, and inputs and outputs in micro-units stopped the search at its cap in one
unit system and not the other. So every input is divided by its root mean square (``B`` and
``D`` columns multiplied by it; the state, and so ``x0``, unchanged), and every output by a
scale that leaves the criterion's minimiser where it was:

- ``weighting="noise"`` (the determinant ``det(E^T E / N)``, the errors weighed by the inverse
  of their covariance): each output by its own root mean square. The determinant of errors
  divided by ``s`` per output is ``det / prod(s^2)``: a constant factor, the same minimiser,
  and the re-estimated weighting absorbs the scales (``e^T W e`` does not change at all);
- ``weighting="output"``: each output by its own root mean square, which is the criterion's
  own definition (the sum of squares of each output relative to its scale);
- ``weighting="identity"`` (a plain sum of squares in the record's units): one common factor
  for all outputs, the root mean square over all of them, so that the criterion only changes
  by a constant (a per-output factor would change which output the fit favours).

:func:`sysid.pem` then balances the state basis (:func:`sysid.pem.pem._balance`) on these
unit-free matrices, maps the result back with :func:`sysid.subspace.scaling.rescaled`, and
reports its criterion (``info["pem"]["cost"]``, the progress callback's cost) in the record's
units (for ``"output"``, as before, of the errors relative to each output's scale). With a
``regularization`` (its ``R`` and nominal are the record's parameters) the search stays in
the record's units, only the outputs scaled for ``"output"``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..models.statespace import StateSpaceModel
from ..subspace.scaling import rescaled, safe_rms

__all__ = ["SearchUnits", "channel_rms", "search_units"]


def channel_rms(x: np.ndarray) -> np.ndarray:
    """Each column's root mean square, 1 for a column that is zero throughout (or not finite:
    the record's own checks name it).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.pem.units import channel_rms
    >>> channel_rms(np.array([[3.0, 0.0], [-3.0, 0.0]])).tolist()
    [3.0, 1.0]
    """
    rms = safe_rms(x, 0) if x.shape[0] else np.ones(x.shape[1])
    return np.where((rms > 0) & np.isfinite(rms), rms, 1.0)


@dataclass(frozen=True)
class SearchUnits:
    """The channel scales of a search: inputs divided by ``su``, outputs by ``sy``.

    Attributes
    ----------
    su, sy : ndarray
        Input and output scales (ones: the record's units).
    weighting : str
        The search's weighting (``"noise"``, ``"identity"`` or ``"output"``).
    """

    su: np.ndarray
    sy: np.ndarray
    weighting: str

    @property
    def cost_factor(self) -> float:
        """The search's criterion times this is the record's: ``prod(sy^2)`` for the
        determinant, the common ``s^2`` for the plain sum of squares, 1 for ``"output"``
        (its criterion is of the scaled errors)."""
        if self.weighting == "noise":
            return self.det_factor
        if self.weighting == "identity":
            return float(self.sy[0] ** 2)
        return 1.0

    @property
    def det_factor(self) -> float:
        """The determinant of the scaled errors' covariance times this is the record's."""
        return float(np.prod(self.sy ** 2))

    def data(self, data: IOData) -> IOData:
        """``data`` with every channel divided by its scale (``data`` itself when all are
        1)."""
        if np.all(self.su == 1.0) and np.all(self.sy == 1.0):
            return data
        kw = {"dt": data.dt, "input_names": data.input_names,
              "output_names": data.output_names}
        us = [u / self.su if u.shape[1] else u for u, _ in data.experiments]
        ys = [y / self.sy for _, y in data.experiments]
        return (IOData(u=us[0], y=ys[0], **kw) if len(us) == 1 else
                IOData(u=us, y=ys, **kw))

    def start(self, B: np.ndarray, C: np.ndarray, D: np.ndarray, K: np.ndarray | None
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
        """A start's ``B, C, D, K`` for the scaled channels (the inverse of
        :meth:`record_units`)."""
        su, sy = self.su[None, :], self.sy[:, None]
        return (B * su, C / sy, D * su / sy,
                None if K is None else K * self.sy[None, :])

    def record_units(self, model: StateSpaceModel) -> StateSpaceModel:
        """A model of the scaled channels in the record's units
        (:func:`sysid.subspace.scaling.rescaled`)."""
        return rescaled(model, self.su, self.sy)

    def report(self, res: dict[str, Any]) -> None:
        """The core's histories in ``res`` in the record's units, in place: ``history``
        (the criterion), ``loss_history`` (the determinant) and ``weighted_history`` (the
        plain sum of squares; ``N l / 2`` with the re-estimated weighting)."""
        f, fd = self.cost_factor, self.det_factor
        res["history"] = [float(c) * f for c in res["history"]]
        res["loss_history"] = [float(c) * fd for c in res["loss_history"]]
        if self.weighting == "identity":
            res["weighted_history"] = [float(c) * f for c in res["weighted_history"]]

    def progress(self, cb: Callable[..., Any] | None) -> Callable[..., Any] | None:
        """A progress callback given the criterion in the record's units."""
        f = self.cost_factor
        if cb is None or f == 1.0:
            return cb

        def scaled_cb(iteration: Any, cost: float, *rest: Any) -> Any:
            return cb(iteration, float(cost) * f, *rest)
        return scaled_cb

    def info(self) -> dict[str, list[float]]:
        """The scales for ``info["pem"]["channel_scaling"]``."""
        return {"input": self.su.tolist(), "output": self.sy.tolist()}


def search_units(data: IOData, weighting: str, scale: bool) -> SearchUnits:
    """The channel scales a search on ``data`` with ``weighting`` runs in (module docstring);
    ``scale=False`` (a regularised search): the record's units, but each output at unit root
    mean square for ``weighting="output"`` (the criterion's definition)."""
    u = np.vstack([e[0] for e in data.experiments])
    y = np.vstack([e[1] for e in data.experiments])
    ones_u, ones_y = np.ones(data.n_inputs), np.ones(data.n_outputs)
    if weighting == "output":
        sy = channel_rms(y)
    elif not scale:
        sy = ones_y
    elif weighting == "identity":
        sy = ones_y * channel_rms(y.reshape(-1, 1))[0]
    else:
        sy = channel_rms(y)
    su = channel_rms(u) if scale and data.n_inputs else ones_u
    return SearchUnits(su, sy, weighting)
