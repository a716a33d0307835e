"""The operating point of a Hammerstein-Wiener model: ``y = y0 + g(L f(u - u0))``.

A Hammerstein-Wiener model is simulated from rest (a zero state), and its linear start (OE,
or a subspace fit) has no constant term. On a record whose signals sit off zero (tank levels,
temperatures, a valve around half open) the linear block then starts far from where the
record runs, a transient as long as its slowest mode, and the start spends its fit on the
offset: on the cascaded-tanks benchmark (levels 2.6 standard deviations off zero) nlhw ended
at a 61.7 % training fit where the linear model had 75.1 %. So :func:`sysid.nlhw` and
:func:`sysid.nlhw_ss` fit the record about its means and keep them in the model
(``u_offset``, ``y_offset``), which adds them back when it simulates: the nonlinearities
then act on the deviations from the operating point.

``offsets="auto"`` (the default) does this when a channel's mean lies farther from zero
than its standard deviation (the operating point is farther off than the signal varies;
closer, the rest state is near it already) and every nonlinearity is a black box (a
``SigmoidNetwork`` or the identity): the others have parameters in the data's own units (a
saturation's or dead zone's levels, breakpoints, a polynomial about zero, a user function),
whose meaning the shift would change (and a noise-free record of such a system is then no
longer fitted exactly). ``True`` and ``False`` force it. The threshold was set before any
record was tried; measured (nlhw with sigmoid networks, benches/nonlinear_unshipped.py):
the cascaded tanks (levels 2.6 standard deviations off zero) test RMSE 1.218 -> 0.589, EMPS
(position 1.5 off) 0.0796 -> 0.0269; centred regardless, the Wiener-Hammerstein benchmark
(0.16 off) landed in a worse minimum (training sum of squares 20.4 -> 128).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError

__all__ = ["has_levels", "use_offsets", "record_means", "centred"]


def has_levels(nl: Any) -> bool:
    """Whether a nonlinearity's parameters are in the data's own units (everything but a
    sigmoid network and the identity).

    Examples
    --------
    >>> import sysid
    >>> from sysid.nonlinear.operating_point import has_levels
    >>> has_levels(sysid.SigmoidNetwork(3)), has_levels(sysid.Saturation())
    (False, True)
    """
    from .hw_model import Nonlinearity, SigmoidNetwork

    return not (isinstance(nl, SigmoidNetwork) or type(nl) is Nonlinearity)


def use_offsets(offsets: Any, nls: list[Any], exps: list[tuple[np.ndarray, np.ndarray]]
                ) -> bool:
    """Resolve ``offsets`` (``"auto"``, ``True`` or ``False``) for these nonlinearities and
    experiments (the module docstring has the rule)."""
    if isinstance(offsets, (bool, np.bool_)):
        return bool(offsets)
    if offsets != "auto":
        raise DataError(f"offsets must be 'auto', True or False, got {offsets!r}")
    if any(has_levels(nl) for nl in nls):
        return False
    z = np.hstack([np.concatenate([u for u, _ in exps]), np.concatenate([y for _, y in exps])])
    return bool(np.any(np.abs(z.mean(axis=0)) > z.std(axis=0)))


def record_means(exps: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """Per channel the means of the inputs and the outputs over every experiment."""
    u = np.concatenate([u for u, _ in exps])
    y = np.concatenate([y for _, y in exps])
    return u.mean(axis=0), y.mean(axis=0)


def centred(exps: list[tuple[np.ndarray, np.ndarray]], u0: np.ndarray, y0: np.ndarray
            ) -> list[tuple[np.ndarray, np.ndarray]]:
    """The experiments about ``(u0, y0)``."""
    return [(u - u0, y - y0) for u, y in exps]
