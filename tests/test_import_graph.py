"""The uvsim modules import each other without cycles.

Every module under ``src/uvsim`` is parsed with :mod:`ast` (no module is imported), and
every ``import`` / ``from ... import`` statement anywhere in it -- at module level, inside
functions, relative or absolute -- becomes an edge to the deepest existing uvsim module
the imported name resolves to (``from uvsim.forces import make_term`` -> ``uvsim.forces``,
``from uvsim import thrusters`` -> ``uvsim.thrusters``).  An import of a package from one
of its own submodules is an edge like any other, so ``uvsim.forces.base`` importing
``uvsim.forces`` while ``uvsim.forces`` imports ``uvsim.forces.base`` is a cycle.
Dynamic imports (``importlib.import_module("...")``) are not statements and are not
counted.
"""
from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"


def module_files(root: Path, package: str) -> dict[str, Path]:
    """Module name -> file for every ``.py`` file of ``package`` under ``root``."""
    out = {}
    for path in sorted((root / package).rglob("*.py")):
        parts = list(path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _deepest(name: str, modules) -> str | None:
    parts = name.split(".")
    for k in range(len(parts), 0, -1):
        cand = ".".join(parts[:k])
        if cand in modules:
            return cand
    return None


def import_graph(root: Path, package: str) -> dict[str, dict[str, str]]:
    """``{module: {imported module: "file:line" of the first such import}}``."""
    files = module_files(root, package)
    graph: dict[str, dict[str, str]] = {m: {} for m in files}
    for mod, path in files.items():
        is_pkg = path.name == "__init__.py"
        here = mod.split(".") if is_pkg else mod.split(".")[:-1]  # the package `.` refers to
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    if node.level - 1 > len(here):
                        continue
                    base = here[:len(here) - (node.level - 1)]
                    base = ".".join(base + ([node.module] if node.module else []))
                else:
                    base = node.module or ""
                # ``from pkg import sub`` imports the submodule when there is one.
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in files else base for a in node.names]
            for name in targets:
                dep = _deepest(name, files)
                if dep is not None and dep != mod:
                    graph[mod].setdefault(dep, f"{path.relative_to(root)}:{node.lineno}")
    return graph


def cycles(graph: dict[str, dict[str, str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found = []
    counter = 0
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph[w]))))
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
                        found.append(sorted(comp))
    return sorted(found)


def describe(graph, comp) -> str:
    members = set(comp)
    edges = [f"    {a} -> {b} ({where})" for a in comp for b, where in sorted(graph[a].items()) if b in members]
    return "import cycle between " + ", ".join(comp) + ":\n" + "\n".join(edges)


def test_uvsim_has_no_import_cycle():
    graph = import_graph(SRC, "uvsim")
    assert len(graph) > 50 and "uvsim.forces.base" in graph  # the walk found the package
    found = cycles(graph)
    assert not found, "\n".join(describe(graph, c) for c in found)


def test_the_check_finds_cycles(tmp_path):
    """The checker itself: function-level, relative and package-from-submodule imports
    close cycles; an import of a sibling that imports nothing back does not."""
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    files = {
        "__init__.py": "",
        "a.py": "def f():\n    from pkg.b import g\n",                      # a -> b (in a function)
        "b.py": "from . import a\nimport pkg.c\n",                           # b -> a (relative), b -> c
        "c.py": "import numpy\nfrom pkg.sub.leaf import x\n",                # c -> sub.leaf
        "sub/__init__.py": "from .base import Thing\n",                    # sub -> sub.base
        "sub/base.py": "def make():\n    from pkg.sub import helper\n",      # sub.base -> sub (package)
        "sub/leaf.py": "from ..sub import base\n",                           # sub.leaf -> sub.base
    }
    for name, text in files.items():
        (pkg / name).write_text(text)
    graph = import_graph(tmp_path, "pkg")
    assert graph["pkg.b"] == {"pkg.a": "pkg/b.py:1", "pkg.c": "pkg/b.py:2"}
    assert set(graph["pkg.c"]) == {"pkg.sub.leaf"}
    assert set(graph["pkg.sub.leaf"]) == {"pkg.sub.base"}
    found = cycles(graph)
    assert found == [["pkg.a", "pkg.b"], ["pkg.sub", "pkg.sub.base"]]
    msg = describe(graph, found[1])
    assert "pkg.sub.base -> pkg.sub (pkg/sub/base.py:2)" in msg
    # breaking the upward import removes that cycle
    (pkg / "sub" / "base.py").write_text("def make():\n    pass\n")
    assert cycles(import_graph(tmp_path, "pkg")) == [["pkg.a", "pkg.b"]]
