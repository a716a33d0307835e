"""The covariance of a simulation-focus :func:`sysid.greyest` fit whose errors are coloured.

With ``focus="simulation"`` the errors the search minimises are the output disturbance
itself; its Gauss-Newton covariance assumes them white and was a third of the spread on a
mass-spring-damper with an AR(1) disturbance. The sandwich of :mod:`sysid.pem.sandwich`
(the one :func:`sysid.ssest`, :func:`sysid.oe` and :func:`sysid.tfest` carry) is formed on
the sampled model the search simulated, every record, an estimated initial state fitted
again for every parameter vector (the free parameters' covariance with it profiled out),
the errors weighted as the criterion weighted them (``weighting="noise"``: the inverse of
their covariance). ``info["covariance"]`` says which covariance the estimate carries.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..models.paramtable import ParameterTable
from ..models.statespace import StateSpaceModel
from ..models.uncertainty import ParameterUncertainty

__all__: list[str] = []


def coloured_covariance(fit: Any, res: dict[str, Any], est: Any) -> None:
    """``est`` (a :class:`~sysid.greybox.results.GreyEstimate` of the linear fit ``fit``,
    the core's result ``res``) with the sandwich covariance for coloured simulation errors:
    its ``covariance``, parameter table and model's uncertainty (same parameters, same
    order). Nothing changes where the correction is not formed (``info["covariance"]``
    says why)."""
    from ..pem.sandwich import free_response, sandwich_covariance, with_fitted_state

    unc = est.model.uncertainty
    n, m, l = fit.n, fit.m, fit.l
    z_hat = np.asarray(res["p"], float)
    if fit.reweight:
        lam = np.atleast_2d(np.asarray(res["innovation_covariance"], float))
        try:
            weights: Any = np.linalg.inv(np.linalg.cholesky(lam))
        except np.linalg.LinAlgError:
            est.info["covariance"] = ("gauss-newton, as for white errors (the errors' "
                                      "covariance is singular)")
            return
    else:
        weights = None
    estimated = [isinstance(md, str) and md == "estimate" for md in fit.modes]

    def sampled(values: np.ndarray) -> np.ndarray:  # free values -> the sampled model, x0s
        z = z_hat.copy()
        z[:fit.nf] = np.asarray(values, float) / fit.scale
        return fit.theta(z, False)[0]

    def sim(th: np.ndarray) -> list[np.ndarray]:
        sizes = [n * n, n * m, l * n, l * m]
        A, B, C, D = (th[a:a + s] for a, s in zip(np.cumsum([0, *sizes[:-1]]), sizes))
        A, C = A.reshape(n, n), C.reshape(l, n)
        ss = StateSpaceModel(A, B.reshape(n, m), C, D.reshape(l, m), dt=fit.dt)
        row = sum(sizes)
        out = []
        for e, ((u, y), est_x0) in enumerate(zip(fit.exps, estimated)):
            if est_x0:
                out.append(with_fitted_state(ss.simulate(u), y, free_response(A, C, len(y)),
                                             weights))
            else:
                out.append(ss.simulate(u, th[row + e * n:row + (e + 1) * n]))
        return out

    work = ParameterUncertainty(unc.theta, unc.covariance, sampled, names=unc.names,
                                dof=unc.dof, undetermined=unc.undetermined)
    got, note = sandwich_covariance(work, sim, [y for _, y in fit.exps], weights)
    est.info["covariance"] = note
    if got is None:
        return
    P = got.covariance
    est.covariance = P
    est.model.uncertainty = ParameterUncertainty(
        unc.theta, P, unc.build, names=unc.names, dof=got.dof, method=got.method,
        undetermined=unc.undetermined)
    est.parameters = _with_std(est.parameters, fit, P)


def _with_std(t: ParameterTable, fit: Any, P: np.ndarray) -> ParameterTable:
    """The table ``t`` with the free parameters' standard deviations from ``P`` (an
    undetermined one's stays infinite), the intervals cut at the bounds."""
    std = t.std.copy()
    for i, k in enumerate(fit.free):
        j = t.names.index(k)
        if np.isfinite(std[j]):
            std[j] = float(np.sqrt(max(P[i, i], 0.0)))
    out = ParameterTable(t.names, t.value, std, t.fixed, t.bound, t.units, t.descriptions)
    return out.cut_at_bounds(*np.array([fit.s.params[k].bounds for k in t.names], float).T)
