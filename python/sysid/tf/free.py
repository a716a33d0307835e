""":func:`sysid.tfest`'s search free of the stability bound on time records: where it starts.

With ``enforce_stability=True`` (the default) the fit is kept stable, and a search free of
the bound decides whether the data insist on an unstable model (:func:`.refine.free_test`);
with ``False`` the free search's model is returned. From the stable fit alone the free search
stops at once wherever that fit is a minimum of the free criterion too: on 7 of 100
records of an unstable plant (the warning audit's ``unstable`` scenario, a real pole at
``z`` = 1.01-1.03) it did not move, and the stable model was returned without a word (on 6
more it moved, but not to the plant's pole). The
free search therefore also starts from the output's least-squares ARX fit, whose ``A`` is
not held stable (:func:`.starts.arx_pairs`, as :func:`sysid.oe`'s test does), when that fit
has a mode that grows over the record.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..errors import DataError
from .refine import PairStructure, free_search, refine

__all__ = ["arx_start", "free_fit", "reflected"]


def reflected(pair: PairStructure, q: np.ndarray) -> np.ndarray:
    """A pair's parameters ``[a_1.., b..]`` with the unstable poles of
    ``s^n + a_1 s^(n-1) + ...`` mirrored into the left half-plane (``s -> -conj(s)``; the
    numerator kept).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.tf.free import reflected
    >>> from sysid.tf.refine import PairStructure
    >>> pr = PairStructure(lambda p: (p[1:], np.concatenate([[1.0], p[:1]])), np.zeros(2),
    ...                    np.zeros(2, bool), np.full(2, -np.inf), np.full(2, np.inf))
    >>> reflected(pr, np.array([-0.5, 2.0])).tolist()
    [0.5, 2.0]
    """
    num, den = pair.coef(np.asarray(q, float))
    r = np.roots(den)
    r = np.where(r.real > 0, -np.conj(r), r)
    return np.concatenate([np.real(np.poly(r))[1:], num])


def arx_start(res: dict[str, Any], pairs: list[PairStructure],
              exps: list[tuple[np.ndarray, np.ndarray]], dt: float, npo: np.ndarray,
              nze: np.ndarray, hold: str) -> list[PairStructure] | None:
    """The pairs of one output (the structures ``pairs``, the delays where the search
    ``res`` ended) started at its least-squares ARX fit (:func:`.starts.arx_pairs`); ``None``
    when that fit has no growing mode or fails.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.tf.free import arx_start
    >>> from sysid.tf.refine import PairStructure
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(400)
    >>> y = sysid.TransferFunction([1.0], [1.0, -0.02]).simulate(u, dt=1.0)[:, 0]
    >>> pr = PairStructure(lambda p: (p[1:], np.concatenate([[1.0], p[:1]])),
    ...                    np.array([0.5, 1.0]), np.zeros(2, bool), np.full(2, -np.inf),
    ...                    np.full(2, np.inf))
    >>> got = arx_start({"delays": [0.0]}, [pr], [(u[:, None], y)], 1.0, np.array([1]),
    ...                 np.array([0]), "zoh")
    >>> np.round(got[0].p0, 3).tolist()
    [-0.02, 1.0]
    """
    from .starts import arx_pairs

    got = arx_pairs(exps, dt, np.ravel(npo), np.ravel(nze), list(res["delays"]), hold)
    if got is None:
        return None
    return [PairStructure(pr.coef, np.concatenate([a[1:], b]), pr.fixed, pr.lower, pr.upper,
                          t, pr.delay_free, pr.delay_max, pr.names)
            for pr, (a, b, t) in zip(pairs, got)]


def free_fit(res: dict[str, Any], pairs: list[PairStructure],
             exps: list[tuple[np.ndarray, np.ndarray]], dt: float, npo: np.ndarray,
             nze: np.ndarray, hold: str, x0_mode: str, max_iter: int, tol: float
             ) -> tuple[dict[str, Any], list[Any]] | None:
    """``enforce_stability=False``: the search free of the bound from the stable fit ``res``
    and from the ARX start (:func:`arx_start`), the lower criterion kept with its warnings
    (held back: the caller raises them); ``None`` when neither lowers ``res``'s."""
    best = None
    arx = arx_start(res, pairs, exps, dt, npo, nze, hold)
    for start in [None] + ([arx] if arx is not None else []):
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            try:
                got = free_search(res, pairs, exps, dt, hold, x0_mode, max_iter, tol) \
                    if start is None else refine(start, exps, dt, hold, x0_mode=x0_mode,
                                                 max_iter=max_iter, tol=tol, stable=False)
            except (DataError, ArithmeticError):
                got = None
        if got is None:
            continue
        c = got["cost_history"][-1]
        if c < res["cost_history"][-1] and (best is None or c < best[0]["cost_history"][-1]):
            best = (got, list(said))
    return best
