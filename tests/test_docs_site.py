"""The API reference site (MkDocs + mkdocstrings, ``make docs``): every public name of
``sysid`` has an entry that points at the object, and the site's configuration builds with
warnings as errors. After ``make docs`` the built pages are checked too."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

import sysid

ROOT = Path(__file__).resolve().parents[1]


def _hook():
    spec = importlib.util.spec_from_file_location("api_pages", ROOT / "docs/hooks/api_pages.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_every_public_name_has_an_api_entry():
    hook = _hook()
    pages = hook.api_pages()
    entries = {name: path for items in pages.values() for name, path in items}
    assert sorted(entries) == sorted(sysid.__all__)
    for name, path in entries.items():
        if name == "__version__":
            continue
        assert hook.resolve(path) is getattr(sysid, name), (name, path)
    text = "".join(hook.page_text(p, e) for p, e in pages.items())
    for name in entries:
        assert f'heading: "sysid.{name}"' in text or name == "__version__", name


def test_site_configuration():
    yaml = (ROOT / "mkdocs.yml").read_text()
    assert "strict: true" in yaml and "docstring_style: numpy" in yaml
    assert "docs/hooks/api_pages.py" in yaml
    for guide in sorted((ROOT / "docs").glob("*.md")):
        assert f": {guide.name}" in yaml, f"{guide.name} is not in the mkdocs.yml nav"
    assert "docs:" in (ROOT / "Makefile").read_text()


def test_built_site_has_every_name():
    site = ROOT / "site" / "api"
    if not site.is_dir():
        pytest.skip("the site is not built here (make docs builds it into site/)")
    if (site / "index.html").stat().st_mtime < Path(sysid.__file__).stat().st_mtime:
        pytest.skip("site/ is older than sysid/__init__.py: run make docs again")
    html = "".join(p.read_text(encoding="utf-8") for p in site.rglob("index.html"))
    for items in _hook().api_pages().values():
        for name, path in items:
            if name != "__version__":
                assert f'id="{path}"' in html, (name, path)
