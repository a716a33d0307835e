"""Order choice by simulation error cross-validated inside the estimation record.

The singular values of a subspace projection fall off smoothly on real records (unmodelled
dynamics, coloured noise, nonlinearity), so the largest gap of their logarithms usually sits
after the first one or two and picks order 1-2 where the data support more. What an engineer
checks instead is how well a model of each order *simulates data it was not fitted on*. This
module does that without touching the user's validation data: the estimation record is cut
into contiguous blocks (two halves, or the experiments themselves), models of every order are
fitted on all blocks but one and simulated on the one left out (initial state fitted by least
squares), and the order whose held-out simulation fit is best wins; a smaller order within
``tol`` fit points (and 5 % of the best's error) of the best is preferred (the models of
half the data are noisier, and a smaller model generalises better). Fits are on compressions
of the blocks, so a sweep costs about one pass over the record per block plus one simulation
per order and block.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..data.iodata import IOData

__all__ = ["OrderChoice", "cross_validated_order", "folds", "simulation_fit"]

#: fit points a smaller order may give up and still win (held-out fits of half-record
#: models scatter by about this much between neighbouring orders)
TOL = 0.5
#: largest order tried by the automatic choice
MAX_ORDER = 20


@dataclass
class OrderChoice:
    """The automatic order, the table it was read from, and why.

    Attributes
    ----------
    order : int
    table : dict
        ``{order: held-out simulation fit %}`` (mean over outputs and blocks).
    reason : str
    criterion : str
    """

    order: int
    table: dict[int, float] = field(default_factory=dict)
    reason: str = ""
    criterion: str = "cross-validated simulation fit"

    def as_dict(self) -> dict[str, Any]:
        return {"order": self.order, "criterion": self.criterion, "reason": self.reason,
                "table": {int(k): float(v) for k, v in self.table.items()}}


def folds(data: IOData, k: int = 2) -> list[tuple[IOData, IOData]]:
    """(fit, held-out) pairs: leave one experiment out, or for one experiment its ``k``
    contiguous blocks (each held out once, the rest fitted as separate experiments)."""
    exps = data.experiments
    kw = {"dt": data.dt, "input_names": data.input_names, "output_names": data.output_names}
    if len(exps) >= 2:
        blocks = [[e] for e in exps]
    else:
        u, y = exps[0]
        edges = np.linspace(0, u.shape[0], k + 1).astype(int)
        blocks = [[(u[a:b], y[a:b])] for a, b in zip(edges[:-1], edges[1:])]
    out = []
    for i in range(len(blocks)):
        rest = [e for j, b in enumerate(blocks) if j != i for e in b]
        out.append((_io(rest, kw), _io(blocks[i], kw)))
    return out


def _io(exps: list[tuple[np.ndarray, np.ndarray]], kw: dict[str, Any]) -> IOData:
    if len(exps) == 1:
        return IOData(u=exps[0][0], y=exps[0][1], **kw)
    return IOData(u=[e[0] for e in exps], y=[e[1] for e in exps], **kw)


def simulation_fit(model: Any, data: IOData) -> float:
    """Held-out simulation fit (NRMSE %, mean over outputs and experiments); ``-inf`` for a
    model that diverges (a model with a pole just outside the unit circle is scored on what
    it does over the block).

    The initial state and a constant offset per output are fitted by least squares (as
    :func:`sysid.compare` fits the initial state): every block keeps some offset after the
    record's means are removed, and without the free offset a slow mode of an over-fitted
    model (a pole near 1 excited by ``x0``) would absorb it and look better than it predicts.
    """
    fits = []
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        for u, y in data.experiments:
            try:
                ys = model.simulate(u)
                n, l = model.nstates, y.shape[1]
                cols = [np.kron(np.ones((u.shape[0], 1)), np.eye(l))]  # (N l, l) offsets
                cols += [model.simulate(np.zeros_like(u), x0=np.eye(n)[i]).reshape(-1, 1)
                         for i in range(n)]
                phi = np.hstack(cols)
                theta = np.linalg.lstsq(phi, (y - ys).ravel(), rcond=None)[0]
                ys = ys + (phi @ theta).reshape(ys.shape)
            except Exception:  # noqa: BLE001 - a model that cannot be simulated scores -inf
                return -np.inf
            dev = np.linalg.norm(y - y.mean(0), axis=0)
            f = 100.0 * (1.0 - np.linalg.norm(y - ys, axis=0) / np.where(dev > 0, dev, np.nan))
            fits.append(np.nanmean(f))
    out = float(np.mean(fits))
    return out if np.isfinite(out) else -np.inf


def choose(table: dict[int, float], tol: float = TOL) -> tuple[int, str]:
    """The smallest order within ``min(tol, 5 % of the best's error)`` fit points of the best
    held-out fit (a smaller model generalises better; on noise-free data only round-off
    separates the orders from the true one up, and the true one is taken)."""
    finite = {n: f for n, f in table.items() if np.isfinite(f)}
    if not finite:
        raise ValueError("no order gave a model that simulates the held-out data")
    best_n = max(finite, key=lambda n: finite[n])
    best = finite[best_n]
    # within 5 % of the best's error, at most tol points (noise-free data: round-off only)
    slack = max(min(tol, 0.05 * (100.0 - best)), 1e-6)
    n = min(o for o, f in finite.items() if f >= best - slack)
    why = (f"held-out simulation fit {finite[n]:.1f} % at order {n}"
           + (f" (best {best:.1f} % at order {best_n}; a smaller order within {slack:.2g} "
              "points is preferred)" if n != best_n else " (the best)"))
    return n, why


def cross_validated_order(
    data: IOData,
    estimator: Any,
    *,
    method: str = "moesp",
    past: int | None = None,
    future: int | None = None,
    feedthrough: bool = False,
    orders: list[int] | None = None,
    tol: float = TOL,
) -> OrderChoice:
    """Choose a subspace model's order by simulation fit on blocks of the record held out.

    Parameters
    ----------
    data : IOData
        The estimation record (the user's validation data are never needed).
    estimator : type
        :class:`sysid.SubspaceEstimator` (or a class with its constructor and ``fit``).
    method : str
        Subspace weighting.
    past, future : int, optional
        Horizons (default: :func:`sysid.default_horizon` of the shortest fitted block).
    feedthrough : bool
        Estimate ``D`` in the fits.
    orders : list of int, optional
        Orders to try (default ``1 .. min(max_order, 20)``).
    tol : float
        Fit points a smaller order may give up and still win.

    Returns
    -------
    OrderChoice

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.crossval import cross_validated_order
    >>> rng = np.random.default_rng(0)
    >>> true = sysid.StateSpaceModel([[0.9, 0.3, 0], [-0.3, 0.9, 0], [0, 0, 0.5]],
    ...                              [[1.0], [0.0], [1.0]], [[1.0, 0.5, 1.0]])
    >>> u = rng.standard_normal(1000)
    >>> y = true.simulate(u) + 0.1 * rng.standard_normal((1000, 1))
    >>> cross_validated_order(sysid.IOData(u=u, y=y), sysid.SubspaceEstimator).order
    3
    """
    table: dict[int, list[float]] = {}
    for fit_part, held in folds(data):
        # the given horizons, clipped to a quarter of the fitted part; else the part's default
        shortest = min(fit_part.lengths)
        kw = {k: min(v, max(1, shortest // 4)) for k, v in (("past", past), ("future", future))
              if v is not None}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            est = estimator(fit_part, method=method, **kw)
        top = min(est.max_order, MAX_ORDER)
        for n in orders or range(1, top + 1):
            if n > est.max_order:
                continue
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    m = est.fit(n, feedthrough=feedthrough, kalman=False)
                table.setdefault(n, []).append(simulation_fit(m, held))
            except Exception:  # noqa: BLE001 - an order the block cannot support
                table.setdefault(n, []).append(-np.inf)
    mean = {n: float(np.mean(v)) if len(v) == max(map(len, table.values())) else -np.inf
            for n, v in table.items()}
    n, why = choose(mean, tol)
    return OrderChoice(n, mean, why)
