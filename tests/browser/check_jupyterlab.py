"""Real-browser test of the live notebooks (``make browser-test``; not collected by pytest).

The README's live path: ``make notebooks`` writes every chapter as a notebook in Markdown that
Jupyter renders (``tools/notebook_markdown.py``: roles and directives resolved, the book's macros
defined), and JupyterLab opens them. This test starts the environment's JupyterLab headless on
the loopback interface (a random port and token, no browser, no update or news check), opens
each given notebook in headless Chromium (``check_book.py``'s launch, every request to another
host blocked), alone (a reset workspace, kept in the test's temporary settings: JupyterLab restores
the last workspace, which made the check of the k-th notebook draw the k-1 before it too, start
their kernels and report their problems under its name), waits for its Markdown cells and their
maths to render (the notebook drawn whole: ``windowingMode`` none), shuts its kernel down, and
fails on what a reader would see of MyST that JupyterLab cannot read:

- ``role``: a raw role in the rendered text (``{numref}`` before ``fig-x`` in code);
- ``directive``: a directive fence (```` ```{prf:proposition} ````: a code block of that
  "language", or ``:::{admonition}`` as text);
- ``macro``: maths that MathJax could not typeset (an undefined macro such as ``\\T``, which
  MathJax draws in red, or an error), or TeX left raw outside maths (``\\lambda``);
- ``render``: a notebook with no rendered Markdown cell, or maths that never typeset.

Usage: ``python tests/browser/check_jupyterlab.py [--notebooks _build/notebooks] [glob ...]``
(default: every chapter notebook).
"""

from __future__ import annotations

import argparse
import json
import os
import secrets
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from check_book import CHROMIUM, CHROMIUM_ARGS, VIEWPORTS  # noqa: E402

# Runs in JupyterLab's page: the problems visible in the notebook's rendered Markdown.
RENDERED_JS = r"""
() => {
  const out = [];
  const cells = document.querySelectorAll('.jp-MarkdownCell .jp-RenderedMarkdown');
  if (cells.length === 0) out.push(['render', 'notebook', 'no rendered Markdown cell']);
  for (const cell of cells) {
    // MathJax draws an undefined macro as red text (its noundefined extension) or an error
    for (const e of cell.querySelectorAll('mjx-merror, mtext[mathcolor="red"]'))
      out.push(['macro', 'maths', `undefined in MathJax: ${e.textContent.slice(0, 60)}`]);
    // a fence's directive name becomes the language of a code block
    for (const e of cell.querySelectorAll('pre > code[class*="language-{"]'))
      out.push(['directive', 'code block', e.className.replace('language-', '')]);
    const walker = document.createTreeWalker(cell, NodeFilter.SHOW_TEXT, {acceptNode: (n) =>
      n.parentElement.closest('pre, code, mjx-container, script, style')
        ? NodeFilter.FILTER_REJECT : NodeFilter.FILTER_ACCEPT});
    for (let n = walker.nextNode(); n; n = walker.nextNode()) {
      const t = n.nodeValue;
      for (const [kind, re] of [['role', /\{[a-z][\w:-]*\}/], ['directive', /(```|:::)\{[\w:-]+\}/],
                                ['macro', /\\[a-zA-Z]{2,}|\\[TRE]\b/]]) {
        const m = t.match(re);
        if (m) out.push([kind, 'text',
                         t.slice(Math.max(0, m.index - 30), m.index + 40).replace(/\s+/g, ' ')]);
      }
    }
  }
  return out;
}
"""

#: JupyterLab settings for the test: the whole notebook drawn (not only the cells in view).
SETTINGS = {
    "@jupyterlab/notebook-extension/tracker.jupyterlab-settings": {"windowingMode": "none"},
    "@jupyterlab/apputils-extension/notification.jupyterlab-settings": {
        "fetchNews": "false",
        "checkForUpdates": False,
    },
}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_lab(root: Path, settings: Path) -> tuple[subprocess.Popen, str, str]:
    """JupyterLab serving ``root`` on 127.0.0.1 (a free port, a random token); returns the
    process, its base URL and its token once it answers."""
    for name, value in SETTINGS.items():
        path = settings / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(value))
    port, token = free_port(), secrets.token_hex(16)
    lab = Path(sys.executable).with_name("jupyter-lab")
    env = dict(
        os.environ,
        JUPYTERLAB_SETTINGS_DIR=str(settings),
        JUPYTERLAB_WORKSPACES_DIR=str(settings / "workspaces"),
    )
    log = (settings / "lab.log").open("w")
    proc = subprocess.Popen(  # as root in CI; no extension manager (it asks PyPI)
        [
            str(lab),
            "--no-browser",
            "--allow-root",
            "--ServerApp.ip=127.0.0.1",
            f"--ServerApp.port={port}",
            "--ServerApp.port_retries=0",
            f"--IdentityProvider.token={token}",
            f"--ServerApp.root_dir={root}",
            "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate",
            "--LabApp.extension_manager=readonly",
        ],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=log,
    )
    base = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            log_text = (settings / "lab.log").read_text(errors="replace")
            raise SystemExit(f"JupyterLab exited: {log_text[-2000:]}")
        try:
            urllib.request.urlopen(f"{base}/api/status?token={token}", timeout=2)
            return proc, base, token
        except OSError:
            time.sleep(0.5)
    proc.terminate()
    raise SystemExit("JupyterLab did not answer within 120 s")


def check_notebook(context, base: str, token: str, name: str) -> list[tuple[str, str, str]]:
    page = context.new_page()
    page.goto(f"{base}/lab/tree/{name}?reset&token={token}", wait_until="load")
    page.wait_for_selector(
        ".jp-MarkdownCell .jp-RenderedMarkdown", state="attached", timeout=120_000
    )
    # every cell drawn and its maths typeset: the count of MathJax's containers stops growing
    seen, still = -1, 0
    for _ in range(120):
        n = page.evaluate(
            "() => document.querySelectorAll('.jp-MarkdownCell mjx-container').length"
        )
        still = still + 1 if n == seen else 0
        seen = n
        if still >= 4:
            break
        page.wait_for_timeout(500)
    found = [tuple(f) for f in page.evaluate(RENDERED_JS)]
    tex = page.evaluate(
        "() => Array.from(document.querySelectorAll("
        "'.jp-MarkdownCell .jp-RenderedMarkdown'))"
        ".some(c => /\\$[^$]+\\$/.test(c.innerText))"
    )
    if seen == 0 and tex:
        found.append(("render", "maths", "the notebook's maths never typeset"))
    page.close()
    shut_down_sessions(base, token)
    return found


def shut_down_sessions(base: str, token: str) -> None:
    """Shut down every session (and its kernel) of the server: opening a notebook started one."""
    headers = {"Authorization": f"token {token}"}
    with urllib.request.urlopen(
        urllib.request.Request(f"{base}/api/sessions", headers=headers)
    ) as r:
        sessions = json.load(r)
    for session in sessions:
        req = urllib.request.Request(
            f"{base}/api/sessions/{session['id']}", headers=headers, method="DELETE"
        )
        urllib.request.urlopen(req).close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--notebooks", default="_build/notebooks", type=Path)
    parser.add_argument("names", nargs="*", help="notebooks relative to --notebooks (default: all)")
    args = parser.parse_args(argv)
    from playwright.sync_api import sync_playwright

    root = args.notebooks.resolve()
    names = args.names or sorted(
        p.relative_to(root).as_posix()
        for p in root.rglob("*.ipynb")
        if ".ipynb_checkpoints" not in p.parts
    )
    if not names:
        print(f"no notebooks under {root}: run `make notebooks` first", file=sys.stderr)
        return 2
    results: list[tuple[str, str, str, str]] = []
    with tempfile.TemporaryDirectory() as settings:
        proc, base, token = start_lab(root, Path(settings))
        try:
            with sync_playwright() as pw:
                browser = pw.chromium.launch(
                    executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True
                )
                context = browser.new_context(viewport=VIEWPORTS["1280"], service_workers="block")
                blocked = []

                def route(r):
                    if r.request.url.startswith((base, "data:")):
                        r.continue_()
                    else:
                        blocked.append(r.request.url)
                        r.abort("blockedbyclient")

                context.route("**/*", route)
                for name in names:
                    t0 = time.monotonic()
                    try:
                        found = check_notebook(context, base, token, name)
                    except Exception as exc:  # a notebook that breaks the driver is a failure too
                        found = [("driver", "page", f"{type(exc).__name__}: {exc}"[:200])]
                    results += [(name, *f) for f in found]
                    print(
                        f"  {name}: {len(found)} failures ({time.monotonic() - t0:.1f} s)",
                        file=sys.stderr,
                        flush=True,
                    )
                results += [
                    ("jupyterlab", "network", "request", f"blocked {u[:150]}") for u in blocked
                ]
                browser.close()
        finally:
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:  # a server slow to stop (a loaded machine, seen
                proc.kill()  # with every notebook checked) says nothing about the notebooks
                proc.wait()
    for r in results:
        print(" | ".join(map(str, r)))
    print(f"{len(names)} notebooks in JupyterLab: {len(results)} failures")
    return 1 if results else 0


if __name__ == "__main__":
    sys.exit(main())
