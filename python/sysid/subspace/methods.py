"""The subspace weightings by name (``method=``), and which of them are closed-loop methods."""

from __future__ import annotations

from ..errors import DataError

__all__ = ["METHODS", "CLOSED_LOOP"]

METHODS = ("moesp", "ordinary-moesp", "pi-moesp", "n4sid", "cva", "pbsid", "ssarx")
CLOSED_LOOP = ("pbsid", "ssarx")
_ALIASES = {"po-moesp": "moesp", "pomoesp": "moesp", "moesp-ordinary": "ordinary-moesp",
            "pbsid-opt": "pbsid"}


def _method(method: str) -> str:
    """The canonical name of a weighting (aliases and case folded); a DataError otherwise."""
    if not isinstance(method, str):
        raise DataError(f"method must be one of {METHODS}, got {method!r}")
    key = _ALIASES.get(method.lower(), method.lower())
    if key not in METHODS:
        raise DataError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    return key
