"""``feedthrough="auto"`` for frequency-response data: estimate ``D`` when the lines held out
of the fit say so.

A response with a direct term (an accelerometer driven by a force: ``G(s) -> D`` at high
frequency) fitted without ``D`` misses the whole upper band (the F-16 ground-vibration BLA,
2-15 Hz: 89 % relative error at order 8 without ``D``, 24 % with it). The decision is the time
records' (:func:`sysid.subspace.feedthrough.choose_feedthrough`) in the frequency domain:
both structures are fitted by :func:`sysid.frd_subspace` on every other line and scored on
the lines between (two folds, each line held out once), by the relative squared error of the
response (each line weighed by its inverse variance when the FRD has a ``std``). ``D`` is
estimated when it lowers that error by more than a tenth: a response that needs it misses a
whole band without it (a tenfold error on the F-16), while one that does not gains a few per
cent from the extra parameters (the dryer's smoothed response: 0.0107 against 0.0109); a
smaller gain keeps MATLAB's default, no ``D``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import SysidError

__all__ = ["choose_feedthrough_frd", "warn_if_left_out_frd"]

#: the held-out error with D must be below this share of the error without it
MARGIN = 0.9
#: a relative squared error this small is round-off: D is not needed
ROUND_OFF = 1e-20


def choose_feedthrough_frd(frd: Any, order: Any, fit: Any) -> tuple[bool, dict[str, Any]]:
    """Whether ``feedthrough="auto"`` estimates ``D`` for this FRD, and why.

    Parameters
    ----------
    frd : FRD
        The response.
    order : int or "auto"
        The order both fits use; ``"auto"``: each structure at the order ``fit`` picks for it
        on all the lines.
    fit : callable
        ``fit(frd, order, feedthrough) -> model``: :func:`sysid.frd_subspace` with the
        caller's other settings (discrete for a discrete FRD, continuous for one without
        ``dt``).

    Returns
    -------
    (bool, dict)
        The decision and ``{"feedthrough", "criterion", "held_out_error", "reason"}``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.subspace.feedthrough_frd import choose_feedthrough_frd
    >>> true = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], [[0.7]])
    >>> w = np.linspace(0.05, 3.0, 60)
    >>> fit = lambda g, n, d: sysid.frd_subspace(g, n, feedthrough=d)
    >>> choose_feedthrough_frd(sysid.FRD(w, true.freqresp(w), dt=1.0), 1, fit)[0]
    True
    """
    nf = frd.omega.size
    weight = (np.ones(frd.response.shape) if frd.std is None
              else 1.0 / np.maximum(np.asarray(frd.std, float), 1e-300) ** 2)
    errors: dict[bool, float] = {}
    try:
        for ft in (False, True):
            n = order if not isinstance(order, str) else fit(frd, "auto", ft).nstates
            num = den = 0.0
            for k in (0, 1):
                held = np.arange(nf) % 2 == k
                model = fit(frd.fselect(~held), n, ft)
                g = np.asarray(frd.response)[held]
                e = np.asarray(model.freqresp(frd.omega[held])) - g
                num += float(np.sum(weight[held] * np.abs(e) ** 2))
                den += float(np.sum(weight[held] * np.abs(g) ** 2))
            errors[ft] = num / max(den, 1e-300) if np.isfinite(num) else np.inf
    except SysidError as e:
        return False, {"feedthrough": False, "criterion": "none",
                       "reason": f"not decided from the lines ({e}): no feedthrough"}
    # (lines fitted to round-off without D, as exact data of a system without one, leave
    # nothing for D to explain)
    use = bool(errors[True] < MARGIN * errors[False] and errors[False] > ROUND_OFF)
    said = "with" if use else "without"
    return use, {"feedthrough": use, "criterion": "held-out lines",
                 "held_out_error": {"without": errors[False], "with": errors[True]},
                 "reason": (f"{said} D: relative squared error on the held-out lines "
                            f"{errors[True]:.3g} with D, {errors[False]:.3g} without (every "
                            "other line fitted, the others scored, both ways)")}


def warn_if_left_out_frd(frd: Any, model: Any, refit: Any, who: str) -> dict[str, Any] | None:
    """Warn (:class:`~sysid.errors.FeedthroughWarning`) when ``model``, fitted to ``frd``
    without ``D`` by default, leaves out a direct term the response shows: ``refit(True)``
    (the same fit with ``D``) has a relative squared error on the lines at least
    ``LEFT_OUT_RATIO`` times smaller. Kept in ``model.info["feedthrough_check"]``.

    Examples
    --------
    >>> import numpy as np, sysid, warnings
    >>> from sysid.subspace.feedthrough_frd import warn_if_left_out_frd
    >>> true = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], [[0.7]])
    >>> w = np.linspace(0.05, 3.0, 60)
    >>> g = sysid.FRD(w, true.freqresp(w), dt=1.0)
    >>> fit = lambda d: sysid.frd_subspace(g, 1, feedthrough=d)
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     check = warn_if_left_out_frd(g, fit(False), fit, "frd_subspace")
    >>> [type(x.message).__name__ for x in caught], check["ratio"] > 2
    (['FeedthroughWarning'], True)
    """
    import warnings

    from .._checks import user_stacklevel
    from ..errors import FeedthroughWarning
    from .feedthrough import LEFT_OUT_RATIO

    g = np.asarray(frd.response)
    if np.max(np.abs(model.D), initial=0.0) > 1e-9 * np.max(np.abs(g), initial=0.0):
        return None  # it has a D (a continuous fit's Tustin map leaves round-off there)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with_d = refit(True)
    except SysidError:  # a check that cannot be made says nothing
        return None

    def err(m: Any) -> float:
        return float(np.sum(np.abs(np.asarray(m.freqresp(frd.omega)) - g) ** 2))
    without, with_ = err(model), err(with_d)
    scale = float(np.sum(np.abs(g) ** 2))
    ratio = without / with_ if with_ > 0 else np.inf
    if not without > ROUND_OFF * scale:
        ratio = 1.0  # fitted to round-off without D
    check = {"ratio": ratio, "threshold": LEFT_OUT_RATIO,
             "what": "squared error on the lines of the fit without D over that with D"}
    model.info["feedthrough_check"] = check
    if ratio >= LEFT_OUT_RATIO:
        warnings.warn(
            f"{who} fitted no direct term (D = 0, the default), but the response shows one: "
            f"with D estimated its error on the lines is {ratio:.3g} times smaller (the "
            "response does not roll off, as an acceleration driven by a force). Pass "
            "feedthrough=True, or feedthrough='auto' to decide on held-out lines",
            FeedthroughWarning, stacklevel=user_stacklevel())
    return check
