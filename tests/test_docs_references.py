"""Every ``sysid.<name>`` the guides, the README and the examples write resolves: a renamed or
moved function is caught here, not by a reader (``docs/pem.md`` wrote
``sysid.plot.plot_bode``, which raised ``AttributeError``, and ``docs/performance.md``
``sysid.streaming.CompressionFallbackWarning``, a module that does not exist)."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import sysid

ROOT = Path(__file__).resolve().parents[1]


def _resolves(chain: list[str]) -> bool:
    obj, path = sysid, "sysid"
    for name in chain:
        try:
            obj = getattr(obj, name)
        except AttributeError:
            try:  # a submodule not imported yet
                obj = importlib.import_module(f"{path}.{name}")
            except ImportError:
                return False
        path = f"{path}.{name}"
    return True


def test_every_sysid_name_the_docs_write_resolves():
    files = [*sorted((ROOT / "docs").glob("*.md")), ROOT / "README.md",
             *sorted((ROOT / "examples").glob("*.py"))]
    assert len(files) > 10
    bad = set()
    for f in files:
        for m in re.finditer(r"(?<![\w.])sysid((?:\.[A-Za-z_]\w*)+)", f.read_text()):
            if not _resolves(m.group(1).split(".")[1:]):
                bad.add(f"{f.relative_to(ROOT)}: sysid{m.group(1)}")
    assert not bad, sorted(bad)
