"""Local Sphinx extension of fdi-book (loaded from ``_config.yml``, ``sphinx.local_extensions``).

1. Offline MathJax: copies MathJax 3 (TeX input, CommonHTML output and the fonts, from the PyPI
   package ``django-static-mathjax`` that ``requirements.lock`` pins) to ``<html>/mathjax/`` at the
   end of an HTML build. ``_config.yml`` points ``mathjax_path`` at it with a URL relative to
   ``_static``, which works at every page depth, from a web server and from ``file://``. It is
   not under ``_static`` because Jupyter Book adds every ``.js`` found there to every page.
2. Author-year citations in the bibliography: a pybtex label style whose labels are the in-text
   author-year citations ("Zhang and Basseville, 2014"), and a formatting style using it
   (``bibtex_default_style: fdi_author_year``).
3. The proof index (``prf-prf.html``) lists each proposition by its title and kind instead of its
   raw label.
4. Every chapter's header has a ".ipynb" download (the executed notebook, with outputs) next to
   the ".md" source: sphinx-book-theme adds it only when a launch service (Binder, JupyterHub,
   Thebe, Colab) is configured, and this book loads nothing from another host. At the end of
   the build the downloads are rewritten in Markdown that Jupyter renders (macros defined,
   roles and glue references resolved: ``tools/notebook_markdown.py``).
5. No Thebe scripts (Thebe is off; sphinx-thebe would reference a CDN and declares its constants
   twice on every page, a console error).
6. The catalogue of reproductions (``book/reproductions.md``) is generated when the book is read:
   from the registry of :mod:`fdi_lib.reproduce`, in book order (the order of the chapters in
   ``_toc.yml``, then of the first code cell that calls each reproduction), with a link to the
   figure that draws it (the figure label of the cell that calls ``get(ID).plot``) or else to the
   section that runs it, the command line that recomputes it at the book's settings
   (:func:`fdi_lib.reproduce.book.book_command`, the settings the chapters' ``book_run`` uses) and
   its documentation rendered, names as code and ASCII maths as maths (:func:`docstring_rst`).
7. The execution table of the status page (myst-nb's ``nb-exec-table``) says "ok" / "failed"
   instead of emoji, which show as empty boxes without an emoji font.
8. Maths as readable text where it cannot be typeset: the text of references to a heading with
   maths (``{ref}`` to "The rule for $\\lambda$" reads "The rule for λ", not "\\lambda"; pages
   such as the ledger load no MathJax), and the alt text of every figure's image, taken from
   its caption (Sphinx would otherwise write the image's file path). :func:`tex_to_text` does
   the conversion; the catalogue's headings (from the registry's ASCII titles, "Gamma_k") are
   written in real maths by :func:`title_markdown`.
9. Lighter pages (issue 23): no Font Awesome script (1.5 MB on every page; the theme's own
   Font Awesome stylesheet and web font draw the icons: ``templates/layout.html`` with the
   filter :func:`without_script`; the theme's Font Awesome font cut to the icons the pages use:
   :func:`subset_icon_font`, ``static/fdi-icons.css``), and MathJax only on pages with maths of
   their own
   (:func:`_mathjax_where_needed`; Sphinx also loads it on the root page because its toctree
   includes pages with maths).
10. Hover previews offline (sphinx-tippy): tippy.js and Popper are served from the build
   (``static/vendor/tippy``, committed with their licences; ``_config.yml`` ``tippy_js``), the
   maths of a preview is typeset by ``static/fdi-previews.js`` (loading MathJax on demand on a
   page without maths: :func:`_mathjax_where_needed` gives it the address and configuration)
   and styled by ``static/fdi-previews.css``; a preview holds no script or slider
   (:func:`preview_html`).
11. The PDF edition (LaTeX builder, ``make pdf``, ``tools/pdf_edition.py``): the book's maths
   macros (``mathjax3_config``, one source for MathJax and LaTeX) as ``\\newcommand`` in the
   preamble (:func:`latex_macros`); a ``bbm.sty`` stand-in (``\\mathbbm`` as ``\\mathbb``: the
   class of sphinx-jupyterbook-latex loads ``bbm``, whose fonts Debian ships only in the 500 MB
   texlive-fonts-extra); the sub- and superscript characters of plain-text captions ("Γₖ")
   that the text font lacks set in DejaVu (:func:`latex_script_fallback`); citations in
   captions protected (sphinxcontrib-bibtex writes a fragile ``\\hyperlink`` into the moving
   argument of ``\\caption``); the chapters numbered as in the
   HTML (1-7 in the parts ``numbered: true`` of ``_toc.yml``, the other pages and every part
   unnumbered); each explorable as a figure of its small multiples with its caption
   (:meth:`fdi_lib.explorables.Explorable.small_multiples`); a cover page with the version and
   the claims ledger per status and paper, as the ledger page of the same build computed it; a
   list of figures after the contents and an index of the terms a student looks up
   (:data:`INDEX_TERMS`, :class:`_IndexTerms`); tables within the text width, ragged-right,
   intervals and units unbroken (:class:`_PrintedTables`, :data:`LATEX_LAYOUT`), floats kept in
   their section and LaTeX passes that converge (:data:`LATEX_LAYOUT`); a reference to an
   exercise that reaches it (:func:`_latex_exercise_targets`).
   In the HTML, the header's download menu links the PDF when there is one: ``make pdf`` puts it
   beside the pages (:func:`publish_pdf`), and ``make book`` after ``make pdf`` copies it there.
12. Tables that can be read on a phone: every body cell of a table carries its column's header as
   a ``data-label`` attribute (its readable text, :func:`readable_text`), which the book's CSS
   and ``_static/fdi-tables.js`` use to show a table too wide for the column as one card per row
   (``fdi_lib.report.Table`` writes the same attribute for its tables).
13. Numbered explorables: the output of a cell that shows an explorable
    (:mod:`fdi_lib.explorables`, whose HTML carries its own caption) becomes a figure of the book
    with that caption as plain text, numbered like the others ("Figure 2.5") and labelled
    ``fig-<page>-explore`` (``fig-glr-explore``; ``-2``, ``-3`` for further ones on a page), so
    that the text can cite it with ``{numref}``.
14. The intro's map of the book and reading path, made from ``_toc.yml`` (every page in it) and
    one line per page in the intro's ``{fdi-book-map}`` block (:func:`book_map_markdown`).
15. Accessible names and roles (issue 33; checked by axe-core in ``tests/browser/check_book.py``):
    the folds of hidden code cells and the search button are named by the text they show
    (``templates/search-button-field.html``), the bibliography's entries are the
    items of its list, and the site has an icon (``_static/favicon.svg``).
16. Figure references resolved without re-reading pages: Sphinx 7.4 resolves every ``{numref}``
    by unpickling the whole target page (up to 3.4 MB, the explorables' frames are inline), 121
    times a build. :class:`_StandardDomain` reads each target page once per build and keeps, for
    each id, a childless copy of its node (class, attributes, the classes of its children: all
    that Sphinx's numbering looks at); the copies are dropped when the pages are read again.
17. Figures numbered without re-reading pages: to number the figures, tables and listings,
   Sphinx 7.4 unpickles every page of the book (``env-get-updated``, 1.4 s a build), although
   the pages it has just read are in memory, unchanged, until they are written
   (:func:`_doctrees_in_memory`).
"""

from __future__ import annotations

import ast
import html
import html.parser
import importlib.util
import inspect
import json
import re
import shutil
import sys
import subprocess
import unicodedata
from pathlib import Path
from typing import Any

from docutils import nodes
from markupsafe import Markup

import pybtex.plugin
from pybtex.backends.plaintext import Backend as PlainTextBackend
from pybtex.richtext import Text
from pybtex.style.formatting.plain import Style as PlainStyle
from pybtex.style.labels import BaseLabelStyle
from sphinx.application import Sphinx
from sphinx.domains.std import StandardDomain
from sphinx.errors import ExtensionError
from sphinx.transforms.post_transforms import SphinxPostTransform
from sphinx.util import logging
from sphinx.transforms import SphinxTransform
from sphinx.util.nodes import clean_astext

from fdi_lib.explorables import caption_text, script_text

logger = logging.getLogger(__name__)

# What pages load from MathJax's es5 tree: the combined TeX + CommonHTML component, the TeX
# extensions it autoloads (\begin{aligned}, \boldsymbol, ...), the CommonHTML fonts, the
# context menu and the accessibility components the menu can switch on.
MATHJAX_ENTRY = "tex-chtml.js"
MATHJAX_PARTS = (
    "tex-chtml.js",
    "input/tex",
    "output/chtml",
    "output/chtml.js",
    "ui",
    "a11y",
    "sre",
    "adaptors",
)


def mathjax_source() -> Path:
    """The ``es5`` folder of the MathJax 3 copy shipped by ``django-static-mathjax``."""
    spec = importlib.util.find_spec("mathjax")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError("MathJax not found: install django-static-mathjax (requirements.lock)")
    es5 = Path(next(iter(spec.submodule_search_locations))) / "static" / "mathjax" / "es5"
    if not (es5 / MATHJAX_ENTRY).is_file():
        raise RuntimeError(f"MathJax not found: no {MATHJAX_ENTRY} in {es5}")
    return es5


def copy_mathjax(app: Sphinx, exception: Exception | None) -> None:
    if exception is not None or app.builder.format != "html":
        return
    src, dst = mathjax_source(), Path(app.outdir) / "mathjax"
    for part in MATHJAX_PARTS:
        source, target = src / part, dst / part
        if source.is_dir():
            shutil.copytree(source, target, dirs_exist_ok=True)
        elif source.is_file():
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, target)
    logger.info("fdi_book: MathJax copied to %s", dst)


#: pybtex's plain-text backend, given to :meth:`pybtex.richtext.Text.render` directly:
#: ``render_as("text")`` looks it up among the installed packages' entry points on every call
#: (``importlib.metadata.entry_points()`` reads every distribution's metadata, 4 ms each).
_PLAIN_TEXT = PlainTextBackend()


def _plain(text: str) -> str:
    return Text.from_latex(text).render(_PLAIN_TEXT)


class AuthorYearLabelStyle(BaseLabelStyle):
    """Labels equal to the in-text author-year citation: "Zhang", "Zhang and Basseville" or
    "Rosa et al.", then ", year" (sphinxcontrib-bibtex ``author_year`` reference style)."""

    def format_labels(self, sorted_entries):
        seen: dict[str, int] = {}
        for entry in sorted_entries:
            label = self.format_label(entry)
            seen[label] = seen.get(label, 0) + 1
            # two works with the same authors and year: 2014a, 2014b (never seen in this book)
            yield label if seen[label] == 1 else f"{label}{chr(ord('a') + seen[label] - 1)}"

    def format_label(self, entry) -> str:
        persons = entry.persons.get("author") or entry.persons.get("editor") or []
        names = [_plain(" ".join(p.prelast_names + p.last_names)) for p in persons]
        if not names:
            who = _plain(entry.fields.get("title", entry.key))
        elif len(names) == 1:
            who = names[0]
        elif len(names) == 2:
            who = f"{names[0]} and {names[1]}"
        else:
            who = f"{names[0]} et al."
        year = entry.fields.get("year", "n.d.")
        return f"{who}, {year}"


class AuthorYearStyle(PlainStyle):
    """pybtex's plain style, sorted by author and year, labelled by author-year."""

    default_label_style = "fdi_author_year"
    default_sorting_style = "author_year_title"


def _record_proof_titles(app: Sphinx, doctree) -> None:
    titles = app.env.__dict__.setdefault("fdi_proof_titles", {})
    for node in doctree.findall(lambda n: "realtype" in getattr(n, "attributes", {})):
        label = node.get("label")
        if label:
            titles[label] = (node.get("title") or "", node["realtype"])


def _purge_proof_titles(app: Sphinx, env, docname: str) -> None:
    titles = env.__dict__.get("fdi_proof_titles", {})
    proofs = getattr(env, "proof_list", {})
    for label in [k for k in titles if proofs.get(k, {}).get("docname") in (None, docname)]:
        del titles[label]


def _titled_proof_index(original):
    def generate(self, docnames=None):
        content, collapse = original(self, docnames)
        titles = self.domain.env.__dict__.get("fdi_proof_titles", {})
        renamed: dict[str, list] = {}
        for _letter, entries in content:
            for name, subtype, docname, anchor, extra, qualifier, descr in entries:
                title, kind = titles.get(anchor, ("", descr))
                title = re.sub(r"^\s*\((.*)\)\s*$", r"\1", title)  # proof_title_format " (%t)"
                shown = f"{kind.title()}: {title}" if title else f"{kind.title()} ({name})"
                renamed.setdefault(shown[0].upper(), []).append(
                    (shown, subtype, docname, anchor, docname, qualifier, "")
                )
        return sorted((k, sorted(v)) for k, v in renamed.items()), collapse

    return generate


CATALOGUE_DOC = "book/reproductions"
_CELL = re.compile(r"^```\{code-cell\}[^\n]*\n(.*?)^```\s*$", re.S | re.M)
_RUN = re.compile(r"""\b(?:book_run|reproduce)\(\s*["']([a-z0-9]+-[a-z0-9-]+)["']""")
_PLOT = re.compile(r"""\bget\(\s*["']([a-z0-9]+-[a-z0-9-]+)["']\s*\)\s*\.plot\(""")
_FIG_NAME = re.compile(r"^\s+name:\s*([\w.-]+)\s*$", re.M)
_HEADING = re.compile(r"^(#{1,6})\s+(.+?)\s*$", re.M)
_LABEL = re.compile(r"^\(([\w.-]+)\)=\s*$")


def _toc_files(confdir: Path) -> list[str]:
    from fdi_lib.reproduce.book import toc_documents

    return toc_documents(confdir)


def _occurrences(text: str):
    """(position, id, kind, figure name or None, heading, heading label or None) for each call of
    a reproduction in a code cell of a chapter: kind ``"run"`` for ``book_run``/``reproduce``,
    ``"plot"`` for ``get(ID).plot(``; the figure name is the ``name:`` of the cell's figure."""
    headings = []
    lines = text.splitlines(keepends=True)
    offsets = [0]
    for line in lines:
        offsets.append(offsets[-1] + len(line))
    fenced = False
    for i, line in enumerate(lines):
        if line.startswith("```"):
            fenced = not fenced
        m = None if fenced else _HEADING.match(line)
        if m:
            prev = lines[i - 1].strip() if i else ""
            label = _LABEL.match(prev)
            headings.append((offsets[i], m.group(2), label.group(1) if label else None))
    for cell in _CELL.finditer(text):
        body = cell.group(1)
        name = _FIG_NAME.search(body.split("\n---", 1)[0] if body.startswith("---") else "")
        head = [h for h in headings if h[0] < cell.start()]
        title, label = (head[-1][1], head[-1][2]) if head else ("", None)
        for kind, pattern in (("run", _RUN), ("plot", _PLOT)):
            for call in pattern.finditer(body):
                yield (
                    cell.start() + call.start(),
                    call.group(1),
                    kind,
                    name.group(1) if name else None,
                    title,
                    label,
                )


def shown_in(confdir: Path) -> dict[str, dict]:
    """Where the book shows each reproduction, from the chapter sources (in book order).

    Returns
    -------
    dict
        id -> ``{"doc", "figure", "section", "label"}``: the chapter (``book/<paper>/<name>``),
        the figure label (``name:``) of the first cell that *plots* the id (``get(ID).plot(``),
        ``None`` if no figure of the book draws it; the heading and heading label of the section
        of its first call. Ids are in the order of their first call in the book.
    """
    out: dict[str, dict] = {}
    for doc in _toc_files(confdir):
        path = confdir / f"{doc}.md"
        if doc.count("/") < 2 or not path.is_file():  # chapters only: book/<paper>/<chapter>
            continue
        for _pos, rid, kind, name, title, label in sorted(_occurrences(path.read_text())):
            entry = out.setdefault(
                rid, {"doc": doc, "figure": None, "section": title, "label": label}
            )
            if entry["doc"] == doc and kind == "plot" and name and entry["figure"] is None:
                entry["figure"] = name
    return out


def _paper_item(rid: str, title: str) -> str:
    m = re.search(r"-(fig|table)(\d+)$", rid)
    if m:
        return f"{'Fig.' if m.group(1) == 'fig' else 'Table'} {m.group(2)}"
    m = re.search(r"(Prop\. \d+|Remark \d+|Solution \d+|Lemma \w+)", title)
    return m.group(1) if m else "no numbered figure or table"


def _docstring_html(func, id_prefix: str) -> str:
    """The docstring rendered to HTML by docutils (numpydoc sections and definition lists).

    Docstrings are written for ``--describe`` in a terminal, not as strict reStructuredText:
    docutils renders what it can and its complaints are not shown (a docstring is never a reason
    for the build to fail); cross-reference roles become literals, ``:math:`` stays maths."""
    from docutils.core import publish_parts

    doc = inspect.getdoc(func) or ""
    doc = docstring_rst(re.sub(r":(?!math:)[\w:]+:`~?([^`]+)`", r"``\1``", doc))
    parts = publish_parts(
        doc,
        writer_name="html5",
        settings_overrides={
            "report_level": 5,
            "halt_level": 5,
            "initial_header_level": 4,
            "doctitle_xform": False,
            "embed_stylesheet": False,
            "warning_stream": False,
            "id_prefix": id_prefix,
            "math_output": "MathJax",  # \\( \\) spans that the page's MathJax typesets
        },
    )
    return parts["body"]


_GREEK = (
    "alpha beta gamma delta epsilon zeta eta theta iota kappa lambda mu nu xi pi rho sigma tau "
    "upsilon phi chi psi omega"
).split()
_ASCII_MATH = re.compile(
    r"(?<![\w\\$])(?:(?P<greek>"
    + "|".join(_GREEK + [g.title() for g in _GREEK])
    + r")|(?P<letter>[A-Za-z]))"
    r"(?:_(?P<sub>[A-Za-z0-9]+))?(?P<arg>\([a-z]\))?(?!\w)"
)


#: A numpydoc entry's line "name : type" (or "a, b : type"): its names.
_TERM_LINE = re.compile(r"^(\s*)([A-Za-z_]\w*(?:, [A-Za-z_]\w*)*)( : .*)$", re.M)
#: A name with an underscore and a word after it ("hull_area", "state2_scale"): code.
_CODE_NAME = re.compile(r"(?<![\w`\\{])([A-Za-z]\w*_(?:\w*[A-Za-z]{2,}\w*))(?![\w`}])")
_NORM = re.compile(r"\|\|([^|\n]+?)\|\|(_\w)?")


def _ascii_tex(text: str) -> str:
    r"""ASCII maths as TeX: Greek letters' names as macros, subscripts of several characters
    braced, ``max``/``min`` as operators ("max_k Gamma_k" -> ``\max_k \Gamma_k``)."""
    text = re.sub(
        r"(?<![A-Za-z\\])("
        + "|".join(_GREEK + [g.title() for g in _GREEK] + ["max", "min"])
        + r")(?![A-Za-z])",
        r"\\\1",
        text,
    )
    return re.sub(r"([_^])([A-Za-z0-9]{2,})", r"\1{\2}", text)


_SYMBOL = re.compile(
    r"(?<![\w\\`])(?:(?P<base>max|min|"
    + "|".join(_GREEK + [g.title() for g in _GREEK])
    + r")|[A-Za-z])(?:(?P<sub>_(?:\{[^{}\n]*\}|[A-Za-z0-9]+))?(?P<sup>\^(?:\{[^{}\n]*\}|[A-Za-z0-9]+))?)"
    r"(?:\([a-z]\))?(?![\w`])"
)


def docstring_rst(doc: str) -> str:
    """A registry docstring (written for a terminal) with its names as code and its ASCII maths
    as maths (issue 33: no TeX-like text outside maths on the catalogue page): the names of
    numpydoc entries and names with a worded subscript ("hull_area") as literals, symbols with
    a sub- or superscript, Greek letters' names with one, and norms ("||Gamma_k||_2") as
    ``:math:``. Literals and roles already in the text are left as they are."""

    def symbol(m: re.Match) -> str:
        if not (m["sub"] or m["sup"]):
            return m[0]
        return f":math:`{_ascii_tex(m[0])}`"

    def prose(text: str) -> str:
        text = _TERM_LINE.sub(
            lambda m: m[1] + ", ".join(f"``{n}``" for n in m[2].split(", ")) + m[3], text
        )
        parts = re.split(r"(``[^`]+``|:\w+:`[^`]+`)", text)
        for i in range(0, len(parts), 2):
            piece = _CODE_NAME.sub(r"``\1``", parts[i])
            pieces = re.split(r"(``[^`]+``)", piece)
            for j in range(0, len(pieces), 2):
                pieces[j] = _SYMBOL.sub(
                    symbol,
                    _NORM.sub(lambda m: f":math:`\\|{_ascii_tex(m[1])}\\|{m[2] or ''}`", pieces[j]),
                )
            parts[i] = "".join(pieces)
        return "".join(parts)

    return prose(doc)


def title_markdown(title: str) -> str:
    """A registry title (plain ASCII for the terminal: "Spectral norm of Gamma_k", "GLR l_k")
    as MyST with its symbols in maths: "Spectral norm of $\\Gamma_k$", "GLR $l_k$". A symbol is
    a Greek letter's name or a letter with a subscript, with an optional one-letter argument."""

    def maths(m: re.Match) -> str:
        if not (m["greek"] or m["sub"]):
            return m[0]
        sub = m["sub"] or ""
        sub = f"_{{{sub}}}" if len(sub) > 1 else f"_{sub}" if sub else ""
        return f"${chr(92) + m['greek'] if m['greek'] else m['letter']}{sub}{m['arg'] or ''}$"

    return _ASCII_MATH.sub(maths, title)


def claims_markdown(rep) -> str:
    """The claims a reproduction declares (:mod:`fdi_lib.reproduce.ledger`): each location in the
    paper with its comparison ("Fig. 8, type I error of fault … (95 % interval)"), or why none."""
    own = [c for _, c in rep.claims if not c.shown_under]
    if not own:
        under = sorted({c.shown_under for _, c in rep.claims})
        return (
            f"listed under {', '.join(f'`{u}`' for u in under)}"
            if under
            else "none (an illustration, or a study of ours)"
        )
    return "; ".join(
        f"{title_markdown(re.sub(r'{[^}]*}', '…', c.location))} ({c.test})" for c in own
    )


def catalogue_markdown(confdir: Path) -> tuple[str, list[Path]]:
    """The generated part of the catalogue page (MyST) and the files it was made from."""
    from fdi_lib.reproduce import list_reproductions
    from fdi_lib.reproduce.book import book_command, book_settings

    reps = {r.id: r for r in list_reproductions()}
    where = {rid: w for rid, w in shown_in(confdir).items() if rid in reps}
    order = list(where) + [rid for rid in reps if rid not in where]
    sources = [
        confdir / f"{doc}.md"
        for doc in _toc_files(confdir)
        if doc.count("/") >= 2 and (confdir / f"{doc}.md").is_file()
    ]
    out = []
    current = None
    for rid in order:
        r = reps[rid]
        w = where.get(rid)
        doc = w["doc"] if w else None
        if doc != current:
            current = doc
            if doc:
                title = _HEADING.search((confdir / f"{doc}.md").read_text()).group(2)
                out.append(f"## {title}\n\nChapter {{doc}}`/{doc}`.\n")
            else:
                out.append("## Not shown in a chapter\n")
        out.append(f"### {title_markdown(r.title)}\n")
        out.append(f"**Paper:** {r.paper}, {_paper_item(rid, r.title)}.  ")
        if w is None:
            out.append("**Shown in:** no chapter yet.  ")
        elif w["figure"]:
            out.append(
                f'**Shown in:** {{numref}}`{w["figure"]}`, section "{w["section"]}" of '
                f"{{doc}}`/{doc}`.  "
            )
        elif w["label"]:
            out.append(f"**Shown in:** {{ref}}`{w['label']}` of {{doc}}`/{doc}`.  ")
        else:
            out.append(f'**Shown in:** section "{w["section"]}" of {{doc}}`/{doc}`.  ')
        plot = " (`--plot FILE.png` draws the figure)" if r.plot else ""
        s = book_settings(rid)
        trials = (
            ""
            if s.trials is None
            else f"; {s.trials} Monte Carlo trial{'s' * (s.trials != 1)}, "
            + (
                f"the command line's default is {r.default_trials} (`--trials "
                f"{r.default_trials}`), more than a chapter can spend"
                if r.book_trials is not None
                else "the paper's count"
                if s.trials == r.default_trials
                else f"the paper's {r.default_trials} with `--trials {r.default_trials}`"
                if r.default_trials
                else "the book's count"
            )
        )
        out.append(f"**Command (the book's settings):** `{book_command(rid)}`{plot}{trials}.  ")
        out.append(
            f"**Claims** (declared at its registration; statuses in the "
            f"{{ref}}`claims ledger <sec-ledger>`): {claims_markdown(r)}.\n"
        )
        out.append(
            f":::{{dropdown}} What `{rid}` computes and its headline keys\n"
            f'```{{raw}} html\n<div class="fdi-docstring">\n{_docstring_html(r.func, rid + "-")}'
            f"</div>\n```\n:::\n"
        )
    modules = {Path(inspect.getsourcefile(r.func)) for r in reps.values()}
    import fdi_lib.reproduce.book as book

    return "\n".join(out), sources + sorted(modules | {Path(inspect.getsourcefile(book))})


def _generate_catalogue(app: Sphinx, docname: str, source: list[str]) -> None:
    if docname != CATALOGUE_DOC:
        return
    text, deps = catalogue_markdown(Path(app.confdir))
    for dep in deps:
        app.env.note_dependency(str(dep))
    source[0] = source[0].rstrip() + "\n\n" + text


# --- 14. The intro's map of the book, from _toc.yml -----------------------------------------
#: The page whose ``{fdi-book-map}`` block becomes the map of the book and its reading path.
MAP_DOC = "book/intro"
_MAP_BLOCK = re.compile(r"^```\{fdi-book-map\}[ \t]*\n(.*?)^```[ \t]*$", re.M | re.S)


def _toc_parts(confdir: Path) -> list[tuple[str, bool, list[str]]]:
    """``(caption, numbered, files)`` of each part of ``_toc.yml``, in book order."""
    import yaml

    toc = yaml.safe_load((confdir / "_toc.yml").read_text())
    return [
        (
            part.get("caption", ""),
            bool(part.get("numbered")),
            [c["file"] for c in part.get("chapters", []) if "file" in c],
        )
        for part in toc.get("parts", [])
    ]


#: Pages the PDF has no chapter for (its bibliography is the list at the end of the book, see
#: :class:`_NumberedParts`; the library reference is online only, ``ONLINE_ONLY`` of
#: ``tools/pdf_edition.py``): the PDF's map names them without a link.
NO_PDF_CHAPTER = ("book/bibliography", "book/api/")  # a trailing "/": every page below


def book_map_markdown(confdir: Path, block: str, unlinked: tuple[str, ...] = ()) -> str:
    """The map of the book (a table: part, page, what it holds) and the reading path (the
    numbered chapters in order), every page of ``_toc.yml`` in it. ``block`` holds one line
    ``FILE: what the page holds`` per page but the root (indented lines continue it); a page of
    the table of contents
    without a line, or a line for no page of it, is a build error. The pages in ``unlinked`` (an
    entry ending in "/": every page below it)
    are named by their title, without a link."""
    what: dict[str, str] = {}
    for line in re.sub(r"\n[ \t]+", " ", block).splitlines():  # indented: continues the last
        if line.strip():
            file, sep, text = line.partition(":")
            if not sep or not text.strip():
                raise ExtensionError(
                    f"fdi_book: book map line {line!r}: expected 'FILE: what it holds'"
                )
            what[file.strip()] = text.strip()
    parts = _toc_parts(confdir)
    files = [f for _, _, chapters in parts for f in chapters]
    missing, unknown = [f for f in files if f not in what], sorted(set(what) - set(files))
    if missing or unknown:
        raise ExtensionError(
            f"fdi_book: the map of the book in {MAP_DOC}.md needs one line per "
            f"page of _toc.yml: missing {missing}, not in _toc.yml {unknown}"
        )
    rows = ["| Part | Page | What it holds |", "|---|---|---|"]
    for caption, _, chapters in parts:
        for k, f in enumerate(chapters):
            plain = any(f == u or (u.endswith("/") and f.startswith(u)) for u in unlinked)
            source = confdir / f"{f}.md"
            title = _HEADING.search(source.read_text()).group(2) if source.is_file() else ""
            if plain:
                page = title
            elif "`" in title:  # code in the title: {doc} would show it as plain text
                page = f"[{title}](/{f}.md)"
            else:
                page = f"{{doc}}`/{f}`"
            rows.append(f"| {caption if k == 0 else ''} | {page} | {what[f]} |")
    numbered = [f for _, num, chapters in parts if num for f in chapters]
    path = "\n".join(f"{i}. {{doc}}`/{f}`" for i, f in enumerate(numbered, 1))
    return "\n".join(rows) + "\n\nThe numbered chapters, in reading order:\n\n" + path + "\n"


def _generate_book_map(app: Sphinx, docname: str, source: list[str]) -> None:
    if docname != MAP_DOC:
        return
    app.env.note_dependency(str(Path(app.confdir) / "_toc.yml"))
    confdir = Path(app.confdir)
    unlinked = NO_PDF_CHAPTER if app.builder.format == "latex" else ()
    source[0], count = _MAP_BLOCK.subn(
        lambda m: book_map_markdown(confdir, m.group(1), unlinked), source[0]
    )
    if count != 1:
        raise ExtensionError(
            f"fdi_book: {MAP_DOC}.md needs one ```{{fdi-book-map}} block, found {count}"
        )


def _add_notebook_download(
    app: Sphinx, pagename: str, templatename: str, context: dict, doctree
) -> None:
    if app.builder.format != "html" or context.get("ipynb_source"):
        return
    executed = Path(app.outdir).parent / "jupyter_execute" / f"{pagename}.ipynb"
    groups = [b for b in context.get("header_buttons", []) if b.get("label") == "download-buttons"]
    if not executed.is_file() or not groups:
        return
    target = Path(app.outdir) / "_sources" / f"{pagename}.ipynb"
    target.parent.mkdir(parents=True, exist_ok=True)
    shutil.copy2(executed, target)
    groups[0]["buttons"].insert(
        0,
        {
            "type": "link",
            "url": f"{context['pathto']('_sources', 1)}/{pagename}.ipynb",
            "text": ".ipynb",
            "icon": "fas fa-code",
            "tooltip": "Download the notebook (executed)",
            "label": "download-notebook-button",
        },
    )


def _render_notebook_downloads(app: Sphinx, exception: Exception | None) -> None:
    """The ".ipynb" downloads in Markdown that Jupyter renders: the book's macros defined, MyST
    roles, directives and glue references resolved (``tools/notebook_markdown.py``, loaded from
    the repository of :mod:`fdi_lib`: the student edition builds a copy of the sources without
    ``tools``)."""
    if (
        exception is not None
        or app.builder.format != "html"
        or not (Path(app.outdir) / "_sources").is_dir()
    ):
        return
    if not (
        Path(app.confdir) / "_toc.yml"
    ).is_file():  # a Sphinx project, not a Jupyter Book: no numbering
        logger.info("fdi_book: no _toc.yml, the notebook downloads are left as built")
        return
    import fdi_lib

    path = Path(fdi_lib.__file__).resolve().parents[1] / "tools" / "notebook_markdown.py"
    spec = importlib.util.spec_from_file_location("notebook_markdown", path)
    module = sys.modules.setdefault("notebook_markdown", importlib.util.module_from_spec(spec))
    spec.loader.exec_module(module)
    done = module.convert_downloads(
        Path(app.outdir),
        Path(app.confdir),
        Path(app.outdir).parent / "jupyter_execute",
        _book_macros(app.config),
    )
    logger.info("fdi_book: %d notebook downloads in plain Markdown", len(done))


def _drop_thebe_scripts(app: Sphinx, env, docnames) -> None:
    """Remove sphinx-thebe's scripts: Jupyter Book always loads the extension, but this book has
    no Thebe button (it would load Thebe from a CDN), and the extension declares its constants
    twice on every page (a console error)."""

    def keep(js) -> bool:  # registry entries are (filename, attributes); builder's are objects
        name = getattr(js, "filename", js[0] if isinstance(js, tuple) else "") or ""
        attrs = getattr(js, "attributes", js[1] if isinstance(js, tuple) else {}) or {}
        return "sphinx-thebe" not in name and "THEBE_JS_URL" not in str(attrs.get("body", ""))

    app.registry.js_files = [js for js in app.registry.js_files if keep(js)]
    if hasattr(app.builder, "_js_files"):
        app.builder._js_files = [js for js in app.builder._js_files if keep(js)]


#: myst-nb's execution table marks a chapter's status with emoji, which a reader without an
#: emoji font (headless Chromium on Debian, many offline Linux machines) sees as empty boxes.
_STATUS_WORDS = {"\u2705": "ok", "\u274c": "failed"}


def _plain_status_words(app: Sphinx, doctree, docname: str) -> None:
    """The execution table's status in words (after myst-nb's post-transform has built it)."""
    for table in doctree.findall(nodes.table):
        for text in list(table.findall(nodes.Text)):
            word = _STATUS_WORDS.get(text.astext())
            if word is not None:
                text.parent.replace(text, nodes.Text(word))


# --- 8. Maths as readable text -------------------------------------------------------------
# Written here rather than taken from a library: the environment has no TeX-to-Unicode
# converter (latexcodec, which pybtex uses, leaves maths as it is; pylatexenc would be a new
# dependency for a few dozen symbols). It covers the maths the book writes in headings and
# captions; an unknown command is shown by its name, never with its backslash.


def _greek(name: str) -> str:
    base = name[3:] if name.startswith("var") else name
    case = "CAPITAL" if base[0].isupper() else "SMALL"
    try:
        return unicodedata.lookup(f"GREEK {case} LETTER {base.upper().replace('LAMBDA', 'LAMDA')}")
    except KeyError:
        return ""


_SYMBOLS = {
    "le": "≤",
    "leq": "≤",
    "ge": "≥",
    "geq": "≥",
    "ne": "≠",
    "neq": "≠",
    "sim": "~",
    "approx": "≈",
    "equiv": "≡",
    "propto": "∝",
    "ll": "≪",
    "gg": "≫",
    "in": "∈",
    "notin": "∉",
    "subset": "⊂",
    "subseteq": "⊆",
    "cup": "∪",
    "cap": "∩",
    "emptyset": "∅",
    "times": "×",
    "cdot": "·",
    "pm": "±",
    "mp": "∓",
    "infty": "∞",
    "to": "→",
    "rightarrow": "→",
    "leftarrow": "←",
    "mapsto": "↦",
    "ldots": "…",
    "dots": "…",
    "cdots": "⋯",
    "sum": "Σ",
    "prod": "Π",
    "int": "∫",
    "partial": "∂",
    "nabla": "∇",
    "top": "ᵀ",
    "prime": "′",
    "forall": "∀",
    "exists": "∃",
    "ell": "ℓ",
    "circ": "∘",
    "otimes": "⊗",
    "oplus": "⊕",
    "star": "⋆",
    "ast": "*",
    "mid": "|",
    "vert": "|",
    "lvert": "|",
    "rvert": "|",
    "Vert": "‖",
    "lVert": "‖",
    "rVert": "‖",
    "langle": "⟨",
    "rangle": "⟩",
    "quad": " ",
    "qquad": " ",
    "setminus": "∖",
    "perp": "⊥",
    "dagger": "†",
    "lfloor": "⌊",
    "rfloor": "⌋",
    "lceil": "⌈",
    "rceil": "⌉",
    "neg": "¬",
    "land": "∧",
    "lor": "∨",
    "Rightarrow": "⇒",
    "iff": "⇔",
    "implies": "⇒",
}
_ESCAPES = {
    ",": " ",
    ";": " ",
    ":": " ",
    " ": " ",
    "!": "",
    "|": "‖",
    "{": "{",
    "}": "}",
    "\\": "; ",
    "%": "%",
    "$": "$",
    "&": "&",
    "#": "#",
    "_": "_",
}
_FONTS = {
    "mathrm",
    "mathit",
    "mathbf",
    "mathsf",
    "mathcal",
    "mathscr",
    "mathfrak",
    "boldsymbol",
    "bm",
    "text",
    "textrm",
    "textit",
    "textbf",
    "mbox",
    "operatorname",
    "mathbb",
}
_ACCENTS = {
    "hat": "\u0302",
    "widehat": "\u0302",
    "bar": "\u0304",
    "overline": "\u0305",
    "tilde": "\u0303",
    "widetilde": "\u0303",
    "dot": "\u0307",
    "ddot": "\u0308",
    "vec": "\u20d7",
    "check": "\u030c",
    "breve": "\u0306",
}
_SIZES = {
    "left",
    "right",
    "big",
    "Big",
    "bigg",
    "Bigg",
    "bigl",
    "bigr",
    "Bigl",
    "Bigr",
    "biggl",
    "biggr",
    "displaystyle",
    "textstyle",
    "scriptstyle",
    "limits",
    "nolimits",
}


class _TexText:
    """Recursive reader of a TeX maths string; :meth:`read` returns its readable text."""

    def __init__(self, tex: str, macros: dict[str, str]):
        self.s, self.i, self.macros, self.depth = tex, 0, macros, 0

    def read(self, stop: str = "") -> str:
        out = []
        while self.i < len(self.s) and self.s[self.i] not in stop:
            c = self.s[self.i]
            if c in "^_":
                self.i += 1
                out.append(script_text(self.atom(), c))
            elif c == "&":
                self.i += 1
                out.append(" ")
            elif c == "~" or c.isspace():  # the source's spacing, collapsed at the end
                self.i += 1
                out.append(" ")
            else:
                out.append(self.atom())
        return "".join(out)

    def atom(self) -> str:
        """One group, command (with its arguments) or character."""
        while self.i < len(self.s) and self.s[self.i] == " ":
            self.i += 1
        if self.i >= len(self.s):
            return ""
        c = self.s[self.i]
        if c == "{":
            self.i += 1
            text = self.read("}")
            self.i += 1
            return text
        if c != "\\":
            self.i += 1
            return "−" if c == "-" else c
        m = re.match(r"\\([a-zA-Z]+)", self.s[self.i :])
        if not m:
            self.i += 2
            return _ESCAPES.get(self.s[self.i - 1 : self.i], self.s[self.i - 1 : self.i])
        self.i += m.end()
        return self.command(m.group(1))

    def command(self, name: str) -> str:
        if name in self.macros and self.depth < 10:
            inner = _TexText(self.macros[name], self.macros)
            inner.depth = self.depth + 1
            return inner.read()
        if name == "mathbb":
            arg = self.atom()
            for prefix in ("", "MATHEMATICAL "):
                try:
                    return "".join(
                        unicodedata.lookup(f"{prefix}DOUBLE-STRUCK CAPITAL {a}") for a in arg
                    )
                except KeyError:
                    continue
            return arg
        if name in _FONTS:
            return self.atom()
        if name in _ACCENTS:
            return self.atom() + _ACCENTS[name]
        if name in ("frac", "dfrac", "tfrac"):
            num, den = self.atom(), self.atom()
            wrap = lambda t: t if len(t) <= 1 or t.isalnum() else f"({t})"  # noqa: E731
            return f"{wrap(num)}/{wrap(den)}"
        if name == "sqrt":
            if self.s.startswith("[", self.i):
                self.i = self.s.index("]", self.i) + 1
            arg = self.atom()
            return f"√{arg}" if len(arg) <= 1 else f"√({arg})"
        if name in ("begin", "end"):
            self.atom()
            return " " if name == "end" else ""
        if name in _SIZES:
            return ""
        return _SYMBOLS.get(name) or _greek(name) or name


def tex_to_text(tex: str, macros: dict[str, str] | None = None) -> str:
    """TeX maths as readable plain text: Greek letters and symbols in Unicode, sub- and
    superscripts in Unicode where they exist, accents as combining marks, font commands
    dropped. ``macros`` are the book's own (``mathjax3_config``), expanded first.

    >>> tex_to_text(r"\\hat\\theta_k \\le \\|\\alpha_k(r)\\|_2, A^\\T", {"T": r"\\mathsf{T}"})
    'θ̂ₖ ≤ ‖αₖ(r)‖₂, Aᵀ'
    """
    return re.sub(r"\\s+", " ", _TexText(tex, macros or {}).read()).strip()


def _macro_definitions(config) -> dict[str, tuple[str, int]]:
    """The book's maths macros, ``name -> (body, number of arguments)``, from MathJax's
    configuration (a macro is ``"body"`` or ``["body", n]`` there)."""
    macros = ((getattr(config, "mathjax3_config", None) or {}).get("tex") or {}).get("macros") or {}
    return {
        k: (v, 0) if isinstance(v, str) else (v[0], int(v[1]) if len(v) > 1 else 0)
        for k, v in macros.items()
    }


def _book_macros(config) -> dict[str, str]:
    return {k: body for k, (body, _) in _macro_definitions(config).items()}


def readable_text(node: nodes.Node, macros: dict[str, str]) -> str:
    """The text of ``node`` with its maths as :func:`tex_to_text` (raw nodes left out, as
    :func:`sphinx.util.nodes.clean_astext` does)."""
    parts = []
    for n in node.findall(lambda n: isinstance(n, (nodes.Text, nodes.math))):
        if isinstance(n, nodes.math):
            parts.append(tex_to_text(n.astext(), macros))
        elif not any(isinstance(a, (nodes.math, nodes.raw)) for a in _ancestors(n, node)):
            parts.append(n.astext())
    return re.sub(r"\s+", " ", "".join(parts)).strip()


def _ancestors(n: nodes.Node, top: nodes.Node):
    n = n.parent
    while n is not None and n is not top:
        yield n
        n = n.parent


def _readable_section_labels(app: Sphinx, doctree) -> None:
    """References to a heading with maths carry its readable text: the standard domain records a
    heading's text for ``{ref}`` as the raw TeX of its maths ("The rule for \\\\lambda")."""
    labels = app.env.get_domain("std").labels
    macros = _book_macros(app.config)
    docname = app.env.docname
    for name, (doc, labelid, sectname) in list(labels.items()):
        if doc != docname or not sectname:
            continue
        section = doctree.ids.get(labelid)
        if not isinstance(section, nodes.section) or not any(section[0].findall(nodes.math)):
            continue
        if clean_astext(section[0]) == sectname:
            labels[name] = (doc, labelid, readable_text(section[0], macros))


def _alt_from_captions(app: Sphinx, doctree, docname: str) -> None:
    """Every figure's image has its caption as alt text (Sphinx writes the file path when a
    figure, such as myst-nb's, gives none)."""
    macros = _book_macros(app.config)
    for figure in doctree.findall(nodes.figure):
        captions = [c for c in figure.findall(nodes.caption)]
        text = readable_text(captions[0], macros) if captions else ""
        for image in figure.findall(nodes.image):
            if text and (not image.get("alt") or image.get("alt") == image.get("uri")):
                image["alt"] = text


# --- 9. Lighter pages; 10. hover previews offline ------------------------------------------
EXT_DIR = Path(__file__).resolve().parent
PREVIEWS_JS = "fdi-previews.js"
PREVIEWS_CSS = "fdi-previews.css"
TIPPY_JS_PREFIX = "vendor/tippy/"


def _add_ext_paths(app: Sphinx, config) -> None:
    """This extension's templates (the layout without the Font Awesome script) and static files
    (tippy.js, Popper, the previews script), which the build copies to ``_static``. They live
    here, not in the book's ``_static``, where Jupyter Book adds every script to every page."""
    if config.html_theme in ("sphinx_book_theme", "pydata_sphinx_theme"):  # themes with the script
        config.templates_path = [*config.templates_path, str(EXT_DIR / "templates")]
    config.html_static_path = [*config.html_static_path, str(EXT_DIR / "static")]


def without_script(html: str, name: str) -> Markup:
    """``html`` without its ``<script src=...name...>`` tag (a Jinja filter of the layout).

    Raises :class:`~sphinx.errors.ExtensionError` when there is no such tag: the theme has
    changed how it loads the script, and ``templates/layout.html`` must follow."""
    tag = re.compile(
        r"\s*<script\b[^>]*\bsrc=\"[^\"]*" + re.escape(name) + r"[^\"]*\"[^>]*>\s*</script>"
    )
    out, count = tag.subn("", str(html))
    if count == 0:
        raise ExtensionError(
            f"fdi_book: the theme's page head has no <script> for {name!r} to drop; "
            "update _ext/templates/layout.html"
        )
    return Markup(out)


def _register_filters(app: Sphinx) -> None:
    environment = getattr(getattr(app.builder, "templates", None), "environment", None)
    if environment is not None:
        environment.filters["fdi_without_script"] = without_script


def _static_name(js) -> str:
    """A page script's path under ``_static`` (the builder stores ``_static/NAME``)."""
    return str(js.filename or "").removeprefix("_static/")


def _has_previews(scripts) -> bool:
    return any(_static_name(js).startswith(TIPPY_JS_PREFIX) for js in scripts)


def _mathjax_where_needed(
    app: Sphinx, pagename: str, templatename: str, context: dict, doctree
) -> None:
    """MathJax (1.2 MB with its fonts) only on a page with maths of its own.

    Sphinx's test also counts the maths of the pages a page's toctree includes (for the
    single-page builder), so the root page, whose toctree is the whole book, loads MathJax for
    none. Here a page without maths of its own loses MathJax's scripts; if it has previews,
    ``window.fdiMathJax`` tells ``fdi-previews.js`` where MathJax is and how the book configures
    it, to load it when a preview with maths is first shown."""
    if app.builder.format != "html" or "script_files" not in context:
        return
    if app.env.get_domain("math").data["has_equations"].get(pagename, False):
        return
    scripts = context["script_files"]

    def is_mathjax(js) -> bool:
        return _static_name(js) == app.config.mathjax_path or str(
            js.attributes.get("body", "")
        ).startswith("window.MathJax")

    scripts[:] = [js for js in scripts if not is_mathjax(js)]
    if _has_previews(scripts):
        lazy = {
            "src": context["pathto"](f"_static/{app.config.mathjax_path}", 1),
            "config": app.config.mathjax3_config or {},
        }
        app.builder.add_js_file("", body=f"window.fdiMathJax = {json.dumps(lazy)}")


ICON_CSS = "fdi-icons.css"
ICON_FONT = "fdi-icons.woff"
THEME_CSS = "_static/styles/pydata-sphinx-theme.css"
THEME_SOLID_FONT = "_static/vendor/fontawesome/webfonts/fa-solid-900.ttf"
_ICON_RULE = re.compile(r'((?:\.fa-[\w-]+:before,?)+)\{content:"\\([0-9a-f]{4})"\}')
# a private-use codepoint in a stylesheet, escaped ("\f107") or as the character itself
_PUA_CONTENT = re.compile(r"\\([ef][0-9a-f]{3})\b|([\ue000-\uf8ff])")


def icon_codepoints(outdir: Path) -> set[int]:
    """The Font Awesome codepoints the built HTML at ``outdir`` can show: the icon classes
    (``fa-bars``) written in its pages and scripts (the Font Awesome script itself excepted: it
    names them all), and every icon the stylesheets draw themselves (admonitions, links: any
    private-use codepoint outside the icon classes' rules, ``--pst-icon-*`` included)."""
    theme_css = (outdir / THEME_CSS).read_text()
    classes = {
        name: int(code, 16)
        for rule, code in _ICON_RULE.findall(theme_css)
        for name in re.findall(r"\.(fa-[\w-]+):before", rule)
    }
    used: set[str] = set()
    files = [
        *outdir.rglob("*.html"),
        *(p for p in (outdir / "_static").rglob("*.js") if p.name != "fontawesome.js"),
    ]
    for path in files:
        used |= set(re.findall(r"\bfa-[a-z0-9-]+", path.read_text(errors="replace")))
    codes = {classes[name] for name in used if name in classes}
    for css in (outdir / "_static").rglob("*.css"):
        text = _ICON_RULE.sub("", css.read_text(errors="replace"))
        codes |= {int(esc, 16) if esc else ord(char) for esc, char in _PUA_CONTENT.findall(text)}
    return codes


def subset_icon_font(app: Sphinx, exception: Exception | None) -> None:
    """``_static/fdi-icons.woff``: the theme's solid Font Awesome font (its TrueType copy: the
    WOFF2 one needs brotli to read) with only those of :func:`icon_codepoints` it has, for
    ``fdi-icons.css``. fontTools (a matplotlib dependency) does the cutting."""
    if (
        exception is not None
        or app.builder.format != "html"
        or app.config.html_theme not in ("sphinx_book_theme", "pydata_sphinx_theme")
    ):
        return
    from fontTools import subset
    from fontTools.ttLib import TTFont

    outdir = Path(app.outdir)
    codes = icon_codepoints(outdir)
    font = TTFont(outdir / THEME_SOLID_FONT)
    # the brands and regular faces (GitHub's icon, weight 400) keep the theme's own fonts
    codes &= set(font.getBestCmap())
    options = subset.Options()
    options.flavor = "woff"
    subsetter = subset.Subsetter(options)
    subsetter.populate(unicodes=codes)
    subsetter.subset(font)
    font.flavor = "woff"
    font.save(outdir / "_static" / ICON_FONT)
    logger.info("fdi_book: %d icons in %s", len(codes), ICON_FONT)


def _add_previews_script(
    app: Sphinx, pagename: str, templatename: str, context: dict, doctree
) -> None:
    """``fdi-previews.js`` (after tippy.js) and ``fdi-previews.css`` on every page that
    sphinx-tippy gives previews."""
    if app.builder.format == "html" and _has_previews(context.get("script_files", [])):
        app.builder.add_js_file(PREVIEWS_JS, defer="defer")
        app.builder.add_css_file(PREVIEWS_CSS)


#: What :func:`preview_html` takes out or changes: a script, the sliders, a permalink, an image.
_PREVIEW_EDITS = re.compile(r"<script|fdi-explorable-sliders|headerlink|<img", re.IGNORECASE)


def preview_html(html: str) -> str:
    """A preview's HTML without what only works on its own page: scripts (an explorable's
    holds all its frames, megabytes), sliders and permalink anchors. Its images stay, loaded
    lazily: tippy.js builds every preview of a page when the page loads, and an image file in
    one would be fetched then, shown or not (a data: image is in the previews' script already).
    A preview with none of them (most: paragraphs, equations, headings) is returned as it is
    without being parsed: sphinx-tippy wrote it with BeautifulSoup already, and parsing it again
    gives the same text (828 of the book's 1,164 shown previews; 1.7 -> 0.3 s of the build)."""
    if not _PREVIEW_EDITS.search(html):
        return html
    from bs4 import BeautifulSoup

    soup = BeautifulSoup(html, "html.parser")
    for tag in soup.select("script, .fdi-explorable-sliders, a.headerlink"):
        tag.decompose()
    for img in soup.find_all("img"):
        if not str(img.get("src", "")).startswith("data:"):
            img["loading"] = "lazy"
    return str(soup)


def _lighter_previews(app: Sphinx, exception: Exception | None) -> None:
    """Applies :func:`preview_html` to every preview a link shows before sphinx-tippy writes
    them (its ``build-finished`` handler runs at the default priority, after this one). The
    others (most paragraphs of every page) are never written: :func:`shown_previews`."""
    if exception is not None or app.builder.format != "html":
        return
    pages = getattr(app.env, "tippy_data", {}).get("pages", {})
    for name, key in shown_previews(pages):
        pages[name]["id_to_html"][key] = preview_html(pages[name]["id_to_html"][key])


def shown_previews(pages: dict[str, dict]) -> set[tuple[str, str | None]]:
    """``(page, key)`` of every preview in sphinx-tippy's ``pages`` that a link of a page shows,
    found as sphinx-tippy's ``write_tippy_props_page`` finds them (``key`` ``None``: the page's
    title)."""
    out = set()
    for name, data in pages.items():
        for refpage, target in data["refs_in_page"]:
            page = name if refpage is None else refpage
            if page not in pages:
                continue
            key = None if target is None else pages[page]["element_id_map"].get(target)
            if (target is None or key is not None) and key in pages[page]["id_to_html"]:
                out.add((page, key))
    return out


# --- 11. The PDF edition -------------------------------------------------------------------
#: File name of the PDF edition, in ``_build/pdf/`` and beside the HTML pages.
PDF_NAME = "fdi-book.pdf"
#: The A4 edition, beside :data:`PDF_NAME` (US letter, Sphinx's default paper).
A4_NAME = "fdi-book-a4.pdf"
#: Script of the HTML pages that adds the PDF to the header's download menu when it is there.
PDF_SCRIPT = "fdi-pdf.js"
_PDF_JS = """// The PDF edition in the header's download menu, when `make pdf` has put it beside the pages
// (written by _ext/fdi_book.py: the HTML build cannot know whether a PDF will follow).
(function () {
  const pdf = %s, a4 = %s;
  if (!pdf) return;
  document.addEventListener("DOMContentLoaded", function () {
    const menu = document.querySelector(".dropdown-download-buttons .dropdown-menu");
    if (!menu) return;
    const root = document.documentElement.dataset.content_root || "";
    [[a4, "A4", "book (PDF, A4)"], [pdf, "US letter", "book (PDF)"]].forEach(function (e) {
      if (!e[0]) return;
      const li = document.createElement("li"), a = document.createElement("a");
      a.href = root + e[0];
      a.className = "btn btn-sm btn-download-book-pdf-button dropdown-item";
      a.title = "Download the whole book (PDF edition, " + e[1] + " paper)";
      a.innerHTML = '<span class="btn__icon-container"><i class="fas fa-book"></i></span>' +
        '<span class="btn__text-container">' + e[2] + '</span>';
      li.appendChild(a);
      menu.insertBefore(li, menu.firstChild);
    });
  });
})();
"""


def publish_pdf(html_dir: Path, pdf: Path | None) -> None:
    """Put ``pdf`` beside the HTML pages in ``html_dir`` (as :data:`PDF_NAME`), with its A4
    edition when there is one beside it (:data:`A4_NAME`), and let every page's download menu
    link them; with ``pdf`` None, the pages link no PDF."""
    a4 = None if pdf is None else pdf.with_name(A4_NAME)
    for source, name in ((pdf, PDF_NAME), (a4, A4_NAME)):
        target = html_dir / name
        if source is not None and source.is_file() and source.resolve() != target.resolve():
            shutil.copy2(source, target)
    a4_there = a4 is not None and (html_dir / A4_NAME).is_file()
    script = html_dir / "_static" / PDF_SCRIPT
    script.parent.mkdir(parents=True, exist_ok=True)
    script.write_text(
        _PDF_JS
        % (
            json.dumps(PDF_NAME if pdf is not None else None),
            json.dumps(A4_NAME if a4_there else None),
        )
    )


def _pdf_script(app: Sphinx, exception: Exception | None) -> None:
    if exception is not None or app.builder.format != "html":
        return
    # the PDF of an earlier `make pdf` (``_build/pdf``, beside ``_build/html``), or one it put
    # beside the pages (book-fast keeps them): the pages link it whichever ran last
    found = [
        p
        for p in (Path(app.outdir).parent / "pdf" / PDF_NAME, Path(app.outdir) / PDF_NAME)
        if p.is_file()
    ]
    publish_pdf(Path(app.outdir), found[0] if found else None)


def _record_run_times(app: Sphinx, env) -> None:
    """Each chapter's execution time beside its executed notebook (``jupyter_execute/<doc>.
    exec.json``) when this build executed it: the PDF edition, which takes the notebooks of the
    HTML build (``tools/pdf_edition.py``), shows them on its status page.

    In execution mode ``cache`` (``make book``, whose chapters ``tools/execute_book.py`` executed
    side by side just before, and ``make book-fast``) myst-nb takes the outputs from the
    jupyter-cache but writes the notebook as read, without them: the executed one is written
    instead (:func:`_write_cached_notebook`), as in mode ``force``, for the ".ipynb" downloads and
    the PDF edition."""
    from myst_nb.sphinx_ import NbMetadataCollector

    folder = Path(app.outdir).parent / "jupyter_execute"
    for docname in sorted(env.found_docs):
        data = NbMetadataCollector.get_exec_data(env, docname) or {}
        if data.get("method") == "cache" and data.get("succeeded"):
            _write_cached_notebook(
                folder / f"{docname}.ipynb", env.mystnb_config.execution_cache_path
            )
        if (
            data.get("method") in ("force", "cache")
            and data.get("succeeded")
            and data.get("runtime") is not None
        ):
            path = folder / f"{docname}.exec.json"
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps({"runtime": data["runtime"]}))


def _write_cached_notebook(path: Path, cache_path: str) -> None:
    """Replace the notebook myst-nb wrote at ``path`` by its executed version from the jupyter-cache
    at ``cache_path``, its glued values taken out as myst-nb does in mode ``force``
    (``extract_glue_data``: they are in ``<doc>.glue.json``)."""
    import nbformat
    from jupyter_cache import get_cache
    from myst_nb.ext.glue import extract_glue_data

    if not path.is_file():  # an incremental build that did not read the page: nothing written
        return
    nb = nbformat.read(path, as_version=4)
    try:
        _, executed = get_cache(cache_path or ".jupyter_cache").merge_match_into_notebook(nb)
    except KeyError:  # not in the cache: myst-nb executed it, and wrote it so
        return
    extract_glue_data(executed, [0] * len(executed.cells), logger)
    nbformat.write(executed, path)


def latex_macros(config) -> str:
    """The book's maths macros as LaTeX definitions (``\\providecommand`` then
    ``\\renewcommand``: a macro of the book wins over a command of the same name)."""
    out = []
    for name, (body, nargs) in _macro_definitions(config).items():
        args = f"[{nargs}]" if nargs else ""
        out.append(f"\\providecommand{{\\{name}}}{{}}\\renewcommand{{\\{name}}}{args}{{{body}}}")
    return "\n".join(out)


#: ``bbm.sty`` for the LaTeX build (see 9. in the module docstring).
_BBM_STY = r"""\ProvidesPackage{bbm}[2026/01/01 fdi-book stand-in: mathbbm as amssymb mathbb, no bbm fonts]
\providecommand{\mathbbm}[1]{\mathbb{#1}}
"""


#: Fonts, by family, for a script character that the font in use lacks: GNU FreeFont (Sphinx's
#: fonts for xelatex) has ``ₖ`` in no face and ``ᵀ`` only in FreeSerif upright and bold. DejaVu
#: (Debian's fonts-dejavu-core and -extra) has every character of
#: :data:`fdi_lib.explorables._SCRIPTS` in every face, unscaled: its monospaced face has
#: FreeMono's advance width (0.6 em), so that a code listing keeps its columns. (DejaVu Serif
#: Bold draws ``ᵀ`` as an ``S``; FreeSerif Bold has the character, so it is never asked for it.)
SCRIPT_FALLBACK_FONTS = {"rm": "DejaVu Serif", "sf": "DejaVu Sans", "tt": "DejaVu Sans Mono"}


def latex_script_fallback() -> str:
    """Preamble lines that set each sub- and superscript character which plain-text captions
    and tables use (:data:`fdi_lib.explorables._SCRIPTS`: "Γₖ", "Hᵀ") in
    :data:`SCRIPT_FALLBACK_FONTS` where the current font lacks it, in any context (text, table
    cell, caption, heading, code listing).

    XeTeX inserts the tokens of ``\\XeTeXinterchartoks`` before each such character (its
    class), and they typeset the character in a group, in the fallback font of the current
    family (series and shape kept) unless ``\\iffontchar`` finds it in the current font. The
    characters stay ordinary characters: nothing is active or maths (``newunicodechar`` with
    ``\\textsubscript`` broke table cells), and bookmarks and labels see plain Unicode.
    fontspec has no fallback font for XeTeX (only LuaTeX's), and ucharclasses switches whole
    Unicode blocks (Latin-1 Supplement, where ``¹`` is, with them), hence these lines. The
    classes are set at ``\\begin{document}``: sphinx-jupyterbook-latex loads ucharclasses
    after this preamble, which gives Latin and Greek letters classes of their own, so the
    tokens are set from every class (and from a non-character, 4095) to this one."""
    from fdi_lib.explorables import _SCRIPTS

    codes = sorted({ord(c) for _, scripted in _SCRIPTS.values() for c in scripted})
    fonts = [
        f"\\newfontfamily\\fdi@script{family}{{{font}}}"
        for family, font in SCRIPT_FALLBACK_FONTS.items()
    ]
    return "\n".join(
        [
            "\\makeatletter",
            *fonts,
            r"\def\fdi@scriptfont{\edef\fdi@f{\f@family}\edef\fdi@tt{\ttdefault}\edef\fdi@sf{\sfdefault}%",
            r"  \ifx\fdi@f\fdi@tt\fdi@scripttt\else\ifx\fdi@f\fdi@sf\fdi@scriptsf\else\fdi@scriptrm\fi\fi}",
            # the interchar tokens are off in the group, where the character comes again
            r"\def\fdi@script#1{{\XeTeXinterchartokenstate=\z@\iffontchar\font`#1 \else\fdi@scriptfont\fi#1}}",
            r"\newXeTeXintercharclass\fdi@scriptclass",
            r"\AtBeginDocument{%",
            *(f'  \\XeTeXcharclass"{code:04X}=\\fdi@scriptclass' for code in codes),
            r"  \count@=\z@",
            r"  \loop\XeTeXinterchartoks\count@\fdi@scriptclass={\fdi@script}%",
            r"  \ifnum\count@<\xe@alloc@intercharclass\advance\count@\@ne\repeat",
            r"  \XeTeXinterchartoks\e@alloc@intercharclass@top\fdi@scriptclass={\fdi@script}%",
            r"  \XeTeXinterchartokenstate=\@ne}",
            "\\makeatother",
        ]
    )


#: Preamble lines for the printed layout (issue 33; ``tools/check_pdf.py`` fails on what they
#: prevent): tables ragged-right (tabulary's ``L`` for Sphinx's ``T``, which is ``J``,
#: justified into wide gaps), a table column never squeezed below 5 em (tabulary's ``\tymin``:
#: Sphinx's 3 digits left "week" and "99.4 %" wider than their column), and an image at most 80 %
#: of the text height, so that a figure and its caption fit on a page (Sphinx caps the image
#: alone at the text height: "Float too large for page"). A float stays in its section
#: (placeins), so that a page's running footer names the section its figures belong to. And
#: LaTeX passes that converge: the end-of-run check of the labels compares their text, not
#: their tokens. unicode-math gives the
#: Greek letters of the text (a caption's "Γ", a heading's "α") catcode 12 at
#: ``\begin{document}``, after the ``.aux`` was read with catcode 11, so that a label with one
#: never matched its stored self and every pass asked for a rerun ("Label(s) may have changed").
#: And a framed box (Sphinx's admonitions: exercises, solutions) that a page break splits keeps
#: its first part on the page: framed.sty splits the box (``\vsplit``) with TeX's default
#: ``\splitmaxdepth`` (any depth) and then boxes the part with no depth, so that the depth of
#: its last line or code cell (up to 20 pt) went into the bottom margin ("Overfull \vbox ...
#: detected at" the box's end: 13 over 5 pt in the two editions of December 2026); split with no
#: depth, the part is measured as it is set. And a name from the code (``\sphinxcode``) may break
#: after its underscores: unbroken, ``alpha_slack_deg`` in a ledger cell stood 6 pt beyond its
#: column in the A4 edition.
LATEX_LAYOUT = r"""\newcolumntype{T}{L}
\usepackage[section]{placeins}
\setlength{\tymin}{5em}
\makeatletter\AtBeginDocument{\spx@image@maxheight=0.8\textheight}
\AtBeginDocument{\patchcmd{\fb@put@frame}{\boxmaxdepth\z@\splittopskip\z@}%
  {\boxmaxdepth\z@\splittopskip\z@\splitmaxdepth\z@}{}{\errmessage{fdi-book: framed.sty changed}}}
\def\@testdef#1#2#3{\edef\reserved@a{\detokenize{#3}}%
  \edef\reserved@b{\expandafter\expandafter\expandafter\detokenize
    \expandafter\expandafter\expandafter{\csname #1@#2\endcsname}}%
  \ifx\reserved@a\reserved@b\else\@tempswatrue\fi}
\let\fdi@upquote\sphinxupquote
\protected\def\sphinxupquote#1{\fdi@upquote{\let\_\fdiUnderscore#1}}
\def\fdiUnderscore{\textunderscore\allowbreak}
\makeatother
"""


def _latex_preamble(app: Sphinx, config) -> None:
    elements = config.latex_elements
    elements.setdefault("tableofcontents", "\\sphinxtableofcontents\n\\listoffigures\n")
    elements["preamble"] = (
        elements.get("preamble", "") + "\n% fdi-book: the maths macros of the book "
        "(mathjax3_config in _config.yml)\n" + latex_macros(config) + "\n"
        "% sub- and superscript characters the text font lacks, from DejaVu\n"
        + latex_script_fallback()
        + "\n"
        + LATEX_LAYOUT
    )


def _latex_exercise_targets(app: Sphinx, doctree, docname: str) -> None:
    """A ``{ref}`` to an exercise reaches it in the PDF: sphinx-exercise labels an exercise
    ``exercise:<label>`` in LaTeX, where such a reference points at ``<page>:<label>`` (a dead
    link, "Hyper reference ... undefined", which ``tools/check_pdf.py`` fails); each exercise
    gets that label too, just before it."""
    if app.builder.format != "latex":
        return
    from sphinx_exercise.nodes import exercise_enumerable_node, exercise_node

    registry = getattr(app.env, "sphinx_exercise_registry", {})
    for node in list(
        doctree.findall(lambda n: isinstance(n, (exercise_node, exercise_enumerable_node)))
    ):
        label = node.get("label")
        page = registry.get(label, {}).get("docname") if label else None
        if page:
            target = f"{page}:{label}"
            node.parent.insert(
                node.parent.index(node),
                nodes.raw(
                    "", f"\\phantomsection\\label{{\\detokenize{{{target}}}}}\n", format="latex"
                ),
            )


def _latex_files(app: Sphinx) -> None:
    if app.builder.name != "latex":
        return
    out = Path(app.outdir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "bbm.sty").write_text(_BBM_STY)


def _version(confdir: Path) -> str:
    """The library's version and, in a git checkout, ``git describe`` of the sources."""
    import fdi_lib

    try:
        described = subprocess.run(
            ["git", "describe", "--tags", "--always", "--dirty"],
            cwd=confdir,
            capture_output=True,
            text=True,
            timeout=30,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        described = ""
    return f"{fdi_lib.__version__} (git {described})" if described else fdi_lib.__version__


def _latex_escape(text: str) -> str:
    return re.sub(r"([&%$#_{}])", r"\\\1", text).replace("~", r"\textasciitilde{}")


#: The glued value of the ledger page that the cover shows (``book/zz-ledger.md``).
LEDGER_DOC, LEDGER_GLUE = "book/zz-ledger", "ledger-counts-by-paper"


def ledger_counts(app: Sphinx) -> dict[str, dict[str, int]]:
    """``{paper: {status: claims}}`` as the ledger page of this build computed it
    (:meth:`fdi_lib.reproduce.ledger.Ledger.counts_by_paper`, glued by the page)."""
    path = Path(app.outdir).parent / "jupyter_execute" / f"{LEDGER_DOC}.glue.json"
    if not path.is_file():
        raise FileNotFoundError(f"the cover needs the ledger page's glue data: no {path}")
    glued = json.loads(path.read_text())
    if LEDGER_GLUE not in glued:
        raise KeyError(f"the cover needs {LEDGER_GLUE!r} glued by {LEDGER_DOC}: not in {path}")
    return ast.literal_eval(glued[LEDGER_GLUE]["data"]["text/plain"])


def cover_latex(title: str, version: str, counts: dict[str, dict[str, int]]) -> str:
    """The cover page: title, version, and the claims ledger (statuses as rows, papers as
    columns, totals), for ``latex_elements["maketitle"]``."""
    from fdi_lib.reproduce.ledger_claims import PAPERS, STATUSES

    papers = [p for p in PAPERS if p in counts]
    head = " & ".join(["status", *(_latex_escape(PAPERS[p]) for p in papers), "all"])
    rows = []
    for status in STATUSES:
        n = [counts[p].get(status, 0) for p in papers]
        rows.append(" & ".join([_latex_escape(status), *map(str, n), str(sum(n))]) + r" \\")
    totals = [sum(counts[p].values()) for p in papers]
    rows.append(
        r"\midrule " + " & ".join(["all claims", *map(str, totals), str(sum(totals))]) + r" \\"
    )
    main, _, sub = title.partition(": ")
    return "\n".join(
        [
            r"\begin{titlepage}\centering",
            r"\vspace*{3cm}{\Huge\bfseries " + _latex_escape(main) + r"\par}",
            r"\vspace{1em}{\Large " + _latex_escape(sub) + r"\par}" if sub else "",
            r"\vspace{2em}{\large PDF edition, version " + _latex_escape(version) + r"\par}",
            r"\vspace{0.5em}{\large \today\par}",
            r"\vfill",
            r"{\large Claims of the papers checked by this edition, by status (see the claims ledger)\par}",
            r"\vspace{1em}\small",
            # within the text width: the papers' names wrap in columns sharing what the status
            # column leaves, ragged-left over their counts
            r"\begin{tabular}{@{}>{\raggedright\arraybackslash}p{0.3\linewidth}"
            + rf"*{{{len(papers) + 1}}}{{>{{\raggedleft\arraybackslash}}"
            + rf"p{{\dimexpr(0.7\linewidth-{2 * (len(papers) + 1)}\tabcolsep)/{len(papers) + 1}\relax}}}}@{{}}}}",
            r"\toprule " + head + r" \\ \midrule",
            *rows,
            r"\bottomrule\end{tabular}",
            r"\vspace*{2cm}",
            r"\end{titlepage}",
        ]
    )


def _latex_cover(app: Sphinx, env) -> None:
    """The cover, once every page (the ledger's included) has been read and executed."""
    if app.builder.name != "latex":
        return
    # the title of the book's LaTeX document (Jupyter Book puts _config.yml's title there)
    title = app.config.latex_documents[0][2] if app.config.latex_documents else app.config.project
    app.builder.context["maketitle"] = cover_latex(
        title, _version(Path(app.confdir)), ledger_counts(app)
    )


class _ProtectCaptionCitations(SphinxPostTransform):
    """``\\protect`` before the ``\\hyperlink`` of a citation in a caption (LaTeX errors
    "Paragraph ended before \\Hy@tempa was complete" otherwise)."""

    default_priority = 800
    builders = ("latex",)

    def run(self, **kwargs: Any) -> None:
        from sphinxcontrib.bibtex.nodes import raw_latex  # written as its rawsource

        for caption in self.document.findall(nodes.caption):
            for raw in caption.findall(raw_latex):
                if raw.rawsource.startswith("\\hyperlink{"):
                    raw.rawsource = "\\protect" + raw.rawsource


#: Terms of the PDF's index: what a student looks up, indexed where each chapter first uses them.
INDEX_TERMS = (
    "GLR",
    "innovation",
    "Kalman filter",
    "Kitanidis filter",
    "set-valued observer",
    "fault signature",
    "minmax",
    "Lasso",
    "RLS",
    "forgetting factor",
    "Willsky-Jones",
    "chi-square",
    "false alarm",
    "detection delay",
    "isolation",
    "polytope",
    "convex hull",
    "LPV",
    "LTV",
    "Monte Carlo",
    "Ljung-Box",
    "unknown input",
    "claims ledger",
    "wind turbine",
    "threshold",
)


class _IndexTerms(SphinxPostTransform):
    """The PDF's index (issue 33): each of :data:`INDEX_TERMS` indexed at the first paragraph of
    each chapter (source file) that uses it, by an ``\\index`` entry at that paragraph."""

    default_priority = 760
    builders = ("latex",)

    def run(self, **kwargs: Any) -> None:
        from sphinx import addnodes

        patterns = [
            (t, re.compile(r"(?<![\w-])" + re.escape(t) + r"(?![\w-])", re.I)) for t in INDEX_TERMS
        ]
        done: set[tuple[str, str]] = set()
        for par in list(self.document.findall(nodes.paragraph)):
            if par.source is None or any(
                isinstance(a, (nodes.caption, nodes.title, nodes.table))
                for a in _ancestors(par, self.document)
            ):
                continue
            text = par.astext()
            terms = [t for t, pat in patterns if (t, par.source) not in done and pat.search(text)]
            for term in terms:
                done.add((term, par.source))
                par.insert(0, addnodes.index(entries=[("single", term, "", "", None)]))


#: A bracketed interval of two numbers ("[0.02, 0.05]", "[-0.333, 1]") and a number before its
#: unit ("0.032 s", "5 %"): the spaces that a printed table must not break at.
_INTERVAL = re.compile(r"(\[[^\[\]\s,]{1,20},)\s+([^\[\]\s,]{1,20}\])")
_NUMBER_UNIT = re.compile(r"(\d)\s+(%|s|ms|µs|min|m/s|rad|°|deg)(?![\w/])")
NBSP = "\u00a0"

#: Characters of the text width that a table's columns share (FreeSerif 10 pt on the narrower
#: page, A4, with Sphinx's margins: about 80 average characters), for :class:`_PrintedTables`.
TABLE_CHARS = 80
#: What a column's padding (two ``\tabcolsep``, 12 pt) and the wider header font take, in characters.
PAD_CHARS = 3


#: Printed lines of a table (its rows' wrapped lines, :func:`printed_lines`) above which it is
#: made a ``longtable``, which breaks across pages: tabulary's box does not, and a taller one ran
#: into the bottom margin (the map of the book, 38 pt: 92 lines by the estimate; a ten-week
#: course plan, 230 pt: 85 lines). The estimate counts more lines than tabulary prints (its
#: widths follow the text better): the map, about 57 lines printed, is a page of US letter's
#: shorter text block and a bit; the tallest table that fitted was 63 lines by the estimate.
PAGE_TABLE_LINES = 70


def printed_lines(columns: list[list[str]], chars: int = TABLE_CHARS) -> int:
    """Lines that a table of ``columns`` (cell texts, the header row first) takes when printed
    at the widths of :func:`printed_widths` (the natural ones when they fit), each row as many
    as its cell that wraps most (about: words do not break, a line holds its width's
    characters), and a third of a line of padding per row."""
    widths = printed_widths(columns, chars) or [
        max((len(c) for c in col), default=1) + PAD_CHARS for col in columns
    ]
    rows = zip(*columns)
    return round(
        sum(
            max(-(-len(cell) // max(w - PAD_CHARS, 1)) or 1 for cell, w in zip(row, widths)) + 1 / 3
            for row in rows
        )
    )


def printed_widths(columns: list[list[str]], chars: int = TABLE_CHARS) -> list[int] | None:
    """Column widths (in characters, padding included) for a long table that would not fit on one
    line per row: each column gets at least its longest unbreakable piece (no-break spaces join),
    the rest of ``chars`` in proportion to its longest cell; ``None`` when every column fits at
    its natural width (``l`` columns do)."""
    natural = [max((len(c) for c in col), default=1) + PAD_CHARS for col in columns]
    if sum(natural) <= chars:
        return None
    # the unbreakable pieces: split at ordinary spaces, not at the no-break ones
    words = [
        max((len(w) for c in col for w in re.split(r"[ \t\n]+", c)), default=1) + PAD_CHARS
        for col in columns
    ]
    spare = max(chars - sum(words), 0)
    extra = [n - w for n, w in zip(natural, words)]
    total = sum(extra) or 1
    return [w + round(spare * e / total) for w, e in zip(words, extra)]


class _PrintedTables(SphinxPostTransform):
    """Tables for the printed page (issue 33): the spaces in an interval and between a number
    and its unit are no-break spaces (a cell wraps between a value and its interval, not inside
    either), and a long table (Sphinx's ``longtable``, more than 30 rows, whose columns are
    ``l`` and never wrap, or one made so because it takes more than :data:`PAGE_TABLE_LINES`
    printed lines) gets ragged-right columns of :func:`printed_widths` (a ``tabularcolumns``
    spec before it); the shorter tables are ragged-right by the preamble (tabulary's ``L`` for
    Sphinx's ``T``, :func:`_latex_preamble`)."""

    default_priority = 820
    builders = ("latex",)

    def run(self, **kwargs: Any) -> None:
        from sphinx import addnodes

        for table in list(self.document.findall(nodes.table)):
            for entry in table.findall(nodes.entry):
                for text in list(entry.findall(nodes.Text)):
                    new = _NUMBER_UNIT.sub(rf"\1{NBSP}\2", _INTERVAL.sub(rf"\1{NBSP}\2", str(text)))
                    if new != str(text):
                        text.parent.replace(text, nodes.Text(new))
            previous = table.previous_sibling()
            if isinstance(previous, addnodes.tabular_col_spec):
                continue
            for tgroup in table.findall(nodes.tgroup):
                rows = list(tgroup.findall(nodes.row))
                if any(e.get("morecols") or e.get("morerows") for e in tgroup.findall(nodes.entry)):
                    continue
                columns: list[list[str]] = [[] for _ in range(int(tgroup.get("cols", 0)))]
                for row in rows:
                    for column, entry in zip(columns, row.children):
                        column.append(entry.astext().strip())
                if len(rows) <= 30:
                    if printed_lines(columns) <= PAGE_TABLE_LINES:
                        continue
                    table["classes"].append("longtable")
                widths = printed_widths(columns)
                if widths is None:
                    continue
                spec = "".join(
                    rf">{{\raggedright\arraybackslash}}\X{{{w}}}{{{sum(widths)}}}" for w in widths
                )
                table.parent.insert(table.parent.index(table), addnodes.tabular_col_spec(spec=spec))


class _NumberedParts(SphinxPostTransform):
    """Chapters numbered as in the HTML: in LaTeX every ``\\chapter`` of the book would be
    numbered (1-17); here only those of the parts ``numbered: true`` in ``_toc.yml`` are (1-7,
    continuously: an unnumbered chapter does not step LaTeX's counter), with their sections as
    in the HTML (2.1, 2.1.1), and no part is numbered; a chapter left empty (the bibliography's)
    is dropped. Runs after sphinx-jupyterbook-latex has made the parts (priority 700) in the root
    document."""

    default_priority = 750
    builders = ("latex",)

    def run(self, **kwargs: Any) -> None:
        site_map = getattr(self.config, "external_site_map", None)
        if (
            site_map is None
            or self.app.project.path2doc(self.document["source"]) != self.config.root_doc
        ):
            return
        numbered = {
            tree.caption: bool(tree.numbered) for tree in site_map.root.subtrees if tree.caption
        }

        def depth(n: int) -> nodes.raw:
            return nodes.raw("", f"\\setcounter{{secnumdepth}}{{{n}}}\n", format="latex")

        self.document.insert(0, depth(-2))
        # the bibliography page: sphinx-jupyterbook-latex moved its list to the end of the book
        # (an unnumbered "Bibliography" there), which leaves its chapter empty
        # (a placeholder without text in its place)
        for section in list(self.document.findall(nodes.section)):
            rest = section.children[1:]
            if (
                section.children
                and isinstance(section[0], nodes.title)
                and not "".join(c.astext() for c in rest).strip()
                and not any(c.next_node(nodes.image) for c in rest if isinstance(c, nodes.Element))
            ):
                section.parent.remove(section)
        for section in list(self.document.findall(nodes.section)):
            if (
                section.get("docname") in numbered
                and section.children
                and isinstance(section[0], nodes.title)
            ):
                section.parent.insert(section.parent.index(section), depth(-2))
                section.insert(1, depth(2 if numbered[section["docname"]] else -2))


class _CaptionHTML(html.parser.HTMLParser):
    """An explorable's caption (HTML: text, ``<sub>``, ``<sup>``, ``<i>``, ``<b>``) as docutils
    inline nodes."""

    KINDS = {
        "sub": nodes.subscript,
        "sup": nodes.superscript,
        "i": nodes.emphasis,
        "em": nodes.emphasis,
        "b": nodes.strong,
        "strong": nodes.strong,
    }

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack: list[nodes.Element] = [nodes.caption()]

    def handle_starttag(self, tag, attrs):
        node = self.KINDS.get(tag, nodes.inline)()
        self.stack[-1] += node
        self.stack.append(node)

    def handle_endtag(self, tag):
        if len(self.stack) > 1:
            self.stack.pop()

    def handle_data(self, data):
        self.stack[-1] += nodes.Text(data)


def _image_caption(app: Sphinx, image: nodes.image) -> str | None:
    """The ``fdi:caption`` of an image file (an explorable's small multiples), else None."""
    from PIL import Image

    candidate = image.get("candidates", {}).get("*") or image.get("uri", "")
    path = Path(candidate) if Path(candidate).is_absolute() else Path(app.srcdir) / candidate
    if path.suffix.lower() != ".png" or not path.is_file():
        return None
    with Image.open(path) as img:
        return img.info.get("fdi:caption")


class _ExplorableFigures(SphinxPostTransform):
    """Each explorable's small multiples (its ``image/png`` output, chosen by myst-nb for
    LaTeX) as a figure with the explorable's caption (unless the cell already makes a figure)."""

    default_priority = 810
    builders = ("latex",)

    def run(self, **kwargs: Any) -> None:
        for image in list(self.document.findall(nodes.image)):
            if any(isinstance(a, nodes.figure) for a in _ancestors(image, self.document)):
                continue
            caption = _image_caption(self.app, image)
            if caption is None:
                continue
            parser = _CaptionHTML()
            parser.feed(caption)
            parser.close()
            image["alt"] = readable_text(parser.stack[0], {})
            figure = nodes.figure("", image.deepcopy(), parser.stack[0], align="center")
            image.parent.replace(image, figure)


# --- 12. Tables on a phone; 13. numbered explorables ----------------------------------------
def _column_labels(tgroup: nodes.tgroup, macros: dict[str, str]) -> list[str]:
    """The readable text of the last header row of ``tgroup``, one entry per column (a header
    cell spanning columns labels each of them); empty strings if the table has no header."""
    labels = [""] * int(tgroup.get("cols", 0))
    for thead in tgroup.findall(nodes.thead):
        rows = list(thead.findall(nodes.row))
        column = 0
        for entry in rows[-1].children if rows else []:
            text = readable_text(entry, macros)
            for _ in range(1 + entry.get("morecols", 0)):
                if column < len(labels):
                    labels[column] = text
                column += 1
    return labels


def _visit_entry(self, node: nodes.entry) -> None:
    """The HTML translator's cell, with ``data-label`` (its column's header) in a body cell."""
    type(self).visit_entry(self, node)
    row = node.parent
    if isinstance(row.parent, nodes.thead):
        return
    tgroup = row.parent.parent
    cache = self.__dict__.setdefault("_fdi_column_labels", {})
    if id(tgroup) not in cache:
        cache[id(tgroup)] = _column_labels(tgroup, _book_macros(self.config))
    labels = cache[id(tgroup)]
    column = row.column - 1 - node.get("morecols", 0)  # visit_entry has counted this cell
    if 0 <= column < len(labels) and labels[column]:
        tag = self.body[-1]
        self.body[-1] = tag[:-1] + f' data-label="{self.attval(labels[column])}">'


def _depart_entry(self, node: nodes.entry) -> None:
    type(self).depart_entry(self, node)


_EXPLORABLE_CAPTION = re.compile(r"<figcaption>(.*?)</figcaption>", re.S)


class NumberedExplorables(SphinxTransform):
    """Each cell output showing an explorable becomes a numbered, labelled figure (item 10).

    Runs on the doctree as read (before the standard domain collects labels and Sphinx numbers
    figures): the output's MIME bundle (myst-nb keeps every format until the builder picks one)
    is wrapped in a ``figure`` whose caption is the explorable's own, as text
    (:func:`fdi_lib.explorables.caption_text`); the HTML loses its ``<figcaption>`` (shown once,
    under the number) and its ``<figure>`` becomes a ``<div>`` (one figure, not two nested)."""

    default_priority = 500

    def apply(self, **kwargs: Any) -> None:
        stem = self.env.docname.rsplit("/", 1)[-1]
        count = 0
        for bundle in list(
            self.document.findall(
                lambda n: isinstance(n, nodes.container) and n.get("nb_element") == "mime_bundle"
            )
        ):
            raws = [r for r in bundle.findall(nodes.raw) if 'class="fdi-explorable"' in r.astext()]
            if not raws or isinstance(bundle.parent, nodes.figure):
                continue
            html_text = raws[0].astext()
            found = _EXPLORABLE_CAPTION.search(html_text)
            if found is None:
                continue
            text = caption_text(found.group(1))
            html_text = (
                (html_text[: found.start()] + html_text[found.end() :])
                .replace('<figure class="fdi-explorable"', '<div class="fdi-explorable"', 1)
                .replace("</figure><script>", "</div><script>", 1)
            )
            raws[0].replace_self(
                nodes.raw(html_text, html_text, format="html", classes=raws[0].get("classes", []))
            )
            count += 1
            figure = nodes.figure(classes=["fdi-explorable-figure"])
            figure["names"].append(f"fig-{stem}-explore" + (f"-{count}" if count > 1 else ""))
            bundle.replace_self(figure)
            figure += bundle
            figure += nodes.caption(text, text)
            self.document.note_explicit_target(figure, figure)


# --- 15. Accessible names and roles ---------------------------------------------------------
def _visit_hidden_cell(self, node) -> None:
    """myst-nb's fold of a hidden cell without its ``aria-label`` ("Toggle hidden content"), which
    hid the visible "Show code cell source" from screen readers: the toggle's name is now the text
    it shows (the other prompt is ``display: none``)."""
    self.body.append(f'<details class="admonition hide {" ".join(node["classes"])}">\n<summary>\n')
    for kind, prompt in (("collapsed", node["prompt_show"]), ("expanded", node["prompt_hide"])):
        self.body.append(f'<p class="{kind} admonition-title">{html.escape(prompt)}</p>\n')
    self.body.append("</summary>\n")


def _visit_citation(self, node: nodes.citation) -> None:
    """A bibliography entry as an item of its list (docutils writes ``role="doc-biblioentry"``,
    deprecated, in a ``role="list"`` that then has no list item)."""
    if not isinstance(node.previous_sibling(), type(node)):
        self.body.append('<div role="list" class="citation-list">\n')
    self.body.append(self.starttag(node, "div", classes=[node.tagname], role="listitem"))


class _Targets:
    """The environment as :meth:`_StandardDomain._resolve_numref_xref` passes it to Sphinx,
    whose :meth:`get_doctree` returns a page's reference targets from ``cache`` (read once)."""

    def __init__(self, env, cache: dict[str, nodes.document]):
        self._env, self._cache = env, cache

    def __getattr__(self, name: str):
        return getattr(self._env, name)

    def get_doctree(self, docname: str) -> nodes.document:
        if docname not in self._cache:
            self._cache[docname] = _target_stubs(self._env.get_doctree(docname))
        return self._cache[docname]


def _stub(node: nodes.Node) -> nodes.Node:
    """``node`` without its tree: same class and attributes (a text: its text)."""
    if isinstance(node, nodes.Text):
        return nodes.Text(str(node))
    return node.__class__(
        **{k: v.copy() if isinstance(v, list) else v for k, v in node.attributes.items()}
    )


def _target_stubs(doctree: nodes.document) -> nodes.document:
    """A document whose ``ids`` map every id of ``doctree`` to its node's :func:`_stub` with its
    children's stubs (Sphinx's std domain numbers a target by its class, ``ids`` and, for a
    container, whether a child is a literal block)."""
    out = nodes.document(doctree.settings, doctree.reporter)
    for ident, node in doctree.ids.items():
        stub = _stub(node)
        if isinstance(node, nodes.Element):
            stub.extend(_stub(child) for child in node.children)
        out.ids[ident] = stub
    return out


class _StandardDomain(StandardDomain):
    """Sphinx's std domain, its figure references resolved against :class:`_Targets`."""

    def __init__(self, env) -> None:
        super().__init__(env)
        self._targets: dict[str, nodes.document] = {}

    def _resolve_numref_xref(self, env, *args, **kwargs):
        return super()._resolve_numref_xref(_Targets(env, self._targets), *args, **kwargs)


def _forget_targets(app: Sphinx, *args) -> None:
    """Drops the cached targets when pages are read (before and after: they may have changed)."""
    app.env.get_domain("std")._targets.clear()


# --- 17. Figures numbered from the pages in memory -----------------------------------------
def _doctrees_in_memory(app: Sphinx, env) -> list[str]:
    """``env-get-updated``, before Sphinx's handlers: ``env.get_doctree`` gives a page that this
    build has read as it is in memory, until :func:`_doctrees_from_disk`.

    Sphinx numbers the figures, tables and listings of the book by walking every page's doctree,
    which it unpickles from ``.doctrees`` (up to 2 MB a page: 1.4 s for the book) although the
    pages read by this build are still in memory (``env._write_doc_doctree_cache``, the very
    objects it pickled, kept to be written): the walk, and sphinx-external-toc's, only read them.
    A page read by an earlier build (``make book-fast``) is unpickled as before."""
    in_memory = getattr(env, "_write_doc_doctree_cache", {})
    from_disk = env.get_doctree

    def get_doctree(docname: str) -> nodes.document:
        doctree = in_memory.get(docname)
        return from_disk(docname) if doctree is None else doctree

    env.get_doctree = get_doctree
    return []


def _doctrees_from_disk(app: Sphinx, env) -> list[str]:
    """``env-get-updated``, after Sphinx's handlers: ``env.get_doctree`` unpickles again (and the
    environment, pickled next, holds no function of this module)."""
    env.__dict__.pop("get_doctree", None)
    return []


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_transform(NumberedExplorables)
    app.add_domain(_StandardDomain, override=True)
    app.connect("env-before-read-docs", _forget_targets)
    app.connect("env-updated", _forget_targets)
    app.connect("env-get-updated", _doctrees_in_memory, priority=1)
    app.connect("env-get-updated", _doctrees_from_disk, priority=999)
    app.add_node(nodes.entry, override=True, html=(_visit_entry, _depart_entry))
    from docutils.writers._html_base import HTMLTranslator
    from myst_nb.sphinx_ import HideCodeCellNode, depart_HideCellInput

    app.add_node(
        nodes.citation, override=True, html=(_visit_citation, HTMLTranslator.depart_citation)
    )
    app.add_node(HideCodeCellNode, override=True, html=(_visit_hidden_cell, depart_HideCellInput))
    app.connect("env-before-read-docs", _drop_thebe_scripts, priority=900)
    app.connect("source-read", _generate_catalogue)
    app.connect("source-read", _generate_book_map)
    # after sphinx-book-theme's header buttons (priority 501)
    app.connect("html-page-context", _add_notebook_download, priority=502)
    pybtex.plugin.register_plugin("pybtex.style.labels", "fdi_author_year", AuthorYearLabelStyle)
    pybtex.plugin.register_plugin("pybtex.style.formatting", "fdi_author_year", AuthorYearStyle)
    # sphinxcontrib-bibtex looks the plain-text backend up for every citation it resolves
    # (``find_plugin("pybtex.backends", "plaintext")``, 113 a build), each time among the entry
    # points (as ``_PLAIN_TEXT``); pybtex's runtime registry, searched first, holds the same class.
    pybtex.plugin.register_plugin("pybtex.backends", "plaintext", PlainTextBackend, force=True)
    app.connect("build-finished", copy_mathjax)
    app.connect("config-inited", _add_ext_paths)
    app.connect("builder-inited", _register_filters)
    # after Sphinx's MathJax (500) and sphinx-tippy's scripts (450)
    app.connect("html-page-context", _mathjax_where_needed, priority=600)
    app.connect("html-page-context", _add_previews_script, priority=600)
    app.connect("build-finished", _lighter_previews, priority=400)
    app.connect("build-finished", subset_icon_font)
    app.add_css_file(ICON_CSS)
    app.connect("build-finished", _render_notebook_downloads)
    app.connect("doctree-resolved", _plain_status_words)
    app.connect("doctree-resolved", _alt_from_captions)
    app.connect("doctree-read", _readable_section_labels)
    app.connect("doctree-read", _record_proof_titles)
    app.connect("env-purge-doc", _purge_proof_titles)
    app.connect("config-inited", _latex_preamble)
    app.connect("doctree-resolved", _latex_exercise_targets)
    app.connect("builder-inited", _latex_files)
    app.connect("env-updated", _latex_cover)
    app.add_post_transform(_ProtectCaptionCitations)
    app.add_post_transform(_NumberedParts)
    app.add_post_transform(_IndexTerms)
    app.add_post_transform(_ExplorableFigures)
    app.add_post_transform(_PrintedTables)
    app.add_js_file(PDF_SCRIPT)
    app.connect("build-finished", _pdf_script)
    app.connect("env-updated", _record_run_times)
    from sphinx_proof.domain import ProofIndex

    if not getattr(ProofIndex.generate, "_fdi_titled", False):
        ProofIndex.generate = _titled_proof_index(ProofIndex.generate)
        ProofIndex.generate._fdi_titled = True
    return {"version": "1", "parallel_read_safe": False, "parallel_write_safe": True}
