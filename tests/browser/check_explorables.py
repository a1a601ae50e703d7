"""Real-browser test of the book's kernel-free explorables (``make browser-test``; not pytest).

On every page of ``_build/html`` that has an explorable (``.fdi-explorable``, written by
:mod:`fdi_lib.explorables`), in headless Chromium with every request to a non-local host
blocked (the launch and the blocking are those of ``check_book.py``), moves each slider of each
explorable to each of its values in turn and fails when:

- ``pixels``: the figure's pixels (the image drawn to a canvas) do not change on a move, or
  the frame shown is not the one the slider positions index;
- ``response``: the image takes 50 ms or more from the ``input`` event to decoded pixels (best
  of three repetitions of the move);
- ``aria``: after a move, a slider does not announce the value it shows (its ``aria-valuetext``
  differs from its visible value), the image's alt text does not name every slider's value, or
  the polite live region (``aria-live``) does not announce the new values;
- ``network``: the page tried to reach another host; ``console``: any console or page error;
- ``missing``: a page that should have one has no explorable (``--expect``).

Usage: ``python tests/browser/check_explorables.py [--html _build/html]``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from check_book import CHROMIUM, CHROMIUM_ARGS, VIEWPORTS, built_book, is_local, serve  # noqa: E402

MAX_RESPONSE_MS = 50.0
# The chapters with an Explore section (issue 10); each must have at least one explorable.
EXPECTED = [
    "book/zb2014/signature.html",
    "book/zb2014/glr.html",
    "book/zb2014/pipeline.html",
    "book/zhang2021/sparse.html",
    "book/bz/parametric-nonparametric.html",
    "book/rosa2013/svo.html",
]

# Runs in the page: for explorable `e`, slider `j`, moves the slider through all its values
# (from the last back to the first, then to its start value) and reports, per move, the
# response time, whether the pixels changed, and whether the shown frame is the indexed one.
MOVE_JS = r"""
async ([e, j]) => {
  const root = document.querySelectorAll('.fdi-explorable')[e];
  const img = root.querySelector('img');
  const ins = Array.from(root.querySelectorAll('input[type=range]'));
  const input = ins[j];
  const canvas = document.createElement('canvas');
  const pixels = () => {
    canvas.width = img.naturalWidth; canvas.height = img.naturalHeight;
    const ctx = canvas.getContext('2d'); ctx.drawImage(img, 0, 0);
    const d = ctx.getImageData(0, 0, canvas.width, canvas.height).data;
    let h = 0; for (let i = 0; i < d.length; i += 4) h = (h * 31 + d[i] + 7 * d[i + 1] + 13 * d[i + 2]) >>> 0;
    return h;
  };
  await img.decode();
  const out = [], start = Number(input.value), n = Number(input.max) + 1;
  const order = []; for (let v = n - 1; v >= 0; v--) order.push(v); order.push(start);
  let before = pixels(), prev = start;
  for (const v of order) {
    if (v === prev) continue;
    // best of three (prev -> v, back, again): one scheduling hiccup of a loaded machine is not
    // the page's response time, a slow swap or decode repeats
    let ms = Infinity;
    for (let rep = 0; rep < 3; rep++) {
      if (rep > 0) { input.value = String(prev); input.dispatchEvent(new Event('input', {bubbles: true})); await img.decode(); }
      const t0 = performance.now();
      input.value = String(v);
      input.dispatchEvent(new Event('input', {bubbles: true}));
      await img.decode();
      ms = Math.min(ms, performance.now() - t0);
    }
    const after = pixels();
    const live = root.querySelector('[aria-live]');
    out.push({from: prev, to: v, ms: ms, changed: after !== before, frame: Number(root.dataset.frame),
              positions: ins.map(x => Number(x.value)),
              shown: ins.map(x => x.nextElementSibling.textContent),
              valuetext: ins.map(x => x.getAttribute('aria-valuetext')),
              alt: img.alt,
              live: live ? live.getAttribute('aria-live') + ': ' + live.textContent : ''});
    before = after; prev = v;
  }
  return out;
}
"""

COUNT_JS = r"""
() => Array.from(document.querySelectorAll('.fdi-explorable')).map(r => ({
  sliders: r.querySelectorAll('input[type=range]').length,
  sizes: Array.from(r.querySelectorAll('input[type=range]')).map(x => Number(x.max) + 1),
  bytes: r.outerHTML.length + (r.nextElementSibling ? r.nextElementSibling.outerHTML.length : 0),
  caption: ((r.closest('figure') || r).querySelector('figcaption') || {innerText: ''}).innerText.slice(0, 60)}))
"""


def aria_problems(move: dict) -> list[str]:
    """What a screen reader would get wrong after a slider move (see ``aria`` above)."""
    out = []
    for shown, said in zip(move["shown"], move["valuetext"]):
        if said != shown:
            out.append(f"slider announces {said!r}, shows {shown!r}")
        if f"= {shown}" not in move["alt"]:
            out.append(f"alt text does not name the value {shown!r}: {move['alt'][-80:]!r}")
        if not move["live"].startswith("polite: ") or f"= {shown}" not in move["live"]:
            out.append(f"no polite announcement of the value {shown!r}: {move['live'][-80:]!r}")
    return out


def check_page(context, url: str) -> tuple[list[tuple[str, str, str]], list[str]]:
    failures: list[tuple[str, str, str]] = []
    notes: list[str] = []
    page = context.new_page()
    page.on(
        "console",
        lambda m: failures.append(("console", "page", m.text[:200])) if m.type == "error" else None,
    )
    page.on("pageerror", lambda e: failures.append(("console", "uncaught", str(e)[:200])))
    page.goto(url, wait_until="load")
    for e, info in enumerate(page.evaluate(COUNT_JS)):
        name = f'explorable {e} "{info["caption"]}"'
        strides = [1] * len(info["sizes"])
        for i in range(len(info["sizes"]) - 2, -1, -1):
            strides[i] = strides[i + 1] * info["sizes"][i + 1]
        times = []
        for j in range(info["sliders"]):
            for move in page.evaluate(MOVE_JS, [e, j]):
                times.append(move["ms"])
                where = f"{name} slider {j} {move['from']} -> {move['to']}"
                if not move["changed"]:
                    failures.append(("pixels", where, "figure pixels unchanged"))
                expected = sum(s * p for s, p in zip(strides, move["positions"]))
                if move["frame"] != expected:
                    failures.append(
                        ("pixels", where, f"frame {move['frame']} shown, {expected} indexed")
                    )
                failures += [("aria", where, problem) for problem in aria_problems(move)]
                if move["ms"] >= MAX_RESPONSE_MS:
                    failures.append(
                        ("response", where, f"{move['ms']:.1f} ms >= {MAX_RESPONSE_MS:g} ms")
                    )
        notes.append(
            f"{name}: {info['sliders']} sliders {info['sizes']}, {info['bytes'] / 1e6:.2f} MB, "
            f"{len(times)} moves, response max {max(times, default=0):.1f} ms, "
            f"median {sorted(times)[len(times) // 2] if times else 0:.1f} ms"
        )
    page.close()
    return failures, notes


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--html", default="_build/html", type=Path)
    parser.add_argument(
        "--expect",
        nargs="*",
        default=EXPECTED,
        help="pages that must have an explorable (paths relative to --html)",
    )
    args = parser.parse_args(argv)
    from playwright.sync_api import sync_playwright

    root = built_book(args.html)
    if root is None:
        return 2
    pages = sorted(
        p.relative_to(root).as_posix()
        for p in root.rglob("*.html")
        if "fdi-explorable" in p.read_text(errors="replace")
    )
    results = [(p, "missing", "page", "no explorable") for p in args.expect if p not in pages]
    server, base = serve(root)

    def route(r, name: str):
        if is_local(r.request.url, base):
            r.continue_()
        else:
            results.append(
                (name, "network", r.request.resource_type, f"blocked {r.request.url[:150]}")
            )
            r.abort("blockedbyclient")

    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(
                executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True
            )
            for name in pages:
                context = browser.new_context(
                    viewport=VIEWPORTS["1280"], device_scale_factor=1, service_workers="block"
                )
                context.route("**/*", lambda r, *_, n=name: route(r, n))
                try:
                    found, notes = check_page(context, base + name)
                except Exception as exc:  # a page that breaks the driver is a failure too
                    found, notes = [("driver", "page", f"{type(exc).__name__}: {exc}"[:200])], []
                results.extend((name, *f) for f in found)
                for note in notes:
                    print(f"  {name}: {note}")
                context.close()
            browser.close()
    finally:
        server.shutdown()
    for r in results:
        print(" | ".join(map(str, r)))
    print(f"{len(pages)} pages with explorables: {len(results)} failures")
    return 1 if results else 0


if __name__ == "__main__":
    sys.exit(main())
