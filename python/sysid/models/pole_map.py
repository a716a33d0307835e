"""A pole's continuous-time equivalent and its damping ratio: one rule for every table that
shows them (:func:`sysid.damp`, a model's ``summary()`` and notebook display,
:func:`sysid.modal_analysis`).

A discrete pole ``z`` maps to ``s = log(z) / dt`` (principal logarithm); ``z = 0`` (a pure
delay, infinitely fast) to ``s = -inf``, whose natural frequency is infinite and damping
1, as MATLAB's ``damp`` and python-control's ``damp`` report it. The damping ratio is
``-Re(s) / |s|``, and -1 at ``s = 0`` (an integrator, as MATLAB).

Examples
--------
>>> import numpy as np
>>> from sysid.models.pole_map import continuous_equivalent, damping_ratio
>>> s = continuous_equivalent(np.array([0.5, 0.0, 1.0]), 0.1)
>>> s
array([-6.93147181+0.j,        -inf+0.j,  0.        +0.j])
>>> damping_ratio(s)
array([ 1.,  1., -1.])
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["continuous_equivalent", "damping_ratio"]


def continuous_equivalent(poles: Any, dt: float | None) -> np.ndarray:
    """``s = log(z) / dt`` of discrete poles ``z`` (``dt > 0``; ``z = 0`` gives ``-inf``), or
    the poles themselves (a copy, complex) for a continuous model (``dt`` 0 or None)."""
    p = np.asarray(poles, dtype=complex)
    if not dt:
        return p.copy()
    nonzero = np.abs(p) > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(nonzero, np.log(np.where(nonzero, p, 1.0)) / dt, -np.inf)
    return s.astype(complex)


def damping_ratio(s: Any) -> np.ndarray:
    """``-Re(s) / |s|`` of continuous-time poles ``s``: 1 at ``s = -inf`` (``z = 0``), -1 at
    ``s = 0``."""
    s = np.asarray(s, dtype=complex)
    with np.errstate(divide="ignore", invalid="ignore"):
        wn = np.abs(s)
        zeta = np.where(wn > 0, -s.real / np.where(wn > 0, wn, 1.0), -1.0)
        return np.where(np.isinf(s.real), 1.0, zeta)
