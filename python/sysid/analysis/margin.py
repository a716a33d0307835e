"""Gain and phase margins of a single-input single-output loop (MATLAB's ``margin``).

With the open-loop response ``L(j omega)`` (any sysid model, delays included):

- phase crossovers ``omega_pc``: ``angle L = -180 deg (mod 360)``; the gain margin is
  ``1 / |L(j omega_pc)|`` (the factor by which the gain may grow before the loop is unstable);
- gain crossovers ``omega_gc``: ``|L| = 1``; the phase margin is ``180 deg + angle L``
  (wrapped to ``(-180, 180]``).

Crossovers are bracketed on a dense logarithmic grid and refined by Brent's method on the
exact response; with several, the reported margins are the smallest (MATLAB's convention:
the gain margin closest to 1 in decibels, the smallest phase margin). :meth:`Margins.all`
lists every crossover (``allmargin``). The default grid is widened, a decade at a time, past
an end where ``|L|`` still heads for 1 (a slow integral loop crosses far below its poles),
and the end points where ``L`` is real are checked too: ``omega = 0`` (a negative DC gain is a
phase crossover) and, discrete, the Nyquist frequency ``pi / dt``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.optimize import brentq

from ..errors import DataError

__all__ = ["margin", "Margins"]


class Margins:
    """Stability margins (see :func:`margin`).

    Attributes
    ----------
    gain_margin : float
        Absolute gain margin (``inf`` without phase crossover); ``gain_margin_db`` in dB.
    phase_margin : float
        Degrees (``inf`` without gain crossover).
    phase_crossover, gain_crossover : float
        The frequencies (rad/s) where they are read (``nan`` when absent).
    phase_crossovers, gain_crossovers : ndarray
        Every crossover found, with ``gain_margins`` and ``phase_margins``.
    """

    def __init__(self, wpc: np.ndarray, gms: np.ndarray, wgc: np.ndarray,
                 pms: np.ndarray) -> None:
        self.phase_crossovers, self.gain_margins = wpc, gms
        self.gain_crossovers, self.phase_margins = wgc, pms
        if gms.size:
            k = int(np.argmin(np.abs(np.log(gms))))
            self.gain_margin, self.phase_crossover = float(gms[k]), float(wpc[k])
        else:
            self.gain_margin, self.phase_crossover = float("inf"), float("nan")
        if pms.size:
            k = int(np.argmin(np.abs(pms)))
            self.phase_margin, self.gain_crossover = float(pms[k]), float(wgc[k])
        else:
            self.phase_margin, self.gain_crossover = float("inf"), float("nan")

    @property
    def gain_margin_db(self) -> float:
        """Gain margin in decibels."""
        return float(20 * np.log10(self.gain_margin)) if self.gain_margin > 0 else -np.inf

    def as_tuple(self) -> tuple[float, float, float, float]:
        """``(gm, pm, wcg, wcp)`` in MATLAB's order (``wcg`` the phase crossover)."""
        return self.gain_margin, self.phase_margin, self.phase_crossover, self.gain_crossover

    def to_pandas(self) -> Any:
        """Every crossover found: one row each, its kind (``"gain margin"`` at a phase
        crossover, ``"phase margin"`` at a gain crossover), frequency (rad/s) and margin.

        Examples
        --------
        >>> import sysid
        >>> m = sysid.margin(sysid.TransferFunction([1.0], [1.0, 2.0, 1.0, 0.0]))
        >>> m.to_pandas()["kind"].tolist()
        ['gain margin', 'phase margin']
        """
        import pandas as pd

        rows = [("gain margin", w, g, 20 * np.log10(g) if g > 0 else -np.inf, np.nan)
                for w, g in zip(self.phase_crossovers, self.gain_margins)]
        rows += [("phase margin", w, np.nan, np.nan, p)
                 for w, p in zip(self.gain_crossovers, self.phase_margins)]
        return pd.DataFrame(rows, columns=["kind", "frequency [rad/s]", "gain margin",
                                           "gain margin [dB]", "phase margin [deg]"])

    def summary(self) -> str:
        """The margins read (the smallest) and every crossover found.

        Examples
        --------
        >>> import sysid
        >>> print(sysid.margin(sysid.TransferFunction([1.0], [1.0, 2.0, 1.0, 0.0])).summary())
        Margins(gain=2 (6.02 dB) at 1 rad/s, phase=21.39 deg at 0.6823 rad/s)
          phase crossovers (rad/s): 1 (gain margin 2)
          gain crossovers (rad/s): 0.6823 (phase margin 21.39 deg)
        """
        def listed(ws: np.ndarray, vs: np.ndarray, fmt: str) -> str:
            return ", ".join(f"{w:.4g} ({fmt.format(v)})" for w, v in zip(ws, vs)) or "none"

        return "\n".join([
            repr(self),
            "  phase crossovers (rad/s): " + listed(self.phase_crossovers, self.gain_margins,
                                                    "gain margin {:.4g}"),
            "  gain crossovers (rad/s): " + listed(self.gain_crossovers, self.phase_margins,
                                                   "phase margin {:.4g} deg")])

    def __repr__(self) -> str:
        return (f"Margins(gain={self.gain_margin:.4g} ({self.gain_margin_db:.3g} dB) at "
                f"{self.phase_crossover:.4g} rad/s, phase={self.phase_margin:.4g} deg at "
                f"{self.gain_crossover:.4g} rad/s)")


def _siso(sys: Any, what: str = "margin") -> Any:
    if not hasattr(sys, "freqresp"):
        raise DataError(f"{what} needs a model with freqresp (a sysid model), got "
                        f"{type(sys).__name__}")
    if getattr(sys, "ninputs", 1) != 1 or getattr(sys, "noutputs", 1) != 1:
        raise DataError(f"{what} is defined for a single-input single-output loop; select one "
                        "pair: model[i, j] (output i from input j)")
    return sys


def _range(sys: Any, omega: Any) -> np.ndarray:
    if omega is not None:
        w = np.asarray(omega, dtype=float).ravel()
        if w.size < 2 or np.any(w <= 0) or not np.all(np.isfinite(w)):
            raise DataError("omega must hold at least two positive finite frequencies")
        return np.sort(w)
    measured = getattr(sys, "omega", None)
    if measured is not None and not hasattr(sys, "poles"):  # an FRD: its own frequencies
        w = np.asarray(measured, dtype=float).ravel()
        return np.sort(w[w > 0])
    dt = float(getattr(sys, "dt", 0.0) or 0.0)
    p = np.asarray(sys.poles()) if hasattr(sys, "poles") else np.zeros(0)
    if dt > 0:
        p = np.log(p[np.abs(p) > 0].astype(complex)) / dt
        top = np.pi / dt
    else:
        top = None
    mag = np.abs(p[np.abs(p) > 1e-12]) if p.size else np.ones(1)
    if mag.size == 0:
        mag = np.ones(1)
    lo = float(np.min(mag)) / 1000
    hi = float(np.max(mag)) * 1000 if top is None else top * (1 - 1e-9)
    delay = float(np.max(getattr(sys, "iodelay", 0.0), initial=0.0))
    n = 4000 + (int(50 * delay * hi) if top is None and delay > 0 else 0)
    return np.geomspace(min(lo, hi / 1e6), hi, min(n, 200000))


def margin(sys: Any, *, omega: Any = None) -> Margins:
    """Gain margin, phase margin and their crossover frequencies of an open loop.

    Parameters
    ----------
    sys : model
        Single-input single-output open loop (any sysid model: transfer function, state
        space, process model; continuous or discrete; delays included).
    omega : array_like, optional
        Frequency grid (rad/s) to search; default spans the poles by three decades each way
        (up to the Nyquist frequency for discrete models), widened while ``|L|`` heads for 1
        past an end, plus the end points ``omega = 0`` and (discrete) ``pi / dt``, where a
        negative real ``L`` is a phase crossover. A given grid is searched as it is.

    Returns
    -------
    Margins

    Examples
    --------
    >>> import sysid
    >>> m = sysid.margin(sysid.TransferFunction([4.0], [1.0, 3.0, 2.0, 0.0]))   # 4 / (s (s+1)(s+2))
    >>> round(m.gain_margin, 6), round(m.phase_crossover, 6)                    # 6/4 at sqrt 2
    (1.5, 1.414214)

    A negative DC gain is a phase crossover at ``omega = 0`` (the closed loop ``s + 1 - 2 k``
    of ``-2 / (s + 1)`` is unstable for ``k > 0.5``):

    >>> m = sysid.margin(sysid.TransferFunction([-2.0], [1.0, 1.0]))
    >>> m.gain_margin, m.phase_crossover
    (0.5, 0.0)
    """
    sys = _siso(sys)
    w = _range(sys, omega)
    parametric = omega is None and hasattr(sys, "poles")   # not an FRD's own lines
    dt = float(getattr(sys, "dt", 0.0) or 0.0)
    if parametric:
        w = _widen(sys, w, dt)

    def L(x: float) -> complex:
        return complex(np.asarray(sys.freqresp([x]))[0, 0, 0])

    g = np.asarray(sys.freqresp(w))[:, 0, 0]
    ph = np.unwrap(np.angle(g))
    # phase crossovers: (phase + pi) crosses a multiple of 2 pi
    k = (ph + np.pi) / (2 * np.pi)
    wpc = []
    for i in np.flatnonzero(np.floor(k[:-1]) != np.floor(k[1:])):
        target = np.floor(max(k[i], k[i + 1])) * 2 * np.pi - np.pi
        base = ph[i] - np.angle(g[i])          # the unwrapping offset at w[i]

        def f(x: float, t: float = target, b: float = base, i: int = i) -> float:
            a = np.angle(L(x)) + b
            # keep continuity with the grid's unwrapped phase
            a += 2 * np.pi * np.round((ph[i] - a) / (2 * np.pi))
            return a - t
        wpc.append(_root(f, w[i], w[i + 1]))
    d = np.abs(g) - 1.0
    wgc = [_root(lambda x: abs(L(x)) - 1.0, w[i], w[i + 1])
           for i in np.flatnonzero(d[:-1] * d[1:] < 0)]
    # |L| = 1 right on a grid point it crosses through (not at an end, where it may only touch)
    wgc += list(w[1:-1][(d[1:-1] == 0) & (d[:-2] * d[2:] < 0)])
    wgc.sort()
    wpc = [x for x in wpc if np.isfinite(x)]
    if parametric:   # the ends, where L is real: a phase crossover if it is negative there
        ends = [x for x in ([0.0] + ([np.pi / dt] if dt > 0 else []))
                if _negative_real(_at(sys, x))
                and not any(abs(y - x) <= 1e-9 * max(x, 1e-300) for y in wpc)]
        wpc = sorted(wpc + ends)
    wpc_a = np.array(wpc, dtype=float)
    wgc_a = np.array([x for x in wgc if np.isfinite(x)])
    gms = np.array([1.0 / abs(_at(sys, x)) for x in wpc_a])
    pms = np.array([(np.degrees(np.angle(L(x))) + 180.0 + 180.0) % 360.0 - 180.0
                    for x in wgc_a])
    return Margins(wpc_a, gms, wgc_a, pms)


def _at(sys: Any, x: float) -> complex:
    """``L(j x)``; a pole there (an integrator at ``x = 0``) gives a non-finite value."""
    with np.errstate(all="ignore"):
        return complex(np.asarray(sys.freqresp([x]))[0, 0, 0])


def _negative_real(v: complex) -> bool:
    return bool(np.isfinite(v) and v.real < 0 and abs(v.imag) <= 1e-9 * abs(v))


_DECADES = 60     # how far past the poles' span a gain crossover is looked for


def _widen(sys: Any, w: np.ndarray, dt: float) -> np.ndarray:
    """The default grid, extended past an end where ``|L|`` still heads for 1 (downwards; also
    upwards for a continuous loop) to a decade past where it has crossed; unchanged when
    ``|L|`` is flat there or moves away from 1 (no gain crossover out there)."""
    def reach(x: float, step: float) -> float:
        m = abs(_at(sys, x))
        for _ in range(_DECADES):
            y = x * step
            n = abs(_at(sys, y))
            if not (np.isfinite(m) and np.isfinite(n) and m > 0 and n > 0):
                break
            if (m - 1.0) * (n - 1.0) <= 0:
                return y * step      # a decade beyond: the crossing strictly inside the grid
            if abs(np.log(n)) > abs(np.log(m)) - 0.1:   # flat or receding from 1
                break
            x, m = y, n
        return float("nan")

    lo, hi = float(w[0]), float(w[-1])
    parts = [w]
    new_lo = reach(lo, 0.1)
    if np.isfinite(new_lo):
        parts.insert(0, np.geomspace(new_lo, lo, int(200 * np.log10(lo / new_lo)) + 2)[:-1])
    new_hi = reach(hi, 10.0) if dt == 0 else float("nan")
    if np.isfinite(new_hi):
        delay = float(np.max(getattr(sys, "iodelay", 0.0), initial=0.0))
        n = int(200 * np.log10(new_hi / hi) + 50 * delay * new_hi) + 2
        parts.append(np.geomspace(hi, new_hi, min(n, 200000))[1:])
    return np.concatenate(parts) if len(parts) > 1 else w


def _root(f: Any, a: float, b: float) -> float:
    try:
        fa, fb = f(a), f(b)
        if fa == 0:
            return a
        if fa * fb > 0:
            return float("nan")
        return float(brentq(f, a, b, xtol=1e-14, rtol=4 * np.finfo(float).eps))
    except (ValueError, RuntimeError):
        return float("nan")
