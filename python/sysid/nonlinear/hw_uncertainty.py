"""The parameter uncertainty of the Hammerstein-Wiener fits (:func:`sysid.nlhw`,
:func:`sysid.nlhw_ss`): MATLAB's ``getcov`` / ``getpvec`` for ``idnlhw``.

The searched parameters are the model's ``theta`` (the nonlinearities', the linear block's)
and, about the record's means, the estimated output levels (``y_offset``). Their
Gauss-Newton covariance comes from the search of ``sysid-core`` (``sigma^2 (J^T J)^+`` at the
estimate; with estimated initial states the marginal one of the model's parameters, the
states a nuisance; for :func:`sysid.nlhw_ss` the pseudo-inverse's, zero along the similarity
directions of the free ``A, B, C`` that the data do not determine). The errors the search
minimises are the simulation errors, the output disturbance itself, coloured on nearly every
real record: as for :func:`sysid.oe` and ``pem(focus="simulation")``, the model carries the
sandwich covariance of :mod:`sysid.pem.sandwich`, formed when first used (its Jacobian by
central differences of the simulation along the Gauss-Newton covariance's directions; white
errors keep the Gauss-Newton covariance). An estimated initial state is held at its estimate
and profiled out to first order (:func:`sysid.pem.sandwich.with_fitted_state` on the
simulation's derivative in it at the estimate): the Jacobian is the model parameters' with
the states' directions projected out, so the sandwich is the marginal covariance too.

``model.uncertainty`` is a :class:`~sysid.ParameterUncertainty` whose ``build(theta)``
rebuilds the model: standard deviations of anything computed from it
(``model.uncertainty.propagate(fn)``, ``dcgain(std=True)``, ``poles(std=True)`` and
``freqresp(omega, std=True)`` of the linear block). ``info["covariance"]`` keeps the
Gauss-Newton array (as before); ``info["covariance_method"]`` says which covariance the
uncertainty is. :func:`sysid.save_model` writes it (the stored numbers are linear in the
parameters: the saved map is exact).

Measured (``tests/test_hw_uncertainty.py``, 200 Monte Carlo runs of 1000 samples): a
Hammerstein model (``x + 0.2 x^2 + 0.3 x^3`` into ``0.5 q^-1 / (1 - 0.8 q^-1)``) with an
AR(1) output disturbance (pole 0.9). The Gauss-Newton standard deviations of the pole and of
the steady output at ``u = 0.5`` were 0.40 and 0.35 of the sample ones (95 % intervals
covering 58 % and 52 % of the runs); the sandwich's are 0.95 and 0.97 of them, covering
93.5 % and 94 % (``nlhw_ss``: 0.93 and 0.93, covering 93 % and 93.5 %). White noise: 1.00
and 0.92, covering 93.5 %, as Gauss-Newton's. Two records of 500 samples that start
mid-response, their initial states estimated: Gauss-Newton 0.46 and 0.39 (covering 64 % and
56 %), the sandwich with the states profiled out 1.10 and 1.01 (covering 96.5 % and 95 %).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__: list[str] = []

_STEP = 1e-6


def _state_derivative(sim: Any, x: np.ndarray) -> np.ndarray:
    """``(N, l, n)``: central differences of ``sim(x)`` (``(N, l)``) in the state ``x``."""
    cols = []
    for j in range(x.size):
        h = _STEP * max(1.0, abs(float(x[j])))
        e = np.zeros(x.size)
        e[j] = h
        cols.append((sim(x + e) - sim(x - e)) / (2 * h))
    return np.stack(cols, axis=-1)


def attach(model: Any, covariance: Any, records: Sequence[tuple[np.ndarray, np.ndarray]],
           states: Sequence[np.ndarray] | None) -> None:
    """Give a fitted Hammerstein-Wiener model (either family) its ``uncertainty``: the
    core's Gauss-Newton ``covariance`` over ``model._searched()``, becoming the sandwich for
    coloured simulation errors when first used, on the ``records`` ``(u, y)`` as given to
    the estimator (the model's own units, offsets included); ``states``: the estimated
    initial states per record (``None``: from rest). Without a finite covariance the model
    carries none and ``info["uncertainty"]`` says why."""
    from ..models.uncertainty import ParameterUncertainty
    from ..pem.sandwich import defer_sandwich, with_fitted_state

    theta = model._searched()
    cov = None if covariance is None else np.asarray(covariance, float)
    if cov is None or cov.shape != (theta.size, theta.size) or not np.all(np.isfinite(cov)):
        model.info["uncertainty"] = {
            "method": "none", "why": "the Gauss-Newton matrix at the estimate is not finite "
            "(the search's sensitivities overflow there)"}
        return
    model.uncertainty = ParameterUncertainty(theta, cov, model._rebuilt,
                                             names=model._searched_names(),
                                             method="gauss-newton")
    recs = [(np.asarray(u, float), np.asarray(y, float).reshape(len(y), -1))
            for u, y in records]
    if states is None:
        def sim(m: Any) -> list[np.ndarray]:
            return [m.simulate(u) for u, _ in recs]
    else:
        xs = [np.asarray(x, float).ravel() for x in states]
        derivs: list[np.ndarray] = []  # at the estimate, when the sandwich is formed

        def sim(m: Any) -> list[np.ndarray]:
            if not derivs:
                nominal = model._rebuilt(theta)
                derivs.extend(_state_derivative(lambda x, u=u: nominal._from_state(u, x), x)
                              for (u, _), x in zip(recs, xs))
            return [with_fitted_state(m._from_state(u, x), y, o)
                    for (u, y), x, o in zip(recs, xs, derivs)]
    defer_sandwich(model, sim, [y for _, y in recs], None, key="covariance_method")
