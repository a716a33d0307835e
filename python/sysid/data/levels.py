"""Amplitude levels of an input: how many distinct values it takes, and so which powers of it
the data can tell apart.

An input that takes ``k`` distinct values (a step test: two; a binary PRBS or a square wave:
two; a three-level PRBS: three) satisfies a polynomial of degree ``k`` on the record, so
every power ``u^p`` with ``p >= k`` equals a combination of ``1, u, ..., u^(k-1)`` there, and
a term ``u^p x`` one of ``x, u x, ..., u^(k-1) x``. A model with such a term fits the record
exactly as well as one without it: its coefficient is not determined by the data, yet it
decides how the model behaves between and beyond the levels (on a binary input, any curve
through the two levels fits; the data say nothing of its shape). A nonlinear model of that
input can use at most the powers ``0 .. k - 1``; only an input of more levels (a multisine, a
random-level signal) reveals a static nonlinearity in it.

Values count as one level when they differ by less than ``tol`` times the input's range
(default ``1e-9``: rounding, not measurement noise; a measured binary signal with noise on
its levels has as many levels as samples, and its powers are determined, if poorly).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["input_levels"]

#: values closer than this, relative to the input's range, count as one level
TOL = 1e-9


def input_levels(us: Any, cap: int = 8, tol: float = TOL) -> np.ndarray:
    """The number of distinct values each input takes over all records, counted up to ``cap``
    (an input of more levels counts ``cap``).

    Parameters
    ----------
    us : array_like or list of array_like
        Input samples ``(n_samples, n_inputs)``, or a list of such records (one count over
        all of them).
    cap : int
        Counting stops here (the powers a model uses are few).
    tol : float
        Values closer than ``tol`` times the input's range are one level.

    Returns
    -------
    numpy.ndarray of int
        One count per input.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.data.levels import input_levels
    >>> u = np.column_stack([np.repeat([1.0, 5.0], 50), np.linspace(0, 1, 100)])
    >>> input_levels(u).tolist()
    [2, 8]
    >>> input_levels([u[:50], u[50:]], cap=3).tolist()
    [2, 3]
    """
    recs = [np.asarray(u, dtype=float) for u in (us if isinstance(us, list) else [us])]
    recs = [r.reshape(r.shape[0], -1) for r in recs]
    m = recs[0].shape[1]
    out = np.empty(m, dtype=int)
    for j in range(m):
        v = np.sort(np.concatenate([r[:, j] for r in recs]))
        span = v[-1] - v[0] if v.size else 0.0
        gaps = np.count_nonzero(np.diff(v) > tol * span) if span > 0 else 0
        out[j] = min(int(gaps) + (1 if v.size else 0), cap)
    return out
