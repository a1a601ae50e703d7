"""The book's API reference (book/api/*.md): numpydoc docstrings rendered by autodoc, strict references.

The reference pages are ``automodule`` directives over the library's modules, rendered by
autodoc with numpydoc (sections as the docstrings write them; parameter types as text, not as
links). The book builds with ``nitpicky``, so every cross-reference in a docstring must resolve.
Two kinds of target are allowed to stay text, by ``nitpick_ignore_regex`` in ``_config.yml``:
objects of other packages (numpy, scipy, the standard library: no inventory is fetched, the
build is offline) and private names (a leading underscore: not part of the API). Everything
else resolves or fails the build. Docstrings name objects of their own module unqualified
(``:class:`NonFiniteError``` in :mod:`fdi_lib.glr`); Sphinx looks such a name up only in the
current module and class, so :func:`resolve_unqualified` completes the lookup: a reference
that Sphinx could not resolve is retried by suffix among the documented ``fdi_lib`` objects and
resolved when exactly one matches (two or more stay unresolved and fail the build); a field of a
dataclass (``LassoPath.solver``), which numpydoc lists in its class's Attributes section, links
to the class.
"""

from __future__ import annotations

import re
from typing import Any


def _unique(domain: Any, target: str) -> str | None:
    """The one documented ``fdi_lib`` object whose full name ends with ``.target``, else None."""
    suffix = "." + target
    matches = [name for name, obj in domain.objects.items()
               if name.startswith("fdi_lib.") and (name == target or name.endswith(suffix))
               and not obj.aliased]
    return matches[0] if len(matches) == 1 else None


def resolve_unqualified(app: Any, env: Any, node: Any, contnode: Any) -> Any:
    """``missing-reference`` handler: a unique ``fdi_lib`` object whose name ends with the target."""
    if node.get("refdomain") != "py":
        return None
    target = node.get("reftarget", "")
    if not target or target.startswith("_") or "._" in target:
        return None
    domain = env.get_domain("py")
    name = _unique(domain, target)
    if name is None and "." in target:
        # ``mod.NAME`` through a module alias (``uav.svo_scale``), or a dataclass field
        # (``LassoPath.solver``: numpydoc lists fields in the class's Attributes section, they are
        # not objects of their own): the object itself, else the class that describes the field.
        head, last = target.rsplit(".", 1)
        name = _unique(domain, last) if head.islower() else _unique(domain, head)
    if name is None:
        return None
    obj = domain.objects[name]
    from sphinx.util.nodes import make_refnode
    return make_refnode(app.builder, node["refdoc"], obj.docname, obj.node_id, contnode, name)


_LITERAL = re.compile(r"(``.*?``|:\w+:`.*?`|`[^`]*`_?)")


def _sections_as_rubrics(lines: list[str]) -> None:
    """A module docstring's numpydoc section (``Examples`` over dashes) as a rubric.

    numpydoc leaves a module docstring's sections as section titles; two modules on one page with
    an ``Examples`` section would then give two targets of one name (a duplicate-label warning).
    """
    for i in range(len(lines) - 1):
        title, rule = lines[i], lines[i + 1]
        if title.strip() and set(rule.strip()) == {"-"} and len(rule.strip()) >= len(title.strip()):
            lines[i], lines[i + 1] = f".. rubric:: {title.strip()}", ""


def escape_bars(app: Any, what: str, name: str, obj: Any, options: Any, lines: list[str]) -> None:
    """``autodoc-process-docstring`` handler: a ``|`` outside a literal is an absolute value or a norm.

    The docstrings write ``|Delta| <= 1`` and ``||d(k)||_inf`` in plain text, as a reader of the
    source reads them; reStructuredText would take ``|Delta|`` for a substitution. The docstrings
    use no substitutions and no grid tables, so every bar outside inline literals, roles and
    interpreted text is escaped.
    """
    if what == "module":
        _sections_as_rubrics(lines)
    for i, line in enumerate(lines):
        parts = _LITERAL.split(line)
        lines[i] = "".join(p if j % 2 else p.replace("|", "\\|") for j, p in enumerate(parts))


def drop_object_base(app: Any, name: str, obj: Any, options: Any, bases: list[type]) -> None:
    """``autodoc-process-bases`` handler: "Bases: object" says nothing; other bases stay shown."""
    bases[:] = [b for b in bases if b is not object]


def setup(app: Any) -> dict[str, Any]:
    app.connect("autodoc-process-bases", drop_object_base)
    app.connect("missing-reference", resolve_unqualified)
    app.connect("autodoc-process-docstring", escape_bars)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
