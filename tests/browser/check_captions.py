"""Post-build check: every figure caption of the built book agrees with the claims ledger.

After ``make book`` (not collected by pytest; ``tests/reproduce/test_captions.py`` tests the
rule and the chapter sources). For each caption in ``_build/html`` that names a paper figure or
table ("reproduces / compare with / redraws paper Fig. N"), it reads the reproduction identifier
in the caption's parenthesis and recomputes :func:`fdi_lib.reproduce.views.ledger.figure_claim` from
the result the build cached for that identifier (``_build/results-cache``, the results the
claims ledger page shows). It fails when

- ``verb``: the caption's verb is not the ledger's (a typed verb, or a caption glued from
  another run than the one the ledger reads);
- ``differs``: the caption does not say what differs, as the ledger does;
- ``result``: no cached result for the caption's identifier (the ledger could not show it);
- ``caption``: a caption names a paper figure without a verb or an identifier.

The explorables (figures of class ``fdi-explorable-figure`` around sliders over a widget
callback, written by the book's extension; ``fdi-explorable`` outside the book) are not
results: their captions say "as paper Fig. N" for the setting they redraw and carry no ledger
claim, so they are not checked.

Usage: ``python tests/browser/check_captions.py [--html _build/html] [--cache _build/results-cache]``
(run with the library that built the book: the cache is keyed by the code's hash). Prints
``page | check | detail`` per failure and exits 1 if there is any.
"""

from __future__ import annotations

import argparse
import html
import os
import re
import sys
from pathlib import Path

VERBS = ("reproduces", "compare with", "redraws")
_PAPER_FIGURE = re.compile(r"(?:\b(\w+(?: with)?) )?[Pp]aper (?:Fig\.|Table)")
_ID = re.compile(r"\(((?:zb2014|zhang2021|bz|rosa2013)-[a-z0-9-]+?)(?=[;)])")
SKIP_DIRS = {"_static", "_sources", "_images", "mathjax", "_sphinx_design_static"}


def captions(page: Path) -> list[str]:
    """The plain text of every ``<figcaption>`` of an HTML page but the explorables' (tags
    removed, entities and typographic quotes undone, white space collapsed)."""
    out = []
    figures = re.findall(r"<figure\b([^>]*)>(.*?)</figure>", page.read_text(), flags=re.S)
    for raw in (
        c
        for attrs, body in figures
        if "fdi-explorable" not in attrs  # -figure too
        for c in re.findall(r"<figcaption>(.*?)</figcaption>", body, flags=re.S)
    ):
        text = html.unescape(re.sub(r"<[^>]+>", "", raw))
        text = text.replace("\u2019", "'").replace("\u00b6", "")
        out.append(" ".join(text.split()))
    return out


def check(root: Path) -> list[tuple[str, str, str]]:
    """``(page, check, detail)`` for every caption that disagrees with the ledger."""
    from fdi_lib.reproduce.book import book_settings
    from fdi_lib.reproduce.views.ledger import figure_claim
    from fdi_lib.reproduce.registry import cached_run, list_reproductions

    # the build's run of each id at the book's settings, the one the ledger reads (none computed)
    results = {}
    for rep in list_reproductions():
        book = book_settings(rep.id)
        hit = cached_run(rep.id, seed=book.seed, trials=book.trials)
        if hit is not None:
            results[rep.id] = hit
    failures = []
    pages = sorted(
        p for p in root.rglob("*.html") if not SKIP_DIRS & set(p.relative_to(root).parts[:-1])
    )
    for page in pages:
        name = page.relative_to(root).as_posix()
        for text in captions(page):
            m = _PAPER_FIGURE.search(text)
            if not m:
                continue
            ids = _ID.findall(text[m.end() :])
            if m.group(1) not in VERBS or not ids:
                failures.append((name, "caption", f"no ledger verb or identifier: {text[:120]}"))
                continue
            id = ids[0]
            if id not in results:
                failures.append(
                    (name, "result", f"{id}: no cached result at the book's settings in this build")
                )
                continue
            claim = figure_claim(results[id])
            if m.group(1) != claim.verb:
                failures.append(
                    (name, "verb", f"{id}: caption says {m.group(1)!r}, the ledger {claim.verb!r}")
                )
            differs = " ".join(claim.differs.replace("\u2019", "'").split())
            if f"{id}{differs})" not in text:
                failures.append((name, "differs", f"{id}: the ledger says {differs!r}"))
    return failures


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--html", default="_build/html", type=Path)
    parser.add_argument("--cache", default="_build/results-cache", type=Path)
    args = parser.parse_args(argv)
    if not (args.html / "index.html").exists() or not args.cache.is_dir():
        print(
            f"error: build the book first (no {args.html}/index.html or {args.cache})",
            file=sys.stderr,
        )
        return 2
    os.environ["FDI_RESULTS_CACHE"] = str(args.cache.resolve())
    failures = check(args.html)
    for f in failures:
        print(" | ".join(f))
    n = sum(
        len([t for t in captions(p) if _PAPER_FIGURE.search(t)])
        for p in args.html.rglob("*.html")
        if not SKIP_DIRS & set(p.relative_to(args.html).parts[:-1])
    )
    print(f"{n} captions naming a paper figure, {len(failures)} disagreeing with the ledger")
    return 1 if failures else 0


if __name__ == "__main__":
    raise SystemExit(main())
