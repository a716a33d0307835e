"""Every docstring example in the package runs and prints what it shows."""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest
from _guides import assert_prints_shown, guide_text, run_guide

import sysid


def _modules():
    names = ["sysid"]
    for info in pkgutil.walk_packages(sysid.__path__, "sysid."):
        if info.name.endswith("__main__"):
            continue
        names.append(info.name)
    return names


@pytest.mark.parametrize("name", _modules())
def test_docstring_examples(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS)
    assert result.failed == 0, f"{result.failed} docstring example(s) failed in {name}"


def test_polynomial_guide(capsys):
    """docs/polynomial.md runs, and prints the numbers the guide shows."""
    ns = run_guide("polynomial.md")
    assert_prints_shown(guide_text("polynomial.md"), capsys.readouterr().out, atol=0.15)
    assert ns["oe"].info["stop"][0] in ("cost tolerance", "step tolerance", "gradient tolerance")


# issue 27 (branch tfproc): the transfer-function and process-model guide
def test_tf_process_guide(capsys):
    """docs/tf_process.md runs, and prints the numbers the guide shows."""
    run_guide("tf_process.md")
    assert_prints_shown(guide_text("tf_process.md"), capsys.readouterr().out, atol=1e-3)
