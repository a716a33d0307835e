"""Modal analysis of a discrete-time model: natural frequencies, damping ratios, mode shapes.

Each pole ``z`` of A maps to ``s = ln(z) / dt``; the natural frequency is ``|s|`` rad/s
(``|s| / 2 pi`` Hz) and the damping ratio ``-Re(s) / |s|``. One mode is reported per real pole
and per complex-conjugate pair. Mode shapes are ``C psi`` for the eigenvector psi, scaled so
that the largest entry is 1. The numerics run in the Rust core.

Examples
--------
>>> import numpy as np, sysid
>>> dt, f, zeta = 0.01, 5.0, 0.02
>>> s = -zeta * 2 * np.pi * f + 1j * 2 * np.pi * f * np.sqrt(1 - zeta**2)
>>> z = np.exp(s * dt)
>>> A = [[z.real, z.imag], [-z.imag, z.real]]
>>> m = sysid.modal_analysis(sysid.StateSpaceModel(A, [[1.0], [0.0]], [[1.0, 0.0]], dt=dt))
>>> round(float(m.frequencies_hz[0]), 6), round(float(m.damping[0]), 6)
(5.0, 0.02)
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_dt
from .._display import HTMLResult
from ..data.formats import _pandas
from ..errors import DataError
from ..models.checks import discrete_statespace
from ..models.pole_map import continuous_equivalent, damping_ratio
from ..models.statespace import StateSpaceModel

__all__ = ["ModalAnalysis", "modal_analysis"]


class ModalAnalysis(HTMLResult):
    """Modes of a model, sorted by natural frequency.

    Attributes
    ----------
    eigenvalues : ndarray
        Discrete-time poles (complex; the member with positive imaginary part of each pair).
    s : ndarray
        Continuous-time equivalents ``ln(z) / dt`` (1/s); ``-inf`` for a pole at ``z = 0``.
    omega : ndarray
        Natural frequencies in rad/s (``inf`` for a pole at ``z = 0``, infinitely fast, with
        damping 1, as :func:`sysid.damp`).
    frequencies_hz : ndarray
        Natural frequencies in Hz.
    damping : ndarray
        Damping ratios (1 for a positive real pole, negative for an unstable mode, -1 for a
        pole at ``z = 1``, an integrator, as :func:`sysid.damp` and MATLAB's ``damp``).
    mode_shapes : ndarray
        Complex, ``(n_modes, noutputs)``, largest entry of each shape equal to 1.
    dt : float
        Sample time used.
    output_names : list of str
        Names of the mode-shape entries.
    extra : dict
        Additional per-mode columns (ERA adds ``mac`` and ``mpc``).
    """

    def __init__(self, d: dict[str, Any], dt: float, output_names: list[str]) -> None:
        self.eigenvalues = np.asarray(d["eig_re"]) + 1j * np.asarray(d["eig_im"])
        self.omega = np.asarray(d["omega"])
        self.frequencies_hz = np.asarray(d["frequency_hz"])
        self.mode_shapes = np.asarray(d["shape_re"]) + 1j * np.asarray(d["shape_im"])
        self.dt = dt
        self.s = continuous_equivalent(self.eigenvalues, dt)  # z = 0: -inf, as damp()
        # damp()'s rule (sysid.models.pole_map), not the core's: -1 at z = 1 (s = 0), as
        # MATLAB's damp, where the core says 1
        self.damping = damping_ratio(self.s)
        self.output_names = output_names
        self.extra: dict[str, np.ndarray] = {}

    def __len__(self) -> int:
        return len(self.eigenvalues)

    def select(self, mask: Any) -> ModalAnalysis:
        """The modes where ``mask`` (boolean or index array) selects, as a new object.

        Examples
        --------
        >>> import sysid
        >>> m = sysid.modal_analysis(sysid.StateSpaceModel([[0.5, 0], [0, 0.9]], [[1], [1]],
        ...                                               [[1, 1]]))
        >>> len(m.select(m.damping > 0.5)), len(m.select([0]))
        (2, 1)
        """
        out = copy.copy(self)
        idx = np.asarray(mask)
        for name in ("eigenvalues", "s", "omega", "frequencies_hz", "damping", "mode_shapes"):
            setattr(out, name, getattr(self, name)[idx])
        out.extra = {k: v[idx] for k, v in self.extra.items()}
        return out

    def table(self) -> str:
        """The modes as a text table (frequency in Hz and rad/s, damping, extra columns)."""
        head = f"{'mode':>4} {'freq (Hz)':>11} {'omega (rad/s)':>14} {'damping':>9}"
        for k in self.extra:
            head += f" {k.upper():>7}"
        lines = [head]
        for i in range(len(self)):
            row = (f"{i:>4} {self.frequencies_hz[i]:>11.4f} {self.omega[i]:>14.4f} "
                   f"{self.damping[i]:>9.4f}")
            for k, v in self.extra.items():
                row += f" {v[i]:>7.3g}" if k.startswith("sd_") else f" {v[i]:>7.3f}"
            lines.append(row)
        return "\n".join(lines)

    def to_pandas(self) -> Any:
        """The modes as a pandas DataFrame (pandas imported lazily)."""
        pd = _pandas()
        cols: dict[str, Any] = {
            "frequency_hz": self.frequencies_hz, "omega": self.omega, "damping": self.damping,
            "eigenvalue": self.eigenvalues, **self.extra,
        }
        return pd.DataFrame(cols)

    def summary(self) -> str:
        """The modes as a text table (frequency, damping, and the extra columns)."""
        return repr(self)

    def __repr__(self) -> str:
        return f"ModalAnalysis({len(self)} modes, dt={self.dt:g})\n" + self.table()


def modal_analysis(model: StateSpaceModel, dt: float | None = None, std: bool = False
                   ) -> ModalAnalysis:
    """Natural frequencies, damping ratios and mode shapes of a discrete-time model.

    Parameters
    ----------
    model : StateSpaceModel
        The model; its ``dt`` is the sample time.
    dt : float, optional
        Sample time in seconds: must agree with ``model.dt`` (a different one raises a
        :class:`~sysid.errors.DataError`: the frequencies would be wrong by their ratio).
    std : bool
        Add the first-order standard deviations of each mode's frequency and damping
        (``extra["sd_hz"]``, ``extra["sd_damping"]``) from the model's ``uncertainty``.

    Returns
    -------
    ModalAnalysis

    Examples
    --------
    >>> import sysid
    >>> m = sysid.modal_analysis(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1))
    >>> round(float(m.damping[0]), 12), round(float(m.omega[0]), 6)
    (1.0, 6.931472)
    """
    if not isinstance(model, StateSpaceModel):
        model = discrete_statespace(model, "modal analysis")
    dt = as_dt(model.dt if dt is None else dt)
    if model.dt and not np.isclose(dt, model.dt, rtol=1e-9, atol=0.0):
        raise DataError(
            f"dt={dt:.10g} contradicts the model's sample time dt={model.dt:.10g}: its "
            "frequencies would be wrong by their ratio; drop dt, or if the model really is "
            "sampled every dt, rebuild it with that sample time (sysid.StateSpaceModel(A, B, "
            "C, D, dt=dt))")
    d = _sysid.modal_analysis(model.A, model.C, dt)
    out = ModalAnalysis(d, dt, list(model.output_names))
    if std:
        from ..models.pole_uncertainty import damping_std

        sd = damping_std(model, dt)
        idx = [int(np.argmin(np.abs(sd["poles"] - z))) for z in out.eigenvalues]
        out.extra["sd_hz"] = sd["wn_hz_std"][idx]
        out.extra["sd_damping"] = sd["zeta_std"][idx]
    return out
