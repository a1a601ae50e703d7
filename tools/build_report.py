"""What ``make book`` measures once the HTML is written: build time and page weights.

The status page (``book/status.md``) is executed while the book is read, before any page is
written: it cannot know how long the build took, nor what the written pages weigh. ``make book``
runs this script right after Jupyter Book:

    python tools/build_report.py --html _build/html --log _build.log --started EPOCH

1. The execution time of each chapter, from the "Executed notebook in N seconds" lines of the
   build log (``tools/execute_book.py``, which executes the chapters side by side before Jupyter
   Book builds the pages, writes them as myst-nb does), printed with their sum and the wall time
   of the whole execution, against the book's budget of 60 s for the latter (issue 35).
2. The wall time of the build: from ``EPOCH`` (when ``make book`` started) to now, the end of
   Jupyter Book.
3. The weight of every page: what a first visit loads, measured in headless Chromium by
   ``tests/browser/page_weights.py`` (the browser test checks the same figures against the page
   budget). Without Chromium the status page says so.
4. Both tables replace the placeholders of the built status page (``<div id="fdi-build-time">``
   and ``<div id="fdi-page-weights">``, each closed by a ``<!-- /id -->`` comment), and
   everything is written to ``--json`` (default ``_build/build-report.json``).
"""

from __future__ import annotations

import argparse
import datetime
import json
import re
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "browser"))

from fdi_lib.report import NBSP, fmt_number, fmt_time, table  # noqa: E402

#: Execution budget of the whole book: the wall time from the first chapter started to the last
#: finished, the chapters side by side on 2 cores (issue 35; README, status page).
EXECUTION_BUDGET_S = 60.0
STATUS_PAGE = "book/status.html"
_EXECUTED = re.compile(r"^(\S+\.(?:md|ipynb)): Executed notebook in ([0-9.]+) seconds")
_EXECUTION_WALL = re.compile(r"^Executed \d+ notebooks in ([0-9.]+) s of wall time")


def execution_wall(log: str) -> float | None:
    """The wall time of the whole execution (``tools/execute_book.py``'s last line), if logged."""
    found = [float(m.group(1)) for m in map(_EXECUTION_WALL.match, log.splitlines()) if m]
    return found[-1] if found else None


def execution_times(log: str, root: Path) -> dict[str, float]:
    """Chapter (path relative to ``root``) -> seconds, from the build log's myst-nb lines."""
    out: dict[str, float] = {}
    for line in log.splitlines():
        m = _EXECUTED.match(line.strip())
        if m:
            path = Path(m.group(1))
            out[path.relative_to(root).as_posix() if path.is_relative_to(root) else m.group(1)] = (
                float(m.group(2))
            )
    return out


def _mb(n: int) -> str:
    return f"{fmt_number(n / 1e6, 3)}{NBSP}MB"


def times_html(times: dict[str, float], wall: float, execution: float | None = None) -> str:
    rows = {"make book, wall time up to the end of Jupyter Book": [fmt_time(wall)]}
    if execution is not None:
        rows["execution of the chapters, side by side, wall time"] = [fmt_time(execution)]
    if times:
        slow = max(times, key=times.get)
        rows[f"execution of the {len(times)} chapters, sum"] = [fmt_time(sum(times.values()))]
        rows["slowest chapter"] = [f"{fmt_time(times[slow])} ({slow})"]
    notes = [
        f"Execution budget of the book: {fmt_time(EXECUTION_BUDGET_S)} of wall time on 2 "
        "cores, the chapters executed side by side (tools/execute_book.py), each chapter's "
        "time being its own wall time on its share of the cores; the rest of the build is "
        "Sphinx reading and writing the pages.",
        "Measured on "
        + datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
        + " by tools/build_report.py.",
    ]
    if not times:
        notes.append("No chapter was executed in this build (cached execution).")
    return table(rows, ["time"], notes=notes, index_header="")._repr_html_()


#: What a page's bytes are, the columns of the status page's table of page weights.
PARTS = ("HTML", "MathJax", "images", "theme and scripts")


def weight_parts(w: dict) -> dict[str, int]:
    """A page's bytes by :data:`PARTS`: its HTML, MathJax (scripts and fonts), image files
    (figures), and the rest (theme, icon font, search index, previews)."""
    parts = dict.fromkeys(PARTS, 0)
    for path, size in w["assets"]:
        if path == w["page"]:
            parts["HTML"] += size
        elif path.startswith("mathjax/"):
            parts["MathJax"] += size
        elif Path(path).suffix.lower() in {".png", ".jpg", ".jpeg", ".gif", ".svg", ".webp"}:
            parts["images"] += size
        else:
            parts["theme and scripts"] += size
    return parts


def weights_html(weights: list[dict], budget_mb: float) -> str:
    rows = {}
    for w in sorted(weights, key=lambda w: -w["bytes"]):
        parts = weight_parts(w)
        rows[w["page"].removeprefix("book/").removesuffix(".html")] = [
            _mb(w["bytes"]),
            *(_mb(v) if v else "none" for v in parts.values()),
        ]
    notes = [
        f"What a first visit to the page loads (empty cache): the HTML (explorable frames are "
        f"inside it), MathJax's scripts and fonts, the figures' image files, and the rest: the "
        f"theme's stylesheets and scripts, its icon font, the search index, the previews; measured "
        f"in headless Chromium from a local server that does not compress "
        f"(tests/browser/page_weights.py). Budget: {fmt_number(budget_mb)}{NBSP}MB a page, checked "
        "by make browser-test.",
        "MathJax is loaded only by pages with maths; on another page a preview with maths loads it "
        "when first shown.",
    ]
    return table(rows, ["loaded", *PARTS], notes=notes, index_header="page")._repr_html_()


def inject(page: Path, ident: str, html: str) -> None:
    """Replace the content of ``<div id="ident">…</div><!-- /ident -->`` in ``page``."""
    text = page.read_text()
    pattern = re.compile(rf'(<div id="{ident}">)(.*?)(</div><!-- /{ident} -->)', re.S)
    if not pattern.search(text):
        raise SystemExit(f'{page}: no placeholder <div id="{ident}"> (book/status.md)')
    page.write_text(pattern.sub(lambda m: m.group(1) + html + m.group(3), text, count=1))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--html", default=ROOT / "_build" / "html", type=Path)
    parser.add_argument("--log", default=ROOT / "_build.log", type=Path)
    parser.add_argument(
        "--started", type=float, required=True, help="start of the build (Unix time)"
    )
    parser.add_argument("--json", default=ROOT / "_build" / "build-report.json", type=Path)
    args = parser.parse_args(argv)
    wall = time.time() - args.started
    log = args.log.read_text(errors="replace")
    times, execution = execution_times(log, ROOT), execution_wall(log)
    print("Execution time per chapter:")
    for chapter, t in times.items():
        print(f"  {chapter:45s} {t:8.1f} s")
    print("  " + "-" * 57)
    print(f"  {'sum over the chapters':45s} {sum(times.values()):8.1f} s")
    if execution is not None:
        print(
            f"  {'execution, wall time':45s} {execution:8.1f} s (budget {EXECUTION_BUDGET_S:g} s)"
        )
    print(f"  {'make book, wall time':45s} {wall:8.1f} s")
    status = args.html / STATUS_PAGE
    inject(status, "fdi-build-time", times_html(times, wall, execution))

    from check_book import CHROMIUM, book_pages, built_book
    from page_weights import PAGE_BUDGET_MB, failures, measure

    report = {"wall_s": wall, "execution_s": times, "execution_wall_s": execution, "pages": None}
    if Path(CHROMIUM).exists():
        root = built_book(args.html)
        report["pages"] = measure(root, book_pages(root))
        inject(status, "fdi-page-weights", weights_html(report["pages"], PAGE_BUDGET_MB))
        heavy = max(report["pages"], key=lambda w: w["bytes"])
        print(
            f"Page weights: {len(report['pages'])} pages, heaviest {heavy['page']} "
            f"{heavy['bytes'] / 1e6:.2f} MB; {len(failures(report['pages']))} over budget or "
            "loading what they do not need (make browser-test fails on them)"
        )
    else:
        inject(
            status,
            "fdi-page-weights",
            f"<p>Not measured in this build: no Chromium at {CHROMIUM} "
            "(<code>make browser-test</code> installs it).</p>",
        )
        print(f"Page weights not measured: no Chromium at {CHROMIUM}")
    args.json.write_text(json.dumps(report, indent=1))
    print(f"Build report in {args.json} and {status}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
