"""Whether input channels are linearly dependent in every sample (one a combination of the
others): the test behind :func:`sysid._checks.require_independent_inputs` and the command
line's refusal of inputs dependent in the estimation part only."""

from __future__ import annotations

from typing import Any

import numpy as np

#: smallest eigenvalue of the inputs' unit-diagonal Gram matrix, relative to its largest,
#: below which they are dependent
TOL = 1e-12


def input_dependence(us: list[Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(w, v, d)`` when the inputs ``us`` (arrays of samples x channels, pooled) are
    linearly dependent in every sample: the eigenvalues ``w`` of their Gram matrix scaled
    to a unit diagonal, the direction ``v`` of its smallest (``u @ (v / d)`` is zero in
    every sample) and the channels' norms ``d``; ``None`` when they are not, or for fewer
    than two channels, an all-zero or a non-finite one (their own checks refuse those).

    Examples
    --------
    >>> import numpy as np
    >>> x = np.arange(6.0)[:, None]
    >>> w, v, d = input_dependence([np.hstack([x, 2 * x])])
    >>> bool(np.allclose(np.hstack([x, 2 * x]) @ (v / d), 0.0))
    True
    >>> input_dependence([np.hstack([x, x ** 2])]) is None
    True
    """
    m = us[0].shape[1] if us else 0
    if m < 2:
        return None
    G = np.zeros((m, m))
    for u in us:
        if len(u):
            G += u.T @ u
    d = np.sqrt(np.diag(G))
    if not np.all(np.isfinite(G)) or np.any(d == 0):
        return None
    w, V = np.linalg.eigh(G / np.outer(d, d))
    return (w, V[:, 0], d) if w[0] <= TOL * w[-1] else None
