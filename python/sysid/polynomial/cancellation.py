"""Pole-zero cancellation in an estimated input channel ``B/F``: a pole of ``F`` closer to a
zero of ``B`` than the pole's own standard deviation is a common factor the data do not
determine (the order is higher than they support). Its static gain, step response and the
pole itself then mean nothing, though the simulation can fit well: say so."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .._checks import user_stacklevel
from ..errors import IdentifiabilityWarning

__all__ = ["cancellation", "root_std", "warn_cancellations"]


def root_std(poly: np.ndarray, cov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roots of the monic polynomial ``1 + poly[0] q^-1 + ...`` (``z^n + poly[0] z^(n-1) +
    ...``) and their first-order standard deviations (modulus of the complex std) from the
    covariance ``cov`` of ``poly``.

    Examples
    --------
    >>> import numpy as np
    >>> r, s = root_std(np.array([-0.5]), np.array([[1e-4]]))
    >>> np.round(r.real, 6).tolist(), np.round(s, 6).tolist()
    ([0.5], [0.01])
    """
    poly = np.asarray(poly, float).ravel()
    n = poly.size
    roots = np.roots(np.r_[1.0, poly]).astype(complex)
    dpoly = np.polyder(np.r_[1.0, poly])
    sd = np.full(n, np.nan)
    for i, p in enumerate(roots):
        d = np.polyval(dpoly, p)
        if abs(d) < 1e-300:
            continue  # a repeated root: no first-order value
        g = -(p ** (n - 1 - np.arange(n))) / d  # d p / d poly[k]
        var = float(g.real @ cov @ g.real + g.imag @ cov @ g.imag)
        sd[i] = np.sqrt(max(var, 0.0))
    return roots, sd


def cancellation(b: np.ndarray, f: np.ndarray, cov_f: np.ndarray) -> str | None:
    """A description of the first pole of ``F`` that lies closer to a zero of ``B`` than the
    pole's standard deviation (or than 1e-6: an exact common factor), else ``None``."""
    b = np.trim_zeros(np.asarray(b, float).ravel(), "f")
    f = np.asarray(f, float).ravel()
    if b.size < 2 or f.size < 1 or not np.all(np.isfinite(cov_f)):
        return None
    zeros = np.roots(b)
    poles, sd = root_std(f, cov_f)
    for p, s in zip(poles, sd):
        dist = np.abs(zeros - p)
        k = int(np.argmin(dist))
        if dist[k] <= max(s if np.isfinite(s) else 0.0, 1e-6 * max(1.0, abs(p))):
            return (f"the pole {_z(p)} of F and the zero {_z(zeros[k])} of B are "
                    f"{dist[k]:.2g} apart, within the pole's standard deviation {s:.2g}")
    return None


def warn_cancellations(method: str, found: list[tuple[str, str]]) -> None:
    """One :class:`~sysid.IdentifiabilityWarning` for the channels ``(name, description)``
    of an estimate whose pole and zero cancel within the pole's uncertainty."""
    if not found:
        return
    where = "; ".join(f"in channel {c} {d}" for c, d in found[:4]) + (
        f" (and {len(found) - 4} more channels)" if len(found) > 4 else "")
    warnings.warn(IdentifiabilityWarning(
        f"{method}: {where}: they cancel, a common factor the data do not determine. The fit "
        "can be good, but that pole, the static gain and the step response are not "
        "determined: lower nb and nf by one" + (" in those channels" if len(found) > 1
                                                 else "")), stacklevel=user_stacklevel())


def _z(z: Any) -> str:
    z = complex(z)
    return f"{z.real:.6g}" if abs(z.imag) < 1e-12 else f"{z.real:.6g}{z.imag:+.4g}j"
