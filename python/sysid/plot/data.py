"""Plots of records and of their non-parametric analysis (spectra, coherence, correlation)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from . import _pyplot

__all__ = ["plot_data", "plot_spectra", "plot_coherence", "plot_correlation"]


def _label(name: str, unit: str) -> str:
    return f"{name} [{unit}]" if unit else name


def plot_data(data: Any, *, fig: Any = None) -> Any:
    """One panel per channel (inputs first) against time; experiments in turn, separated by
    dashed lines where one ends.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> import numpy as np, sysid, matplotlib
    >>> matplotlib.use("Agg")
    >>> fig = sysid.IOData(u=np.ones(10), y=np.arange(10.0)).plot()
    >>> len(fig.axes)
    2
    """
    plt = _pyplot()
    nc = data.n_inputs + data.n_outputs
    if fig is None:
        fig = plt.figure(figsize=(8, 1.6 * nc + 0.6))
    axes = fig.subplots(nc, 1, sharex=True, squeeze=False)[:, 0]
    labels = [_label(n, u) for n, u in zip(data.input_names + data.output_names,
                                            data.input_units + data.output_units)]
    for (u, y), t in zip(data.experiments, data.times):
        z = np.hstack([u, y])
        for j, ax in enumerate(axes):
            ax.plot(t, z[:, j], lw=0.8, color="C0" if j < data.n_inputs else "C1")
            if data.n_experiments > 1:
                ax.axvline(t[-1], color="0.6", ls="--", lw=0.6)
    for ax, lab in zip(axes, labels):
        ax.set_ylabel(lab)
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    fig.tight_layout()
    return fig


def plot_spectra(spectra: Any, *, channels: Sequence[str] | None = None, ax: Any = None) -> Any:
    """Log-log auto spectra of the chosen channels (default all) on one axes."""
    plt = _pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4))
    names = spectra.names if channels is None else list(channels)
    f = spectra.hz
    sel = f > 0
    for n in names:
        ax.loglog(f[sel], np.maximum(spectra.psd(n)[sel], 1e-300), lw=0.9, label=n)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("PSD [unit$^2$/Hz]")
    ax.set_title(f"power spectral density ({spectra.method})")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="small")
    return ax


def plot_coherence(coh: Any, *, fig: Any = None, threshold: float | None = 0.6) -> Any:
    """One panel per input; each output's coherence with it against frequency."""
    plt = _pyplot()
    m = len(coh.input_names)
    if fig is None:
        fig = plt.figure(figsize=(7, 2.2 * m + 0.6))
    axes = fig.subplots(m, 1, sharex=True, squeeze=False)[:, 0]
    f = coh.hz
    for j, ax in enumerate(axes):
        for i, o in enumerate(coh.output_names):
            ax.semilogx(f[f > 0], coh.values[f > 0, i, j], lw=0.9, label=o)
        if threshold is not None:
            ax.axhline(threshold, color="0.5", ls="--", lw=0.8)
        ax.set_ylim(0, 1.02)
        ax.set_ylabel(f"coherence with {coh.input_names[j]}")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize="small")
    axes[-1].set_xlabel("frequency [Hz]")
    fig.tight_layout()
    return fig


def plot_correlation(corr: Any, a: str, b: str, *, ax: Any = None) -> Any:
    """Correlation ``r_ab(tau)`` against lag with the confidence bounds."""
    plt = _pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 3))
    r = corr.pair(a, b)
    ax.vlines(corr.lags, 0, r, lw=1.2)
    ax.plot(corr.lags, r, "o", ms=3)
    ax.axhline(corr.bound, color="C3", ls="--", lw=0.8)
    ax.axhline(-corr.bound, color="C3", ls="--", lw=0.8)
    ax.set_xlabel("lag [samples]")
    ax.set_ylabel(f"r({a}, {b})")
    ax.grid(True, alpha=0.3)
    return ax
