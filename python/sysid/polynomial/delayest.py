"""Input delays from data (MATLAB's ``delayest`` signature): the first lag at which the input
acts on the output, with the ARX(na, nb) loss over delays (MATLAB's criterion) where the
data show none.

MATLAB's criterion alone, the ``nk`` whose ARX(na, nb, nk) model leaves the smallest
residual, comes out late when the input is coloured and the output noisy: the low-order ARX
model cannot describe the plant, its error is coloured, and a later window of ``nb`` input
lags fits it better (a second-order plant with delay 1: 2 in 27 of 30 runs with a smooth
input, 30 of 30 with a narrowband one; the ball and beam: 10). So each output gets an ARX
model of an order high enough for its tests to hold: ``n`` past outputs and, per input, every
lag from ``nk_min`` to ``nk_max + n``, ``n`` chosen by BIC; an input's delay is the smallest
``k`` whose lags ``nk_min..k`` are jointly significant (F test at 1 %, Bonferroni over the
lags tested), so no earlier lag shows a response. The least ARX(na, nb) loss gives the delay,
as before, where nothing in the range is significant, where the record is too short for that
model, and where the input's lags in it are not linearly independent (a sum of a few sines,
or a steep low-pass such as the wing flutter record's input, 15 independent lags of 41: which
lag acts first is not in the data then, and its 14 samples stay): each input alone gives a
start, then a coordinate search changes one input's delay at a time in the ARX model with all
inputs until none improves the loss.

Real records carry offsets (a heater at 5 V, a temperature at 40 degC); an ARX model without
an intercept fits them through its coefficients and the loss then says little about the
delay, so the means of each experiment are removed first. A delay on the edge of the searched
range is reported with a warning, because the response may start beyond it; so is a pair
whose input explains nothing of the output at any delay searched (an F test of its ``nb``
terms at the chosen delay, 1 % with the search over the range corrected for): a delay longer
than the range leaves the loss flat, and its smallest value then falls anywhere in the range
(a delay of 16 samples came out as 2).

Examples
--------
>>> import sysid
>>> sysid.delayest(sysid.datasets.load_dryer())      # Ljung's dryer (MATLAB's delayest: 3)
2

The dryer's response at lag 2 is small (its ARX coefficient under a tenth of lag 3's) but
significant on the full record (t = 4.8); models at delays 2 and 3 fit its validation half
equally (within 0.5 %).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import (
    as_int,
    check_magnitudes,
    experiment_arrays,
    require_inputs_vary,
    user_stacklevel,
)
from .._display import pvalue
from .._threads import one_blas_thread
from ..data.iodata import require_record
from ..errors import DataError, ExcitationError, SysidWarning

__all__ = ["delayest", "delays", "DelayWarning"]


class DelayWarning(SysidWarning):
    """The estimated delay sits on the edge of the searched range, or no delay in the range
    makes the input explain the output (the delay returned there is not determined)."""


@one_blas_thread
def delayest(data: Any, na: int = 2, nb: int = 2, nk_min: int = 0,
             nk_max: int | None = None) -> Any:
    """Input delay(s) in samples: per pair, the first lag with a significant response in a
    high-order ARX model (see the module's description), else MATLAB's least ARX(na, nb)
    loss.

    Parameters
    ----------
    data : IOData or (u, y)
        One or several experiments; one or several inputs and outputs.
    na, nb : int
        Orders of the ARX models whose losses are compared where no lag in the range shows a
        significant response, and of the test that the input explains the output at the
        delay found (``na >= 0``, ``nb >= 1``).
    nk_min, nk_max : int
        Range of delays searched (samples); ``nk_max`` defaults to ``nk_min + 20``, as
        MATLAB's (less when the shortest experiment allows fewer).

    Returns
    -------
    int or ndarray
        The delay of a single-input single-output record; ``(noutputs, ninputs)`` otherwise.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from scipy import signal
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((600, 2))
    >>> y = signal.lfilter([0, 0, 0, 0.7], [1, -0.5], u[:, 0]) + \\
    ...     signal.lfilter([0, 1.0], [1, -0.2], u[:, 1]) + 5.0   # an offset, as real records
    >>> sysid.delayest(sysid.IOData(u, y[:, None], 1.0))
    array([[3, 1]])
    """
    data = require_record(data, "delayest")
    out, weak, nk_min, nk_max = delays(data, na, nb, nk_min, nk_max)
    flat = [(i, j) for i, j, p in weak if np.isnan(p)]
    weak = [w for w in weak if not np.isnan(w[2])]
    if flat:
        warnings.warn("the delay of " + ", ".join(f"{data.input_names[j]} -> "
                                                   f"{data.output_names[i]}" for i, j in flat)
                      + " is not determined: the input does not excite its lags "
                      "independently (a few sines, a steep low-pass), so which acts first is "
                      "not in the data; the delay returned there is the least ARX "
                      f"({na}, {nb}) loss's, which such an input can place anywhere",
                      DelayWarning, stacklevel=user_stacklevel())
    if weak:
        names = [f"{data.input_names[j]} -> {data.output_names[i]} ({pvalue(p)})"
                 for i, j, p in weak]
        warnings.warn(f"no delay in {nk_min}..{nk_max} makes the input explain the output "
                      f"for {', '.join(names)} (F test of its ARX terms at 1 %, corrected for "
                      "the search): the delay "
                      "may be longer than the range (search a larger nk_max) or the input "
                      "not act on that output; the delay returned there is not determined",
                      DelayWarning, stacklevel=user_stacklevel())
    edge = (out == nk_max) & (nk_max > nk_min)
    if np.any(edge):
        warnings.warn(f"the estimated delay equals nk_max={nk_max} for "
                      f"{int(edge.sum())} pair(s): the loss may fall further beyond; "
                      "search a larger range (nk_max)", DelayWarning, stacklevel=user_stacklevel())
    l, m = out.shape
    return int(out[0, 0]) if l == m == 1 else out


def delays(data: Any, na: int = 2, nb: int = 2, nk_min: int = 0, nk_max: int | None = None
           ) -> tuple[np.ndarray, list[tuple[int, int, float]], int, int]:
    """:func:`delayest`'s work without its warnings: the ``(noutputs, ninputs)`` delays, the
    pairs ``(output, input, p)`` whose delay the data do not determine (its input explains
    nothing at it, ``p`` the test's; or ``p`` NaN: the input does not excite its lags
    independently, so which acts first is not in the data, and the delay there is MATLAB's
    least ARX loss), and the range searched ``(nk_min, nk_max)``.

    Examples
    --------
    >>> import sysid
    >>> from sysid.polynomial.delayest import delays
    >>> nk, weak, lo, hi = delays(sysid.datasets.load_dryer())
    >>> int(nk[0, 0]), weak, (lo, hi)
    (2, [], (0, 20))
    """
    data = require_record(data, "delayest")
    na = as_int(na, "na", 0, 50)
    nb = as_int(nb, "nb", 1, 50)
    nk_min = as_int(nk_min, "nk_min", 0)
    default = nk_max is None
    nk_max = nk_min + 20 if default else as_int(nk_max, "nk_max", 0)
    if nk_min > nk_max:
        raise DataError(f"need nk_min <= nk_max, got {nk_min} and {nk_max}")
    exps = experiment_arrays(data)
    m, l = exps[0][0].shape[1], exps[0][1].shape[1]
    if m == 0:
        raise DataError("delayest needs inputs: a time series has no input delay")
    require_inputs_vary(exps, "delayest", getattr(data, "input_names", None),
                        error=ExcitationError)  # a constant input shows no delay
    # nor does a constant output (its ARX losses are all zero)
    require_inputs_vary(exps, "delayest", getattr(data, "output_names", None), side=1)
    check_magnitudes(exps, "delayest")  # ARX losses of outputs near 1e200 overflow
    shortest = min(u.shape[0] for u, _ in exps)
    if default:  # MATLAB's range, or what the shortest experiment allows
        nk_max = max(nk_min, min(nk_max, (shortest - 2) // 2 - max(na, nb) - na - m * nb))
    need = 2 * (nk_max + max(na, nb) + na + m * nb) + 2
    if shortest < need:
        raise DataError(f"the shortest experiment has {shortest} samples, too few to compare "
                        f"delays up to nk_max={nk_max} with ARX({na}, {nb}): give at least "
                        f"{need} samples or "
                        + ("smaller na and nb" if nk_max <= nk_min else "a smaller nk_max"))
    centred = [(np.ascontiguousarray(u - u.mean(axis=0)), y - y.mean(axis=0)) for u, y in exps]
    out = np.zeros((l, m), dtype=int)
    grid = list(range(nk_min, nk_max + 1))
    weak: list[tuple[int, int, float]] = []
    memo: dict[str, Any] = {}  # the inputs' part of the normal equations, the same for all
    for i in range(l):
        one = [(u, np.ascontiguousarray(y[:, [i]])) for u, y in centred]
        out[i] = _first_response(one, nk_min, nk_max, memo)
        unexcited = out[i] == -2  # which lag acts first is not in the data
        if np.any(out[i] < 0):  # no response found in the range: the least ARX loss
            out[i] = np.where(out[i] < 0, _output_delays(one, na, nb, grid), out[i])
        # the chosen delay is the best of len(grid): Bonferroni's correction for the search
        weak += [(i, j, float("nan") if unexcited[j] else min(1.0, p * len(grid)))
                 for j, p in enumerate(_input_p_values(one, na, nb, out[i]))
                 if unexcited[j] or p * len(grid) > 0.01]
    return out, weak, nk_min, nk_max


def _input_p_values(exps: list[tuple[np.ndarray, np.ndarray]], na: int, nb: int,
                    nk: np.ndarray) -> list[float]:
    """Per input, the p-value of the F test of its ``nb`` terms in the ARX model of one
    output at the delays ``nk`` (the model without that input nested in it, both fitted on
    the same samples)."""
    from scipy.special import fdtrc  # the F distribution's survival function (no scipy.stats:
    # its import costs about a second, and identify searches delays on every record)

    m = len(nk)
    t0 = max(na, int(max(nk)) + nb - 1)
    p = na + m * nb
    G, g, zz, count = np.zeros((p, p)), np.zeros(p), 0.0, 0
    for u, y in exps:  # the normal equations, accumulated over blocks of samples
        for a in range(t0, y.shape[0], 65536):
            b = min(a + 65536, y.shape[0])
            cols = [-y[a - k:b - k, 0] for k in range(1, na + 1)]
            cols += [u[a - int(nk[j]) - q:b - int(nk[j]) - q, j] for j in range(m)
                     for q in range(nb)]
            X, z = np.column_stack(cols), y[a:b, 0]
            G += X.T @ X
            g += X.T @ z
            zz += float(z @ z)
            count += b - a
    dof = count - p

    def loss(keep: np.ndarray) -> float:
        if keep.size == 0:
            return zz
        theta = np.linalg.lstsq(G[np.ix_(keep, keep)], g[keep], rcond=None)[0]
        return max(zz - float(theta @ g[keep]), 0.0)

    full = loss(np.arange(p))
    out = []
    for j in range(m):
        own = na + j * nb + np.arange(nb)
        low = loss(np.setdiff1d(np.arange(p), own))
        if dof <= 0 or not full > 0:
            out.append(0.0)
            continue
        F = (low - full) / nb / (full / dof)
        out.append(float(fdtrc(nb, dof, max(F, 0.0))))
    return out


def _output_delays(exps: list[tuple[np.ndarray, np.ndarray]], na: int, nb: int,
                   grid: list[int]) -> np.ndarray:
    m = exps[0][0].shape[1]
    nk = []
    for j in range(m):
        sub = [(np.ascontiguousarray(u[:, [j]]), y) for u, y in exps]
        table = np.asarray(_sysid.arx_struc(sub, [na], [nb], grid))
        nk.append(int(table[int(np.argmin(table[:, 3])), 2]))
    if m == 1:
        return np.array(nk)

    loss = _ArxLosses(exps, na, nb, grid)

    best = loss(nk)
    for _ in range(5):                   # coordinate sweeps until no input's delay moves
        moved = False
        for j in range(m):
            for cand in grid:
                if cand == nk[j]:
                    continue
                trial = list(nk)
                trial[j] = cand
                v = loss(trial)
                if v < best * (1 - 1e-12):
                    best, nk, moved = v, trial, True
        if not moved:
            break
    return np.array(nk)


class _ArxLosses:
    """``loss(nk)``: the loss of the ARX(na, nb, nk) model of one output with every input
    (the mean squared residual on the rows ``t >= max(na, nk_j + nb - 1, 1)`` of each
    experiment), exactly as ``_sysid.arx_fit`` computes it, for the coordinate search's many
    delays from one compression: the QR factor of every regressor the delays in ``grid`` use
    (``R``, on the rows all of them have) and the few earlier rows a shorter structure also
    fits; each loss is then the QR of a small matrix, not of the record (on the steam
    generator's 4 inputs, 565 losses took 23 s through ``arx_fit``). A structure whose
    regressors are dependent goes to ``arx_fit``, for its error."""

    def __init__(self, exps: list[tuple[np.ndarray, np.ndarray]], na: int, nb: int,
                 grid: list[int]) -> None:
        self.exps, self.na, self.nb = exps, na, nb
        self.m = exps[0][0].shape[1]
        self.lo = min(grid)
        self.width = max(grid) + nb - self.lo          # lags per input
        self.top = max(na, max(grid) + nb - 1, 1)
        R = np.zeros((0, na + self.m * self.width + 1))
        self.heads: list[np.ndarray] = []
        for u, y in exps:
            for a in range(self.top, y.shape[0], 65536):
                b = min(a + 65536, y.shape[0])
                R = np.linalg.qr(np.vstack([R, self._rows(u, y, a, b)]), mode="r")
            self.heads.append(self._rows(u, y, 1, self.top))
        self.R = R

    def _rows(self, u: np.ndarray, y: np.ndarray, a: int, b: int) -> np.ndarray:
        """The regressors (``y(t-1..t-na)``, then per input ``u_j(t-lo..)``) and the output
        of rows ``a..b-1``; a lag before the record is NaN (never used)."""
        t = np.arange(a, b)

        def lagged(x: np.ndarray, k: int) -> np.ndarray:
            return np.where(t - k >= 0, x[np.maximum(t - k, 0)], np.nan)

        cols = [-lagged(y[:, 0], k) for k in range(1, self.na + 1)]
        cols += [lagged(u[:, j], self.lo + q) for j in range(self.m)
                 for q in range(self.width)]
        cols.append(y[a:b, 0])
        return np.column_stack(cols) if b > a else np.zeros((0, len(cols)))

    def __call__(self, nk: list[int]) -> float:
        na, nb = self.na, self.nb
        start = max(na, max(nk) + nb - 1, 1)
        cols = list(range(na)) + [na + j * self.width + k - self.lo + q
                                  for j, k in enumerate(nk) for q in range(nb)]
        cols.append(self.R.shape[1] - 1)
        S = np.vstack([self.R[:, cols]] + [h[start - 1:, cols] for h in self.heads])
        r = np.linalg.qr(S, mode="r")
        d = np.abs(np.diag(r)[:-1])
        rows = sum(y.shape[0] - start for _, y in self.exps)
        if d.size == 0 or not np.all(d > 1e-12 * d.max()):  # arx_fit's rank check: its error
            return float(_sysid.arx_fit(self.exps, [[na]], [[nb] * self.m], [nk])[0]["loss"])
        return float(r[-1, -1] ** 2 / rows)


#: the ARX orders tried (same for the output's past and the input lags past the range)
ORDERS = (2, 4, 6, 8, 12, 16, 20)


def _first_response(exps: list[tuple[np.ndarray, np.ndarray]], nk_min: int,
                    nk_max: int, memo: dict[str, Any] | None = None) -> np.ndarray:
    """Per input, the first lag in ``nk_min..nk_max`` with evidence of a response, or -1
    where there is none.

    The model: ARX with ``n`` past outputs and, per input, every lag from ``nk_min`` to
    ``nk_max + n``, ``n`` in :data:`ORDERS` by BIC (at most a quarter as many regressors as
    samples), all fitted on the same samples, so its residuals are near white and its F
    tests hold. The delay of input ``j``: the smallest ``k`` whose lags ``nk_min..k`` are
    jointly significant (F test at 1 %, Bonferroni over the ``nk_max - nk_min + 1`` lags
    tested); none before it is. -1 for every input where no order fits the record and for
    an input whose lags in the range are not significant; -2 for an input whose lags in the
    model are not linearly independent (it is not persistently exciting of that order:
    which lag acts first is then not in the data, and the test would only find where too
    few lags are left to stand in for the dropped ones)."""
    m = exps[0][0].shape[1]
    out = np.full(m, -1)
    top = max(ORDERS)
    t0 = nk_max + top
    width = nk_max - nk_min + top + 1          # lags per input at the largest order
    rows = sum(max(y.shape[0] - t0, 0) for _, y in exps)
    orders = [n for n in ORDERS if n + m * (nk_max - nk_min + n + 1) <= rows / 4]
    if not orders:
        return out
    lags = [list(range(nk_min, nk_max + top + 1))] * m
    G, g, zz, count = _normal_equations(exps, top, lags, t0, memo)
    if not zz > 0:
        return out

    def columns(n: int) -> np.ndarray:  # the regressors of order n among the largest's
        return np.concatenate([np.arange(n)] + [top + j * width
                                                + np.arange(nk_max - nk_min + n + 1)
                                                for j in range(m)])

    def loss(keep: np.ndarray) -> float:
        return float(_nested_losses(G, g, zz, keep)[-1])

    bic = [count * np.log(loss(columns(n)) / count) + np.log(count) * columns(n).size
           for n in orders]
    n = orders[int(np.argmin(bic))]
    cols = columns(n)
    full, dof, ntest = loss(cols), count - cols.size, nk_max - nk_min + 1
    exact = not full > 1e-13 * zz    # noise-free: only whether the terms are needed at all
    from scipy.special import fdtrc

    for j in range(m):
        own = top + j * width + np.arange(nk_max - nk_min + n + 1)
        if _nested_losses(G, g, zz, own, pivots=True).min() <= 1e-10:
            out[j] = -2  # its lags are not independent: a few sines, or a steep low-pass
            continue
        block = own[:ntest]                         # u_j(t - nk_min) .. u_j(t - nk_max)
        # the block last, latest lag first: leaving out lags nk_min..k leaves a leading set
        losses = _nested_losses(G, g, zz, np.r_[np.setdiff1d(cols, block), block[::-1]])
        for k in range(ntest):
            low = losses[cols.size - k - 1]
            if exact:
                hit = low > 1e-9 * zz
            else:
                F = (low - full) / (k + 1) / (full / dof)
                hit = float(fdtrc(k + 1, dof, max(F, 0.0))) * ntest < 0.01
            if hit:
                out[j] = nk_min + k
                break
    return out


def _nested_losses(G: np.ndarray, g: np.ndarray, zz: float, order: np.ndarray,
                   pivots: bool = False) -> np.ndarray:
    """The least-squares losses of the models on the first ``q`` regressors of ``order``,
    ``q = 0 .. len(order)``, from the normal equations ``(G, g, zz)``: Gaussian elimination
    of the scaled equations in that order (a Cholesky factor), a regressor that the ones
    before it already span (its residual below ``1e-10`` of its own square) left out, so it
    explains nothing (a sum of sines excites only a few lags: the others are combinations of
    them). Floored at ``1e-13 zz``. ``pivots=True``: instead, each regressor's residual
    variance given the ones before it, relative to its own (0 .. 1)."""
    p = len(order)
    d = np.sqrt(np.maximum(np.diag(G)[order], 1e-300))
    M = np.empty((p + 1, p + 1))
    M[:p, :p] = G[np.ix_(order, order)] / np.outer(d, d)
    M[:p, p] = M[p, :p] = g[order] / d
    M[p, p] = zz
    out, piv = np.empty(p + 1), np.empty(p)
    out[0] = zz
    for k in range(p):
        piv[k] = M[k, k]
        if M[k, k] > 1e-10:
            M[k + 1:, k + 1:] -= np.outer(M[k + 1:, k], M[k, k + 1:] / M[k, k])
        out[k + 1] = M[p, p]
    return piv if pivots else np.maximum(out, 1e-13 * zz)


def _normal_equations(exps: list[tuple[np.ndarray, np.ndarray]], na: int,
                      lags: list[list[int]], t0: int, memo: dict[str, Any] | None = None
                      ) -> tuple[np.ndarray, np.ndarray, float, int]:
    """``(X'X, X'z, z'z, rows)`` of the regression of one output ``y(t)`` on ``-y(t - 1) ..
    -y(t - na)`` and, per input ``j``, ``u_j(t - k)`` for ``k`` in ``lags[j]``, over the
    samples ``t >= t0`` of every experiment, accumulated in blocks. ``memo`` (a dict shared
    by the outputs of one record, same ``lags`` and ``t0``) keeps the inputs' block of
    ``X'X``, the largest, formed once for all outputs."""
    q = sum(len(k) for k in lags)
    uu = None if memo is None else memo.get("uu")
    Guu = np.zeros((q, q)) if uu is None else uu
    Gyy, Gyu, gy, gu = np.zeros((na, na)), np.zeros((na, q)), np.zeros(na), np.zeros(q)
    zz, count = 0.0, 0
    for u, y in exps:
        for a in range(t0, y.shape[0], 65536):
            b = min(a + 65536, y.shape[0])
            Y = np.column_stack([-y[a - k:b - k, 0] for k in range(1, na + 1)]
                                or [np.zeros((b - a, 0))])
            U = np.column_stack([u[a - k:b - k, j] for j, ks in enumerate(lags) for k in ks])
            z = y[a:b, 0]
            if uu is None:
                Guu += U.T @ U
            Gyy += Y.T @ Y
            Gyu += Y.T @ U
            gy += Y.T @ z
            gu += U.T @ z
            zz += float(z @ z)
            count += b - a
    if memo is not None:
        memo["uu"] = Guu
    G = np.block([[Gyy, Gyu], [Gyu.T, Guu]])
    return G, np.r_[gy, gu], zz, count
