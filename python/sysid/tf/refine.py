"""Output-error refinement of continuous-time rational models on sampled data, shared by
:func:`sysid.tfest` and :func:`sysid.procest`.

One output ``y = sum_j G_j(s; p_j) e^{-s tau_j} u_j + e`` with any parameterisation
``p_j -> (num_j, den_j)`` of each pair: the pairs are realised (controllable canonical form),
sampled exactly with the data's hold and their delays (:mod:`sysid.tf.sampling`), and the
simulation error is minimised by the grey-box predictor on the shared Gauss-Newton search
(``_sysid.greybox_linear`` with focus ``"simulation"``; the map from ``p`` and the delays to
the sampled matrices is differentiated exactly, :mod:`sysid.tf.sensitivity`: complex step
through the rational coefficients, Fréchet derivatives of the sampling exponentials). A delay moves
freely inside one sample interval ``[l h, (l + 1) h]`` (the sampled model is smooth there);
when it ends on an edge the interval moves and the search resumes. The covariance of ``p``
and the delays is the Gauss-Newton one with the residual variance (shared
:mod:`sysid_core::optim::covariance`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import user_stacklevel, warn_if_capped, warn_iteration_limit
from ..errors import DataError, IterationLimitWarning
from ..greybox.delays import shift_taps
from .model import assemble
from .sampling import canonical, natural_frequency, sample_pair
from .sensitivity import pair_derivatives

__all__ = ["PairStructure", "refine", "free_search", "free_test", "ConvergenceWarning"]

#: iterations of the search in a neighbouring delay interval before the best one is run out
TRIAL_ITER = 8


class ConvergenceWarning(IterationLimitWarning):
    """The search stopped on its iteration limit, before a convergence test was met."""

Coef = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


@dataclass
class PairStructure:
    """One input's rational model: ``coef(p) -> (num, den)`` (descending powers)."""

    coef: Coef
    p0: np.ndarray
    fixed: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    delay: float = 0.0
    delay_free: bool = False
    delay_max: float = np.inf
    names: list[str] = field(default_factory=list)


class _Map:
    """``z -> theta`` of the grey-box predictor for fixed delay intervals."""

    def __init__(self, pairs: Sequence[PairStructure], dt: float, hold: str,
                 whole: list[int], exps: list[tuple[np.ndarray, np.ndarray]],
                 x0_mode: str) -> None:
        self.pairs, self.dt, self.hold, self.whole = pairs, dt, hold, whole
        # each pair realised in time scaled by its start's natural frequency, fixed for the
        # search (a high-order pair's plain companion form lost its poles in the sampling)
        self.freqs = [natural_frequency(p.coef(p.p0)[1]) for p in pairs]
        self.sizes = [p.p0.size for p in pairs]
        self.delay_idx = [j for j, p in enumerate(pairs) if p.delay_free or p.delay > 0]
        self.m = len(pairs)
        v0 = self.vector([p.p0 for p in pairs], [p.delay for p in pairs])
        self.scale = np.maximum(np.abs(v0), 1e-3)
        for k, _ in enumerate(self.delay_idx):
            self.scale[sum(self.sizes) + k] = dt
        base = self.sampled(v0)
        self.taps, self.n = base[4], base[0].shape[0]
        self.x0_mode = x0_mode
        self.u0 = [u[0] for u, _ in exps]
        self.n_x0 = self.n * len(exps) if x0_mode == "estimate" else 0
        self._layouts: list[np.ndarray] | None = None

    def vector(self, ps: Sequence[np.ndarray], taus: Sequence[float]) -> np.ndarray:
        return np.concatenate(list(ps) + [np.array([taus[j] for j in self.delay_idx])])

    def split(self, v: np.ndarray) -> tuple[list[np.ndarray], list[float]]:
        ps, o = [], 0
        for k in self.sizes:
            ps.append(v[o:o + k])
            o += k
        taus = [p.delay for p in self.pairs]
        for k, j in enumerate(self.delay_idx):
            taus[j] = float(v[o + k])
        return ps, taus

    def sampled(self, v: np.ndarray) -> tuple[Any, ...]:
        ps, taus = self.split(v)
        blocks, canon = [], []
        for j, (pair, p, tau) in enumerate(zip(self.pairs, ps, taus)):
            num, den = pair.coef(p)
            A, b, c, d = canonical(den, num, self.freqs[j])
            r = tau - self.whole[j] * self.dt
            blocks.append((0, j, sample_pair(A, b, c, d, self.dt, self.whole[j], r, self.hold)))
            canon.append((A, b, c, d))
        return assemble(blocks, canon, 1, self.m)

    def theta(self, z: np.ndarray) -> np.ndarray:
        nv = z.size - self.n_x0
        Ad, Bt, Cd, Dt, _, G = self.sampled(z[:nv] * self.scale)
        x0s = [-G @ u0 for u0 in self.u0]
        if self.n_x0:
            x0s = [x + z[nv + e * self.n:nv + (e + 1) * self.n] for e, x in enumerate(x0s)]
        return np.concatenate([Ad.ravel(), Bt.ravel(), Cd.ravel(), Dt.ravel(), *x0s])

    def __call__(self, z: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
        z = np.asarray(z, dtype=float)
        # a trial step far out (a time constant at its bound, poles near -1e9 on the winding
        # record) overflows the sampling's matrix exponentials: the search rejects the
        # non-finite result, and NumPy's RuntimeWarning reached the user
        with np.errstate(over="ignore", invalid="ignore"):
            if not jac:
                return self.theta(z), None
            return self.theta_and_jacobian(z)

    def theta_and_jacobian(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``theta(z)`` and ``d theta / d z``, exact (:mod:`sysid.tf.sensitivity`)."""
        nv = z.size - self.n_x0
        v = z[:nv] * self.scale
        ps, taus = self.split(v)
        derivs = []
        for j, (pair, p, tau) in enumerate(zip(self.pairs, ps, taus)):
            r = tau - self.whole[j] * self.dt
            derivs.append(pair_derivatives(pair.coef, p, self.dt, self.whole[j], r,
                                           self.hold, self.freqs[j]))
        th = self._assembled([(d.Ad, d.cols, d.G, d.c) for d in derivs])
        if self.n_x0:
            th[th.size - self.n_x0:] += z[nv:]
        M = np.zeros((th.size, z.size))
        offs = np.concatenate([[0], np.cumsum(self.sizes)])
        layout = self._layout(derivs)
        for j, d in enumerate(derivs):
            cols = [offs[j] + k for k in range(self.sizes[j])]
            if j in self.delay_idx:
                cols.append(int(offs[-1]) + self.delay_idx.index(j))
            else:
                cols.append(-1)
            for k, col in enumerate(cols):
                if col < 0:
                    continue
                M[:, col] = layout[j] @ _flat((d.d_Ad[k], d.d_cols[k], d.d_G[k], d.d_c[k]))
        M[:, :nv] *= self.scale
        if self.n_x0:
            M[th.size - self.n_x0:, nv:] = np.eye(self.n_x0)
        return th, M

    def _layout(self, derivs: list[Any]) -> list[np.ndarray]:
        """Per pair, the matrix that takes its part ``(Ad, cols, G, c)`` flattened
        (:func:`_flat`) to ``theta`` with every other pair's part zero: :meth:`_assembled` is
        linear, so it is found once per map (the pairs' shapes and taps are fixed) by
        assembling each unit part, and a Jacobian column is then one product."""
        if self._layouts is None:
            zero = [_unflat(np.zeros(_flat(p).size), p)
                    for p in ((d.Ad, d.cols, d.G, d.c) for d in derivs)]
            layouts = []
            for j, part in enumerate(zero):
                size = _flat(part).size
                cols = []
                for i in range(size):
                    unit = np.zeros(size)
                    unit[i] = 1.0
                    cols.append(self._assembled(zero[:j] + [_unflat(unit, part)]
                                                + zero[j + 1:]))
                layouts.append(np.stack(cols, axis=1) if cols
                               else np.zeros((self._assembled(zero).size, 0)))
            self._layouts = layouts
        return self._layouts

    def _assembled(self, parts: list[tuple[Any, ...]]) -> np.ndarray:
        """``theta`` (initial states at rest) from per-pair ``(Ad, cols, G, c)``; linear in
        them, so it maps derivatives too."""
        blocks = [(0, j, (a, cols, g)) for j, (a, cols, g, _) in enumerate(parts)]
        canon = [(None, None, c, None) for *_, c in parts]
        Ad, Bt, Cd, Dt, _, G = assemble(blocks, canon, 1, self.m)
        return np.concatenate([Ad.ravel(), Bt.ravel(), Cd.ravel(), Dt.ravel(),
                               *[-G @ u0 for u0 in self.u0]])


def _flat(part: tuple[Any, ...]) -> np.ndarray:
    """A pair's part ``(Ad, cols, G, c)`` (``cols``: ``(tap, b column, d entry)``) as one
    vector."""
    Ad, cols, G, c = part
    return np.concatenate([np.ravel(Ad)] + [np.concatenate([np.ravel(b), np.ravel(d)])
                                            for _, b, d in cols] + [np.ravel(G), np.ravel(c)])


def _unflat(v: np.ndarray, like: tuple[Any, ...]) -> tuple[Any, ...]:
    """The inverse of :func:`_flat`, shapes and taps from ``like``."""
    Ad, cols, G, c = like
    o = 0

    def take(a: Any) -> np.ndarray:
        nonlocal o
        a = np.asarray(a)
        out = v[o:o + a.size].reshape(a.shape)
        o += a.size
        return out
    return take(Ad), [(s, take(b), take(d)) for s, b, d in cols], take(G), take(c)


def _bounds(pairs: Sequence[PairStructure], mp: _Map) -> tuple[np.ndarray, ...]:
    lo = np.concatenate([p.lower for p in pairs])
    hi = np.concatenate([p.upper for p in pairs])
    fx = np.concatenate([p.fixed for p in pairs])
    dlo, dhi, dfx = [], [], []
    for j in mp.delay_idx:
        w = mp.whole[j]
        dhi.append(min((w + 1) * mp.dt, pairs[j].delay_max))
        # a bound on a sample multiple (0.3 s at dt = 0.1) starts the interval above it by
        # round-off (0.30000000000000004 > 0.3): the interval is then that bound alone
        dlo.append(min(w * mp.dt, dhi[-1]))
        dfx.append(not pairs[j].delay_free)
    lo = np.concatenate([lo, dlo]) / mp.scale
    hi = np.concatenate([hi, dhi]) / mp.scale
    fx = np.concatenate([fx, np.array(dfx, dtype=bool)])
    return lo, hi, fx


def _run(pairs: Sequence[PairStructure], exps: list[tuple[np.ndarray, np.ndarray]], dt: float,
         hold: str, whole: list[int], x0_mode: str, max_iter: int, tol: float,
         progress: Any, stable: bool = True) -> tuple[dict[str, Any], _Map]:
    mp = _Map(pairs, dt, hold, whole, exps, x0_mode)
    lo, hi, fx = _bounds(pairs, mp)
    v0 = mp.vector([p.p0 for p in pairs], [p.delay for p in pairs])
    z0 = np.clip(v0 / mp.scale, lo, hi)
    nz = z0.size
    z0 = np.concatenate([z0, np.zeros(mp.n_x0)])
    inf = np.full(mp.n_x0, np.inf)
    data = [(np.ascontiguousarray(shift_taps(u, mp.taps)), np.ascontiguousarray(y[:, None]))
            for u, y in exps]
    res = _sysid.greybox_linear(
        (mp.n, len(mp.taps), 1), data, mp, list(map(float, z0)), focus="simulation",
        with_k=False, reweight=False, x0_params=list(range(nz, nz + mp.n_x0)),
        search={"lower": list(np.concatenate([lo, -inf])),
                "upper": list(np.concatenate([hi, inf])),
                "fixed": list(map(bool, np.concatenate([fx, np.zeros(mp.n_x0, bool)]))),
                "max_iter": max_iter, "tol_cost": tol, "tol_step": tol,
                "tol_gradient": tol * 1e-2},
        progress=progress, unbounded=not stable)
    return res, mp


def _reached(res: dict[str, Any], mp: _Map, pairs: Sequence[PairStructure]
             ) -> tuple[list[PairStructure], list[float]]:
    """The pairs started where the search ``res`` (on the map ``mp``) ended, and the delays."""
    ps, taus = mp.split(np.asarray(res["p"])[:mp.scale.size] * mp.scale)
    return [PairStructure(p.coef, q, p.fixed, p.lower, p.upper, t, p.delay_free, p.delay_max,
                          p.names) for p, q, t in zip(pairs, ps, taus)], taus


def _interval_trials(pairs: Sequence[PairStructure], delay_idx: list[int], whole: list[int],
                     taus: list[float], started: list[float], dt: float) -> list[list[int]]:
    """The sample intervals of the delays to try next: the neighbouring one of every free
    delay that ended near an edge of its interval (together, one trial), and both
    neighbours of each free delay the search left where it started: the cost is flat in it
    inside the interval (a zero as fast as the sampling absorbs a fractional delay under a
    hold: on a heating system the search stopped at 3 samples where 5 fit 14 % better),
    so only another interval can lower it."""
    trial = list(whole)
    trials = []
    for j in delay_idx:
        p, w, tau = pairs[j], whole[j], taus[j]
        if not p.delay_free:
            continue
        if abs(tau - started[j]) <= 1e-6 * dt:
            for k in (w - 1, w + 1):
                if k >= 0 and k * dt < p.delay_max:
                    side = list(whole)
                    side[j] = k
                    trials.append(side)
        elif tau >= (w + 0.75) * dt and (w + 1) * dt < p.delay_max:
            trial[j] = w + 1
        elif tau <= (w + 0.25) * dt and w > 0:
            trial[j] = w - 1
    if trial != whole:
        trials.insert(0, trial)
    return trials


def refine(pairs: Sequence[PairStructure], exps: list[tuple[np.ndarray, np.ndarray]],
           dt: float, hold: str, *, x0_mode: str = "zero", max_iter: int = 100,
           tol: float = 1e-10, progress: Any = None,
           fix: str = "Lower n_zeros, fix the delay or use more informative data",
           stable: bool = True) -> dict[str, Any]:
    """Output-error fit of one output; returns ``p`` per pair, the delays, the covariance of
    ``[p..., estimated delays...]`` (physical units), ``std``, the search report. ``fix``:
    what an :class:`~sysid.IdentifiabilityWarning` tells the user to do. ``stable``: the
    sampled model is kept stable (``False``: the search is free to leave the unit circle)."""
    whole = [int(np.floor(p.delay / dt + 1e-9)) for p in pairs]
    res, mp = _run(pairs, exps, dt, hold, whole, x0_mode, max_iter, tol, progress, stable)
    history: list[float] = list(res["history"])
    moves = 0
    # the delay intervals already searched: a delay whose input hardly matters has the same
    # cost in two intervals, and the moves went back and forth between them 20 times
    visited = {tuple(whole)}
    while moves < 20:
        started = [p.delay for p in pairs]
        pairs, taus = _reached(res, mp, pairs)
        trials = [t for t in _interval_trials(pairs, mp.delay_idx, whole, taus, started, dt)
                  if tuple(t) not in visited]
        visited.update(tuple(t) for t in trials)
        if not trials:
            break
        # the neighbouring sample intervals, each searched a few iterations from the current
        # point (every trial run out took procest(winding, "P2D") 80 s); the best, run out
        # from where its trial stopped, kept only if it fits better
        best = None
        for trial in trials:
            moved = [PairStructure(p.coef, p.p0, p.fixed, p.lower, p.upper,
                                   float(np.clip(p.delay, t * dt, (t + 1) * dt)), p.delay_free,
                                   p.delay_max, p.names) for p, t in zip(pairs, trial)]
            res2, mp2 = _run(moved, exps, dt, hold, trial, x0_mode,
                             min(max_iter, TRIAL_ITER), tol, progress, stable)
            if best is None or res2["cost"] < best[0]["cost"]:
                best = (res2, mp2, trial, moved)
        moves += 1
        assert best is not None
        if not best[0]["cost"] < res["cost"] * (1 - 1e-12):
            break
        res2, mp2, trial, moved = best
        if res2["stop"] == "maximum iterations" and max_iter > TRIAL_ITER:
            moved = _reached(res2, mp2, moved)[0]
            res2, mp2 = _run(moved, exps, dt, hold, trial, x0_mode, max_iter, tol, progress,
                             stable)
        res, mp, whole, pairs = res2, mp2, trial, moved
        history += list(res["history"])
    pairs = _reached(res, mp, pairs)[0]
    # the rule of every other capped search (sysid._checks.warn_if_capped): no warning when
    # the last iterations had settled or the rest of the way is negligible (a tfest whose
    # last ten iterations lowered the cost by 4e-8, 0.0009 residual variances from its
    # minimum, warned; 1000 iterations gave the same fit to 0.001 %)
    if max_iter == 0 and res["stop"] == "maximum iterations":  # the start, as asked
        warn_iteration_limit("the output-error search", 0, history,
                             "raise max_iter (the result is the start)",
                             category=ConvergenceWarning)
    warn_if_capped({"stop": res["stop"], "cost": history,
                    "remaining_decrease": float(res.get("remaining_decrease", np.inf))},
                   "the output-error search", max_iter,
                   "raise max_iter (the result is never worse than the start)",
                   n_residuals=int(res["n_samples"]), category=ConvergenceWarning)
    assert res is not None and mp is not None
    S = mp.scale
    cov = np.asarray(res["covariance"])[:S.size, :S.size] * np.outer(S, S)
    names = [n for p in pairs for n in p.names] + [f"{pairs[j].names[0].split(':')[0]}:iodelay"
                                                   if pairs[j].names else f"iodelay{j}"
                                                   for j in mp.delay_idx]
    weak = _unidentifiable(np.asarray(res["unidentifiable"])[:S.size], names, fix)
    lam = float(np.asarray(res["innovation_covariance"])[0, 0])
    return {"p": [p.p0 for p in pairs], "delays": [p.delay for p in pairs],
            "delay_index": mp.delay_idx, "covariance": cov, "noise_variance": lam,
            "iterations": int(res["iterations"]), "stop": res["stop"],
            "cost_history": history, "interval_moves": moves,
            "n_samples": int(res["n_samples"]), "rank": int(res["rank"]),
            "condition": float(res["condition"]), "unidentifiable": weak}


def free_search(res: dict[str, Any], pairs: Sequence[PairStructure],
                exps: list[tuple[np.ndarray, np.ndarray]], dt: float, hold: str, x0_mode: str,
                max_iter: int, tol: float) -> dict[str, Any] | None:
    """The search from where the stable search ``res`` (from ``pairs``) ended, free to
    leave the unit circle (``None`` when it fails); from a stable start of its own, a free
    search can wander (an unstable plant's record: a criterion 10^3 times the one from the
    stable fit)."""
    start = [PairStructure(pr.coef, q, pr.fixed, pr.lower, pr.upper, d, pr.delay_free,
                           pr.delay_max, pr.names)
             for pr, q, d in zip(pairs, res["p"], res["delays"])]
    try:
        return refine(start, exps, dt, hold, x0_mode=x0_mode, max_iter=max_iter, tol=tol,
                      stable=False)
    except (DataError, ArithmeticError):
        return None


def free_test(res: dict[str, Any], pairs: Sequence[PairStructure],
              exps: list[tuple[np.ndarray, np.ndarray]], dt: float, hold: str, x0_mode: str,
              max_iter: int, tol: float,
              reflect: Callable[[PairStructure, np.ndarray], np.ndarray] | None = None,
              other: Sequence[PairStructure] | None = None
              ) -> tuple[int, complex, float] | None:
    """Whether the data insist on an unstable model where the stable search ``res`` (from
    ``pairs``) ended: the search runs again from there, free to leave the unit circle, and
    the likelihood-ratio test of :func:`sysid.pem.boundary.insists` (1 %) decides;
    ``(pair, pole, statistic)`` of the free fit's most unstable pole when the data insist,
    else ``None``. Run after every stable fit, not only where a pole sits at the bound (a
    step refused at the bound can also stop the search away from it); from a minimum inside
    the stable region the free search stops at once.

    The test's stable model must be the best stable one near the free fit: a stable search
    can stop with a spurious pole held at the bound (clean stable records of order 6: a pole
    at s = -0.000 the truth does not have, which the free search moved to +0.014 at a 15 %
    lower criterion). With ``reflect`` (a pair and its parameters -> the same with its
    unstable poles mirrored into the stable region), the stable search also runs from the free fit
    mirrored, and the lower stable criterion is the one tested.

    With ``other`` (another start of the free search: an unconstrained fit,
    :func:`sysid.tf.free.arx_start`), the free search also runs from there and the lower
    free criterion is the one tested: 13 of 100 records of an unstable plant (a real pole
    at ``z`` = 1.01-1.03) were left silent without it: on 7 the free search from the stable
    fit did not move, on 2 it moved to a nearby unstable pair short of the test, and on 4
    the stable search from the free fit mirrored reached a criterion the free fit did not
    beat significantly."""
    import warnings

    from ..pem.boundary import insists

    slowest = max((float(np.max(np.roots(pr.coef(q)[1]).real)) for pr, q in zip(pairs, res["p"])
                   if pr.coef(q)[1].size > 1), default=-np.inf)
    if slowest >= 0.0:
        return None  # unstable already (said by the StabilityWarning of an unstable model)
    with warnings.catch_warnings():  # a test: its own search's warnings are not the user's
        warnings.simplefilter("ignore")
        free = free_search(res, pairs, exps, dt, hold, x0_mode, max_iter, tol)
        if other is not None:
            try:
                alt = refine(other, exps, dt, hold, x0_mode=x0_mode, max_iter=max_iter,
                             tol=tol, stable=False)
                if free is None or alt["cost_history"][-1] < free["cost_history"][-1]:
                    free = alt
            except (DataError, ArithmeticError):
                pass
    if free is None:
        return None
    kept = res["cost_history"][-1]
    lr, yes = insists(kept, free["cost_history"][-1], res["n_samples"])
    if yes and reflect is not None:
        start = [PairStructure(pr.coef, reflect(pr, q), pr.fixed, pr.lower, pr.upper, d,
                               pr.delay_free, pr.delay_max, pr.names)
                 for pr, q, d in zip(pairs, free["p"], free["delays"])]
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                again = refine(start, exps, dt, hold, x0_mode=x0_mode, max_iter=max_iter,
                               tol=tol)
            kept = min(kept, again["cost_history"][-1])
        except (DataError, ArithmeticError):
            pass
        lr, yes = insists(kept, free["cost_history"][-1], res["n_samples"])
    if not yes:
        return None
    from ..pem.boundary import grows

    # a mode growing less than 1 / PERSISTENT_DECAY over the record is one on the bound (an
    # integrating plant), not an unstable one
    longest = max(len(y) for _, y in exps)
    best: tuple[int, complex, float] | None = None
    for j, (pr, q) in enumerate(zip(pairs, free["p"])):
        r = np.roots(pr.coef(q)[1])
        if grows(r, longest, dt) and (best is None or r.real.max() > best[1].real):
            best = (j, complex(r[np.argmax(r.real)]), lr)
    return best


def _unidentifiable(null: np.ndarray, names: list[str], fix: str) -> list[int]:
    """Indices of the parameters in directions the data do not determine, with an
    :class:`~sysid.IdentifiabilityWarning` naming them (their std is then reported as inf)."""
    import warnings

    from ..greybox.greybox import IdentifiabilityWarning

    if null.size == 0 or null.ndim != 2 or null.shape[1] == 0:
        return []
    idx: set[int] = set()
    parts = []
    for v in null.T:
        # the parameters the direction moves (in the search's scaled coordinates): any part
        # makes a variance unbounded, but a direction found numerically at a symmetric point
        # (two equal time constants, the direction Tp1 - Tp2) carries parts of others at the
        # level of its error (the delay's 2e-5 on the dryer), while a genuine trade-off is
        # far above it (a zero at b0 = 0 against the delay: 1e-2)
        big = np.flatnonzero(np.abs(v) >= 1e-3 * np.max(np.abs(v)))
        idx |= set(int(i) for i in big)
        parts.append(", ".join(names[i] if i < len(names) else f"p{i}" for i in big))
    delay = any(n.endswith(("iodelay", ":Td")) for n in names)
    why = (" (a zero far beyond the bandwidth trades off against the delay, for example)"
           if delay and "n_zeros" in fix else "")
    warnings.warn("the data cannot determine these parameters separately: " + "; ".join(parts)
                  + f"{why}. {fix}; their standard deviations are reported as inf.",
                  IdentifiabilityWarning, stacklevel=user_stacklevel())
    return sorted(idx)


def check_experiments(exps: list[tuple[np.ndarray, np.ndarray]], n_par: int) -> None:
    """Enough samples for the parameters."""
    N = sum(u.shape[0] for u, _ in exps)
    if N < 2 * n_par + 2:
        raise DataError(f"the data have {N} samples but the model has {n_par} parameters: "
                        f"give at least {2 * n_par + 2} samples or fewer poles and zeros")
