"""Notebooks that render in Jupyter (tools/notebook_markdown.py): the MyST markup of the chapters
as plain Markdown with the book's numbers, the book's macros defined, and the check that finds
raw markup and maths MathJax cannot typeset.

The chapters are converted here from their sources (no book build); the notebooks a build
produced (the ".ipynb" downloads of ``_build/html``, ``make notebooks``, the student edition) are
checked too when they exist, as in CI after the build.
"""

from __future__ import annotations

import pickle
import re
import sys
from pathlib import Path

import nbformat
import pytest

from source_module import load as _load  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


sys.path.insert(0, str(ROOT / "tools"))
import notebook_markdown as NM  # noqa: E402

DOC = "book/zb2014/glr"


@pytest.fixture(scope="module")
def refs():
    return NM.BookReferences.from_sources(ROOT)


def _glued(refs, values: dict[str, str], doc: str = DOC):
    """``refs`` with the glue values ``values`` (text/plain) for ``doc``, in myst-nb's format."""
    out = NM.BookReferences(
        refs.titles, refs.notebooks, refs.targets, refs.citations, dict(refs.glue)
    )
    out.glue[doc] = {
        k: {
            "output_type": "display_data",
            "data": {NM_PREFIX + "text/plain": v},
            "metadata": {"scrapbook": {"name": k, "mime_prefix": NM_PREFIX}},
        }
        for k, v in values.items()
    }
    return out


NM_PREFIX = "application/papermill.record/"


# ----------------------------------------------------------------------------- roles
def test_references_have_the_books_numbers_and_labels(refs):
    md = NM.convert_markdown
    assert md("see {numref}`fig-zb2014-3`", DOC, refs) == "see Figure 2.2"
    assert md("By {prf:ref}`zb-glr-chi2`.", DOC, refs) == "By Proposition 2.1."
    # another chapter's: a link to its notebook, relative to this one
    assert md("{prf:ref}`zb-prop-2`", DOC, refs) == "[Proposition 1.2](signature.ipynb)"
    assert (
        md("{prf:ref}`bz-lemma-a1`", DOC, refs)
        == "[Lemma 5.1](../bz/parametric-nonparametric.ipynb)"
    )
    assert md("{doc}`../instructor`", DOC, refs) == "[For instructors](../instructor.ipynb)"
    assert md("{doc}`../notation`", DOC, refs) == "Notation"  # not a notebook: its title
    assert (
        md("the {ref}`claims ledger <sec-ledger>`", DOC, refs)
        == "the [claims ledger](../zz-ledger.ipynb)"
    )
    assert (
        md("{ref}`zhang2021-lambda-rule`", "book/zhang2021/sparse", refs)
        == "The rule for $\\lambda$, the oracle and the initial state"
    )
    assert md("exercise {ref}`ex-sparse-3`", "book/zhang2021/sparse", refs) == "exercise sparse-3"


def test_citations_read_as_author_year(refs):
    md = NM.convert_markdown
    assert (
        md("as in {cite:t}`zhang2014statistical`", DOC, refs) == "as in Zhang and Basseville (2014)"
    )
    assert (
        md("{cite:p}`zhang2014statistical,basseville_1993_detection`", DOC, refs)
        == "(Zhang and Basseville, 2014; Basseville and Nikiforov, 1993)"
    )
    assert md("{cite:p}`rosa2013svo`", DOC, refs) == "(Rosa and Silvestre, 2013)"


def test_glue_references_show_the_formatted_values(refs):
    glued = _glued(refs, {"h": "20.123456", "n": "4000", "s": "'w − 1 and w + 3'"})
    md = NM.convert_markdown
    assert (
        md("threshold {glue:text}`h:.1f`, {glue:text}`n` runs", DOC, glued)
        == "threshold 20.1, 4000 runs"
    )
    assert (
        md("between {glue:text}`s` samples and {glue}`n`", DOC, glued)
        == "between w − 1 and w + 3 samples and 4000"
    )
    # {glue:md} with the Markdown's format after the key (myst-nb's `key:myst`)
    assert md("{glue:md}`n:myst` runs", DOC, glued) == "4000 runs"
    # another document's value
    other = _glued(refs, {"total": "27"}, doc="book/zz-ledger")
    assert md("{glue:text}`zz-ledger.md::total:d` claims", "book/intro", other) == "27 claims"
    # no executed notebook: a placeholder naming the value, never raw markup
    assert md("{glue:text}`h:.1f`", DOC, refs) == "[computed when you run the notebook: `h`]"


def test_unknown_markup_is_an_error_not_silently_dropped(refs):
    with pytest.raises(ValueError, match="role {kbd}"):
        NM.convert_markdown("{kbd}`Ctrl`", DOC, refs)
    with pytest.raises(ValueError, match="directive {mermaid}"):
        NM.convert_markdown("```{mermaid}\ngraph\n```", DOC, refs)
    with pytest.raises(KeyError, match="no target 'fig-none'"):
        NM.convert_markdown("{numref}`fig-none`", DOC, refs)


# ----------------------------------------------------------------------------- directives
def test_directives_become_block_quotes_with_numbered_titles(refs):
    text = (
        ":::{prf:proposition} Law of the GLR statistic\n:label: zb-glr-chi2\n\n"
        "Under $\\mathbb H_0$ it is\n\n$$\nl = d^\\T C^{-1} d\n$$\n:::\n\n(sec-x)=\n"
        ":::{prf:proof}\nBy {prf:ref}`zb-minmax-chi2`.\n:::\n\n"
        ":::{admonition} What you will learn\n:class: tip\n* one\n:::\n\n:::{note}\nA note.\n:::\n"
    )
    assert NM.convert_markdown(text, DOC, refs) == (
        "> **Proposition 2.1** (Law of the GLR statistic)\n>\n> Under $\\mathbb H_0$ it is\n>\n"
        "> $$l = d^\\T C^{-1} d$$\n\n"  # display maths on one line: no ">" inside it
        "> *Proof.*\n>\n> By Proposition 2.2.\n\n"
        "> **What you will learn**\n>\n> * one\n\n> **Note**\n>\n> A note.\n"
    )


def test_labelled_equations_are_numbered_and_tagged():
    refs = NM.BookReferences()
    refs._read_document("book/x", "# X\n\n$$\na = b\n$$ (eq-a)\n\n$$\nc\n$$ (eq-c)\n", chapter=3)
    assert refs.targets["eq-c"] == ("book/x", "(3.2)")
    assert (
        NM.convert_markdown("$$\nc\n$$ (eq-c)\n\nas {eq}`eq-c` says", "book/x", refs)
        == "$$\nc\n\\tag{3.2}\n$$\n\nas (3.2) says"
    )


def test_exercises_and_solutions_get_bold_headings(refs):
    text = (
        "```{exercise-start} glr-1 · warm-up · A threshold\n:label: ex-glr-1\n:nonumber:\n```\n\n"
        "Which threshold?\n\n```{exercise-end}\n```\n\n```{solution-start} ex-glr-1\n"
        ":class: dropdown\n```\n\nThe quantile.\n\n```{solution-end}\n```\n"
    )
    assert NM.convert_markdown(text, DOC, refs) == (
        "**Exercise glr-1 · warm-up · A threshold**\n\nWhich threshold?\n\n"
        "**Solution of exercise glr-1**\n\nThe quantile.\n"
    )


def test_figures_with_numbers_and_their_images(refs):
    text = "```{figure} img/a.png\n:name: fig-zb2014-3\n\nThe caption.\n```\n"
    assert (
        NM.convert_markdown(text, DOC, refs)
        == "![The caption.](img/a.png)\n\n**Figure 2.2.** The caption.\n"
    )
    glued = NM.BookReferences(
        refs.titles,
        refs.notebooks,
        refs.targets,
        refs.citations,
        {DOC: {"fig": {"data": {"image/png": "iVBORw0KGgo="}, "metadata": {}}}},
    )
    out = NM.convert_markdown(
        "```{glue:figure} fig\n:name: fig-zb2014-4\n\nIts caption.\n```\n", DOC, glued
    )
    assert (
        out
        == "![Its caption.](data:image/png;base64,iVBORw0KGgo=)\n\n**Figure 2.3.** Its caption.\n"
    )


# ----------------------------------------------------------------------------- macros and the check
def test_macro_cell_is_generated_from_the_mathjax_config():
    import yaml

    config = yaml.safe_load((ROOT / "_config.yml").read_text())["sphinx"]["config"]
    macros = config["mathjax3_config"]["tex"]["macros"]
    assert NM.book_macros(ROOT) == macros and {"T", "R", "E"} <= set(macros)
    cell = NM.macro_cell(macros)
    for name, body in macros.items():
        assert f"\\newcommand{{\\{name}}}{{{body}}}" in cell.source
    assert cell.metadata["jupyter"]["source_hidden"]
    assert NM.macro_definitions({"norm": ["\\|#1\\|", 1]}) == "\\newcommand{\\norm}[1]{\\|#1\\|}"


def test_the_check_finds_undefined_macros_and_raw_markup(refs):
    """The check can fail: a chapter as plain jupytext writes it has both, the converted one neither."""
    import jupytext

    raw = jupytext.read(ROOT / "book" / "zb2014" / "glr.md")
    nb = NM.convert_notebook(
        jupytext.read(ROOT / "book" / "zb2014" / "glr.md"), DOC, refs, NM.book_macros(ROOT)
    )
    defs = f"${NM.macro_definitions(NM.book_macros(ROOT))}$\n\n"
    uses = [c for c in nb.cells[1:] if c.cell_type == "markdown" and "\\T" in c.source]
    assert uses and all(c.source.startswith(defs) for c in uses)  # each cell defines what it uses
    # the converted one without its macro cell and without its cells' own definitions
    bare = [
        nbformat.v4.new_markdown_cell(c.source.removeprefix(defs))
        if c.cell_type == "markdown"
        else c
        for c in nb.cells[1:]
    ]
    no_macros = nbformat.v4.new_notebook(cells=bare)
    planted = nbformat.v4.new_notebook(
        cells=[
            *nb.cells,
            nbformat.v4.new_markdown_cell("> :::{note}\nSee {numref}`fig-x` and $\\foo$."),
        ]
    )
    found_raw, found, found_no_macros, found_planted = NM.problems(raw, nb, no_macros, planted)
    assert any("Undefined control sequence \\T" in p for p in found_raw)
    assert any("{prf:ref}" in p for p in found_raw) and any(
        "```{exercise-start}" in p for p in found_raw
    )
    assert found == []
    assert any("Undefined control sequence" in p for p in found_no_macros)
    assert ":::{note}" in str(found_planted) and "{numref}`fig-x`" in str(found_planted)
    assert "\\foo" in str(found_planted) and len(found_planted) == 3
    # a code cell is not Markdown: its text is not checked
    assert (
        NM.raw_markup(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("'{numref}`a`'")]))
        == []
    )


def test_every_chapter_converts_to_notebooks_that_render(tmp_path):
    """All chapters as `make notebooks` writes them (no build: glued values are placeholders)."""
    written = NM.write_notebooks(ROOT, tmp_path, None)
    assert len(written) == len(NM.chapters(ROOT / "book"))
    # every cell says which exercise it belongs to (issue 30.3), as in the student notebooks
    from fdi_lib.exercises import CELL_KEY, EXERCISES

    glr = nbformat.read(tmp_path / "zb2014" / "glr.ipynb", as_version=4)
    tags = [c.metadata.get(CELL_KEY, {"missing": True}) for c in glr.cells]
    assert all(set(t) == {"exercise"} for t in tags), tags
    seen = {t["exercise"] for t in tags} - {None}
    assert seen == {e for e in EXERCISES if EXERCISES[e].chapter == "zb2014/glr"}
    first = next(c for c in glr.cells if c.metadata[CELL_KEY]["exercise"] == "glr-5")
    assert "glr-5" in first.source and first.cell_type == "markdown"
    found = NM.problems(*[nbformat.read(p, as_version=4) for p in written])
    bad = {p.relative_to(tmp_path).as_posix(): f for p, f in zip(written, found) if f}
    assert bad == {}


# ----------------------------------------------------------------------------- against a built book
ENV = ROOT / "_build" / ".doctrees" / "environment.pickle"


@pytest.mark.skipif(not ENV.is_file(), reason="no built book (make book)")
def test_numbers_and_labels_agree_with_the_built_book(refs):
    """The numbers computed from the sources are the ones Sphinx gave the built book."""
    sys.path.insert(0, str(ROOT / "_ext"))
    env = pickle.loads(ENV.read_bytes())
    ext = _load("fdi_book_ext", ROOT / "_ext" / "fdi_book.py")
    numbered = set()
    for doc, kinds in env.toc_fignumbers.items():
        for kind, labels in kinds.items():
            for label, number in labels.items():
                assert refs.targets[label] == (doc, f"{kind.title()} {'.'.join(map(str, number))}")
                numbered.add(label)
    macros = NM.book_macros(ROOT)

    def readable(text: str) -> str:  # the maths as the book's text of a reference, quotes straight
        text = re.sub(r"\$([^$]+)\$", lambda m: ext.tex_to_text(m.group(1), macros), text)
        text = re.sub(r"`([^`]+)`", r"\1", text)  # code in a title: its text
        return text.translate(str.maketrans("\u2018\u2019\u201c\u201d", "''\"\""))

    for label, (doc, _anchor, title) in env.domaindata["std"]["labels"].items():
        # (an exercise's {ref} reads "Exercise" in the book, the notebooks give its identifier)
        if label in refs.targets and label not in numbered and not label.startswith("ex-"):
            assert (doc, readable(refs.targets[label][1])) == (
                refs.targets[label][0],
                readable(title),
            )
    for doc, title in refs.titles.items():
        assert readable(title) == readable(env.titles[doc].astext())
    for cite in env.domaindata["cite"]["citations"]:
        assert ", ".join(refs.citations[cite.key]) == cite.formatted_entry.label


BUILT = sorted(
    [
        *(ROOT / "_build" / "html" / "_sources").rglob("*.ipynb"),
        *(ROOT / "_build" / "notebooks").rglob("*.ipynb"),
        *(ROOT / "_build" / "student" / "notebooks").rglob("*.ipynb"),
        *(ROOT / "_build" / "student" / "html" / "_sources").rglob("*.ipynb"),
    ]
)


@pytest.mark.skipif(
    not BUILT, reason="no built notebooks (make book, make notebooks, make student)"
)
def test_built_notebooks_render():
    found = NM.problems(*[nbformat.read(p, as_version=4) for p in BUILT])
    found = [found] if len(BUILT) == 1 else found
    bad = {p.relative_to(ROOT / "_build").as_posix(): f for p, f in zip(BUILT, found) if f}
    assert bad == {}
