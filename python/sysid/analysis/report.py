"""An interactive HTML report of any model against data: summary, fit, residual tests,
spectra, Bode with confidence bands, poles, and the order choice.

:func:`report` writes a folder with ``index.html`` (one self-contained page: tables, foldable
sections, zoomable charts drawn by an inline script, no network needed), ``fit.csv`` and, when
the model can be saved, ``model.json``; with an
:class:`~sysid.validation.criteria.OrderSelection` it adds the order sweep (``orders.csv``,
singular values, stabilisation diagram). Warnings raised while the report is computed (and
those passed in ``warnings=``, e.g. from the identification run) are shown at the top with
what to do. ``sysid identify --report`` uses it.
"""

from __future__ import annotations

import csv
import html
import warnings as _warnings
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from .._atomic import atomic_path, write_text
from ..data.iodata import IOData
from ..errors import DataError, SysidError
from ..models.checks import check_model
from ..validation.compare import compare_quiet as compare
from ..validation.criteria import _pct
from ..validation.error_spectrum import error_spectrum
from ..validation.residuals import default_max_lag, no_noise_model, residuals
from . import report_figures as rf
from .report_page import Page, reissue, relevant, status, warning_items

__all__ = ["report"]

esc = html.escape
HINT = ('<p class="hint">Charts: drag a box to zoom, double-click to reset; hover for '
        "values.</p>")


def report(model: Any, data: Any, path: str | Path, *, selection: Any = None,
           which: str = "validation", max_lag: int | None = None,
           warnings: Iterable[Any] | None = None, title: str = "sysid report"
           ) -> dict[str, Path]:
    """Write an HTML report of ``model`` on ``data`` into the folder ``path``.

    Parameters
    ----------
    model : sysid.Model
        Any model (state-space, continuous, polynomial, your own class).
    data : IOData or (u, y)
        Data to validate on (a continuous model needs an IOData). Channel units of an
        IOData label the charts.
    path : str or Path
        Output folder (created).
    selection : OrderSelection, optional
        An order sweep to include (:func:`sysid.select_order`).
    which : str
        What the data are, for the captions (``"validation"`` or ``"estimation"``).
    max_lag : int, optional
        Largest residual lag (default :func:`~sysid.validation.residuals.default_max_lag`:
        ``min(25, N / 5)``, lower when the inputs' lags would leave too few samples).
    warnings : iterable, optional
        Warnings of the run that produced the model, shown in the summary with what to do:
        :class:`warnings.WarningMessage` objects (``catch_warnings(record=True)``),
        ``(category name, message)`` pairs or strings. Warnings raised while the report is
        computed are added, and re-issued after the page is written.
    title : str
        The page title.

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
    >>> sorted(files)
    ['fit', 'html', 'model']
    """
    model = check_model(model)
    _check_selection(selection)
    if which not in ("validation", "estimation"):
        raise DataError(f"which must be 'validation' or 'estimation' (what the data are, for "
                        f"the captions), got {which!r}")
    root = Path(path)
    root.mkdir(parents=True, exist_ok=True)
    data = data if isinstance(data, IOData) else IOData(*data, dt=model.dt or 1.0,
                                                        input_names=list(model.input_names),
                                                        output_names=list(model.output_names))
    found = [_as_pair(w) for w in (warnings or [])
             if not isinstance(w, _warnings.WarningMessage) or relevant([w])]
    with _warnings.catch_warnings(record=True) as caught:
        _warnings.simplefilter("always")
        files, page = _build(model, data, root, selection, which, max_lag, title, found)
    own = [_as_pair(w) for w in relevant(caught)]
    page.parts.insert(1, _summary(model, page.facts, selection, found + own))
    files["html"] = root / "index.html"
    write_text(files["html"], page.html())
    reissue(caught)  # the caller still sees them
    return files


def _check_selection(selection: Any) -> None:
    """Refuse a ``selection`` that is not an order sweep, saying what to pass."""
    from ..validation.criteria import OrderSelection

    if selection is None or isinstance(selection, OrderSelection):
        return
    hint = (": the report of an identify result is sysid.report(result.model, data, path)"
            if hasattr(selection, "leaderboard") else "")
    raise DataError(f"selection must be an order sweep (the OrderSelection of "
                    f"sysid.select_order) or None, got {type(selection).__name__}{hint}")


def _as_pair(w: Any) -> tuple[str, str]:
    if isinstance(w, tuple):
        return str(w[0]), str(w[1])
    if isinstance(w, str):
        return "Warning", w
    return getattr(w.category, "__name__", "Warning"), " ".join(str(w.message).split())


def _units(data: IOData) -> dict[str, str]:
    return {n: u for n, u in zip(data.input_names + data.output_names,
                                 data.input_units + data.output_units) if u}


def _build(model: Any, data: IOData, root: Path, sel: Any, which: str,
           max_lag: int | None, title: str, found: list[tuple[str, str]]
           ) -> tuple[dict[str, Path], Page]:
    sim = compare(model, data)
    pred = compare(model, data, horizon=1)
    res = residuals(model, data, max_lag=max_lag or default_max_lag(data))
    units = _units(data)
    files: dict[str, Path] = {}
    page = Page(title)
    page.facts = {"sim": sim, "pred": pred, "res": res, "which": which}
    page.add(f"<h1>{esc(title)}</h1>")
    notes: list[str] = []
    if callable(getattr(model, "to_dict", None)):
        from ..models.serialize import save_model

        files["model"] = root / "model.json"
        save_model(model, files["model"])
    else:
        notes.append(f"{type(model).__name__} has no to_dict(): model file not written")
    files["fit"] = _write_fit(root, model, sim, pred, res)
    page.section(f"Fit on the {which} data", _fit_body(page, model, sim, pred, res, data)
                 + HINT + "".join(page.figure(f) for f in rf.time_figures(
                     sim, pred, data.times, units, which)), sid="fit")
    page.section("Residual analysis", _residual_body(page, res) + "".join(
        page.figure(f) for f in rf.residual_figures(res)), open_=False, sid="residuals")
    frd = None
    if model.ninputs:
        from ..nonparametric.frf import spa

        try:
            frd = spa(data)
        except SysidError as e:
            notes.append(f"no spa estimate on the Bode plot: {e}")
        body = ("<p>The model (blue, with its 95 % band when it has a parameter uncertainty) "
                "and the spa (Blackman-Tukey) estimate (red, with its confidence band). Phases"
                " on one branch: the model's unwrapped from (-180, 180] at the lowest "
                "frequency, the estimate's moved by multiples of 360 to the nearest.</p>")
        if getattr(model, "uncertainty", None) is None:
            body += "<p>No model band: the model has no parameter uncertainty.</p>"
        page.section("Frequency response", body + "".join(
            page.figure(f) for f in rf.bode_figures(model, frd, units)), sid="bode")
        page.section("Step response", "".join(page.figure(f) for f in rf.step_figures(
            model, units)), open_=False, sid="step")
    else:
        notes.append("time-series model (no inputs): no Bode plot or step response; the "
                     "error spectrum shows what the model leaves unexplained")
    spec = error_spectrum(model, data)
    page.section("Simulation error spectrum", "".join(
        page.figure(f) for f in rf.error_spectrum_figures(spec, units)), open_=False,
        sid="spectrum")
    page.section("Poles", _pole_section(page, model, notes), open_=False, sid="poles")
    params = _parameter_table(page, model)
    if params:
        page.section("Parameters", params, sid="parameters")
    if sel is not None:
        files["orders"] = root / "orders.csv"
        with atomic_path(files["orders"]) as tmp:
            sel.to_pandas().to_csv(tmp, index=False)
        page.section("Order choice", _order_body(page, sel, frd), sid="orders")
    links = ", ".join(f'<a href="{esc(p.name)}">{esc(p.name)}</a>' for p in files.values())
    page.section("Files and notes", f"<p>Files: {links}</p>" + "".join(
        f"<p><em>{esc(n)}</em></p>" for n in notes), open_=False, sid="files")
    return files, page


def _write_fit(root: Path, model: Any, sim: Any, pred: Any, res: Any) -> Path:
    path = root / "fit.csv"
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["output", "simulation fit %", "1-step fit %", "simulation VAF %",
                    "simulation RMSE", "whiteness p", "independence p"])
        for j, name in enumerate(model.output_names):
            w.writerow([name, f"{sim.fit.mean(0)[j]:.4f}", f"{pred.fit.mean(0)[j]:.4f}",
                        f"{sim.vaf.mean(0)[j]:.4f}", f"{sim.rmse.mean(0)[j]:.6g}",
                        f"{res.ljung_box_pvalue[j]:.4g}", f"{res.independence_pvalue[j]:.4g}"])
    return path


def _stability(model: Any) -> tuple[bool | None, str]:
    try:
        p = np.asarray(model.poles(), dtype=complex)
    except Exception:  # noqa: BLE001 - a model without poles
        return None, "no poles (this model family does not define them)"
    if not p.size:
        return True, "static model (no poles)"
    if model.dt:
        r = float(np.max(np.abs(p)))
        return r < 1, f"largest |pole| {r:.4f}"
    a = float(np.max(p.real))
    return a < 0, f"largest Re(pole) {a:.4g}"


def _summary(model: Any, facts: dict[str, Any], sel: Any,
             found: list[tuple[str, str]]) -> str:
    sim, pred, res, which = facts["sim"], facts["pred"], facts["res"], facts["which"]
    order = getattr(model, "nstates", None)
    chosen = f"{type(model).__name__}" + (f" of order {order}" if order is not None else "")
    method = (getattr(model, "info", None) or {}).get("method")
    lines = [f'<p id="chosen-model"><strong>Chosen model:</strong> {esc(chosen)}'
             + (f" ({esc(str(method))})" if method else "") + "</p>"]
    if sel is not None:
        lines.append(f"<p><strong>Why this order:</strong> {esc(sel.reason)}</p>")
    stable, how = _stability(model)
    st = "n/a" if stable is None else status(stable, "stable", "UNSTABLE")
    lines.append(f"<p><strong>Stability:</strong> {st} ({esc(how)})</p>")
    rows = []
    for j, name in enumerate(model.output_names):
        rows.append([name, f"{sim.fit.mean(0)[j]:.1f}", f"{pred.fit.mean(0)[j]:.1f}",
                     f"{res.ljung_box_pvalue[j]:.3g}",
                     status(bool(res.whiteness[j]), "white", "not white"),
                     f"{res.independence_pvalue[j]:.3g}",
                     "n/a" if res.independence[j] is None else
                     status(bool(res.independence[j]), "independent", "correlated")])
    head = ["output", f"{which} simulation fit %", "1-step fit %", "whiteness p",
            "residuals", "independence p", "residual vs input"]
    th = "".join(f"<th>{esc(h)}</th>" for h in head)
    body = "".join("<tr>" + "".join(f"<td>{c if '<span' in c else esc(c)}</td>" for c in r)
                   + "</tr>" for r in rows)
    lines.append(f'<table id="summary-fit"><thead><tr>{th}</tr></thead><tbody>{body}'
                 "</tbody></table>")
    if not all(res.whiteness) and no_noise_model(model):
        lines.append("<p>Residuals not white, as expected: the model has no noise model "
                     "(output error, or a simulation-focus fit), so its one-step errors are "
                     "its simulation errors. For a model of the noise too, fit with "
                     "focus='prediction' (sysid.ssest) or a structure with one (armax, "
                     "bj).</p>")
    elif not all(res.whiteness):
        lines.append("<p>Residuals not white: the noise model or some dynamics are missing; "
                     "try a higher order or a prediction-error refinement (sysid.ssest).</p>")
    if any(ok is not None and not ok for ok in res.independence):
        lines.append("<p>Residuals correlated with the input: dynamics are missing (or the "
                     "data are closed-loop); try a higher order or check feedback "
                     "(sysid.check_feedback).</p>")
    lines.append(f"<h3>Warnings ({len(found)})</h3>" + warning_items(found))
    return f'<section class="summary" id="summary"><h2>Summary</h2>{"".join(lines)}</section>'


def _fit_body(page: Page, model: Any, sim: Any, pred: Any, res: Any, data: IOData) -> str:
    rows = [[name, f"{sim.fit.mean(0)[j]:.2f}", f"{pred.fit.mean(0)[j]:.2f}",
             f"{sim.vaf.mean(0)[j]:.2f}", f"{sim.rmse.mean(0)[j]:.4g}",
             f"{res.ljung_box_pvalue[j]:.3g}", "yes" if res.whiteness[j] else "no"]
            for j, name in enumerate(model.output_names)]
    return (f"<p>{esc(repr(model))}</p><p>{esc(repr(data))}</p>" + page.table(
        "fit", ["output", "simulation fit %", "1-step fit %", "simulation VAF %",
                "simulation RMSE", "whiteness p", "white"], rows))


def _residual_body(page: Page, res: Any) -> str:
    rows = [[name, f"{res.ljung_box[j]:.4g}", f"{res.ljung_box_pvalue[j]:.3g}",
             "yes" if res.whiteness[j] else "no", f"{res.independence_stat[j]:.4g}",
             f"{res.independence_pvalue[j]:.3g}",
             "n/a" if res.independence[j] is None else "yes" if res.independence[j] else "no"]
            for j, name in enumerate(res.output_names)]
    return (f"<p>One-step prediction errors, lags up to {res.max_lag}, level "
            f"{100 * res.alpha:g} %; bound {res.bound:.3g}.</p>" + page.table(
                "residual-tests", ["output", "Ljung-Box Q", "p", "white", "independence S",
                                   "p", "independent of inputs"], rows))


def _sv(value: Any) -> str:
    """A candidate's singular value, or a dash where it has none (a refinement's row)."""
    v = float(value)
    return f"{v:.4g}" if np.isfinite(v) else "-"


def _order_body(page: Page, sel: Any, frd: Any) -> str:
    # the held-out fits (estimation record's blocks) when the order was cross-validated
    held = any("fit_held_out" in r for r in sel.rows)
    rows = [[r.get("model", r["method"]), r["order"], _sv(r["singular_value"]),
             f"{r['aic']:.2f}", f"{r['bic']:.2f}"]
            + ([_pct(r.get("fit_held_out", np.nan)).strip()] if held else [])
            + [_pct(r["fit_validation"]).strip(), "yes" if r["stable"] else "no"]
            for r in sel.rows if r["error"] is None]
    return (f"<p>{esc(sel.reason)}</p>" + page.table(
        "orders", ["method", "order", "singular value", "AIC", "BIC"]
        + (["held-out fit %"] if held else []) + ["validation fit %", "stable"], rows)
        + ("<p>A dash for the singular value: that row's model was not chosen from a "
           "subspace fit's singular values (a refinement, chosen as the line above "
           "says).</p>"
           if any(not np.isfinite(float(r["singular_value"])) for r in sel.rows
                  if r["error"] is None) else "")
        + page.figure(rf.singular_value_figure(sel))
        + f"<p>Stabilisation diagram: a pole is stable in frequency when a pole of the next "
          f"lower order lies within {100 * rf.FREQ_TOL:g} % of its natural frequency, and in "
          f"damping too when its damping is within {100 * rf.DAMP_TOL:g} %.</p>"
        + page.figure(rf.stabilization_figure(sel, frd)))


def _parameter_table(page: Page, model: Any) -> str:
    """The grey-box parameter table (name, value, std, fixed, active bound, 95 % interval,
    unit) when the model carries one (``info["greybox"]["parameters"]``, set by greyest)."""
    from ..models.uncertainty import form_deferred

    form_deferred(model)  # a deferred sandwich writes its std into the rows when formed
    info = getattr(model, "info", None) or {}
    rows = (info.get("greybox") or {}).get("parameters")
    if not rows:
        return ""

    def g(x: float) -> str:
        return f"{x:.6g}"
    body = [[r["name"], g(r["value"]), g(r["std"]), "fixed" if r["fixed"] else "",
             r["bound"], "" if r["fixed"] else f"[{g(r['ci95'][0])}, {g(r['ci95'][1])}]",
             r["unit"], r["description"]] for r in rows]
    return page.table("parameters", ["parameter", "value", "std", "fixed", "bound active",
                                     "95 % interval", "unit", "description"], body)


def _pole_section(page: Page, model: Any, notes: list[str]) -> str:
    """Poles with frequency and damping, their standard deviations when the model has an
    uncertainty (first order; Monte Carlo, marked *, for poles that coincide with another),
    and the map."""
    from ..models.uncertainty import UncertaintyWarning
    from .lti import damp

    has = getattr(model, "uncertainty", None) is not None
    try:
        with _warnings.catch_warnings():
            _warnings.simplefilter("ignore", UncertaintyWarning)
            t = damp(model, std=has)
    except DataError as e:
        notes.append(f"no pole table: {e}")
        return "<p>This model has no poles.</p>"

    def g(x: float, mark: str = "") -> str:
        return "n/a" if not np.isfinite(x) else f"{x:.4g}{mark}"
    header = ["pole", "|pole|", "wn [Hz]", "damping"]
    if has:
        header += ["std Re", "std Im", "std wn [Hz]", "std damping"]
    rows = []
    for k, p in enumerate(t.poles):
        row = [f"{p.real:.5g}{p.imag:+.5g}j", f"{abs(p):.4f}", g(t.wn_hz[k]), g(t.zeta[k])]
        if has and t.pole_std is not None and t.wn_hz_std is not None and \
                t.zeta_std is not None:
            mc = "*" if t.std_method is not None and t.std_method[k] == "monte-carlo" else ""
            row += [g(t.pole_std[k].real, mc), g(t.pole_std[k].imag, mc),
                    g(t.wn_hz_std[k], mc), g(t.zeta_std[k], mc)]
        rows.append(row)
    marked = has and t.std_method is not None and bool(np.any(t.std_method == "monte-carlo"))
    note = ("<p>Standard deviations: first order, from the model's parameter uncertainty ("
            f"{esc(str(model.uncertainty.method))})"
            + ("; * marks poles that coincide with another within their uncertainty, where "
               "first order does not hold: Monte Carlo from the same covariance" if marked
               else "") + ".</p>" if has else "")
    return page.table("poles", header, rows) + note + page.figure(rf.pzmap_figure(model))
