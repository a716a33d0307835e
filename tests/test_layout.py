"""The package's shape: imports run one way (no cycle), modules stay readable, and the
top-level namespace shows only public names.

The import graph is read from the source with :mod:`ast` (nothing is imported): an edge
``a -> b`` for every ``import``/``from ... import`` in module ``a`` that names module ``b`` of
the package, at module level or inside a function; a second graph adds the imports under
``if TYPE_CHECKING:`` (annotations only, never executed, but a cycle there is still two
modules that cannot be read apart). Importing ``sysid.x.y`` also runs the package
``__init__`` files above it; those implicit edges are left out, as Python initialises parent
packages first.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import sysid

PACKAGE = Path(sysid.__file__).resolve().parent
MAX_LINES = 800  # issue 31: no source over 800 lines


def _module_name(path: Path) -> str:
    rel = path.relative_to(PACKAGE.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    """Every module of the package: sources, and compiled ones by their stub (``_sysid``)."""
    out = {_module_name(p): p for p in sorted(PACKAGE.rglob("*.pyi"))}
    out.update({_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))})
    return out


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.AST, type_only: bool = False) -> list[ast.Import | ast.ImportFrom]:
    """Every import statement, skipping the bodies of ``if TYPE_CHECKING:`` blocks unless
    ``type_only``."""
    out: list[ast.Import | ast.ImportFrom] = []

    def visit(node: ast.AST) -> None:
        if not type_only and isinstance(node, ast.If) and _is_type_checking(node.test):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            out.append(node)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    return out


def import_graph(modules: dict[str, Path], type_only: bool = False) -> dict[str, set[str]]:
    """``{module: {modules of the package it imports}}`` (with ``type_only``, the imports
    under ``if TYPE_CHECKING:`` too)."""
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        is_pkg = path.name == "__init__.py"
        package = name if is_pkg else name.rpartition(".")[0]
        edges: set[str] = set()
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        for node in _imports(tree, type_only):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                if node.level:
                    base_parts = package.split(".")
                    base_parts = base_parts[: len(base_parts) - (node.level - 1)]
                    base = ".".join(base_parts + ([node.module] if node.module else []))
                else:
                    base = node.module or ""
                # `from pkg import name` imports the submodule pkg.name when there is one
                targets = [
                    f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base
                    for a in node.names
                ]
            for t in targets:
                # `import sysid.a.b` binds the innermost module that exists
                while t and t not in modules:
                    t = t.rpartition(".")[0]
                if t and t != name:
                    edges.add(t)
        graph[name] = edges
    return graph


def find_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Every strongly connected component of more than one module (Tarjan's algorithm,
    iterative), each shown as the shortest closed paths through its modules (first module
    repeated at the end), one per distinct cycle found."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[list[str]] = []
    counter = 0
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph.get(w, ())))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    if len(comp) > 1:
                        components.append(sorted(comp))
    cycles: list[list[str]] = []
    for comp in sorted(components):
        for start in comp:
            c = _closed_path(graph, set(comp), start)
            k = c.index(min(c[:-1]))  # the same cycle from another start: rotate to compare
            c = c[k:-1] + c[:k] + [c[k]]
            if c not in cycles:
                cycles.append(c)
    return cycles


def _closed_path(graph: dict[str, set[str]], comp: set[str], start: str) -> list[str]:
    """A shortest cycle through ``start`` inside a strongly connected component."""
    prev: dict[str, str] = {}
    frontier = [start]
    while frontier:
        nxt = []
        for v in frontier:
            for w in sorted(graph[v] & comp):
                if w == start:
                    path = [v]
                    while path[-1] != start:
                        path.append(prev[path[-1]])
                    return [*reversed(path), start]
                if w not in prev:
                    prev[w] = v
                    nxt.append(w)
        frontier = nxt
    raise AssertionError("not a strongly connected component")  # pragma: no cover


# ------------------------------------------------------------------------------ the checker


def test_cycle_finder_names_the_cycle_and_accepts_a_dag():
    """The checker itself: it finds a planted cycle (and names it in order), and none in a DAG."""
    dag = {"a": {"b", "c"}, "b": {"c"}, "c": set(), "d": {"a"}}
    assert find_cycles(dag) == []
    cyc = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(), "e": {"f"}, "f": {"e"}}
    assert find_cycles(cyc) == [["a", "b", "c", "a"], ["e", "f", "e"]]
    # two cycles sharing a module: both are named
    two = {"m": {"x", "y"}, "x": {"m"}, "y": {"m"}}
    assert find_cycles(two) == [["m", "x", "m"], ["m", "y", "m"]]


def test_import_reader_resolves_relative_imports_and_skips_type_checking(tmp_path):
    src = (
        "from typing import TYPE_CHECKING\n"
        "from . import b\n"
        "from .. import _checks\n"
        "from ..x.y import z\n"
        "if TYPE_CHECKING:\n"
        "    from .c import C\n"
        "def f():\n"
        "    from .d import g\n"
    )
    pkg = tmp_path / "p" / "q"
    pkg.mkdir(parents=True)
    for n, text in {"a": src, "b": "", "c": "", "d": ""}.items():
        (pkg / f"{n}.py").write_text(text)
    (pkg / "__init__.py").write_text("")
    (tmp_path / "p" / "__init__.py").write_text("")
    (tmp_path / "p" / "_checks.py").write_text("")
    (tmp_path / "p" / "x").mkdir()
    (tmp_path / "p" / "x" / "__init__.py").write_text("")
    (tmp_path / "p" / "x" / "y.py").write_text("")
    modules = {
        ".".join(p.relative_to(tmp_path).with_suffix("").parts).removesuffix(".__init__"): p
        for p in sorted(tmp_path.rglob("*.py"))
    }
    graph = import_graph(modules)
    assert graph["p.q.a"] == {"p.q.b", "p._checks", "p.x.y", "p.q.d"}
    assert import_graph(modules, type_only=True)["p.q.a"] == graph["p.q.a"] | {"p.q.c"}


# ------------------------------------------------------------------------------ the package


# Back-edges tolerated for now, each with its owner; delete an entry as soon as its edge is
# gone; add none. (The model modules import nothing from analysis/, io or plot/ since branch
# `protocol`: the computation lives in models/, analysis and io call it.)
TOLERATED_EDGES: set[tuple[str, str]] = set()


def test_no_import_cycle_between_modules():
    graph = import_graph(_modules())
    for a, b in TOLERATED_EDGES:
        graph[a].discard(b)
    cycles = find_cycles(graph)
    assert not cycles, "import cycle(s) in python/sysid:\n" + "\n".join(
        "  " + " -> ".join(c) for c in cycles
    )


# Type-only back-edges tolerated for now; delete an entry as soon as its edge is gone; add none.
TOLERATED_TYPE_EDGES: set[tuple[str, str]] = set()


def test_no_import_cycle_with_type_only_imports():
    """Imports under ``if TYPE_CHECKING:`` count too: two modules that name each other's types
    are one concept split in two (fold them, or name the type structurally)."""
    graph = import_graph(_modules(), type_only=True)
    for a, b in TOLERATED_TYPE_EDGES:
        graph[a].discard(b)
    cycles = find_cycles(graph)
    assert not cycles, "import cycle(s) counting type-only imports:\n" + "\n".join(
        "  " + " -> ".join(c) for c in cycles
    )


_IMPORT_EACH = r"""
import importlib, json, sys, traceback
import sysid  # the compiled core can be initialised once per process: keep it loaded
failed = {}
for name in sys.argv[1:]:
    for k in [k for k in sys.modules if k.startswith("sysid") and k != "sysid._sysid"]:
        del sys.modules[k]
    try:
        importlib.import_module(name)
    except BaseException:  # noqa: BLE001 - reported by the test
        failed[name] = traceback.format_exc(limit=3)
print(json.dumps(failed))
"""


@pytest.fixture(scope="module")
def import_failures() -> dict[str, str]:
    """Each module imported first, after every ``sysid`` module but the compiled core is
    dropped from ``sys.modules`` (one subprocess for all: seconds, not one interpreter each)."""
    import json
    import subprocess
    import sys

    names = _source_modules()
    out = subprocess.run([sys.executable, "-c", _IMPORT_EACH, *names], capture_output=True,
                         text=True, timeout=300, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _source_modules() -> list[str]:
    """Modules written in Python, except ``sysid.__main__`` (importing it runs the CLI)."""
    return sorted(n for n, p in _modules().items() if p.suffix == ".py" and n != "sysid.__main__")


@pytest.mark.parametrize("name", _source_modules())
def test_every_module_imports_on_its_own(name, import_failures):
    assert name not in import_failures, import_failures.get(name)


# Add none.
TOLERATED_LONG: set[str] = set()


def test_no_module_over_600_lines():
    long = {
        name: n
        for p in PACKAGE.rglob("*.py")
        if (name := p.relative_to(PACKAGE.parent).as_posix()) not in TOLERATED_LONG
        and (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES
    }
    assert not long, f"modules over {MAX_LINES} lines (split them by concept): {long}"


def test_namespace_holds_only_public_names():
    names = dir(sysid)
    private = [n for n in names if n.startswith("_") and n != "__version__"]
    assert not private, private
    assert set(names) == set(sysid.__all__) | {"datasets", "__version__"}
    for leaked in ("annotations", "importlib", "Any", "np"):
        assert leaked not in names


@pytest.mark.parametrize("name", sorted(sysid.__all__))
def test_every_public_name_resolves(name):
    """Every name in ``__all__`` loads (the lazy map points at a module that defines it)."""
    assert getattr(sysid, name) is not None


def test_readme_where_things_are_points_at_existing_names_and_files():
    """The README's map from a method's name to its Python and Rust files stays true."""
    import re

    root = Path(__file__).resolve().parents[1]
    text = (root / "README.md").read_text(encoding="utf-8")
    section = text[text.index("## Where things are") :]
    section = section[: section.index("\n## ", 3)]
    rows = [r for r in section.splitlines() if r.startswith("| ") and not r.startswith("| concept")]
    assert len(rows) > 20
    # a family announced for this wave ("(planned, issue NN)") is checked once it lands
    rows = [r for r in rows if "(planned" not in r]
    problems = []
    for row in rows:
        _, names, py, rs = [c.strip() for c in row.strip().strip("|").split("|")]
        for n in re.findall(r"`([^`]+)`", names):
            head = re.split(r"[./ ]", n)[0]
            if head and head != "sysid" and not hasattr(sysid, head):
                problems.append(f"no sysid.{head} ({row[:40]}...)")
        for f in re.findall(r"[\w/]+\.py|[\w/]+/", py):
            if not (PACKAGE / f).exists():
                problems.append(f"no python/sysid/{f}")
        for f in re.findall(r"[\w/]+\.rs|[\w/]+/", rs):
            if not (root / "crates" / "sysid-core" / "src" / f).exists():
                problems.append(f"no crates/sysid-core/src/{f}")
    assert not problems, problems


def test_subpackages_load_on_first_attribute_access():
    """``sysid.plot.bode`` after ``import sysid`` alone raised AttributeError (as SciPy's
    submodules, they now load on first use); unknown names still raise."""
    import subprocess
    import sys

    code = ("import sysid\n"
            "assert sysid.plot.__name__ == 'sysid.plot'\n"
            "assert callable(sysid.validation.crossval.record_folds)\n"
            "try:\n    sysid.no_such_thing\nexcept AttributeError as e:\n"
            "    assert 'no_such_thing' in str(e)\nelse:\n    raise SystemExit(1)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
