"""Public functions of the core document exactly the parameters they take (numpydoc)."""

import importlib
import inspect
import re

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
