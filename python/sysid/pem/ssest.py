"""The one-call state-space estimator :func:`ssest`: the best subspace start (several
weightings, with and without ``x0``), refined by :func:`sysid.pem`."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

from .._checks import as_int
from ..data.iodata import IOData
from ..errors import DataError, OffsetWarning
from ..models.statespace import StateSpaceModel
from ..subspace.estimator import CLOSED_LOOP, SubspaceEstimator
from .pem import _experiments, pem


def _start_loss(data: IOData, start: StateSpaceModel, focus: str, feedthrough: bool,
                x0: Any, noise: str) -> float:
    """det of the error covariance of a candidate start (initial states fitted), the cost the
    refinement will minimise; inf when its predictor is unstable."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", OffsetWarning)  # said once, by the caller
            m = pem(data, start, focus=focus, feedthrough=feedthrough, x0=x0, noise=noise,
                    max_iter=0)
    except Exception:  # noqa: BLE001 - an unusable candidate is skipped
        return float("inf")
    if m.info["pem"]["stabilized"]:
        return float("inf")
    return float(m.info["pem"]["cost"][0])


def ssest(
    data: Any,
    order: int,
    *,
    focus: str = "prediction",
    feedthrough: bool = False,
    x0: Any = "estimate",
    noise: str = "estimate",
    horizon: int | None = None,
    methods: tuple[str, ...] = ("moesp", "n4sid", "cva"),
    method: str | None = None,
    max_iter: int = 50,
    tol: float = 1e-6,
    regularization: dict[str, Any] | None = None,
    progress: bool | None | Callable[..., Any] = None,
) -> StateSpaceModel:
    """Estimate a state-space model: the best subspace start, refined by :func:`pem`.

    The candidates are the subspace weightings in ``methods``, each with ``B, D`` from the
    regression on the compressed data and (single-experiment records) from least squares on
    the data jointly with ``x0``; the one with the lowest cost that :func:`pem` will minimise
    (the determinant of the error covariance, initial states fitted) is refined.

    Parameters
    ----------
    data : IOData or (u, y)
    order : int
    focus, feedthrough, x0, noise, max_iter, tol, regularization, progress
        As for :func:`pem`.
    horizon : int, optional
        Subspace horizon (default :func:`sysid.default_horizon`).
    methods : tuple of str
        Subspace weightings tried for the start.
    method : str, optional
        One subspace method for the start (overrides ``methods``); ``"pbsid"`` or
        ``"ssarx"`` for closed-loop data (their start is consistent under feedback, and the
        start's ``B, D`` are then not re-fitted on the data with ``x0``, which would be an
        output-error fit).

    Returns
    -------
    StateSpaceModel
        With ``info["pem"]`` and ``info["start"]`` (the chosen candidate and every
        candidate's loss).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> true = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], K=[[0.5]])
    >>> u = rng.standard_normal(500)
    >>> e = 0.1 * rng.standard_normal((500, 1))
    >>> y = true.simulate(u) + 0.0
    >>> m = sysid.ssest(sysid.IOData(u=u, y=y + e), order=1)
    >>> bool(abs(m.poles()[0] - 0.8) < 0.05)
    True
    """
    data = _experiments(data)
    order = as_int(order, "order", 1)
    est = SubspaceEstimator(data, horizon)
    candidates = []
    names = methods if method is None else (method,)
    for name in names:
        x0_options = (False, True) if data.n_experiments == 1 else (False,)
        if name in CLOSED_LOOP:
            x0_options = (False,)
        for use_x0 in x0_options:
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    cand = est.fit(order, method=name, feedthrough=feedthrough, x0=use_x0)
            except Exception:  # noqa: BLE001 - a failing weighting is just not a candidate
                if method is not None:
                    raise
                continue
            loss = _start_loss(data, cand, focus, feedthrough, x0, noise)
            candidates.append((loss, name, use_x0, cand))
    if not candidates:
        raise DataError("no subspace start could be computed for this order; lower the order")
    candidates.sort(key=lambda c: c[0])
    best = candidates[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OffsetWarning)  # said once, by the subspace start
        model = pem(data, best[3], focus=focus, feedthrough=feedthrough, x0=x0, noise=noise,
                    max_iter=max_iter, tol=tol, regularization=regularization,
                    progress=progress)
    model.info["start"] = {
        "method": best[1],
        "bd_x0": best[2],
        "losses": {f"{c[1]}{'+x0' if c[2] else ''}": c[0] for c in candidates},
    }
    return model
