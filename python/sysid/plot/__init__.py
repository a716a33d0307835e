"""Plots (matplotlib, imported lazily: ``pip install sysid[plot]``).

Every function takes an optional ``ax`` (or ``fig``) and returns the matplotlib objects it
drew on, so that plots can be composed and saved by the caller.
"""

from __future__ import annotations

from typing import Any


def _pyplot() -> Any:
    """Import matplotlib.pyplot on first use, with a clear message when it is missing."""
    try:
        import matplotlib.pyplot as plt
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError(
            "plotting needs matplotlib: pip install 'sysid[plot]' (or pip install matplotlib)"
        ) from e
    return plt
