"""The first-order uncertainty of a model estimated by another method (a subspace one): a
prediction-error criterion's covariance at it, with no search.

A subspace estimate is not the minimum of any criterion, but near one: the covariance of the
simulation-error criterion at it (:func:`sysid.pem` with ``max_iter=0``: the Gauss-Newton
matrix over the record, with the correction for coloured errors) gives the spread its poles,
gains and responses have. Checked by Monte Carlo against ``n4sid``'s own spread
(``tests/test_subspace_uncertainty.py``); MATLAB's ``n4sid`` reports a covariance by default
as well. An unstable model has no simulation-error criterion; the prediction-error one is
used when its predictor ``A - K C`` is stable (the data insist on the unstable plant).
Under feedback the simulation-error criterion's minimum is biased and its covariance
formula assumes an input independent of the noise: the closed-loop estimators
(:func:`sysid.pbsid`, :func:`sysid.ssarx`) take the prediction-error criterion with their
``K`` (``focus="prediction"``), whose covariance holds in closed loop (Monte Carlo in
``tests/test_subspace_uncertainty.py``). A time series (no input) takes the prediction-error
criterion too: its simulation is zero whatever ``A`` and ``C`` are, so the simulation-error
criterion is flat in them and its covariance tens of times too wide; the prediction-error
one, whose parameters are ``A``, ``C`` and ``K``, matches the estimator's spread (Monte Carlo
in ``tests/test_subspace_uncertainty_ts.py``).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..validation.output_error import feedback_checked

__all__ = ["criterion_at", "attach_criterion_uncertainty"]


def criterion_at(model: Any, data: IOData, focus: str = "simulation") -> tuple[Any, str]:
    """``(fitted, focus)``: ``model`` as :func:`sysid.pem` returns it with no iteration (the
    same ``A, B, C, D``, its uncertainty attached, ``K`` left out in simulation focus) and
    the focus used; ``(None, why)`` when no criterion can be evaluated at it. ``focus``:
    the criterion of a stable model with inputs (an unstable one and a time series always
    take the prediction error); ``"prediction"`` needs the model's ``K`` and a stable
    predictor, else the simulation error is used (a time series has none then).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.pem.at_estimate import criterion_at
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((400, 1))
    >>> y = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]]).simulate(u)
    >>> d = sysid.IOData(u=u, y=y + 0.1 * rng.standard_normal((400, 1)))
    >>> m = sysid.SubspaceEstimator(d, 5).fit(1)
    >>> fitted, focus = criterion_at(m, d)
    >>> focus, bool(np.allclose(fitted.A, m.A)), fitted.poles(std=True)[1].shape
    ('simulation', True, (1,))
    """
    from .pem import pem

    K = getattr(model, "K", None)
    stable_predictor = K is not None and np.max(np.abs(np.linalg.eigvals(
        np.asarray(model.A) - np.asarray(K) @ np.asarray(model.C)))) < 1.0
    if data.n_inputs == 0:
        # no input: the simulation is zero for every A, C, the criterion flat in them
        if not stable_predictor:
            return None, ("a time series has only the prediction-error criterion, and the "
                          "model has no stable predictor A - K C; refine it with "
                          "sysid.ssest(data, model) for a model with uncertainty")
        focus = "prediction"
    if focus == "prediction" and not stable_predictor:
        focus = "simulation"
    # an integrator made explicit (``info["integrating"]``, :mod:`sysid.identify.integrating`)
    # is a pole at exactly 1: the simulation error grows at most linearly, and is defined
    integrating = bool((getattr(model, "info", None) or {}).get("integrating"))
    if not model.is_stable() and not integrating:
        # the simulation-error criterion diverges at an unstable A; the prediction-error one
        # is defined wherever the predictor A - K C is stable
        if not stable_predictor:
            return None, ("the model is unstable and has no stable predictor, so neither "
                          "prediction-error criterion is defined at it; refine it with "
                          "sysid.ssest(data, model) for a model with uncertainty")
        focus = "prediction"
    wt = "output" if data.n_outputs > 1 else None
    try:
        with warnings.catch_warnings(), feedback_checked():  # no fit: no feedback check
            warnings.simplefilter("ignore")
            m = pem(data, model, focus=focus, weighting=wt, max_iter=0,
                    feedthrough=bool(np.any(np.asarray(model.D) != 0)), progress=False)
        if m.uncertainty is None:
            raise ValueError("no covariance")
        if not _same_model(m, model, focus, data.n_inputs):
            raise ValueError("the criterion moved the model")
    except Exception as e:  # noqa: BLE001 - reported to the caller, never raised
        return None, f"could not be evaluated ({type(e).__name__}: {e})"[:300]
    return m, focus


def _same_model(m: Any, model: Any, focus: str, n_inputs: int) -> bool:
    """Whether ``m`` is ``model`` in whatever state basis: the same step response and, in
    prediction focus, the same noise path ``C A^k K`` (all a time series has)."""
    step = np.ones((20, n_inputs))
    if not np.allclose(m.simulate(step), model.simulate(step), rtol=1e-8, atol=1e-12):
        return False
    if focus != "prediction":
        return True

    def markov(s: Any) -> np.ndarray:
        A, C, K = (np.asarray(x, dtype=float) for x in (s.A, s.C, s.K))
        out, P = [], K
        for _ in range(20):
            out.append(C @ P)
            P = A @ P
        return np.array(out)

    return bool(np.allclose(markov(m), markov(model), rtol=1e-8, atol=1e-12))


def attach_criterion_uncertainty(model: Any, data: IOData, focus: str = "simulation") -> Any:
    """``model`` (unchanged, its ``K`` kept) with the uncertainty of :func:`criterion_at`
    (``focus`` as there),
    and ``info["uncertainty"]`` saying what it is (``"criterion"``: the focus used, and why
    when it is not the one asked for), or why there is none. The draws of the uncertainty
    carry the model's initial state, and its ``K`` unless the criterion is the prediction
    error (where ``K`` is a parameter: a draw carries its own).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.pem.at_estimate import attach_criterion_uncertainty
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((400, 1))
    >>> y = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]]).simulate(u)
    >>> d = sysid.IOData(u=u, y=y + 0.1 * rng.standard_normal((400, 1)))
    >>> m = attach_criterion_uncertainty(sysid.SubspaceEstimator(d, 5).fit(1), d)
    >>> m.K is not None, m.uncertainty.build(m.uncertainty.theta).K is not None
    (True, True)
    """
    from .sandwich import through_deferred

    asked = focus
    fitted, focus = criterion_at(model, data, focus)
    if fitted is None:
        model.info["uncertainty"] = {"method": "none", "why": focus}
        return model
    K, noise, x0 = model.K, model.noise_cov, model.x0
    own_k = focus == "prediction"

    def like_model(draw: Any) -> Any:
        draw.K = draw.K if own_k else K
        draw.noise_cov, draw.x0 = noise, x0
        return draw

    model.uncertainty = through_deferred(fitted.uncertainty, like_model)
    model.info["uncertainty"] = {
        "method": f"the {focus}-error criterion's covariance at the estimate (first order, "
                  "no search: sysid.pem(data, model, max_iter=0))",
        "criterion": focus}
    if focus != asked:
        model.info["uncertainty"]["why"] = (
            "the model has no stable predictor A - K C" if focus == "simulation" else
            "a time series: without an input the simulation-error criterion is flat in A, C"
            if data.n_inputs == 0 else "the model is unstable (the data insist on it)")
    return model
