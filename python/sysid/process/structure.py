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

__all__ = ["ProcessType", "FAST"]

#: a pole whose time constant is under ``dt / FAST`` acts within one sample (``exp(-40)``,
#: 4e-18: the sampled model does not have it)
FAST = 40.0

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

    def fast(self, p: dict[str, float], dt: float) -> dict[str, str]:
        """The poles of ``p`` that act within one sample of ``dt``: their time constant under
        ``dt / FAST`` (decayed to ``exp(-40)`` within a sample, so the sampled model does not
        have them). Keys: ``"Tp1"`` .. ``"Tp3"`` (a real pole), ``"pair"`` (the ``U`` pair:
        value ``"both"``, or ``"one"`` for the faster of an overdamped pair's real poles).

        Examples
        --------
        >>> from sysid.process.structure import ProcessType
        >>> ProcessType.parse("P2").fast({"Kp": 1.0, "Tp1": 2.0, "Tp2": 1e-9}, 0.1)
        {'Tp2': 'Tp2'}
        """
        lim, out = dt / FAST, {}
        if self.underdamped:
            tw, z = abs(p["Tw"]), p["Zeta"]
            times = _pair_times(tw, z)
            if times is not None:
                if times[0] < lim:
                    out["pair"] = "both"
                elif times[1] < lim:
                    out["pair"] = "one"
            elif z > 0 and tw / z < lim:  # complex poles that decay within a sample
                out["pair"] = "both"
        reals = ["Tp3"] if self.underdamped and self.poles == 3 else \
            ([] if self.underdamped else [f"Tp{k + 1}" for k in range(self.poles)])
        for k in reals:
            if abs(p[k]) < lim:
                out[k] = k
        return out

    def text(self, p: dict[str, float], leave: dict[str, str] | None = None
             ) -> tuple[str, str]:
        """The type code and the factored transfer function ``Kp (1 + Tz s) / ((1 + Tp1 s)
        ...) * exp(-Td s)`` of the values ``p``, the poles ``leave`` (:meth:`fast`) left out.

        Examples
        --------
        >>> from sysid.process.structure import ProcessType
        >>> t = ProcessType.parse("P2D")
        >>> p = {"Kp": 2.0, "Tp1": 1.5, "Tp2": 1e-9, "Td": 0.3}
        >>> t.text(p)
        ('P2D', '2 / ((1 + 1.5 s) (1 + 1e-09 s)) * exp(-0.3 s)')
        >>> t.text(p, t.fast(p, 0.1))
        ('P1D', '2 / (1 + 1.5 s) * exp(-0.3 s)')
        """
        leave = leave or {}
        facs, poles, pair = [], 0, False
        if self.underdamped:
            tw, z = p["Tw"], p["Zeta"]
            if leave.get("pair") == "one":
                times = _pair_times(abs(tw), z)
                facs.append(f"(1 + {times[0] if times else tw:.6g} s)")
                poles += 1
            elif "pair" not in leave:
                facs.append(f"(1 + {2.0 * z * tw:.6g} s + {tw * tw:.6g} s^2)")
                poles, pair = poles + 2, True
        for k in range(self.poles):
            name = f"Tp{k + 1}"
            if name in p and name not in leave:
                facs.append(f"(1 + {p[name]:.6g} s)")
                poles += 1
        if self.integrator:
            facs.insert(0, "s")
        num = f"{p['Kp']:.6g}" + (f" (1 {'-' if p['Tz'] < 0 else '+'} {abs(p['Tz']):.6g} s)"
                                  if self.zero else "")
        den = " ".join(facs)
        if len(facs) > 1:
            den = f"({den})"
        td = p.get("Td", 0.0)
        tail = f" * exp(-{td:.6g} s)" if self.delay and td > 0 else ""
        code = ProcessType(poles, self.delay, self.zero and poles > 0, self.integrator,
                           pair).code
        return code, (f"{num} / {den}" if den else num) + tail

    def default_bounds(self, name: str) -> tuple[float, float]:
        """MATLAB-like defaults: time constants and damping positive, the rest free."""
        if name == "Kp":
            return -np.inf, np.inf
        if name == "Tz":
            return -np.inf, np.inf
        if name == "Td":
            return 0.0, np.inf
        return 1e-9, np.inf


def _pair_times(tw: float, zeta: float) -> tuple[float, float] | None:
    """The real time constants (slower, faster) of an overdamped pair ``1 + 2 zeta Tw s +
    (Tw s)^2``; None for complex poles."""
    if zeta < 1.0:
        return None
    r = float(np.sqrt(zeta * zeta - 1.0))
    return tw * (zeta + r), tw / (zeta + r)
