"""MkDocs hook: the API reference pages, generated from ``sysid.__all__`` at build time.

Every public name gets an entry on the page of the subpackage that defines it
(``api/<subpackage>.md``), rendered by mkdocstrings from its numpydoc docstring; a name added
to ``sysid.__all__`` is documented without editing any page. ``tests/test_docs_site.py``
checks that every name has an entry and that the entry points at the object.
"""

from __future__ import annotations

import importlib
from collections import defaultdict
from typing import Any

TITLES = {
    "data": "Data", "models": "Models", "estimate": "Estimators", "analysis": "Analysis",
    "validation": "Validation", "subspace": "Subspace methods", "pem": "Prediction error",
    "polynomial": "Polynomial models", "greybox": "Grey-box models",
    "nonlinear": "Nonlinear models", "nonparametric": "Non-parametric estimates",
    "realization": "Realisation", "identify": "Automatic identification",
    "plot": "Plots", "errors": "Errors", "core": "Core", "batch": "Many records at once",
    "timeseries": "Time series", "tf": "Transfer functions", "process": "Process models",
    "oma": "Operational modal analysis", "recursive": "Recursive estimators",
    "nlss": "Nonlinear state space",
}


def target(name: str) -> tuple[str, str]:
    """``(group, dotted path of the defining object)`` of a public name of ``sysid``."""
    import sysid

    if name == "__version__":
        return "core", "sysid.__version__"
    obj = getattr(sysid, name)
    if name == "datasets":
        return "data", obj.__name__
    module = getattr(obj, "__module__", None) or "sysid"
    if module.startswith("sysid._sysid") or module == "sysid":
        module = "sysid"
    qual = getattr(obj, "__qualname__", name)
    path = f"{module}.{name if '<locals>' in qual else qual}"
    parts = module.split(".")
    group = parts[1] if len(parts) > 1 else "core"
    if group.startswith("_"):
        group = "core"
    return group, path


def api_pages() -> dict[str, list[tuple[str, str]]]:
    """``{page path: [(public name, dotted path), ...]}`` covering ``sysid.__all__``."""
    import sysid

    pages: dict[str, list[tuple[str, str]]] = defaultdict(list)
    for name in sorted(sysid.__all__, key=str.lower):
        group, path = target(name)
        pages[f"api/{group}.md"].append((name, path))
    return dict(pages)


def page_text(page: str, entries: list[tuple[str, str]]) -> str:
    group = page.split("/")[-1][:-3]
    lines = [f"# {TITLES.get(group, group.capitalize())}", "",
             f"Public names of `sysid` defined in `sysid.{group}`." if group != "core" else
             "Public names of `sysid` defined at its top level.", ""]
    for name, path in entries:
        if path == "sysid.__version__":
            import sysid

            lines += ["## `__version__`", "", f"The version string (`{sysid.__version__}`).", ""]
            continue
        lines += [f"::: {path}", "    options:", f"      heading: \"sysid.{name}\""]
        if not _static(path):  # made at run time (a factory): read by inspection
            lines.append("      force_inspection: true")
        lines.append("")
    return "\n".join(lines)


def index_text(pages: dict[str, list[tuple[str, str]]]) -> str:
    lines = ["# API reference", "", "Every public name of `sysid` (`sysid.__all__`), by the "
             "subpackage that defines it.", ""]
    for page, entries in sorted(pages.items()):
        group = page.split("/")[-1][:-3]
        lines.append(f"- [{TITLES.get(group, group.capitalize())}]({page.split('/')[-1]}): "
                     + ", ".join(f"`{n}`" for n, _ in entries))
    return "\n".join(lines) + "\n"


def on_config(config: Any) -> Any:
    """The API pages in the navigation, after the guides."""
    pages = api_pages()
    nav = config.get("nav") or []
    nav.append({"API reference": ["api/index.md"] + [
        {TITLES.get(p.split("/")[-1][:-3], p.split("/")[-1][:-3].capitalize()): p}
        for p in sorted(pages)]})
    config["nav"] = nav
    return config


def on_files(files: Any, config: Any) -> Any:
    from mkdocs.structure.files import File

    pages = api_pages()
    files.append(File.generated(config, "api/index.md", content=index_text(pages)))
    for page, entries in pages.items():
        files.append(File.generated(config, page, content=page_text(page, entries)))
    return files


def _static(path: str) -> bool:
    """Whether the object is a class, function or module written in the source."""
    import inspect

    obj = resolve(path)
    if inspect.ismodule(obj):
        return True
    qual = getattr(obj, "__qualname__", "")
    return "<locals>" not in qual and (inspect.isclass(obj) or inspect.isfunction(obj))


def resolve(path: str) -> Any:
    """The object at a dotted path (module, then attributes)."""
    parts = path.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        for p in parts[k:]:
            obj = getattr(obj, p)
        return obj
    raise ImportError(path)
