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
to the class; an object that exists in the library without an entry of its own (a helper outside
its module's ``__all__``) stays text. A name that exists nowhere fails the build.
"""

from __future__ import annotations

import functools
import re
import warnings
from typing import Any


def _unique(domain: Any, target: str) -> str | None:
    """The one documented ``fdi_lib`` object whose full name ends with ``.target``, else None."""
    suffix = "." + target
    matches = [
        name
        for name, obj in domain.objects.items()
        if name.startswith("fdi_lib.")
        and (name == target or name.endswith(suffix))
        and not obj.aliased
    ]
    return matches[0] if len(matches) == 1 else None


def _exists(target: str, module: str | None, cls: str | None = None) -> bool:
    """Whether ``target`` (absolute, or relative to ``module`` or to its class ``cls``) names an
    object of ``fdi_lib``: a module, a module's attribute, or a class's attribute or dataclass
    field."""
    import importlib

    scopes = [module] + ([f"{module}.{cls}"] if module and cls else [])
    for full in (target, *(f"{scope}.{target}" for scope in scopes if scope)):
        if not full or not full.startswith("fdi_lib"):
            continue
        parts = full.split(".")
        for i in range(len(parts), 0, -1):
            try:
                obj: Any = importlib.import_module(".".join(parts[:i]))
            except ImportError:
                continue
            try:
                for j, attr in enumerate(parts[i:], i):
                    fields = getattr(obj, "__dataclass_fields__", {})
                    if attr in fields and j == len(parts) - 1:
                        return True
                    obj = getattr(obj, attr)
            except AttributeError:
                break
            return True
    return False


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
        # An object of the library that exists but has no entry (a helper outside its module's
        # ``__all__``): the reference stays text. A name that does not exist still fails.
        found = _exists(target, node.get("py:module"), node.get("py:class"))
        return contnode if found else None
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


#: The sections numpydoc knows (it renders them in its own order and drops any other).
_NUMPYDOC_SECTIONS = {
    "Parameters",
    "Attributes",
    "Methods",
    "Returns",
    "Yields",
    "Receives",
    "Other Parameters",
    "Raises",
    "Warns",
    "Warnings",
    "See Also",
    "Notes",
    "References",
    "Examples",
}
#: The library's own sections (``Headline keys`` of a reproduction: its public JSON keys), cut
#: out before numpydoc reads a docstring and set back after it, keyed by the object's name.
_OWN_SECTIONS: dict[str, list[str]] = {}


def _is_header(lines: list[str], i: int) -> bool:
    title, rule = lines[i].strip(), lines[i + 1].strip() if i + 1 < len(lines) else ""
    return bool(title) and set(rule) == {"-"} and len(rule) >= len(title)


#: A parameter-list entry's first line: ``name`` or ``name, other : type``.
_PARAM = re.compile(r"^(\s*$|\s+|[A-Za-z_]\w*(, [A-Za-z_]\w*)*( : .+)?$)")


def cut_own_sections(
    app: Any, what: str, name: str, obj: Any, options: Any, lines: list[str]
) -> None:
    """Before numpydoc: take out the sections it does not know (it would drop them).

    A reproduction documents its JSON contract in ``Headline keys`` and ``Paper keys`` sections,
    written as parameter lists; :func:`restore_own_sections` sets them back in numpydoc's own
    layout for a parameter list, under their own titles. A paragraph after such a list (after a
    blank line, not an entry) is prose of the docstring, as numpydoc reads one after Parameters.
    """
    if what == "module":
        return  # a module's sections are prose, set as rubrics by escape_bars
    kept: list[str] = []
    own: dict[str, list[str]] = {}
    body = kept
    i = 0
    while i < len(lines):
        if _is_header(lines, i):
            title = lines[i].strip()
            if title not in _NUMPYDOC_SECTIONS:
                body = own.setdefault(title, [])
                i += 2
                continue
            body = kept
        elif body is not kept and i and not lines[i - 1].strip() and not _PARAM.match(lines[i]):
            body = kept  # a paragraph after the list, at its indentation: prose again
        body.append(lines[i])
        i += 1
    if own:
        _OWN_SECTIONS[name] = [
            line for title, section in own.items() for line in _param_list(title, section)
        ]
        lines[:] = kept


def _param_list(title: str, section: list[str]) -> list[str]:
    """A section written as a numpydoc parameter list, rendered as numpydoc renders Parameters."""
    from numpydoc.docscrape_sphinx import SphinxDocString

    # A description line that starts like a list item continues the sentence above it.
    text = "\n".join(re.sub(r"^(\s+)([*+-] )", r"\1\\\2", line) for line in section)
    config = {"xref_param_type": False, "template": numpydoc_template()}
    doc = SphinxDocString("Parameters\n----------\n" + text, config=config)
    rendered = doc._str_param_list("Parameters")
    return [""] + [line.replace(":Parameters:", f":{title}:", 1) for line in rendered]


def restore_own_sections(
    app: Any, what: str, name: str, obj: Any, options: Any, lines: list[str]
) -> None:
    """After numpydoc: the sections :func:`cut_own_sections` took out, at the end."""
    lines.extend(_OWN_SECTIONS.pop(name, []))


def drop_object_base(app: Any, name: str, obj: Any, options: Any, bases: list[type]) -> None:
    """``autodoc-process-bases`` handler: "Bases: object" says nothing; other bases stay shown."""
    bases[:] = [b for b in bases if b is not object]


@functools.cache
def numpydoc_template(builder: Any = None) -> Any:
    """numpydoc's docstring template (``numpydoc_docstring.rst``), loaded once per builder.

    Loaded as numpydoc 1.11's :func:`numpydoc.docscrape_sphinx.get_doc_object` loads it: through
    the builder's template loader (a ``templates_path`` of the project may override it), else
    from numpydoc's own folder. numpydoc makes a new Jinja environment and compiles the template
    for every docstring (1,299 a build of the book, 1 ms each); a compiled template renders any
    number of them.
    """
    from pathlib import Path

    from jinja2 import FileSystemLoader
    from jinja2.sandbox import SandboxedEnvironment
    from numpydoc import docscrape_sphinx
    from sphinx.jinja2glue import BuiltinTemplateLoader

    dirs = [str(Path(docscrape_sphinx.__file__).parent / "templates")]
    if builder is None:
        loader: Any = FileSystemLoader(dirs)
    else:
        loader = BuiltinTemplateLoader()
        loader.init(builder, dirs=dirs)
    return SandboxedEnvironment(loader=loader).get_template("numpydoc_docstring.rst")


def get_doc_object(
    obj: Any,
    what: str | None = None,
    doc: str | None = None,
    config: Any = None,
    builder: Any = None,
) -> Any:
    """numpydoc's :func:`~numpydoc.docscrape_sphinx.get_doc_object` with the template of
    :func:`numpydoc_template` (numpydoc's own compiles it anew on every call)."""
    from numpydoc import docscrape
    from numpydoc.docscrape_sphinx import SphinxClassDoc, SphinxFunctionDoc, SphinxObjDoc

    config = {} if config is None else config
    config["template"] = numpydoc_template(builder)
    return docscrape.get_doc_object(
        obj,
        what=what,
        doc=doc,
        config=config,
        class_doc=SphinxClassDoc,
        func_doc=SphinxFunctionDoc,
        obj_doc=SphinxObjDoc,
    )


def drop_type_comments(app: Any, config: Any) -> None:
    """``config-inited`` handler: no reading of type comments when signatures show no types.

    autodoc reads a function's ``# type:`` comments into its annotations before it formats its
    signature (``sphinx.ext.autodoc.type_comment``: the function's source parsed again, for the
    576 signatures of the reference, 0.4 s a build); with ``autodoc_typehints: none`` the
    signatures show no annotation, whatever its source, so the handler is disconnected.
    """
    if config.autodoc_typehints != "none":
        return
    from sphinx.ext.autodoc.type_comment import update_annotations_using_type_comments

    for listener in list(app.events.listeners.get("autodoc-before-process-signature", [])):
        if listener.handler is update_annotations_using_type_comments:
            app.disconnect(listener.id)


def setup(app: Any) -> dict[str, Any]:
    # numpydoc renders every docstring through its module's ``get_doc_object``, the function its
    # own ``setup(app, get_doc_object_=...)`` lets a caller replace: :func:`get_doc_object` above,
    # the same with the template compiled once (tests/test_api_reference.py compares the two).
    app.setup_extension("numpydoc")
    import numpydoc.numpydoc

    numpydoc.numpydoc.get_doc_object = get_doc_object
    # numpydoc also reads the raw docstring for a signature and warns about the sections above.
    warnings.filterwarnings("ignore", r"Unknown section (Headline|Paper) Keys", UserWarning)
    app.connect("autodoc-process-bases", drop_object_base)
    app.connect("config-inited", drop_type_comments)
    app.connect("missing-reference", resolve_unqualified)
    # numpydoc's own handler has the default priority (500): the library's sections are cut
    # before it reads a docstring and set back after it has rendered one.
    app.connect("autodoc-process-docstring", cut_own_sections, priority=400)
    app.connect("autodoc-process-docstring", restore_own_sections, priority=600)
    app.connect("autodoc-process-docstring", escape_bars, priority=700)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
