"""Plots (matplotlib, imported lazily: ``pip install sysid[plot]``).

Every function takes an optional ``ax`` (or ``fig``) and returns the matplotlib objects it
drew on, so that plots can be composed and saved by the caller. The functions live in one
module per subject (``model``, ``frequency``, ``data``, ``validation``, ``realization``)
and are also reached here, ``sysid.plot.plot_bode`` (loaded on first use).
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


#: the functions reached as ``sysid.plot.<name>``: name -> module (``plot_stabilization``
#: is in both ``validation`` and ``realization``: import it from the one meant)
_FUNCTIONS = {
    **dict.fromkeys(("plot_bode", "plot_sigma", "plot_pzmap", "plot_time_response", "bode",
                     "pzmap"), "model"),
    "plot_frd": "frequency",
    **dict.fromkeys(("plot_data", "plot_spectra", "plot_coherence", "plot_correlation"),
                    "data"),
    **dict.fromkeys(("plot_compare", "plot_compare_set", "plot_residuals",
                     "plot_error_spectrum", "plot_singular_values", "plot_order_selection"),
                    "validation"),
    "plot_hankel_singular_values": "realization",
}


def __getattr__(name: str) -> Any:
    import importlib
    import importlib.util

    module = _FUNCTIONS.get(name)
    if module is None:
        if not name.startswith("_") and importlib.util.find_spec(f"{__name__}.{name}"):
            return importlib.import_module(f".{name}", __name__)  # a submodule, on first use
        raise AttributeError(f"module 'sysid.plot' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_FUNCTIONS))
