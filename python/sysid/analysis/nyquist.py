"""The Nyquist curve of a single-input single-output loop and its encirclements of -1.

``L(j omega)`` for ``omega`` from ``-inf`` to ``+inf`` (the negative half is the complex
conjugate of the positive one); the number of clockwise encirclements of ``-1`` is the winding
number of ``1 + L`` around the origin, from the unwrapped phase along the closed curve. By
Nyquist's criterion the closed loop ``L / (1 + L)`` has ``Z = N + P`` unstable poles, ``P``
the unstable open-loop poles (MATLAB's ``nyquist``; python-control's ``nyquist_response``).
Open-loop poles on the imaginary axis are passed on their right: the contour is shifted to
``Re s = 1e-3 omega_min`` (for a discrete loop, poles on the unit circle such as an
integrator's ``z = 1`` are passed outside, on the circle of radius ``e^(1e-3 omega_min dt)``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_int, check_elements
from ..errors import DataError

__all__ = ["nyquist", "NyquistResponse"]


class NyquistResponse:
    """The Nyquist curve (see :func:`nyquist`).

    Attributes
    ----------
    omega : ndarray
        Positive frequencies (rad/s) of :attr:`response`.
    response : ndarray
        ``L(j omega)`` (complex).
    encirclements : int
        Clockwise encirclements ``N`` of ``-1`` by the whole curve.
    open_loop_unstable : int
        Open-loop poles ``P`` in the right half plane (outside the unit circle).
    closed_loop_unstable : int
        ``N + P``: unstable closed-loop poles under unit negative feedback.
    """

    def __init__(self, omega: np.ndarray, response: np.ndarray, n: int, p: int) -> None:
        self.omega, self.response = omega, response
        self.encirclements, self.open_loop_unstable = n, p
        self.closed_loop_unstable = n + p

    def plot(self, ax: Any = None) -> Any:
        """The curve (solid for positive, dashed for negative frequencies) and ``-1``;
        returns the axis (matplotlib)."""
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots()
        g = self.response
        ax.plot(g.real, g.imag, "C0-", label="omega > 0")
        ax.plot(g.real, -g.imag, "C0--", label="omega < 0")
        ax.plot([-1], [0], "r+", markersize=12)
        ax.set_xlabel("real")
        ax.set_ylabel("imaginary")
        ax.set_title(f"Nyquist: N = {self.encirclements}, P = {self.open_loop_unstable}")
        ax.axis("equal")
        ax.legend()
        return ax

    def to_pandas(self) -> Any:
        """The curve: frequency (rad/s), real and imaginary parts, magnitude and phase
        (degrees)."""
        import pandas as pd

        g = np.asarray(self.response)
        return pd.DataFrame({"omega [rad/s]": self.omega, "real": g.real, "imag": g.imag,
                             "magnitude": np.abs(g), "phase [deg]": np.degrees(np.angle(g))})

    def summary(self) -> str:
        """The Nyquist criterion's numbers: ``N + P = Z`` and what it says."""
        z = self.closed_loop_unstable
        return (f"{self!r}\n  N + P = {self.encirclements} + {self.open_loop_unstable} = {z}: "
                + ("the closed loop under unit negative feedback is stable" if z == 0 else
                   f"{z} closed-loop pole(s) unstable under unit negative feedback"))

    def __repr__(self) -> str:
        return (f"NyquistResponse(encirclements={self.encirclements}, open-loop unstable="
                f"{self.open_loop_unstable}, closed-loop unstable={self.closed_loop_unstable})")


def nyquist(sys: Any, *, omega: Any = None, n_points: int = 20000) -> NyquistResponse:
    """Nyquist curve, encirclements of ``-1`` and the closed-loop stability they imply.

    Parameters
    ----------
    sys : model
        Single-input single-output open loop (continuous or discrete; delays included).
    omega : array_like, optional
        Positive frequencies; default a logarithmic grid spanning the poles and zeros.
    n_points : int
        Size of the default grid (at least 2; below 100 the grid has 100 points).

    Examples
    --------
    >>> import sysid
    >>> r = sysid.nyquist(sysid.TransferFunction([10.0], [1.0, 3.0, 3.0, 1.0]))  # 10/(s+1)^3
    >>> r.encirclements, r.closed_loop_unstable
    (2, 2)
    """
    from .margin import _range, _siso

    n_points = as_int(n_points, "n_points", 2)
    # the curve and its mirror image: 2 complex values (4 floats) and 1 frequency a point
    check_elements(5 * n_points, f"n_points = {n_points}",
                   "pass fewer n_points (the default 20000 resolves the curve)")
    sys = _siso(sys, "nyquist")
    dt = float(getattr(sys, "dt", 0.0) or 0.0)
    p = np.asarray(sys.poles()) if hasattr(sys, "poles") else np.zeros(0)
    on_axis = np.abs(np.abs(p) - 1) < 1e-9 if dt > 0 else np.abs(p.real) < 1e-9
    P = int(np.sum(np.abs(p) > 1 + 1e-9)) if dt > 0 else int(np.sum(p.real > 1e-9))
    if omega is None:
        w = _range(sys, None)
        if hasattr(sys, "poles"):  # a model: a dense grid; an FRD: its measured lines
            w = np.geomspace(w[0], w[-1], max(int(n_points), 100))
    else:
        w = np.sort(np.asarray(omega, dtype=float).ravel())
        if w.size < 2 or np.any(w <= 0):
            raise DataError("omega must hold at least two positive frequencies")
    if np.any(on_axis):
        # the contour Re s = eps passes the poles on the axis on their right; through 0
        eps = 1e-3 * float(w[0])
        mid = np.linspace(-w[0], w[0], 401)[1:-1]
        full = _curve(sys, np.concatenate([-w[::-1], mid, w]), dt, eps)
        g = full[-w.size:]
    else:
        g = np.asarray(sys.freqresp(w))[:, 0, 0]
        full = np.concatenate([np.conj(g[::-1]), g])   # -inf .. +inf
    ang = np.unwrap(np.angle(1.0 + full))
    n = -int(np.round((ang[-1] - ang[0]) / (2 * np.pi)))
    return NyquistResponse(w, g, n, P)


def _curve(sys: Any, w: np.ndarray, dt: float, eps: float) -> np.ndarray:
    """``L`` on the contour, shifted by ``eps`` to the right of poles on the axis (outside
    poles on the unit circle: ``z = e^((eps + j omega) dt)``)."""
    from ..tf.model import TransferFunction

    if not isinstance(sys, TransferFunction):
        from ..tf.conversion import ss2tf

        sys = ss2tf(sys)  # the curve off the axis needs L at complex frequencies
    s = eps + 1j * w
    num, den = sys.num[0][0], sys.den[0][0]
    if dt > 0:
        z = np.exp(s * dt)
        return np.polyval(num, z) / np.polyval(den, z) * z ** (-sys.iodelay[0, 0])
    return np.polyval(num, s) / np.polyval(den, s) * np.exp(-s * sys.iodelay[0, 0])
