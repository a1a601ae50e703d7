"""The book's API reference (book/api/) documents every public module of the library."""

import io
import pkgutil
import re
import sys
from pathlib import Path

import pytest

import fdi_lib

ROOT = Path(__file__).resolve().parents[1]
#: Not part of the reference: the student-facing exercise package (its answers are not shipped,
#: its pages are the chapters' exercises) and ``python -m fdi_lib``'s entry module.
EXCLUDED = re.compile(r"fdi_lib\.(exercises(\..*)?|__main__)$")


def _documented() -> list[str]:
    text = "\n".join(p.read_text() for p in sorted((ROOT / "book" / "api").glob("*.md")))
    return re.findall(r"^\.\. automodule:: (\S+)$", text, re.M)


def _public_modules() -> set[str]:
    names = {"fdi_lib"}
    for info in pkgutil.walk_packages(fdi_lib.__path__, "fdi_lib."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.add(info.name)
    return {n for n in names if not EXCLUDED.match(n)}


def test_every_public_module_has_a_reference_section():
    missing = _public_modules() - set(_documented())
    assert not missing, f"modules without an automodule in book/api/: {sorted(missing)}"


def test_no_module_is_documented_twice_or_unknown():
    documented = _documented()
    assert len(documented) == len(set(documented)), "a module is documented on two pages"
    unknown = set(documented) - _public_modules()
    assert not unknown, f"book/api/ documents modules that do not exist: {sorted(unknown)}"


def test_reference_pages_are_in_the_table_of_contents():
    toc = (ROOT / "_toc.yml").read_text()
    for page in sorted((ROOT / "book" / "api").glob("*.md")):
        assert f"book/api/{page.stem}" in toc, page.name


@pytest.fixture(scope="module")
def api_app(tmp_path_factory):
    """A Sphinx application (HTML builder, nothing built) with autodoc, numpydoc and the
    reference's extension, configured as ``_config.yml`` does; numpydoc's own renderer is put
    back afterwards."""
    import numpydoc.numpydoc
    from sphinx.application import Sphinx
    from sphinx.util.docutils import docutils_namespace

    tmp = tmp_path_factory.mktemp("api")
    (tmp / "conf.py").write_text(
        "import sys\n"
        f"sys.path.insert(0, {str(ROOT / '_ext')!r})\n"
        "extensions = ['sphinx.ext.autodoc', 'numpydoc', 'fdi_api']\n"
        "autodoc_typehints = 'none'\n"
    )
    (tmp / "index.rst").write_text("Index\n=====\n")
    original = numpydoc.numpydoc.get_doc_object
    with docutils_namespace():
        yield Sphinx(
            str(tmp),
            str(tmp),
            str(tmp / "out"),
            str(tmp / "doctrees"),
            "html",
            status=None,
            warning=io.StringIO(),
            freshenv=True,
        )
    numpydoc.numpydoc.get_doc_object = original


def test_numpydoc_renders_as_its_own_with_the_template_compiled_once(api_app):
    """_ext/fdi_api.py's get_doc_object: what numpydoc's gives, one compiled template."""
    import numpydoc.numpydoc
    from numpydoc import docscrape_sphinx

    from fdi_lib import glr

    fdi_api = sys.modules["fdi_api"]
    assert numpydoc.numpydoc.get_doc_object is fdi_api.get_doc_object
    config = {"show_class_members": False, "xref_param_type": False}
    cases = [
        (glr.glr_known_profile, "function"),
        (glr.GLRResult, "class"),
        (glr, "module"),
        (glr.quadratic_form, None),
    ]
    templates = set()
    for builder in (api_app.builder, None):
        for obj, what in cases:
            ours = fdi_api.get_doc_object(obj, what, config=dict(config), builder=builder)
            theirs = docscrape_sphinx.get_doc_object(
                obj, what, config=dict(config), builder=builder
            )
            assert type(ours) is type(theirs) and str(ours) == str(theirs), (obj, builder)
            templates.add(id(ours.template))
    assert len(templates) == 2  # one per builder (and one without), however many docstrings


def test_type_comments_are_read_only_when_signatures_show_types(api_app):
    from types import SimpleNamespace

    from sphinx.ext.autodoc.type_comment import update_annotations_using_type_comments as read

    def connected() -> bool:
        listeners = api_app.events.listeners["autodoc-before-process-signature"]
        return any(listener.handler is read for listener in listeners)

    fdi_api = sys.modules["fdi_api"]
    assert not connected()  # autodoc_typehints: none, as the book
    api_app.connect("autodoc-before-process-signature", read)
    fdi_api.drop_type_comments(api_app, SimpleNamespace(autodoc_typehints="signature"))
    assert connected()
    fdi_api.drop_type_comments(api_app, SimpleNamespace(autodoc_typehints="none"))
    assert not connected()
