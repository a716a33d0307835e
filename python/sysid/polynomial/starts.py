"""Where the polynomial prediction-error searches (``armax``, ``oe``, ``bj``) start: another
polynomial model's coefficients (``init=``) and, for ``oe`` and ``bj``, a subspace fit per
output written as ``B/F`` (:func:`second_start` runs it)."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import DataError, NumericalError
from .model import PolynomialModel

__all__ = ["RESTART_GAIN", "init_parameters", "second_start", "subspace_starts"]

#: the subspace start's search replaces the default one's (per output) only when it ends
#: lower by more than this fraction of the criterion (both reach the same minimum on most
#: records)
RESTART_GAIN = 1e-8


def _fit(c: np.ndarray, n: int) -> list[float]:
    out = np.zeros(n)
    out[: min(n, c.size)] = c[:n]
    return out.tolist()


def _stable(c: Any) -> np.ndarray:
    """Coefficients (after the leading 1) of the monic polynomial with the roots of
    ``1 + c_1 q^-1 + ...`` outside the unit circle reflected inside (``r -> 1 / conj(r)``,
    at most 0.995 in modulus): the same magnitude response up to a gain, and a predictor
    the search can start from."""
    c = np.asarray(c, dtype=float).ravel()
    if c.size == 0:
        return c
    r = np.roots(np.concatenate([[1.0], c]))
    if np.all(np.abs(r) < 1.0):
        return c
    out = np.where(np.abs(r) >= 1.0, 1.0 / np.conj(r), r)
    big = np.abs(out) > 0.995
    out[big] *= 0.995 / np.abs(out[big])
    return np.real(np.poly(out))[1:]


def init_parameters(
    init: PolynomialModel, i: int, na: int, nb: list[int], nc: int, nd: int, nf: list[int]
) -> tuple[list[float], bool]:
    """Starting parameters of output ``i`` from another polynomial model (``F`` from its
    ``F``, or from its ``A`` when it has none, as when refining an ARX model into OE; each
    polynomial cut or padded with zeros to the order asked), and whether an unstable ``C``,
    ``D`` or ``F`` had its roots reflected into the unit circle (MATLAB stabilises an
    initial model the same way; the search needs a stable predictor).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.polynomial.starts import init_parameters
    >>> arx = sysid.PolynomialModel([[np.array([-0.9])]], [[np.array([0.5])]], [[1]], 1.0)
    >>> init_parameters(arx, 0, 0, [2], 0, 0, [1])  # OE(2, 1): B padded, F from A
    ([0.5, 0.0, -0.9], False)
    """
    if init.n_inputs != len(nb) or init.n_outputs <= i:
        raise DataError("init has other input/output counts than the data")
    a = init.a[i][i]
    th = _fit(a, na)
    th += [v for j, n in enumerate(nb) for v in _fit(init.b[i][j], n)]
    moved = False
    for c, n in ((init.c[i], nc), (init.d[i], nd)) + tuple(
            (init.f[i][j] if init.f[i][j].size else a, n) for j, n in enumerate(nf)):
        got = np.asarray(_fit(np.asarray(c, dtype=float), n))
        st = _stable(got)
        moved |= bool(got.size and not np.array_equal(st, got))
        th += st.tolist()
    return th, moved


def subspace_starts(data: IOData, nb: list[list[int]], nf: list[list[int]],
                    nk: list[list[int]]) -> list[PolynomialModel | None]:
    """Per output ``i``, ``B_ij / F_ij`` of :func:`sysid.n4sid` of order ``max_j nf_ij`` on
    that output alone: every ``F_ij`` its characteristic polynomial (cut to ``nf_ij`` when
    lower), ``B_ij`` its numerator from lag ``nk_ij`` on (``C (zI - A)^-1 b_j + d_j =
    (det(zI - A + b_j C) - det(zI - A)) / det(zI - A) + d_j``, ``d_j`` only where
    ``nk_ij = 0``), as a one-output model;
    ``None`` for an output whose subspace fit fails or has no ``F`` to start.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.polynomial.starts import subspace_starts
    >>> g = sysid.TransferFunction([0.0, 0.5], [1.0, -0.8], dt=1.0)
    >>> u = np.random.default_rng(0).standard_normal(500)
    >>> s = subspace_starts(sysid.IOData(u, g.simulate(u), 1.0), [[1]], [[1]], [[1]])[0]
    >>> np.round([s.b[0][0][0], s.f[0][0][0]], 6).tolist()
    [0.5, -0.8]
    """
    from ..subspace.estimator import SubspaceEstimator, horizon_for_order

    out: list[PolynomialModel | None] = []
    exps = data.experiments
    for i in range(data.n_outputs):
        n = max(nf[i], default=0)
        if n < 1 or not any(nb[i]):
            out.append(None)
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                one = IOData([u for u, _ in exps], [y[:, [i]] for _, y in exps], data.dt) \
                    if len(exps) > 1 else IOData(exps[0][0], exps[0][1][:, [i]], data.dt)
                s = SubspaceEstimator(one, horizon_for_order(one, n, None), method="n4sid").fit(
                    n, feedthrough=min(nk[i]) == 0)
        except Exception:  # noqa: BLE001 - no subspace start for this output: the default's
            out.append(None)
            continue
        A, B, C, D = (np.asarray(x, dtype=float) for x in (s.A, s.B, s.C, s.D))
        den = np.real(np.poly(A))
        b, f = [], []
        for j in range(data.n_inputs):
            # D only where this input acts at lag 0 (another input's nk = 0 made n4sid fit it)
            d = float(D[0, j]) if nk[i][j] == 0 else 0.0
            num = np.real(np.poly(A - B[:, [j]] @ C)) - den + d * den
            b.append(np.array([num[nk[i][j] + k] if nk[i][j] + k < num.size else 0.0
                               for k in range(nb[i][j])]))
            f.append(den[1:nf[i][j] + 1])
        if not all(np.all(np.isfinite(x)) for x in b + f):
            out.append(None)
            continue
        out.append(PolynomialModel([[np.zeros(0)]], [b], [list(nk[i])], data.dt,
                                   c=[np.zeros(0)], d=[np.zeros(0)], f=[f]))
    return out


def second_start(data: Any, rs: list[dict[str, Any]], search: Callable[..., Any],
                 nb: Any, nf: Any, nk: Any, na: Any, nc: Any, nd: Any,
                 progress: bool | None | Callable[..., Any], info: dict[str, Any]) -> None:
    """Each output's search also from its subspace start (``C = D = 1``): its result
    replaces the default one's in ``rs`` when its criterion is lower by more than
    ``RESTART_GAIN``; ``info["start"]`` names the start kept (one name for one output, a
    list per output otherwise). The Steiglitz-McBride iterates need not come near the
    minimum: on a motor-position record (EMPS, an integrating plant) every stable iterate is
    far from it; ``oe(2, 2, 1)`` ended at a 1.9 % fit (83.7 % from the subspace start) and
    ``bj(2, 1, 1, 2, 1)`` simulated at 0.05 % (94.7 %, at a lower prediction-error
    criterion). A search stopped by the user's callback is not followed by another. The
    second search sets the initial conditions as the first chose (``"auto"`` decides once per
    output, so that the two criteria compare)."""
    names = ["Steiglitz-McBride"] * len(rs)
    if any(r["stop"] == "cancelled" for r in rs):
        info["start"] = names[0] if len(rs) == 1 else names
        return
    # the bar counted the first searches; a callable of the user's sees every step
    cb = progress if callable(progress) else None
    for i, s in enumerate(subspace_starts(data, nb, nf, nk)):
        if s is None:
            continue
        theta0 = init_parameters(s, 0, na[i], nb[i], nc[i], nd[i], nf[i])[0]
        try:
            with warnings.catch_warnings():  # a failed second search says nothing
                warnings.simplefilter("ignore")
                r = search(i, theta0, cb, rs[i]["initial_condition"])
        except (DataError, NumericalError):
            continue  # the first search stands
        if r["history"][-1] < rs[i]["history"][-1] * (1 - RESTART_GAIN):
            r["auto_costs"] = rs[i].get("auto_costs")  # what decided the initial conditions
            rs[i], names[i] = r, "subspace (n4sid)"
        if r["stop"] == "cancelled":
            break
    info["start"] = names[0] if len(rs) == 1 else names
