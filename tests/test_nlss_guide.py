"""docs/nlss.md runs and prints the numbers it shows."""

import re
from pathlib import Path


def test_nlss_guide(capsys):
    text = (Path(__file__).parents[1] / "docs" / "nlss.md").read_text()
    ns: dict = {}
    for i, block in enumerate(re.findall(r"```python\n(.*?)```", text, re.S)):
        exec(compile(block, f"docs/nlss.md[python block {i}]", "exec"), ns)
    out = capsys.readouterr().out
    shown = "".join(re.findall(r"Output \(this machine\):\n\n((?:    .*\n)+)", text))
    shown_lines = [ln.strip() for ln in shown.splitlines()]
    run_lines = [ln.strip() for ln in out.splitlines()]
    assert len(shown_lines) == len(run_lines), f"the guide shows:\n{shown}\nthe run prints:\n{out}"
    num = r"[-+]?\d*\.?\d+(?:e[-+]?\d+)?"
    for a, b in zip(shown_lines, run_lines):
        assert re.sub(num, "#", a) == re.sub(num, "#", b), (a, b)
        for x, y in zip(re.findall(num, a), re.findall(num, b)):
            assert abs(float(x) - float(y)) <= max(2e-3, 0.1 * abs(float(x))), (a, b)
    # what the guide claims in words
    assert ns["pn"].info["fit"]["cost"][-1] < ns["pn"].info["fit"]["cost"][0]
