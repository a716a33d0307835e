"""Argument checks and small helpers shared by :func:`sysid.tfest` (time and frequency
domain) and :func:`sysid.procest`."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError

__all__ = ["orders", "pole_zero_orders", "delays", "search_limits", "progress_callback",
           "blockdiag", "fit_percent"]


def orders(x: Any, l: int, m: int, name: str, lo: int) -> np.ndarray:
    if isinstance(x, str):  # "auto": as MATLAB's tfest, the orders are the user's
        raise DataError(
            f"{name} must be a whole number (or one per output/input pair), got {x!r}: "
            "tfest has no automatic order (as MATLAB's); compare a few with "
            "sysid.select_order(est, models=[sysid.tfest(est, n) for n in range(1, 5)], "
            "validation=val), or let sysid.identify(data) choose a model")
    a = np.asarray(x)
    # inf equals its rounding: refused here, before the cast to int wraps it
    if a.dtype.kind not in "iuf" or not np.all(np.isfinite(a)) or not np.all(a == np.round(a)):
        raise DataError(f"{name} must be a whole number (or one per output/input pair), got {x!r}")
    try:
        out = np.broadcast_to(a.astype(int), (l, m)).copy()
    except ValueError:
        raise DataError(f"{name} must be one number or an array ({l}, {m}) for {l} output(s) "
                        f"and {m} input(s), got shape {a.shape}") from None
    if np.any(out < lo) or np.any(out > 30):
        raise DataError(f"{name} must lie in {lo}..30, got {out.ravel().tolist()}")
    return out


def pole_zero_orders(n_poles: Any, n_zeros: Any, l: int, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Poles and zeros per output/input pair (``n_zeros=None``: one fewer than the poles),
    checked proper.

    Examples
    --------
    >>> from sysid.tf.options import pole_zero_orders
    >>> npo, nze = pole_zero_orders(2, None, 1, 2)
    >>> npo.tolist(), nze.tolist()
    ([[2, 2]], [[1, 1]])
    """
    npo = orders(n_poles, l, m, "n_poles", 0)
    nze = np.maximum(npo - 1, 0) if n_zeros is None else orders(n_zeros, l, m, "n_zeros", 0)
    if np.any(nze > npo):
        raise DataError("n_zeros must not exceed n_poles (the model would be improper); give "
                        "n_zeros <= n_poles")
    return npo, nze


def delays(iodelay: Any, l: int, m: int) -> tuple[np.ndarray, bool]:
    if iodelay is None:
        return np.zeros((l, m)), False
    if isinstance(iodelay, str):
        if iodelay != "auto":
            raise DataError(f"iodelay must be None, seconds, or 'auto', got {iodelay!r}")
        return np.zeros((l, m)), True
    try:
        d = np.broadcast_to(np.asarray(iodelay, dtype=float), (l, m)).copy()
    except (ValueError, TypeError):
        raise DataError(f"iodelay must be seconds (one value or ({l}, {m})) or 'auto', got "
                        f"{iodelay!r}") from None
    if not np.all(np.isfinite(d)) or np.any(d < 0):
        raise DataError(f"iodelay must be finite and >= 0 seconds, got {d.ravel().tolist()}")
    return d, False


def search_limits(max_iter: Any, tol: Any, max_delay: Any) -> tuple[int, float]:
    """Checked ``(max_iter, tol)``; ``max_delay`` must be ``None`` or positive seconds.

    Examples
    --------
    >>> from sysid.tf.options import search_limits
    >>> search_limits(50, 1e-8, None)
    (50, 1e-08)
    """
    from .._checks import as_int

    it = as_int(max_iter, "max_iter", 0)
    try:
        t = float(tol)
    except (TypeError, ValueError):
        t = float("nan")
    if not (np.isfinite(t) and t > 0):
        raise DataError(f"tol must be a positive finite number (e.g. 1e-10), got {tol!r}")
    if max_delay is not None:
        try:
            d = float(max_delay)
        except (TypeError, ValueError):
            d = float("nan")
        if not (np.isfinite(d) and d > 0):
            raise DataError(f"max_delay must be None or a positive number of seconds, got "
                            f"{max_delay!r}")
    return it, t


def progress_callback(progress: Any, max_iter: int) -> Any:
    from .._progress import iteration_callback, iteration_printer

    return iteration_callback(progress, "tfest", max_iter,
                              iteration_printer("tfest", "sum of squares / 2"))


def blockdiag(mats: list[np.ndarray]) -> np.ndarray:
    k = sum(m.shape[0] for m in mats)
    out, o = np.zeros((k, k)), 0
    for m in mats:
        out[o:o + m.shape[0], o:o + m.shape[0]] = m
        o += m.shape[0]
    return out


def fit_percent(G: Any, data: Any) -> None:
    num = den = 0.0
    fits = []
    for i in range(G.noutputs):
        num = den = 0.0
        for u, y in data.experiments:
            yh = G.simulate(u, dt=data.dt)[:, i]
            num += float(np.sum((y[:, i] - yh) ** 2))
            den += float(np.sum((y[:, i] - np.mean(y[:, i])) ** 2))
        fits.append(100.0 * (1 - np.sqrt(num / den)) if den > 0 else float("nan"))
    G.info["fit_percent"] = [round(f, 4) for f in fits]
