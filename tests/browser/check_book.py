"""Real-browser test of the built book (``make browser-test``; not collected by pytest).

Opens every page of ``_build/html`` in headless Chromium (Debian's ``/usr/bin/chromium``, driven
by the ``playwright`` Python package, which downloads no browser), served by a local
``http.server``, with every request to a non-local host blocked and recorded, in two modes:
``1280`` (a desktop window, 1280x900, scale 1) and ``phone`` (Chrome DevTools mobile emulation as
playwright sets it: 390x844 CSS px, device scale factor 2, ``isMobile``, touch; Chromium then
uses a phone's overlay scrollbars, which are not visible until the reader scrolls). One page is
also opened from ``file://``. Fails on:

- ``math``: unrendered TeX (``\\(``, ``\\[``, ``$$``) left in the visible text, or no MathJax;
- ``macro``: a raw TeX macro (``\\lambda``: a backslash and two letters or more) in the visible
  text outside maths (a link to a heading with maths, a title written in TeX);
- ``tex``: TeX-like text outside the maths, an ASCII subscript or superscript (``Gamma_k``,
  ``x^T``) or a norm's double bar (``||``) in the visible text, code and parameter names
  (``<code>``, literals, ``<pre>``, the catalogue's docstring terms) excepted: to be written as
  maths, code or words (issue 33 took the book from 373 such tokens at 1280 px to 0: the
  reference's docstrings write :math: and ``code``, tables and the claims ledger set their
  symbols as maths and their names as code, :func:`fdi_lib.report.text_pieces`);
- ``zero``: a signed zero (``-0.0``, ``−0``) in the text, code and maths excepted: a glued number
  rounded to zero from below reads as a negative quantity;
- ``pdf``: when a PDF edition sits beside the pages (``fdi-book.pdf``), a page whose download
  menu does not link it;
- ``alt``: an image in the text whose alt text is empty, a file name or path, or raw TeX (it
  must say what the figure shows: its caption);
- ``network``: any attempted request to a non-local host;
- ``image``: an image that fails to load;
- ``console``: any console error or uncaught page error;
- ``caption``: a figure (an image in a notebook output) without a caption;
- ``number``: a figure without a number ("Figure 3.2", so that it can be cited), explorables
  (``.fdi-explorable``) included;
- ``overflow``: a display equation, table or figure cut by the text column or by its scroll box
  (wider than what shows of it). At 1280 px nothing may be cut. On the phone, a cut object must
  sit in a horizontal scroll box that fits the column and shows the book's scroll cue: the
  scroll shadow of ``_static/fdi.css`` (a background with ``background-attachment`` ``local``
  and ``scroll`` layers: a shadow at each edge beyond which there is more, which scrolls away
  with the content);
- ``a11y``: an accessibility violation of impact "critical" or "serious" found by axe-core
  (``--axe``: the npm registry's ``axe.min.js``, which ``make browser-test`` installs under
  ``_build/axe`` and the test injects into the page it checks, never into the built pages), with
  every WCAG 2.x A/AA and best-practice rule and the experimental
  ``label-content-name-mismatch`` (a control whose name leaves out the text it shows). The
  moderate and minor ones are counted per rule in the report (``_build/axe-report.json``), not
  failed;
- ``font``: figure text smaller than 9 CSS px on the phone. Measured, not guessed from the
  screen: ``fdi_lib.plotting`` stores in each PNG (figures and explorable frames) the smallest
  font size of the figure in points and the resolution it was drawn at (``fdi:min_font_pt``,
  ``fdi:dpi``), so that text is ``pt / 72 * dpi`` image pixels high (font size, the em, as
  CSS's ``font-size``), and the page shows the image at ``rendered width / natural width`` CSS px
  per image pixel. The product does not depend on the device scale factor (a 2x PNG has twice
  the pixels and is shown at half as many CSS px per pixel); a figure without the metadata
  fails (size unknown).

Every failure is reported as ``page | viewport | check | element | detail``, followed by counts
per check and page; the report is also written to ``_build/browser-report.txt`` and
``_build/browser-report.json``. Full-page screenshots (the top 15 000 CSS px of a longer page) go to
``_build/screenshots/``, ``<page>-1280.png`` and ``<page>-phone.png``.

Usage: ``python tests/browser/check_book.py [--html _build/html] [--pages glob ...]``.
"""

from __future__ import annotations

import argparse
import base64
import collections
import functools
import http.server
import json
import sys
import threading
import time
import urllib.parse
from pathlib import Path

CHROMIUM = "/usr/bin/chromium"
# As root, in a sandbox with no network: no setuid sandbox, and none of Chromium's own
# background connections (they would be refused, many at a time).
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-dev-shm-usage",
]
VIEWPORTS = {"1280": {"width": 1280, "height": 900}, "phone": {"width": 390, "height": 844}}
#: The two modes, as playwright context options (``device_scale_factor``, ``is_mobile`` and
#: ``has_touch`` are DevTools' device emulation: Emulation.setDeviceMetricsOverride with
#: ``mobile: true`` and Emulation.setTouchEmulationEnabled).
MODES = {
    "1280": {"viewport": VIEWPORTS["1280"], "device_scale_factor": 1},
    "phone": {
        "viewport": VIEWPORTS["phone"],
        "device_scale_factor": 2,
        "is_mobile": True,
        "has_touch": True,
    },
}
MIN_TEXT_CSS_PX = 9.0
MAX_SHOT_PX = 15000
SKIP_DIRS = {"_static", "_sources", "_images", "mathjax", "_sphinx_design_static"}

# Runs in the page: collects the failures visible in the DOM. Returns a list of
# [check, element, detail].
PAGE_CHECKS_JS = r"""
([viewport, pdfBeside]) => {
  const out = [];
  const describe = (el) => {
    const id = el.id || (el.closest('[id]') || {}).id || '';
    const cap = el.closest('figure') && el.closest('figure').querySelector('figcaption');
    let text = (cap ? cap.innerText : (el.innerText || el.getAttribute('src') || '')).trim();
    text = text.replace(/\s+/g, ' ').slice(0, 70);
    return `${el.tagName.toLowerCase()}${id ? '#' + id : ''} "${text}"`;
  };
  const article = document.querySelector('article.bd-article') || document.querySelector('main');
  if (!article) { return [['page', 'document', 'no article element']]; }
  const cs = getComputedStyle(article);
  const colRect = article.getBoundingClientRect();
  const colLeft = colRect.left + parseFloat(cs.paddingLeft);
  const colWidth = article.clientWidth - parseFloat(cs.paddingLeft) - parseFloat(cs.paddingRight);
  const colRight = colLeft + colWidth;

  // 1. unrendered math in visible text (code blocks excluded)
  const walker = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT, {
    acceptNode: (n) => (n.parentElement.closest('pre, code, script, style, mjx-container, textarea, .highlight')
      ? NodeFilter.FILTER_REJECT : NodeFilter.FILTER_ACCEPT)});
  for (let n = walker.nextNode(); n; n = walker.nextNode()) {
    const t = n.nodeValue;
    const m = t.match(/\\\(|\\\[|\$\$/);
    if (m && n.parentElement.offsetParent !== null) {
      const i = t.indexOf(m[0]);
      out.push(['math', describe(n.parentElement), t.slice(Math.max(0, i - 20), i + 50).replace(/\s+/g, ' ')]);
    }
  }
  // 1b. a raw TeX macro (\\lambda) in visible text outside maths: MathJax's output and the
  // unrendered \\( \\) left to check 1 are excluded
  const macro = /\\[a-zA-Z]{2,}/;
  const walker2 = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT, {
    acceptNode: (n) => (n.parentElement.closest('pre, code, script, style, mjx-container, textarea, .highlight, .math')
      ? NodeFilter.FILTER_REJECT : NodeFilter.FILTER_ACCEPT)});
  for (let n = walker2.nextNode(); n; n = walker2.nextNode()) {
    const t = n.nodeValue, m = t.match(macro);
    if (m && !/\\\(|\\\[|\$\$/.test(t) && n.parentElement.offsetParent !== null) {
      const i = t.indexOf(m[0]);
      out.push(['macro', describe(n.parentElement), t.slice(Math.max(0, i - 30), i + 40).replace(/\s+/g, ' ')]);
    }
  }
  // 1c. TeX-like text outside the maths: x_k, x_{k}, x^T, ||x||
  const texLike = /\b[A-Za-z][A-Za-z0-9]*(?:_(?:\{|[A-Za-z0-9])|\^(?:\{|[A-Za-z0-9(]))|\|\|/g;
  const walker3 = document.createTreeWalker(article, NodeFilter.SHOW_TEXT, {
    acceptNode: (n) => (n.parentElement.closest('pre, code, kbd, .literal, script, style, '
                                                 + 'mjx-container, textarea, .highlight, .math, '
                                                 + '.fdi-docstring dt, '
                                                 // the library reference: signatures, parameter
                                                 // names and their types are code
                                                 + '.sig, .classifier, dl.field-list dt')
      ? NodeFilter.FILTER_REJECT : NodeFilter.FILTER_ACCEPT)});
  for (let n = walker3.nextNode(); n; n = walker3.nextNode()) {
    if (n.parentElement.offsetParent === null && !n.parentElement.closest('details')) continue;
    for (const m of n.nodeValue.matchAll(texLike)) {
      const t = n.nodeValue;
      const around = t.slice(Math.max(0, m.index - 25), m.index + 35).replace(/\s+/g, ' ');
      out.push(['tex', describe(n.parentElement), around]);
    }
  }
  // 1e. a signed zero in the prose ("-0.0", "−0"): a glued number rounded to zero from below
  // reads as a negative quantity (code and maths excluded)
  const signedZero = /(^|[^\w.\-−])[-−]0(?:\.0+)?(?![\d.])/;
  const walker4 = document.createTreeWalker(article, NodeFilter.SHOW_TEXT, {
    acceptNode: (n) => (n.parentElement.closest('pre, code, kbd, .literal, script, style, '
                                                 + 'mjx-container, textarea, .highlight, .math')
      ? NodeFilter.FILTER_REJECT : NodeFilter.FILTER_ACCEPT)});
  for (let n = walker4.nextNode(); n; n = walker4.nextNode()) {
    const t = n.nodeValue, m = t.match(signedZero);
    if (m) out.push(['zero', describe(n.parentElement), t.slice(Math.max(0, m.index - 30), m.index + 20).replace(/\s+/g, ' ')]);
  }
  // 1d. the PDF edition, when it is beside the pages, in the download menu (a page without one,
  // the search page, has nothing to link it from)
  const pdfLink = 'a.btn-download-book-pdf-button[href$="fdi-book.pdf"]';
  const hasMenu = document.querySelector('.dropdown-download-buttons .dropdown-menu');
  if (pdfBeside && hasMenu && !document.querySelector(pdfLink)) {
    out.push(['pdf', 'header', 'a PDF edition is beside the pages; the menu does not link it']);
  }
  const mathNodes = document.querySelectorAll('.math, span.math, div.math').length;
  if (mathNodes > 0 && document.querySelectorAll('mjx-container').length === 0) {
    out.push(['math', 'document', `${mathNodes} math elements but MathJax rendered none`]);
  }

  // 2. images that failed to load
  for (const img of document.querySelectorAll('img')) {
    if (!img.complete || img.naturalWidth === 0) {
      out.push(['image', describe(img), `not loaded: ${img.getAttribute('src')}`]);
    }
  }

  // 2b. alt text: every image in the text has one, neither empty, nor a file name or path,
  // nor raw TeX
  for (const img of article.querySelectorAll('img')) {
    const alt = (img.getAttribute('alt') || '').trim();
    const src = img.getAttribute('src') || '';
    if (!alt) out.push(['alt', describe(img), 'image without alt text']);
    else if (alt === src || /^\S*\.(png|jpe?g|gif|svg|webp)$/i.test(alt) || alt.startsWith('data:'))
      out.push(['alt', describe(img), `alt text is a file name: ${alt.slice(0, 60)}`]);
    else if (macro.test(alt)) out.push(['alt', describe(img), `raw TeX in alt text: ${alt.slice(0, 60)}`]);
  }

  // 3. figures without a caption or without a number (an explorable sits in a numbered figure)
  for (const fig of article.querySelectorAll('figure')) {
    const cap = fig.querySelector(':scope > figcaption');
    if (!cap || !cap.innerText.trim()) out.push(['caption', describe(fig), 'figure without caption']);
    else if (!cap.querySelector('.caption-number') && !fig.classList.contains('fdi-explorable')
             && !(fig.parentElement && fig.parentElement.closest('figure')))
      out.push(['number', describe(fig), 'figure without a number (cannot be cited)']);
  }
  for (const el of article.querySelectorAll('.fdi-explorable')) {
    const fig = el.closest('figure');
    const cap = fig && Array.from(fig.querySelectorAll('figcaption')).find(c => c.querySelector('.caption-number'));
    if (!cap) out.push(['number', describe(el), 'explorable not in a numbered figure (cannot be cited)']);
  }
  for (const img of article.querySelectorAll('.cell_output img, .output img')) {
    if (!img.closest('figure')) out.push(['caption', describe(img), 'notebook image not in a captioned figure']);
  }

  // 4. equations, tables and figures cut by the column or by their scroll box
  const scrollsX = (b) => ['auto', 'scroll'].includes(getComputedStyle(b).overflowX);
  // the book's scroll cue (_static/fdi.css): shadows drawn by a background with 'local' and
  // 'scroll' layers, gradients
  const hasCue = (b) => {
    const st = getComputedStyle(b);
    const att = st.backgroundAttachment.split(',').map(x => x.trim());
    return att.includes('local') && att.includes('scroll') && /gradient/.test(st.backgroundImage);
  };
  const items = [];
  for (const el of article.querySelectorAll('mjx-container[display="true"]')) {
    items.push(['equation', el, el.querySelector('mjx-math') || el]);
  }
  for (const el of article.querySelectorAll('table')) items.push(['table', el, el]);
  for (const el of article.querySelectorAll('figure, img')) items.push(['figure', el, el]);
  for (const [kind, el, inner] of items) {
    if (el.offsetParent === null) continue;  // hidden (folded) content
    const r = inner.getBoundingClientRect();
    // what shows of it: the column, narrowed by every clipping or scrolling ancestor
    let left = colLeft, right = colRight, box = null;
    for (let b = kind === 'equation' ? el : el.parentElement; b && b !== article.parentElement; b = b.parentElement) {
      const ox = getComputedStyle(b).overflowX;
      if (ox === 'visible') continue;
      const br = b.getBoundingClientRect();
      left = Math.max(left, br.left + b.clientLeft);
      right = Math.min(right, br.left + b.clientLeft + b.clientWidth);
      if (!box) box = b;  // the innermost box that clips or scrolls it
    }
    if (r.left >= left - 1 && r.right <= right + 1) continue;
    const hidden = Math.round(100 * (r.width - Math.max(0, Math.min(r.right, right) - Math.max(r.left, left))) / r.width);
    const what = `${kind} ${Math.round(r.width)} px wide, ${hidden} % not shown (column ${Math.round(colWidth)} px)`;
    if (viewport === '1280') { out.push(['overflow', describe(el), what]); continue; }
    let why = null;
    if (!box || !scrollsX(box)) why = box ? `clipped by ${box.tagName.toLowerCase()}.${box.className}` : 'no horizontal scroll box';
    else {
      const br = box.getBoundingClientRect();
      if (br.right > colRight + 1 || br.left < colLeft - 1) why = 'scroll box wider than the column';
      else if (!hasCue(box)) why = 'scrolls with no visible cue (no scroll shadow)';
    }
    if (why) out.push(['overflow', describe(el), `${what}: ${why}`]);
  }
  // whole page wider than the viewport (horizontal page scroll)
  if (document.documentElement.scrollWidth > window.innerWidth + 1) {
    out.push(['overflow', 'document', `page ${document.documentElement.scrollWidth} px wide in a ${window.innerWidth} px viewport`]);
  }
  return out;
}
"""

IMAGES_JS = r"""
() => Array.from(document.querySelectorAll('article img')).filter(i => i.offsetParent !== null).map(i => ({
  src: i.currentSrc || i.src, width: i.getBoundingClientRect().width, natural: i.naturalWidth,
  caption: ((i.closest('figure') || {}).innerText || i.getAttribute('alt') || '').trim().replace(/\s+/g, ' ').slice(0, 70),
  inOutput: !!i.closest('.cell_output, .output')
}))
"""

WAIT_MATHJAX_JS = r"""
async () => {
  const t0 = Date.now();
  while (Date.now() - t0 < 20000) {
    if (window.MathJax && window.MathJax.startup && window.MathJax.startup.promise) {
      await window.MathJax.startup.promise; return true;
    }
    if (!document.querySelector('script[src*="mathjax"]')) return true;  // page without math
    await new Promise(r => setTimeout(r, 100));
  }
  return false;
}
"""


def png_text_chunks(data: bytes) -> dict[str, str]:
    """The tEXt chunks of a PNG file."""
    out, pos = {}, 8
    while pos + 8 <= len(data):
        length = int.from_bytes(data[pos : pos + 4], "big")
        kind = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + length]
        if kind == b"tEXt" and b"\0" in body:
            key, value = body.split(b"\0", 1)
            out[key.decode("latin-1")] = value.decode("latin-1")
        if kind == b"IEND":
            break
        pos += 12 + length
    return out


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):  # noqa: D102 - silence the access log
        pass


def serve(root: Path) -> tuple[http.server.ThreadingHTTPServer, str]:
    handler = functools.partial(_QuietHandler, directory=str(root))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server, f"http://127.0.0.1:{server.server_address[1]}/"


def is_local(url: str, base: str) -> bool:
    scheme = urllib.parse.urlsplit(url).scheme
    return url.startswith(base) or scheme in {"file", "data", "blob", "about"}


def font_failures(images: list[dict], html_root: Path, base: str) -> list[tuple[str, str, str]]:
    out = []
    for im in images:
        if not im["inOutput"]:
            continue
        if im["src"].startswith("data:image/png;base64,"):  # frames of fdi_lib.explorables
            data = base64.b64decode(im["src"].split(",", 1)[1])
            meta = png_text_chunks(data)
            element = f'img "{im["caption"]}" (data: PNG)'
            out += _font_failure(element, meta, im)
            continue
        url = urllib.parse.unquote(urllib.parse.urlsplit(im["src"]).path)
        if im["src"].startswith(base):
            path = html_root / urllib.parse.unquote(im["src"][len(base) :]).split("?")[0]
        else:
            path = Path(url)
        element = f'img "{im["caption"]}" ({path.name[:12]})'
        if path.suffix.lower() != ".png" or not path.is_file():
            out.append(("font", element, "not a PNG of the book's house style: text size unknown"))
            continue
        out += _font_failure(element, png_text_chunks(path.read_bytes()), im)
    return out


def _font_failure(element: str, meta: dict[str, str], im: dict) -> list[tuple[str, str, str]]:
    if "fdi:min_font_pt" not in meta or "fdi:dpi" not in meta:
        return [
            (
                "font",
                element,
                "PNG without fdi:min_font_pt/fdi:dpi metadata "
                "(not drawn with fdi_lib.plotting): text size unknown",
            )
        ]
    pt, dpi = float(meta["fdi:min_font_pt"]), float(meta["fdi:dpi"])
    px = pt / 72.0 * dpi * im["width"] / im["natural"]
    if px < MIN_TEXT_CSS_PX:
        return [
            (
                "font",
                element,
                f"smallest text {px:.1f} CSS px < {MIN_TEXT_CSS_PX:g} "
                f"({pt:g} pt at {dpi:g} dpi shown {im['width']:.0f} of "
                f"{im['natural']} px)",
            )
        ]
    return []


#: axe-core's impacts, most severe first, and those that fail the test.
AXE_IMPACTS = ("critical", "serious", "moderate", "minor")
AXE_FAILING = ("critical", "serious")

# Runs in the page after axe.min.js: its violations, one entry per rule and node.
AXE_RUN_JS = r"""
async () => {
  const res = await axe.run(document, {
    runOnly: {type: 'tag',
              values: ['wcag2a', 'wcag2aa', 'wcag21a', 'wcag21aa', 'wcag22aa', 'best-practice']},
    rules: {'label-content-name-mismatch': {enabled: true}},
    resultTypes: ['violations']});
  const out = [];
  for (const v of res.violations) for (const n of v.nodes)
    out.push([v.id, n.impact || v.impact || 'minor', n.target.join(' '),
              (n.failureSummary || '').replace(/\s+/g, ' ').slice(0, 160)]);
  return out;
}
"""


def axe_violations(page, axe_js: Path) -> list[list[str]]:
    """axe-core's violations on ``page``: ``[rule, impact, element, summary]`` per node."""
    page.add_script_tag(path=str(axe_js))
    return page.evaluate(AXE_RUN_JS)


def check_page(
    context,
    url: str,
    page_name: str,
    viewport: str,
    html_root: Path,
    base: str,
    shots: Path | None,
    axe_js: Path | None = None,
    axe_found: list | None = None,
) -> list[tuple[str, str, str]]:
    failures: list[tuple[str, str, str]] = []
    page = context.new_page()
    page.on(
        "console",
        lambda m: (
            failures.append(
                ("console", m.location.get("url", "").rsplit("/", 1)[-1] or "page", m.text[:200])
            )
            if m.type == "error"
            else None
        ),
    )
    page.on("pageerror", lambda e: failures.append(("console", "uncaught", str(e)[:200])))
    page.on(
        "requestfailed",
        lambda r: (
            failures.append(
                ("image", r.url.rsplit("/", 1)[-1][:60], f"request failed: {r.failure}")
            )
            if r.resource_type == "image" and is_local(r.url, base)
            else None
        ),
    )
    page.goto(url, wait_until="load")
    if not page.evaluate(WAIT_MATHJAX_JS):
        failures.append(("math", "document", "MathJax did not finish within 20 s"))
    # load every image (some are lazy) before checking them
    page.evaluate(
        "() => Promise.all(Array.from(document.images).map(i => { i.loading = 'eager';"
        " return i.decode().catch(() => null); }))"
    )
    pdf_beside = (html_root / "fdi-book.pdf").is_file() if base.startswith("http") else False
    failures += [tuple(f) for f in page.evaluate(PAGE_CHECKS_JS, [viewport, pdf_beside])]
    if viewport == "phone":
        failures += font_failures(page.evaluate(IMAGES_JS), html_root, base)
    if axe_js is not None:
        found = axe_violations(page, axe_js)
        if axe_found is not None:
            axe_found.extend([page_name, viewport, *v] for v in found)
        failures += [
            ("a11y", element, f"{rule} ({impact}): {summary}")
            for rule, impact, element, summary in found
            if impact in AXE_FAILING
        ]
    if shots is not None:
        # the whole page, or its top MAX_SHOT_PX (the ledger is some 50 000 px tall on a phone:
        # a full screenshot at scale 2 would be a 100 000 px high image)
        height = page.evaluate("() => document.documentElement.scrollHeight")
        width = page.viewport_size["width"]
        page.screenshot(
            path=str(
                shots / f"{page_name.removesuffix('.html').replace('/', '__')}-{viewport}.png"
            ),
            full_page=True,
            clip={"x": 0, "y": 0, "width": width, "height": min(height, MAX_SHOT_PX)},
        )
    page.close()
    return failures


def built_book(html: Path) -> Path | None:
    """The resolved HTML folder, or ``None`` (with a message) when no book has been built there."""
    root = html.resolve()
    if not (root / "index.html").is_file():
        print(f"no built book at {root}: run `make book` first", file=sys.stderr)
        return None
    return root


def book_pages(root: Path) -> list[str]:
    """Every page of the built book at ``root`` (paths relative to it), but redirects (Jupyter
    Book's root index.html only redirects to the first page) and the asset folders."""
    return sorted(
        p.relative_to(root).as_posix()
        for p in root.rglob("*.html")
        if not SKIP_DIRS & set(p.relative_to(root).parts[:-1])
        and 'http-equiv="Refresh"' not in p.read_text(errors="replace")[:2000]
    )


def axe_summary(found: list[list[str]], n_pages: int) -> str:
    """axe-core's violations counted per viewport and impact, then per rule."""
    lines = [f"axe-core over {n_pages} pages (critical and serious fail the test):"]
    for viewport in MODES:
        counts = collections.Counter(v[3] for v in found if v[1] == viewport)
        lines.append(f"  {viewport}: " + ", ".join(f"{counts.get(i, 0)} {i}" for i in AXE_IMPACTS))
    rules = collections.Counter((v[1], v[3], v[2]) for v in found)
    lines += [
        f"  {vp} {impact} {rule}: {n} nodes" for (vp, impact, rule), n in sorted(rules.items())
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--html", default="_build/html", type=Path)
    parser.add_argument("--screenshots", default="_build/screenshots", type=Path)
    parser.add_argument("--report", default="_build/browser-report", type=Path)
    parser.add_argument("--pages", nargs="*", help="only these pages (paths relative to --html)")
    parser.add_argument("--axe", type=Path, help="axe-core's axe.min.js: check accessibility")
    args = parser.parse_args(argv)
    if args.axe is not None and not args.axe.is_file():
        print(f"no axe-core at {args.axe}: `make browser-test` installs it", file=sys.stderr)
        return 2
    axe_found: list[list[str]] = []
    from playwright.sync_api import sync_playwright

    root = built_book(args.html)
    if root is None:
        return 2
    pages = book_pages(root)
    if args.pages:
        pages = [p for p in pages if p in args.pages]
    args.screenshots.mkdir(parents=True, exist_ok=True)
    server, base = serve(root)
    results: list[tuple[str, str, str, str, str]] = []

    def route(r, page_name: str, viewport: str, local_base: str):
        if is_local(r.request.url, local_base):
            r.continue_()
        else:
            results.append(
                (
                    page_name,
                    viewport,
                    "network",
                    r.request.resource_type,
                    f"blocked request to {r.request.url[:150]}",
                )
            )
            r.abort("blockedbyclient")

    try:
        with sync_playwright() as pw:
            # Playwright hides scrollbars in headless mode by default: show them as a browser
            # would (classic ones at 1280 px, a phone's overlay ones under mobile emulation).
            browser = pw.chromium.launch(
                executable_path=CHROMIUM,
                args=CHROMIUM_ARGS,
                headless=True,
                ignore_default_args=["--hide-scrollbars"],
            )
            for viewport, options in MODES.items():
                for name in pages:
                    context = browser.new_context(**options, service_workers="block")
                    context.route("**/*", lambda r, *_, n=name, v=viewport: route(r, n, v, base))
                    t0 = time.monotonic()
                    try:
                        found = check_page(
                            context,
                            base + name,
                            name,
                            viewport,
                            root,
                            base,
                            args.screenshots,
                            args.axe,
                            axe_found,
                        )
                    except Exception as exc:  # a page that breaks the driver is a failure too
                        found = [("driver", "page", f"{type(exc).__name__}: {exc}"[:200])]
                    results.extend((name, viewport, *f) for f in found)
                    print(
                        f"  {viewport:>5} {name}: {len(found)} failures "
                        f"({time.monotonic() - t0:.1f} s)",
                        file=sys.stderr,
                        flush=True,
                    )
                    context.close()
            # the same book opened from file:// (no server): math and assets must still load
            for name in [p for p in ("book/intro.html", "book/zb2014/glr.html") if p in pages]:
                context = browser.new_context(**MODES["1280"])
                file_base = root.as_uri() + "/"
                context.route(
                    "**/*", lambda r, *_, n=name: route(r, "file://" + n, "1280", file_base)
                )
                for check, element, detail in check_page(
                    context, file_base + name, name, "1280", root, file_base, None
                ):
                    results.append(("file://" + name, "1280", check, element, detail))
                context.close()
            browser.close()
    finally:
        server.shutdown()

    # text sliced in the page may end inside a UTF-16 surrogate pair
    results = [tuple(str(x).encode("utf-8", "replace").decode("utf-8") for x in r) for r in results]
    lines = [" | ".join(r) for r in results]
    counts = collections.Counter((r[0], r[2]) for r in results)
    checks = sorted({c for _, c in counts})
    table = ["", "Failures per page and check:", "page | " + " | ".join(checks)]
    for name in sorted({p for p, _ in counts}):
        table.append(f"{name} | " + " | ".join(str(counts.get((name, c), 0)) for c in checks))
    table.append(
        "total | "
        + " | ".join(str(sum(v for (p, c), v in counts.items() if c == ck)) for ck in checks)
    )
    summary = f"{len(pages)} pages x {len(MODES)} modes (+ file://): {len(results)} failures"
    report = "\n".join(lines + (table if results else []) + ["", summary])
    print(report)
    args.report.parent.mkdir(parents=True, exist_ok=True)
    args.report.with_suffix(".txt").write_text(report + "\n")
    args.report.with_suffix(".json").write_text(
        json.dumps(
            [dict(zip(("page", "viewport", "check", "element", "detail"), r)) for r in results],
            indent=1,
        )
    )
    if args.axe is not None:
        print(axe_summary(axe_found, len(pages)))
        args.report.with_name("axe-report.json").write_text(
            json.dumps(
                [
                    dict(zip(("page", "viewport", "rule", "impact", "element", "summary"), v))
                    for v in axe_found
                ],
                indent=1,
            )
        )
    print(f"screenshots in {args.screenshots}/, report in {args.report}.txt")
    return 1 if results else 0


if __name__ == "__main__":
    sys.exit(main())
