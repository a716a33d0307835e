"""What a predictor is given: the measured signals (or a record holding them) and the horizon.

One place for the arguments every model's ``predict(u, y, horizon)`` checks, so that
``model.predict(data, horizon=k)`` (MATLAB's ``predict(sys, data, K)``) works for every model.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import errors
from ._checks import as_2d
from .errors import DataError, ShapeError


def predict_args(u: Any, y: Any) -> tuple[Any, Any]:
    """The measured ``(u, y)`` a ``predict`` call was given: the arrays themselves, or a
    single-experiment record's signals when the record is passed in ``u``'s place and ``y``
    is left out (MATLAB's ``predict(sys, data, K)``). Shapes are checked by the caller.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid._measured import predict_args
    >>> data = sysid.IOData(u=np.zeros(5), y=np.ones(5), dt=1.0)
    >>> [a.shape for a in predict_args(data, None)]
    [(5, 1), (5, 1)]
    >>> predict_args(np.zeros(5), None)
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: predict needs the measured outputs y, or a record in u's place: ...
    """
    if errors.is_record(u):
        if y is not None:
            raise DataError("predict was given a record and y: pass the record alone "
                            "(model.predict(data, horizon=k)) or its signals "
                            "(model.predict(data.u, data.y, k))")
        n = u.n_experiments
        if n != 1:
            raise DataError(
                f"the record has {n} experiments and predict returns one array: predict "
                "each (model.predict(data.experiment(i), horizon=k) for i in range(n)), or "
                "compare all of them with sysid.compare(data, model, horizon=k)")
        return u.u, u.y
    if y is None:
        raise DataError("predict needs the measured outputs y, or a record in u's place: "
                        "model.predict(u, y, k) or model.predict(data, horizon=k)")
    return u, y


def record_dt(u: Any, dt: float | None) -> float | None:
    """``dt``, or the sample time of the record passed in ``u``'s place when ``dt`` is not
    given: what a continuous-time model's ``predict(data)`` samples at.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid._measured import record_dt
    >>> record_dt(sysid.IOData(u=np.zeros(3), y=np.ones(3), dt=0.5), None), record_dt(None, 2.0)
    (0.5, 2.0)
    """
    return u.dt if dt is None and errors.is_record(u) else dt


def as_horizon(horizon: Any) -> int | None:
    """A prediction horizon: a positive integer (an integral float too), or ``np.inf`` (the
    simulation), returned as ``None``.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid._measured import as_horizon
    >>> as_horizon(3), as_horizon(2.0), as_horizon(np.inf)
    (3, 2, None)
    """
    if isinstance(horizon, (float, np.floating)) and horizon == np.inf:
        return None
    if (isinstance(horizon, (bool, np.bool_)) or not isinstance(horizon, (int, np.integer,
                                                                          float, np.floating))
            or not np.isfinite(horizon) or int(horizon) != horizon or horizon < 1):
        raise DataError(f"horizon must be a positive integer (or np.inf for the simulation), "
                        f"got {horizon!r}")
    return int(horizon)


def as_measured(u: Any, y: Any, ninputs: int, noutputs: int) -> tuple[np.ndarray, np.ndarray]:
    """A predictor's measured ``(u, y)``: real, finite, ``(samples, ninputs)`` and
    ``(samples, noutputs)`` with one number of samples (``u=None`` for a model without
    inputs); the errors of :func:`as_2d`, naming the argument at fault.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid._measured import as_measured
    >>> as_measured(np.zeros(4), np.zeros(3), 1, 1)
    Traceback (most recent call last):
    ...
    sysid.errors.ShapeError: u has 4 samples but y has 3
    """
    y = as_2d(y, "y", ncols=noutputs)
    if u is None and ninputs == 0:
        return np.zeros((y.shape[0], 0)), y
    u = as_2d(u, "u", ncols=ninputs, allow_empty=ninputs == 0)
    if u.shape[0] != y.shape[0]:
        raise ShapeError(f"u has {u.shape[0]} samples but y has {y.shape[0]}")
    return u, y
