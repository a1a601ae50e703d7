"""Student edition of the book: the same chapters without the exercise solutions.

sphinx-exercise's ``hide_solutions`` option crashes on the gated ``solution-start`` syntax that
the chapters use (the solutions hold executed code cells), so the solutions are removed from the
sources before building instead:

    python tools/student_edition.py build  [--out _build/student] [jupyter-book options...]
    python tools/student_edition.py verify [--out _build/student]

``build`` copies the book's sources to ``OUT/src`` with every solution block cut out
(:func:`fdi_lib.exercises.strip_solutions`), builds that tree with the same Jupyter Book
configuration into ``OUT/html``, writes one unexecuted notebook per chapter (starter cells kept)
into ``OUT/notebooks``, then runs ``verify``. ``verify`` fails (exit status 1) if a page or a
notebook of the student edition, or its PDF (``make student-pdf``), contains a solution: a
solution directive, or any run of eight words that occurs in a solution and nowhere else in the
chapter (:func:`fdi_lib.exercises.solution_fingerprints`).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from fdi_lib.exercises import parse_chapter, solution_fingerprints, strip_solutions, words  # noqa: E402

#: Top-level entries of the repository that are not part of the book's sources.
NOT_SOURCES = {"_build", "fdi_lib", "tests", "benchmarks", "tools", "build"}


def chapters(book: Path) -> list[Path]:
    """The MyST chapters (with a jupytext header) under ``book``."""
    return sorted(p for p in book.rglob("*.md") if p.read_text().startswith("---\njupytext:"))


def copy_sources(out: Path) -> Path:
    """Copy the book's sources to ``out/src`` with the solutions removed; returns ``out/src``."""
    src = out / "src"
    if src.exists():
        shutil.rmtree(src)
    src.mkdir(parents=True)
    for entry in REPO.iterdir():
        if entry.name.startswith(".") or entry.name in NOT_SOURCES or entry.name.endswith(".egg-info"):
            continue
        if entry.is_dir():
            shutil.copytree(entry, src / entry.name,
                            ignore=shutil.ignore_patterns("*.ipynb", ".ipynb_checkpoints", "__pycache__"))
        else:
            shutil.copy2(entry, src / entry.name)
    for path in (src / "book").rglob("*.md"):
        text = path.read_text()
        stripped = strip_solutions(text)
        if stripped != text:
            path.write_text(stripped)
    return src


def write_notebooks(src: Path, out: Path) -> list[Path]:
    """One unexecuted notebook per chapter of the stripped sources, in ``out/notebooks``."""
    import jupytext

    target = out / "notebooks"
    if target.exists():
        shutil.rmtree(target)
    written = []
    for path in chapters(src / "book"):
        nb_path = target / path.relative_to(src / "book").with_suffix(".ipynb")
        nb_path.parent.mkdir(parents=True, exist_ok=True)
        jupytext.write(jupytext.read(path), nb_path)
        written.append(nb_path)
    return written


def build(out: Path, extra: list[str]) -> None:
    src = copy_sources(out)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])))
    work = out / "build"
    cmd = [str(Path(sys.executable).with_name("jupyter-book")), "build", str(src), "--path-output", str(work),
           "--builder", "html", *extra]
    print("+", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True, env=env)
    html = out / "html"
    if html.exists():
        shutil.rmtree(html)
    shutil.move(str(work / "_build" / "html"), str(html))
    notebooks = write_notebooks(src, out)
    print(f"student book: {html / 'index.html'}; {len(notebooks)} notebooks in {out / 'notebooks'}")


def _page_text(path: Path) -> tuple[str, bool]:
    """Visible text of an HTML page and whether it has a solution admonition."""
    from bs4 import BeautifulSoup

    soup = BeautifulSoup(path.read_text(errors="replace"), "html.parser")
    has_solution = bool(soup.select(".solution"))
    for tag in soup(["script", "style"]):
        tag.decompose()
    return soup.get_text(" "), has_solution


def _notebook_text(path: Path) -> tuple[str, bool]:
    import nbformat

    nb = nbformat.read(path, as_version=4)
    text = "\n".join(cell.source for cell in nb.cells)
    return text, ("solution-start" in text or "{solution}" in text)


def _pdf_text(path: Path) -> tuple[str, bool]:
    """Text of a PDF (``pdftotext``, poppler-utils); a solution shows as its text only."""
    return subprocess.run(["pdftotext", "-enc", "UTF-8", str(path), "-"], capture_output=True, text=True,
                          check=True).stdout, False


def verify(out: Path) -> list[str]:
    """Problems found in the student edition under ``out`` (empty when it has no solution text),
    its PDF (``out/pdf``, ``make student-pdf``) included when built."""
    problems = []
    fingerprints, n_exercises, pages = set(), 0, {}
    for path in chapters(REPO / "book"):
        full = path.read_text()
        n_exercises += len(parse_chapter(full))
        fingerprints |= solution_fingerprints(full, strip_solutions(full))
        pages[path.relative_to(REPO / "book").with_suffix("").as_posix()] = path
    html_files = sorted((out / "html").rglob("*.html"))
    notebooks = sorted((out / "notebooks").rglob("*.ipynb"))
    if not html_files:
        problems.append(f"no HTML pages under {out / 'html'}")
    if len(notebooks) != len(pages):
        problems.append(f"expected {len(pages)} notebooks under {out / 'notebooks'}, found {len(notebooks)}")
    seen_exercises = 0
    pdfs = sorted((out / "pdf").glob("*.pdf"))
    for path, reader in ([(p, _page_text) for p in html_files] + [(p, _notebook_text) for p in notebooks]
                         + [(p, _pdf_text) for p in pdfs]):
        text, has_solution = reader(path)
        if has_solution:
            problems.append(f"{path}: contains a solution directive")
        ws = words(text)
        leaked = {tuple(ws[i:i + 8]) for i in range(len(ws) - 7)} & fingerprints
        if leaked:
            problems.append(f"{path}: {len(leaked)} runs of solution text, e.g. {' '.join(sorted(leaked)[0])!r}")
        if path.suffix == ".ipynb":
            seen_exercises += text.count("{exercise-start}")
    if seen_exercises != n_exercises:
        problems.append(f"the notebooks hold {seen_exercises} exercises, the chapters {n_exercises}")
    return problems


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("command", choices=["build", "verify"])
    parser.add_argument("--out", type=Path, default=REPO / "_build" / "student")
    args, extra = parser.parse_known_args(argv)
    out = args.out.resolve()
    if args.command == "build":
        build(out, extra)
    problems = verify(out)
    for p in problems:
        print("student edition:", p, file=sys.stderr)
    if not problems:
        pdf = f", {out / 'pdf'}" if any((out / "pdf").glob("*.pdf")) else ""
        print(f"student edition verified: no solution text in {out / 'html'}{pdf} and {out / 'notebooks'}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
