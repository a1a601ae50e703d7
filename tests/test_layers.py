"""The package's modules import only downward, and no two of them import each other (issue 34).

Layers, top to bottom:

3. presentation for the book: ``fdi_lib.widgets`` (the live sliders' callbacks) and
   ``fdi_lib.explorables`` (the kernel-free sliders drawn at build time; it calls the widgets'
   callbacks through the book, and needs only the redraw helpers below);
2.5 what the reproductions show: ``fdi_lib.reproduce.views`` (figures, reader tables, helpers
   for the prose), above the modules that compute them; a registration names its figure by a
   dotted path (``plot="fdi_lib.reproduce.views.zb2014.plot_fig1"``), imported when drawn;
2. the papers' reproductions, the CLI and the claims ledger: ``fdi_lib.reproduce`` (and
   ``fdi_lib.__main__``, the CLI's entry point); beside them ``fdi_lib.exercises``, which may
   import the library and the reproductions, and which no module of the package imports (the
   book's tools do);
1. the library: every other module (models, filters, ..., sets, systems, windturbine,
   montecarlo, report, plotting, redraw).

Imports are read statically (:mod:`ast`) from every module, module-level and function-level alike.
An import of a name from a submodule's own package (``fdi_lib.exercises.book`` reads
``fdi_lib.exercises.exercises`` at call time) is checked for its layer but left out of the cycle
search: the package's ``__init__`` re-exports its submodules, so that edge runs back up the tree
for every package that re-exports, and says nothing of two modules depending on each other.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "fdi_lib"

#: Layer of each top-level part of the package (anything not listed is the library, layer 1).
LAYERS = {"widgets": 3, "explorables": 3, "reproduce": 2, "__main__": 2, "exercises": 2}
#: Sub-packages with a layer of their own, above their parent's (longest prefix first).
SUBLAYERS = {"reproduce.views": 2.5}
#: Parts no other part of the package may import.
PRIVATE = {"exercises"}


def modules(root: Path) -> dict[str, Path]:
    """Dotted name -> file of every module of the package at ``root``."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _known(name: str, mods: dict[str, Path]) -> str | None:
    """The module ``name`` or the deepest package of the tree that holds it."""
    while name and name not in mods:
        name = name.rpartition(".")[0]
    return name or None


def import_graph(root: Path) -> dict[str, set[str]]:
    """Module -> the modules of the same package it imports, anywhere in its body."""
    mods = modules(root)
    top = root.name
    graph: dict[str, set[str]] = {}
    for name, path in mods.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        targets: set[str | None] = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
            if isinstance(node, ast.Import):
                targets.update(
                    _known(a.name, mods) for a in node.names if a.name.split(".")[0] == top
                )
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[: len(package.split(".")) - node.level + 1]
                    source = ".".join(base + ([node.module] if node.module else []))
                else:
                    source = node.module or ""
                if source.split(".")[0] != top:
                    continue
                # ``from pkg import sub`` imports the submodule ``pkg.sub``
                targets.update(
                    f"{source}.{a.name}" if f"{source}.{a.name}" in mods else _known(source, mods)
                    for a in node.names
                )
        graph[name] = {t for t in targets if t is not None and t != name}
    return graph


def layer(module: str) -> tuple[float, str]:
    """``(rank, part)`` of ``module``: its layer and its part of the package (top-level, or one of
    :data:`SUBLAYERS`)."""
    inner = module.partition(".")[2]
    for sub, rank in SUBLAYERS.items():
        if inner == sub or inner.startswith(sub + "."):
            return rank, sub
    part = inner.split(".")[0]
    return LAYERS.get(part, 1), part


def upward_edges(graph: dict[str, set[str]]) -> list[str]:
    """Every import of a higher layer, or of a private part from outside it, spelled out."""
    bad = []
    for source in sorted(graph):
        (rank, part) = layer(source)
        for target in sorted(graph[source]):
            (trank, tpart) = layer(target)
            if trank > rank:
                bad.append(f"{source} (layer {rank}) imports {target} (layer {trank})")
            elif tpart in PRIVATE and tpart != part:
                bad.append(f"{source} imports {target}: nothing in the package may import {tpart}")
    return bad


def _ancestor(package: str, module: str) -> bool:
    return module.startswith(package + ".")


def cycles(graph: dict[str, set[str]]) -> list[str]:
    """One cycle ``a -> b -> ... -> a`` for each group of modules that import each other."""
    edges = {m: sorted(t for t in ts if not _ancestor(t, m)) for m, ts in graph.items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    groups: list[set[str]] = []

    def visit(m: str) -> None:  # Tarjan's strongly connected components
        index[m] = low[m] = len(index)
        stack.append(m)
        for t in edges.get(m, ()):
            if t not in index:
                visit(t)
                low[m] = min(low[m], low[t])
            elif t in stack:
                low[m] = min(low[m], index[t])
        if low[m] == index[m]:
            group = set()
            while True:
                t = stack.pop()
                group.add(t)
                if t == m:
                    break
            if len(group) > 1:
                groups.append(group)

    for m in sorted(edges):
        if m not in index:
            visit(m)
    out = []
    for group in groups:  # a shortest way back to the group's first module (breadth first)
        start = min(group)
        paths = {t: [start, t] for t in edges[start] if t in group}
        frontier = list(paths)
        while start not in paths:
            nxt = []
            for m in frontier:
                for t in edges[m]:
                    if t in group and t not in paths:
                        paths[t] = paths[m] + [t]
                        nxt.append(t)
            frontier = nxt
        out.append(" -> ".join(paths[start]))
    return out


def test_no_module_imports_a_higher_layer_or_the_exercises():
    assert upward_edges(import_graph(PACKAGE)) == []


def test_no_import_cycles():
    assert cycles(import_graph(PACKAGE)) == []


def test_the_graph_sees_function_level_relative_and_submodule_imports():
    graph = import_graph(PACKAGE)
    assert "fdi_lib.redraw" in graph["fdi_lib.reproduce.views.zb2014"]  # inside a function
    assert "fdi_lib.widgets.zb2014" in graph["fdi_lib.widgets.explorables"]  # from pkg import sub
    assert "fdi_lib.reproduce.cli" in graph["fdi_lib.__main__"]
    assert layer("fdi_lib.explorables") == (3, "explorables")
    assert layer("fdi_lib.redraw") == (1, "redraw")
    assert layer("fdi_lib.reproduce.views.zb2014") == (2.5, "reproduce.views")
    assert layer("fdi_lib.reproduce.views") == (2.5, "reproduce.views")
    assert layer("fdi_lib.reproduce.zb2014") == (2, "reproduce")


def test_every_registered_figure_is_drawn_by_a_view():
    """A registration's ``plot`` names a function of :mod:`fdi_lib.reproduce.views` that exists
    (the computing module cannot import it to check; this does)."""
    from fdi_lib.reproduce import list_reproductions
    from fdi_lib.reproduce.registry import DeferredPlot

    for rep in list_reproductions():
        if rep.plot is not None:
            assert isinstance(rep.plot, DeferredPlot), rep.id
            assert rep.plot.path.startswith("fdi_lib.reproduce.views."), rep.id
            assert callable(rep.plot.resolve()), rep.id


def _package(tmp_path: Path, files: dict[str, str]) -> Path:
    root = tmp_path / "fdi_lib"
    for rel, text in {"__init__.py": "", **files}.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)
    return root


def test_an_upward_import_and_an_import_of_the_exercises_are_named(tmp_path):
    root = _package(
        tmp_path,
        {
            "widgets/__init__.py": "",
            "reproduce/__init__.py": "",
            "reproduce/paper.py": "def f():\n    from fdi_lib.widgets import render\n",
            "reproduce/views/__init__.py": "",
            "reproduce/views/paper.py": "from fdi_lib.reproduce import paper\n",
            "reproduce/other.py": "from fdi_lib.reproduce.views.paper import plot\n",
            "exercises/__init__.py": "from ..reproduce import paper\n",
            "reproduce/cli.py": "from fdi_lib.exercises import check\n",
            "models.py": "import fdi_lib.exercises\n",
        },
    )
    assert upward_edges(import_graph(root)) == [
        "fdi_lib.models (layer 1) imports fdi_lib.exercises (layer 2)",
        "fdi_lib.reproduce.cli imports fdi_lib.exercises: "
        "nothing in the package may import exercises",
        "fdi_lib.reproduce.other (layer 2) imports fdi_lib.reproduce.views.paper (layer 2.5)",
        "fdi_lib.reproduce.paper (layer 2) imports fdi_lib.widgets (layer 3)",
    ]


@pytest.mark.parametrize(
    "b_imports_a",
    ["from fdi_lib.a import x", "from . import a", "def g():\n    import fdi_lib.a\n"],
)
def test_a_cycle_is_spelled_out(tmp_path, b_imports_a):
    root = _package(
        tmp_path,
        {
            "a.py": "from fdi_lib.c import y\n",
            "b.py": b_imports_a + "\n",
            "c.py": "from fdi_lib import b\n",
            "sub/__init__.py": "from fdi_lib.sub.d import z\n",
            "sub/d.py": "from fdi_lib.sub import w\n",
        },
    )
    assert cycles(import_graph(root)) == ["fdi_lib.a -> fdi_lib.c -> fdi_lib.b -> fdi_lib.a"]
