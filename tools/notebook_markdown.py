"""Notebooks that render in Jupyter: the book's MyST markup as plain Markdown, its macros defined.

A chapter is MyST Markdown: Jupyter Book resolves its roles (``{numref}``, ``{prf:ref}``,
``{cite:t}``, ``{glue:text}``, ...) and directives (``{prf:proposition}``, ``{admonition}``, the
gated exercises) and defines the maths macros of ``_config.yml`` (``\\T``, ``\\R``, ``\\E``) for
MathJax. A notebook opened in JupyterLab has none of that: the roles show as raw text and the
macros as red errors. :func:`convert_notebook` rewrites every Markdown cell of a notebook made
from a chapter:

* a first Markdown cell, hidden from view, defines the book's macros with ``\\newcommand``,
  generated from ``_config.yml`` (:func:`book_macros`), the same source as the HTML's MathJax;
* references become text with the book's numbers and labels (:class:`BookReferences`):
  "Figure 3.2", "Proposition 1.2", a section's title, a chapter's title (a link to its notebook),
  "Zhang and Basseville (2014)" / "(Zhang and Basseville, 2014)";
* glue references become the glued values, formatted as the book formats them (myst-nb's own
  formatter), read from the ``<doc>.glue.json`` files that myst-nb writes beside the executed
  notebooks. A notebook converted without executed ones (``make notebooks`` from a fresh clone)
  says where a value comes from instead ("[computed when you run the notebook: `name`]");
  ``make notebooks`` and the student edition use the values of the last book build when there is
  one (``_build/jupyter_execute``, the student build's own);
* directives become Markdown: a bold title and the body in a block quote (propositions with
  their number, proofs, admonitions, notes), exercises and solutions with a bold heading.

Used by ``make notebooks`` (``python tools/notebook_markdown.py notebooks``), by the student
edition (:mod:`tools.student_edition`) and by the book's extension (``_ext/fdi_book.py``), which
rewrites the ".ipynb" downloads of the built HTML. :func:`problems` is the check the tests run on
every produced notebook: raw roles or directives, and maths that MathJax (node, the copy the book
ships) cannot typeset with the notebook's own definitions.

The numbers are computed from the sources (chapters numbered in ``_toc.yml`` order, figures,
propositions and lemmas counted per chapter, as ``numfig_secnum_depth: 1`` numbers them) so that
a notebook can be converted without a book build; ``tests/test_notebook_markdown.py`` compares
them with the built book's Sphinx environment when there is one.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

#: Metadata tag of the hidden first cell that defines the macros.
MACRO_TAG = "fdi-macros"


# ----------------------------------------------------------------------------- macros
def book_macros(root: Path = REPO) -> dict[str, str | list]:
    """The maths macros of the book: ``mathjax3_config.tex.macros`` of ``root/_config.yml``."""
    import yaml

    config = yaml.safe_load((root / "_config.yml").read_text())
    return dict(config["sphinx"]["config"]["mathjax3_config"]["tex"]["macros"])


def macro_definitions(macros: dict[str, str | list]) -> str:
    """``\\newcommand`` definitions of ``macros`` (MathJax's ``name: def`` or ``name: [def, nargs]``)."""
    out = []
    for name, value in macros.items():
        body, nargs = (value, 0) if isinstance(value, str) else (value[0], int(value[1]))
        out.append(f"\\newcommand{{\\{name}}}{'[%d]' % nargs if nargs else ''}{{{body}}}")
    return "".join(out)


def macro_cell(macros: dict[str, str | list]):
    """The first cell of a converted notebook: the macros as inline maths, which typesets as
    nothing; its source is hidden in JupyterLab and the book drops it (``remove-cell``)."""
    import nbformat

    cell = nbformat.v4.new_markdown_cell(f"${macro_definitions(macros)}$")
    cell.metadata.update({"tags": ["remove-cell", MACRO_TAG], "jupyter": {"source_hidden": True}})
    return cell


# ----------------------------------------------------------------------------- references
@dataclass
class BookReferences:
    """What the roles of the chapters point at, as the book shows it.

    Attributes
    ----------
    titles : dict
        Document (``"book/zb2014/glr"``) -> its title (first heading).
    notebooks : set
        Documents that are notebooks (a jupytext header).
    targets : dict
        Label -> (document, text): numbered figures, propositions, lemmas and equations
        ("Figure 3.2", "Proposition 1.2", "(2.1)"), section labels (the heading), exercises.
    citations : dict
        Bibliography key -> (authors, year), the book's author-year labels.
    glue : dict
        Document -> {key: the glued display data}; a document absent here has no executed values.
    """

    titles: dict[str, str] = field(default_factory=dict)
    notebooks: set[str] = field(default_factory=set)
    targets: dict[str, tuple[str, str]] = field(default_factory=dict)
    citations: dict[str, tuple[str, str]] = field(default_factory=dict)
    glue: dict[str, dict[str, dict]] = field(default_factory=dict)

    @classmethod
    def from_sources(cls, root: Path = REPO, glue_dir: Path | None = None) -> "BookReferences":
        """Read the book under ``root`` (``_toc.yml``, the chapters, ``book/references.bib``)
        and the glue values of the executed notebooks under ``glue_dir`` (myst-nb's
        ``jupyter_execute`` folder), if given."""
        import yaml

        refs = cls()
        toc = yaml.safe_load((root / "_toc.yml").read_text())
        docs: list[tuple[str, bool]] = [(toc["root"], False)]
        for part in toc.get("parts", []):
            docs += [(ch["file"], bool(part.get("numbered"))) for ch in part.get("chapters", [])]
        number = 0
        for doc, numbered in docs:
            path = root / f"{doc}.md"
            if not path.is_file():
                continue
            text = path.read_text()
            number += numbered
            refs._read_document(doc, text, number if numbered else None)
            if glue_dir is not None and (glue_dir / f"{doc}.glue.json").is_file():
                refs.glue[doc] = json.loads((glue_dir / f"{doc}.glue.json").read_text())
        refs.citations = _citations(root / "book" / "references.bib")
        return refs

    def _read_document(self, doc: str, text: str, chapter: int | None) -> None:
        heading = re.search(r"^# (.+?)\s*$", text, re.M)
        self.titles[doc] = heading.group(1) if heading else doc
        if text.startswith("---\njupytext:"):
            self.notebooks.add(doc)
        counters: dict[str, int] = {}
        pending_label = None
        explorables = 0
        lines = text.splitlines()
        for line_no, line in enumerate(lines):
            following = lines[line_no + 1] if line_no + 1 < len(lines) else ""
            if m := re.match(r"^\(([\w.:-]+)\)=\s*$", line):
                pending_label = m.group(1)
                continue
            if pending_label and (m := re.match(r"^#{1,6} (.+?)\s*$", line)):
                self.targets[pending_label] = (doc, m.group(1))
            if line.strip():
                pending_label = None
            kind = label = None
            if m := re.match(r"^(?:`{3,}|:{3,})\{prf:(\w+)\}", line):
                kind = m.group(1)
                option = re.match(r"^:label:\s*(\S+)", following)
                label = option.group(1) if option else None
            elif m := re.match(r"^ {4}name:\s*([\w.-]+)\s*$", line):  # a myst-nb figure's name
                kind, label = "figure", m.group(1)
            elif m := re.match(r"^:name:\s*([\w.-]+)\s*$", line):  # a {figure} directive
                kind, label = "figure", m.group(1)
            elif line.startswith(
                "explorable("
            ):  # a numbered figure (the book's NumberedExplorables)
                explorables += 1
                kind = "figure"
                label = f"fig-{doc.rsplit('/', 1)[-1]}-explore" + (
                    f"-{explorables}" if explorables > 1 else ""
                )
            elif m := _EQUATION_LABEL.match(line):  # $$ ... $$ (label)
                kind, label = "equation", m.group(1)
            elif m := re.match(r"^```\{exercise-start\} (.+)$", line):
                option = re.match(r"^:label:\s*(\S+)", following)
                if option:  # an exercise is unnumbered: its identifier names it
                    self.targets[option.group(1)] = (doc, m.group(1).split(" · ")[0].strip())
            if kind is None or kind == "proof" or label is None:
                continue
            counters[kind] = counters.get(kind, 0) + 1
            number = f"{chapter}.{counters[kind]}" if chapter else str(counters[kind])
            self.targets[label] = (
                doc,
                f"({number})" if kind == "equation" else f"{kind.title()} {number}",
            )

    # --- rendering of one role
    def link(self, doc: str, target_doc: str, text: str) -> str:
        """``text``, linking to the notebook of ``target_doc`` from that of ``doc`` when it is one."""
        if target_doc == doc or target_doc not in self.notebooks:
            return text
        rel = os.path.relpath(f"{target_doc}.ipynb", os.path.dirname(doc))
        return f"[{text}]({Path(rel).as_posix()})"

    def role(self, name: str, content: str, doc: str) -> str:
        """The Markdown of the role ``{name}`content``` in the document ``doc``."""
        explicit = re.match(r"^(.*?)\s*<([^<>]+)>$", content, re.S)
        title, target = (explicit.group(1), explicit.group(2)) if explicit else (None, content)
        if name in ("numref", "ref", "prf:ref", "eq"):
            if target not in self.targets:
                raise KeyError(f"{doc}: no target {target!r} for {{{name}}}")
            target_doc, text = self.targets[target]
            if title:
                text = title.replace("%s", text.split()[-1]) if "%s" in title else title
            return self.link(doc, target_doc, text)
        if name == "doc":
            target_doc = _resolve_doc(doc, target)
            if target_doc not in self.titles:
                raise KeyError(f"{doc}: no document {target!r} for {{doc}}")
            return self.link(doc, target_doc, title or self.titles[target_doc])
        if name in ("cite:t", "cite:p", "cite"):
            keys = [k.strip() for k in target.split(",")]
            missing = [k for k in keys if k not in self.citations]
            if missing:
                raise KeyError(f"{doc}: no bibliography entry {missing} for {{{name}}}")
            if name == "cite:t":
                return ", ".join(
                    f"{who} ({year})" for who, year in (self.citations[k] for k in keys)
                )
            return "(" + "; ".join(", ".join(self.citations[k]) for k in keys) + ")"
        if name in ("glue:text", "glue", "glue:any", "glue:md"):
            return self.glue_text(doc, content, formatted=name == "glue:text")
        if name == "math":
            return f"${content}$"
        if name in ("mod", "func", "class", "meth", "attr", "data", "exc"):  # the library's API
            shown = title or (target[1:].rsplit(".", 1)[-1] if target.startswith("~") else target)
            return f"`{shown}`"
        raise ValueError(f"{doc}: no Markdown rendering for the role {{{name}}}")

    def glue_value(self, doc: str, key: str) -> dict | None:
        """The display data glued as ``key`` (``"other.md::key"`` for another document's)."""
        if "::" in key:
            other, key = key.split("::", 1)
            doc = _resolve_doc(doc, other.removesuffix(".md").removesuffix(".ipynb"))
        return self.glue.get(doc, {}).get(key)

    def glue_text(self, doc: str, content: str, formatted: bool) -> str:
        """A glue reference's text: myst-nb's formatting of the glued ``text/plain``."""
        from myst_nb.core.variables import format_plain_text

        if not formatted and content.endswith((":myst", ":commonmark", ":gfm")):
            content = content.rsplit(":", 1)[0]  # {glue:md}`key:myst`: the Markdown's format
        key, fmt = (
            content.rsplit(":", 1)
            if formatted and ":" in content.split("::")[-1]
            else (content, "")
        )
        output = self.glue_value(doc, key)
        if output is None:
            return placeholder(key)
        data = output.get("data", {})
        prefix = output.get("metadata", {}).get("scrapbook", {}).get("mime_prefix", "")
        data = {k.removeprefix(prefix): v for k, v in data.items()}
        if not formatted and "text/markdown" in data:
            return data["text/markdown"].strip()
        plain = data.get("text/plain", "")
        return format_plain_text(plain, fmt) if fmt else format_plain_text(plain, "")


def placeholder(key: str) -> str:
    """What a notebook converted without executed values shows for the glued value ``key``."""
    return f"[computed when you run the notebook: `{key}`]"


def _resolve_doc(doc: str, target: str) -> str:
    """A ``{doc}`` target (relative to ``doc``'s folder, or absolute from the root) as a document name."""
    if target.startswith("/"):
        return target.lstrip("/")
    parts = list(Path(doc).parent.parts)
    for piece in target.split("/"):
        if piece == "..":
            parts.pop()
        elif piece not in ("", "."):
            parts.append(piece)
    return "/".join(parts)


def _citations(bib: Path) -> dict[str, tuple[str, str]]:
    """Key -> (authors, year): the labels of the book's bibliography style (``_ext/fdi_book.py``,
    "Zhang, 2021a" and "Zhang, 2021b" for two works with the same authors and year)."""
    import pybtex.database
    import pybtex.plugin

    sys.path.insert(0, str(REPO / "_ext"))
    try:
        from fdi_book import AuthorYearLabelStyle, AuthorYearStyle
    finally:
        sys.path.remove(str(REPO / "_ext"))
    # as the extension's setup() does (a no-op when it has run)
    pybtex.plugin.register_plugin("pybtex.style.labels", "fdi_author_year", AuthorYearLabelStyle)
    entries = pybtex.database.parse_file(str(bib)).entries.values()
    out = {}
    for formatted in AuthorYearStyle().format_entries(entries):
        who, year = formatted.label.rsplit(", ", 1)
        out[formatted.key] = (who, year)
    return out


# ----------------------------------------------------------------------------- Markdown
_EQUATION_LABEL = re.compile(r"^\$\$\s*\(([\w.:-]+)\)\s*$")
_ROLE = re.compile(r"\{(?P<name>[a-z][\w:-]*)\}`(?P<content>[^`]*)`")
_OPEN = re.compile(
    r"^(?P<indent> *)(?P<fence>`{3,}|:{3,})\{(?P<name>[\w:.-]+)\}\s*(?P<arg>.*?)\s*$"
)
_ADMONITIONS = {
    "note",
    "tip",
    "hint",
    "important",
    "warning",
    "caution",
    "attention",
    "danger",
    "error",
    "seealso",
}
#: Directives whose content only exists in the built book.
_BOOK_ONLY = {
    "nb-exec-table": "*(The execution time of every chapter is shown in the built book.)*",
    "bibliography": "*(The bibliography is a page of the built book.)*",
    "toctree": "",
    "tableofcontents": "",
}


def convert_markdown(text: str, doc: str, refs: BookReferences) -> str:
    """The MyST Markdown ``text`` of the document ``doc`` as plain Markdown."""
    lines = text.splitlines()
    out: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        m = _OPEN.match(line)
        if m:
            j, options = _options(lines, i + 1)
            k = j
            fence = m["fence"]
            while k < len(lines) and not (
                set(lines[k].strip()) == {fence[0]} and len(lines[k].strip()) >= len(fence)
            ):
                k += 1  # the closing fence: the same character, at least as many
            body = "\n".join(x[len(m["indent"]) :] for x in lines[j:k])
            out.append(_directive(m["name"], m["arg"], options, body, doc, refs))
            i = k + 1
            continue
        if m := _EQUATION_LABEL.match(line):  # a labelled equation: its number as a tag
            number = refs.targets.get(m.group(1), (doc, ""))[1].strip("()")
            out += [f"\\tag{{{number}}}" if number else "", "$$"]
            i += 1
            continue
        if re.match(r"^\([\w.:-]+\)=\s*$", line) or re.match(r"^%", line):
            i += 1  # a target label or a MyST comment: nothing to show
            continue
        out.append(line)
        i += 1
    result = "\n".join(out)
    result = _ROLE.sub(lambda r: refs.role(r["name"], r["content"], doc), result)
    return re.sub(r"\n{3,}", "\n\n", result).strip("\n") + ("\n" if text.endswith("\n") else "")


def _options(lines: list[str], i: int) -> tuple[int, dict[str, str]]:
    """The options of a directive starting at line ``i`` (``:key: value`` lines or a ``---`` block)."""
    options = {}
    if i < len(lines) and lines[i].strip() == "---":
        end = next((k for k in range(i + 1, len(lines)) if lines[k].strip() == "---"), i)
        import yaml

        options = {
            k: str(v) for k, v in (yaml.safe_load("\n".join(lines[i + 1 : end])) or {}).items()
        }
        return end + 1, options
    while i < len(lines) and (m := re.match(r"^\s*:([\w-]+):\s*(.*)$", lines[i])):
        options[m.group(1)] = m.group(2)
        i += 1
    return i, options


def _quote(title: str, body: str) -> str:
    """A bold title and ``body`` in a block quote; display maths on one line, so that no ``>``
    lands inside it (JupyterLab takes the maths out of the Markdown before parsing it)."""
    body = re.sub(
        r"\$\$(.+?)\$\$", lambda m: "$$" + " ".join(m.group(1).split()) + "$$", body, flags=re.S
    )
    quoted = "\n".join(f"> {x}" if x.strip() else ">" for x in body.strip("\n").splitlines())
    return f"> {title}\n>\n{quoted}\n" if body.strip() else f"> {title}\n"


def _directive(
    name: str, arg: str, options: dict[str, str], body: str, doc: str, refs: BookReferences
) -> str:
    if name not in ("raw", "code-block", "code", "math"):
        body = convert_markdown(body, doc, refs)
    if name == "exercise-start":
        return f"**Exercise {arg}**\n"
    if name == "solution-start":
        return f"**Solution of exercise {arg.removeprefix('ex-')}**\n"
    if name in ("exercise-end", "solution-end"):
        return ""
    if name.startswith("prf:"):
        kind = name.split(":", 1)[1]
        if kind == "proof":
            return _quote("*Proof.*", body)
        label = options.get("label")
        number = refs.targets.get(label, (doc, kind.title()))[1] if label else kind.title()
        return _quote(f"**{number}**" + (f" ({arg})" if arg else ""), body)
    if name in ("exercise", "solution"):
        return _quote(f"**{name.title()}** {arg}".strip(), body)
    if name in ("admonition", "dropdown"):
        return _quote(f"**{arg}**", body)
    if name in _ADMONITIONS:
        title = "See also" if name == "seealso" else name.title()
        return _quote(f"**{title}**" + (f" {arg}" if arg else ""), body)
    if name == "figure":
        label = options.get("name")
        number = refs.targets.get(label, (doc, "Figure"))[1] if label else "Figure"
        return f"![{' '.join(body.split())}]({arg})\n\n**{number}.** {body.strip()}\n"
    if name == "glue:figure":
        output = refs.glue_value(doc, arg)
        label = options.get("name")
        number = refs.targets.get(label, (doc, "Figure"))[1] if label else "Figure"
        png = (output or {}).get("data", {})
        png = next((v for k, v in png.items() if k.endswith("image/png")), None)
        image = (
            f"![{' '.join(body.split())}](data:image/png;base64,{png.strip()})"
            if png
            else placeholder(arg)
        )
        return f"{image}\n\n**{number}.** {body.strip()}\n"
    if name in ("glue", "glue:any", "glue:md", "glue:text"):
        return refs.glue_text(doc, arg, formatted=name == "glue:text") + "\n"
    if name == "math":
        return f"$$\n{body.strip()}\n$$\n"
    if name in ("code-block", "code"):
        return f"```{arg}\n{body.rstrip()}\n```\n"
    if name == "raw":
        return body + "\n"
    if name in _BOOK_ONLY:
        return _BOOK_ONLY[name] + "\n"
    raise ValueError(f"{doc}: no Markdown rendering for the directive {{{name}}}")


def convert_notebook(nb, doc: str, refs: BookReferences, macros: dict[str, str | list]):
    """Rewrite the Markdown cells of the notebook ``nb`` of document ``doc`` (in place; returned)
    and put the macro cell first (replacing one there already). A cell that uses a macro also
    starts with the definitions (typesetting nothing): JupyterLab renders the cells of a notebook
    concurrently, and under load a cell's maths was typeset before the macro cell's, its macros
    undefined (``tests/browser/check_jupyterlab.py``, 21 red ``\\T`` in one chapter).

    Every cell also gets the exercise it belongs to as metadata
    (:func:`fdi_lib.exercises.tag_exercise_cells`, read from the MyST exercise directives before
    they become Markdown; kept when a cell has it already): the notebooks of ``make notebooks``,
    the book's downloads and the student edition's notebooks carry the exercise boundaries the
    grader (``tools/grader.py``) attributes cells by."""
    from fdi_lib.exercises import CELL_KEY, tag_exercise_cells

    if not any(CELL_KEY in c.metadata for c in nb.cells):
        tag_exercise_cells(nb)
    uses = re.compile(r"\\(?:" + "|".join(map(re.escape, macros)) + r")(?![A-Za-z])")
    defs = f"${macro_definitions(macros)}$\n\n"
    for cell in nb.cells:
        if cell.cell_type == "markdown" and MACRO_TAG not in cell.metadata.get("tags", []):
            cell.source = convert_markdown(cell.source, doc, refs)
            if macros and uses.search(cell.source) and not cell.source.startswith(defs):
                cell.source = defs + cell.source
    nb.cells = [c for c in nb.cells if MACRO_TAG not in c.metadata.get("tags", [])]
    nb.cells.insert(0, macro_cell(macros))
    nb.cells[0].metadata[CELL_KEY] = {"exercise": None}
    return nb


def chapter_notebook(path: Path, doc: str, refs: BookReferences, macros: dict[str, str | list]):
    """The unexecuted notebook of the MyST chapter at ``path``, converted."""
    import jupytext

    return convert_notebook(jupytext.read(path), doc, refs, macros)


def chapters(book: Path) -> list[Path]:
    """The MyST chapters (with a jupytext header) under ``book``."""
    return sorted(p for p in book.rglob("*.md") if p.read_text().startswith("---\njupytext:"))


def write_notebooks(root: Path, out: Path, glue_dir: Path | None) -> list[Path]:
    """One converted, unexecuted notebook per chapter of the book under ``root``, written to
    ``out`` with the chapters' layout (``out/zb2014/glr.ipynb``); returns their paths."""
    import nbformat

    refs = BookReferences.from_sources(root, glue_dir)
    macros = book_macros(root)
    written = []
    for path in chapters(root / "book"):
        doc = path.relative_to(root).with_suffix("").as_posix()
        nb_path = out / path.relative_to(root / "book").with_suffix(".ipynb")
        nb_path.parent.mkdir(parents=True, exist_ok=True)
        nbformat.write(chapter_notebook(path, doc, refs, macros), nb_path)
        written.append(nb_path)
    return written


def convert_downloads(
    html: Path, root: Path, glue_dir: Path, macros: dict[str, str | list] | None = None
) -> list[Path]:
    """Rewrite the ".ipynb" downloads of the book under ``root`` built into ``html``
    (``html/_sources/<doc>.ipynb``, executed notebooks) in place; returns their paths.
    ``macros`` default to :func:`book_macros`."""
    import nbformat

    refs = BookReferences.from_sources(root, glue_dir)
    macros = book_macros(root) if macros is None else macros
    done = []
    for path in sorted((html / "_sources").rglob("*.ipynb")):
        doc = path.relative_to(html / "_sources").with_suffix("").as_posix()
        nb = nbformat.read(path, as_version=4)
        nbformat.write(convert_notebook(nb, doc, refs, macros), path)
        done.append(path)
    return done


# ----------------------------------------------------------------------------- checking
_RAW_DIRECTIVE = re.compile(r"^\s*(?:>\s*)*(?:`{3,}|:{3,})\{[\w:.-]+\}", re.M)
_MATHJAX_CHECK = r"""
const es5 = process.argv[1];
const groups = JSON.parse(require('fs').readFileSync(0, 'utf8'));
require(es5 + '/node-main.js').init({
  loader: {load: ['input/tex-full']},
  // every package JupyterLab's MathJax has, but no red text for an unknown macro: an error
  tex: {packages: {'[-]': ['bussproofs', 'noundefined']}, formatError: (jax, err) => { throw err; }},
}).then((MathJax) => {
  const out = groups.map((maths) => {
    MathJax.startup.getComponents();   // a fresh TeX input: no definitions from another notebook
    MathJax.startup.makeMethods();
    const errors = [];
    for (const [tex, display] of maths) {
      try { MathJax.tex2mml(tex, {display}); } catch (err) { errors.push([tex, err.message]); }
    }
    return errors;
  });
  console.log(JSON.stringify(out));
}).catch((err) => { console.error(String(err)); process.exit(2); });
"""


def notebook_maths(nb) -> list[tuple[str, bool]]:
    """The maths of the Markdown cells of ``nb``, in order, as ``(tex, display)`` (markdown-it
    with the dollar-maths and amsmath rules, as MyST and JupyterLab read ``$``, ``$$`` and
    ``\\begin{...}``)."""
    from markdown_it import MarkdownIt
    from mdit_py_plugins.amsmath import amsmath_plugin
    from mdit_py_plugins.dollarmath import dollarmath_plugin

    md = MarkdownIt("commonmark").use(dollarmath_plugin, double_inline=True).use(amsmath_plugin)
    out = []

    def walk(tokens):
        for t in tokens:
            if t.type in (
                "math_inline",
                "math_inline_double",
                "math_block",
                "math_block_label",
                "amsmath",
            ):
                out.append((t.content, t.type != "math_inline"))
            if t.children:
                walk(t.children)

    for cell in nb.cells:
        if cell.cell_type == "markdown":
            walk(md.parse(cell.source))
    return out


def mathjax_errors(groups: list[list[tuple[str, bool]]]) -> list[list[tuple[str, str]]]:
    """For each group of formulas (one notebook's, in order), ``(tex, message)`` for every
    formula MathJax 3 (the copy the book ships, run by node) cannot typeset, definitions made by
    earlier formulas of the group applying to later ones as in a JupyterLab page."""
    import importlib.util

    import shutil

    if shutil.which("node") is None:
        raise RuntimeError(
            "node not found: the maths check runs the book's MathJax in Node.js "
            "(Debian: apt-get install nodejs)"
        )
    spec = importlib.util.find_spec("mathjax")
    es5 = Path(next(iter(spec.submodule_search_locations))) / "static" / "mathjax" / "es5"
    run = subprocess.run(
        ["node", "-e", _MATHJAX_CHECK, str(es5)],
        input=json.dumps(groups),
        capture_output=True,
        text=True,
        check=True,
    )
    return [[tuple(e) for e in errors] for errors in json.loads(run.stdout)]


def raw_markup(nb) -> list[str]:
    """The MyST roles and directive openings left in the Markdown cells of ``nb``."""
    found = []
    for cell in nb.cells:
        if cell.cell_type == "markdown":
            found += [m.group(0) for m in _ROLE.finditer(cell.source)]
            found += [m.group(0).strip() for m in _RAW_DIRECTIVE.finditer(cell.source)]
    return found


def problems(*nbs) -> list[str] | list[list[str]]:
    """What would not render in Jupyter, for each notebook: raw MyST markup and maths MathJax
    cannot typeset (one list for one notebook; a list per notebook for several, checked by
    one MathJax)."""
    maths = mathjax_errors([notebook_maths(nb) for nb in nbs])
    out = [
        [f"raw MyST markup {m!r}" for m in raw_markup(nb)]
        + [f"maths error in ${tex}$: {msg}" for tex, msg in errors]
        for nb, errors in zip(nbs, maths)
    ]
    return out[0] if len(nbs) == 1 else out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    nbs = sub.add_parser("notebooks", help="one converted notebook per chapter")
    nbs.add_argument("--root", type=Path, default=REPO)
    nbs.add_argument("--out", type=Path, default=REPO / "_build" / "notebooks")
    nbs.add_argument(
        "--glue",
        type=Path,
        default=REPO / "_build" / "jupyter_execute",
        help="myst-nb's executed notebooks (glue values); placeholders when absent",
    )
    chk = sub.add_parser("check", help="report what would not render in Jupyter")
    chk.add_argument("notebooks", type=Path, nargs="+")
    args = parser.parse_args(argv)
    if args.command == "notebooks":
        glue = args.glue if args.glue.is_dir() else None
        written = write_notebooks(args.root, args.out, glue)
        print(
            f"{len(written)} notebooks in {args.out} (glue values "
            f"{'from ' + str(glue) if glue else 'not computed: placeholders'})"
        )
        return 0
    import nbformat

    found = problems(*[nbformat.read(path, as_version=4) for path in args.notebooks])
    found = [found] if len(args.notebooks) == 1 else found
    for path, probs in zip(args.notebooks, found):
        for p in probs:
            print(f"{path}: {p}", file=sys.stderr)
    print(f"{len(args.notebooks)} notebooks checked: {sum(map(len, found))} problems")
    return 1 if any(found) else 0


if __name__ == "__main__":
    sys.exit(main())
