"""Poles the stability bound of a search holds at the unit circle.

A search that keeps ``A`` stable (simulation focus, ``enforce_stability=True``) refuses every
step across the unit circle, so where the data pull a pole outwards the result has it just
inside: at ``1 - 1e-8`` on the ball and beam record (an integrating plant), or as an undamped
pair fitted to noise by an order higher than the data support. Within the record such a mode
does not decay, and the model is not what the engineer would read it as (a static gain, a
damping): :func:`warn_boundary` says so, and what to do.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .._checks import PERSISTENT_DECAY, mode_kept, user_stacklevel
from ..errors import StabilityWarning

__all__ = ["cap_advice", "grows", "insists", "integrator_advice", "spectral_radius",
           "warn_boundary", "warn_insisted", "warn_poles_at_bound"]


def grows(poles: Any, n: int, dt: float = 0.0) -> bool:
    """Whether the fastest mode of ``poles`` grows by more than ``1 / PERSISTENT_DECAY`` over
    ``n`` samples: discrete poles (``dt = 0``: modulus to the ``n``) or continuous ones
    (``exp(real n dt)``). A mode that grows less cannot be told from one on the stability
    bound (an integrator) by the record; empty or non-finite poles: False.

    Examples
    --------
    >>> from sysid.pem.boundary import grows
    >>> grows([1.02, 0.5], 600), grows([1.00001], 600), grows([0.02], 600, dt=1.0)
    (True, False, True)
    """
    p = np.asarray(poles, complex).ravel()
    if not p.size or not np.all(np.isfinite(p)):
        return False
    with np.errstate(divide="ignore"):
        rate = float(p.real.max()) * dt if dt else float(np.log(np.abs(p).max()))
    return bool(rate * n > -np.log(PERSISTENT_DECAY))


def warn_boundary(A: np.ndarray, n: int, stacklevel: int | None = None,
                  held: bool = True) -> bool:
    """A :class:`~sysid.StabilityWarning` when a pole of the stable ``A`` keeps more than
    ``PERSISTENT_DECAY`` of its mode over ``n`` samples (the longest experiment); True if it
    warned. A real pole (or one turning less than once over the record) acts as an
    integrator there; an oscillating one as an undamped oscillation. ``held``: the search
    kept ``A`` stable (else it ended there freely, from an unstable start).

    Examples
    --------
    >>> import numpy as np, warnings
    >>> from sysid.pem.boundary import warn_boundary
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     warn_boundary(np.array([[1 - 1e-9]]), 500), warn_boundary(np.array([[0.9]]), 500)
    (True, False)
    >>> w[0].category.__name__
    'StabilityWarning'
    """
    p = np.linalg.eigvals(np.asarray(A, float)) if n and np.size(A) else np.zeros(0)
    return warn_poles_at_bound(
        p, n, "the refined model", "the search keeps A stable" if held else None,
        integrating=("identify the differenced output or use focus='prediction' with "
                     "enforce_stability=False"),
        lower="order='auto' chooses one on data held out of the fit; a model of an "
              "automatic order holds every order's score in info['order_selection']",
        stacklevel=user_stacklevel() if stacklevel is None else stacklevel + 1)


def integrator_advice(integrating: str) -> str:
    """What a pole the record cannot tell from 1 leaves undetermined, and the two fixes
    (``integrating``: the advice for an integrating plant), for the warnings that name one.

    Examples
    --------
    >>> from sysid.pem.boundary import integrator_advice
    >>> integrator_advice("use arx")[:30]
    'so the static gain and the ste'
    """
    return ("so the static gain and the step response's final value (which grow as "
            f"1 / (1 - |p|)) are not determined. If the plant integrates, {integrating}; if "
            "not, remove the offset and any drift first (sysid.detrend(data, 'linear') "
            "removes both)")


def warn_poles_at_bound(poles: np.ndarray, n: int, model: str, bound: str | None, *,
                        integrating: str, lower: str, stacklevel: int | None = None) -> bool:
    """:func:`warn_boundary` for the ``poles`` of any search that keeps them inside the
    unit circle (``bound`` says which, e.g. "the search keeps F stable"; ``None`` for a
    search that ended there freely; ``model`` names the model; ``integrating`` is the
    advice for an integrating plant, ``lower`` how to ask for a lower order). True if it
    warned.

    Examples
    --------
    >>> import numpy as np, warnings
    >>> from sysid.pem.boundary import warn_poles_at_bound
    >>> pair = (1 - 1e-9) * np.exp(0.3j * np.array([1.0, -1.0]))  # an undamped pair
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     said = warn_poles_at_bound(pair, 500, "oe's model", "the search keeps F stable",
    ...                                integrating="use arx", lower="a smaller nf")
    >>> said, "an undamped oscillation of period 20.9 samples" in str(w[0].message)
    (True, True)
    """
    p = np.asarray(poles, complex).ravel() if n else np.zeros(0)
    p = p[np.isfinite(p)]
    kept = np.array([mode_kept(abs(z), n) for z in p])
    if not p.size or kept.max() <= PERSISTENT_DECAY or np.abs(p).max() >= 1.0:
        return False
    i = int(np.argmax(kept))
    z, share = p[i], 100 * kept[i]
    what = f"a pole of modulus 1 - {1.0 - abs(z):.2g}, which keeps {share:.0f} % of its mode " \
           f"over the record ({n} samples)"
    turns = abs(float(np.angle(z))) * n / (2 * np.pi)
    if turns < 1.0:
        # an offset left in the data pulls a pole there as a drift does (a level pilot
        # plant's pump voltage, mean 3.5 V, std 0.15 V): named with the drift, one fix
        why = (f"{bound}, and such a pole usually sits where that bound held it (an "
               f"integrating plant, a drift, or an offset left in the data); the record "
               f"cannot tell it from an integrator"
               if bound else "the record cannot tell it from an integrator (an integrating "
               "plant, a drift, or an offset left in the data)")
        msg = f"{model} has {what}: {why}, {integrator_advice(integrating)}"
    else:
        where = (f"{bound}, and such a pair usually sits where that bound held it" if bound
                 else "such a pair usually comes from")
        msg = (f"{model} has {what}, an undamped oscillation of period "
               f"{2 * np.pi / abs(float(np.angle(z))):.3g} samples: {where} (an order higher "
               f"than the data support, fitting noise, or a periodic disturbance in the "
               f"output); try a lower order ({lower}) or look for the disturbance "
               f"(sysid.spectra(data))")
    warnings.warn(msg, StabilityWarning,
                  stacklevel=user_stacklevel() if stacklevel is None else stacklevel + 1)
    return True


def cap_advice(res: dict[str, Any], focus: str = "prediction") -> str:
    """What to do about a search stopped at its cap (``res``: its ``iterations`` and
    ``shortened``, the accepted steps the stability bound shortened; ``focus``: the
    criterion, which the advice to refine again repeats, since ``pem`` defaults to
    prediction). When the bound shortened most of them, more iterations creep along it: on
    the unshipped DaISy heat exchanger (its offset not removed), ``ssest(data, 4)`` held a
    pole at 1 - 2e-10, shortened all 50 steps (by 2^10 to 2^21) and needed 838 iterations
    to converge.

    Examples
    --------
    >>> cap_advice({"iterations": 50, "shortened": 50})[:40]
    'the stability bound shortened 50 of its '
    >>> cap_advice({"iterations": 50, "shortened": 3})
    'raise max_iter, or refine again with sysid.pem(data, model)'
    >>> print(cap_advice({"iterations": 50, "shortened": 3}, "simulation"))
    raise max_iter, or refine again with sysid.pem(data, model, focus='simulation')
    """
    it, cut = int(res["iterations"]), int(res.get("shortened", 0))
    if it and 2 * cut > it:
        return (f"the stability bound shortened {cut} of its {it} steps (a pole held at the "
                "unit circle), so more iterations creep along that bound; see the "
                "StabilityWarning for that pole, try another order, or raise max_iter "
                "(it may take hundreds)")
    again = "" if focus == "prediction" else f", focus={focus!r}"
    return f"raise max_iter, or refine again with sysid.pem(data, model{again})"


def spectral_radius(A: Any) -> float:
    """The largest eigenvalue modulus of the square matrix ``A`` (0 for an empty one).

    Examples
    --------
    >>> from sysid.pem.boundary import spectral_radius
    >>> spectral_radius([[0.5, 1.0], [0.0, -0.9]])
    0.9
    """
    A = np.asarray(A, dtype=float)
    return float(np.max(np.abs(np.linalg.eigvals(A)), initial=0.0)) if A.size else 0.0


def insists(kept: float, free: float, n: int, l: int = 1) -> tuple[float, bool]:
    """Whether the data insist on a free fit (sum of squared errors ``free``) over the one a
    stability bound kept (``kept``), over ``n`` samples and ``l`` outputs: the
    likelihood-ratio statistic ``n l ln(kept / free)`` and whether it exceeds the 1 % level
    of chi-square with one degree of freedom (6.63). The rule of ``ssest``/``pem``'s
    default stability choice (``sysid_core::pem::insists``), here for the estimators that
    keep their model stable and warn instead (``tfest``, ``oe``).

    Examples
    --------
    >>> from sysid.pem.boundary import insists
    >>> [round(v, 2) if isinstance(v, float) else v for v in insists(1.02, 1.0, 1000)]
    [19.8, True]
    >>> insists(1.001, 1.0, 1000)[1]
    False
    """
    from .. import _sysid

    if not (np.isfinite(kept) and np.isfinite(free) and kept > 0 and free > 0):
        return 0.0, False
    lr, yes = _sysid.stability_insists(float(kept), float(free), int(n), int(l), False)
    return float(lr), bool(yes)


def warn_insisted(model: str, pair: str, pole: complex, dt: float, lr: float, option: str,
                  stacklevel: int | None = None) -> None:
    """A :class:`~sysid.StabilityWarning`: ``model`` was held stable, but the search left free
    of the bound (from its fit, and from the least-squares ARX fit when its ``A`` grows) puts
    a pole of ``pair`` at ``pole`` (continuous when ``dt`` is 0, else discrete) with a
    likelihood ratio ``lr`` above the 1 % level (:func:`insists`); ``option`` says how to
    have the unstable model.

    Examples
    --------
    >>> import warnings
    >>> from sysid.pem.boundary import warn_insisted
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     warn_insisted("tfest's model", "y1<-u1", 0.02 + 0j, 0.0, 40.0,
    ...                   "pass enforce_stability=False")
    >>> "s = 0.02" in str(w[0].message), w[0].category.__name__
    (True, 'StabilityWarning')
    """
    p = complex(pole)
    where = f"z = {p:.4g} (modulus {abs(p):.4g})" if dt else f"s = {p:.3g}"
    warnings.warn(
        f"{model} is held stable, but the data insist on an unstable one: the search left "
        f"free of the bound (from the stable fit, and from the least-squares ARX fit when "
        f"its A grows) puts a pole of {pair} at {where} and lowers the criterion "
        f"significantly (likelihood ratio {lr:.3g} > 6.63, the 1 % level of "
        f"chi-square(1)). If the plant is unstable, {option}; if not, look for a drift or an "
        "offset left in the data (sysid.detrend(data, 'linear') removes both)",
        StabilityWarning,
        stacklevel=user_stacklevel() if stacklevel is None else stacklevel + 1)
