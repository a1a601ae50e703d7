"""Public functions of the core document exactly the parameters they take (numpydoc), and the
docstrings of the API reference write their equations as maths, not as ASCII literal blocks."""

import ast
import importlib
import importlib.util
import inspect
import re
from pathlib import Path

import pytest

CORE = [
    "fdi_lib.models",
    "fdi_lib.simulate",
    "fdi_lib.filters",
    "fdi_lib.signatures",
    "fdi_lib.glr",
    "fdi_lib.isolation",
    "fdi_lib.montecarlo",
    "fdi_lib.calibration",
    "fdi_lib.kitanidis",
    "fdi_lib.sparse",
    "fdi_lib.nonparametric",
    "fdi_lib.rls",
    "fdi_lib.sets.polytope",
    "fdi_lib.sets.svo",
    "fdi_lib.threads",
]


def _documented(doc: str) -> set[str]:
    match = re.search(r"Parameters\n-{3,}\n(.*?)(?:\n\n[A-Z][a-z]+\n-{3,}|\Z)", doc, re.S)
    if not match:
        return set()
    names = set()
    for line in match.group(1).splitlines():
        head = re.match(r"^(\*{0,2}[A-Za-z_][\w, *]*?)\s*(?::|$)", line)
        if head and not line.startswith(" "):
            names.update(n.strip().lstrip("*") for n in head.group(1).split(","))
    return names


def _public_functions():
    for name in CORE:
        mod = importlib.import_module(name)
        for attr in getattr(mod, "__all__", []):
            obj = getattr(mod, attr)
            if inspect.isfunction(obj):
                yield f"{name}.{attr}", obj


@pytest.mark.parametrize(
    "qualname, func", list(_public_functions()), ids=lambda x: x if isinstance(x, str) else ""
)
def test_parameters_section_matches_signature(qualname, func):
    doc = inspect.getdoc(func) or ""
    assert doc, f"{qualname} has no docstring"
    documented = _documented(doc)
    params = {p.name for p in inspect.signature(func).parameters.values()}
    if (
        not documented
    ):  # short docstrings of small helpers document each argument inline, as ``name``
        inline = {p for p in params if re.search(rf"``\**{p}``", doc)}
        assert inline == params, (
            f"{qualname}: no Parameters section and {params - inline} not mentioned"
        )
        return
    assert documented <= params, (
        f"{qualname} documents parameters it does not take: {documented - params}"
    )
    assert params <= documented, f"{qualname} takes undocumented parameters: {params - documented}"


ROOT = Path(__file__).resolve().parents[1]
#: Equation-like text: an ASCII subscript on a letter or a Greek name (``X_k``, ``Gamma_{k+1}``,
#: ``theta_a``), a transpose ``^T`` or a norm ``||``.
GREEK = (
    "alpha|beta|gamma|delta|epsilon|varepsilon|eps|zeta|eta|theta|lambda|mu|nu|xi|pi|rho|sigma|"
    "tau|phi|psi|chi|omega|Gamma|Delta|Theta|Lambda|Xi|Pi|Sigma|Upsilon|Phi|Psi|Omega"
)
EQUATION = re.compile(
    rf"\b(?:[A-Za-z]|{GREEK})_(?:\{{[^}}]+\}}|[A-Za-z0-9]{{1,3}})(?![\w(])|\^T\b|\|\|"
)


def _rendered_modules() -> list[str]:
    text = "\n".join(p.read_text() for p in sorted((ROOT / "book" / "api").glob("*.md")))
    return re.findall(r"^\.\. automodule:: (\S+)$", text, re.M)


def _docstrings(source: str):
    """(name, docstring) of the module and of every class and function of ``source``."""
    tree = ast.parse(source)
    yield "<module>", ast.get_docstring(tree)
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            yield node.name, ast.get_docstring(node)


def literal_blocks(doc: str) -> list[str]:
    """The bodies of the reST literal blocks (a paragraph ending in ``::``) of ``doc``."""
    lines, blocks, i = doc.splitlines(), [], 0
    while i < len(lines):
        line = lines[i]
        i += 1
        if not line.rstrip().endswith("::") or re.match(r"\s*\.\. ", line):
            continue  # directives (``.. math::``, ``.. code-block::``) are not literal blocks
        indent, body = len(line) - len(line.lstrip()), []
        while i < len(lines) and (
            not lines[i].strip() or len(lines[i]) - len(lines[i].lstrip()) > indent
        ):
            body.append(lines[i])
            i += 1
        blocks.append("\n".join(body).strip())
    return blocks


def test_literal_block_detection():
    doc = (
        "Text::\n\n    X_{k+1} = F_k X_k\n\nAfter.\n\n.. math::\n\n    X_k\n\nCode::\n\n    f(x)\n"
    )
    assert literal_blocks(doc) == ["X_{k+1} = F_k X_k", "f(x)"]
    assert [bool(EQUATION.search(b)) for b in literal_blocks(doc)] == [True, False]
    assert not EQUATION.search("cause_text='a', fig8(*, seed)")


@pytest.mark.parametrize("name", _rendered_modules())
def test_equations_are_maths_not_literal_blocks(name):
    source = Path(importlib.util.find_spec(name).origin).read_text()
    ascii_maths = [
        f"{where}: {block.splitlines()[0]}"
        for where, doc in _docstrings(source)
        for block in literal_blocks(doc or "")
        if not block.startswith(">>>") and EQUATION.search(block)
    ]
    assert not ascii_maths, (
        f"{name}: equations in literal blocks, write them as '.. math::' (LaTeX, the book's "
        f"macros): {ascii_maths}"
    )
