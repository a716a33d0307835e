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

import warnings
from typing import Any

import numpy as np

__all__ = ["input_levels", "warn_two_levels"]

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


def warn_two_levels(us: Any, channels: list[int], names: list[str], who: str) -> None:
    """An :class:`~sysid.ExcitationWarning` from ``who`` when an input of ``channels`` (those
    given a static nonlinearity to fit) takes at most two levels over the records ``us``: a
    curve through two points is any curve, so the data determine the nonlinearity there only,
    and an affine map (the identity, its gain in the linear block) fits the record as well.

    Examples
    --------
    >>> import warnings
    >>> import numpy as np
    >>> from sysid.data.levels import warn_two_levels
    >>> u = np.repeat([[0.0], [1.0]], 50, axis=0)
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     warn_two_levels([u], [0], ["valve"], "nlhw")
    >>> "valve takes 2 levels" in str(w[0].message)
    True
    """
    from .._checks import user_stacklevel
    from ..errors import ExcitationWarning

    if not channels:
        return
    levels = input_levels(us, cap=3)
    few = [f"{names[j]} takes {int(levels[j])} levels" for j in channels if levels[j] <= 2]
    if few:
        warnings.warn(f"{who}: in the estimation data input {' and input '.join(few)}, so "
                      f"its input nonlinearity is determined at those values only: any curve "
                      f"through them fits the record as well, and between and beyond them "
                      f"its shape comes from its start, not the data (an affine map, the "
                      f"identity with the linear block's gain, fits the same). Use "
                      f"input_nl=None for it, or an excitation of more levels (a multisine, "
                      f"random levels)", ExcitationWarning, stacklevel=user_stacklevel())
