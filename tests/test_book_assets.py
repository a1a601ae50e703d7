"""What the book's pages load (``_ext/fdi_book.py``, items 9 and 10; issue 23): no Font Awesome
script, MathJax only on pages with maths of their own, hover previews served from the build with
a lazy MathJax, previews without scripts; and the post-build report of ``make book``
(``tools/build_report.py``). The real-browser checks of the whole book are
``tests/browser/check_previews.py`` and ``tests/browser/page_weights.py``."""

from __future__ import annotations

import io
import json
import re
from pathlib import Path

import pytest

from source_module import load as _load  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


EXT = _load("fdi_book_assets_ext", ROOT / "_ext" / "fdi_book.py")
REPORT = _load("fdi_build_report", ROOT / "tools" / "build_report.py")


def _scripts(html: str) -> list[str]:
    return re.findall(r'<script[^>]*\bsrc="([^"]+)"', html)


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> Path:
    """A three-page book with the book's theme, sphinx-tippy and this extension, configured as
    ``_config.yml`` does: the root page has no maths of its own but its toctree includes a page
    with maths (Sphinx would load MathJax on it); ``other`` has an equation and a figure with a
    script in it; ``plain`` refers to both."""
    import yaml
    from sphinx.application import Sphinx
    from sphinx.util.docutils import docutils_namespace

    config = yaml.safe_load((ROOT / "_config.yml").read_text())["sphinx"]["config"]
    tippy = {k: v for k, v in config.items() if k.startswith("tippy_")}
    tmp = tmp_path_factory.mktemp("book")
    src = tmp / "src"
    src.mkdir()
    (src / "conf.py").write_text(
        "import sys\n"
        f"sys.path.insert(0, {str(ROOT / '_ext')!r})\n"
        "extensions = ['myst_parser', 'sphinx_tippy', 'fdi_book']\n"
        "html_theme = 'sphinx_book_theme'\n"
        # its own parser for .md: a Sphinx app of another test module in this process
        # (myst-nb's) leaves ``.md -> myst-nb`` in a default shared by later apps
        "source_suffix = {'.md': 'markdown'}\n"
        "myst_enable_extensions = ['dollarmath', 'amsmath']\n"
        "numfig = True\n"
        f"mathjax_path = {config['mathjax_path']!r}\n"
        f"mathjax3_config = {config['mathjax3_config']!r}\n"
        + "".join(f"{k} = {v!r}\n" for k, v in tippy.items())
    )
    (src / "index.md").write_text("# Index\n\n```{toctree}\nother\nplain\n```\n\nNo maths here.\n")
    (src / "other.md").write_text(
        "# Other\n\n$$\nx_k \\in \\R^n\n$$ (eq-x)\n\n"
        '````{admonition} Live $y$\n:name: fig-live\n\n```{raw} html\n<img src="data:image/png;base64,AAAA" '
        "alt=\"a\"><script>var frames = ['MANY-FRAMES'];</script>\n```\n````\n\n"
        "```{code-block} python\n:caption: Code\n:name: code-x\n\nx = 1\n```\n"
    )
    (src / "plain.md").write_text(
        '# Plain\n\nSee {eq}`eq-x` and\n<a href="other.html#fig-live">the live figure</a>.\n\n'
        "{numref}`code-x` and {numref}`Listing {number} again <code-x>`.\n"
    )
    warnings = io.StringIO()
    with docutils_namespace():  # the directives and nodes it registers go with it
        app = Sphinx(
            str(src),
            str(src),
            str(tmp / "out"),
            str(tmp / "doctrees"),
            "html",
            status=None,
            warning=warnings,
            freshenv=True,
        )
        app.build()
    assert not warnings.getvalue()
    return tmp / "out"


def test_no_font_awesome_script(built):
    for page in ("index.html", "other.html", "plain.html"):
        html = (built / page).read_text()
        assert not [s for s in _scripts(html) if "fontawesome" in s], page
        # the theme's stylesheet (with Font Awesome's CSS and web font) still draws the icons
        assert "styles/pydata-sphinx-theme.css" in html and 'class="fa-solid fa-bars"' in html


def test_icon_font_holds_the_icons_the_pages_use(built):
    from fontTools.ttLib import TTFont

    html = (built / "index.html").read_text()
    assert "_static/fdi-icons.css" in html
    font = TTFont(built / "_static" / "fdi-icons.woff")
    icons = set(font.getBestCmap())
    # the header's menu (fa-bars) and search (fa-magnifying-glass), the theme's note icon
    # (--pst-icon-info-circle, drawn by its stylesheet), the scripts' close button (fa-xmark)
    assert {0xF0C9, 0xF002, 0xF05A, 0xF00D} <= icons
    assert 0xF1B9 not in icons  # fa-car: no page shows it
    assert font.flavor == "woff" and (built / "_static" / "fdi-icons.woff").stat().st_size < 10_000


def test_mathjax_only_on_pages_with_maths(built):
    other, index = (built / "other.html").read_text(), (built / "index.html").read_text()
    assert [s for s in _scripts(other) if s.endswith("mathjax/tex-chtml.js")]
    assert "window.fdiMathJax" not in other
    for page in ("index.html", "plain.html"):
        html = (built / page).read_text()
        assert not [s for s in _scripts(html) if "mathjax" in s], page
        assert "window.MathJax" not in html, page
        # the previews' MathJax, loaded on demand: where it is, and the book's macros
        lazy = json.loads(re.search(r"window\.fdiMathJax = (\{.*?\})</script>", html).group(1))
        assert lazy["src"].endswith("mathjax/tex-chtml.js")
        assert lazy["config"]["tex"]["macros"]["R"] == "\\mathbb{R}"
    assert 'src="_static/../mathjax/tex-chtml.js"' not in index


def test_previews_are_served_from_the_build(built):
    html = (built / "plain.html").read_text()
    scripts = _scripts(html)
    assert not [s for s in scripts if s.startswith(("http:", "https:", "//"))]
    names = [s.split("?")[0].rsplit("/", 1)[-1] for s in scripts]
    tippy_at = names.index("tippy-bundle.umd.min.js")
    assert names.index("popper.min.js") < tippy_at < names.index("fdi-previews.js")
    for name in ("popper.min.js", "tippy-bundle.umd.min.js"):
        assert (built / "_static" / "vendor" / "tippy" / name).stat().st_size > 10_000
    assert (built / "_static" / "fdi-previews.js").is_file()
    assert "_static/fdi-previews.css" in html


def test_previews_hold_the_target_without_its_scripts(built):
    tips = next((built / "_static" / "tippy").glob("plain.*.js")).read_text()
    assert 'a[href=\\"other.html#equation-eq-x\\"]' in tips and "x_k \\\\in \\\\R^n" in tips
    assert 'a[href=\\"other.html#fig-live\\"]' in tips and "Live" in tips
    assert "MANY-FRAMES" not in tips and "<script" not in tips


def test_figure_references_are_numbered_from_the_cached_targets(built):
    html = (built / "plain.html").read_text()
    assert html.count('href="other.html#code-x"') == 2
    assert "Listing 1</span>" in html and "Listing 1 again</span>" in html


def test_figures_are_numbered_from_the_pages_in_memory():
    """Item 17: while Sphinx numbers the figures (``env-get-updated``), a page read by this build
    is the doctree in memory; any other is unpickled; afterwards every page is unpickled again."""
    from docutils.utils import new_document

    read, pickled = new_document("read"), new_document("pickled")

    class Env:
        _write_doc_doctree_cache = {"read": read}

        def get_doctree(self, docname):
            return pickled

    env = Env()
    assert EXT._doctrees_in_memory(None, env) == []
    assert env.get_doctree("read") is read and env.get_doctree("earlier") is pickled
    assert EXT._doctrees_from_disk(None, env) == []
    assert "get_doctree" not in vars(env) and env.get_doctree("read") is pickled


def test_bibliography_text_without_looking_up_plugins(built, monkeypatch):
    """The labels' plain text (:func:`_plain`) and sphinxcontrib-bibtex's plain-text backend
    (registered by the extension's setup, which ``built`` ran) come without a look-up among the
    installed packages' entry points (4 ms each)."""
    import pybtex.plugin
    from pybtex.backends.plaintext import Backend
    from pybtex.richtext import Text

    latex = [
        r"Basseville and Nikiforov",
        r"{\'E}mile Zola",
        r"Zhang {\textendash} Rosa",
        r"M{\"u}ller",
    ]
    expected = [Text.from_latex(t).render_as("text") for t in latex]

    def no_entry_points(**kwargs):
        raise AssertionError(f"entry points looked up: {kwargs}")

    monkeypatch.setattr(pybtex.plugin, "entry_points", no_entry_points)
    assert [EXT._plain(t) for t in latex] == expected
    assert expected[1] == "Émile Zola" and expected[3] == "Müller"
    assert pybtex.plugin.find_plugin("pybtex.backends", "plaintext") is Backend


def test_target_stubs_number_as_the_nodes_they_copy():
    from docutils import nodes
    from docutils.utils import new_document
    from sphinx.domains.std import StandardDomain

    doc = new_document("page")
    code = nodes.container("", nodes.caption("", "Code"), nodes.literal_block("x", "x"))
    code["literal_block"] = True
    plain = nodes.container("", nodes.paragraph("", "text"))
    plain["literal_block"] = True
    figure = nodes.figure("", nodes.image(uri="a.png"), nodes.caption("", "A"))
    for ident, node in (("code", code), ("plain", plain), ("fig", figure)):
        node["ids"] = [ident, ident + "-2"]
        doc += node
        doc.note_implicit_target(node)
    stubs = EXT._target_stubs(doc)
    assert set(stubs.ids) == set(doc.ids) and not stubs.children
    domain = type("D", (), {"enumerable_nodes": StandardDomain.enumerable_nodes})()

    def kinds(ids):
        return {i: StandardDomain.get_enumerable_node_type(domain, n) for i, n in ids.items()}

    assert kinds(stubs.ids) == kinds(doc.ids)
    assert {kinds(doc.ids)[i] for i in ("code", "fig", "plain")} == {"code-block", "figure"}
    assert [type(c) for c in stubs.ids["code"]] == [nodes.caption, nodes.literal_block]
    assert not stubs.ids["code"][0].children  # the children's own children are not copied
    assert stubs.ids["fig"]["ids"] == ["fig", "fig-2"] and stubs.ids["fig"].parent is None


def test_shown_previews_are_those_a_link_points_to():
    pages = {
        "a": {
            "refs_in_page": {(None, "x"), ("b", "y2"), ("b", None), ("b", "gone"), ("c", "z")},
            "element_id_map": {"x": "x"},
            "id_to_html": {None: "A", "x": "X", "unused": "U"},
        },
        "b": {
            "refs_in_page": set(),
            "element_id_map": {"y": "y", "y2": "y", "gone": "gone"},
            "id_to_html": {None: "B", "y": "Y", "other": "O"},
        },
    }
    assert EXT.shown_previews(pages) == {("a", "x"), ("b", "y"), ("b", None)}


def test_preview_html_drops_scripts_sliders_and_permalinks():
    html = (
        '<figure class="fdi-explorable" id="f"><div class="fdi-explorable-sliders"><input type="range">'
        '</div><img src="data:image/png;base64,AAAA" alt="x"><script>var F = [1, 2];</script>'
        '<figcaption>Caption <a class="headerlink" href="#f">#</a></figcaption></figure>'
    )
    out = EXT.preview_html(html)
    assert "<script" not in out and "range" not in out and "headerlink" not in out
    assert '<img alt="x" src="data:image/png;base64,AAAA"/>' in out and "Caption" in out
    # an image file is fetched only when its preview is shown
    assert EXT.preview_html('<figure id="g"><img alt="y" src="../_images/g.png"/></figure>') == (
        '<figure id="g"><img alt="y" loading="lazy" src="../_images/g.png"/></figure>'
    )


def test_preview_html_returns_a_preview_with_nothing_to_drop_unparsed_and_the_same():
    from bs4 import BeautifulSoup

    html = '<p id="p">A <em>paragraph</em> &amp; <span class="math">\\(x &lt; 1\\)</span></p>'
    assert EXT.preview_html(html) is html
    assert str(BeautifulSoup(html, "html.parser")) == html  # what parsing would have given
    # any of what it drops or changes is parsed, whatever its case
    assert EXT.preview_html('<p id="q">x<SCRIPT>1</SCRIPT></p>') == '<p id="q">x</p>'


def test_without_script_drops_one_tag_and_fails_when_there_is_none():
    head = (
        '<link href="a.css" rel="stylesheet" />\n  <script defer src="../_static/scripts/fontawesome.js'
        '?digest=55c"></script>\n  <link rel="preload" as="script" href="b.js" />'
    )
    out = EXT.without_script(head, "scripts/fontawesome.js")
    assert "fontawesome" not in out and 'href="a.css"' in out and 'href="b.js"' in out
    with pytest.raises(EXT.ExtensionError, match="fontawesome"):
        EXT.without_script(out, "scripts/fontawesome.js")


def test_execution_times_from_the_build_log():
    log = (
        f"{ROOT}/book/zb2014/glr.md: Executing notebook using local CWD [mystnb]\n"
        f"{ROOT}/book/zb2014/glr.md: Executed notebook in 12.50 seconds [mystnb]\n"
        f"{ROOT}/book/status.md: Using cached notebook: ID=3 [mystnb]\n"
        f"{ROOT}/book/intro.md: Executed notebook in 0.75 seconds [mystnb]\n"
    )
    assert REPORT.execution_times(log, ROOT) == {"book/zb2014/glr.md": 12.5, "book/intro.md": 0.75}
    assert REPORT.execution_wall(log) is None
    # tools/execute_book.py's lines (the chapters side by side, before Jupyter Book)
    log = (
        "Executing 2 notebooks, 2 at a time on 2 cores\n"
        "book/zb2014/glr.md: Executed notebook in 7.25 seconds (on 1 core)\n"
        "book/zz-ledger.md: Executed notebook in 2.00 seconds (on 2 cores)\n"
        "Executed 2 notebooks in 9.5 s of wall time (9.2 s summed over the chapters)\n"
    )
    assert REPORT.execution_times(log, ROOT) == {
        "book/zb2014/glr.md": 7.25,
        "book/zz-ledger.md": 2.0,
    }
    assert REPORT.execution_wall(log) == 9.5


def test_inject_replaces_the_placeholder_only(tmp_path):
    page = tmp_path / "status.html"
    page.write_text('<p>a</p><div id="fdi-x"><p>Not filled in</p></div><!-- /fdi-x --><div>b</div>')
    REPORT.inject(page, "fdi-x", "<div><table><tr><td>1 s</td></tr></table></div>")
    REPORT.inject(page, "fdi-x", "<div><table><tr><td>2 s</td></tr></table></div>")  # again
    assert page.read_text() == (
        '<p>a</p><div id="fdi-x"><div><table><tr><td>2 s</td></tr></table></div>'
        "</div><!-- /fdi-x --><div>b</div>"
    )
    with pytest.raises(SystemExit, match="fdi-y"):
        REPORT.inject(page, "fdi-y", "")


def test_status_page_has_the_placeholders():
    text = (ROOT / "book" / "status.md").read_text()
    for ident in ("fdi-build-time", "fdi-page-weights"):
        assert re.search(rf'<div id="{ident}">.*?</div><!-- /{ident} -->', text, re.S), ident


def test_the_pdf_script_page_weights_exempts_is_the_one_make_pdf_writes(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT / "tests" / "browser"))
    pw = _load("fdi_page_weights", ROOT / "tests" / "browser" / "page_weights.py")
    EXT.publish_pdf(tmp_path, None)
    assert [p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*.js")] == list(
        pw.AFTER_BUILD
    )


def test_page_weights_reopen_only_what_changed_since_the_build(tmp_path, monkeypatch):
    """``page_weights.py --report``: a page measured by ``make book`` is reused while its HTML has
    the same SHA-1 and every file it loaded the same size; any change has it measured again."""
    import hashlib

    monkeypatch.syspath_prepend(str(ROOT / "tests" / "browser"))
    pw = _load("fdi_page_weights", ROOT / "tests" / "browser" / "page_weights.py")
    root = tmp_path / "html"
    (root / "book").mkdir(parents=True)
    (root / "_static").mkdir()
    (root / "index.html").write_text('<meta http-equiv="Refresh" content="0; url=book/a.html">')
    page, script = root / "book" / "a.html", root / "_static" / "x.js"
    page.write_text("<p>a</p>")
    script.write_text("x" * 10)
    w = {
        "page": "book/a.html",
        "bytes": 18,
        "by_kind": {"html": 8, "script": 10},
        "assets": [["_static/x.js", 10], ["book/a.html", 8]],
        "has_math": False,
        "sha1": hashlib.sha1(b"<p>a</p>").hexdigest(),
    }
    assert pw.unchanged(w, root)
    assert not pw.unchanged({**w, "sha1": None}, root)  # a report without hashes
    script.write_text("x" * 11)
    assert not pw.unchanged(w, root)
    script.write_text("x" * 10)
    page.write_text("<p>b</p>")  # same size, other bytes
    assert not pw.unchanged(w, root)
    page.write_text("<p>a</p>")
    # the PDF edition's script, rewritten by make pdf after the build: reused, its size read again
    pdf_js = root / pw.AFTER_BUILD[0]
    pdf_js.write_text("y" * 4)
    with_pdf = {
        **w,
        "bytes": 22,
        "by_kind": {"html": 8, "script": 14},
        "assets": [["_static/x.js", 10], ["book/a.html", 8], [pw.AFTER_BUILD[0], 4]],
    }
    pdf_js.write_text("y" * 40)
    assert pw.unchanged(with_pdf, root)
    assert pw.resized(with_pdf, root) == {
        **with_pdf,
        "bytes": 58,
        "by_kind": {"html": 8, "script": 50},
        "assets": [[pw.AFTER_BUILD[0], 40], ["_static/x.js", 10], ["book/a.html", 8]],
    }
    assert pw.resized(w, root) == w  # the same sizes: the same measurement
    pdf_js.unlink()
    assert not pw.unchanged(with_pdf, root)  # a file gone is a change

    report = tmp_path / "build-report.json"
    report.write_text(json.dumps({"pages": [w]}))
    asked = []

    def measure(root, pages):
        asked.append(list(pages))
        return [{**w, "page": p, "bytes": 6e6, "assets": [[p, 6_000_000]]} for p in pages]

    monkeypatch.setattr(pw, "measure", measure)
    assert pw.main(["--html", str(root), "--report", str(report)]) == 0
    assert asked == [[]]
    page.write_text("<p>c</p>")
    assert pw.main(["--html", str(root), "--report", str(report)]) == 1  # measured: 6 MB > budget
    assert asked[-1] == ["book/a.html"]
