"""Running the guides in docs/ as tests: their ```python blocks in order, and what they print
against the "Output (this machine):" blocks they show."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

DOCS = Path(__file__).resolve().parents[1] / "docs"
NUMBER = r"[-+]?\d*\.?\d+(?:e[-+]?\d+)?"


def guide_text(name: str, section: str | None = None) -> str:
    """The text of ``docs/<name>``, or of its ``## <section>`` only."""
    text = (DOCS / name).read_text()
    if section is not None:
        text = text.split(f"## {section}")[1].split("\n## ")[0]
    return text


def python_blocks(text: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", text, re.S)


def run_blocks(text: str, label: str, ns: dict[str, Any] | None = None) -> dict[str, Any]:
    """Executes the python blocks of ``text`` in order in one namespace (the blocks build on
    each other; ``ns`` seeds it) and returns it; ``label`` names the file in tracebacks."""
    ns = {} if ns is None else ns
    for i, block in enumerate(python_blocks(text)):
        exec(compile(block, f"{label}[python block {i}]", "exec"), ns)
    return ns


def run_guide(name: str, **kw: Any) -> dict[str, Any]:
    """:func:`run_blocks` on ``docs/<name>``."""
    return run_blocks(guide_text(name), f"docs/{name}", **kw)


def assert_prints_shown(text: str, out: str, atol: float, rtol: float = 0.02) -> None:
    """``out`` prints the lines ``text`` shows under "Output (this machine):": the same words,
    numbers within ``max(atol, rtol * |shown|)``."""
    shown = "".join(re.findall(r"Output \(this machine\):\n\n((?:    .*\n)+)", text))
    shown_lines = [ln.strip() for ln in shown.splitlines()]
    run_lines = [ln.strip() for ln in out.splitlines()]
    assert len(shown_lines) == len(run_lines), f"the guide shows:\n{shown}\nthe run prints:\n{out}"
    for a, b in zip(shown_lines, run_lines):
        assert re.sub(NUMBER, "#", a) == re.sub(NUMBER, "#", b), (a, b)
        for x, y in zip(re.findall(NUMBER, a), re.findall(NUMBER, b)):
            assert abs(float(x) - float(y)) <= max(atol, rtol * abs(float(x))), (a, b)
