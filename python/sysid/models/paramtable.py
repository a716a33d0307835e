"""The table of estimated grey-box parameters: value, standard deviation, fixed, active bound,
95 % interval, unit and description.

Examples
--------
>>> from sysid.models.paramtable import ParameterTable
>>> t = ParameterTable(["a", "g"], [0.5, 9.81], [0.01, 0.0], [False, True])
>>> t["a"]["std"]
0.01
>>> print(t)
parameter        value         std   fixed  bound        95 % interval
a                  0.5        0.01                 [  0.4804,   0.5196]
g                 9.81           0   fixed
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["ParameterTable"]

Z95 = 1.959963984540054


class ParameterTable:
    """Estimated parameters with their standard deviations (see ``sysid.greyest``).

    Attributes
    ----------
    names : list of str
    value, std : ndarray
    fixed : ndarray of bool
    bound : list of str
        ``"lower"``/``"upper"`` when the estimate sits on that bound, else ``""``.
    lower, upper : ndarray
        The 95 % interval ``value -+ 1.96 std`` (equal to the value for fixed parameters).
    """

    def __init__(self, names: Sequence[str], value: Any, std: Any, fixed: Any,
                 bound: Sequence[str] | None = None, units: Sequence[str] | None = None,
                 descriptions: Sequence[str] | None = None) -> None:
        self.names = list(names)
        k = len(self.names)
        self.value = np.asarray(value, dtype=float).reshape(k)
        self.std = np.asarray(std, dtype=float).reshape(k)
        self.fixed = np.asarray(fixed, dtype=bool).reshape(k)
        self.bound = list(bound) if bound is not None else [""] * k
        self.units = list(units) if units is not None else [""] * k
        self.descriptions = list(descriptions) if descriptions is not None else [""] * k
        self.lower = self.value - Z95 * self.std
        self.upper = self.value + Z95 * self.std

    def cut_at_bounds(self, lower: Any, upper: Any) -> ParameterTable:
        """Cut the 95 % intervals at the parameters' bounds ``lower``/``upper`` (one per
        parameter, ``-inf``/``inf`` for none) and return the table: an estimate on a bound
        has the std of the unconstrained curvature, and its interval must not reach past the
        bound (a damping on its upper bound 1.0 is not ``[0.958, 1.042]``).

        Examples
        --------
        >>> t = ParameterTable(["c"], [1.0], [0.0214], [False], ["upper"])
        >>> lo, hi = t.cut_at_bounds([0.0], [1.0])["c"]["ci95"]
        >>> round(lo, 4), hi
        (0.9581, 1.0)
        """
        self.lower = np.maximum(self.lower, np.asarray(lower, dtype=float).reshape(len(self)))
        self.upper = np.minimum(self.upper, np.asarray(upper, dtype=float).reshape(len(self)))
        return self

    def __len__(self) -> int:
        return len(self.names)

    def __getitem__(self, name: str) -> dict[str, Any]:
        i = self.names.index(name)
        return {"value": float(self.value[i]), "std": float(self.std[i]),
                "fixed": bool(self.fixed[i]), "bound": self.bound[i],
                "ci95": (float(self.lower[i]), float(self.upper[i])),
                "unit": self.units[i], "description": self.descriptions[i]}

    def as_dict(self) -> dict[str, float]:
        """``{name: value}``."""
        return dict(zip(self.names, self.value.tolist()))

    def rows(self) -> list[dict[str, Any]]:
        """One dict per parameter (what the HTML report shows)."""
        return [{"name": n, **self[n]} for n in self.names]

    def to_pandas(self) -> Any:
        """A :class:`pandas.DataFrame` indexed by parameter name."""
        import pandas as pd

        with np.errstate(divide="ignore", invalid="ignore"):
            rel = np.where(self.fixed, np.nan, self.std / np.abs(self.value))
        return pd.DataFrame({"value": self.value, "std": self.std, "relative std": rel,
                             "fixed": self.fixed, "bound active": self.bound,
                             "ci95 lower": self.lower, "ci95 upper": self.upper,
                             "unit": self.units, "description": self.descriptions},
                            index=pd.Index(self.names, name="parameter"))

    def summary(self) -> str:
        """The table as text."""
        return str(self)

    def __str__(self) -> str:
        w = max([9] + [len(n) for n in self.names])
        lines = [f"{'parameter':<{w}} {'value':>12} {'std':>11}   fixed  bound "
                 f"       95 % interval"]
        for i, n in enumerate(self.names):
            row = f"{n:<{w}} {self.value[i]:12.6g} {self.std[i]:11.4g}"
            if self.fixed[i]:
                row += "   fixed"
            else:
                row += f"   {'':5}  {self.bound[i]:<6} [{self.lower[i]:9.4g}, {self.upper[i]:9.4g}]"
            if self.units[i]:
                row += f"  {self.units[i]}"
            lines.append(row.rstrip())
        return "\n".join(lines)

    def __repr__(self) -> str:
        return str(self)

    def _repr_html_(self) -> str:
        """Notebook display: the table (see :mod:`sysid._display`)."""
        from .._display import _wrap, table

        rows = [[n, self.value[i], self.std[i], bool(self.fixed[i]), self.bound[i],
                 "" if self.fixed[i] else f"[{self.lower[i]:.4g}, {self.upper[i]:.4g}]",
                 self.units[i], self.descriptions[i]] for i, n in enumerate(self.names)]
        return _wrap(f"{len(self)} parameters", table(
            ["parameter", "value", "std", "fixed", "bound active", "95 % interval", "unit",
             "description"], rows, tid="parameters", max_rows=None))
