"""A model's parameter uncertainty carried into a model derived from it (a realisation, a
resampling, a conversion between forms).

The derived model's parameters are a function ``g(theta)`` of the estimate's. Its
uncertainty is the estimate's ``ParameterUncertainty(theta, P, build)`` seen through the
conversion, ``build'(theta) = convert(build(theta))`` (:meth:`ParameterUncertainty.through`):
every function ``f`` of the derived model then gets the first-order covariance
``J P J^T`` of ``J = d f(g(theta)) / d theta`` by the same central differences as on the
estimate, and a Monte Carlo draw is the conversion of a draw. A quantity the conversion
leaves unchanged (a pole, the DC gain, a frequency response point of an exact realisation)
therefore has the same standard deviation before and after it.

Examples
--------
>>> import numpy as np, sysid
>>> from sysid.models.carried import carry
>>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
>>> m.uncertainty = sysid.ParameterUncertainty(
...     [0.5], [[1e-4]], lambda t: sysid.StateSpaceModel([[t[0]]], [[1.0]], [[1.0]]))
>>> two = carry(m, sysid.d2d(m, 2.0), lambda d: sysid.d2d(d, 2.0))   # A^2
>>> round(float(two.poles(std=True)[1][0].real), 6)                     # 2 a std(a)
0.01
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from typing import Any

__all__ = ["carry", "carry_basis", "plain"]


def plain(m: Any) -> Any:
    """A draw without an uncertainty of its own (a conversion of it carries none: no chain
    of uncertainties through the draws).

    Examples
    --------
    >>> import sysid
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    >>> m.uncertainty = "set"
    >>> plain(m).uncertainty is None
    True
    """
    if getattr(m, "uncertainty", None) is not None:
        m.uncertainty = None
    return m


def carry(source: Any, derived: Any, convert: Callable[[Any], Any]) -> Any:
    """``derived`` (``convert(source)``) with ``source``'s parameter uncertainty seen through
    ``convert`` (none when ``source`` has none); returns ``derived``.

    Examples
    --------
    >>> import sysid
    >>> tf = sysid.TransferFunction([1.0], [1.0, -0.5], dt=1.0)
    >>> carry(tf, tf.to_statespace(), lambda m: m.to_statespace()).uncertainty is None
    True
    """
    unc = getattr(source, "uncertainty", None)
    if unc is not None:
        derived.uncertainty = unc.through(lambda m: convert(plain(m)))
    return derived


def carry_basis(source: Any, derived: Any, T: Any, T_inv: Any) -> Any:
    """``derived``, ``source`` in the state basis ``x = T x_new`` (``x_new = T_inv x``; a
    state-space model), with ``source``'s parameter uncertainty: each draw taken to the same
    basis (the nominal's ``T``: a fixed similarity, smooth in the parameters, where the
    canonical basis of each draw would reorder or flip its modes). Returns ``derived``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    >>> m.uncertainty = sysid.ParameterUncertainty(
    ...     [0.5], [[1e-4]], lambda t: sysid.StateSpaceModel([[t[0]]], [[1.0]], [[1.0]]))
    >>> T, Ti = np.array([[2.0]]), np.array([[0.5]])
    >>> out = carry_basis(m, sysid.StateSpaceModel([[0.5]], [[0.5]], [[2.0]]), T, Ti)
    >>> out.uncertainty.build(np.array([0.6])).B.tolist(), out.poles(std=True)[1].real
    ([[0.5]], array([0.01]))
    """
    import numpy as np

    T, T_inv = np.asarray(T, dtype=float), np.asarray(T_inv, dtype=float)

    def to_basis(m: Any) -> Any:
        new = copy.copy(derived)
        new.uncertainty = None
        A, B, C = (np.asarray(x, dtype=float) for x in (m.A, m.B, m.C))
        new.A, new.B, new.C, new.D = T_inv @ A @ T, T_inv @ B, C @ T, np.array(m.D, float)
        if getattr(derived, "K", None) is not None and getattr(m, "K", None) is not None:
            new.K = T_inv @ np.asarray(m.K, dtype=float)
        return new

    return carry(source, derived, to_basis)
