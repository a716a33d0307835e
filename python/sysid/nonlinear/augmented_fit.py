"""``augmented_fit``: a linear model (subspace or ARX) on inputs augmented by basis
functions of the inputs."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ..errors import DataError
from .augmented import AugmentedInputModel, augment_inputs

__all__ = ["augmented_fit"]


def augmented_fit(data: Any, functions: Sequence[Any], *, method: str = "n4sid",
                  order: int | None = None, na: Any = None, nb: Any = None,
                  nk: Any = 1) -> AugmentedInputModel:
    """Linear model on inputs augmented by basis functions (seed 001, section 5.2).

    Parameters
    ----------
    data : IOData
        Estimation record.
    functions : sequence of str or callable
        Basis functions applied to every input.
    method : "n4sid", "moesp", "cva" or "arx"
        The linear engine.
    order : int
        State order (subspace methods).
    na, nb, nk : int or array_like
        ARX orders (``method="arx"``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> u = rng.uniform(-1, 1, (500, 1)); y = np.zeros((500, 1))
    >>> for t in range(1, 500): y[t] = 0.6 * y[t - 1] + u[t - 1] + 0.5 * u[t - 1] ** 2
    >>> m = sysid.augmented_fit(sysid.IOData(u, y, 1.0), ["square"], method="arx",
    ...                         na=1, nb=1)
    >>> float(np.max(np.abs(m.simulate(u) - y))) < 1e-8
    True
    """
    aug = augment_inputs(data, functions)
    if method == "arx":
        from ..polynomial.arx import arx

        if na is None or nb is None:
            raise DataError("method='arx' needs na and nb")
        lin = arx(aug, na, nb, nk)
    elif method in ("n4sid", "moesp", "cva"):
        from ..subspace import shortcuts as subspace

        if order is None:
            raise DataError(f"method={method!r} needs the state order")
        lin = getattr(subspace, method)(aug, order)
    else:
        raise DataError(f"method must be 'n4sid', 'moesp', 'cva' or 'arx', got {method!r}")
    return AugmentedInputModel(lin, functions, data.n_inputs)
