"""MATLAB's ``goodnessOfFit``: error norms of test data against reference data.

``goodness_of_fit(x, xref, cost)`` takes MATLAB's argument order (the test data first, the
reference second) and its cost functions, per channel (column), ``Ns`` samples:

- ``"MSE"``: ``||xref - x||^2 / Ns``,
- ``"NRMSE"``: ``||xref - x|| / ||xref - mean(xref)||``,
- ``"NMSE"``: ``||xref - x||^2 / ||xref - mean(xref)||^2``.

All are 0 for a perfect fit (MATLAB's current definitions, errors rather than fits):
``compare``'s fit percentage is ``100 (1 - NRMSE)``, :func:`sysid.fit_metrics` ``["fit"]``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_2d
from ..errors import DataError, ShapeError

__all__ = ["goodness_of_fit"]

_COSTS = ("MSE", "NRMSE", "NMSE")


def goodness_of_fit(x: Any, xref: Any, cost: str = "NRMSE") -> np.ndarray:
    """Error norm of the test data ``x`` against the reference ``xref`` per channel, as
    MATLAB's ``goodnessOfFit(x, xref, cost_func)`` (module docs).

    Parameters
    ----------
    x : array_like, (n_samples,) or (n_samples, n_channels)
        Test data (a model's output).
    xref : array_like, same shape
        Reference data (the measurements).
    cost : {"MSE", "NRMSE", "NMSE"}
        MATLAB's cost function (case-insensitive).

    Returns
    -------
    ndarray, (n_channels,)
        0 is a perfect fit; NRMSE and NMSE are 1 for ``x = mean(xref)`` and infinite for a
        constant reference channel that ``x`` misses (NaN where both are that constant).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> xref = np.array([0.0, 1.0, 2.0, 3.0])
    >>> sysid.goodness_of_fit(xref + 0.1, xref)          # NRMSE
    array([0.08944272])
    >>> 100 * (1 - sysid.goodness_of_fit(xref + 0.1, xref))   # compare's fit percentage
    array([91.05572809])
    >>> sysid.goodness_of_fit(xref + 0.1, xref, "MSE")
    array([0.01])
    """
    name = cost.upper() if isinstance(cost, str) else cost
    if name not in _COSTS:
        raise DataError(f"cost must be one of {', '.join(_COSTS)} (MATLAB's cost "
                        f"functions), got {cost!r}")
    xref = as_2d(xref, "xref")
    x = as_2d(x, "x", ncols=xref.shape[1])
    if x.shape != xref.shape:
        raise ShapeError(f"x has shape {x.shape} but xref has {xref.shape} (test data first, "
                         "reference second, as MATLAB's goodnessOfFit)")
    err = np.sum((xref - x) ** 2, axis=0)
    if name == "MSE":
        return err / xref.shape[0]
    dev = np.sum((xref - xref.mean(0)) ** 2, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        nmse = err / dev
    return np.sqrt(nmse) if name == "NRMSE" else nmse
