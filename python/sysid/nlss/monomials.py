"""The monomials of a polynomial nonlinear state-space model: which variables they take, the
state basis of the ``"outputs"`` terms, and the powers of an input its data determine.

An input that takes ``k`` distinct values on the estimation record (a step test or a binary
PRBS: two) determines only its powers below ``k`` (:mod:`sysid.data.levels`): a monomial with a
higher power of it equals a combination of other terms on that record, fits it no better, and
decides alone how the model behaves between and beyond the levels. Such monomials are left
out of the model, and ``pnlss`` says so. Measured on a heated air duct (heater voltage ->
air temperature; step test 1 -> 5 V to estimate, a PID run moving the heater over 0.6-10 V to
validate; records of ``benches/results/realdata_fresh6.md``): ``pnlss(est, 3)`` validated at
-64.5 % with them (its linear start 49.8 %) and at 56.9 % with the state monomials alone.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .. import _sysid
from ..models.statespace import StateSpaceModel

__all__ = ["TERMS", "equation_terms", "output_basis", "warn_undetermined"]

#: the variables a monomial set may take (``"none"``, for the output equation only, adds none)
TERMS = ("full", "states", "inputs", "outputs")


def equation_terms(n: int, m: int, l_: int, terms: str, output_terms: str | None,
                   degs: list[int], levels: Any = None
                   ) -> tuple[list[list[int]], list[list[int]], int]:
    """The state and output equations' terms ``zeta``, ``eta``: a constant (the channel
    offsets removed by the scaling, and the mean of the nonlinear terms, enter the scaled
    equations as constants), then the monomials of ``terms`` and ``output_terms``, without
    those whose power of an input reaches its number of ``levels`` (one count per input;
    ``None``: all kept). Returns ``(zeta, eta, left_out)``, ``left_out`` the monomials
    dropped from both.

    Examples
    --------
    >>> from sysid.nlss.monomials import equation_terms
    >>> zeta, eta, dropped = equation_terms(1, 1, 1, "full", "none", [2], levels=[2])
    >>> zeta, eta, dropped  # x0^2 and x0 u0 kept, u0^2 (index 1 twice) left out
    ([[], [0, 0], [0, 1]], [[]], 1)
    """
    ot = terms if output_terms is None else output_terms
    zeta = _monomials(n, m, l_, terms, degs)
    eta = [] if ot == "none" else _monomials(n, m, l_, ot, degs)
    if levels is None:
        return [[]] + zeta, [[]] + eta, 0
    cap = [int(k) - 1 for k in levels]
    keep = [t for t in zeta if _determined(t, n, cap)], [t for t in eta if _determined(t, n, cap)]
    return [[]] + keep[0], [[]] + keep[1], len(zeta) + len(eta) - len(keep[0]) - len(keep[1])


def _determined(t: list[int], n: int, cap: list[int]) -> bool:
    return all(t.count(n + j) <= c for j, c in enumerate(cap))


def _monomials(n: int, m: int, l_: int, terms: str, degs: list[int]) -> list[list[int]]:
    """The monomials (index lists into ``z = [x; u]``) of ``terms``; ``"outputs"``: those of
    the first ``min(l_, n)`` states (the output-aligned ones, see :func:`output_basis`) and
    the inputs."""
    if terms != "outputs":
        return list(_sysid.pnlss_monomials(n, m, terms, degs))
    k = min(l_, n)
    return [[v if v < k else n + v - k for v in t]
            for t in _sysid.pnlss_monomials(k, m, "full", degs)]


def output_basis(m: StateSpaceModel) -> StateSpaceModel:
    """``m`` in the state basis whose first ``min(ny, n)`` states are the rows of ``C x``
    (orthogonal complement for the rest), so that monomials of those states are monomials
    of the linear part's outputs (less their direct term); ``m`` when ``C``'s rows are
    dependent.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.nlss.monomials import output_basis
    >>> m = sysid.StateSpaceModel([[0.5, 0.1], [0.0, 0.3]], [[1.0], [1.0]], [[1.0, 2.0]],
    ...                           [[0.0]])
    >>> np.round(output_basis(m).C, 12).tolist()  # the first state is the output
    [[1.0, 0.0]]
    """
    n, l_ = m.nstates, m.noutputs
    k = min(l_, n)
    C = np.asarray(m.C, float)
    u_, s, vt = np.linalg.svd(C)
    r = int(np.sum(s > 1e-9 * max(s[0], 1e-300))) if s.size else 0
    if r < k:
        return m
    # rows: k independent output directions, then the orthogonal complement of C's rows
    Ti = np.vstack([C[:k] if k == l_ else (u_[:, :k].T @ C), vt[r:]])
    if Ti.shape[0] != n:
        return m
    T = np.linalg.inv(Ti)
    return StateSpaceModel(Ti @ m.A @ T, Ti @ m.B, C @ T, m.D, dt=m.dt)


def warn_undetermined(names: list[str], levels: Any, degs: list[int], dropped: int,
                      kept: int) -> None:
    """An :class:`~sysid.ExcitationWarning` when monomials were left out because an input
    takes too few levels (:func:`equation_terms`): which inputs, their levels, how many
    monomials, and what data would determine them.

    Examples
    --------
    >>> import warnings
    >>> from sysid.nlss.monomials import warn_undetermined
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     warn_undetermined(["heater"], [2], [2, 3], 5, 4)
    >>> "heater takes 2 levels" in str(w[0].message)
    True
    """
    from .._checks import user_stacklevel
    from ..errors import ExcitationWarning

    if dropped == 0:
        return
    top = max(degs) if degs else 0
    few = [f"{names[j]} takes {int(k)} levels, so its powers from {int(k)} up"
           for j, k in enumerate(levels) if int(k) <= top]
    warnings.warn(f"pnlss: in the estimation data {' and '.join(few)} equal combinations of "
                  f"lower terms there: monomials with them fit the data no better and would "
                  f"decide alone how the model behaves between and beyond the levels. The "
                  f"{dropped} such monomials are left out ({kept} kept; "
                  f"info['undetermined_monomials']). A nonlinearity in that input needs an "
                  f"excitation of more levels (a multisine, a random-level signal)",
                  ExcitationWarning, stacklevel=user_stacklevel())
