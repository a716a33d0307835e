"""An HTML report of any model against data: fit, residual tests, spectra, Bode, poles.

:func:`report` writes a folder with ``index.html``, the figures (PNG, matplotlib ``Agg``),
``fit.csv`` and, when the model can be saved, ``model.json``; with an
:class:`~sysid.validation.criteria.OrderSelection` it adds the order sweep (``orders.csv``,
singular values, criteria, stabilisation diagram). ``sysid identify --report`` uses it.
"""

from __future__ import annotations

import csv
import html
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..data.iodata import IOData
from ..errors import DataError, SysidError
from ..models.checks import check_model
from ..validation.compare import compare, error_spectrum
from ..validation.criteria import _pct
from ..validation.residuals import residuals

__all__ = ["report"]


def report(model: Any, data: Any, path: str | Path, *, selection: Any = None,
           which: str = "validation", max_lag: int | None = None) -> dict[str, Path]:
    """Write an HTML report of ``model`` on ``data`` into the folder ``path``.

    Parameters
    ----------
    model : sysid.Model
        Any model (state-space, continuous, polynomial, your own class).
    data : IOData or (u, y)
        Data to validate on (a continuous model needs an IOData).
    path : str or Path
        Output folder (created).
    selection : OrderSelection, optional
        An order sweep to include (:func:`sysid.select_order`).
    which : str
        What the data are, for the captions (``"validation"`` or ``"estimation"``).
    max_lag : int, optional
        Largest residual lag (default ``min(25, N / 5)``).

    Returns
    -------
    dict
        ``name -> Path`` of every file written (``"html"`` is the page).

    Examples
    --------
    >>> import tempfile, numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]], K=[[0.5]])
    >>> u, e = np.random.default_rng(0).standard_normal((2, 300, 1))
    >>> files = sysid.report(m, (u, m.simulate(u) + 0.1 * e), tempfile.mkdtemp())
    >>> sorted(files)[:4]
    ['bode', 'compare', 'error_spectrum', 'fit']
    """
    import matplotlib

    matplotlib.use("Agg")
    from ..plot import _pyplot
    from ..plot.model import plot_bode, plot_pzmap

    check_model(model)
    root = Path(path)
    root.mkdir(parents=True, exist_ok=True)
    plt = _pyplot()
    sim = compare(model, data)
    pred = compare(model, data, horizon=1)
    shortest = min(y.shape[0] for y in sim.y)
    res = residuals(model, data, max_lag=max_lag or min(25, max(1, shortest // 5)))
    spec = error_spectrum(model, data)
    files: dict[str, Path] = {}
    notes: list[str] = []
    if callable(getattr(model, "to_dict", None)):
        from ..models.serialize import save_model

        files["model"] = root / "model.json"
        save_model(model, files["model"])
    else:
        notes.append(f"{type(model).__name__} has no to_dict(): model file not written")

    files["fit"] = root / "fit.csv"
    with open(files["fit"], "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["output", "simulation fit %", "1-step fit %", "simulation VAF %",
                    "simulation RMSE", "whiteness p", "independence p"])
        for j, name in enumerate(model.output_names):
            w.writerow([name, f"{sim.fit.mean(0)[j]:.4f}", f"{pred.fit.mean(0)[j]:.4f}",
                        f"{sim.vaf.mean(0)[j]:.4f}", f"{sim.rmse.mean(0)[j]:.6g}",
                        f"{res.ljung_box_pvalue[j]:.4g}", f"{res.independence_pvalue[j]:.4g}"])

    def save(name: str, fig: Any) -> None:
        files[name] = root / f"{name}.png"
        fig.savefig(files[name], dpi=90, bbox_inches="tight")  # no clipped axis labels
        plt.close(fig)

    if selection is not None:
        from ..plot.validation import plot_singular_values

        files["orders"] = root / "orders.csv"
        selection.to_pandas().to_csv(files["orders"], index=False)
        if selection.method in selection.singular_values:
            ax = plot_singular_values(selection.singular_values[selection.method],
                                      selection.order)
            ax.set_title("singular values (order choice)")
            save("singular_values", ax.figure)
        save("order_selection", selection.plot())
        save("stabilization", selection.stabilization_plot().figure)
    save("compare", sim.plot())
    if shortest > 2 * _WINDOW:
        save("compare_window", _window(sim.plot(), _WINDOW))
    save("residuals", res.plot())
    save("error_spectrum", spec.plot())
    if model.ninputs == 0:
        notes.append("time-series model (no inputs): no Bode plot or step response; the "
                     "error spectrum shows what the model leaves unexplained")
    else:
        save("bode", _bode_with_spa(model, data, plot_bode, notes))
    try:
        save("pzmap", plot_pzmap(model).figure)
    except DataError as e:  # no poles()/zeros() nor to_statespace()
        plt.close("all")
        notes.append(f"no pole-zero map: {e}")
    from .lti import step

    if model.ninputs:
        save("step", step(model).plot())
    files["html"] = root / "index.html"
    files["html"].write_text(_html(model, sim, pred, res, selection, which, files, notes),
                             encoding="utf-8")
    return files


_WINDOW = 500  # samples shown in the zoomed comparison of a long record


def _window(fig: Any, n: int) -> Any:
    """The comparison figure zoomed on its first ``n`` samples (a long record is a block)."""
    for ax in fig.axes:
        lines = [ln for ln in ax.get_lines() if len(ln.get_xdata()) > n]
        if lines:
            x = np.asarray(lines[0].get_xdata(), dtype=float)
            ax.set_xlim(x[0], x[n - 1])
            ax.relim(visible_only=True)
    fig.suptitle(f"first {n} samples")
    return fig


def _bode_with_spa(model: Any, data: Any, plot_bode: Any, notes: list[str]) -> Any:
    """The model's Bode plot with the non-parametric (spa) estimate beside it."""
    from ..nonparametric.frf import spa

    try:
        frd = spa(data if isinstance(data, IOData) else IOData(*data))
    except SysidError as e:
        notes.append(f"no spa estimate on the Bode plot: {e}")
        return plot_bode(model)
    return plot_bode([model, frd], labels=["model", "spa (non-parametric)"])


def _html(model: Any, sim: Any, pred: Any, res: Any, sel: Any, which: str,
          files: dict[str, Path], notes: list[str]) -> str:
    esc = html.escape

    def table(tid: str, header: list[str], rows: list[list[Any]]) -> str:
        th = "".join(f"<th>{esc(h)}</th>" for h in header)
        body = "".join("<tr>" + "".join(f"<td>{esc(str(c))}</td>" for c in r) + "</tr>"
                       for r in rows)
        return f'<table id="{tid}" border="1" cellpadding="3"><tr>{th}</tr>{body}</table>'

    fit_rows = [[name, f"{sim.fit.mean(0)[j]:.2f}", f"{pred.fit.mean(0)[j]:.2f}",
                 f"{res.ljung_box_pvalue[j]:.3g}", "yes" if res.whiteness[j] else "no"]
                for j, name in enumerate(model.output_names)]
    captions = (
        ("compare", f"{which} data: measured and simulated outputs"),
        ("compare_window", f"{which} data: the first {_WINDOW} samples"),
        ("residuals", "residual correlations with 99 % bounds"),
        ("error_spectrum", "spectrum of the simulation error"),
        ("singular_values", "singular values"),
        ("order_selection", "order selection"),
        ("stabilization", "stabilisation diagram"),
        ("bode", "Bode plot: the model and the spa (Blackman-Tukey) estimate"),
        ("pzmap", "pole-zero map"),
        ("step", "step response"),
    )
    imgs = "".join(
        f'<figure><img src="{esc(files[k].name)}" alt="{esc(k)}"><figcaption>{esc(cap)}'
        "</figcaption></figure>"
        for k, cap in captions if k in files
    )
    details = res.summary()
    from .lti import damp

    poles = ""
    try:
        details += "\n\n" + repr(damp(model))
        poles = "<h2>Poles</h2>\n" + _pole_table(model, table)
    except DataError:
        pass
    params = _parameter_table(model, table)
    sweep = ""
    if sel is not None:
        order_rows = [[r.get("model", r["method"]), r["order"], f"{r['singular_value']:.4g}",
                       f"{r['aic']:.2f}", f"{r['bic']:.2f}", _pct(r["fit_validation"]).strip(),
                       "yes" if r["stable"] else "no"] for r in sel.rows if r["error"] is None]
        sweep = (f"<p>Order choice: {esc(sel.reason)}</p>\n<h2>Order sweep</h2>\n"
                 + table("orders", ["method", "order", "singular value", "AIC", "BIC",
                                    "validation fit %", "stable"], order_rows))
    links = ", ".join(f'<a href="{esc(p.name)}">{esc(p.name)}</a>' for k, p in files.items()
                      if p.suffix in (".json", ".csv"))
    note = "".join(f"<p><em>{esc(n)}</em></p>" for n in notes)
    return f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>sysid report</title>
<style>body{{font-family:sans-serif;max-width:1100px;margin:auto}}img{{max-width:100%}}
td,th{{text-align:right}}</style></head><body>
<h1>sysid identification report</h1>
<p>{esc(repr(model))}</p>
{sweep}
<pre>{esc(details)}</pre>
{params}
{poles}
<h2>Fit on the {esc(which)} data</h2>
{table("fit", ["output", "simulation fit %", "1-step fit %", "whiteness p", "white"], fit_rows)}
<p>Files: {links}</p>
{note}
{imgs}
</body></html>
"""


def _parameter_table(model: Any, table: Callable[[str, list[str], list[list[Any]]], str]
                     ) -> str:
    """The grey-box parameter table (name, value, std, fixed, active bound, 95 % interval,
    unit) when the model carries one (``info["greybox"]["parameters"]``, set by greyest)."""
    info = getattr(model, "info", None) or {}
    rows = (info.get("greybox") or {}).get("parameters")
    if not rows:
        return ""

    def g(x: float) -> str:
        return f"{x:.6g}"
    body = [[r["name"], g(r["value"]), g(r["std"]), "fixed" if r["fixed"] else "",
             r["bound"], "" if r["fixed"] else f"[{g(r['ci95'][0])}, {g(r['ci95'][1])}]",
             r["unit"], r["description"]] for r in rows]
    return "<h2>Parameters</h2>\n" + table(
        "parameters", ["parameter", "value", "std", "fixed", "bound active", "95 % interval",
                       "unit", "description"], body)


def _pole_table(model: Any, table: Callable[[str, list[str], list[list[Any]]], str]) -> str:
    """Poles with frequency and damping, and their standard deviations when the model has
    an uncertainty (NaN, shown as n/a, where first order does not hold)."""
    import warnings

    from ..models.uncertainty import UncertaintyWarning
    from .lti import damp

    has = getattr(model, "uncertainty", None) is not None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UncertaintyWarning)
        t = damp(model, std=has)

    def g(x: float) -> str:
        return "n/a" if not np.isfinite(x) else f"{x:.4g}"
    header = ["pole", "|pole|", "wn [Hz]", "damping"]
    if has:
        header += ["std Re", "std Im", "std wn [Hz]", "std damping"]
    rows = []
    for k, p in enumerate(t.poles):
        row = [f"{p.real:.5g}{p.imag:+.5g}j", f"{abs(p):.4f}", g(t.wn_hz[k]), g(t.zeta[k])]
        if has and t.pole_std is not None and t.wn_hz_std is not None and \
                t.zeta_std is not None:
            row += [g(t.pole_std[k].real), g(t.pole_std[k].imag), g(t.wn_hz_std[k]),
                    g(t.zeta_std[k])]
        rows.append(row)
    note = ("<p>Standard deviations: first order, from the model's parameter uncertainty ("
            f"{html.escape(str(model.uncertainty.method))}).</p>" if has else "")
    return table("poles", header, rows) + note

