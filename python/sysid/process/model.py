"""The :class:`ProcessModel`: a transfer function written with physical parameters (gain,
time constants, damping, zero, integrator, dead time), MATLAB's ``idproc``."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..errors import DataError
from ..tf.model import TransferFunction
from .structure import ProcessType

__all__ = ["ProcessModel"]


class ProcessModel(TransferFunction):
    """Process model ``Kp (1 + Tz s) / ((1 + Tp1 s)(1 + Tp2 s)(1 + Tp3 s)) / s^[I] e^{-Td s}``.

    A :class:`~sysid.TransferFunction` (continuous time) with named parameters; see
    :func:`sysid.procest` for the type codes.

    Parameters
    ----------
    type_code : str
        ``"P1D"``, ``"P2DU"``, ``"P1DI"``, ``"P3DZ"``, ...
    values : dict or nested lists of dicts, optional
        Parameter values by name: one dict (single input and output) or ``[output][input]``.
    hold : {"zoh", "foh"}
        Inter-sample behaviour when meeting sampled data.
    input_names, output_names : sequence of str, optional
    info : dict, optional
    **params : float
        Single-input single-output shortcut: ``ProcessModel("P1D", Kp=2, Tp1=1, Td=0.1)``.

    Examples
    --------
    >>> import sysid
    >>> m = sysid.ProcessModel("P1D", Kp=2.0, Tp1=1.5, Td=0.37)
    >>> m
    ProcessModel(P1D: Kp=2, Tp1=1.5, Td=0.37)
    >>> print(m)
    ProcessModel(P1D: Kp=2, Tp1=1.5, Td=0.37)
    y0 <- u0:  1.33333 / (s + 0.666667) * exp(-0.37 s)
    """

    def __init__(self, type_code: str, values: Any = None, *, hold: str = "zoh",
                 input_names: Sequence[str] | None = None,
                 output_names: Sequence[str] | None = None,
                 info: dict[str, Any] | None = None, **params: float) -> None:
        t = ProcessType.parse(type_code)
        if values is None:
            values = dict(params)
        elif params:
            raise DataError("give the parameters either as values=... or as keywords, not both")
        grid = [[values]] if isinstance(values, Mapping) else values
        try:
            grid = [[{k: float(v) for k, v in dict(d).items()} for d in row] for row in grid]
        except (TypeError, ValueError) as e:
            raise DataError(f"values must be a dict of numbers or [output][input] lists of "
                            f"them ({e})") from None
        for row in grid:
            for d in row:
                missing = [k for k in t.names if k not in d and k != "Td"]
                extra = sorted(set(d) - set(t.names))
                if missing or extra:
                    raise DataError(f"{t.code} has the parameters {t.names}; missing "
                                    f"{missing}, unknown {extra}")
                bad = [k for k, v in d.items() if not np.isfinite(v)]
                if bad:
                    raise DataError(f"{t.code}: parameter(s) {bad} must be finite numbers, "
                                    f"got {[d[k] for k in bad]}")
        self.type = t
        self._values = grid
        nums = [[t.coefficients(d)[0] for d in row] for row in grid]
        dens = [[t.coefficients(d)[1] for d in row] for row in grid]
        delays = [[d.get("Td", 0.0) for d in row] for row in grid]
        super().__init__(nums, dens, iodelay=delays, hold=hold, input_names=input_names,
                         output_names=output_names, info=info)

    @property
    def values(self) -> Any:
        """Parameter values: a dict (single pair) or ``[output][input]`` lists of dicts."""
        if self.noutputs == self.ninputs == 1:
            return dict(self._values[0][0])
        return [[dict(d) for d in row] for row in self._values]

    @property
    def n_parameters(self) -> int:
        """Free parameters (all named parameters of every pair, minus fixed ones)."""
        fixed = set(self.info.get("fixed", []))
        return sum(1 for n in self.parameter_names() if n.split(":")[-1] not in fixed)

    def parameter_names(self) -> list[str]:
        """``"y<-u:name"`` for every pair and parameter (just the names for one pair)."""
        if self.noutputs == self.ninputs == 1:
            return [k for k in self.type.names]
        return [f"{self.output_names[i]}<-{self.input_names[j]}:{k}"
                for i, j in self.pairs() for k in self.type.names]

    def parameter_vector(self) -> np.ndarray:
        """All parameter values in :meth:`parameter_names` order."""
        return np.array([self._values[i][j].get(k, 0.0) for i, j in self.pairs()
                         for k in self.type.names])

    def with_parameter_vector(self, theta: Any) -> ProcessModel:
        """A copy with the parameters ``theta`` (:meth:`parameter_names` order)."""
        th = np.asarray(theta, dtype=float).ravel()
        k = len(self.type.names)
        vals = [[{} for _ in range(self.ninputs)] for _ in range(self.noutputs)]
        for c, (i, j) in enumerate(self.pairs()):
            vals[i][j] = dict(zip(self.type.names, th[c * k:(c + 1) * k]))
            if "Td" in vals[i][j]:
                vals[i][j]["Td"] = max(vals[i][j]["Td"], 0.0)
        return ProcessModel(self.type.code, vals, hold=self.hold, input_names=self.input_names,
                            output_names=self.output_names)

    def _select(self, iy: list[int], iu: list[int]) -> ProcessModel:
        """Outputs ``iy`` from inputs ``iu`` (:meth:`select`), with their parameters."""
        from ..models.subsystem import names

        return ProcessModel(self.type.code, [[dict(self._values[i][j]) for j in iu]
                                             for i in iy], hold=self.hold,
                            input_names=names(self.input_names, iu),
                            output_names=names(self.output_names, iy), info=self.info)

    def to_tf(self) -> TransferFunction:
        """The same model as a plain :class:`~sysid.TransferFunction`, its parameter
        uncertainty carried (:mod:`sysid.models.carried`)."""
        from ..models.carried import carry

        return carry(self, TransferFunction(
            self.num, self.den, iodelay=self.iodelay, hold=self.hold,
            input_names=self.input_names, output_names=self.output_names, info=self.info),
            ProcessModel.to_tf)

    def to_dict(self) -> dict[str, Any]:
        """Type, parameter values, names and info (see :func:`sysid.save_model`)."""
        return {"type": self.type.code, "values": self._values, "hold": self.hold,
                "input_names": list(self.input_names), "output_names": list(self.output_names),
                "info": self.info}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ProcessModel:  # type: ignore[override]
        """Inverse of :meth:`to_dict`."""
        return cls(d["type"], d["values"], hold=d.get("hold", "zoh"),
                   input_names=d.get("input_names"), output_names=d.get("output_names"),
                   info=d.get("info"))

    def collapsed(self, dt: float | None = None) -> dict[str, tuple[str, str]]:
        """The pairs with a pole that acts within one sample of ``dt`` (default: the sample
        interval of the data :func:`sysid.procest` fitted, ``info["sample_time"]``), a time
        constant under ``dt / 40``, as a search that ran one to its lower bound leaves it:
        ``{"y<-u": (type, transfer function)}`` of what the pair is in effect, those poles
        left out (the sampled model is the same to ``exp(-40)``).

        Examples
        --------
        >>> import sysid
        >>> m = sysid.ProcessModel("P2", Kp=2.0, Tp1=1.5, Tp2=1e-9)
        >>> m.collapsed(dt=0.1)
        {'y0<-u0': ('P1', '2 / (1 + 1.5 s)')}
        """
        dt = self.info.get("sample_time") if dt is None else dt
        if dt is None or not dt > 0:
            return {}
        out = {}
        for i, j in self.pairs():
            p = self._values[i][j]
            fast = self.type.fast(p, float(dt))
            if fast:
                out[f"{self.output_names[i]}<-{self.input_names[j]}"] = self.type.text(p, fast)
        return out

    def __str__(self) -> str:
        gone = self.collapsed()
        if not gone:
            return f"{self!r}\n{TransferFunction.__str__(self)}"
        # a pole run to 1e-9 makes the expanded coefficients 1e9 .. 1e18: the factored form,
        # and what the pair is in effect
        lines = [repr(self)]
        for i, j in self.pairs():
            key = f"{self.output_names[i]}<-{self.input_names[j]}"
            p = self._values[i][j]
            lines.append(f"{self.output_names[i]} <- {self.input_names[j]}:  "
                         f"{self.type.text(p)[1]}")
            if key in gone:
                code, text = gone[key]
                lines.append(f"    in effect {code}: {text} (a pole acts within one sample, "
                             f"dt = {self.info['sample_time']:g})")
        return "\n".join(lines)

    def __repr__(self) -> str:
        if self.noutputs == self.ninputs == 1:
            v = ", ".join(f"{k}={self._values[0][0].get(k, 0.0):.6g}" for k in self.type.names)
            return f"ProcessModel({self.type.code}: {v})"
        return (f"ProcessModel({self.type.code}, {self.noutputs} output(s) x "
                f"{self.ninputs} input(s))")


def _register() -> None:
    from ..models.serialize import register_model

    register_model(ProcessModel)


_register()
