"""Under feedback identify adds the closed-loop subspace fits (ssarx, pbsid); their fit
refuses a stable ``A`` (``stable=True`` is for the open-loop methods), so no stable-``A``
variant of them may be offered: one took the order slots of identify's refinements from a
stable ``A`` and of its last-resort stable candidates, and left a ``DataError`` row in its
candidate table (a rotary flexible link under a servo controller, orders 12, 14 and 15)."""

import importlib
import warnings

import numpy as np
from scipy import signal

import sysid
from sysid._progress import Bar
from sysid.identify.board import informative

core = importlib.import_module("sysid.identify.core")


def _closed_loop_record(seed: int = 0, n: int = 3000, k: float = 0.25) -> sysid.IOData:
    """A slow pole beside a resonance under proportional feedback, a coloured disturbance
    large against the reference: the feedback test detects the loop."""
    rng = np.random.default_rng(seed)
    A = np.array([[0.998, 0.0, 0.0], [0.0, 1.6, -0.8], [0.0, 1.0, 0.0]])
    B, C = np.array([0.02, 1.0, 0.0]), np.array([1.0, 0.3, 0.2])
    r = 0.3 * signal.lfilter([1.0], [1.0, -0.7], rng.standard_normal(n))
    v = (0.3 * signal.lfilter([1.0], [1.0, -0.95], rng.standard_normal(n))
         + 0.2 * rng.standard_normal(n))
    x, u, y = np.zeros(3), np.zeros(n), np.zeros(n)
    for t in range(n):
        y[t] = C @ x + v[t]
        u[t] = r[t] - (k * y[t - 1] if t else 0.0)
        x = A @ x + B * u[t]
    return sysid.IOData(u - u.mean(), y - y.mean(), 1.0)


def test_closed_loop_subspace_candidates_offer_no_stable_a_variant():
    data = _closed_loop_record()
    parts, _ = informative(core.record_folds(data), data)
    with warnings.catch_warnings(), Bar(None, "identify", enabled=False) as bar:
        warnings.simplefilter("ignore")
        board = core.Board(parts, bar, None)
        core._subspace_candidates(board, data, core.SUBSPACE + core.CLOSED_LOOP, 6)
        families = {r["family"] for r in board.rows}
        offered = [r for r in board.rows if "stabilised" in r]
        assert set(core.CLOSED_LOOP) <= families and offered
        for r in offered:  # every variant offered can be fitted, and is stable
            assert r["family"] not in core.CLOSED_LOOP
            assert r["stabilised"][0](0).is_stable()

