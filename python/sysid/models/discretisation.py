"""Zero- and first-order-hold sampling of continuous dynamics, written once: the exponential
of one augmented matrix (and its Fréchet derivatives, for sensitivities) from the Rust core's
``expm_frechet`` (scaling and squaring; no LAPACK threads for these small matrices).

- ZOH: ``expm([[A, B], [0, 0]] dt) = [[Ad, G1], [0, I]]``, ``Bd = G1``.
- FOH: ``expm([[A dt, B dt, 0], [0, 0, I], [0, 0, 0]])`` holds ``Ad``, ``G1`` and ``G2``;
  ``Bd = G1 + (Ad - I) G2`` and ``Dd = D + C G2`` (see :mod:`sysid.models.continuous`).

Used by :mod:`sysid.models.continuous` (``c2d``, simulation of sampled data) and the grey-box
structures (:mod:`sysid.greybox.greybox`, :mod:`sysid.greybox.delays`).

Examples
--------
>>> import numpy as np
>>> from sysid.models.discretisation import expm, from_blocks, hold_blocks
>>> A, B, C, D = np.array([[-1.0]]), np.array([[1.0]]), np.array([[1.0]]), np.array([[0.0]])
>>> E, _ = expm(hold_blocks(A, B, 0.1, "zoh"))
>>> Ad, Bd, dD = from_blocks(E, C, D, 1, 1, "zoh")
>>> bool(np.isclose(Ad[0, 0], np.exp(-0.1)) and np.isclose(Bd[0, 0], 1 - np.exp(-0.1)))
True
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .. import _sysid

__all__ = ["expm", "from_blocks", "hold_blocks", "require_finite_sampling"]


def expm(M: np.ndarray, dirs: Sequence[np.ndarray] = ()) -> tuple[np.ndarray, list[np.ndarray]]:
    """``exp(M)`` and its Fréchet derivatives in the directions ``dirs``."""
    E, L = _sysid.expm_frechet(np.ascontiguousarray(M, dtype=float),
                               [np.ascontiguousarray(d, dtype=float) for d in dirs])
    return E, list(L)


def hold_blocks(A: np.ndarray, B: np.ndarray, dt: float, hold: str) -> np.ndarray:
    """The augmented matrix whose exponential samples ``(A, B)`` every ``dt`` under ``hold``."""
    n, m = B.shape
    if hold == "zoh":
        M = np.zeros((n + m, n + m))
        M[:n, :n], M[:n, n:] = A * dt, B * dt
        return M
    M = np.zeros((n + 2 * m, n + 2 * m))
    M[:n, :n], M[:n, n:n + m] = A * dt, B * dt
    M[n:n + m, n + m:] = np.eye(m)
    return M


def from_blocks(E: np.ndarray, C: np.ndarray, D: np.ndarray, n: int, m: int, hold: str
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Ad, Bd, Dd - D)`` from the exponential of :func:`hold_blocks`."""
    Ad = E[:n, :n]
    if hold == "zoh":
        return Ad, E[:n, n:n + m], np.zeros_like(D)
    G1, G2 = E[:n, n:n + m], E[:n, n + m:]
    return Ad, G1 + (Ad - np.eye(n)) @ G2, C @ G2


def require_finite_sampling(mats: Sequence[np.ndarray], poles: Any, dt: float) -> None:
    """Raises :class:`~sysid.NumericalError` (what a diverging simulation raises, so that
    :func:`sysid.compare` reports the model as diverged, fit ``-inf``) when the sampled
    matrices of a continuous model are not finite: ``exp(A dt)`` overflows for a pole with
    ``Re(s) dt`` above ~700, a model unstable within one sample.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.errors import NumericalError
    >>> try:
    ...     require_finite_sampling([np.array([[np.inf]])], np.array([2.7e7]), 1.0)
    ... except NumericalError as e:
    ...     print(str(e)[:59])
    sampling every dt = 1 s overflows: the continuous model has
    """
    if all(np.all(np.isfinite(m)) for m in mats):
        return
    from ..errors import NumericalError

    p = np.asarray(poles, complex).ravel()
    worst = p[np.argmax(p.real)] if p.size else complex("nan")
    raise NumericalError(
        f"sampling every dt = {dt:g} s overflows: the continuous model has a pole at s = "
        f"{worst:.3g} (Re(s) dt = {worst.real * dt:.3g}): it is unstable and its simulation "
        "diverges within one sample; use a smaller dt, or stabilise the model (feedback) "
        "before sampling it")

