"""The subspace weightings by name (``method=``), and which of them are closed-loop methods."""

from __future__ import annotations

from ..errors import DataError

__all__ = ["METHODS", "CLOSED_LOOP", "MATRICES", "MATRICES_DEFAULT"]

METHODS = ("moesp", "ordinary-moesp", "pi-moesp", "n4sid", "cva", "pbsid", "ssarx")
CLOSED_LOOP = ("pbsid", "ssarx")
#: how a fit takes A, B, C, D from the weighted SVD (``matrices=``): ``"shift"``, A and C by
#: the shift invariance of the observability matrix, B and D by least squares; ``"states"``,
#: all four by least squares on the estimated state sequence; ``"auto"``, the shift unless its
#: ``A`` is unstable, then the states if theirs is stable (the core's ``SystemMatrices``)
MATRICES = ("shift", "states", "auto")
MATRICES_DEFAULT = "shift"
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


def _matrices(matrices: str | None) -> str:
    """``matrices`` checked (None: :data:`MATRICES_DEFAULT`); a DataError otherwise."""
    if matrices is None:
        return MATRICES_DEFAULT
    if not isinstance(matrices, str) or matrices.lower() not in MATRICES:
        raise DataError(f"matrices must be one of {MATRICES}, got {matrices!r}")
    return matrices.lower()
