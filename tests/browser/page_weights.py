"""What each page of the built book loads, measured in a real browser (``make browser-test``;
also used by ``tools/build_report.py`` for the status page's table after ``make book``).

Every page is opened in headless Chromium as ``check_book.py`` opens it (served by a local
``http.server``, every request to another host blocked), in a fresh browser context (an empty
cache: what a first visit loads), at 1280 px. Once the page has loaded, MathJax has finished,
every image (lazy ones too) and every font face it lays out is loaded, and every request has been
answered with none for :data:`QUIET_S`, the weight of the page is the sum of the sizes of every
file it requested: the HTML, scripts, stylesheets, fonts and images (``data:`` images are inside
the HTML). The local server sends
files as they are on disk (no compression), so a file's size is what it transfers; a web server
that compresses would send less (MathJax's scripts by about 3x, PNG images not at all).

Fails (exit status 1) on:

- ``weight``: a page that loads more than :data:`PAGE_BUDGET_MB`;
- ``mathjax``: a page that loads MathJax but has no maths (no ``.math`` element);
- ``fontawesome``: a page that loads the theme's 1.5 MB Font Awesome script (the icons come
  from the theme's Font Awesome stylesheet and font).

A page measured by ``make book`` (``--report``, the build report of ``tools/build_report.py``) is not
opened again when nothing it loaded has changed since: its HTML file has the same SHA-1 and every
file it requested the same size (a page's weight is the sum of those sizes, and the same HTML
requests the same files). One file may differ: the PDF edition's script (:data:`AFTER_BUILD`),
which ``make pdf`` rewrites after the build to link the PDF from the download menu (it requests
nothing); a reused page's sizes are then read again. Any other page is measured afresh (the status
page, for one: the build writes its tables into it after measuring).

Usage: ``python tests/browser/page_weights.py [--html _build/html] [--pages ...] [--json FILE]
[--report _build/build-report.json]``.
"""

from __future__ import annotations

import argparse
import asyncio
import hashlib
import json
import sys
import time
import urllib.parse
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from check_book import (
    CHROMIUM,
    CHROMIUM_ARGS,
    VIEWPORTS,
    WAIT_MATHJAX_JS,
    book_pages,  # noqa: E402
    built_book,
    is_local,
    serve,
)

#: Most bytes a page may load on a first visit (HTML and every asset). Issue 23 measured the
#: chapters at 4.3-6.2 MB, 1.5 MB of them a Font Awesome script on every page; without it (and
#: with the icon font cut to the icons used) the heaviest chapter, its explorable frames inside
#: the HTML, loads 4.7 MB. The build's status page shows every page's weight.
PAGE_BUDGET_MB = 5.0

#: Pages measured at a time, each in its own browser context (an empty cache each). A page is
#: about 0.3-1.7 s of Chromium's parsing, layout and MathJax. When each page also waited half a
#: second without a request, the 26 pages took 46.0 s one at a time on 2 quiet cores, 34.2 s two,
#: 31.4 s three and 28.8 s four at a time, every page's measurement the same.
PAGES_AT_ONCE = 4

MATHJAX_ENTRY = "mathjax/tex-chtml.js"
#: Files that ``make pdf`` rewrites beside the built pages without changing what a page requests:
#: the script that adds the PDF edition to the download menu (``_ext/fdi_book.py``, ``PDF_SCRIPT``).
#: Every page loads it, so before it was exempt here the browser test measured every page again
#: after ``make pdf`` (26 pages, none reused).
AFTER_BUILD = ("_static/fdi-pdf.js",)
FONTAWESOME_JS = "scripts/fontawesome.js"

#: After MathJax and the images: a layout forced (the fonts a page's text needs, MathJax's
#: among them, are requested when it is laid out) and every font face that is loading loaded.
_FONTS_READY_JS = "async () => { void document.body.offsetHeight; await document.fonts.ready; }"
#: Seconds without a request, once every request has been answered, before a page counts as
#: loaded. On the 26 pages no request came after MathJax had typeset and the images had loaded;
#: waiting half a second of silence instead cost 13 s of the 26 pages' measurement.
QUIET_S = 0.1

_LOAD_ALL_IMAGES_JS = (
    "() => Promise.all(Array.from(document.images).map(i => { i.loading = 'eager';"
    " return i.decode().catch(() => null); }))"
)


def _kind(path: str, resource_type: str) -> str:
    suffix = Path(path).suffix.lower()
    if resource_type == "document" or suffix == ".html":
        return "html"
    if suffix in {".woff", ".woff2", ".ttf", ".otf"}:
        return "font"
    if suffix in {".png", ".jpg", ".jpeg", ".gif", ".svg", ".webp", ".ico"}:
        return "image"
    return {".js": "script", ".css": "stylesheet"}.get(suffix, "other")


async def measure_page(browser, base: str, root: Path, name: str) -> dict:
    """What the page ``name`` (a path under ``root``) loads on a first visit.

    Returns
    -------
    dict
        ``page``, ``bytes`` (total), ``by_kind`` (html, script, stylesheet, font, image,
        other: bytes), ``assets`` (``[path, bytes]`` of every file, largest first),
        ``has_math`` (the page has a ``.math`` element), ``sha1`` (of the page's HTML file as
        measured: :func:`unchanged`).
    """
    sha1 = _sha1(root / name)
    context = await browser.new_context(
        viewport=VIEWPORTS["1280"], device_scale_factor=1, service_workers="block"
    )
    requested: dict[str, str] = {}

    # another host is never asked (check_book.py reports such requests)
    async def route(r):
        if is_local(r.request.url, base):
            await r.continue_()
        else:
            await r.abort("blockedbyclient")

    await context.route("**/*", route)
    page = await context.new_page()
    last = [time.monotonic()]

    pending: set = set()

    def on_request(r):
        last[0] = time.monotonic()
        pending.add(r)
        if r.url.startswith(base):
            requested.setdefault(r.url, r.resource_type)

    def on_done(r):
        last[0] = time.monotonic()
        pending.discard(r)

    page.on("request", on_request)
    page.on("requestfinished", on_done)
    page.on("requestfailed", on_done)
    await page.goto(base + name, wait_until="load")
    await page.evaluate(WAIT_MATHJAX_JS)
    await page.evaluate(_LOAD_ALL_IMAGES_JS)
    await page.evaluate(_FONTS_READY_JS)
    # every request answered and none for QUIET_S, at most 10 s
    start = time.monotonic()
    while (pending or time.monotonic() - last[0] < QUIET_S) and time.monotonic() - start < 10:
        await page.wait_for_timeout(25)
    has_math = await page.evaluate(
        "() => document.querySelector('article .math, article mjx-container') !== null"
    )
    await context.close()
    assets: dict[str, int] = {}
    for url, resource_type in requested.items():
        path = urllib.parse.unquote(urllib.parse.urlsplit(url).path).lstrip("/")
        file = root / path
        if file.is_file():
            assets[path] = file.stat().st_size
    by_kind: dict[str, int] = {}
    for path, size in assets.items():
        kind = _kind(path, requested.get(base + path, ""))
        by_kind[kind] = by_kind.get(kind, 0) + size
    return {
        "page": name,
        "bytes": sum(assets.values()),
        "by_kind": by_kind,
        "assets": sorted(([p, s] for p, s in assets.items()), key=lambda a: -a[1]),
        "has_math": has_math,
        "sha1": sha1,
    }


def _sha1(file: Path) -> str:
    return hashlib.sha1(file.read_bytes()).hexdigest()


def unchanged(w: dict, root: Path) -> bool:
    """Whether the measurement ``w`` (:func:`measure_page`) still holds for the book at ``root``:
    the page's HTML file has the SHA-1 it had when measured and every file it loaded is there with
    the size it had (any size for :data:`AFTER_BUILD`; :func:`resized` reads the sizes again)."""
    page = root / w["page"]
    return (
        page.is_file()
        and w.get("sha1") == _sha1(page)
        and all(
            (root / p).is_file() and (p in AFTER_BUILD or (root / p).stat().st_size == n)
            for p, n in w["assets"]
        )
    )


def resized(w: dict, root: Path) -> dict:
    """The measurement ``w`` of an :func:`unchanged` page with the files' sizes of now."""
    assets = {p: (root / p).stat().st_size for p, _ in w["assets"]}
    by_kind: dict[str, int] = {}
    for path, size in assets.items():
        kind = _kind(path, "")
        by_kind[kind] = by_kind.get(kind, 0) + size
    return {
        **w,
        "bytes": sum(assets.values()),
        "by_kind": by_kind,
        "assets": sorted(([p, n] for p, n in assets.items()), key=lambda a: -a[1]),
    }


def measure(root: Path, pages: list[str], *, at_once: int = PAGES_AT_ONCE) -> list[dict]:
    """:func:`measure_page` for each page, in one headless Chromium (not started for none),
    ``at_once`` pages at a time (each in its own context: an empty cache), in the order of
    ``pages``."""
    if not pages:
        return []
    server, base = serve(root)
    try:
        return asyncio.run(_measure_all(root, base, pages, at_once))
    finally:
        server.shutdown()


async def _measure_all(root: Path, base: str, pages: list[str], at_once: int) -> list[dict]:
    from playwright.async_api import async_playwright

    slots = asyncio.Semaphore(at_once)

    async def one(browser, name: str) -> dict:
        async with slots:
            w = await measure_page(browser, base, root, name)
        print(f"  measured {name}: {w['bytes'] / 1e6:.2f} MB", file=sys.stderr, flush=True)
        return w

    async with async_playwright() as pw:
        browser = await pw.chromium.launch(
            executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True
        )
        try:
            return list(await asyncio.gather(*(one(browser, name) for name in pages)))
        finally:
            await browser.close()


def failures(weights: list[dict], budget_mb: float = PAGE_BUDGET_MB) -> list[tuple[str, str, str]]:
    """``(page, check, detail)`` for every page over budget, with MathJax but no maths, or with
    the Font Awesome script."""
    out = []
    for w in weights:
        loaded = {path for path, _ in w["assets"]}
        if w["bytes"] > budget_mb * 1e6:
            top = ", ".join(f"{Path(p).name} {s / 1e6:.2f} MB" for p, s in w["assets"][:3])
            out.append(
                (w["page"], "weight", f"{w['bytes'] / 1e6:.2f} MB > {budget_mb:g} MB ({top})")
            )
        if any(p.endswith(MATHJAX_ENTRY) for p in loaded) and not w["has_math"]:
            out.append((w["page"], "mathjax", "loads MathJax but has no maths"))
        if any(p.endswith(FONTAWESOME_JS) for p in loaded):
            out.append((w["page"], "fontawesome", f"loads {FONTAWESOME_JS}"))
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--html", default="_build/html", type=Path)
    parser.add_argument("--pages", nargs="*", help="only these pages (paths relative to --html)")
    parser.add_argument("--json", type=Path, help="write the measured weights there")
    parser.add_argument(
        "--report",
        type=Path,
        help="make book's build report: reuse its measurement of every page that has not changed",
    )
    args = parser.parse_args(argv)
    root = built_book(args.html)
    if root is None:
        return 2
    pages = [p for p in book_pages(root) if not args.pages or p in args.pages]
    known = {}
    if args.report is not None and args.report.is_file():
        known = {
            w["page"]: resized(w, root)
            for w in json.loads(args.report.read_text()).get("pages") or []
            if w["page"] in pages and unchanged(w, root)
        }
        print(f"  {len(known)} of {len(pages)} pages unchanged since {args.report}: not reopened")
    fresh = iter(measure(root, [p for p in pages if p not in known]))
    weights = [known[p] if p in known else next(fresh) for p in pages]
    for w in weights:
        top = ", ".join(f"{Path(p).name} {s / 1e6:.2f}" for p, s in w["assets"][:3])
        print(f"  {w['bytes'] / 1e6:6.2f} MB  {w['page']:45s} ({top})")
    if args.json:
        args.json.write_text(json.dumps(weights, indent=1))
    found = failures(weights)
    for page, check, detail in found:
        print(f"{page} | {check} | {detail}")
    print(f"{len(weights)} pages: {len(found)} failures (budget {PAGE_BUDGET_MB:g} MB a page)")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
