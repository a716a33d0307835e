"""Plots of realisation results: Hankel singular values and stabilisation diagrams."""

from __future__ import annotations

from typing import Any

import numpy as np

from . import _pyplot

__all__ = ["plot_hankel_singular_values", "plot_stabilization"]


def plot_hankel_singular_values(sv: Any, order: int | None = None, *, ax: Any = None) -> Any:
    """Singular values of the block-Hankel matrix (log scale), the chosen order marked.

    Returns
    -------
    matplotlib.axes.Axes

    Examples
    --------
    >>> import matplotlib, sysid
    >>> matplotlib.use("Agg")
    >>> m = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0], [0.0]], [[1.0, 0.0]])
    >>> ax = sysid.era(m.markov(30)).plot()
    >>> ax.get_ylabel()
    'singular value'
    """
    plt = _pyplot()
    if ax is None:
        ax = plt.figure(figsize=(5, 3.2)).add_subplot()
    s = np.asarray(sv, dtype=float)
    k = np.arange(1, s.size + 1)
    ax.semilogy(k, np.maximum(s, s[0] * 1e-16 if s.size else 1e-300), "o-", ms=3, lw=0.8)
    if order is not None:
        ax.axvline(order + 0.5, color="C3", lw=0.8, ls="--", label=f"order {order}")
        ax.legend()
    ax.set_xlabel("index")
    ax.set_ylabel("singular value")
    return ax


def plot_stabilization(diagram: Any, *, ax: Any = None) -> Any:
    """Stabilisation diagram: natural frequency of each mode against the model order.

    Filled markers: the mode is stable in frequency and damping with respect to the previous
    order (and coherent, MAC above the threshold); open markers: stable in frequency only;
    dots: new modes.

    Returns
    -------
    matplotlib.axes.Axes
    """
    plt = _pyplot()
    if ax is None:
        ax = plt.figure(figsize=(6, 4)).add_subplot()
    styles = {2: dict(marker="o", color="C2", ls="none", ms=5, label="stable (f, zeta, MAC)"),
              1: dict(marker="o", mfc="none", color="C1", ls="none", ms=5,
                      label="stable frequency"),
              0: dict(marker=".", color="0.6", ls="none", ms=4, label="new")}
    for level, style in styles.items():
        xs, ys = [], []
        for order, modes, status in zip(diagram.orders, diagram.modes, diagram.status):
            sel = status == level
            ys.extend(modes.frequencies_hz[sel])
            xs.extend([order] * int(sel.sum()))
        ax.plot(ys, xs, **style)
    ax.set_xlabel("natural frequency (Hz)")
    ax.set_ylabel("model order")
    ax.legend(loc="best", fontsize="small")
    return ax
