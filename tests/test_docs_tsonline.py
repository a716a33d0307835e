"""The guides of issue 27's time series, modal analysis and online estimators run and print
the numbers they show."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

GUIDES = ["online.md", "timeseries.md", "oma.md"]


@pytest.mark.parametrize("guide", GUIDES)
def test_guide_runs_and_prints_what_it_shows(guide, capsys):
    text = (Path(__file__).parents[1] / "docs" / guide).read_text()
    ns: dict = {}
    for i, block in enumerate(re.findall(r"```python\n(.*?)```", text, re.S)):
        exec(compile(block, f"docs/{guide}[python block {i}]", "exec"), ns)
    out = capsys.readouterr().out
    shown = "".join(re.findall(r"Output \(this machine\):\n\n((?:    .*\n)+)", text))
    shown_lines = [ln.strip() for ln in shown.splitlines()]
    run_lines = [ln.strip() for ln in out.splitlines()]
    assert len(shown_lines) == len(run_lines), f"the guide shows:\n{shown}\nthe run prints:\n{out}"
    num = r"[-+]?\d*\.?\d+(?:e[-+]?\d+)?"
    for a, b in zip(shown_lines, run_lines):  # same words; numbers within rounding
        assert re.sub(num, "#", a) == re.sub(num, "#", b), (a, b)
        for x, y in zip(re.findall(num, a), re.findall(num, b)):
            assert abs(float(x) - float(y)) <= max(1e-3, 0.02 * abs(float(x))), (a, b)
