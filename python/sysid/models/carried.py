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

from collections.abc import Callable
from typing import Any

__all__ = ["carry", "plain"]


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

