"""The warnings a prediction-error refinement's result carries: a pole the stability bound
held at the unit circle, an unstable model, a search stopped at its cap, and directions of
the model the data leave undetermined (the same for the time-domain search and the fit on
the excited lines of periodic data)."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .._checks import user_stacklevel, warn_iteration_limit
from .._display import modulus
from ..errors import IdentifiabilityWarning, StabilityWarning
from ..models.frd import FRD
from .boundary import cap_advice, grows, integrator_advice, warn_boundary

__all__ = ["lines_record_length", "warn_refinement", "warn_undetermined"]


def warn_refinement(res: dict[str, Any], focus: str, max_iter: int, enforce: bool | None,
                    n: int = 0, held: bool = True, boundary: bool = True) -> None:
    """The warnings of a refinement: an unstable model, a pole at the unit circle
    (:func:`.boundary.warn_boundary`; ``held``: a bound kept ``A`` stable, else the search
    ended there freely; ``n``: samples of the longest experiment; not with ``boundary``
    false: a warning that the data insist on an unstable model said more), a capped search;
    each at the user's line."""
    rho = float(res["spectral_radius"])
    level = user_stacklevel()
    if boundary and (focus == "simulation" or enforce is not False):
        warn_boundary(res["a"], n, stacklevel=level, held=held)
    if rho >= 1.0 and enforce is None and n and not grows([rho], n):
        # a pole the record cannot tell from 1 (an offset left in the data puts one there):
        # the likelihood-ratio test's "better" is the record's, not the plant's instability
        warnings.warn(
            f"the refined model is unstable only marginally (largest pole modulus "
            f"{modulus(rho)}, a mode that grows by {100 * (rho ** n - 1):.2g} % over the "
            f"record's {n} samples): the record cannot tell it from an integrator (an "
            f"integrating plant, a drift, or an offset left in the data), "
            f"{integrator_advice('identify the differenced output')}; pass "
            f"enforce_stability=True (or focus='simulation') for a stable model",
            StabilityWarning, stacklevel=level)
    elif rho >= 1.0:
        why = ("an unstable model fits the data significantly better than the best stable "
               "one (likelihood-ratio test at 1 %)" if enforce is None else
               "enforce_stability=False keeps only the predictor stable")
        warnings.warn(
            f"the refined model is unstable (largest pole modulus {modulus(rho)}): {why}; pass "
            f"enforce_stability=True (or focus='simulation') for a stable model",
            StabilityWarning, stacklevel=level)
    if res["stop"] == "maximum iterations" and max_iter > 0:
        warn_iteration_limit(f"the {focus} search", max_iter, res["history"], cap_advice(
            res, focus), remaining=res["remaining_decrease"])


def lines_record_length(frd: FRD) -> int:
    """The samples a model fitted on the lines of ``frd`` is judged over, for
    :func:`.boundary.warn_boundary`: the steady-state periods of the record the lines came
    from, else one period of the lines' grid (``2 pi`` over their smallest spacing)."""
    info = frd.info or {}
    if info.get("n_per") and info.get("periods"):
        return int(info["n_per"]) * max(1, int(info["periods"]) - int(info.get("transient", 0)))
    w = np.diff(np.sort(np.asarray(frd.omega, float) * float(frd.dt or 1.0)))
    w = w[w > 0]
    return int(round(2 * np.pi / float(w.min()))) if w.size else 0


def warn_undetermined(res: dict[str, Any], n: int) -> int:
    """The number of directions of the refined model, beyond its similarity orbit (``n^2``
    of the full parametrisation), that its Gauss-Newton matrix leaves undetermined; an
    :class:`~sysid.IdentifiabilityWarning` when there are any (an order above what the data
    support: the heating record's order-7 choice had rank 17 of 22, three poles near 0.98
    beside zeros at 0.982 +- 0.021j and 0.991)."""
    p, rank = int(np.asarray(res["theta"]).size), int(res["rank"])
    lost = max(0, p - n * n - rank) if n else 0
    if lost:
        warnings.warn(IdentifiabilityWarning(
            f"the data do not determine {lost} of the {p - n * n} identifiable parameter "
            f"directions of the refined order-{n} model (its Gauss-Newton matrix has rank "
            f"{rank}; the similarity orbit takes {n * n} of its {p} parameters): the order is "
            "higher than the data support "
            "(poles that nearly cancel zeros, for example). The fit stands, but standard "
            "deviations leave those directions out and are not reliable: a lower order will "
            "likely fit as well"), stacklevel=user_stacklevel())
    return lost
