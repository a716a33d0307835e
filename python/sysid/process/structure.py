"""MATLAB's process-model type codes and the transfer functions they stand for.

A type code is ``P`` followed by the number of poles (0-3) and any of the letters ``D``
(dead time), ``Z`` (a zero), ``I`` (an integrator) and ``U`` (underdamped: two of the poles a
complex pair, for 2 or 3 poles), e.g. ``"P1D"``, ``"P2DU"``, ``"P1DI"``, ``"P3DZ"``:

.. math::

    G(s) = K_p \\frac{1 + T_z s}{(1 + T_{p1} s)(1 + T_{p2} s)(1 + T_{p3} s)}
    \\,\\frac{1}{s^{[I]}}\\, e^{-T_d s},

with ``(1 + T_{p1} s)(1 + T_{p2} s)`` replaced by ``1 + 2 \\zeta T_w s + (T_w s)^2`` when the
code has ``U``.

Examples
--------
>>> from sysid.process.structure import ProcessType
>>> t = ProcessType.parse("p2du")
>>> t.code, t.names
('P2DU', ['Kp', 'Tw', 'Zeta', 'Td'])
>>> t.coefficients({"Kp": 2.0, "Tw": 0.5, "Zeta": 0.3})
(array([2.]), array([0.25, 0.3 , 1.  ]))
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import DataError

__all__ = ["ProcessType"]

_FIX = ("use a code like 'P1D', 'P2DU', 'P1DI' or 'P3DZ': P, the number of poles 0-3, then "
        "any of D (dead time), Z (zero), I (integrator), U (underdamped, 2 or 3 poles)")


@dataclass(frozen=True)
class ProcessType:
    """A parsed type code."""

    poles: int
    delay: bool
    zero: bool
    integrator: bool
    underdamped: bool

    @classmethod
    def parse(cls, code: Any) -> ProcessType:
        """Read a type code (case-insensitive); a clear error names the grammar otherwise."""
        if isinstance(code, (list, tuple)):
            raise DataError(f"one process type for every input, got a {type(code).__name__} "
                            f"{list(code)!r} (MATLAB's per-input types): give one code, or fit "
                            "a structure per input with sysid.tfest(data, n_poles, n_zeros, "
                            "iodelay='auto') and per-pair orders, e.g. n_poles=[[1, 2]]")
        if not isinstance(code, str):
            raise DataError(f"the process type must be a string such as 'P1D', got "
                            f"{type(code).__name__}; {_FIX}")
        c = code.strip().upper()
        if len(c) < 2 or c[0] != "P" or c[1] not in "0123":
            raise DataError(f"invalid process type {code!r}: {_FIX}")
        rest = c[2:]
        bad = [ch for ch in rest if ch not in "DZIU"]
        if bad or len(set(rest)) != len(rest):
            raise DataError(f"invalid process type {code!r} (letters {''.join(bad) or rest}): "
                            f"{_FIX}")
        t = cls(int(c[1]), "D" in rest, "Z" in rest, "I" in rest, "U" in rest)
        if t.underdamped and t.poles < 2:
            raise DataError(f"invalid process type {code!r}: U (underdamped) needs 2 or 3 "
                            "poles, e.g. 'P2DU'")
        if t.zero and t.poles == 0:
            raise DataError(f"invalid process type {code!r}: a zero needs at least one pole "
                            "(the model would be improper); use 'P1DZ'")
        return t

    @property
    def code(self) -> str:
        """The canonical code (``P``, poles, then D, Z, I, U as present)."""
        return "P" + str(self.poles) + "".join(
            ch for ch, on in zip("DZIU", (self.delay, self.zero, self.integrator,
                                          self.underdamped)) if on)

    @property
    def names(self) -> list[str]:
        """Parameter names in MATLAB's order (``Kp, Tp1, Tp2, Tp3, Tw, Zeta, Tz, Td``)."""
        out = ["Kp"]
        if self.underdamped:
            out += ["Tw", "Zeta"] + (["Tp3"] if self.poles == 3 else [])
        else:
            out += [f"Tp{k + 1}" for k in range(self.poles)]
        if self.zero:
            out.append("Tz")
        if self.delay:
            out.append("Td")
        return out

    def coefficients(self, p: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
        """``(num, den)`` in descending powers of ``s`` (without the dead time)."""
        den = np.ones(1)
        if self.underdamped:
            tw = p["Tw"]
            den = np.array([tw * tw, 2.0 * p["Zeta"] * tw, 1.0])
            if self.poles == 3:
                den = np.convolve(den, [p["Tp3"], 1.0])
        else:
            for k in range(self.poles):
                den = np.convolve(den, [p[f"Tp{k + 1}"], 1.0])
        if self.integrator:
            den = np.convolve(den, [1.0, 0.0])
        num = np.array([p["Kp"] * p["Tz"], p["Kp"]]) if self.zero else np.array([p["Kp"]])
        return num, den

    def default_bounds(self, name: str) -> tuple[float, float]:
        """MATLAB-like defaults: time constants and damping positive, the rest free."""
        if name == "Kp":
            return -np.inf, np.inf
        if name == "Tz":
            return -np.inf, np.inf
        if name == "Td":
            return 0.0, np.inf
        return 1e-9, np.inf
