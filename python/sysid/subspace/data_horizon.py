"""The horizon the data allow: how long the past and future windows of a subspace fit can
be for the record's length and channels (:func:`available_horizon`), the default of the
input-output records and the bound of the time-series horizons
(:mod:`sysid.subspace.series_horizon`)."""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["available_horizon"]


def available_horizon(lengths: Sequence[int], n_inputs: int, n_outputs: int) -> int:
    """The horizon from the data available: the largest ``i`` (2 to 20) whose data matrix,
    from the experiments of at least ``4 i`` samples, has ten times as many columns as rows
    (``20 i (m + l)`` samples), as :func:`default_horizon` asks of one experiment (the same
    horizon for one). Not the shortest experiment's: a short experiment next to a long one
    held every model to order 1 or 2.

    Examples
    --------
    >>> from sysid.subspace.data_horizon import available_horizon
    >>> available_horizon([500, 30], 1, 1), available_horizon([500], 1, 1)
    (12, 12)
    """
    ch = n_inputs + n_outputs
    for i in range(20, 1, -1):
        if sum(n for n in lengths if n >= 4 * i) >= 20 * i * ch:
            return i
    return 2
