"""Checks of the PDF edition (run by ``tools/pdf_edition.py build``, hence by ``make pdf``).

    python tools/check_pdf.py --pdf _build/pdf/fdi-book.pdf --tex .../fdi-book.tex [--html _build/html]

Fails (exit status 1, one line per problem) when:

- the page count is outside :data:`PAGES` (an empty or runaway document);
- the text of the PDF (``pdftotext``) shows a Python repr (``Table(``, ``<Explorable``) or a
  raw TeX macro (``\\name`` with two letters or more) more often than the code listings of the
  LaTeX source print it (a cell's source may hold TeX in a string: ``r"$\\Psi_k$"``), outside
  :data:`ALLOWED_MACROS`;
- the LaTeX log has an undefined reference or citation (printed as "??" in the PDF) or hyper
  reference (a dead link), or a
  character that the font lacks (xelatex drops it from the page: "Missing character");
- the layout regressed (issue 33): an overfull box over :data:`OVERFULL_ALLOWANCE_PT`
  (horizontal: a table, a figure or a line beyond the text width; vertical: something taller
  than its page or box, in the bottom margin), a float too large for its page, or a last LaTeX
  pass that still asks for a rerun (cross-references not settled);
- a word of the PDF lies outside the text block (:func:`width_problems`, measured in the PDF by
  ``pdftotext -bbox-layout``: a table, a figure's label or a code line wider than the text,
  whatever the log says);
- the chapters numbered in the PDF's table of contents are not 1, 2, ... for the chapters of the
  parts ``numbered: true`` of ``_toc.yml``, in order and with their titles, or another chapter
  is numbered;
- with ``--html``: a page of the HTML book has more images in its article than its part of the
  LaTeX source includes (every figure, explorables included, must be in the PDF), or the PDF
  embeds fewer images than the LaTeX source includes files (``pdfimages -list``);
- a figure's smallest text prints under :data:`PRINTED_MIN_FONT_PT` (issue 33: an
  explorable's small multiples), measured in the PDF (:func:`printed_fonts`).
"""

from __future__ import annotations

import argparse
import contextlib
import html
import re
from collections import Counter
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

#: A sane page count for the book (about 180 pages in 2026): fewer means pages went missing,
#: more that something runs away (a table or listing breaking one line per page).
PAGES = (60, 600)

#: Backslash names that the PDF may show as text: none so far (a code listing that prints TeX
#: would need its macro here, with the listing named).
ALLOWED_MACROS: frozenset[str] = frozenset()

_MACRO = re.compile(r"\\([a-zA-Z]{2,})")
_REPRS = ("Table(", "<Explorable")
_DOC_LABEL = re.compile(r"\\label\{\\detokenize\{([^}]*)::doc\}\}")
_GRAPHICS = re.compile(r"\\(?:sphinx)?includegraphics(?:\[[^\]]*\])?\{(?:\{)?([^}]+)")
_TOC_CHAPTER = re.compile(r"\\contentsline \{chapter\}\{(.*)\}\{[^{}]*\}\{[^{}]*\}%?\s*$")
_NUMBERLINE = re.compile(r"^\\numberline \{(\d+)\}(.*)$")


def run(*cmd: str) -> str:
    return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout


def page_count(pdf: Path) -> int:
    m = re.search(r"^Pages:\s+(\d+)", run("pdfinfo", str(pdf)), re.M)
    if not m:
        raise RuntimeError(f"pdfinfo gives no page count for {pdf}")
    return int(m.group(1))


def code_macros(tex: str) -> Counter:
    """How often each backslash name is printed by the code listings of a LaTeX source
    (``sphinxVerbatim``, where Pygments writes a backslash as ``\\PYGZbs{}``)."""
    code = "\n".join(re.findall(r"\\begin\{sphinxVerbatim\}.*?\\end\{sphinxVerbatim\}", tex, re.S))
    code = code.replace(r"\PYGZbs{}", "\x00")
    code = re.sub(r"\\PYG\{[^}]*\}\{", "", code)  # the opening of a highlighted token
    code = re.sub(r"\\PYGZ\w+\{\}", " ", code).replace("}", "")
    return Counter(re.findall("\x00([a-zA-Z]{2,})", code))


def text_problems(pdf: Path, tex: Path) -> list[str]:
    """Reprs and raw macros in the text of the PDF, with their page; a macro is raw where the
    PDF shows it more often than its code listings do (every occurrence is then listed)."""
    problems = []
    pages = run("pdftotext", "-enc", "UTF-8", str(pdf), "-").split("\f")
    shown = Counter(m.group(1) for text in pages for m in _MACRO.finditer(text))
    in_code = code_macros(tex.read_text(errors="replace"))
    raw = {name for name, n in shown.items() if n > in_code[name] and name not in ALLOWED_MACROS}
    for page, text in enumerate(pages, start=1):
        for r in _REPRS:
            if r in text:
                i = text.index(r)
                problems.append(f"page {page}: a Python repr {text[i : i + 60]!r}")
        for m in _MACRO.finditer(text):
            if m.group(1) in raw:
                problems.append(
                    f"page {page}: raw macro {m.group(0)!r} in "
                    f"{text[max(m.start() - 30, 0) : m.end() + 30]!r}"
                )
    return problems


def log_problems(log: Path) -> list[str]:
    if not log.is_file():
        return [f"no LaTeX log {log}"]
    return log_problems_in(log.read_text(errors="replace"))


def log_problems_in(text: str) -> list[str]:
    """The problems of a LaTeX log's text (see the module docstring)."""
    # a hyper reference too (a link whose target has no label: a dead link in the PDF); the
    # warning may wrap before "undefined"
    problems = [
        "LaTeX: " + " ".join(m.group(0).split())
        for m in re.finditer(
            r"LaTeX Warning: (?:Reference|Citation|Hyper reference) `[^']*' on page \d+\s+"
            r"undefined[^\n]*",
            text,
        )
    ]
    problems += overfull_boxes(text)
    problems += [f"LaTeX: {m.group(0)}" for m in re.finditer(r"Float too large[^\n]*", text)]
    if log_counts(text)["rerun"]:
        problems.append("LaTeX: the last pass asks for a rerun (cross-references not settled)")
    problems += [
        f"LaTeX: {n} times no {c!r} in the font (dropped from the page)"
        for c, n in sorted(missing_characters(text).items())
    ]
    return problems


#: Overfull boxes up to this many points are tolerated (:func:`log_problems`).
OVERFULL_ALLOWANCE_PT = 5.0
#: Every overfull box over it fails, horizontal (a table, figure or line wider than the text) or
#: vertical (issue 33: a framed box split by a page break or a table taller than a page ran into
#: the bottom margin, 9 times in the letter edition and 8 in the A4 one of December 2026, allowed
#: then by a budget of 12; ``LATEX_LAYOUT`` and ``_PrintedTables`` of ``_ext/fdi_book.py``).
_OVERFULL = re.compile(r"^Overfull \\[hv]box \(([\d.]+)pt too (\w+)\) (.*)$", re.M)

#: How far (in PDF points) a word may stick out of the text block: the rounding of glyph boxes.
OUTSIDE_ALLOWANCE_PT = 2.0
_LINE_BOX = re.compile(r'<line xMin="([\d.]+)" yMin="[\d.]+" xMax="([\d.]+)"')
_WORD_BOX = re.compile(
    r'<word xMin="([\d.]+)" yMin="[\d.]+" xMax="([\d.]+)" yMax="[\d.]+">([^<]*)<'
)


def overfull_boxes(log_text: str) -> list[str]:
    """Each overfull box of a LaTeX log over :data:`OVERFULL_ALLOWANCE_PT`, with where it is."""
    return [
        f"LaTeX: overfull box {m.group(1)} pt too {m.group(2)} {m.group(3)}"
        for m in _OVERFULL.finditer(log_text)
        if float(m.group(1)) > OVERFULL_ALLOWANCE_PT
    ]


def text_block(pages: list[str]) -> tuple[float, float]:
    """The left and right edges of the text block (PDF points), measured: the most frequent
    start and end of a line of the PDF (a justified paragraph's lines fill the text width)."""
    starts = Counter(round(float(a)) for page in pages for a, _ in _LINE_BOX.findall(page))
    ends = Counter(round(float(b)) for page in pages for _, b in _LINE_BOX.findall(page))
    if not starts:
        raise RuntimeError("pdftotext found no line of text")
    return float(starts.most_common(1)[0][0]), float(ends.most_common(1)[0][0])


def outside_words(pages: list[str]) -> list[tuple[int, float, str]]:
    """``(page, points outside, word)`` for each word of the PDF that lies outside the text block
    (:func:`text_block`) by more than :data:`OUTSIDE_ALLOWANCE_PT`; the cover page included."""
    left, right = text_block(pages)
    out = []
    for number, page in enumerate(pages, start=1):
        for x0, x1, word in _WORD_BOX.findall(page):
            beyond = max(left - float(x0), float(x1) - right)
            if beyond > OUTSIDE_ALLOWANCE_PT:
                out.append((number, round(beyond, 1), html.unescape(word)))
    return out


def width_problems(pdf: Path) -> list[str]:
    """Every page with words beyond the text block: how far the widest goes, and the words
    (the cut of a table, figure or listing wider than the text)."""
    layout = run("pdftotext", "-bbox-layout", str(pdf), "-")
    pages = layout.split("<page ")[1:]
    by_page: dict[int, list[tuple[float, str]]] = {}
    for number, beyond, word in outside_words(pages):
        by_page.setdefault(number, []).append((beyond, word))
    return [
        f"page {n}: {len(w)} words beyond the text block, up to {max(w)[0]:g} pt "
        f"({' '.join(x for _, x in w[:6])})"
        for n, w in sorted(by_page.items())
    ]


def log_counts(log_text: str) -> dict[str, float]:
    """What the LaTeX log says of the layout: overfull boxes (all, those over
    :data:`OVERFULL_ALLOWANCE_PT`, the widest in points), underfull boxes and rerun requests
    ("Rerun to get ...", "Label(s) may have changed"). Printed by :func:`main`; :func:`log_problems` fails on them."""
    over = [float(x) for x in re.findall(r"^Overfull \\[hv]box \(([\d.]+)pt too", log_text, re.M)]
    return {
        "overfull": len(over),
        "overfull_over_allowance": sum(x > OVERFULL_ALLOWANCE_PT for x in over),
        "overfull_max_pt": max(over, default=0.0),
        "underfull": len(re.findall(r"^Underfull \\[hv]box", log_text, re.M)),
        "rerun": len(
            re.findall(r"^.*(?:Rerun to get|Label\(s\) may have changed).*$", log_text, re.M)
        ),
    }


def missing_characters(log_text: str) -> Counter:
    """Characters that a font of the PDF lacks, which xelatex drops from the page with only a
    log line ("Missing character: There is no ₖ (U+2096) in font ..."), and how often. The
    script characters of plain-text captions ("Γₖ", "Hᵀ") have a fallback font
    (``_ext/fdi_book.py``, :func:`latex_script_fallback`)."""
    return Counter(re.findall(r"Missing character: There is no (\S+)", log_text))


def _plain(tex: str) -> str:
    """A TeX title reduced to its lowercase letters and digits (for comparing titles)."""
    tex = tex.replace(r"\sphinxhyphen {}", "-").replace(r"\sphinxhyphen{}", "-")
    tex = re.sub(r"\\[a-zA-Z]+\s*", "", tex)
    return re.sub(r"[^a-z0-9]", "", tex.lower())


def numbered_chapters(src: Path) -> list[tuple[str, str]]:
    """``(doc, title)`` of the chapters of the numbered parts of ``_toc.yml``, in order."""
    import yaml

    toc = yaml.safe_load((src / "_toc.yml").read_text())
    out = []
    for part in toc.get("parts", []):
        if part.get("numbered"):
            for chapter in part.get("chapters", []):
                text = (src / f"{chapter['file']}.md").read_text()
                title = re.search(r"^#\s+(.+?)\s*$", text, re.M).group(1)
                out.append((chapter["file"], title))
    return out


def toc_problems(toc: Path, src: Path) -> list[str]:
    if not toc.is_file():
        return [f"no table of contents {toc}"]
    found = []
    for line in toc.read_text(errors="replace").splitlines():
        m = _TOC_CHAPTER.match(line.strip())
        if m:
            n = _NUMBERLINE.match(m.group(1))
            if n:
                found.append((int(n.group(1)), n.group(2)))
    expected = numbered_chapters(src)
    problems = []
    if [n for n, _ in found] != list(range(1, len(expected) + 1)):
        problems.append(f"numbered chapters {[n for n, _ in found]}, expected 1 to {len(expected)}")
    for (n, title), (doc, want) in zip(found, expected):
        if _plain(title) != _plain(re.sub(r"[$\\]", "", want)):
            problems.append(f"chapter {n} is {title!r}, expected {want!r} ({doc})")
    return problems


def html_images(html: Path) -> dict[str, int]:
    """Images in the article of each page of the HTML book, by document name."""
    from bs4 import BeautifulSoup

    counts = {}
    for page in sorted(html.rglob("*.html")):
        doc = page.relative_to(html).with_suffix("").as_posix()
        if not doc.startswith("book/"):
            continue
        article = BeautifulSoup(page.read_text(errors="replace"), "html.parser").select_one(
            "article"
        )
        counts[doc] = len(article.find_all("img")) if article else 0
    return counts


def tex_images(tex: Path) -> dict[str, list[str]]:
    """The image files included by the LaTeX source, by document (the part after the
    document's ``\\label{...::doc}``)."""
    out: dict[str, list[str]] = {}
    doc = None
    for line in tex.read_text(errors="replace").splitlines():
        for m in _DOC_LABEL.finditer(line):
            doc = m.group(1)
        for m in _GRAPHICS.finditer(line):
            out.setdefault(doc, []).append(m.group(1))
    return out


def image_problems(html: Path, tex: Path, pdf: Path) -> list[str]:
    problems = []
    included = tex_images(tex)
    for doc, n in html_images(html).items():
        if n > len(included.get(doc, [])):
            problems.append(
                f"{doc}: {n} images in the HTML page, {len(included.get(doc, []))} in the PDF"
            )
    files = {f for fs in included.values() for f in fs}
    rows = [line.split() for line in run("pdfimages", "-list", str(pdf)).splitlines()[2:]]
    embedded = sum(1 for r in rows if len(r) > 2 and r[2] == "image")
    if embedded < len(files):
        problems.append(
            f"the PDF embeds {embedded} images, the LaTeX source includes {len(files)} files"
        )
    return problems


#: Smallest text of a figure of the PDF, in points as printed (issue 33).
PRINTED_MIN_FONT_PT = 8.0


def printed_fonts(tex: Path, pdf: Path) -> dict[str, float]:
    """The smallest text of each figure of the LaTeX source ``tex`` that says its size (the PNG
    text ``fdi:min_font_pt``, points at the resolution ``fdi:dpi``: the book's figures and the
    explorables' small multiples), in points as ``pdf`` prints it: ``font * dpi / ppi``, with
    ``ppi`` the resolution the PDF gives the image (``pdfimages -list``), by ``"page N
    (file)"``. The PDF's images are those the source includes, in its order (a figure does not
    pass another); if their sizes in pixels say otherwise, each figure is measured at the
    highest resolution of the PDF's images of its size."""
    from PIL import Image

    rows = [r.split() for r in run("pdfimages", "-list", str(pdf)).splitlines()[2:]]
    shown = [(int(r[3]), int(r[4]), float(r[12]), int(r[0])) for r in rows if r[2:3] == ["image"]]
    files = [tex.parent / f"{name}.png" for names in tex_images(tex).values() for name in names]
    sizes = []
    for png in files:
        with Image.open(png) if png.is_file() else contextlib.nullcontext() as img:
            sizes.append(None if img is None else (img.size, img.info))
    if [s[0] if s else None for s in sizes] != [(w, h) for w, h, _, _ in shown]:
        best = {}
        for w, h, ppi, page in shown:
            best[(w, h)] = max(best.get((w, h), (0.0, 0)), (ppi, page))
        shown = [(*s[0], *best[s[0]]) if s and s[0] in best else None for s in sizes]
    out = {}
    for png, size, image in zip(files, sizes, shown):
        if size is None or image is None:
            continue
        font, dpi = size[1].get("fdi:min_font_pt"), size[1].get("fdi:dpi")
        if font and dpi:
            out[f"page {image[3]} ({png.name})"] = float(font) * float(dpi) / image[2]
    return out


def font_problems(fonts: dict[str, float]) -> list[str]:
    return [
        f"{name}: its smallest text prints at {pt:.1f} pt, under {PRINTED_MIN_FONT_PT:g} pt "
        "(PRINTED_MIN_FONT_PT)"
        for name, pt in sorted(fonts.items())
        if pt < PRINTED_MIN_FONT_PT
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pdf", type=Path, required=True)
    parser.add_argument("--tex", type=Path, required=True, help="the LaTeX source of the PDF")
    parser.add_argument("--html", type=Path, help="the HTML build of the same sources")
    parser.add_argument("--src", type=Path, default=REPO, help="the book's sources (_toc.yml)")
    args = parser.parse_args(argv)
    pages = page_count(args.pdf)
    problems = (
        []
        if PAGES[0] <= pages <= PAGES[1]
        else [f"{pages} pages, expected {PAGES[0]} to {PAGES[1]}"]
    )
    problems += text_problems(args.pdf, args.tex)
    problems += width_problems(args.pdf)
    problems += log_problems(args.tex.with_suffix(".log"))
    problems += toc_problems(args.tex.with_suffix(".toc"), args.src)
    if args.html is not None:
        problems += image_problems(args.html, args.tex, args.pdf)
    fonts = printed_fonts(args.tex, args.pdf)
    problems += font_problems(fonts)
    for p in problems:
        print("check_pdf:", p, file=sys.stderr)
    figures = sum(len(v) for v in tex_images(args.tex).values())
    log = args.tex.with_suffix(".log")
    counts = log_counts(log.read_text(errors="replace")) if log.is_file() else {}
    files = {"list of figures": args.tex.with_suffix(".lof"), "index": args.tex.with_suffix(".ind")}
    present = {kind: f.is_file() and f.stat().st_size > 0 for kind, f in files.items()}
    extras = [f"{kind}: {'yes' if there else 'no'}" for kind, there in present.items()]
    if fonts:
        extras.append(f"smallest printed figure text {min(fonts.values()):.1f} pt")
    print("check_pdf: layout: " + ", ".join([f"{k} {v:g}" for k, v in counts.items()] + extras))
    print(
        f"check_pdf: {args.pdf}: {pages} pages, {figures} images, "
        f"{'ok' if not problems else f'{len(problems)} problems'}"
    )
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
