"""Plots of validation results and of order selection (matplotlib, imported lazily)."""

from __future__ import annotations

from typing import Any

import numpy as np

from . import _pyplot

__all__ = [
    "plot_compare",
    "plot_residuals",
    "plot_error_spectrum",
    "plot_singular_values",
    "plot_order_selection",
    "plot_stabilization",
]


def _fig(fig: Any, nrows: int, ncols: int = 1, height: float = 2.4) -> tuple[Any, np.ndarray]:
    plt = _pyplot()
    if fig is None:
        fig = plt.figure(figsize=(8, max(3.0, height * nrows)))
    axes = np.atleast_1d(fig.subplots(nrows, ncols, squeeze=False))
    return fig, axes


def _plot_outputs(results: list[Any], names: list[str], experiment: int, fig: Any,
                  skip_diverged: bool) -> Any:
    """Measured outputs of ``experiment`` (from the first result) and each result's model
    outputs, one axis per output, labelled ``name (fit ...)``; with ``skip_diverged`` a
    result that diverged is named in the legend, not drawn."""
    first = results[0]
    y = first.y[experiment]
    fig, axes = _fig(fig, y.shape[1])
    t0 = getattr(first, "t0", None)  # the record's start time (compare of an IOData)
    t = (t0[experiment] if t0 else 0.0) + np.arange(y.shape[0]) * first.dt
    for j in range(y.shape[1]):
        ax = axes[j, 0]
        ax.plot(t, y[:, j], color="0.3", lw=1.0, label="measured")
        for k, (name, r) in enumerate(zip(names, results)):
            if skip_diverged and r.diverged[experiment]:
                ax.plot([], [], color=f"C{k}", label=f"{name}: diverged")
                continue
            ax.plot(t, r.yhat[experiment][:, j], color=f"C{k}", lw=1.0,
                    label=f"{name} (fit {r.fit[experiment, j]:.1f} %)")
        ax.set_ylabel(first.output_names[j])
        ax.legend(loc="best", fontsize=8)
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("time [s]")
    fig.tight_layout()
    return fig


def plot_compare(result: Any, experiment: int = 0, fig: Any = None) -> Any:
    """Measured and model outputs of a :class:`~sysid.validation.compare.CompareResult`."""
    return _plot_outputs([result], [result.kind], experiment, fig, skip_diverged=False)


def plot_compare_set(cset: Any, experiment: int = 0, fig: Any = None) -> Any:
    """Measured outputs and every model's of a :class:`~sysid.validation.comparison.CompareSet`
    (a model that diverged is named in the legend, not drawn)."""
    return _plot_outputs(list(cset.results), list(cset.names), experiment, fig,
                         skip_diverged=True)


def plot_residuals(res: Any, fig: Any = None) -> Any:
    """Auto-correlations (left) and input cross-correlations (right) with the band per lag."""
    l, m = len(res.output_names), len(res.input_names)
    ncols = 2 if m else 1
    fig, axes = _fig(fig, l, ncols)
    for i in range(l):
        ax = axes[i, 0]
        ax.vlines(res.lags[1:], 0, res.autocorr[1:, i, i], color="C0")
        ax.fill_between(res.lags[1:], -res.bounds[1:], res.bounds[1:], color="C2", alpha=0.2,
                        step="mid")
        verdict = "white" if res.whiteness[i] else "NOT white"
        ax.set_title(f"auto-correlation of e({res.output_names[i]}): {verdict} "
                     f"(p = {res.ljung_box_pvalue[i]:.2g})", fontsize=9)
        ax.set_xlabel("lag")
        if m:
            ax = axes[i, 1]
            for j in range(m):
                ax.plot(res.xlags, res.crosscorr[:, i, j], marker=".", lw=0.8,
                        label=res.input_names[j])
            ax.fill_between(res.xlags, -res.xbounds, res.xbounds, color="C2", alpha=0.2,
                            step="mid")
            ax.set_title(f"cross-correlation e({res.output_names[i]}) with u(t - lag)",
                         fontsize=9)
            ax.set_xlabel("lag")
            if m > 1:
                ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def plot_error_spectrum(spec: Any, fig: Any = None) -> Any:
    """Spectra of the simulation error and the output."""
    l = len(spec.output_names)
    fig, axes = _fig(fig, l)
    for j in range(l):
        ax = axes[j, 0]
        ax.semilogy(spec.freq, spec.output_psd[:, j], color="0.4", label="output")
        ax.semilogy(spec.freq, spec.error_psd[:, j], color="C3", label="simulation error")
        ax.set_ylabel(f"PSD {spec.output_names[j]}")
        ax.legend(fontsize=8)
        ax.grid(True, which="both", alpha=0.3)
    axes[-1, 0].set_xlabel("frequency [Hz]")
    fig.tight_layout()
    return fig


def plot_singular_values(sv: Any, order: int | None = None, ax: Any = None) -> Any:
    """Singular values on a log scale, the chosen order marked; returns the axis."""
    plt = _pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 3.5))
    sv = np.asarray(sv, dtype=float)
    k = np.arange(1, sv.size + 1)
    ax.semilogy(k, np.maximum(sv, 1e-300), "o-", color="C0")
    if order is not None and 1 <= order <= sv.size:
        ax.semilogy([order], [sv[order - 1]], "o", ms=12, mfc="none", color="C3",
                    label=f"order {order}")
        ax.legend()
    ax.set_xlabel("index")
    ax.set_ylabel("singular value")
    ax.grid(True, which="both", alpha=0.3)
    return ax


def plot_order_selection(table: Any, fig: Any = None) -> Any:
    """Singular values, information criteria and validation fit versus order."""
    fig, axes = _fig(fig, 1, 3, height=3.5)
    fig.set_size_inches(12, 3.5)
    df = table.rows
    methods = sorted({r["method"] for r in df})
    for meth in methods:
        if meth in table.singular_values:
            sv = table.singular_values[meth]
            plot_singular_values(sv, table.order if meth == table.method else None,
                                 ax=axes[0, 0])
    axes[0, 0].set_title("singular values" if table.singular_values
                         else "no singular values (given models)")
    ax = axes[0, 1]
    rows = [r for r in df if r["method"] == table.method]
    orders = np.array([r["order"] for r in rows])
    for crit, name in (("aic", "AIC"), ("aicc", "AICc"), ("bic", "BIC")):
        vals = np.array([r[crit] for r in rows], dtype=float)
        ax.plot(orders, vals, "o-", label=name)
    ax.set_title(f"information criteria ({table.method})")
    ax.set_xlabel("order")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    ax = axes[0, 2]
    for meth in methods:
        r = [x for x in df if x["method"] == meth]
        key = "fit_validation" if table.has_validation else "fit_estimation"
        fits = np.array([x[key] for x in r], dtype=float)
        # diverging fits of unstable models would flatten everything else: clip them
        ax.plot([x["order"] for x in r], np.where(fits < -100, np.nan, fits), "o-", label=meth)
        held = np.array([x.get("fit_held_out", np.nan) for x in r], dtype=float)
        if np.isfinite(held).any():  # the cross-validated fits the "cv" rule read
            ax.plot([x["order"] for x in r], np.where(held < -100, np.nan, held), "s--",
                    label=f"{meth} (held out)")
    ax.set_title(("validation fit %" if table.has_validation else "estimation fit %")
                 + " (below -100 not shown)")
    ax.set_xlabel("order")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


def plot_stabilization(table: Any, ax: Any = None, hz: bool = True) -> Any:
    """Stabilisation diagram: pole frequencies versus model order.

    The classes of :func:`sysid.analysis.report_figures.stabilization_classes`: a pole is
    *new*, *stable in frequency* (the nearest pole of the next lower order within 1 %) or
    *stable in frequency and damping* (and within 5 % in damping); crosses mark unstable
    poles.
    """
    from ..analysis.report_figures import STAB_STYLE, stabilization_classes

    plt = _pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4))
    cats, _ = stabilization_classes(table, table.method)
    scale = 1.0 if hz else 2 * np.pi
    for key, pts in cats.items():
        if pts:
            arr = np.array(pts)
            name, color, marker = STAB_STYLE[key]
            kw = ({"marker": "x"} if marker == "x" else
                  {"marker": "o", "mfc": "none" if marker == "open" else color})
            ax.plot(arr[:, 0] * scale, arr[:, 1], ls="none", color=color, label=name, **kw)
    ax.legend(fontsize=7, loc="upper right")
    ax.set_xlabel("natural frequency [Hz]" if hz else "natural frequency [rad/s]")
    ax.set_ylabel("model order")
    from matplotlib.ticker import MaxNLocator

    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_title(f"stabilisation diagram ({table.method})")
    ax.grid(True, alpha=0.3)
    return ax
