"""Gramians, Hankel singular values, balanced realisation and truncation, for discrete and
continuous models, stable or not (as MATLAB's ``gram``, ``hsvd``, ``balreal`` and ``balred``).

A stable discrete model's gramians solve ``Wc = A Wc A' + B B'`` and ``Wo = A' Wo A + C' C``
(Smith doubling in the Rust core), a continuous one's ``A Wc + Wc A' + B B' = 0`` and
``A' Wo + Wo A + C' C = 0``; the Hankel singular values are ``sqrt(eig(Wc Wo))``. Balancing
uses the square-root method, and truncation to r states keeps the r largest Hankel singular
values with the H-infinity error bound ``2 * sum(discarded)``.

An unstable model (a pole on or outside the unit circle, or in the closed right half-plane,
within a relative margin of ``1e-8``) has no gramians, so :func:`gramians` refuses it; the
other functions split it into stable and unstable parts
(:mod:`sysid.analysis.stable_split`) and work on the stable part: the Hankel singular values
start with one ``inf`` per unstable pole, :func:`balanced_realization` keeps the unstable
states (first) and balances the rest, :func:`balanced_truncation` keeps the unstable part and
reduces the stable one.

Examples
--------
>>> import numpy as np, sysid
>>> m = sysid.StateSpaceModel([[0.9, 0.0], [0.0, 0.2]], [[1.0], [0.01]], [[1.0, 0.01]])
>>> np.round(sysid.hankel_singular_values(m), 3)
array([5.263, 0.   ])
>>> sysid.balanced_truncation(m, 1).nstates
1
>>> u = sysid.StateSpaceModel(np.diag([1.5, 0.5]), [[1.0], [1.0]], [[1.0, 1.0]])
>>> sysid.hankel_singular_values(u)    # one unstable pole: inf, then the stable part
array([       inf, 1.33333333])
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg

from .. import _sysid
from .._checks import as_int
from ..errors import DataError
from ..models.checks import as_statespace, check_model, discrete_statespace
from ..models.statespace import StateSpaceModel
from .stable_split import is_stable_pole, split_stable

__all__ = [
    "Gramians",
    "gramians",
    "hankel_singular_values",
    "balanced_realization",
    "balanced_truncation",
]

_ABCD = ("A", "B", "C", "D")


def _check(model: Any) -> StateSpaceModel:
    """The model's discrete state-space form (any :class:`sysid.Model` with one)."""
    if isinstance(model, StateSpaceModel):
        return model
    ss = discrete_statespace(model, "balanced realisation")
    if not isinstance(ss, StateSpaceModel):
        ss = StateSpaceModel(ss.A, ss.B, ss.C, ss.D, dt=ss.dt, input_names=model.input_names,
                             output_names=model.output_names)
    return ss


def _state_space(model: Any, purpose: str) -> Any:
    """A continuous model (``dt = 0``) in state-space form (e.g. a
    :class:`sysid.ContinuousStateSpace`, also from a continuous transfer function), or
    :func:`_check`'s discrete form."""
    if getattr(model, "dt", None) != 0:
        return _check(model)
    model = check_model(model)
    ss = model if all(hasattr(model, k) for k in _ABCD) else as_statespace(model, purpose)
    if not all(hasattr(ss, k) for k in _ABCD) or ss.dt != 0:
        raise DataError(f"{type(model).__name__}.to_statespace() returned a "
                        f"{type(ss).__name__}, not a continuous state-space model")
    return ss


def _unstable_poles(m: Any) -> np.ndarray:
    """The poles of ``m`` that :mod:`~sysid.analysis.stable_split` counts as unstable."""
    p = np.linalg.eigvals(m.A) if m.nstates else np.zeros(0, complex)
    return p[~is_stable_pole(p, m.dt)]


def _require_stable(m: Any) -> None:
    """A :class:`DataError` naming the first unstable pole of ``m``, if it has one."""
    bad = _unstable_poles(m)
    if not bad.size:
        return
    p = complex(bad[np.argmax(np.abs(bad) if m.dt else bad.real)])
    shown = f"{p.real:.6g}" if p.imag == 0 else f"{p:.6g}"
    where = (f"has modulus {abs(p):.10g} (stable poles need |z| < 1 - 1e-8)" if m.dt else
             f"has real part {p.real:.6g} (stable poles need Re s < -1e-8 max(1, |s|))")
    raise DataError(
        f"the model is not stable: {bad.size} pole(s) on or beyond the stability boundary, "
        f"e.g. {shown}, which {where}, so its gramians do not exist. For an unstable model "
        "use sysid.hankel_singular_values (inf for each unstable pole, then the stable "
        "part's), sysid.balanced_realization or sysid.balanced_truncation (which keep the "
        "unstable part and balance or reduce the stable one)")


def _continuous_gramians(A: np.ndarray, B: np.ndarray, C: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray]:
    """``A Wc + Wc A' + B B' = 0`` and ``A' Wo + Wo A + C' C = 0`` (A stable), symmetrised."""
    wc = scipy.linalg.solve_continuous_lyapunov(A, -B @ B.T)
    wo = scipy.linalg.solve_continuous_lyapunov(A.T, -C.T @ C)
    return 0.5 * (wc + wc.T), 0.5 * (wo + wo.T)


def _continuous_square_root(A: np.ndarray, B: np.ndarray, C: np.ndarray
                            ) -> tuple[np.ndarray, ...]:
    """``(Lc, Lo, U, hsv, Vt)``: gramian factors ``L L' = W`` and the SVD of ``Lo' Lc``."""
    wc, wo = _continuous_gramians(A, B, C)

    def factor(w: np.ndarray) -> np.ndarray:  # L with L L' = w (w is semi-definite)
        lam, V = np.linalg.eigh(w)
        return V * np.sqrt(np.clip(lam, 0.0, None))

    lc, lo = factor(wc), factor(wo)
    U, hsv, Vt = np.linalg.svd(lo.T @ lc)
    return lc, lo, U, hsv, Vt


def _stable_hsv(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray, dt: float
                ) -> np.ndarray:
    """Hankel singular values of a stable ``(A, B, C, D)`` (``dt = 0``: continuous)."""
    if A.shape[0] == 0:
        return np.zeros(0)
    if dt:
        return np.asarray(_sysid.hankel_singular_values(A, B, C, D))
    return _continuous_square_root(A, B, C)[3]


@dataclass(frozen=True)
class Gramians:
    """Controllability and observability gramians of a stable model.

    Attributes
    ----------
    controllability : ndarray
        ``Wc = A Wc A' + B B'`` (continuous: ``A Wc + Wc A' + B B' = 0``), ``(n, n)``.
    observability : ndarray
        ``Wo = A' Wo A + C' C`` (continuous: ``A' Wo + Wo A + C' C = 0``), ``(n, n)``.
    """

    controllability: np.ndarray
    observability: np.ndarray

    def __repr__(self) -> str:
        n = self.controllability.shape[0]
        return (f"Gramians(n={n}, trace Wc={np.trace(self.controllability):.4g}, "
                f"trace Wo={np.trace(self.observability):.4g})")


def gramians(model: Any) -> Gramians:
    """Controllability and observability gramians of a stable model (as MATLAB's ``gram``).

    A discrete model's solve the discrete Lyapunov equations, a continuous model's
    (:class:`sysid.ContinuousStateSpace`, ``dt = 0``) the continuous ones
    ``A Wc + Wc A' + B B' = 0`` and ``A' Wo + Wo A + C' C = 0``.

    Parameters
    ----------
    model : StateSpaceModel or ContinuousStateSpace
        A stable model (any :class:`sysid.Model` with a state-space form).

    Returns
    -------
    Gramians
        ``controllability`` and ``observability``, ``(n, n)`` each.

    Raises
    ------
    DataError
        For an unstable model (a pole on or beyond the stability boundary, within a relative
        margin of ``1e-8``), whose gramians do not exist; the message names the pole and
        points to :func:`hankel_singular_values` and :func:`balanced_truncation`, which
        handle unstable models.

    Examples
    --------
    >>> import sysid
    >>> g = sysid.gramians(sysid.StateSpaceModel([[0.5]], [[1.0]], [[2.0]]))
    >>> round(float(g.controllability[0, 0]), 12), round(float(g.observability[0, 0]), 12)
    (1.333333333333, 5.333333333333)
    >>> gc = sysid.gramians(sysid.ContinuousStateSpace([[-2.0]], [[1.0]], [[2.0]]))
    >>> float(gc.controllability[0, 0]), float(gc.observability[0, 0])
    (0.25, 1.0)
    """
    m = _state_space(model, "gramians")
    _require_stable(m)
    if m.dt:
        wc, wo = _sysid.gramians(m.A, m.B, m.C, m.D)
    else:
        wc, wo = _continuous_gramians(m.A, m.B, m.C)
    return Gramians(wc, wo)


def hankel_singular_values(model: Any) -> np.ndarray:
    """Hankel singular values, decreasing; ``inf`` first for each unstable pole.

    As MATLAB's ``hsvd``: an unstable model (poles on or outside the unit circle, or in the
    closed right half-plane, within a relative margin of ``1e-8``) is split into stable and
    unstable parts (:mod:`sysid.analysis.stable_split`); the result is one ``inf`` per
    unstable pole followed by the Hankel singular values of the stable part. A continuous
    model (:class:`sysid.ContinuousStateSpace`) uses its continuous gramians.

    Parameters
    ----------
    model : StateSpaceModel or ContinuousStateSpace
        The model (any :class:`sysid.Model` with a state-space form).

    Returns
    -------
    ndarray
        ``(nstates,)``: ``inf`` for the unstable poles, then decreasing.

    Examples
    --------
    >>> import sysid
    >>> sysid.hankel_singular_values(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.5]]))
    array([2.])
    >>> sysid.hankel_singular_values(sysid.ContinuousStateSpace([[1.0, 0.0], [0.0, -2.0]],
    ...                                                           [[1.0], [1.0]], [[1.0, 2.0]]))
    array([inf, 0.5])
    """
    m = _state_space(model, "hankel_singular_values")
    if not _unstable_poles(m).size:
        return _stable_hsv(m.A, m.B, m.C, m.D, m.dt)
    split = split_stable(m.A, m.B, m.C, m.dt)
    nu = m.nstates - split.n_stable
    return np.r_[np.full(nu, np.inf), _stable_hsv(*split.stable, m.D, m.dt)]


def _reduce(model: StateSpaceModel, order: int | None, method: str) -> StateSpaceModel:
    m = _check(model)
    if order is not None:
        order = as_int(order, "order")
    out = _sysid.balanced_truncation(m.A, m.B, m.C, m.D, None if order is None else int(order))
    t_inv = np.asarray(out["t_inv"])
    info = dict(m.info)
    info.update(
        method=method,
        reduced_from=m.nstates,
        hankel_singular_values=np.asarray(out["hankel_singular_values"]),
        error_bound=float(out["error_bound"]) + 0.0,  # never -0.0 (nothing discarded)
        T=np.asarray(out["t"]),
        T_inv=t_inv,
    )
    return StateSpaceModel(
        out["a"], out["b"], out["c"], out["d"],
        None if m.K is None else t_inv @ m.K,
        dt=m.dt, noise_cov=m.noise_cov, x0=None if m.x0 is None else t_inv @ m.x0,
        input_names=m.input_names, output_names=m.output_names, info=info,
    )


def balanced_realization(model: Any) -> Any:
    """Balanced realisation: both gramians equal ``diag(hankel_singular_values)``.

    As MATLAB's ``balreal``, an unstable model keeps its unstable part unchanged and only
    the stable part is balanced: the model is split (:mod:`sysid.analysis.stable_split`) and
    the result has the unstable states first, decoupled from the balanced stable ones, in the
    order of :func:`hankel_singular_values` (``inf`` first). A continuous model
    (:class:`sysid.ContinuousStateSpace`) is balanced with its continuous gramians and stays
    continuous. The stable part must be minimal (use :func:`balanced_truncation` otherwise).
    A Kalman gain and initial state are transformed with the states, and so is the parameter
    uncertainty (each draw in the same basis, :func:`sysid.models.carried.carry_basis`).

    ``info`` of the result holds ``hankel_singular_values`` (with the ``inf``),
    ``unstable_states`` and the transformation ``T``, ``T_inv`` (``x_balanced = T_inv x``).

    Parameters
    ----------
    model : StateSpaceModel or ContinuousStateSpace
        The model (any :class:`sysid.Model` with a state-space form).

    Returns
    -------
    StateSpaceModel or ContinuousStateSpace
        The balanced model, of the same kind and order.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.5, 0.2], [0.0, 0.3]], [[1.0], [1.0]], [[1.0, -0.5]])
    >>> g = sysid.gramians(sysid.balanced_realization(m))
    >>> bool(np.allclose(g.controllability, g.observability))
    True
    >>> u = sysid.StateSpaceModel([[1.5, 0.3], [0.0, 0.5]], [[1.0], [1.0]], [[1.0, 1.0]])
    >>> b = sysid.balanced_realization(u)     # the unstable state first, then balanced
    >>> round(float(b.A[0, 0]), 12), b.info["unstable_states"]
    (1.5, 1)
    """
    from ..models.carried import carry_basis

    m = _state_space(model, "balanced_realization")
    if m.dt and not _unstable_poles(m).size:
        out = _reduce(m, None, "balanced")
        out.info["unstable_states"] = 0
    else:
        out = _truncate_split(m, m.nstates, continuous=not m.dt, realization=True)
    return carry_basis(m, out, out.info["T"], out.info["T_inv"])


def balanced_truncation(model: Any, order: Any) -> Any:
    """Balanced truncation to ``order`` states; an unstable part is kept unchanged.

    As MATLAB's ``balred``, the model is split into stable and unstable parts
    (:mod:`sysid.analysis.stable_split`: ordered Schur form and a Sylvester equation); the
    stable part is balanced and truncated, the unstable part (poles on or outside the unit
    circle, or in the closed right half-plane) added back unchanged, its states first (as
    :func:`balanced_realization` orders them). ``order`` counts all the states and must be at
    least the number of unstable poles. A stable model is truncated as a whole, as before.

    ``info`` of the result holds ``hankel_singular_values`` (of the stable part),
    ``error_bound`` (``2 * sum`` of the discarded ones, a bound on the H-infinity error, which
    comes from the stable part only), ``unstable_states`` and the projections ``T`` and
    ``T_inv`` (``x_reduced = T_inv x``). A Kalman gain and initial state are projected with
    the states. A continuous model (:class:`sysid.ContinuousStateSpace`) is balanced with its
    continuous gramians (``A W + W A' + B B' = 0``; square-root method) and stays continuous.

    Parameters
    ----------
    model : StateSpaceModel or ContinuousStateSpace
        The model (any :class:`sysid.Model` with a state-space form).
    order : int or sequence of int
        States to keep, ``unstable poles <= order <= nstates``. A sequence (MATLAB's
        ``balred(sys, orders)``) returns one model per order, all from one balancing.

    Returns
    -------
    StateSpaceModel or ContinuousStateSpace, or list of them
        The reduced model, of the same kind (a list for a sequence of orders).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.9, 0.0], [0.0, 0.2]], [[1.0], [0.05]], [[1.0, 0.05]])
    >>> r = sysid.balanced_truncation(m, 1)
    >>> r.nstates, r.info["error_bound"] < 0.01
    (1, True)
    >>> u = sysid.StateSpaceModel(np.diag([1.2, 0.9, 0.1]), np.ones((3, 1)), np.ones((1, 3)))
    >>> ru = sysid.balanced_truncation(u, 2)    # keeps the unstable pole 1.2
    >>> round(float(ru.poles().real.max()), 12), ru.info["unstable_states"]
    (1.2, 1)
    >>> [r.nstates for r in sysid.balanced_truncation(u, [1, 3])]
    [1, 3]
    """
    if order is None:
        raise DataError("order is required; use balanced_realization to keep every state")
    if not isinstance(order, (str, bytes)) and np.ndim(order) == 1:
        orders = [as_int(o, "every order") for o in order]
        if not orders:
            raise DataError("order is an empty sequence: pass at least one order")
        res = _truncations(model, sorted(set(orders)))
        bad = [res[o] for o in orders if isinstance(res[o], DataError)]
        if bad:
            raise bad[0]
        return [res[o] for o in orders]
    m = _state_space(model, "balanced_truncation")
    if not m.dt:
        return _truncate_split(m, as_int(order, "order"), continuous=True)
    order = as_int(order, "order")
    if m.nstates == 0 or bool(np.all(is_stable_pole(m.poles(), m.dt))):
        out = _reduce(m, order, "balanced_truncation")
        out.info["unstable_states"] = 0
        return out
    return _truncate_split(m, order, continuous=False)


def _truncate_split(m: Any, order: int, continuous: bool, realization: bool = False) -> Any:
    """Balanced truncation of the stable part of ``m``, the unstable part added back (its
    states first, as in a balanced ``realization``, which keeps every state)."""
    n = m.nstates
    if not 1 <= order <= n:
        raise DataError(f"invalid order: {order}; the model has {n} states, so order must "
                        f"be between 1 and {n}")
    split = split_stable(m.A, m.B, m.C, 0.0 if continuous else m.dt)
    ns = split.n_stable
    nu = n - ns
    if order < nu:
        raise DataError(
            f"invalid order: {order} is fewer than the {nu} unstable poles of the model, which "
            f"balanced truncation keeps unchanged (only the stable part is reduced); ask for "
            f"order >= {nu}, or stabilise the model (feedback) first")
    As, Bs, Cs = split.stable
    Au, Bu, Cu = split.unstable
    r = order - nu
    if ns == 0:
        hsv, a, b, c, d = np.zeros(0), As, Bs, Cs, m.D
        t, t_inv = np.eye(0), np.eye(0)
    elif continuous:
        hsv, a, b, c, d, t, t_inv = _continuous_truncation(As, Bs, Cs, m.D, r)
    elif r == 0:
        hsv = np.asarray(_sysid.hankel_singular_values(As, Bs, Cs, m.D))
        a, b, c, d = np.zeros((0, 0)), np.zeros((0, m.ninputs)), np.zeros((m.noutputs, 0)), m.D
        t, t_inv = np.zeros((ns, 0)), np.zeros((0, ns))
    else:
        out = _sysid.balanced_truncation(As, Bs, Cs, m.D, r)
        hsv = np.asarray(out["hankel_singular_values"])
        a, b, c, d = (np.asarray(out[k]) for k in ("a", "b", "c", "d"))
        t, t_inv = np.asarray(out["t"]), np.asarray(out["t_inv"])
    return _assemble(m, split, order, hsv, (a, b, c, d), (t, t_inv), continuous, realization)


def _assemble(m: Any, split: Any, order: int, hsv: np.ndarray, abcd: tuple[np.ndarray, ...],
              proj: tuple[np.ndarray, np.ndarray], continuous: bool = False,
              realization: bool = False) -> Any:
    """The model of ``order`` states from the stable part's truncation ``abcd`` (projections
    ``proj``) and ``split``'s unstable part, its states first (``split=None``: a stable
    model, ``proj`` of the whole state)."""
    a, b, c, d = abcd
    t, t_inv = proj
    n = m.nstates
    r = a.shape[0]
    nu = order - r
    if split is None:
        Au, Bu, Cu = np.zeros((0, 0)), np.zeros((0, m.ninputs)), np.zeros((m.noutputs, 0))
        sT, sT_inv = np.eye(n), np.eye(n)
    else:
        (Au, Bu, Cu), sT, sT_inv = split.unstable, split.T, split.T_inv
    ns = n - nu
    A = np.block([[a, np.zeros((r, nu))], [np.zeros((nu, r)), Au]])
    T = sT @ np.block([[t, np.zeros((ns, nu))], [np.zeros((nu, r)), np.eye(nu)]])
    T_inv = np.block([[t_inv, np.zeros((r, nu))], [np.zeros((nu, ns)), np.eye(nu)]]) @ sT_inv
    B, C = np.vstack([b, Bu]), np.hstack([c, Cu])
    info = dict(m.info)
    info.update(method="balanced_truncation", reduced_from=n, hankel_singular_values=hsv,
                error_bound=float(2.0 * hsv[r:].sum()) + 0.0, unstable_states=nu)
    # the unstable states first, as MATLAB's balreal and hsvd order them
    p = np.r_[np.arange(r, order), np.arange(r)]
    A, B, C, T, T_inv = A[np.ix_(p, p)], B[p], C[:, p], T[:, p], T_inv[p]
    info.update(T=T, T_inv=T_inv)
    if realization:
        info.update(method="balanced", hankel_singular_values=np.r_[np.full(nu, np.inf), hsv])
    if continuous:
        return type(m)(A, B, C, d,
                       input_names=m.input_names, output_names=m.output_names,
                       hold=getattr(m, "hold", "zoh"), info=info)
    return StateSpaceModel(
        A, B, C, d, None if m.K is None else T_inv @ m.K,
        dt=m.dt, noise_cov=m.noise_cov, x0=None if m.x0 is None else T_inv @ m.x0,
        input_names=m.input_names, output_names=m.output_names, info=info)


def _truncations(model: Any, orders: list[int]) -> dict[int, Any]:
    """Balanced truncation to each of ``orders`` from one balancing: ``{order: model}``, or
    the :class:`DataError` that order raises (fewer states than unstable poles, more than
    the non-zero Hankel singular values). The square-root projections of order ``r`` are the
    first ``r`` columns (rows) of any larger order's, so one balancing serves all."""
    m = _state_space(model, "balanced_truncation")
    n = m.nstates
    out: dict[int, Any] = {}
    if not m.dt:  # continuous: one truncation per order
        for o in orders:
            try:
                out[o] = _truncate_split(m, o, continuous=True)
            except DataError as e:
                out[o] = e
        return out
    split = split_stable(m.A, m.B, m.C, m.dt) if n and _unstable_poles(m).size else None
    As, Bs, Cs = (m.A, m.B, m.C) if split is None else split.stable
    nu = n - As.shape[0]
    hsv = _stable_hsv(As, Bs, Cs, m.D, m.dt)
    keep = int(np.sum(hsv > 1e-13 * hsv[0])) if hsv.size else 0
    for o in orders:
        if not 1 <= o <= n:
            out[o] = DataError(f"invalid order: {o}; the model has {n} states, so order must "
                               f"be between 1 and {n}")
        elif o < nu:
            out[o] = DataError(
                f"invalid order: {o} is fewer than the {nu} unstable poles of the model, "
                "which balanced truncation keeps unchanged (only the stable part is "
                f"reduced); ask for order >= {nu}, or stabilise the model (feedback) first")
        elif o - nu > keep:
            out[o] = DataError(
                f"invalid order: the stable part has only {keep} non-zero Hankel singular "
                "values (the rest of it is uncontrollable or unobservable), so "
                f"{o - nu} of its states cannot be balanced; truncate to order <= {keep + nu}")
    valid = [o for o in orders if o not in out]
    rmax = max((o - nu for o in valid), default=0)
    if rmax:
        core = _sysid.balanced_truncation(As, Bs, Cs, m.D, rmax)
        t_all, ti_all = np.asarray(core["t"]), np.asarray(core["t_inv"])
        at = As @ t_all
    else:
        t_all, ti_all, at = np.zeros((n - nu, 0)), np.zeros((0, n - nu)), np.zeros((n - nu, 0))
    for o in valid:
        r = o - nu
        t, ti = t_all[:, :r], ti_all[:r]
        abcd = (ti @ at[:, :r], ti @ Bs, Cs @ t, m.D.copy())
        out[o] = _assemble(m, split, o, hsv, abcd, (t, ti))
    return out


def _continuous_truncation(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray, r: int
                           ) -> tuple[np.ndarray, ...]:
    """Square-root balanced truncation of a stable continuous ``(A, B, C, D)`` to ``r``
    states: ``(hsv, Ar, Br, Cr, D, T, T_inv)``."""
    lc, lo, U, hsv, Vt = _continuous_square_root(A, B, C)
    if r and hsv[r - 1] <= 1e-12 * hsv[0]:
        keep = int(np.sum(hsv > 1e-12 * hsv[0]))
        raise DataError(
            f"invalid order: the stable part has only {keep} non-zero Hankel singular values "
            "(the rest of it is uncontrollable or unobservable), so "
            f"{r} of its states cannot be balanced; truncate to fewer states")
    s = 1.0 / np.sqrt(hsv[:r])
    T = lc @ Vt[:r].T * s
    T_inv = (U[:, :r] * s).T @ lo.T
    return hsv, T_inv @ A @ T, T_inv @ B, C @ T, D.copy(), T, T_inv


