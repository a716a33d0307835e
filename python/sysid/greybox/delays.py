"""Input delays of grey-box structures, also those that are not whole multiples of the sample
time: the exact sampled model and its derivatives.

A continuous system ``dx/dt = A x + B u(t - tau)`` driven by a zero-order-held input
(``u(t) = u_k`` on ``[k h, (k+1) h)``) is sampled exactly for any delay. Write the delay of
input ``j`` as ``tau = l h + r`` with an integer ``l >= 0`` and a fraction ``0 <= r < h``.
Over one sample interval the delayed input is ``u_{k-l-1}`` on ``[k h, k h + r)`` and
``u_{k-l}`` on ``[k h + r, (k+1) h)``, so

.. math::

    x_{k+1} = \\Phi x_k + \\Gamma_0 u_{k-l} + \\Gamma_1 u_{k-l-1},\\qquad
    y_k = C x_k + D u_{k-l-1}\\ (r > 0),

with :math:`\\Phi = e^{A h}`, :math:`\\Gamma_0 = \\int_0^{h-r} e^{A s}\\,ds\\, b_j` and
:math:`\\Gamma_1 = e^{A (h-r)} \\int_0^{r} e^{A s}\\,ds\\, b_j` (Åström and Wittenmark,
*Computer-Controlled Systems*, section 2.3). Both come from two exponentials of the augmented
matrix ``[[A, b_j], [0, 0]]`` (over ``h - r`` and over ``r``), and their derivatives with
respect to a parameter from the Fréchet derivatives of those exponentials and the product
rule, so the gradient stays exact. ``r = 0`` is the usual ``l``-sample shift. Under a
first-order hold the delayed input is linear between the instants ``k h + r`` and each
sample interval gets ``u_{k-l-1}``, ``u_{k-l}`` and ``u_{k-l+1}`` (:func:`foh_columns`; for
``l = 0`` the last is moved into the state, as for the undelayed first-order hold).

The sampled model is handed to the predictor with one input column per *tap* ``(j, s)``:
input ``j`` shifted by ``s`` samples (``s = l`` with ``Γ0``, and ``s = l + 1`` with ``Γ1``
when ``r > 0``); :func:`tap_states` realises the taps as shift-register states (MATLAB's
``c2d`` of a model with ``InputDelay`` does the same).

Examples
--------
>>> import numpy as np
>>> from sysid.greybox.delays import split_delays
>>> split_delays(np.array([0.0, 0.1, 0.13]), 0.05)
(array([0, 2, 2]), array([0.  , 0.  , 0.03]))
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .._checks import check_elements
from ..errors import DataError
from ..models.discretisation import expm

__all__ = ["split_delays", "input_taps", "fractional_columns", "foh_columns", "tap_states",
           "shift_taps"]

#: a delay within this fraction of the sample time of a whole multiple is that multiple
_SNAP = 1e-9


def split_delays(delays: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """``(l, r)``: whole samples and the remaining fraction in seconds, ``tau = l dt + r``.

    Examples
    --------
    >>> from sysid.greybox.delays import split_delays
    >>> split_delays([0.26], 0.1)
    (array([2]), array([0.06]))
    """
    d = np.asarray(delays, dtype=float) / dt
    near = np.round(d)
    whole = np.abs(d - near) <= _SNAP * np.maximum(1.0, d)
    lo = np.where(whole, near, np.floor(d)).astype(int)
    r = np.where(whole, 0.0, (d - lo) * dt)
    return lo, r


def input_taps(delays: np.ndarray, dt: float, hold: str = "zoh") -> list[tuple[int, int]]:
    """The predictor's input columns ``(input, shift in samples)`` for these delays, sorted:
    a whole-sample delay ``l`` is one column; ``l dt + r`` is two under ZOH (``l``,
    ``l + 1``) and three under FOH (``l - 1``, ``l``, ``l + 1``; two, ``0`` and ``1``, when
    ``l = 0``).

    Examples
    --------
    >>> from sysid.greybox.delays import input_taps
    >>> input_taps([0.1, 0.13], 0.05)
    [(0, 2), (1, 2), (1, 3)]
    >>> input_taps([0.1, 0.13], 0.05, "foh")
    [(0, 2), (1, 1), (1, 2), (1, 3)]
    """
    lo, r = split_delays(delays, dt)
    taps: list[tuple[int, int]] = []
    for j, (l, rj) in enumerate(zip(lo, r)):
        if rj == 0:
            taps.append((j, int(l)))
        elif hold == "zoh":
            taps += [(j, int(l)), (j, int(l) + 1)]
        else:
            taps += [(j, s) for s in range(max(int(l) - 1, 0), int(l) + 2)]
    return taps


def _aug(A: np.ndarray, b: np.ndarray, t: float) -> np.ndarray:
    n = A.shape[0]
    M = np.zeros((n + 1, n + 1))
    M[:n, :n], M[:n, n] = A * t, b * t
    return M


def fractional_columns(A: np.ndarray, b: np.ndarray, dt: float, r: float,
                       dirs: list[tuple[np.ndarray, np.ndarray]]
                       ) -> tuple[np.ndarray, np.ndarray, list[tuple[np.ndarray, np.ndarray]]]:
    """``(Γ0, Γ1)`` of one input column ``b`` delayed by the fraction ``0 < r < dt``, and
    their derivatives along each direction ``(dA, db)``.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.greybox.delays import fractional_columns
    >>> g0, g1, _ = fractional_columns(np.array([[-1.0]]), np.array([1.0]), 0.1, 0.04, [])
    >>> bool(np.isclose(g0[0] + g1[0], 1 - np.exp(-0.1)))   # together: the undelayed Γ
    True
    """
    n = A.shape[0]
    E1, L1 = expm(_aug(A, b, dt - r), [_aug(dA, db, dt - r) for dA, db in dirs])
    E2, L2 = expm(_aug(A, b, r), [_aug(dA, db, r) for dA, db in dirs])
    F1, gr = E1[:n, :n], E2[:n, n]
    g0, g1 = E1[:n, n].copy(), F1 @ gr
    ders = [(d1[:n, n].copy(), d1[:n, :n] @ gr + F1 @ d2[:n, n]) for d1, d2 in zip(L1, L2)]
    return g0, g1, ders


def _aug_foh(A: np.ndarray, b: np.ndarray, t: float, ramp: float) -> np.ndarray:
    n = A.shape[0]
    M = np.zeros((n + 2, n + 2))
    M[:n, :n], M[:n, n] = A * t, b * t
    M[n, n + 1] = ramp * t
    return M


def foh_columns(A: np.ndarray, b: np.ndarray, C: np.ndarray, D: np.ndarray, Ad: np.ndarray,
                dt: float, r: float, whole: int,
                dirs: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]
                ) -> tuple[list[tuple[int, np.ndarray, np.ndarray]],
                           list[list[tuple[np.ndarray, np.ndarray]]]]:
    """First-order hold of one input column ``b`` delayed by ``whole dt + r`` (``0 < r <
    dt``): ``[(shift, B column, D column)]`` and their derivatives along each direction
    ``(dA, db, dC, dD, dAd)``.

    The delayed input is linear between the instants ``k dt + r``: over the first ``r``
    seconds of a sample interval it runs from ``u[k-l-1]`` towards ``u[k-l]``, then from
    ``u[k-l]`` towards ``u[k-l+1]``. A segment of length ``T`` starting at ``w0`` with slope
    ``m`` adds ``E[:n, n] w0 + E[:n, n+1] m`` with ``E = exp([[A, b, 0], [0, 0, 1], [0, 0, 0]]
    T)``. With ``l = 0`` the term in ``u[k+1]`` is moved into the state (``z = x - G u[k]``,
    as the plain first-order hold does), which adds ``Ad G`` to ``B`` and ``C G`` to ``D``.
    """
    n, h = A.shape[0], dt
    E1, L1 = expm(_aug_foh(A, b, r, 1.0), [_aug_foh(dA, db, r, 0.0) for dA, db, *_ in dirs])
    E2, L2 = expm(_aug_foh(A, b, h - r, 1.0),
                   [_aug_foh(dA, db, h - r, 0.0) for dA, db, *_ in dirs])

    def first(E: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The first segment's weights of u[k-l-1] and u[k-l] (before the propagation)."""
        e0, e1 = E[:n, n], E[:n, n + 1]
        return e0 * r / h - e1 / h, e0 * (1 - r / h) + e1 / h

    v1, w1 = first(E1)
    F2 = E2[:n, :n]
    gm = F2 @ v1
    g0 = F2 @ w1 + E2[:n, n] - E2[:n, n + 1] / h
    gp = E2[:n, n + 1] / h
    dm, d0 = D * r / h, D * (1 - r / h)
    ders = []
    for (dA, _, dC, dD, dAd), dE1, dE2 in zip(dirs, L1, L2):
        dv1, dw1 = first(dE1)
        dF2 = dE2[:n, :n]
        dgm = dF2 @ v1 + F2 @ dv1
        dg0 = dF2 @ w1 + F2 @ dw1 + dE2[:n, n] - dE2[:n, n + 1] / h
        dgp = dE2[:n, n + 1] / h
        ders.append((dgm, dg0, dgp, dD * r / h, dD * (1 - r / h), dA, dC, dAd))
    if whole >= 1:
        cols = [(whole - 1, gp, np.zeros_like(dm)), (whole, g0, d0), (whole + 1, gm, dm)]
        dcols = [[(dgp, np.zeros_like(ddm)), (dg0, dd0), (dgm, ddm)]
                 for dgm, dg0, dgp, ddm, dd0, *_ in ders]
        return cols, dcols
    cols = [(0, g0 + Ad @ gp, d0 + C @ gp), (1, gm, dm)]
    dcols = [[(dg0 + dAd @ gp + Ad @ dgp, dd0 + dC @ gp + C @ dgp), (dgm, ddm)]
             for dgm, dg0, dgp, ddm, dd0, _, dC, dAd in ders]
    return cols, dcols


def delayed_blocks(raw: Mapping[str, Any], raw_d: list[Mapping[str, Any]],
                   base: Mapping[str, Any], ders: list[Mapping[str, Any]], dt: float,
                   delays: np.ndarray, hold: str
                   ) -> tuple[np.ndarray, np.ndarray, list[tuple[np.ndarray, np.ndarray]]]:
    """``(B_taps, D_taps)`` over the taps (sorted by input, then shift) of a sampled
    continuous structure
    (``raw``: its continuous matrices, ``base``: sampled without delay; ``raw_d``/``ders``
    their derivatives), and the derivatives of ``(B_taps, D_taps)``."""
    lo, r = split_delays(delays, dt)
    A, B, C, D = raw["A"], raw["B"], raw["C"], raw["D"]
    n, l = A.shape[0], D.shape[0]
    cols: list[tuple[int, int, np.ndarray, np.ndarray]] = []
    dcols: list[list[tuple[int, int, np.ndarray, np.ndarray]]] = [[] for _ in ders]
    for j, rj in enumerate(r):
        if rj == 0:
            cols.append((j, int(lo[j]), base["B"][:, j], base["D"][:, j]))
            for d, out in zip(ders, dcols):
                out.append((j, int(lo[j]), d["B"][:, j], d["D"][:, j]))
            continue
        if hold == "zoh":
            g0, g1, gd = fractional_columns(A, B[:, j], dt, float(rj),
                                            [(q["A"], q["B"][:, j]) for q in raw_d])
            cols += [(j, int(lo[j]), g0, np.zeros(l)), (j, int(lo[j]) + 1, g1, D[:, j])]
            for (dg0, dg1), q, out in zip(gd, raw_d, dcols):
                out += [(j, int(lo[j]), dg0, np.zeros(l)), (j, int(lo[j]) + 1, dg1, q["D"][:, j])]
            continue
        fc, fd = foh_columns(A, B[:, j], C, D[:, j], base["A"], dt, float(rj), int(lo[j]),
                             [(q["A"], q["B"][:, j], q["C"], q["D"][:, j], d["A"])
                              for q, d in zip(raw_d, ders)])
        cols += [(j, s, bc, dc) for s, bc, dc in fc]
        for out, dd in zip(dcols, fd):
            out += [(j, s, db, dx) for (s, _, _), (db, dx) in zip(fc, dd)]
    order = sorted(range(len(cols)), key=lambda c: (cols[c][0], cols[c][1]))

    def stack(items: list[tuple[int, int, np.ndarray, np.ndarray]]
              ) -> tuple[np.ndarray, np.ndarray]:
        if not items:
            return np.zeros((n, 0)), np.zeros((l, 0))
        return (np.column_stack([items[c][2] for c in order]),
                np.column_stack([items[c][3] for c in order]))
    Bt, Dt = stack(cols)
    return Bt, Dt, [stack(out) for out in dcols]


def shift_taps(u: np.ndarray, taps: list[tuple[int, int]]) -> np.ndarray:
    """The input columns of the taps: ``u[:, j]`` delayed by ``s`` samples (zeros before).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.greybox.delays import shift_taps
    >>> shift_taps(np.arange(1.0, 4.0)[:, None], [(0, 0), (0, 1)])
    array([[1., 0.],
           [2., 1.],
           [3., 2.]])
    """
    n = u.shape[0]
    out = np.zeros((n, len(taps)))
    for c, (j, s) in enumerate(taps):
        if s < n:
            out[s:, c] = u[:n - s, j]
    return out


def tap_states(mats: Mapping[str, Any], taps: list[tuple[int, int]], m: int
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, Any]:
    """``(A, B, C, D, K)`` of ``m`` inputs from a model whose input columns are taps, the
    shifts realised as shift-register states (``s`` states for the largest shift ``s`` of
    each input).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.greybox.delays import tap_states
    >>> mats = {"A": np.array([[0.5]]), "B": np.array([[0.3, 0.7]]), "C": np.array([[1.0]]),
    ...         "D": np.array([[0.0, 0.0]])}
    >>> A, B, C, D, K = tap_states(mats, [(0, 0), (0, 1)], 1)
    >>> A.tolist(), B.tolist()
    ([[0.5, 0.7], [0.0, 0.0]], [[0.3], [1.0]])
    """
    A, B, C, D, K = mats["A"], mats["B"], mats["C"], mats["D"], mats.get("K")
    n, l = A.shape[0], C.shape[0]
    depth = [max([s for j, s in taps if j == i], default=0) for i in range(m)]
    if len(taps) == m and all(s == 0 for _, s in taps):
        return A, B, C, D, K
    N = n + sum(depth)
    check_elements(N * (N + m + l), f"input delays of {sum(depth)} samples in all (each "
                   "delayed sample is a state)",
                   "check input_delay (it is in seconds, not samples) and the sample time")
    Aa, Ba, Ca, Da = np.zeros((N, N)), np.zeros((N, m)), np.zeros((l, N)), np.zeros((l, m))
    Aa[:n, :n], Ca[:, :n] = A, C
    start, off = [], n
    for i, d in enumerate(depth):
        # chain: u_i(k) -> z_1 = u_i(k-1) -> ... -> z_d = u_i(k-d)
        start.append(off)
        if d:
            Ba[off, i] = 1.0
            for k in range(1, d):
                Aa[off + k, off + k - 1] = 1.0
        off += d
    for c, (i, s) in enumerate(taps):
        if s == 0:
            Ba[:n, i] += B[:, c]
            Da[:, i] += D[:, c]
        else:
            Aa[:n, start[i] + s - 1] += B[:, c]
            Ca[:, start[i] + s - 1] += D[:, c]
    Ka = None if K is None else np.vstack([K, np.zeros((N - n, l))])
    return Aa, Ba, Ca, Da, Ka


def check_fraction(delays: np.ndarray, dt: float, continuous: bool, hold: str) -> None:
    """An error when a delay that is not a multiple of ``dt`` cannot be sampled exactly."""
    _, r = split_delays(delays, dt)
    if not np.any(r > 0):
        return
    if not continuous:
        raise DataError(f"input_delay {np.asarray(delays).tolist()} s is not a multiple of the "
                        f"discrete structure's sample time {dt} s: a discrete model has no "
                        "values between samples; give a whole number of samples or write the "
                        "structure in continuous time (continuous=True)")
