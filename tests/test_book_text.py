"""Maths as readable text in the built book (``_ext/fdi_book.py``, item 8): references to a heading
with maths, the alt text of figures (from their captions, also the explorables'), and the
catalogue's headings. The real-browser check of the whole book is ``tests/browser/check_book.py``
(``macro`` and ``alt``)."""

from __future__ import annotations

import base64
import importlib.util
import inspect
import io
import re
from pathlib import Path

import pytest

from fdi_lib.explorables import caption_text, explorable, script_text
from fdi_lib.plotting import figure
from fdi_lib.reproduce import list_reproductions

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("fdi_book_text_ext", ROOT / "_ext" / "fdi_book.py")
EXT = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(EXT)
MACROS = {"R": r"\mathbb{R}", "T": r"\mathsf{T}", "E": r"\mathbb{E}"}  # as _config.yml


@pytest.mark.parametrize(
    "tex, text",
    [
        (r"\lambda", "λ"),
        (r"\theta = [4, 0]", "θ = [4, 0]"),
        (r"\hat\theta_j", "θ̂ⱼ"),
        (r"\hat{r}", "r̂"),
        (r"\|\alpha_k(r)\|_2", "‖αₖ(r)‖₂"),
        (r"W_k \sim \mathcal N(0, Q_k)", "Wₖ ~ N(0, Qₖ)"),
        (r"x \in \R^n, A^\T", "x ∈ ℝⁿ, Aᵀ"),
        (r"\chi^2(2)", "χ²(2)"),
        (r"C_k(r)^{-1}", "Cₖ(r)⁻¹"),
        (r"X_{k|k-1}", "X_(k|k-1)"),  # no Unicode subscript for "|": written out
        (r"l_N", "l_N"),
        (r"\frac{1}{2}\,\sigma^2", "1/2 σ²"),
        (r"N > 1", "N > 1"),
        (r"\left( a \right) \foo", "( a ) foo"),  # an unknown command: its name, no backslash
    ],
)
def test_tex_to_text(tex, text):
    assert EXT.tex_to_text(tex, MACROS) == text


def test_script_text_and_caption_text():
    assert script_text("k", "_") == "ₖ" and script_text("-1", "^") == "⁻¹"
    assert script_text("N", "_") == "_N" and script_text("k|k", "_") == "_(k|k)"
    assert (
        caption_text("Spectral norms of Γ<sub>k</sub>(r) &amp; x<sup>2</sup>, <i>w</i>\n = 1")
        == "Spectral norms of Γₖ(r) & x², w = 1"
    )


def _frame(a, fig=None):
    fig, ax = figure(fig=fig)
    ax[0, 0].plot([0.0, 1.0], [0.0, a])
    return fig


def test_explorable_image_without_alt_text_has_its_caption_and_the_values_shown():
    page = explorable(
        _frame, {"a": (1.0, 2.0)}, caption='GLR l<sub>k</sub> for "w" &lt; 3'
    )._repr_html_()
    assert (
        re.search(r'<img [^>]*alt="([^"]*)"', page).group(1)
        == "GLR lₖ for &quot;w&quot; &lt; 3. Shown at a = 1."
    )


def test_catalogue_titles_are_written_in_maths():
    assert (
        EXT.title_markdown(
            "Spectral norm of Willsky-Jones alpha_k(r), GLR l_k, theta = [4, 0], "
            "dG0(1), Set(P, p), r = 1"
        )
        == r"Spectral norm of Willsky-Jones $\alpha_k(r)$, GLR $l_k$, $\theta$ = [4, 0], dG0(1), Set(P, p), r = 1"
    )
    greek = re.compile(r"\b(?:" + "|".join(EXT._GREEK + [g.title() for g in EXT._GREEK]) + r")\b")
    for r in list_reproductions():
        text = re.sub(r"\$[^$]*\$", "", EXT.title_markdown(r.title))  # what is left outside maths
        assert not re.search(r"[A-Za-z]_\w", text) and not greek.search(text), (r.id, text)


def _sphinx_build(
    tmp_path, builder: str, extensions: list[str], pages: dict[str, str], conf: str = ""
) -> tuple[Path, str]:
    """A small Sphinx project with the book's extension, built with ``builder``: the output
    folder and the warnings."""
    from sphinx.application import Sphinx
    from sphinx.util.docutils import docutils_namespace

    src = tmp_path / "src"
    src.mkdir()
    (src / "conf.py").write_text(
        f"import sys\nsys.path.insert(0, {str(ROOT / '_ext')!r})\n"
        f"extensions = {extensions!r}\n" + conf
    )
    for name, text in pages.items():
        (src / name).write_text(text)
    warnings = io.StringIO()
    with docutils_namespace():  # the directives and nodes it registers go with it
        app = Sphinx(
            str(src),
            str(src),
            str(tmp_path / "out"),
            str(tmp_path / "doctrees"),
            builder,
            status=None,
            warning=warnings,
            freshenv=True,
        )
        app.build()
    return tmp_path / "out", warnings.getvalue()


# a 1x1 PNG
_PNG = base64.b64decode(
    "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAAAAAA6fptVAAAACklEQVR4nGP4DwABAQEAG1o0oAAAAABJRU5ErkJggg=="
)


def test_references_and_alt_texts_in_a_sphinx_build(tmp_path):
    """A two-page project built with the extension: a ``{ref}`` to a heading with maths reads
    "The rule for λ", and a figure without ``:alt:`` has its caption as alt text."""
    from sphinx.application import Sphinx
    from sphinx.util.docutils import docutils_namespace

    src = tmp_path / "src"
    src.mkdir()
    (src / "conf.py").write_text(
        "import sys\n"
        f"sys.path.insert(0, {str(ROOT / '_ext')!r})\n"
        "extensions = ['myst_parser', 'fdi_book']\n"
        "myst_enable_extensions = ['dollarmath']\n"
        f"mathjax3_config = {{'tex': {{'macros': {MACROS!r}}}}}\n"
    )
    (src / "fig.png").write_bytes(_PNG)
    (src / "index.md").write_text(
        "# Index\n\n```{toctree}\nother\n```\n\n(lambda-rule)=\n## The rule for $\\lambda$\n\n"
        "```{figure} fig.png\n:name: fig-a\n\nInnovation $\\varepsilon_k$ and GLR $l_k$ for "
        "$\\theta = [4, 0]$.\n```\n\n```{figure} fig.png\n:alt: own words\n\nKept.\n```\n"
    )
    (src / "other.md").write_text("# Other\n\nSee {ref}`lambda-rule`.\n")
    warnings = io.StringIO()
    with docutils_namespace():  # the directives and nodes it registers go with it
        app = Sphinx(
            str(src),
            str(src),
            str(tmp_path / "out"),
            str(tmp_path / "doctrees"),
            "xml",
            status=None,
            warning=warnings,
            freshenv=True,
        )
        app.build()
    assert not warnings.getvalue()
    other = (tmp_path / "out" / "other.xml").read_text()
    assert "The rule for λ" in other and "\\lambda" not in other
    alts = re.findall(r'<image alt="([^"]*)"', (tmp_path / "out" / "index.xml").read_text())
    assert alts == ["Innovation εₖ and GLR lₖ for θ = [4, 0].", "own words"]


def test_table_cells_carry_their_column_header_in_html(tmp_path):
    """Docutils tables of the book (Markdown tables, list-tables) written to HTML: every body
    cell has its column's header as ``data-label``, maths as readable text (item 9)."""
    out, warnings = _sphinx_build(
        tmp_path,
        "html",
        ["myst_parser", "fdi_book"],
        {
            "index.md": "# Index\n\n| Symbol | Size of $\\theta_k$ |\n|---|---|\n"
            "| $X_k$ | $n$ |\n| $U_k$ | |\n"
        },
        "myst_enable_extensions = ['dollarmath']\n",
    )
    assert not warnings
    page = (out / "index.html").read_text()
    assert re.findall(r'<td data-label="([^"]*)"', page) == ["Symbol", "Size of θₖ"] * 2
    assert "<th" in page and not re.search(r"<th[^>]*data-label", page)


def test_explorable_output_becomes_a_numbered_figure():
    """The cell output of an explorable (a myst-nb MIME bundle with its HTML) is wrapped in a
    figure labelled fig-<page>-explore, with the explorable's caption as text; the HTML keeps
    no caption of its own and no nested figure (item 10)."""
    from types import SimpleNamespace

    from docutils import nodes
    from docutils.frontend import get_default_settings
    from docutils.parsers.rst import Parser
    from docutils.utils import new_document

    doc = new_document("glr", get_default_settings(Parser))
    doc.settings.env = SimpleNamespace(docname="book/zb2014/glr")
    pages = [
        explorable(_frame, {"a": (1.0, 2.0)}, caption=f"GLR l<sub>k</sub>, case {i}")._repr_html_()
        for i in (1, 2)
    ]
    for html in pages:
        bundle = nodes.container(nb_element="mime_bundle")
        bundle += nodes.container("", nodes.raw(html, html, format="html"), mime_type="text/html")
        doc += bundle
    EXT.NumberedExplorables(doc).apply()
    figures = list(doc.findall(nodes.figure))
    assert [f["names"] for f in figures] == [["fig-glr-explore"], ["fig-glr-explore-2"]]
    assert [f["ids"] for f in figures] == [["fig-glr-explore"], ["fig-glr-explore-2"]]
    assert [f[-1].astext() for f in figures] == ["GLR lₖ, case 1", "GLR lₖ, case 2"]
    html = next(figures[0].findall(nodes.raw)).astext()
    assert (
        "<figcaption>" not in html
        and "<figure" not in html
        and '<div class="fdi-explorable"' in html
    )


def _toc(tmp_path, parts: str) -> Path:
    (tmp_path / "_toc.yml").write_text("format: jb-book\nroot: book/intro\nparts:\n" + parts)
    return tmp_path


_PARTS = (
    "  - caption: Start\n    chapters:\n      - file: book/running\n"
    "  - caption: A paper\n    numbered: true\n    chapters:\n      - file: book/p/one\n"
    "      - file: book/p/two\n"
)


def test_book_map_lists_every_page_of_the_toc_and_the_numbered_ones_in_order(tmp_path):
    block = (
        "book/running: how to run\nbook/p/one: the first chapter\n  {cite:p}`key`\n"
        "book/p/two: the second\n"
    )
    text = EXT.book_map_markdown(_toc(tmp_path, _PARTS), block)
    rows = [r for r in text.splitlines() if r.startswith("| ") and "doc" in r]
    assert rows == [
        "| Start | {doc}`/book/running` | how to run |",
        "| A paper | {doc}`/book/p/one` | the first chapter {cite:p}`key` |",
        "|  | {doc}`/book/p/two` | the second |",
    ]
    assert text.endswith("1. {doc}`/book/p/one`\n2. {doc}`/book/p/two`\n")
    (tmp_path / "book").mkdir()
    (tmp_path / "book" / "running.md").write_text("---\nx: 1\n---\n# Running it\n")
    unlinked = EXT.book_map_markdown(tmp_path, block, unlinked=("book/running",))
    assert "| Start | Running it | how to run |" in unlinked  # no chapter of its own in the PDF


@pytest.mark.parametrize(
    "block, message",
    [
        ("book/running: x\nbook/p/one: y\n", r"missing \['book/p/two'\]"),  # a chapter left out
        (
            "book/running: x\nbook/p/one: y\nbook/p/two: z\nbook/p/old: w\n",
            r"not in _toc.yml \['book/p/old'\]",
        ),
        ("book/running x\n", "expected 'FILE: what it holds'"),
    ],
)
def test_book_map_fails_when_it_and_the_toc_disagree(tmp_path, block, message):
    from sphinx.errors import ExtensionError

    with pytest.raises(ExtensionError, match=message):
        EXT.book_map_markdown(_toc(tmp_path, _PARTS), block)


def test_the_intro_has_a_book_map_line_for_every_page_of_the_toc():
    intro = (ROOT / "book" / "intro.md").read_text()
    blocks = EXT._MAP_BLOCK.findall(intro)
    assert len(blocks) == 1
    text = EXT.book_map_markdown(ROOT, blocks[0])
    assert "{doc}`/book/windturbine/benchmark`" in text
    # a title with code links by its Markdown, which keeps the code (issue 33)
    assert "[The library `fdi_lib`](/book/api/index.md)" in text
    assert "static figure at default values" not in intro


def test_hidden_cell_toggle_is_named_by_its_text_and_citations_are_list_items(tmp_path):
    """The fold of a hidden cell has no aria-label hiding its visible prompt; a bibliography's
    entries are the list items of its role="list" (not the deprecated doc-biblioentry)."""
    from types import SimpleNamespace

    fake = SimpleNamespace(body=[])
    node = {
        "classes": ["above-input"],
        "prompt_show": "Show code cell source",
        "prompt_hide": "Hide code cell <source>",
    }
    EXT._visit_hidden_cell(fake, node)
    html = "".join(fake.body)
    assert "aria-label" not in html
    assert html.startswith('<details class="admonition hide above-input">')
    assert '<p class="collapsed admonition-title">Show code cell source</p>' in html
    assert "Hide code cell &lt;source&gt;" in html

    out, _ = _sphinx_build(
        tmp_path,
        "html",
        ["myst_nb", "fdi_book"],
        {"index.rst": "Index\n=====\n\nSee [A]_ and [B]_.\n\n.. [A] One.\n.. [B] Two.\n"},
    )
    page = (out / "index.html").read_text()
    assert page.count('role="list"') == 1 and page.count('role="listitem"') == 2
    assert "doc-biblioentry" not in page


def test_pages_link_the_pdf_of_an_earlier_make_pdf(tmp_path):
    from types import SimpleNamespace

    html = tmp_path / "_build" / "html"
    html.mkdir(parents=True)
    app = SimpleNamespace(outdir=str(html), builder=SimpleNamespace(format="html"))
    EXT._pdf_script(app, None)
    assert "const pdf = null, a4 = null;" in (html / "_static" / EXT.PDF_SCRIPT).read_text()
    (tmp_path / "_build" / "pdf").mkdir()
    (tmp_path / "_build" / "pdf" / EXT.PDF_NAME).write_bytes(b"%PDF-1.5 edition")
    EXT._pdf_script(app, None)
    script = (html / "_static" / EXT.PDF_SCRIPT).read_text()
    assert f'const pdf = "{EXT.PDF_NAME}", a4 = null;' in script
    assert (html / EXT.PDF_NAME).read_bytes() == b"%PDF-1.5 edition"


def test_catalogue_docstrings_have_their_names_as_code_and_their_maths_as_maths():
    """docstring_rst (issue 33): the names of numpydoc entries and worded subscripts become
    literals, ASCII symbols and norms become :math:, literals already there stay; and no
    TeX-like token is left outside them in any registered reproduction's docstring."""
    assert EXT.docstring_rst(
        "flat_size_linear : int\nlambda_mid : float\n    Middle of ``flat_range``.\n"
        "Area of X_{+1}; hull_area - union_area; max_k ||Gamma_k||_2 for R = r I_2, n_A = 1."
    ) == (
        "``flat_size_linear`` : int\n``lambda_mid`` : float\n    Middle of ``flat_range``.\n"
        r"Area of :math:`X_{+1}`; ``hull_area`` - ``union_area``; :math:`\max_k` "
        r":math:`\|\Gamma_k\|_2` for R = r :math:`I_2`, :math:`n_A` = 1."
    )
    tex_like = re.compile(
        r"\b[A-Za-z][A-Za-z0-9]*(?:_(?:\{|[A-Za-z0-9])|\^(?:\{|[A-Za-z0-9(]))|\|\|"
    )
    for r in list_reproductions():
        text = EXT.docstring_rst(inspect.getdoc(r.func) or "")
        left = re.sub(r"``[^`]+``|:\w+:`[^`]+`", "", text)
        assert not tex_like.search(left), (r.id, tex_like.findall(left)[:5])
