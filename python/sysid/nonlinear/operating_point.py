"""The operating point of a Hammerstein-Wiener model: ``y = y0 + g(L f(u - u0))``.

A Hammerstein-Wiener model is simulated from rest (a zero state), and its linear start (OE,
or a subspace fit) has no constant term. On a record whose signals sit off zero (tank levels,
temperatures, a valve around half open) the linear block then starts far from where the
record runs, a transient as long as its slowest mode, and the start spends its fit on the
offset: on the cascaded-tanks benchmark (levels 2.6 standard deviations off zero) nlhw ended
at a 61.7 % training fit where the linear model had 75.1 %. So :func:`sysid.nlhw` and
:func:`sysid.nlhw_ss` fit the record about its means and keep them in the model
(``u_offset``, ``y_offset``), which adds them back when it simulates: the nonlinearities
then act on the deviations from the operating point.

``offsets="auto"`` (the default) does this when a channel's mean lies farther from zero
than its standard deviation (the operating point is farther off than the signal varies;
closer, the rest state is near it already) and every nonlinearity is a black box (a
``SigmoidNetwork`` or the identity). The others have parameters in the data's own units (a
saturation's or dead zone's levels, breakpoints, a polynomial about zero, a user function),
whose meaning the shift changes (a noise-free record of such a system from rest is then no
longer fitted exactly), but fitted from rest on a record that runs off zero they start far
from it: with such a nonlinearity on such a record both are fitted and the lower sum of
squares is kept (:func:`better_of_both`; with the shift the levels are about the means).
``True`` and ``False`` force it. The threshold was set before any
record was tried; measured (nlhw with sigmoid networks, benches/nonlinear_unshipped.py):
the cascaded tanks (levels 2.6 standard deviations off zero) test RMSE 1.218 -> 0.589, EMPS
(position 1.5 off) 0.0796 -> 0.0269; centred regardless, the Wiener-Hammerstein benchmark
(0.16 off) landed in a worse minimum (training sum of squares 20.4 -> 128).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError

__all__ = ["has_levels", "use_offsets", "undecided", "better_of_both", "record_means",
           "centred"]


def has_levels(nl: Any) -> bool:
    """Whether a nonlinearity's parameters are in the data's own units (everything but a
    sigmoid network and the identity).

    Examples
    --------
    >>> import sysid
    >>> from sysid.nonlinear.operating_point import has_levels
    >>> has_levels(sysid.SigmoidNetwork(3)), has_levels(sysid.Saturation())
    (False, True)
    """
    from .hw_model import Nonlinearity, SigmoidNetwork

    return not (isinstance(nl, SigmoidNetwork) or type(nl) is Nonlinearity)


def use_offsets(offsets: Any, nls: list[Any], exps: list[tuple[np.ndarray, np.ndarray]]
                ) -> bool:
    """Resolve ``offsets`` (``"auto"``, ``True`` or ``False``) for these nonlinearities and
    experiments (the module docstring has the rule)."""
    if isinstance(offsets, (bool, np.bool_)):
        return bool(offsets)
    if offsets != "auto":
        raise DataError(f"offsets must be 'auto', True or False, got {offsets!r}")
    if any(has_levels(nl) for nl in nls):
        return False
    return _off_zero(exps)


def _off_zero(exps: list[tuple[np.ndarray, np.ndarray]]) -> bool:
    """A channel's mean farther from zero than its standard deviation."""
    z = np.hstack([np.concatenate([u for u, _ in exps]), np.concatenate([y for _, y in exps])])
    return bool(np.any(np.abs(z.mean(axis=0)) > z.std(axis=0)))


def undecided(offsets: Any, nls: list[Any], exps: list[tuple[np.ndarray, np.ndarray]]
              ) -> bool:
    """``offsets="auto"`` that the rule leaves open: a nonlinearity with levels in the
    data's units on a record off zero. Fitted from rest without offsets, such a model starts
    far from where the record runs (a saturation about u = 5 fitted a noise-free record of
    itself at 71 %; about its means, 97 %), while a record that truly starts from rest is
    fitted exactly only without them: both are fitted and the lower sum of squares kept
    (:func:`better_of_both`)."""
    return (isinstance(offsets, str) and offsets == "auto"
            and any(has_levels(nl) for nl in nls) and _off_zero(exps))


def better_of_both(fit: Any) -> Any:
    """``fit(False)`` and ``fit(True)`` (each with its own copies of the nonlinearities),
    the one with the lower final sum of squares, its warnings said and the choice in
    ``info["offsets"]["auto"]``."""
    import warnings

    results = []
    for shift in (False, True):
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            model = fit(shift)
        results.append((float(model.info["cost"][-1]), model, said))
    (c0, m0, w0), (c1, m1, w1) = results
    model, said = (m1, w1) if c1 < c0 else (m0, w0)
    for w in said:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    model.info["offsets"]["auto"] = (
        f"fitted without and with the record's means as the operating point (sums of squares "
        f"{2 * c0:.6g} and {2 * c1:.6g}): " + ("with" if c1 < c0 else "without") + " kept")
    return model


def record_means(exps: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """Per channel the means of the inputs and the outputs over every experiment."""
    u = np.concatenate([u for u, _ in exps])
    y = np.concatenate([y for _, y in exps])
    return u.mean(axis=0), y.mean(axis=0)


def centred(exps: list[tuple[np.ndarray, np.ndarray]], u0: np.ndarray, y0: np.ndarray
            ) -> list[tuple[np.ndarray, np.ndarray]]:
    """The experiments about ``(u0, y0)``."""
    return [(u - u0, y - y0) for u, y in exps]
