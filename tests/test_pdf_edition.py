"""The PDF edition's LaTeX side (``_ext/fdi_book.py``, item 9) and the tools of ``make pdf``: a
small project built with Sphinx's LaTeX builder (and compiled by xelatex when TeX Live is
installed) has the book's macros, citations in captions that compile, an explorable as a figure
with its caption, and the cover with the ledger counts; the cache of ``tools/pdf_edition.py``
gives back the glued values of an executed notebook. The whole book's PDF is checked by
``tools/check_pdf.py`` (``make pdf``)."""

from __future__ import annotations

import io
import json
import os
import re
import shutil
import subprocess
from pathlib import Path
from types import SimpleNamespace

import pytest

from fdi_lib.explorables import explorable
from fdi_lib.plotting import figure
from fdi_lib.reproduce.ledger_claims import PAPERS, STATUSES

from source_module import load as _load  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


EXT = _load("fdi_book_pdf_ext", ROOT / "_ext" / "fdi_book.py")
TOOL = _load("fdi_pdf_edition", ROOT / "tools" / "pdf_edition.py")
#: Script characters in one line: "ₖ" is in no face of FreeFont, "ᵀ" only in FreeSerif and
#: FreeSerif Bold; "₂" and "⁻" are in all of them.
SCRIPTED = "Kₖ, Hᵀ, e₂, Hₖᵀ"
MACROS = {
    "R": r"\mathbb{R}",
    "T": r"\mathsf{T}",
    "E": r"\mathbb{E}",
    "norm": [r"\lVert #1 \rVert", 1],
}


def test_latex_macros_are_the_mathjax_macros():
    config = SimpleNamespace(mathjax3_config={"tex": {"macros": MACROS}})
    lines = EXT.latex_macros(config).splitlines()
    assert lines == [
        r"\providecommand{\R}{}\renewcommand{\R}{\mathbb{R}}",
        r"\providecommand{\T}{}\renewcommand{\T}{\mathsf{T}}",
        r"\providecommand{\E}{}\renewcommand{\E}{\mathbb{E}}",
        r"\providecommand{\norm}{}\renewcommand{\norm}[1]{\lVert #1 \rVert}",
    ]


def _line(a, fig=None):
    fig, ax = figure(fig=fig)
    ax[0, 0].plot([0.0, 1.0], [0.0, a])
    return fig


@pytest.mark.filterwarnings(
    "ignore:nodes.Node.traverse:PendingDeprecationWarning"
)  # sphinx-jupyterbook-latex's
def test_latex_build_of_a_small_book(tmp_path):
    """Macros in the preamble, a cited caption protected, an explorable's small multiples as a
    figure with its caption, the cover with the ledger counts; compiled when xelatex exists,
    with the script characters that FreeFont lacks ("ₖ"; "ᵀ" outside upright serif) typeset
    in a caption, a heading, a table cell, bold and italic text and a code listing, with the
    book's LaTeX extension (sphinx-jupyterbook-latex, which loads ucharclasses after the
    preamble)."""
    from sphinx.application import Sphinx
    from sphinx.util.docutils import docutils_namespace

    src = tmp_path / "src"
    src.mkdir()
    (src / "conf.py").write_text(
        "import sys\n"
        f"sys.path.insert(0, {str(ROOT / '_ext')!r})\n"
        "project = 'fdi-book: a test'\n"
        "extensions = ['myst_parser', 'sphinxcontrib.bibtex', 'sphinx_jupyterbook_latex', 'fdi_book']\n"
        "myst_enable_extensions = ['dollarmath']\n"
        "bibtex_bibfiles = ['refs.bib']\nbibtex_reference_style = 'author_year'\n"
        "latex_engine = 'xelatex'\nlatex_use_xindy = False\n"
        "latex_documents = [('index', 'fdi-book.tex', 'T', 'A', 'manual')]\n"
        f"mathjax3_config = {{'tex': {{'macros': {MACROS!r}}}}}\n"
    )
    (src / "refs.bib").write_text(
        "@article{zb2014, author = {Zhang, Q. and Basseville, M.}, title = {T},"
        " journal = {J}, year = {2014}}\n"
    )
    ex = explorable(
        _line,
        {"a": (1.0, 2.0, 3.0)},
        caption="toy Γ<sub>k</sub> &amp; more",
        labels={"a": "slope a"},
    )
    (src / "sm.png").write_bytes(ex.small_multiples())
    (src / "index.md").write_text(
        "# Index\n\nMaths $x \\in \\R^n$, $A^\\T$, $\\norm{x}$.\n\n"
        "```{figure} sm.png\n:name: fig-a\n\nAs paper Fig. 1 of {cite:t}`zb2014`, Γₖ(r).\n```\n\n"
        "```{image} sm.png\n```\n\n"
        f"## Gains {SCRIPTED}\n\n| gain | value |\n|---|---|\n| {SCRIPTED} | 10⁻⁴ |\n\n"
        f"**{SCRIPTED}** *{SCRIPTED}* ***{SCRIPTED}***\n\n```\n{SCRIPTED}\n```\n\n"
        "```{bibliography}\n```\n"
    )
    counts = {p: {s: i + j for j, s in enumerate(STATUSES)} for i, p in enumerate(PAPERS)}
    glue = tmp_path / "build" / "jupyter_execute" / "book" / "zz-ledger.glue.json"
    glue.parent.mkdir(parents=True)
    glue.write_text(json.dumps({EXT.LEDGER_GLUE: {"data": {"text/plain": repr(counts)}}}))
    out = tmp_path / "build" / "latex"
    warnings = io.StringIO()
    with docutils_namespace():  # no node or directive left registered for the next Sphinx app
        app = Sphinx(
            str(src),
            str(src),
            str(out),
            str(tmp_path / "doctrees"),
            "latex",
            status=None,
            warning=warnings,
            freshenv=True,
        )
        app.build()
    # a Sphinx app built earlier in the same process (tests/test_book_text.py) leaves its nodes
    # registered: the notices that they are registered again are not problems of this build
    assert [w for w in warnings.getvalue().splitlines() if "is already registered" not in w] == []
    tex = (out / "fdi-book.tex").read_text()
    assert (
        r"\renewcommand{\T}{\mathsf{T}}" in tex
        and r"\renewcommand{\norm}[1]{\lVert #1 \rVert}" in tex
    )
    assert (out / "bbm.sty").read_text().startswith(r"\ProvidesPackage{bbm}")
    caption = re.search(r"\\caption\{As paper Fig\. 1 of (.*)\}\\label", tex).group(1)
    assert r"\protect\hyperlink{cite." in caption
    # the plain image of the small multiples became a figure with the explorable's caption
    figures = re.findall(r"\\begin\{figure\}.*?\\end\{figure\}", tex, re.S)
    assert len(figures) == 2 and r"\caption{toy Γ$_{\text{k}}$ \& more}" in figures[1]
    # the cover: every status with its counts per paper and in all
    for status in STATUSES:
        n = [counts[p][status] for p in PAPERS]
        assert " & ".join([status.replace("&", r"\&"), *map(str, n), str(sum(n))]) + r" \\" in tex
    assert "PDF edition, version" in tex
    if shutil.which("xelatex") and shutil.which("latexmk"):
        env = dict(os.environ, LATEXOPTS="-interaction=nonstopmode -halt-on-error")
        done = subprocess.run(["make", "all-pdf"], cwd=out, env=env, capture_output=True, text=True)
        log = (out / "fdi-book.log").read_text(errors="replace")
        assert done.returncode == 0, "\n".join(re.findall(r"^!.*$", log, re.M))
        check = _load("fdi_check_pdf_small", ROOT / "tools" / "check_pdf.py")
        assert check.missing_characters(log) == {}
        if shutil.which("pdftotext"):
            text = check.run("pdftotext", "-enc", "UTF-8", str(out / "fdi-book.pdf"), "-")
            assert text.count("Kₖ") >= 6 and text.count("Hᵀ") >= 6 and "Γₖ(r)" in text
        if shutil.which("pdfimages"):  # the small multiples print at 8 pt or more
            fonts = check.printed_fonts(out / "fdi-book.tex", out / "fdi-book.pdf")
            assert len(fonts) == 2 and check.font_problems(fonts) == []
            assert min(fonts.values()) >= check.PRINTED_MIN_FONT_PT


def test_the_cache_gives_back_glued_values(tmp_path):
    """An executed notebook as myst-nb writes it (glue outputs taken out, kept in .glue.json)
    goes into the cache with them put back, under the hash of its code cells."""
    import nbformat
    from jupyter_cache import get_cache

    nb = nbformat.v4.new_notebook(
        metadata={
            "kernelspec": {"name": "python3", "display_name": "Python 3", "language": "python"}
        }
    )
    nb.cells = [
        nbformat.v4.new_markdown_cell("# T"),
        nbformat.v4.new_code_cell("glue('x', 1, display=False)"),
        nbformat.v4.new_code_cell("1 + 1"),
    ]
    source = nbformat.from_dict(json.loads(json.dumps(nb)))  # as read from the chapter
    executed = tmp_path / "jupyter_execute" / "book"
    executed.mkdir(parents=True)
    nbformat.write(nb, executed / "ch.ipynb")  # as myst-nb's cache mode writes it: not executed
    assert TOOL.prime_cache(tmp_path / "jupyter_execute", tmp_path / "cache") == 0
    nb.cells[1].execution_count = 1
    nb.cells[2].execution_count = 2
    nb.cells[2].outputs = [
        nbformat.v4.new_output("execute_result", {"text/plain": "2"}, execution_count=2)
    ]
    nbformat.write(nb, executed / "ch.ipynb")
    prefix = "application/papermill.record/"
    (executed / "ch.glue.json").write_text(
        json.dumps(
            {
                "x": {
                    "output_type": "display_data",
                    "data": {"text/plain": "1"},
                    "metadata": {"scrapbook": {"name": "x", "mime_prefix": prefix}},
                }
            }
        )
    )
    # a notebook executed before the library's last change is not taken
    newest = (executed / "ch.ipynb").stat().st_mtime
    assert (
        TOOL.prime_cache(tmp_path / "jupyter_execute", tmp_path / "cache", newer_than=newest) == 0
    )
    (executed / "ch.exec.json").write_text(
        json.dumps({"runtime": 12.5})
    )  # the HTML build's run time
    assert (
        TOOL.prime_cache(tmp_path / "jupyter_execute", tmp_path / "cache", newer_than=newest - 1)
        == 1
    )
    cache = get_cache(str(tmp_path / "cache"))
    assert cache.match_cache_notebook(source).data == {"execution_seconds": 12.5}
    _, merged = cache.merge_match_into_notebook(source)
    assert merged.cells[1].outputs[0]["data"] == {prefix + "text/plain": "1"}
    assert merged.cells[1].outputs[0]["metadata"]["scrapbook"]["name"] == "x"
    assert merged.cells[2].outputs[0]["data"] == {"text/plain": "2"}


def test_the_cache_draws_the_paper_figures_the_html_build_deferred(monkeypatch):
    """An explorable executed with its paper figure deferred (``tools/execute_book.py``) carries a
    specification instead of its small multiples: the PDF edition draws them from it, as the
    ``image/png`` output the LaTeX build takes, the bytes the kernel would have drawn; an output
    that has its PNG, or no specification, is left as it is."""
    import base64

    import nbformat

    from fdi_lib import explorables as E

    monkeypatch.setattr(E, "PAPER_CALLBACK_PACKAGE", _line.__module__)  # this module's _line
    ex = explorable(_line, {"a": (1.0, 2.0, 3.0)}, caption="toy", default={"a": 2.0})
    monkeypatch.setenv(E.PAPER_FIGURES_ENV, "deferred")
    deferred = json.loads(json.dumps(ex._repr_mimebundle_()))  # as the notebook stores it
    assert "image/png" not in deferred and E.PAPER_SPEC_MIME in deferred
    drawn = {"text/plain": "x", "image/png": "AAAA"}
    cell = nbformat.v4.new_code_cell("explorable(...)")
    cell.outputs = [
        nbformat.v4.new_output("display_data", deferred),
        nbformat.v4.new_output("display_data", drawn),
        nbformat.v4.new_output("execute_result", {"text/plain": "2"}, execution_count=1),
    ]
    assert TOOL.paper_figures([cell]) == 1
    assert base64.b64decode(cell.outputs[0]["data"]["image/png"]) == ex.small_multiples()
    assert cell.outputs[1]["data"] == drawn and cell.outputs[2]["data"] == {"text/plain": "2"}
    assert TOOL.paper_figures([cell]) == 0  # drawn once


def test_publish_pdf_links_the_pdf_only_when_it_is_there(tmp_path):
    html = tmp_path / "html"
    (html / "_static").mkdir(parents=True)
    script = html / "_static" / EXT.PDF_SCRIPT
    EXT.publish_pdf(html, None)
    assert "const pdf = null, a4 = null;" in script.read_text()
    assert not (html / EXT.PDF_NAME).exists()
    pdf = tmp_path / "x.pdf"
    pdf.write_bytes(b"%PDF-1.5\n")
    EXT.publish_pdf(html, pdf)
    assert f'const pdf = "{EXT.PDF_NAME}", a4 = null;' in script.read_text()
    assert (html / EXT.PDF_NAME).read_bytes() == b"%PDF-1.5\n"
    EXT.publish_pdf(html, html / EXT.PDF_NAME)  # an HTML build over a published PDF keeps it
    assert f'const pdf = "{EXT.PDF_NAME}", a4 = null;' in script.read_text()
    # the A4 edition beside the letter one is published and linked with it
    (tmp_path / EXT.A4_NAME).write_bytes(b"%PDF-1.5 A4\n")
    EXT.publish_pdf(html, pdf)
    assert f'const pdf = "{EXT.PDF_NAME}", a4 = "{EXT.A4_NAME}";' in script.read_text()
    assert (html / EXT.A4_NAME).read_bytes() == b"%PDF-1.5 A4\n"


def test_run_times_of_executed_chapters_are_written_beside_their_notebooks(tmp_path):
    """Executed in the build (mode force) or taken from the jupyter-cache (mode cache: make book,
    whose chapters tools/execute_book.py executed): the run time is written, and a cached
    chapter's notebook as myst-nb wrote it (without outputs) is replaced by the executed one,
    its glued values taken out as myst-nb does; an unexecuted chapter gets nothing."""
    from collections import defaultdict

    import nbformat
    from jupyter_cache import get_cache
    from jupyter_cache.base import CacheBundleIn

    folder = tmp_path / "_build" / "jupyter_execute" / "book"
    folder.mkdir(parents=True)
    cell = nbformat.v4.new_code_cell("glue('x', 1, display=False)\nprint(2)")
    kernel = {"name": "python3", "display_name": "Python 3"}
    read = nbformat.v4.new_notebook(cells=[cell], metadata={"kernelspec": kernel})
    nbformat.write(read, folder / "b.ipynb")
    executed = nbformat.from_dict(json.loads(nbformat.writes(read)))
    executed.cells[0].execution_count = 1
    prefix = "application/papermill.record/"
    executed.cells[0].outputs = [
        nbformat.v4.new_output(
            "display_data",
            data={f"{prefix}text/plain": "1"},
            metadata={"scrapbook": {"name": "x", "mime_prefix": prefix}},
        ),
        nbformat.v4.new_output("stream", name="stdout", text="2\n"),
    ]
    cache = tmp_path / "cache"
    bundle = CacheBundleIn(executed, "book/b.md")
    get_cache(str(cache)).cache_notebook_bundle(bundle, check_validity=False)
    run = {"method": "force", "succeeded": True, "runtime": 3.25}
    env = SimpleNamespace(
        found_docs={"book/a", "book/b", "book/c"},
        nb_metadata=defaultdict(
            dict,
            {
                "book/a": {"exec_data": run},
                "book/b": {"exec_data": dict(run, method="cache", runtime=1.5)},
            },
        ),
        mystnb_config=SimpleNamespace(execution_cache_path=str(cache)),
    )
    EXT._record_run_times(SimpleNamespace(outdir=str(tmp_path / "_build" / "html")), env)
    written = sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*.exec.json"))
    assert written == [
        "_build/jupyter_execute/book/a.exec.json",
        "_build/jupyter_execute/book/b.exec.json",
    ]
    assert json.loads((tmp_path / written[0]).read_text()) == {"runtime": 3.25}
    assert json.loads((tmp_path / written[1]).read_text()) == {"runtime": 1.5}
    cell = nbformat.read(folder / "b.ipynb", as_version=4).cells[0]
    assert cell.execution_count == 1 and [o.output_type for o in cell.outputs] == ["stream"]


def test_check_pdf_reads_code_listings_and_the_numbered_chapters(tmp_path):
    """tools/check_pdf.py: TeX in a code listing is counted as code; the table of contents must
    number exactly the chapters of the numbered parts of _toc.yml, in order."""
    check = _load("fdi_check_pdf", ROOT / "tools" / "check_pdf.py")
    tex = (
        r"\begin{sphinxVerbatim}[commandchars=\\\{\}]"
        "\n"
        r"\PYG{l+s+s2}{\PYGZdq{}}\PYG{l+s+s2}{\PYGZbs{}}\PYG{l+s+s2}{Psi = I\PYGZdl{}}"
        "\n"
        r"\end{sphinxVerbatim}"
        "\n"
        r"\(\Psi\) outside code"
    )
    assert check.code_macros(tex) == {"Psi": 1}
    chapters = check.numbered_chapters(ROOT)
    assert [doc for doc, _ in chapters][:1] == ["book/zb2014/signature"] and len(chapters) == 7
    lines = [r"\contentsline {chapter}{Notation}{7}{chapter*.3}%"] + [
        rf"\contentsline {{chapter}}{{\numberline {{{i}}}{title}}}{{{40 + i}}}{{chapter.{i}}}%"
        for i, (_, title) in enumerate(chapters, start=1)
    ]
    toc = tmp_path / "b.toc"
    toc.write_text("\n".join(lines) + "\n")
    assert check.toc_problems(toc, ROOT) == []
    toc.write_text("\n".join(lines[:-1]) + "\n")
    assert check.toc_problems(toc, ROOT) == [
        "numbered chapters [1, 2, 3, 4, 5, 6], expected 1 to 7"
    ]


def test_characters_the_font_lacks_fail_the_check(tmp_path):
    """xelatex drops a character its font lacks with only a log line (an explorable's "Γₖ" became
    "Γ"): check_pdf fails, naming the character and how often."""
    check = _load("fdi_check_pdf_log", ROOT / "tools" / "check_pdf.py")
    log = tmp_path / "b.log"
    log.write_text(
        "Missing character: There is no \u2096 (U+2096) in font [FreeSerif.otf]/OT:script=latn;!\n"
        * 3
        + "Missing character: There is no \u1d40 (U+1D40) in font [FreeMono.otf]/OT:script=latn;!\n"
    )
    assert check.missing_characters(log.read_text()) == {"\u2096": 3, "\u1d40": 1}
    assert check.log_problems(log) == [
        "LaTeX: 1 times no '\u1d40' in the font (dropped from the page)",
        "LaTeX: 3 times no '\u2096' in the font (dropped from the page)",
    ]
    log.write_text("Output written on b.pdf (3 pages).\n")
    assert check.log_problems(log) == []


def test_log_counts_overfull_boxes_over_the_allowance_and_rerun_requests():
    check = _load("fdi_check_pdf_counts", ROOT / "tools" / "check_pdf.py")
    log = (
        "Overfull \\hbox (12.5pt too wide) in paragraph at lines 3--4\n"
        "Overfull \\hbox (1.0pt too wide) detected at line 9\n"
        "Overfull \\vbox (6.0pt too high) has occurred while \\output is active\n"
        "Underfull \\vbox (badness 10000) has occurred\n"
        "LaTeX Warning: Label(s) may have changed. Rerun to get cross-references right.\n"
    )
    assert check.log_counts(log) == {
        "overfull": 3,
        "overfull_over_allowance": 2,
        "overfull_max_pt": 12.5,
        "underfull": 1,
        "rerun": 1,
    }
    assert check.log_counts("")["overfull_max_pt"] == 0.0
    # a line wider than the text fails, and so does a box in the bottom margin (no budget)
    assert check.log_problems_in(log) == [
        "LaTeX: overfull box 12.5 pt too wide in paragraph at lines 3--4",
        "LaTeX: overfull box 6.0 pt too high has occurred while \\output is active",
        "LaTeX: the last pass asks for a rerun (cross-references not settled)",
    ]
    # within the allowance: counted, not a problem
    assert check.log_problems_in("Overfull \\vbox (4.9pt too high) detected at line 9\n") == []
    assert check.log_problems_in(
        "LaTeX Warning: Float too large for page by 3.1pt on input line 7.\n"
    ) == ["LaTeX: Float too large for page by 3.1pt on input line 7."]
    # undefined references of every kind, the warning wrapped before "undefined" included
    assert check.log_problems_in(
        "LaTeX Warning: Reference `a:b' on page 3 undefined on input line 5.\n"
        "LaTeX Warning: Hyper reference `book/windturbine/benchmark:ex-wt-2' on page 232\n"
        " undefined on input line 23347.\n"
    ) == [
        "LaTeX: LaTeX Warning: Reference `a:b' on page 3 undefined on input line 5.",
        "LaTeX: LaTeX Warning: Hyper reference `book/windturbine/benchmark:ex-wt-2' on page 232 "
        "undefined on input line 23347.",
    ]


def _bbox_page(lines):
    """A page of ``pdftotext -bbox-layout``: one line per ``(x0, x1, words)``."""
    out = []
    for x0, x1, words in lines:
        out.append(f'<line xMin="{x0}" yMin="1" xMax="{x1}" yMax="2">')
        step = (x1 - x0) / len(words)
        out += [
            f'<word xMin="{x0 + i * step}" yMin="1" xMax="{x0 + (i + 1) * step}" yMax="2">{w}</word>'
            for i, w in enumerate(words)
        ]
        out.append("</line>")
    return "\n".join(out)


def test_words_beyond_the_text_block_are_measured_in_the_pdf():
    """check_pdf measures the text block from the PDF (the most frequent start and end of a
    line) and names every word beyond it by more than the allowance: a table 40 pt too wide on
    page 2, none on page 1 (a short line, a line 1 pt over)."""
    check = _load("fdi_check_pdf_width", ROOT / "tools" / "check_pdf.py")
    body = [(72.0, 540.0, ["a", "justified", "line"])] * 5
    page1 = _bbox_page(body + [(72.0, 300.0, ["short"]), (72.0, 541.0, ["rounding"])])
    page2 = _bbox_page(body + [(60.0, 580.0, ["wide", "table", "row", "&amp;", "cut"])])
    assert check.text_block([page1, page2]) == (72.0, 540.0)
    assert check.outside_words([page1, page2]) == [(2, 12.0, "wide"), (2, 40.0, "cut")]


def test_long_tables_get_ragged_right_columns_that_fit_and_intervals_stay_whole():
    """_PrintedTables: a long table wider than the text gets columns that share the text width,
    each at least its longest word; one that fits keeps its natural columns; an interval and a
    number with its unit are joined by no-break spaces."""
    columns = [["ex-1"] * 40, ["a title of an exercise that goes on and on"] * 40, ["10 min"]]
    widths = EXT.printed_widths(columns, chars=40)
    assert sum(widths) == 40 and widths[0] >= 4 and widths[1] >= len("exercise") and widths[2] >= 3
    assert EXT.printed_widths([["ex-1"], ["short"]], chars=40) is None
    nb = EXT.NBSP
    cell = "0.032 s [0.02, 0.05], 5 % [-0.333, 1] and 4 sets"
    joined = EXT._NUMBER_UNIT.sub(rf"\1{nb}\2", EXT._INTERVAL.sub(rf"\1{nb}\2", cell))
    assert joined == f"0.032{nb}s [0.02,{nb}0.05], 5{nb}% [-0.333,{nb}1] and 4 sets"


def test_a_table_taller_than_a_page_breaks_across_pages():
    """_PrintedTables: a table of a few rows whose cells wrap onto more lines than a page holds
    (PAGE_TABLE_LINES, estimated by printed_lines) is a longtable, whose columns share the text
    width; a short one stays a tabulary."""
    from docutils import nodes
    from sphinx import addnodes

    long_cell = "a reading of several sections of a chapter, " * 4
    assert EXT.printed_lines([["week"] + ["w"] * 3, ["topic"] + [long_cell] * 3], chars=80) > 3
    assert EXT.printed_lines([["a", "b"], ["c", "d"]]) == 3  # a line and its padding a row

    def table(rows: int) -> nodes.table:
        tgroup = nodes.tgroup(cols=2)
        tgroup += [nodes.colspec(colwidth=1), nodes.colspec(colwidth=1)]
        body = nodes.tbody()
        for i in range(rows):
            body += nodes.row(
                "", *(nodes.entry("", nodes.paragraph(text=t)) for t in (f"week {i}", long_cell))
            )
        tgroup += body
        return nodes.table("", tgroup)

    doc = nodes.section()
    tall, short = table(25), table(2)  # 25 rows of 3 lines and some padding: over 70 lines
    doc += [tall, short]
    transform = EXT._PrintedTables.__new__(EXT._PrintedTables)
    transform.document = doc
    transform.run()
    assert "longtable" in tall["classes"] and "longtable" not in short["classes"]
    specs = [n for n in doc.children if isinstance(n, addnodes.tabular_col_spec)]
    assert len(specs) == 1 and doc.index(specs[0]) == doc.index(tall) - 1


def test_printed_figure_text_under_8_pt_fails():
    check = _load("fdi_check_pdf_fonts", ROOT / "tools" / "check_pdf.py")
    assert check.font_problems({"page 3 (a.png)": 8.0, "page 9 (b.png)": 6.3}) == [
        "page 9 (b.png): its smallest text prints at 6.3 pt, under 8 pt (PRINTED_MIN_FONT_PT)"
    ]


def test_the_cover_table_spans_the_text_width():
    """The cover's ledger table: a status column of 0.3 text widths and one column per paper
    plus the total sharing the rest, its padding included (the names wrap)."""
    counts = {p: {STATUSES[0]: 1} for p in PAPERS}
    spec = re.search(r"\\begin\{tabular\}\{(.*)\}$", EXT.cover_latex("a: b", "1", counts), re.M)
    n = len(PAPERS) + 1
    assert spec.group(1) == (
        r"@{}>{\raggedright\arraybackslash}p{0.3\linewidth}"
        rf"*{{{n}}}{{>{{\raggedleft\arraybackslash}}p{{\dimexpr(0.7\linewidth-{2 * n}\tabcolsep)/{n}\relax}}}}@{{}}"
    )
