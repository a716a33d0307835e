"""Initial conditions of the Hammerstein-Wiener fits (MATLAB's ``InitialCondition`` of
``nlhwOptions``): :func:`sysid.nlhw` and :func:`sysid.nlhw_ss`.

``"zero"`` (the default, as MATLAB's) starts every experiment's linear block from rest;
``"estimate"`` estimates one initial state per experiment with the other parameters in the
same Gauss-Newton search (the output is not affine in it through the output nonlinearity,
so it is not eliminated as the polynomial estimators do, :mod:`sysid.polynomial.initial`):
extra parameters whose Jacobian columns come from the same sensitivity recursion. For
:func:`sysid.nlhw` the state is the short polynomial ``h`` of
``F x = B w(t - nk) + h`` (``max(nf, nk + nb - 1)`` coefficients: what the samples before
the record leave, past outputs of the block and past inputs still in its delay line; SciPy's
``lfilter(r_[zeros(nk), b], r_[1, f], w, zi=h)`` state, as the polynomial estimators'); for
:func:`sysid.nlhw_ss` the state ``x(0)`` itself (what the model's ``simulate(u, x0)``
takes). The search starts from the states that fit the linear start's errors by least
squares. The reported parameter covariance is the marginal one of the model's parameters
(the states a nuisance). ``"auto"`` is not offered: the polynomial estimators' rule (fit
from rest, then test the drop in the sum of squares that the state alone brings) rests on
the errors being affine in the state.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError
from ..polynomial.initial import check


def check_initial(initial_condition: Any, who: str) -> str:
    """``"zero"`` or ``"estimate"`` (the polynomial estimators' name check, then ``"auto"``
    refused).

    Examples
    --------
    >>> from sysid.nonlinear.hw_initial import check_initial
    >>> check_initial("estimate", "nlhw")
    'estimate'
    """
    name = check(initial_condition)
    if name == "auto":
        raise DataError(f"{who}: initial_condition must be 'zero' or 'estimate' ('auto' is not "
                        "offered for Hammerstein-Wiener models: the output is not affine in "
                        "the initial state, so there is no test of it at the fit from rest)")
    return name


def free_response_bf(f: np.ndarray, nh: int, n: int) -> np.ndarray:
    """``(n, nh)``: column ``j`` the response of ``1/F`` to a unit pulse at sample ``j``
    (the output's derivative in ``h_j``)."""
    from scipy.signal import lfilter

    out = np.zeros((n, nh))
    if nh and n:
        pulse = np.zeros(n)
        pulse[0] = 1.0
        g = lfilter([1.0], np.concatenate([[1.0], f]), pulse)
        for j in range(min(nh, n)):
            out[j:, j] = g[:n - j]
    return out


def free_response_ss(a: np.ndarray, c: np.ndarray, n: int) -> np.ndarray:
    """``(n * p, nx)``: ``C A^t`` stacked sample by sample (outputs fastest); the loop stops
    once the free response has decayed below round-off of its start (zeros after)."""
    p, nx = c.shape
    out = np.zeros((n, p, nx))
    m = c.copy()
    floor = 1e-17 * max(float(np.abs(c).max()), np.finfo(float).tiny)
    for t in range(n):
        out[t] = m
        m = m @ a
        if float(np.abs(m).max()) < floor:
            break
    return out.reshape(n * p, nx)


def least_squares_states(columns: list[np.ndarray], errors: list[np.ndarray]) -> list[np.ndarray]:
    """Per experiment, the state whose free response fits the errors of the linear start
    (from rest) by least squares: the search's starting states."""
    out = []
    for o, e in zip(columns, errors):
        if o.shape[1] == 0:
            out.append(np.zeros(0))
            continue
        sol = np.linalg.lstsq(o, np.ravel(e), rcond=None)[0]
        out.append(np.where(np.isfinite(sol), sol, 0.0))
    return out
