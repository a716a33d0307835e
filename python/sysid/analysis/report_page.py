"""The page of :func:`sysid.report`: summary, foldable sections, tables and inline charts.

One self-contained HTML file: the style sheet, the chart script (``report_chart.js``, a few
kB) and the figures' data are inline, so the page opens without a network or a server.
"""

from __future__ import annotations

import html
import json
from pathlib import Path
from typing import Any

from .._display import fmt
from .._display import table as _table

__all__ = ["Page", "ADVICE", "advice", "relevant", "reissue"]

esc = html.escape

#: What to do about each warning category (the message itself usually names the option).
ADVICE = {
    "ExcitationWarning": "The input may not excite every mode of this order: lower the order, "
                         "check the input with sysid.check_excitation, or record with a richer "
                         "input (sysid.prbs, sysid.multisine).",
    "FeedbackWarning": "The data look closed-loop: open-loop subspace estimates are biased; "
                       "use sysid.pbsid or sysid.ssarx, or sysid.ssest(..., "
                       "method='pbsid').",
    "UncertaintyWarning": "Some standard deviations are not reliable to first order: use the "
                          "bootstrap (--uncertainty bootstrap) or the Monte Carlo option.",
    "StabilityWarning": "The model is unstable: use focus='simulation' or "
                        "enforce_stability=True, or a lower order.",
    "CompressionFallbackWarning": "The fast compressor lost accuracy and the exact one was "
                                  "used: the result is exact; scale the channels if it was "
                                  "slow.",
    "IdentifiabilityWarning": "Some parameters are not determined by the data: fix them "
                              "(sysid.fixed) or add excitation.",
    "ConvergenceWarning": "The search stopped short: raise max_iter or start from a better "
                          "initial model.",
}


def advice(category: str, message: str) -> str:
    """What the reader should do about a warning of this category."""
    return ADVICE.get(category, "Read the message: it names the setting to change.")


_CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;max-width:1100px;margin:auto;
padding:0 16px 40px;color:#222}
h1{font-size:1.5em;margin-bottom:.2em}
summary{font-size:1.15em;font-weight:600;cursor:pointer;padding:6px 0}
details{border-top:1px solid #ddd;padding:2px 0}
table{border-collapse:collapse;margin:6px 0 12px}
td,th{border:1px solid #ccc;padding:3px 8px;text-align:right;font-size:.92em}
th{background:#f3f3f3}td:first-child{text-align:left}
.summary{background:#f7f9fc;border:1px solid #d0d7e2;border-radius:6px;padding:10px 16px}
.ok{color:#1a7f37;font-weight:600}.bad{color:#c62828;font-weight:600}
.warn{background:#fff8e1;border-left:4px solid #f9a825;padding:6px 10px;margin:6px 0}
.sysid-chart{margin:4px 0 14px}
.sysid-svg text{font:11px sans-serif;fill:#333}.sysid-svg text.t{font-weight:600;font-size:12px}
.sysid-svg text.a{font-size:11.5px}.sysid-svg .g{stroke:#eee}
.sysid-svg .f{fill:none;stroke:#999}.sysid-svg .zoom{fill:#1f77b4;fill-opacity:.12;
stroke:#1f77b4}.sysid-svg text.tip{fill:#000;font-size:11px}
.sysid-svg text.lg,.sysid-svg text.tip{font-size:10.5px;paint-order:stroke;stroke:#fff;
stroke-width:3px;stroke-linejoin:round}.hint{color:#666;font-size:.88em}
"""


class Page:
    """Collects sections and figures; :meth:`html` writes the page."""

    def __init__(self, title: str) -> None:
        self.title = title
        self.parts: list[str] = []
        self.n_figures = 0
        self.facts: dict[str, Any] = {}  # what the summary needs from the sections

    def add(self, raw: str) -> None:
        self.parts.append(raw)

    def table(self, tid: str, header: list[str], rows: list[list[Any]]) -> str:
        return _table(header, rows, tid=tid, max_rows=None)

    def figure(self, spec: dict[str, Any] | None) -> str:
        """A chart's ``div`` and its data (``</`` escaped so the JSON cannot end the script)."""
        if spec is None:
            return ""
        self.n_figures += 1
        fid = f"fig{self.n_figures}"
        data = json.dumps(spec, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
        return (f'<div class="sysid-chart" data-spec="{fid}"></div>'
                f'<script type="application/json" id="{fid}">{data}</script>')

    def section(self, title: str, body: str, *, open_: bool = True, sid: str = "") -> None:
        ident = f' id="{esc(sid)}"' if sid else ""
        self.parts.append(f"<details{ident}{' open' if open_ else ''}><summary>{esc(title)}"
                          f"</summary>{body}</details>")

    def html(self) -> str:
        script = (Path(__file__).with_name("report_chart.js")).read_text(encoding="utf-8")
        return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
                f'<meta name="viewport" content="width=device-width,initial-scale=1">'
                f"<title>{esc(self.title)}</title><style>{_CSS}</style></head><body>"
                + "\n".join(self.parts) + f"\n<script>{script}</script></body></html>\n")


def status(ok: bool, good: str, bad: str) -> str:
    return f'<span class="{"ok" if ok else "bad"}">{esc(good if ok else bad)}</span>'


def warning_items(found: list[tuple[str, str]]) -> str:
    """The warnings of the run, each with what to do."""
    if not found:
        return "<p>No warnings were raised.</p>"
    return "".join(f'<div class="warn"><strong>{esc(c)}</strong>: {esc(m)}<br><em>What to do:'
                   f"</em> {esc(advice(c, m))}</div>" for c, m in found)


def fmt_row(row: list[Any]) -> list[str]:
    return [fmt(c) for c in row]


def relevant(caught: list[Any]) -> list[Any]:
    """Recorded warnings without library deprecations (not the reader's business)."""
    return [w for w in caught
            if not issubclass(w.category, (DeprecationWarning, PendingDeprecationWarning))]


def reissue(caught: list[Any]) -> list[tuple[str, str]]:
    """Issue recorded warnings again (the caller sees them); ``(category, message)`` each."""
    import warnings

    kept = relevant(caught)
    for w in kept:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return [(w.category.__name__, str(w.message)) for w in kept]
