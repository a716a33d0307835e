"""The README's Python examples run as written."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
OVERVIEW = README.parent / "docs" / "overview.md"  # what the README held beyond one screen
OVERVIEW_BLOCKS = re.findall(r"```python\n(.*?)```", OVERVIEW.read_text(), flags=re.S)


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_readme_example_runs(index, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(BLOCKS[index], f"README.md[python block {index}]", "exec"), namespace)


def test_readme_has_examples_and_quickstart():
    text = README.read_text()
    assert BLOCKS, "README has no python examples"
    assert "make demo" in text and "make test" in text


@pytest.mark.parametrize("index", range(len(OVERVIEW_BLOCKS)))
def test_overview_example_runs(index, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(OVERVIEW_BLOCKS[index], f"docs/overview.md[python block {index}]", "exec"),
         namespace)


def test_readme_is_short_and_has_one_benchmark_table():
    text = README.read_text()
    assert len(text.splitlines()) < 180
    assert text.count("| figure | sysid |") == 1 and "make bench-full" in text
