"""Every import is declared in pyproject.toml, and requirements.lock pins nothing the project does
not need (issue 34: psutil was imported but not declared; otter-grader's dependencies stayed in
the lock after otter-grader left).

The imports are read from the sources (every ``import`` and ``from ... import`` statement, also
those inside functions), mapped to their distributions by :func:`importlib.metadata
.packages_distributions`; what the project needs is what the declared requirements pull in,
recursively, as pip resolves them (their markers and the extras asked for)."""

from __future__ import annotations

import ast
import functools
import sys
import tomllib
from importlib import metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parents[1]
PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
#: The folders whose own modules are imported by name (sys.path entries of the tools and tests).
LOCAL = {"fdi_lib", "tests", "conftest", "_record"} | {
    p.stem
    for d in ("tools", "tests", "tests/browser", "_ext", "benchmarks")
    for p in (ROOT / d).glob("*.py")
}


def _imports(folder: Path) -> set[str]:
    """The top-level names of every module imported by the Python files under ``folder``."""
    out: set[str] = set()
    for path in folder.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                out |= {a.name.split(".")[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                out.add(node.module.split(".")[0])
    return out


def _third_party(names: set[str]) -> set[str]:
    return {n for n in names if n not in sys.stdlib_module_names and n not in LOCAL}


@functools.cache
def _packages_distributions() -> dict[str, list[str]]:
    # read once per process: each call scans every installed distribution's files (about 1 s)
    return metadata.packages_distributions()


def _distributions(module: str) -> set[str]:
    found = _packages_distributions().get(module)
    assert found, f"{module}: imported, but no installed distribution provides it"
    return {canonicalize_name(d) for d in found}


def _declared(*groups: str) -> set[str]:
    reqs = list(PROJECT["dependencies"])
    for group in groups:
        reqs += PROJECT["optional-dependencies"][group]
    return {canonicalize_name(Requirement(r).name) for r in reqs}


@pytest.mark.parametrize(
    ("folder", "groups"),
    [
        ("fdi_lib", ("cluster",)),  # the cluster extra: dask.distributed, imported when asked for
        ("deploy", ("cluster",)),
        ("tools", ("book", "test")),
        ("_ext", ("book",)),
        ("tests", ("book", "test", "cluster")),
        ("benchmarks", ("book", "test")),
    ],
)
def test_every_import_is_declared(folder, groups):
    declared = _declared(*groups)
    undeclared = {
        module: sorted(_distributions(module))
        for module in sorted(_third_party(_imports(ROOT / folder)))
        if not _distributions(module) & declared
    }
    assert not undeclared, f"{folder}: imported but not declared in pyproject.toml: {undeclared}"


def _needed() -> set[str]:
    """Every distribution that the declared requirements (all extras) pull in, as pip would."""
    todo = [Requirement(r) for r in PROJECT["dependencies"]]
    todo += [Requirement(r) for group in PROJECT["optional-dependencies"].values() for r in group]
    seen: set[tuple[str, frozenset[str]]] = set()
    while todo:
        req = todo.pop()
        name = canonicalize_name(req.name)
        if (name, frozenset(req.extras)) in seen:
            continue
        seen.add((name, frozenset(req.extras)))
        try:
            requires = metadata.requires(name) or []
        except metadata.PackageNotFoundError:
            continue  # a requirement for another platform or Python; not pinned here
        for text in requires:
            sub = Requirement(text)
            extras = [""] + sorted(req.extras)
            if sub.marker is None or any(sub.marker.evaluate({"extra": e}) for e in extras):
                todo.append(sub)
    return {name for name, _ in seen}


def test_the_lock_pins_only_what_the_project_needs():
    pinned = {
        canonicalize_name(line.split("==")[0])
        for line in (ROOT / "requirements.lock").read_text().splitlines()
        if "==" in line
    }
    unneeded = sorted(pinned - _needed())
    assert not unneeded, f"requirements.lock pins packages nothing declared needs: {unneeded}"
