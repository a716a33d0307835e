"""The covariance of a :func:`sysid.greyest` fit whose errors are coloured.

With ``focus="simulation"`` the errors the search minimises are the output disturbance
itself; its Gauss-Newton covariance assumes them white and was a third of the spread on a
mass-spring-damper with an AR(1) disturbance. The sandwich of :mod:`sysid.pem.sandwich`
(the one :func:`sysid.ssest`, :func:`sysid.oe` and :func:`sysid.tfest` carry) is formed on
the sampled model the search simulated, every record, an estimated initial state fitted
again for every parameter vector (the free parameters' covariance with it profiled out),
the errors weighted as the criterion weighted them (``weighting="noise"``: the inverse of
their covariance). ``info["covariance"]`` says which covariance the estimate carries.

A nonlinear structure's errors are always simulation errors: :func:`defer_nonlinear` gives
its estimate the same sandwich, formed when first used (each direction costs two
simulations, Python calls of ``f``), on every searched quantity (estimated initial states
included, each record's simulation started from its own).

With ``focus="prediction"`` and a noise model ``K`` the errors are the one-step prediction
errors, white only when ``K`` can take the disturbance's shape: :func:`prediction_covariance`
forms the sandwich of :mod:`sysid.pem.prediction_sandwich` for them.
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
    weights = _weights(fit.reweight, res)
    if isinstance(weights, str):
        est.info["covariance"] = weights
        return
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
    if got is not None:
        _install(est, fit, got.covariance, got.method, got.dof)


def prediction_covariance(fit: Any, res: dict[str, Any], est: Any) -> None:
    """``est`` (the linear fit ``fit`` with a noise model ``K``, the core's result ``res``)
    with the sandwich covariance of :func:`sysid.pem.prediction_sandwich.prediction_sandwich`
    when its prediction errors are coloured (the structure's noise model cannot take the
    disturbance's shape): formed on every searched quantity (the free parameters, the
    entries of a free ``K``, estimated initial states), the free parameters' block kept.
    ``info["covariance"]`` says which covariance the estimate carries."""
    from ..pem.prediction_sandwich import prediction_errors, state_space_sandwich
    from ..pem.sandwich import MAX_ENTRIES

    n, m, l = fit.n, fit.m, fit.l
    z_hat = np.asarray(res["p"], float)
    size = sum(y.shape[0] for _, y in fit.exps) * l * z_hat.size
    if size > MAX_ENTRIES:
        est.info["covariance"] = (f"gauss-newton, as for white errors: the coloured-error "
                                  f"correction would hold {size:.2g} numbers (at most "
                                  f"{MAX_ENTRIES:.0e})")
        return
    weights = _weights(fit.reweight, res)
    if isinstance(weights, str):
        est.info["covariance"] = weights
        return

    def unpack(z: np.ndarray) -> tuple[Any, ...]:  # A, B, C, D, K, each record's x0
        th = fit.theta(z, False)[0]
        sizes = [n * n, n * m, l * n, l * m, n * l]
        A, B, C, D, K = (th[a:a + s] for a, s in zip(np.cumsum([0, *sizes[:-1]]), sizes))
        x0 = th[sum(sizes):]
        return (A.reshape(n, n), B.reshape(n, m), C.reshape(l, n), D.reshape(l, m),
                K.reshape(n, l), [x0[e * n:(e + 1) * n] for e in range(len(fit.exps))])

    def errors(z: np.ndarray) -> list[np.ndarray]:
        A, B, C, D, K, x0s = unpack(z)
        return prediction_errors(A, B, C, D, K, fit.exps, x0s)

    with np.errstate(all="ignore"):
        cols: list[list[np.ndarray]] = [[] for _ in fit.exps]
        for i in range(z_hat.size):
            h = 1e-6 * max(1.0, abs(z_hat[i]))
            up, dn = z_hat.copy(), z_hat.copy()
            up[i] += h
            dn[i] -= h
            for c, a, b in zip(cols, errors(up), errors(dn)):
                c.append((a - b) / (2 * h))
        jac = [np.stack(c, axis=-1) for c in cols]
    A, B, C, D, K, x0s = unpack(z_hat)
    P, note = state_space_sandwich(jac, A, B, C, D, K, fit.exps, x0s, weights)
    est.info["covariance"] = note
    if P is not None:
        S = np.diag(fit.scale)
        _install(est, fit, S @ P[:fit.nf, :fit.nf] @ S,
                 "gauss-newton with coloured prediction errors (sandwich)", None)


def defer_nonlinear(est: Any, res: dict[str, Any], exps: list[tuple[np.ndarray, np.ndarray]],
                    X: np.ndarray, free_x0: list[tuple[int, int]], reweight: bool,
                    limits: tuple[np.ndarray, np.ndarray]) -> None:
    """``est`` (a :class:`~sysid.greybox.results.GreyEstimate` of a
    :class:`sysid.NonlinearGreyBox` fit, the core's result ``res``) with its Gauss-Newton
    covariance becoming the sandwich for coloured simulation errors when first used (a
    standard deviation, the table, ``est.covariance``, a band, saving): formed on every
    searched quantity, the free parameters and the estimated initial-state entries
    ``free_x0`` (``(experiment, state)``; ``X`` the initial states at the estimate), from
    the Jacobian of the simulations of every record (``exps``, independent) weighted as the
    criterion weighted the errors, and the free parameters' block kept (their covariance
    with the initial states estimated beside them). ``limits`` are the table's bounds.
    ``info["covariance"]`` says which covariance the estimate carries."""
    from ..pem.sandwich import DeferredSandwich, DeferredTable, sandwich_covariance

    model, info = est.model, est.info
    base = model.uncertainty
    weights = _weights(reweight, res)
    if isinstance(weights, str):
        info["covariance"] = weights
        return
    nf = base.theta.size
    theta = np.asarray(res["theta"], float)
    cov_all = np.asarray(res["covariance"], float)

    def build(t: np.ndarray) -> tuple[Any, np.ndarray]:  # every searched quantity
        x = X.copy()
        for k, (e, i) in enumerate(free_x0):
            x[e, i] = t[nf + k]
        return base.build(t[:nf]), x

    def sim(mx: tuple[Any, np.ndarray]) -> list[np.ndarray]:
        m, x = mx
        return [m.simulate(u, x0=x[e]) for e, (u, _) in enumerate(exps)]

    def form() -> tuple[ParameterUncertainty | None, str]:
        full = ParameterUncertainty(theta, cov_all, build)
        got, note = sandwich_covariance(full, sim, [y for _, y in exps], weights)
        if got is None:
            return None, note
        return ParameterUncertainty(base.theta, got.covariance[:nf, :nf], base.build,
                                    names=base.names, dof=base.dof, method=got.method,
                                    undetermined=base.undetermined), note

    def then(note: str) -> None:
        info["covariance"] = note
        info["greybox"]["parameters"] = est.parameters.rows()

    info["covariance"] = ("gauss-newton until first used, then the sandwich for coloured "
                          "simulation errors")
    model.uncertainty = DeferredSandwich(base, form, then)
    est.covariance = model.uncertainty
    names = list(est.parameters.names)
    est.parameters = DeferredTable(est.parameters, model.uncertainty, limits,
                                   rows=[names.index(k) for k in base.names])


def _weights(reweight: bool, res: dict[str, Any]) -> Any:
    """The errors' weighting of a fit that reweights (the inverse Cholesky factor of the
    innovations' covariance), None for one that does not, or the reason the Gauss-Newton
    covariance stays (a singular covariance)."""
    if not reweight:
        return None
    try:
        return np.linalg.inv(np.linalg.cholesky(
            np.atleast_2d(np.asarray(res["innovation_covariance"], float))))
    except np.linalg.LinAlgError:
        return "gauss-newton, as for white errors (the errors' covariance is singular)"


def _install(est: Any, fit: Any, P: np.ndarray, method: str, dof: int | None) -> None:
    """``est`` carrying the covariance ``P`` of its free parameters: its ``covariance``,
    parameter table and model's uncertainty."""
    unc = est.model.uncertainty
    est.covariance = P
    est.model.uncertainty = ParameterUncertainty(
        unc.theta, P, unc.build, names=unc.names, dof=dof, method=method,
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
