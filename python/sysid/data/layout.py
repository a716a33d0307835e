"""The array layout sysid reads: time first, ``(samples, channels)``.

A 2-D array with fewer samples than channels is almost always a channels-first record
(python-control's and MATLAB's ``lsim`` layout for some users) handed over as is: read time
first it would be a handful of samples of hundreds of channels, and every statistic over
time would be computed across channels instead, silently. Such arrays are refused with the
fix (``x.T``), never guessed.

Examples
--------
>>> import numpy as np
>>> from sysid.data.layout import time_first
>>> time_first(np.zeros((500, 2)), "u").shape
(500, 2)
"""

from __future__ import annotations

import numpy as np

from ..errors import ShapeError

__all__ = ["time_first"]


def time_first(a: np.ndarray, name: str) -> np.ndarray:
    """``a`` unchanged, or a :class:`~sysid.ShapeError` when it has fewer samples (rows)
    than channels (columns), with the fix."""
    if a.ndim == 2 and (1 < a.shape[0] < a.shape[1] or a.shape[0] == 1 and a.shape[1] > 1):
        raise ShapeError(
            f"{name} has {a.shape[0]} sample(s) and {a.shape[1]} channels; sysid arrays are "
            f"time-first (samples, channels): if the data are channels-first (python-control's "
            f"layout), pass {name}.T"
        )
    return a
