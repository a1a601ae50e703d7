"""Post-build check: every command printed by the built catalogue recomputes what the book showed.

Run after ``make book`` (it needs the built page and the build's results cache)::

    .venv/bin/python tools/check_catalogue.py --html _build/html --cache _build/results-cache

For each command of ``book/reproductions.html`` (the text a reader copies), it fails when

- ``not run``: the chapters never ran the reproduction at the command's settings (no entry of
  the build's results cache has this id, seed, trial count and options: the command is not
  what the book showed);
- ``differs``: the command, run afresh as a subprocess (``python -m fdi_lib ...``, no cache),
  prints a JSON ``headline`` or ``settings`` other than those of the chapter's result (but for
  the reproduction's ``timed_keys``, wall times of this machine);
- ``failed``: the command exits with an error;
- ``missing``: a registered reproduction has no command on the page.

The commands run at the book's trial counts (the papers' for Monte Carlo figures), so this
takes about as long as the reproductions of a book build; ``--jobs`` runs several at once.
"""

from __future__ import annotations

import argparse
import html
import json
import os
import re
import shlex
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fdi_lib.reproduce.cli import _parser  # noqa: E402
from fdi_lib.reproduce.registry import CACHE_ENV, cached_run, get, list_reproductions  # noqa: E402

# the command of each entry: the literal after the bold "Command" label (the page's introduction
# shows other, generic, commands)
_CODE = re.compile(r"<strong>Command[^<]*</strong>\s*<code[^>]*>(.*?)</code>", re.S)


def page_commands(page: str) -> list[list[str]]:
    """The ``python -m fdi_lib reproduce ...`` command of each entry of a catalogue page (HTML),
    as argv lists."""
    out = []
    for m in _CODE.finditer(page):
        text = html.unescape(re.sub(r"<[^>]+>", "", m.group(1))).replace("\xa0", " ")
        words = shlex.split(text)
        if words[:4] == ["python", "-m", "fdi_lib", "reproduce"]:
            out.append(words[3:])
    return out


def check_command(argv: list[str], cache: Path) -> tuple[str, str, str]:
    """(id, status, detail) of one command: ``ok``, ``not run``, ``differs`` or ``failed``."""
    args = _parser().parse_args(argv)
    os.environ[CACHE_ENV] = str(cache)
    book = cached_run(args.id, seed=args.seed, trials=args.trials)
    if book is None:
        seed = "the default seed" if args.seed is None else f"seed {args.seed}"
        trials = "" if args.trials is None else f", {args.trials} trials"
        return (
            args.id,
            "not run",
            f"no result of the build at {seed}{trials}: the chapters ran other settings",
        )
    env = {k: v for k, v in os.environ.items() if k != CACHE_ENV}
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    proc = subprocess.run(
        [sys.executable, "-m", "fdi_lib", *argv], capture_output=True, text=True, env=env, cwd=ROOT
    )
    if proc.returncode != 0:
        return args.id, "failed", proc.stderr.strip()[-300:]
    got = json.loads(proc.stdout)
    want = json.loads(book.to_json())
    for timed in get(args.id).timed_keys:  # wall times of this machine: not reproducible
        got["headline"].pop(timed), want["headline"].pop(timed)
    for key in ("headline", "settings"):
        if got[key] != want[key]:
            diff = [
                k for k in set(got[key]) | set(want[key]) if got[key].get(k) != want[key].get(k)
            ]
            return args.id, "differs", f"{key} keys {sorted(diff)} differ from the chapter's result"
    return args.id, "ok", ""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--html", default=ROOT / "_build" / "html", type=Path)
    parser.add_argument("--cache", default=ROOT / "_build" / "results-cache", type=Path)
    parser.add_argument("--jobs", default=1, type=int, help="commands run at once (default 1)")
    args = parser.parse_args(argv)
    page = args.html / "book" / "reproductions.html"
    if not page.is_file() or not args.cache.is_dir():
        print(
            f"error: no built catalogue {page} or results cache {args.cache}: run make book first",
            file=sys.stderr,
        )
        return 2
    commands = page_commands(page.read_text())
    ids = [c[1] for c in commands]
    results = [
        (rid, "missing", "no command on the page")
        for rid in sorted({r.id for r in list_reproductions()} - set(ids))
    ]
    results += [
        (rid, "duplicate", f"{ids.count(rid)} commands")
        for rid in sorted(set(ids))
        if ids.count(rid) > 1
    ]
    with ThreadPoolExecutor(max(1, args.jobs)) as pool:
        for rid, status, detail in pool.map(lambda c: check_command(c, args.cache), commands):
            print(f"  {rid:<22} {status}{': ' + detail if detail else ''}", flush=True)
            if status != "ok":
                results.append((rid, status, detail))
    print(f"{len(commands)} catalogue commands: {len(results)} failures")
    return 1 if results else 0


if __name__ == "__main__":
    sys.exit(main())
