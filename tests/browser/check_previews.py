"""Hover previews of the built book in a real browser (``make browser-test``; not collected by
pytest).

On a chapter and on a page without maths of its own, opened in headless Chromium as
``check_book.py`` opens them (local server, every request to another host blocked and
reported), the mouse hovers over one reference of each kind the page's previews hold (a figure,
an equation, a proposition, a citation: the kind of a preview is what its HTML is, read from the
page's sphinx-tippy data ``selector_to_html``), and each preview must show, with text, its maths
typeset by MathJax (no TeX left) and its image loaded. Fails on:

- ``missing``: a page without a preview of a kind it must have (see :data:`PAGES`), or without
  a preview with maths where it must have one, or whose page-specific previews script did not
  load;
- ``preview``: hovering shows no preview, or an empty one;
- ``math``: a preview with maths that MathJax did not typeset within 20 s, or TeX left in it;
- ``image``: an image of a preview that does not load;
- ``network``: a request to another host (tippy.js and Popper are served by the book);
- ``console``: a console error or an uncaught page error.

Usage: ``python tests/browser/check_previews.py [--html _build/html]``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from check_book import CHROMIUM, CHROMIUM_ARGS, VIEWPORTS, built_book, is_local, serve  # noqa: E402

#: Pages checked and the kinds of preview each must show. The ledger has no maths of its own: its
#: previews of figures with maths in their captions load MathJax on demand (``maths``: a preview
#: with typeset maths is required). No chapter refers to a labelled equation yet (no ``{eq}``):
#: equation previews are checked in the build of tests/test_book_assets.py.
PAGES = {
    "book/zb2014/glr.html": {"kinds": ("figure", "proposition", "citation"), "maths": True},
    "book/zz-ledger.html": {"kinds": ("figure",), "maths": True},
}

# In the page: one visible link in the article per kind of preview (the first), marked with
# data-fdi-preview="kind" for the mouse; returns {kind: selector}.
MARK_LINKS_JS = r"""
() => {
  if (typeof selector_to_html === 'undefined') return null;
  const kindOf = (html) => {
    const el = new DOMParser().parseFromString(html, 'text/html').body.firstElementChild;
    if (!el) return 'other';
    if (el.matches('figure')) return 'figure';
    if (el.matches('div.math')) return 'equation';
    if (el.matches('div.citation')) return 'citation';
    if (el.matches('div.proof, div.admonition.proposition, div.admonition.theorem, div.admonition.lemma')) return 'proposition';
    return 'other';
  };
  const found = {};
  // previews with maths first: the check covers their typesetting where a page has any
  const entries = Object.entries(selector_to_html);
  const math = (html) => (/class="[^"]*\bmath\b/.test(html) ? 0 : 1);
  entries.sort((a, b) => math(a[1]) - math(b[1]));
  for (const [selector, html] of entries) {
    const kind = kindOf(html);
    if (found[kind]) continue;
    const link = Array.from(document.querySelectorAll('article.bd-article ' + selector))
      .find((a) => a.offsetParent !== null && a.getBoundingClientRect().width > 0);
    if (!link) continue;
    link.setAttribute('data-fdi-preview', kind);
    found[kind] = selector;
  }
  return found;
}
"""

# In the page: the shown preview's state once its maths is typeset (or 20 s have passed).
PREVIEW_STATE_JS = r"""
async () => {
  const t0 = Date.now();
  let box = null;
  while (Date.now() - t0 < 20000) {
    box = document.querySelector('[data-tippy-root] .tippy-box[data-state="visible"]');
    if (box) {
      const content = box.querySelector('.tippy-content');
      const hasMath = !!content.querySelector('.math');
      const typeset = content.querySelectorAll('mjx-container').length > 0;
      const imgs = Array.from(content.querySelectorAll('img'));
      const imgsDone = imgs.every((i) => i.complete);
      if ((!hasMath || typeset) && imgsDone) {
        return {text: content.innerText.trim().slice(0, 80), hasMath, typeset,
                tex: /\\\(|\\\[|\$\$/.test(content.innerText),
                badImages: imgs.filter((i) => i.naturalWidth === 0).map((i) => i.getAttribute('src').slice(0, 60))};
      }
    }
    await new Promise((r) => setTimeout(r, 100));
  }
  return box ? {text: box.innerText.trim().slice(0, 80), hasMath: true, typeset: false, tex: true, badImages: []}
             : null;
}
"""


def check_page(
    browser, base: str, name: str, kinds: tuple[str, ...], maths: bool
) -> list[tuple[str, str, str]]:
    failures: list[tuple[str, str, str]] = []
    context = browser.new_context(
        viewport=VIEWPORTS["1280"], device_scale_factor=1, service_workers="block"
    )

    def route(r):
        if is_local(r.request.url, base):
            r.continue_()
        else:
            failures.append(
                ("network", r.request.resource_type, f"blocked request to {r.request.url[:150]}")
            )
            r.abort("blockedbyclient")

    context.route("**/*", route)
    page = context.new_page()
    page.on(
        "console",
        lambda m: failures.append(("console", "page", m.text[:200])) if m.type == "error" else None,
    )
    page.on("pageerror", lambda e: failures.append(("console", "uncaught", str(e)[:200])))
    page.goto(base + name, wait_until="load")
    marked = page.evaluate(MARK_LINKS_JS)
    if marked is None:
        failures.append(
            ("missing", "page", "no previews data (sphinx-tippy's script for this page)")
        )
        context.close()
        return failures
    typeset = 0
    for kind in kinds:
        if kind not in marked:
            failures.append(("missing", kind, f"no visible link with a {kind} preview"))
            continue
        page.mouse.move(0, 0)
        page.hover(f'[data-fdi-preview="{kind}"]')
        state = page.evaluate(PREVIEW_STATE_JS)
        where = f"{kind} {marked[kind][:70]}"
        if not state or not state["text"]:
            failures.append(
                ("preview", where, "no preview shown" if not state else "empty preview")
            )
            continue
        if state["hasMath"] and not state["typeset"]:
            failures.append(("math", where, "maths not typeset within 20 s"))
        elif state["tex"]:
            failures.append(("math", where, f"TeX left in the preview: {state['text']}"))
        else:
            typeset += state["hasMath"]
        for src in state["badImages"]:
            failures.append(("image", where, f"not loaded: {src}"))
        print(
            f"  {name}: {kind} preview ok{' (maths typeset)' if state['hasMath'] else ''}: "
            f"{state['text'][:60]!r}",
            file=sys.stderr,
        )
    if maths and not typeset:
        failures.append(("missing", "maths", "no preview with maths typeset"))
    context.close()
    return failures


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--html", default="_build/html", type=Path)
    args = parser.parse_args(argv)
    from playwright.sync_api import sync_playwright

    root = built_book(args.html)
    if root is None:
        return 2
    server, base = serve(root)
    results = []
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(
                executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True
            )
            for name, spec in PAGES.items():
                results += [
                    (name, *f)
                    for f in check_page(browser, base, name, spec["kinds"], spec["maths"])
                ]
            browser.close()
    finally:
        server.shutdown()
    for r in results:
        print(" | ".join(r))
    print(f"previews on {len(PAGES)} pages: {len(results)} failures")
    return 1 if results else 0


if __name__ == "__main__":
    sys.exit(main())
