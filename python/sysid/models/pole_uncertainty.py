"""Standard deviations of poles, natural frequencies and damping ratios, from a model's
:class:`~sysid.models.uncertainty.ParameterUncertainty`.

First order through the eigenvalue derivative: for ``A v = lambda v`` and ``w^H A =
lambda w^H``, ``d lambda = w^H dA v / (w^H v)`` along each identifiable direction of the
parameter covariance (models without ``A`` difference their matched ``poles()``). Where two
poles coincide, numerically or within their uncertainty, the derivative does not exist or
does not describe the spread (the poles move like the square root of the perturbation):
there the standard deviation is the Monte Carlo value from models drawn from the same
covariance, and an :class:`~sysid.models.uncertainty.UncertaintyWarning` says so. Conjugate
pairs get one value.

Examples
--------
>>> import numpy as np, sysid
>>> from sysid.models.uncertainty import ParameterUncertainty
>>> build = lambda t: sysid.StateSpaceModel([[t[0], 0.0], [0.0, t[1]]], [[1.0], [1.0]],
...                                         [[1.0, 1.0]])
>>> m = build([0.5, -0.4])
>>> m.uncertainty = ParameterUncertainty([0.5, -0.4], np.diag([1e-4, 4e-4]), build)
>>> np.round(pole_std(m)[1].real, 6)
array([0.01, 0.02])
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .._checks import user_stacklevel
from ..errors import DataError, NumericalError
from .uncertainty import _METHODS, UncertaintyWarning, _complex_std, _match, require

__all__ = ["coincident_poles", "damping_std", "pole_groups", "pole_jacobian", "pole_std"]


def pole_jacobian(model: Any, *, step: float = 1e-3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Poles, their complex scaled Jacobian ``G`` (``G G^H``-type covariance) and a mask of the
    poles that coincide with another pole, where a first-order expansion does not exist.

    State-space models use ``d lambda_i = w_i^H dA v_i / (w_i^H v_i)`` with the derivative of
    ``A`` along each identifiable direction; other models difference their ``poles()`` and
    match them to the nominal ones, root by root of each polynomial (:func:`pole_groups`).
    See :func:`coincident_poles` for the mask, taken within each polynomial's roots.
    """
    unc = require(model)
    nominal = unc.build(unc.theta)
    A = getattr(nominal, "A", None)
    if isinstance(A, np.ndarray) and A.ndim == 2:
        from scipy.linalg import eig

        lam, W, V = eig(A, left=True, right=True)
        _, dA = unc.scaled_jacobian(lambda m: m.A, step=step)
        n = A.shape[0]
        dA = dA.reshape(n, n, -1)
        denom = np.einsum("ij,ij->j", W.conj(), V)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            G = np.einsum("ai,abk,bi->ik", W.conj(), dA, V) / denom[:, None]
        groups = _whole(lam.size)
    else:
        lam = np.asarray(nominal.poles(), dtype=complex)
        groups = pole_groups(nominal, lam.size)
        _, G = unc.scaled_jacobian(
            lambda m: _match_groups(lam, np.asarray(m.poles(), complex), groups), step=step)
        G = G.astype(complex)
    sd = np.abs(_complex_std(G))
    bad = np.zeros(lam.size, bool)
    for g in groups:
        bad[g] = coincident_poles(lam[g], sd[g])
    return lam.astype(complex), G, bad


def _whole(n: int) -> list[slice]:
    return [slice(0, n)]


def pole_groups(model: Any, n: int) -> list[slice]:
    """The slices of ``model.poles()`` (``n`` poles) whose members are roots of one
    polynomial: the model's ``pole_groups()`` (a polynomial or transfer-function model's
    denominators, whose roots are independent of each other's), else one group. Poles only
    coincide, and draws are only matched, within a group."""
    sizes = getattr(model, "pole_groups", None)
    if not callable(sizes):
        return _whole(n)
    edges = np.cumsum([0, *(int(k) for k in sizes())])
    if edges[-1] != n:
        return _whole(n)
    return [slice(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:]) if b > a]


def _origin_aligned(lam: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``p`` with poles at the origin added or dropped to give ``lam``'s number of poles:
    a dead time realised as a delay line has a pole at ``z = 0`` per sample, so a draw
    whose dead time crosses a sample boundary has one more or one fewer of them (those
    poles carry no uncertainty of their own). Any other difference raises.

    Examples
    --------
    >>> import numpy as np
    >>> _origin_aligned(np.array([0.9, 0.0, 0.0]), np.array([0.91, 0.0])).tolist()
    [(0.91+0j), 0j, 0j]
    >>> _origin_aligned(np.array([0.9, 0.0]), np.array([0.0, 0.91, 0.0])).tolist()
    [(0.91+0j), 0j]
    """
    lam, p = np.asarray(lam, complex), np.asarray(p, complex)
    tiny = 1e-9 * max(1.0, float(np.max(np.abs(lam), initial=0.0)))
    extra = p.size - lam.size
    if extra > 0:
        order = np.argsort(np.abs(p), kind="stable")
        if np.all(np.abs(p[order[:extra]]) <= tiny):
            return p[np.sort(order[extra:])]
    elif extra < 0 and np.sum(np.abs(lam) <= tiny) >= -extra:
        return np.r_[p, np.zeros(-extra, complex)]
    return _match(lam, p)     # raises: the number of poles changed


def _match_groups(lam: np.ndarray, p: np.ndarray, groups: list[slice]) -> np.ndarray:
    """``p`` reordered to match ``lam``, each group among its own roots (a draw with more or
    fewer delay-line poles at the origin first aligned, :func:`_origin_aligned`)."""
    if p.size != lam.size:
        p = _origin_aligned(lam, p)
        if len(groups) > 1:
            return _match(lam, p)  # the groups' sizes are the nominal's: match as a whole
    out = np.empty_like(p)
    for g in groups:
        out[g] = _match(lam[g], p[g])
    return out


def coincident_poles(lam: Any, sd: Any) -> np.ndarray:
    """Mask of the poles that coincide with another pole, numerically or within their
    uncertainty: where the first-order (eigenvalue-derivative) standard deviation does not
    exist or does not hold.

    Pole ``i`` coincides with pole ``j`` when ``|lambda_i - lambda_j|`` is at round-off level
    (``1e-7`` of the largest modulus, at least ``1e-7``), or not larger than pole ``i``'s own
    first-order standard deviation ``sd`` (modulus): the data cannot tell it from ``j``, and
    near a repeated eigenvalue the poles move like the square root of the perturbation, not
    linearly. A pole whose own uncertainty region stays clear of the others keeps its
    first-order standard deviation, however close they are and however uncertain a
    neighbour is (a well-determined slow pole beside a poorly determined one: the Monte
    Carlo value there mixed the two in the matching of the draws, three times the spread
    of the poles' own bootstrap refits).

    Examples
    --------
    >>> import numpy as np
    >>> coincident_poles(np.array([0.5, 0.8, 0.81]), np.array([0.01, 0.002, 0.003]))
    array([False, False, False])
    >>> coincident_poles(np.array([0.5, 0.8, 0.81]), np.array([0.01, 0.02, 0.015]))
    array([False,  True,  True])
    >>> coincident_poles(np.array([0.98, 0.84, 0.66]), np.array([0.01, 0.27, 0.38]))
    array([False,  True,  True])
    """
    lam = np.asarray(lam, complex).ravel()
    sd = np.asarray(sd, float).ravel()
    if lam.size < 2:
        return ~np.isfinite(sd)
    dist = np.abs(lam[:, None] - lam[None, :])
    np.fill_diagonal(dist, np.inf)
    tiny = 1e-7 * max(1.0, float(np.max(np.abs(lam))))
    reach = np.broadcast_to(sd[:, None], dist.shape)
    close = (dist <= tiny) | (dist <= np.where(np.isfinite(reach), reach, np.inf))
    return close.any(axis=1) | ~np.isfinite(sd)


_MC_DRAWS = 2000


def _pole_draws(model: Any, lam: np.ndarray, n: int = _MC_DRAWS, rng: Any = 0) -> np.ndarray:
    """Poles of ``n`` models drawn from the parameter covariance, matched to ``lam``
    (``(n, len(lam))``); the seed is fixed so that reports are reproducible. A draw that
    cannot be built (a continuous-time model whose sampling overflows, drawn far from the
    estimate) is a row of NaN, which makes the stds infinite (:func:`_draws_std`), with an
    :class:`UncertaintyWarning`: one such draw stopped ``poles(std=True)`` on a step test's
    process model."""
    unc = require(model)
    groups = pole_groups(unc.build(unc.theta), lam.size)
    rows, failed = [], 0
    for t in unc.sample_parameters(n, rng):
        try:
            rows.append(_match_groups(lam, np.asarray(unc.build(t).poles(), complex), groups))
        except NumericalError:
            failed += 1
            rows.append(np.full(lam.size, np.nan + 0j))
    if failed:
        warnings.warn(
            f"{failed} of {n} models drawn from the parameter covariance could not be built "
            "(sampling their continuous-time poles overflows: the covariance reaches models "
            "far from this one: the data do not bound its parameters); the Monte Carlo "
            "standard deviations are infinite",
            UncertaintyWarning, stacklevel=user_stacklevel())
    return np.array(rows)


def _partners(lam: np.ndarray) -> np.ndarray:
    """Index of each pole's complex-conjugate partner (itself for a real pole)."""
    idx = np.arange(lam.size)
    for i, z in enumerate(lam):
        if z.imag != 0:
            d = np.abs(lam - np.conj(z))
            d[i] = np.inf
            j = int(np.argmin(d))
            if d[j] <= 1e-7 * max(1.0, abs(z)):
                idx[i] = j
    return idx


def _pooled_std(lam: np.ndarray, x: np.ndarray, odd: bool = False) -> np.ndarray:
    """Sample std of each column of ``x`` (draws of a quantity per pole), pooled with the
    conjugate partner's column (negated when ``odd``, as for imaginary parts): a conjugate
    pair gets one std, whatever way the matching assigned the draws within the pair."""
    part = _partners(lam)
    out = np.empty(lam.size)
    for i, j in enumerate(part):
        v = x[:, i] if i == j else np.r_[x[:, i], -x[:, j] if odd else x[:, j]]
        v = v[np.isfinite(v)]
        out[i] = v.std(ddof=1) if v.size > 1 else np.nan
    return out


def _draws_std(lam: np.ndarray, draws: np.ndarray) -> np.ndarray:
    """Complex std (real and imaginary parts) of matched pole draws, pooled over pairs;
    infinite for every pole the other draws move when a draw could not be built (a row of
    NaN from :func:`_pole_draws`: its poles lie beyond any finite spread)."""
    sd = _pooled_std(lam, draws.real) + 1j * _pooled_std(lam, draws.imag, odd=True)
    if draws.size and np.isnan(draws).all(axis=1).any():
        moved = np.abs(sd) > 1e-9 * np.maximum(1.0, np.abs(lam))  # not round-off of 0
        sd = np.where(moved, complex(np.inf, np.inf), sd)
    return sd


def _warn_monte_carlo(mask: np.ndarray, lam: np.ndarray, what: str) -> None:
    which = ", ".join(f"{z:.4g}" for z in lam[mask][:6]) + (" ..." if mask.sum() > 6 else "")
    warnings.warn(
        f"{int(mask.sum())} pole(s) ({which}) coincide with another pole within their "
        f"uncertainty, where a first-order {what} does not hold: reported the Monte Carlo "
        f"value from {_MC_DRAWS} models drawn from the parameter covariance (first order for "
        "the other poles)", UncertaintyWarning, stacklevel=user_stacklevel())


def _warn_undetermined(model: Any) -> None:
    """An :class:`UncertaintyWarning` when the refinement that gave the model's covariance
    left directions beyond its similarity orbit undetermined (``info["pem"]
    ["undetermined"]``): the covariance leaves them out, so the stds are not reliable."""
    k = int(((getattr(model, "info", None) or {}).get("pem") or {}).get("undetermined", 0))
    if k:
        warnings.warn(
            f"the model's parameter covariance leaves out {k} direction(s) the data do not "
            "determine (an order above what they support): these standard deviations are "
            "not reliable; refit at a lower order, or check them by bootstrap",
            UncertaintyWarning, stacklevel=user_stacklevel())


def pole_std(model: Any, method: str = "linear", *, n: int = 1000, rng: Any = None
             ) -> tuple[np.ndarray, np.ndarray]:
    """Poles and their std (complex: ``sd.real`` of the real parts, ``sd.imag`` of the
    imaginary parts); see :meth:`StateSpaceModel.poles`.

    ``method="linear"`` propagates to first order through the eigenvalue derivative (left
    and right eigenvectors); poles that coincide with another (:func:`coincident_poles`)
    get the Monte Carlo value instead, with an :class:`UncertaintyWarning` saying so.
    """
    if method not in _METHODS:
        raise DataError(f"method must be 'linear' or 'monte-carlo', got {method!r}")
    if method == "monte-carlo":
        unc = require(model)
        lam = np.asarray(unc.build(unc.theta).poles(), complex)
        return lam, _draws_std(lam, _pole_draws(model, lam, n, rng))
    _warn_undetermined(model)
    lam, G, bad = pole_jacobian(model)
    sd = _complex_std(G)
    if bad.any():
        mc = _draws_std(lam, _pole_draws(model, lam))
        sd = np.where(bad, mc, sd)
        # poles no draw moves (the unit delays of an absorbed input delay) are exact: std 0
        moved = bad & (mc != 0)
        if moved.any():
            _warn_monte_carlo(moved, lam, "standard deviation")
    return lam, sd


def _damping_parts(z: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Natural frequency (rad/s) and damping of discrete poles ``z`` (any shape); of
    continuous poles when ``dt == 0``."""
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.log(np.where(z != 0, z, np.nan)) / dt if dt else np.asarray(z, complex)
        wn = np.abs(s)
        return wn, -s.real / wn


def damping_std(model: Any, dt: float) -> dict[str, np.ndarray]:
    """Poles, ``s = log(z)/dt``, natural frequency (rad/s, Hz), damping and their std (first
    order through the pole Jacobian; Monte Carlo for poles that coincide with another, as
    :func:`pole_std`). A pole at ``z = 0`` (infinitely fast) has NaN std. ``dt == 0``: a
    continuous model, whose poles are ``s`` themselves."""
    _warn_undetermined(model)
    lam, G, bad = pole_jacobian(model)
    with np.errstate(divide="ignore", invalid="ignore"):
        if dt:
            s = np.where(lam != 0, np.log(np.where(lam != 0, lam, 1.0)) / dt, -np.inf)
            Gs = G / (lam[:, None] * dt)
        else:
            s, Gs = lam.astype(complex), G
        wn = np.abs(s)
        dwn = (np.conj(s)[:, None] * Gs).real / wn[:, None]
        dzeta = -Gs.real / wn[:, None] + (s.real / wn**2)[:, None] * dwn
        wn_sd = np.sqrt(np.sum(dwn**2, axis=1))
        zeta_sd = np.sqrt(np.sum(dzeta**2, axis=1))
    pole_sd = _complex_std(G)
    # a distinct real pole (positive in discrete time) stays real under a small change: its
    # damping is 1 exactly, its std 0 (not the 1e-17 of round-off)
    real = (lam.imag == 0) & ((lam.real > 0) if dt else np.ones(lam.size, bool))
    zeta_sd = np.where(real, 0.0, zeta_sd)
    at_zero = ~np.isfinite(s) | (wn == 0)
    mc = bad & ~at_zero
    if mc.any():
        draws = _pole_draws(model, lam)
        w_d, z_d = _damping_parts(draws, dt)
        pole_sd = np.where(mc, _draws_std(lam, draws), pole_sd)
        wn_sd = np.where(mc, _pooled_std(lam, w_d), wn_sd)
        zeta_sd = np.where(mc, _pooled_std(lam, z_d), zeta_sd)
        _warn_monte_carlo(mc, lam, "damping and frequency std")
    if at_zero.any():
        where = "z = 0 (infinitely fast)" if dt else "s = 0 (integrators)"
        warnings.warn(f"{int(at_zero.sum())} pole(s) at {where}: their damping and frequency "
                      "std are reported as NaN", UncertaintyWarning, stacklevel=user_stacklevel())
    nan = np.full(lam.size, np.nan)
    return {
        "poles": lam, "s": s, "pole_std": pole_sd,
        "wn_std": np.where(at_zero, nan, wn_sd),
        "wn_hz_std": np.where(at_zero, nan, wn_sd / (2 * np.pi)),
        "zeta_std": np.where(at_zero, nan, zeta_sd),
        "std_method": np.where(mc, "monte-carlo", "linear"),
    }
