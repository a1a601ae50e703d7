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
   Thebe, Colab) is configured, and this book loads nothing from another host.
5. No Thebe scripts (Thebe is off; sphinx-thebe would reference a CDN and declares its constants
   twice on every page, a console error).
6. The catalogue of reproductions (``book/reproductions.md``) is generated when the book is read:
   from the registry of :mod:`fdi_lib.reproduce`, in book order (the order of the chapters in
   ``_toc.yml``, then of the first code cell that calls each reproduction), with a link to the
   figure that draws it (the figure label of the cell that calls ``get(ID).plot``) or else to the
   section that runs it, the command line that recomputes it at the book's settings
   (:func:`fdi_lib.reproduce.book.book_command`, the settings the chapters' ``book_run`` uses) and
   its documentation rendered.
7. The execution table of the status page (myst-nb's ``nb-exec-table``) says "ok" / "failed"
   instead of emoji, which show as empty boxes without an emoji font.
8. Maths as readable text where it cannot be typeset: the text of references to a heading with
   maths (``{ref}`` to "The rule for $\\lambda$" reads "The rule for λ", not "\\lambda"; pages
   such as the ledger load no MathJax), and the alt text of every figure's image, taken from
   its caption (Sphinx would otherwise write the image's file path). :func:`tex_to_text` does
   the conversion; the catalogue's headings (from the registry's ASCII titles, "Gamma_k") are
   written in real maths by :func:`title_markdown`.
9. Tables that can be read on a phone: every body cell of a table carries its column's header as
   a ``data-label`` attribute (its readable text, :func:`readable_text`), which the book's CSS
   and ``_static/fdi-tables.js`` use to show a table too wide for the column as one card per row
   (``fdi_lib.report.Table`` writes the same attribute for its tables).
10. Numbered explorables: the output of a cell that shows an explorable
    (:mod:`fdi_lib.explorables`, whose HTML carries its own caption) becomes a figure of the book
    with that caption as plain text, numbered like the others ("Figure 2.5") and labelled
    ``fig-<page>-explore`` (``fig-glr-explore``; ``-2``, ``-3`` for further ones on a page), so
    that the text can cite it with ``{numref}``.
"""

from __future__ import annotations

import importlib.util
import inspect
import re
import shutil
import unicodedata
from pathlib import Path
from typing import Any

from docutils import nodes

import pybtex.plugin
from pybtex.richtext import Text
from pybtex.style.formatting.plain import Style as PlainStyle
from pybtex.style.labels import BaseLabelStyle
from sphinx.application import Sphinx
from sphinx.util import logging
from sphinx.transforms import SphinxTransform
from sphinx.util.nodes import clean_astext

from fdi_lib.explorables import caption_text, script_text

logger = logging.getLogger(__name__)

# What pages load from MathJax's es5 tree: the combined TeX + CommonHTML component, the TeX
# extensions it autoloads (\begin{aligned}, \boldsymbol, ...), the CommonHTML fonts, the
# context menu and the accessibility components the menu can switch on.
MATHJAX_ENTRY = "tex-chtml.js"
MATHJAX_PARTS = ("tex-chtml.js", "input/tex", "output/chtml", "output/chtml.js", "ui", "a11y",
                 "sre", "adaptors")


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


def _plain(text: str) -> str:
    return Text.from_latex(text).render_as("text")


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
            for (name, subtype, docname, anchor, extra, qualifier, descr) in entries:
                title, kind = titles.get(anchor, ("", descr))
                title = re.sub(r"^\s*\((.*)\)\s*$", r"\1", title)  # proof_title_format " (%t)"
                shown = f"{kind.title()}: {title}" if title else f"{kind.title()} ({name})"
                renamed.setdefault(shown[0].upper(), []).append(
                    (shown, subtype, docname, anchor, docname, qualifier, ""))
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
    import yaml

    toc = yaml.safe_load((confdir / "_toc.yml").read_text())
    files: list[str] = []

    def walk(items):
        for item in items or []:
            if "file" in item:
                files.append(item["file"])
            walk(item.get("chapters")), walk(item.get("sections"))

    walk(toc.get("parts")), walk(toc.get("chapters"))
    return files


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
                yield (cell.start() + call.start(), call.group(1), kind, name.group(1) if name else None,
                       title, label)


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
            entry = out.setdefault(rid, {"doc": doc, "figure": None, "section": title, "label": label})
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
    for the build to fail); cross-reference roles become literals."""
    from docutils.core import publish_parts

    doc = re.sub(r":[\w:]+:`~?([^`]+)`", r"``\1``", inspect.getdoc(func) or "")
    parts = publish_parts(doc, writer_name="html5", settings_overrides={
        "report_level": 5, "halt_level": 5, "initial_header_level": 4, "doctitle_xform": False,
        "embed_stylesheet": False, "warning_stream": False, "id_prefix": id_prefix})
    return parts["body"]


_GREEK = ("alpha beta gamma delta epsilon zeta eta theta iota kappa lambda mu nu xi pi rho sigma tau "
          "upsilon phi chi psi omega").split()
_ASCII_MATH = re.compile(
    r"(?<![\w\\$])(?:(?P<greek>" + "|".join(_GREEK + [g.title() for g in _GREEK]) + r")|(?P<letter>[A-Za-z]))"
    r"(?:_(?P<sub>[A-Za-z0-9]+))?(?P<arg>\([a-z]\))?(?!\w)")


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


def catalogue_markdown(confdir: Path) -> tuple[str, list[Path]]:
    """The generated part of the catalogue page (MyST) and the files it was made from."""
    from fdi_lib.reproduce import list_reproductions
    from fdi_lib.reproduce.book import book_command, book_settings

    reps = {r.id: r for r in list_reproductions()}
    where = {rid: w for rid, w in shown_in(confdir).items() if rid in reps}
    order = list(where) + [rid for rid in reps if rid not in where]
    sources = [confdir / f"{doc}.md" for doc in _toc_files(confdir)
               if doc.count("/") >= 2 and (confdir / f"{doc}.md").is_file()]
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
            out.append(f"**Shown in:** {{numref}}`{w['figure']}`, section \"{w['section']}\" of "
                       f"{{doc}}`/{doc}`.  ")
        elif w["label"]:
            out.append(f"**Shown in:** {{ref}}`{w['label']}` of {{doc}}`/{doc}`.  ")
        else:
            out.append(f"**Shown in:** section \"{w['section']}\" of {{doc}}`/{doc}`.  ")
        plot = " (`--plot FILE.png` draws the figure)" if r.plot else ""
        s = book_settings(rid)
        trials = ("" if s.trials is None else
                  f"; {s.trials} Monte Carlo trial{'s' * (s.trials != 1)}, "
                  + ("the paper's count" if s.trials == r.default_trials
                     else f"the paper's {r.default_trials} with `--trials {r.default_trials}`"
                     if r.default_trials else "the book's count"))
        out.append(f"**Command (the book's settings):** `{book_command(rid)}`{plot}{trials}.\n")
        out.append(f":::{{dropdown}} What `{rid}` computes and its headline keys\n"
                   f"```{{raw}} html\n<div class=\"fdi-docstring\">\n{_docstring_html(r.func, rid + '-')}"
                   f"</div>\n```\n:::\n")
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


def _add_notebook_download(app: Sphinx, pagename: str, templatename: str, context: dict,
                           doctree) -> None:
    if app.builder.format != "html" or context.get("ipynb_source"):
        return
    executed = Path(app.outdir).parent / "jupyter_execute" / f"{pagename}.ipynb"
    groups = [b for b in context.get("header_buttons", []) if b.get("label") == "download-buttons"]
    if not executed.is_file() or not groups:
        return
    target = Path(app.outdir) / "_sources" / f"{pagename}.ipynb"
    target.parent.mkdir(parents=True, exist_ok=True)
    shutil.copy2(executed, target)
    groups[0]["buttons"].insert(0, {
        "type": "link", "url": f"{context['pathto']('_sources', 1)}/{pagename}.ipynb",
        "text": ".ipynb", "icon": "fas fa-code", "tooltip": "Download the notebook (executed)",
        "label": "download-notebook-button"})


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
    "le": "≤", "leq": "≤", "ge": "≥", "geq": "≥", "ne": "≠", "neq": "≠", "sim": "~",
    "approx": "≈", "equiv": "≡", "propto": "∝", "ll": "≪", "gg": "≫", "in": "∈",
    "notin": "∉", "subset": "⊂", "subseteq": "⊆", "cup": "∪", "cap": "∩", "emptyset": "∅",
    "times": "×", "cdot": "·", "pm": "±", "mp": "∓", "infty": "∞", "to": "→",
    "rightarrow": "→", "leftarrow": "←", "mapsto": "↦", "ldots": "…", "dots": "…", "cdots": "⋯",
    "sum": "Σ", "prod": "Π", "int": "∫", "partial": "∂", "nabla": "∇", "top": "ᵀ",
    "prime": "′", "forall": "∀", "exists": "∃", "ell": "ℓ", "circ": "∘", "otimes": "⊗",
    "oplus": "⊕", "star": "⋆", "ast": "*", "mid": "|", "vert": "|", "lvert": "|", "rvert": "|",
    "Vert": "‖", "lVert": "‖", "rVert": "‖", "langle": "⟨", "rangle": "⟩", "quad": " ",
    "qquad": " ", "setminus": "∖", "perp": "⊥", "dagger": "†", "lfloor": "⌊", "rfloor": "⌋",
    "lceil": "⌈", "rceil": "⌉", "neg": "¬", "land": "∧", "lor": "∨", "Rightarrow": "⇒",
    "iff": "⇔", "implies": "⇒",
}
_ESCAPES = {",": " ", ";": " ", ":": " ", " ": " ", "!": "", "|": "‖", "{": "{", "}": "}",
            "\\": "; ", "%": "%", "$": "$", "&": "&", "#": "#", "_": "_"}
_FONTS = {"mathrm", "mathit", "mathbf", "mathsf", "mathcal", "mathscr", "mathfrak", "boldsymbol",
          "bm", "text", "textrm", "textit", "textbf", "mbox", "operatorname", "mathbb"}
_ACCENTS = {"hat": "\u0302", "widehat": "\u0302", "bar": "\u0304", "overline": "\u0305",
            "tilde": "\u0303", "widetilde": "\u0303", "dot": "\u0307", "ddot": "\u0308",
            "vec": "\u20d7", "check": "\u030c", "breve": "\u0306"}
_SIZES = {"left", "right", "big", "Big", "bigg", "Bigg", "bigl", "bigr", "Bigl", "Bigr",
          "biggl", "biggr", "displaystyle", "textstyle", "scriptstyle", "limits", "nolimits"}


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
        m = re.match(r"\\([a-zA-Z]+)", self.s[self.i:])
        if not m:
            self.i += 2
            return _ESCAPES.get(self.s[self.i - 1:self.i], self.s[self.i - 1:self.i])
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
                    return "".join(unicodedata.lookup(f"{prefix}DOUBLE-STRUCK CAPITAL {a}") for a in arg)
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


def _book_macros(config) -> dict[str, str]:
    macros = ((getattr(config, "mathjax3_config", None) or {}).get("tex") or {}).get("macros") or {}
    return {k: v if isinstance(v, str) else v[0] for k, v in macros.items()}


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
        for bundle in list(self.document.findall(
                lambda n: isinstance(n, nodes.container) and n.get("nb_element") == "mime_bundle")):
            raws = [r for r in bundle.findall(nodes.raw) if 'class="fdi-explorable"' in r.astext()]
            if not raws or isinstance(bundle.parent, nodes.figure):
                continue
            html_text = raws[0].astext()
            found = _EXPLORABLE_CAPTION.search(html_text)
            if found is None:
                continue
            text = caption_text(found.group(1))
            html_text = (html_text[:found.start()] + html_text[found.end():]).replace(
                '<figure class="fdi-explorable"', '<div class="fdi-explorable"', 1).replace(
                "</figure><script>", "</div><script>", 1)
            raws[0].replace_self(nodes.raw(html_text, html_text, format="html",
                                           classes=raws[0].get("classes", [])))
            count += 1
            figure = nodes.figure(classes=["fdi-explorable-figure"])
            figure["names"].append(f"fig-{stem}-explore" + (f"-{count}" if count > 1 else ""))
            bundle.replace_self(figure)
            figure += bundle
            figure += nodes.caption(text, text)
            self.document.note_explicit_target(figure, figure)


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_transform(NumberedExplorables)
    app.add_node(nodes.entry, override=True, html=(_visit_entry, _depart_entry))
    app.connect("env-before-read-docs", _drop_thebe_scripts, priority=900)
    app.connect("source-read", _generate_catalogue)
    # after sphinx-book-theme's header buttons (priority 501)
    app.connect("html-page-context", _add_notebook_download, priority=502)
    pybtex.plugin.register_plugin("pybtex.style.labels", "fdi_author_year", AuthorYearLabelStyle)
    pybtex.plugin.register_plugin("pybtex.style.formatting", "fdi_author_year", AuthorYearStyle)
    app.connect("build-finished", copy_mathjax)
    app.connect("doctree-resolved", _plain_status_words)
    app.connect("doctree-resolved", _alt_from_captions)
    app.connect("doctree-read", _readable_section_labels)
    app.connect("doctree-read", _record_proof_titles)
    app.connect("env-purge-doc", _purge_proof_titles)
    from sphinx_proof.domain import ProofIndex

    if not getattr(ProofIndex.generate, "_fdi_titled", False):
        ProofIndex.generate = _titled_proof_index(ProofIndex.generate)
        ProofIndex.generate._fdi_titled = True
    return {"version": "1", "parallel_read_safe": False, "parallel_write_safe": True}
