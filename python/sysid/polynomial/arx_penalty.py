"""ARX with a quadratic penalty on MATLAB's parameter vector (``arx(..., regularization=(lam,
R))`` and ``arx(..., regularization=lam, kernel=M)``).

MATLAB's ``arxOptions`` ``Regularization`` adds ``lam theta^T R theta`` to the least-squares
criterion, with ``theta = [a, b]`` the coefficients of the polynomials (``A = 1 + a_1 q^-1 +
...``): the vector a model reports as ``parameters``. The streaming QR of :func:`sysid.arx`
regresses ``y(t)`` on ``+y(t - k)``, whose coefficients are ``-a``; a penalty handed to it
as given would weigh ``[-a, b]`` (with cross terms between ``A`` and ``B`` coefficients, a
different penalty: other numbers, silently). Here each output's compressed regression
``[[R1, r], [0, rho]]`` (``sysid-core``'s ``ArxCompressor::output_summary``, the same rows as
the plain fit) has its ``A`` columns negated, so that its unknowns are ``theta`` itself, and
the rows ``sqrt(lam) M`` (``M^T M = R``) are appended before the small QR. Every output has
its own ``lam`` and ``M``, sized by its own equation.
"""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np
from scipy.linalg import solve_triangular

from .. import _sysid
from ..errors import DataError, ExcitationError

__all__ = ["kernel_penalties", "pair_penalties", "penalised_fits"]


def _is_number(x: Any) -> bool:
    """A real scalar (a Python or NumPy number or a 0-d array), not a bool."""
    if isinstance(x, (bool, np.bool_)):
        return False
    return isinstance(x, numbers.Real) or (isinstance(x, np.ndarray) and x.ndim == 0
                                           and x.dtype.kind in "iuf")


def _n_params(na_g: list[list[int]], nb_g: list[list[int]], i: int) -> int:
    return sum(na_g[i]) + sum(nb_g[i])


def _lam(lam: Any, i: int, ny: int) -> float:
    at = f" of output {i}" if ny > 1 else ""
    if not _is_number(lam):
        raise DataError(f"lam{at} must be a number >= 0 (MATLAB's Lambda), got {lam!r:.60}")
    value = float(lam)
    if not (value >= 0 and np.isfinite(value)):
        raise DataError(f"lam{at} must be a finite number >= 0, got {value}")
    return value


def pair_penalties(pairs: Any, na_g: list[list[int]], nb_g: list[list[int]]
                   ) -> tuple[list[float], list[np.ndarray]]:
    """Per output, ``lam`` and a factor ``M`` with ``M^T M = R`` (an eigen-factor) from
    MATLAB's ``(Lambda, R)``: one pair for every output, or a sequence of one pair per output.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.polynomial.arx_penalty import pair_penalties
    >>> lams, ms = pair_penalties([(1.0, np.eye(2)), (5.0, 2 * np.eye(3))],
    ...                           [[1, 0], [1, 1]], [[1], [1]])
    >>> lams, [m.shape for m in ms]
    ([1.0, 5.0], [(2, 2), (3, 3)])
    """
    ny = len(na_g)
    if len(pairs) == 2 and _is_number(pairs[0]):  # one pair for every output
        pairs = [pairs] * ny
    if len(pairs) != ny or any(not isinstance(pr, (tuple, list)) or len(pr) != 2
                               for pr in pairs):
        raise DataError(f"regularization=(lam, R): one pair, or {ny} pairs (one per output), "
                        f"each (lam, R) with R a p x p matrix for its output's p parameters")
    lams, factors = [], []
    for i, (lam, R) in enumerate(pairs):
        lams.append(_lam(lam, i, ny))
        p = _n_params(na_g, nb_g, i)
        try:
            R = np.asarray(R, dtype=float)
        except (TypeError, ValueError):
            raise DataError(f"R of output {i} must be a numeric ({p}, {p}) matrix") from None
        if R.shape != (p, p):
            raise DataError(f"R of output {i} has shape {R.shape} but should be ({p}, {p}): "
                            f"output {i}'s equation has {p} parameters ({sum(na_g[i])} of A, "
                            f"{sum(nb_g[i])} of B), in the order of model.parameters[{i}]")
        # theta^T R theta is that of the symmetric part: R's is taken
        w, V = np.linalg.eigh(0.5 * (R + R.T)) if np.all(np.isfinite(R)) else (None, None)
        if w is None or (p and w.min() < -1e-10 * max(1.0, w.max())):
            raise DataError(f"R of output {i} must be a finite symmetric positive "
                            f"semi-definite matrix ({p}, {p})")
        factors.append(np.sqrt(np.clip(w, 0, None))[:, None] * V.T)
    return lams, factors


def kernel_penalties(lam: float, kernel: Any, na_g: list[list[int]], nb_g: list[list[int]]
                     ) -> tuple[list[float], list[np.ndarray]]:
    """Per output, ``lam`` and the factor ``M`` (``kernel``, the same for every output, as
    many columns as each output's equation has parameters)."""
    try:
        M = np.asarray(kernel, dtype=float)
    except (TypeError, ValueError):
        raise DataError("kernel must be a numeric matrix, the factor M of the penalty "
                        "lam |M theta|^2") from None
    M = M[None, :] if M.ndim == 1 else M
    ny = len(na_g)
    for i in range(ny):
        p = _n_params(na_g, nb_g, i)
        if M.ndim != 2 or M.shape[1] != p:
            raise DataError(f"kernel has shape {M.shape} but should be (q, {p}): output {i}'s "
                            f"equation has {p} parameters ({sum(na_g[i])} of A, "
                            f"{sum(nb_g[i])} of B), in the order of model.parameters[{i}]"
                            + ("; give the outputs equations of one size, or a (lam, R) "
                               "pair per output" if ny > 1 else ""))
    if not np.all(np.isfinite(M)):
        raise DataError("kernel has a non-finite entry (NaN or Inf)")
    return [lam] * ny, [M] * ny


def penalised_fits(exps: list[Any], na_g: list[list[int]], nb_g: list[list[int]],
                   nk_g: list[list[int]], lams: list[float], factors: list[np.ndarray]
                   ) -> list[dict[str, Any]]:
    """Per output, the minimiser of ``|y - Phi theta|^2 + lam |M theta|^2`` over MATLAB's
    ``theta = [a, b]``: ``a``, ``b``, ``theta``, ``loss`` (mean squared residual, the penalty
    left out) and ``unscaled_cov`` ``(Phi^T Phi + lam M^T M)^-1``, as ``_sysid.arx_fit`` gives
    them. Every ``lam`` zero: the plain least-squares fit itself."""
    if not any(lams):
        return list(_sysid.arx_fit(exps, na_g, nb_g, nk_g, 0.0, None))
    fits = []
    for i, (s, n) in enumerate(_sysid.arx_summary(exps, na_g, nb_g, nk_g)):
        fits.append(_solve(np.array(s, dtype=float), int(n), na_g[i], nb_g[i], lams[i],
                           factors[i], i))
    return fits


def _solve(summary: np.ndarray, n_rows: int, na_row: list[int], nb_row: list[int],
           lam: float, M: np.ndarray, i: int) -> dict[str, Any]:
    """Output ``i``'s penalised fit from its compressed regression (regressor signs)."""
    p = summary.shape[0] - 1
    na_tot = sum(na_row)
    summary[:, :na_tot] *= -1.0  # regressors -y(t - k): the unknowns are a, not -a
    pen = np.sqrt(lam) * M
    stacked = np.vstack([summary, np.column_stack([pen, np.zeros(pen.shape[0])])])
    r = np.linalg.qr(stacked, mode="r")
    d = np.abs(np.diag(r[:p, :p]))
    dmax = float(d.max()) if p else 1.0
    if p and (dmax == 0 or not np.all(d > 1e-12 * dmax)):
        rank = int(np.sum(d > 1e-12 * dmax)) if dmax > 0 else 0
        raise ExcitationError(
            f"arx: the {p} regressor columns of output {i}'s equation, with the penalty rows, "
            f"have numerical rank {rank} (relative tolerance 1.0e-12), so the data and the "
            "penalty do not determine the parameters; use a positive definite R (or kernel) "
            "or a larger lam, lower orders (na, nb), or a richer input")
    r11 = r[:p, :p]
    theta = solve_triangular(r11, r[:p, p]) if p else np.zeros(0)
    rinv = solve_triangular(r11, np.eye(p)) if p else np.zeros((0, 0))
    rss = max(float(r[p, p]) ** 2 - float(np.sum((pen @ theta) ** 2)), 0.0)
    a, o = [], 0
    for n in na_row:
        a.append(theta[o:o + n].copy())
        o += n
    b = []
    for n in nb_row:
        b.append(theta[o:o + n].copy())
        o += n
    return {"a": a, "b": b, "theta": theta, "loss": rss / n_rows,
            "unscaled_cov": rinv @ rinv.T, "n_rows": n_rows}
