"""Instrumental variables with instruments the user gives (MATLAB's ``ivx``).

``A(q) y = B(q) u + v`` is solved from ``sum z(t) phi(t)^T theta = sum z(t) y(t)``, where the
regressor ``phi`` holds the lagged outputs and inputs and the instrument ``z`` the same lags
of the instrument signal ``x`` (in place of the outputs) and of the inputs. ``x`` must be
correlated with the outputs and not with their noise: a noise-free simulation of a prior
model, a measured signal upstream of the noise, the output of a parallel sensor. One IV solve
per output equation (``sysid_core::polynomial::iv::ivx_multi``); :func:`sysid.iv4` builds its
own instruments in four stages instead.

Examples
--------
>>> import numpy as np, sysid
>>> rng = np.random.default_rng(0)
>>> u = rng.standard_normal(2000)
>>> x = sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]]).simulate(u)   # noise free
>>> y = x + 0.3 * rng.standard_normal((2000, 1))
>>> m = sysid.ivx(sysid.IOData(u=u, y=y), 1, 1, 1, x=x)
>>> bool(abs(m.a[0][0][0] + 0.7) < 0.05)
True
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import _sysid
from ..errors import DataError
from .estimators import _iv_model, iv_setup
from .model import PolynomialModel

__all__ = ["ivx"]


def ivx(data: Any, na: Any, nb: Any = None, nk: Any = None, *, x: Any) -> PolynomialModel:
    """ARX by instrumental variables with given instruments ``x`` (MATLAB's ``ivx``).

    Parameters
    ----------
    data : IOData or (u, y)
    na, nb, nk : int or array_like
        As :func:`sysid.arx` (MATLAB's one vector ``[na nb nk]`` too).
    x : array_like or list of array_like
        The instrument signal, shaped as the outputs ``(samples, outputs)``; one array per
        experiment for a record of several.

    Returns
    -------
    PolynomialModel
        With the IV covariance ``lambda R^-1 S R^-T`` (``uncertainty``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = np.random.default_rng(1).standard_normal(500)
    >>> y = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]).simulate(u)
    >>> sysid.ivx((u, y), 1, 1, 1, x=y).a[0][0].round(8).tolist()
    [-0.5]
    """
    data, exps, (na_g, nb_g, nk_g) = iv_setup("ivx", data, na, nb, nk)
    xs = list(x) if isinstance(x, (list, tuple)) and len(exps) > 1 else [x]
    if len(xs) != len(exps):
        raise DataError(f"x: one instrument array per experiment ({len(exps)}), got {len(xs)}")
    arrays = []
    for xe, (_, y) in zip(xs, exps):
        a = np.asarray(xe, dtype=float)
        a = a.reshape(-1, 1) if a.ndim == 1 else a
        if a.shape != y.shape:
            raise DataError(f"x must be shaped as the outputs {y.shape} (samples, outputs), "
                            f"got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise DataError("x has non-finite values")
        arrays.append(np.ascontiguousarray(a))
    fits = _sysid.ivx([(u, y, None) for u, y in exps], arrays, na_g, nb_g, nk_g)
    return _iv_model(data, fits, na_g, nb_g, nk_g, "ivx", False)
