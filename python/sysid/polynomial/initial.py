"""Initial conditions of the polynomial prediction-error fits (MATLAB's ``InitialCondition``
of ``oeOptions``, ``armaxOptions``, ``bjOptions``, ``polyestOptions`` and ``pemOptions``):
:func:`sysid.oe`, :func:`sysid.armax`, :func:`sysid.bj`, :func:`sysid.polyest`,
:func:`sysid.arma` (a time series: no inputs, only ``h_e``) and :func:`sysid.pem` given a
polynomial model.

From rest, the predictor ``e = D/C (A y - sum_j B_j/F_j u_j(t - nk_j))`` treats every sample
before the record as zero; on a record that starts mid-response the transient this leaves
biases the fit. What the samples before the record were enters the difference equations as
short polynomials ``h`` acting on the first samples,

    F_j w_j = B_j u_j(t - nk_j) + h_j,    v = A y - sum_j w_j,    C e = D v + h_e,

``h_j`` with ``max(nf_j, nk_j + nb_j - 1)`` coefficients (for an input with ``F_j``: exactly
SciPy's ``lfilter(r_[zeros(nk_j), b_j], r_[1, f_j], u_j, zi=h_j)`` state) and ``h_e`` the rest
(the pre-sample outputs of ``A``, the inputs without ``F_j``, the state of ``D/C``). The
errors are affine in ``h``, so ``initial_condition="estimate"`` eliminates ``h`` by least
squares at every step of the search (variable projection), one ``h`` per experiment; the
parameter covariance is then the marginal one (the Schur complement of the joint
information: the initial state a nuisance). ``"zero"`` starts from rest. ``"auto"`` (the
default, as MATLAB's) fits from rest, then estimates the initial state at that fit and, when
this lowers the sum of squared errors by more than ``6.63`` times what it lowers it by on
average when the true state is zero (``n_h sigma^2`` for white errors, ``n_h`` the initial
coefficients of all experiments; more for coloured errors, from their autocovariances), the
result is that of ``"estimate"``: for white errors a chi-square test of a zero initial state,
passed by chance with probability 1 % for one coefficient and below 0.2 % for two or more
(on an OE record at rest with an AR(1) disturbance of pole 0.9, 1 of 100 records; from
mid-response, 47 of 100). MATLAB's ``"backcast"`` is not offered. The choice is
``info["initial_condition"]``, the states ``info["initial_state"]`` and, with ``"auto"``, the
two sums of squares that decided ``info["initial_condition_costs"]`` (one entry for one
output, a list per output otherwise).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import _sysid
from ..errors import DataError


def check(initial_condition: Any, lines: bool = False) -> str:
    """The canonical name of ``initial_condition`` (the core's check: a :class:`DataError`
    naming ``'auto'``, ``'zero'`` and ``'estimate'`` otherwise); with ``lines`` (a fit on the
    excited lines of periodic or frequency-response data, which has no transient)
    ``"estimate"`` is refused.

    Examples
    --------
    >>> from sysid.polynomial.initial import check
    >>> check("estimate")
    'estimate'
    >>> from sysid.errors import DataError
    >>> try:
    ...     check("est")
    ... except DataError as e:
    ...     print(str(e)[:60])
    invalid initial_condition: must be 'auto', 'zero' or 'estima
    """
    name = initial_condition if isinstance(initial_condition, str) else repr(initial_condition)
    name = _sysid.initial_condition_name(name)
    if lines and name == "estimate":
        raise DataError("initial_condition='estimate' does not apply to a fit on the excited "
                        "lines (periods in steady state, or frequency-response data, have no "
                        "transient); leave it 'auto'")
    return name


def record(info: dict[str, Any], results: list[dict[str, Any]]) -> None:
    """The choices, states and (with ``"auto"``) deciding costs of the per-output searches
    ``results`` in ``info``: one entry for one output, a list per output otherwise."""

    def one_or_list(v: list[Any]) -> Any:
        return v[0] if len(v) == 1 else v

    info["initial_condition"] = one_or_list([r["initial_condition"] for r in results])
    info["initial_state"] = one_or_list([r["initial_states"] for r in results])
    costs = [r.get("auto_costs") for r in results]
    if any(c is not None for c in costs):
        info["initial_condition_costs"] = one_or_list(
            [None if c is None else {"zero": 2 * c[0], "estimate": 2 * c[1]} for c in costs])


def simulator(model: Any, u: np.ndarray, y: np.ndarray, orders: list[tuple[Any, ...]],
              chosen: list[str]) -> Any:
    """``sim(m)`` for :func:`sysid.pem.sandwich.sandwich_covariance` of a fit without a noise
    model on one record: per output, the simulation from rest, or (its initial state
    estimated) ``y - e`` with ``e`` the errors at the initial state re-fitted for ``m``, as
    the search formed them. ``orders`` per output ``(na, nb, nc, nd, nf, nk)``."""
    u = np.ascontiguousarray(u, float)

    def theta(m: Any, i: int) -> np.ndarray:
        parts = [m.a[i][i], *m.b[i], m.c[i], m.d[i], *m.f[i]]
        return np.concatenate([np.asarray(p, float).ravel() for p in parts])

    def sim(m: Any) -> np.ndarray:
        out = np.asarray(m.simulate(u), float).copy()
        for i, how in enumerate(chosen):
            if how == "estimate":
                na, nb, nc, nd, nf, nk = orders[i]
                e, _ = _sysid.polynomial_residuals(
                    [(np.ascontiguousarray(y[:, i]), u)], na, nb, nc, nd, nf, nk,
                    theta(m, i), "estimate")
                out[:, i] = y[:, i] - e
        return out

    return sim
