"""Notebook displays: ``_repr_html_`` for models, results, tables and records.

Jupyter (and VS Code, JupyterLab, nbconvert) shows an object's ``_repr_html_()`` instead of
its ``repr``. Everything here is plain HTML with inline SVG: no script, no network, no
matplotlib. Models get a facts table and their poles (:func:`model_html`, used by
:class:`~sysid.ModelMixin` and the classes outside it); results with ``to_pandas()`` get their
table (:class:`HTMLResult`); records a channel table with a small plot per channel
(:func:`iodata_html`).

Examples
--------
>>> import sysid
>>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1)
>>> html = m._repr_html_()
>>> html.startswith('<div class="sysid-repr">') and "0.5" in html
True
"""

from __future__ import annotations

import html as _html
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["table", "svg_lines", "model_html", "result_html", "iodata_html", "frd_html",
           "HTMLResult", "fmt", "greybox_html", "modulus", "pvalue"]

_STYLE = ("<style>.sysid-repr table{border-collapse:collapse;margin:4px 0}"
          ".sysid-repr td,.sysid-repr th{border:1px solid #ccc;padding:2px 6px;"
          "text-align:right}.sysid-repr th{background:#f3f3f3}"
          ".sysid-repr td:first-child{text-align:left}</style>")
MAX_ROWS = 30  # rows shown before a table is cut (the count of the rest is said)


def esc(x: Any) -> str:
    """HTML-escaped ``str(x)``."""
    return _html.escape(str(x))


def fmt(x: Any, digits: int = 4) -> str:
    """A cell: numbers with ``digits`` significant figures (infinities as ``inf``, as the
    text summaries print them; NaN, a value that does not exist, as ``n/a``), complex as
    ``a+bj``, else str.

    Examples
    --------
    >>> from sysid._display import fmt
    >>> fmt(1.23456), fmt(float("inf")), fmt(-float("inf")), fmt(float("nan"))
    ('1.235', 'inf', '-inf', 'n/a')
    """
    if isinstance(x, (bool, np.bool_)):
        return "yes" if x else "no"
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    if isinstance(x, (complex, np.complexfloating)):
        return f"{x.real:.{digits}g}{x.imag:+.{digits}g}j"
    if isinstance(x, (float, np.floating)):
        return "n/a" if np.isnan(x) else f"{float(x):.{digits}g}"
    if x is None:
        return ""
    return str(x)


def modulus(rho: float) -> str:
    """A pole modulus for a stability message: 4 significant digits, more when those would
    show a modulus other than 1 as ``1`` (an integrator just outside the unit circle).

    Examples
    --------
    >>> from sysid._display import modulus
    >>> modulus(1.2207031), modulus(1.0000075), modulus(1.0)
    ('1.221', '1.00001', '1')
    """
    for k in range(4, 18):
        text = f"{rho:.{k}g}"
        if rho == 1.0 or float(text) != 1.0:
            return text
    return f"{rho:.17g}"


def unstable_modes(poles: Any, dt: float | None, most: int = 3) -> str:
    """The unstable modes of discrete-time ``poles`` (modulus at least 1) in words, largest
    first, a complex pair named once with its frequency (in Hz with the sample time ``dt``,
    else in cycles per sample); at most ``most`` modes, then how many more.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid._display import unstable_modes
    >>> p = [1.0048, 1.056 * np.exp(0.5j * np.pi), 1.056 * np.exp(-0.5j * np.pi), 0.9]
    >>> unstable_modes(p, 0.05)
    'a growing oscillation at 5 Hz (pole pair of modulus 1.056), a real pole at 1.005'
    """
    p = np.asarray(poles, dtype=complex).ravel()
    p = p[np.isfinite(p) & (np.abs(p) >= 1.0)]
    p = p[p.imag >= 0]  # a pair once, by its upper half
    p = p[np.argsort(-np.abs(p), kind="stable")]
    words = []
    for z in p[:most]:
        if z.imag == 0.0:
            words.append(f"a real pole at {modulus(z.real) if z.real > 0 else f'{z.real:.4g}'}"
                         + (" (an oscillation at the Nyquist frequency)" if z.real < 0 else ""))
            continue
        cycles = float(np.angle(z)) / (2 * np.pi)
        freq = f"{cycles / dt:.4g} Hz" if dt else f"{cycles:.4g} cycles per sample"
        words.append(f"a growing oscillation at {freq} (pole pair of modulus "
                     f"{modulus(abs(z))})")
    if p.size > most:
        words.append(f"{p.size - most} more")
    return ", ".join(words)


def pvalue(p: float, digits: int = 2) -> str:
    """A p-value for a message, ``p = ...`` with ``digits`` significant digits; one below
    ``1e-300`` (a tail probability that underflowed, computed as 0) as ``p < 1e-300``,
    never ``p = 0``, which no test gives.

    Examples
    --------
    >>> from sysid._display import pvalue
    >>> pvalue(1.5e-24), pvalue(0.0), pvalue(0.31, 3)
    ('p = 1.5e-24', 'p < 1e-300', 'p = 0.31')
    """
    p = float(p)
    return "p < 1e-300" if p < 1e-300 else f"p = {p:.{digits}g}"


def table(header: Sequence[str], rows: Sequence[Sequence[Any]], *, tid: str | None = None,
          max_rows: int | None = MAX_ROWS, caption: str | None = None) -> str:
    """An HTML table; cells formatted by :func:`fmt`, rows beyond ``max_rows`` summarised."""
    th = "".join(f"<th>{esc(h)}</th>" for h in header)
    shown = rows if max_rows is None else rows[:max_rows]
    body = "".join("<tr>" + "".join(f"<td>{esc(fmt(c))}</td>" for c in r) + "</tr>"
                   for r in shown)
    more = len(rows) - len(shown)
    if more:
        body += (f'<tr><td colspan="{len(header)}">... {more} more row{"s" * (more != 1)}'
                 "</td></tr>")
    cap = f"<caption>{esc(caption)}</caption>" if caption else ""
    ident = f' id="{esc(tid)}"' if tid else ""
    return f"<table{ident}>{cap}<thead><tr>{th}</tr></thead><tbody>{body}</tbody></table>"


def _decimate(t: np.ndarray, y: np.ndarray, width: int) -> tuple[np.ndarray, np.ndarray]:
    """At most ``2 width`` points keeping each column's min and max (spikes stay visible)."""
    n = y.size
    if n <= 2 * width:
        return t, y
    edges = np.linspace(0, n, width + 1).astype(int)
    lo = np.minimum.reduceat(y, edges[:-1])
    hi = np.maximum.reduceat(y, edges[:-1])
    tt = np.repeat(t[edges[:-1]], 2)
    yy = np.column_stack([lo, hi]).ravel()
    return tt, yy


def svg_lines(t: Any, ys: Sequence[Any], *, labels: Sequence[str] | None = None,
              title: str = "", width: int = 360, height: int = 90,
              log_x: bool = False) -> str:
    """A small inline SVG line plot of the series ``ys`` against ``t`` (min/max decimated).

    Examples
    --------
    >>> from sysid._display import svg_lines
    >>> svg_lines([0, 1, 2], [[0.0, 1.0, 0.5]], title="y").startswith("<svg")
    True
    """
    colors = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd")
    t = np.asarray(t, dtype=float)
    tx = np.log10(t) if log_x else t
    pad_l, pad_b, pad_t = 4, 4, 14 if title else 4
    w, h = width - pad_l - 4, height - pad_b - pad_t
    series = [np.asarray(y, dtype=float) for y in ys]
    finite = [y[np.isfinite(y)] for y in series]
    allv = np.concatenate(finite) if any(v.size for v in finite) else np.zeros(1)
    lo, hi = float(allv.min()), float(allv.max())
    if hi <= lo:
        lo, hi = lo - 1.0, hi + 1.0
    x0, x1 = float(tx[0]), float(tx[-1]) if tx[-1] > tx[0] else float(tx[0]) + 1.0
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
             f'viewBox="0 0 {width} {height}" role="img">']
    if title:
        parts.append(f'<text x="{pad_l}" y="11" font-size="10" font-family="sans-serif">'
                     f"{esc(title)} [{fmt(lo, 3)} .. {fmt(hi, 3)}]</text>")
    parts.append(f'<rect x="{pad_l}" y="{pad_t}" width="{w}" height="{h}" fill="none" '
                 'stroke="#ddd"/>')
    for k, y in enumerate(series):
        td, yd = _decimate(tx, y, w)
        ok = np.isfinite(yd)
        px = pad_l + (td[ok] - x0) / (x1 - x0) * w
        py = pad_t + (hi - yd[ok]) / (hi - lo) * h
        pts = " ".join(f"{a:.1f},{b:.1f}" for a, b in zip(px, py))
        name = labels[k] if labels and k < len(labels) else ""
        parts.append(f'<polyline fill="none" stroke="{colors[k % len(colors)]}" '
                     f'stroke-width="1" points="{pts}"><title>{esc(name)}</title></polyline>')
    parts.append("</svg>")
    return "".join(parts)


def _wrap(title: str, body: str) -> str:
    return f'<div class="sysid-repr">{_STYLE}<p><strong>{esc(title)}</strong></p>{body}</div>'


# -- models ---------------------------------------------------------------------------------
def _poles(model: Any) -> np.ndarray | None:
    try:
        p = np.asarray(model.poles(), dtype=complex).ravel()
    except Exception:  # noqa: BLE001 - a model without poles shows none
        return None
    return p


def _stable(p: np.ndarray, dt: float) -> bool:
    return bool(np.all(np.abs(p) < 1.0) if dt > 0 else np.all(p.real < 0.0))


def model_facts(model: Any) -> list[list[Any]]:
    """``[[fact, value], ...]`` of any model: family, sampling, channels, order, method."""
    dt = float(getattr(model, "dt", 0.0) or 0.0)
    rows: list[list[Any]] = [["family", type(model).__name__],
                             ["time", f"discrete, dt = {dt:g} s" if dt > 0 else "continuous"]]
    rows.append(["inputs", ", ".join(map(str, getattr(model, "input_names", None) or []))
                 or str(getattr(model, "ninputs", "none"))])
    rows.append(["outputs", ", ".join(map(str, getattr(model, "output_names", None) or []))
                 or str(getattr(model, "noutputs", ""))])
    if getattr(model, "nstates", None) is not None:
        rows.append(["states", int(model.nstates)])
    try:
        rows.append(["free parameters", int(model.n_parameters)])
    except Exception:  # noqa: BLE001, S110 - optional fact
        pass
    info = getattr(model, "info", None) or {}
    if isinstance(info, dict) and info.get("method"):
        rows.append(["method", info["method"]])
    p = _poles(model)
    if p is not None and p.size:
        radius = np.max(np.abs(p)) if dt > 0 else np.max(p.real)
        what = "largest |pole|" if dt > 0 else "largest Re(pole)"
        rows.append(["stable", f"{'yes' if _stable(p, dt) else 'NO'} ({what} {radius:.4g})"])
    if getattr(model, "uncertainty", None) is not None:
        rows.append(["uncertainty", getattr(model.uncertainty, "method", "yes")])
    return rows


def pole_rows(p: np.ndarray, dt: float) -> list[list[Any]]:
    """``[pole, |pole|, natural frequency Hz, damping]`` per pole (discrete: via log z / dt),
    by the rule of :func:`sysid.damp` (:mod:`sysid.models.pole_map`: a pole at ``z = 0``
    is infinitely fast, damping 1).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid._display import pole_rows
    >>> pole_rows(np.array([0.0 + 0.0j]), 0.1)
    [[0j, 0.0, inf, 1.0]]
    """
    from .models.pole_map import continuous_equivalent, damping_ratio

    s = continuous_equivalent(p, dt if dt > 0 else None)
    wn, zeta = np.abs(s), damping_ratio(s)
    return [[complex(p[k]), float(abs(p[k])), float(wn[k] / (2 * np.pi)), float(zeta[k])]
            for k in range(p.size)]


def model_html(model: Any) -> str:
    """The notebook display of any model (facts, poles, grey-box parameters)."""
    body = table(["", ""], model_facts(model))
    p = _poles(model)
    dt = float(getattr(model, "dt", 0.0) or 0.0)
    if p is not None and p.size:
        body += table(["pole", "|pole|", "wn [Hz]", "damping"], pole_rows(p, dt),
                      caption="poles", max_rows=12)
    return _wrap(repr(model), body)


def greybox_html(structure: Any) -> str:
    """A grey-box structure: facts, its parameters (value, fixed, bounds, unit), and the
    poles at the current values."""
    body = table(["", ""], model_facts(structure))
    rows = [[n, pr.value, pr.fixed, pr.bounds[0], pr.bounds[1], pr.unit, pr.description]
            for n, pr in structure.params.items()]
    body += table(["parameter", "value", "fixed", "lower", "upper", "unit", "description"],
                  rows, tid="parameters", caption="parameters", max_rows=None)
    try:
        m = structure.model()
        p = np.asarray(m.poles(), dtype=complex)
        body += table(["pole", "|pole|", "wn [Hz]", "damping"], pole_rows(p, float(m.dt)),
                      caption="poles at these values", max_rows=12)
    except Exception:  # noqa: BLE001, S110 - a structure that needs dt= shows no poles
        pass
    return _wrap(repr(structure), body)


# -- results -------------------------------------------------------------------------------
def frame_table(df: Any, *, tid: str | None = None, max_rows: int | None = MAX_ROWS) -> str:
    """A pandas DataFrame (or Series) as a :func:`table`, the index as first column."""
    if hasattr(df, "to_frame") and not hasattr(df, "columns"):
        df = df.to_frame()
    names = [n for n in getattr(df.index, "names", [None]) if n is not None]
    header = [str(c) for c in df.columns]
    rows = [list(vals) for vals in df.itertuples(index=False, name=None)]
    if names or type(df.index).__name__ != "RangeIndex":  # a meaningful index: first column
        header = [", ".join(map(str, names))] + header
        rows = [[idx if not isinstance(idx, tuple) else ", ".join(map(str, idx)), *r]
                for idx, r in zip(df.index, rows)]
    return table(header, rows, tid=tid, max_rows=max_rows)


def result_html(obj: Any, title: str | None = None) -> str:
    """A result's ``repr`` line (first line) over its ``to_pandas()`` table."""
    text = repr(obj)
    first, _, rest = text.partition("\n")
    try:
        if hasattr(obj, "to_pandas"):
            body = frame_table(obj.to_pandas())
        else:  # a flat result: {name: value}
            d = obj.as_dict()
            body = table(list(d), [list(d.values())])
    except ImportError:  # no pandas: the text form
        body = f"<pre>{esc(rest)}</pre>"
    return _wrap(title or first, body)


class HTMLResult:
    """Mixin: ``_repr_html_`` from the class's ``repr`` and ``to_pandas()``; ``str`` (what
    ``print`` shows) is the class's text ``summary()`` where it has one, the ``repr`` else,
    so that ``print(sysid.advice(data))`` reads as MATLAB's display does, not one line."""

    def _repr_html_(self) -> str:
        return result_html(self)

    def __str__(self) -> str:
        summary = getattr(self, "summary", None)
        text = summary() if callable(summary) else None
        return text if isinstance(text, str) else repr(self)


# -- records -------------------------------------------------------------------------------
def iodata_html(data: Any) -> str:
    """A record: per-channel statistics and a small plot of each channel (first experiment)."""
    s = data.summary()
    header = ["channel", "kind", "unit", "mean", "std", "min", "max", "plot"]
    u, y = data.experiments[0]
    t = data.times[0] if hasattr(data, "times") else np.arange(y.shape[0]) * data.dt
    rows = []
    for r in s.rows:
        col = (u if r["kind"] == "input" else y)[:, (data.input_names if r["kind"] == "input"
                                                     else data.output_names).index(r["channel"])]
        rows.append([r["channel"], r["kind"], r["unit"], r["mean"], r["std"], r["min"],
                     r["max"], col])
    th = "".join(f"<th>{esc(h)}</th>" for h in header)
    body = "".join(
        "<tr>" + "".join(f"<td>{esc(fmt(c))}</td>" for c in r[:-1])
        + f"<td>{svg_lines(t, [r[-1]], width=240, height=40)}</td></tr>" for r in rows)
    extra = (f"<p>experiment lengths: {esc(data.lengths)} (plots: the first)</p>"
             if data.n_experiments > 1 else "")
    return _wrap(repr(data), f"<table><thead><tr>{th}</tr></thead><tbody>{body}</tbody>"
                             f"</table>{extra}")


def frd_html(frd: Any) -> str:
    """A frequency response: its range and a magnitude plot per channel pair (dB, log f)."""
    w = np.asarray(frd.frequencies, dtype=float)
    G = np.asarray(frd.response)
    facts = [["frequencies", f"{w.size} from {w[0]:.4g} to {w[-1]:.4g} {frd.units or 'rad/s'}"],
             ["outputs", ", ".join(frd.output_names)], ["inputs", ", ".join(frd.input_names)],
             ["method", frd.method or ""]]
    plots = ""
    ok = w > 0
    if ok.sum() >= 2:
        with np.errstate(divide="ignore"):
            for i, on in enumerate(frd.output_names[:3]):
                for j, inn in enumerate(frd.input_names[:3]):
                    mag = 20 * np.log10(np.abs(G[ok, i, j]))
                    plots += svg_lines(w[ok], [mag], log_x=True, width=260, height=90,
                                       title=f"{inn} -> {on} |G| dB")
    return _wrap(repr(frd), table(["", ""], facts) + plots)
