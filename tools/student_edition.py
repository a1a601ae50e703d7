"""Student edition of the book: the same chapters without the exercise solutions.

sphinx-exercise's ``hide_solutions`` option crashes on the gated ``solution-start`` syntax that
the chapters use (the solutions hold executed code cells), so the solutions are removed from the
sources before building instead:

    python tools/student_edition.py build  [--out _build/student] [jupyter-book options...]
    python tools/student_edition.py verify [--out _build/student]

``build`` copies the book's sources to ``OUT/src`` with every solution block cut out
(:func:`fdi_lib.exercises.strip_solutions`), builds that tree with the same Jupyter Book
configuration into ``OUT/html``, writes one unexecuted notebook per chapter (starter cells kept)
into ``OUT/notebooks`` (in Markdown that Jupyter renders, ``tools/notebook_markdown.py``), then
runs ``verify``.

``verify`` is the leak scan: it fails (exit status 1) if a page (with the page sources and ".ipynb"
downloads of ``OUT/html``), a notebook or the student wheel (``OUT/dist/*.whl``, when built)
holds solution material of the full book's chapters (:func:`solution_material`):

* a solution block (an element of class ``solution``, gated solution markup, a bold "Solution of
  exercise" heading);
* a run of five words (of three letters or more) that occurs in a solution and nowhere else in
  the book, so that a solution of a line or two is caught as well;
* a line of solution code, or a solution-only display formula, compared without spaces;
* a distinctive reference answer of a checkable exercise printed with at least four significant
  digits ("0.9722", "17.683", "9.722e-01"), unless the book prints it outside the solutions
  (chapter text, exercise data, glued values);
* the output of a solution: :func:`fdi_lib.exercises.check`'s "correct" message, or any output
  in a student notebook (they are not executed);
* cell or notebook metadata that names a solution;
* in the wheel, the functions that compute the reference answers;
* in the student PDF (``OUT/pdf``, ``make student-pdf``, when built), its text (``pdftotext``)
  scanned as a page.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from fdi_lib.exercises import (
    code_cells,
    parse_chapter,
    strip_solutions,
    words,
)
from fdi_lib.exercises._reference import REFERENCES

sys.path.insert(0, str(REPO / "tools"))
import notebook_markdown

#: Top-level entries of the repository that are not part of the book's sources.
NOT_SOURCES = {"_build", "fdi_lib", "tests", "benchmarks", "tools", "build"}


chapters = notebook_markdown.chapters


def copy_sources(out: Path) -> Path:
    """Copy the book's sources to ``out/src`` with the solutions removed; returns ``out/src``."""
    src = out / "src"
    if src.exists():
        shutil.rmtree(src)
    src.mkdir(parents=True)
    for entry in REPO.iterdir():
        if (
            entry.name.startswith(".")
            or entry.name in NOT_SOURCES
            or entry.name.endswith(".egg-info")
        ):
            continue
        if entry.is_dir():
            shutil.copytree(
                entry,
                src / entry.name,
                ignore=shutil.ignore_patterns("*.ipynb", ".ipynb_checkpoints", "__pycache__"),
            )
        else:
            shutil.copy2(entry, src / entry.name)
    for path in (src / "book").rglob("*.md"):
        text = path.read_text()
        stripped = strip_solutions(text)
        if stripped != text:
            path.write_text(stripped)
    return src


def write_notebooks(src: Path, out: Path, glue_dir: Path | None = None) -> list[Path]:
    """One unexecuted notebook per chapter of the stripped sources, in ``out/notebooks``, its
    MyST markup as plain Markdown and the book's macros defined (:mod:`notebook_markdown`),
    with the glued values of the student build's executed notebooks ``glue_dir``."""
    target = out / "notebooks"
    if target.exists():
        shutil.rmtree(target)
    return notebook_markdown.write_notebooks(src, target, glue_dir)


#: The jupyter-cache of the last ``make book`` (``tools/execute_book.py``): a student chapter whose
#: code cells are those of the full book takes its outputs from there instead of executing again.
BOOK_CACHE = REPO / "_build" / ".jupyter_cache-book"
#: The results cache of the last ``make book`` (``$FDI_RESULTS_CACHE``): a reproduction that a
#: student chapter runs at the settings and with the code of a full-book chapter reads its result
#: (keyed by the settings and the library's sources, :mod:`fdi_lib.reproduce.registry`). The
#: student run reads and writes a copy of it (``OUT/results-cache``): the book's cache holds what
#: the book computed and nothing else, whatever runs beside or after (the caption check,
#: ``tests/browser/check_captions.py``, reads it while CI builds this edition).
BOOK_RESULTS = REPO / "_build" / "results-cache"


def build(out: Path, extra: list[str]) -> None:
    src = copy_sources(out)
    env = dict(
        os.environ,
        PYTHONPATH=os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])),
    )
    if BOOK_RESULTS.is_dir() and "FDI_RESULTS_CACHE" not in env:
        results = out / "results-cache"
        if results.exists():
            shutil.rmtree(results)
        shutil.copytree(BOOK_RESULTS, results)
        env["FDI_RESULTS_CACHE"] = str(results)
    work = out / "build"
    config = out / "_config_student.yml"
    # the chapters executed side by side, those unchanged by the stripping taken from make book's
    # run, then the pages built from that cache (as make book does)
    execute = [
        sys.executable,
        str(REPO / "tools" / "execute_book.py"),
        "--root",
        str(src),
        "--cache",
        str(out / ".jupyter_cache"),
        "--reuse",
        str(BOOK_CACHE),
        "--config-out",
        str(config),
    ]
    print("+", " ".join(execute), flush=True)
    subprocess.run(execute, check=True, env=env)
    cmd = [
        str(Path(sys.executable).with_name("jupyter-book")),
        "build",
        str(src),
        "--config",
        str(config),
        "--path-output",
        str(work),
        "--builder",
        "html",
        *extra,
    ]
    print("+", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True, env=env)
    html = out / "html"
    if html.exists():
        shutil.rmtree(html)
    shutil.move(str(work / "_build" / "html"), str(html))
    notebooks = write_notebooks(src, out, work / "_build" / "jupyter_execute")
    print(f"student book: {html / 'index.html'}; {len(notebooks)} notebooks in {out / 'notebooks'}")


# ----------------------------------------------------------------------------- the leak scan
def reference_answer(exercise_id: str) -> np.ndarray:
    """The reference answer of a checkable exercise on the book's data, as floats (the one place
    this tool reads the answers)."""
    from fdi_lib.exercises import reference_answer as answer

    return np.asarray(answer(exercise_id), dtype=float)


#: Significant digits a printed number needs to be compared with the answers: a shorter one
#: ("0.12", "98") is too common in the pages to tell an answer from a coincidence.
SIGNIFICANT = 4
#: A line of solution code shorter than this (without spaces) is not distinctive.
MIN_CODE = 12
#: Runs of this many words that occur only in solutions (the old scan used 8 and missed
#: solutions of a line or two).
SHINGLE = 5
_NUMBER = re.compile(r"(?<![\w.])(\d+(?:\.\d*)?|\.\d+)(?:[eE]([-+]?\d+))?(?![\w.])")
_DISPLAY_MATH = re.compile(r"\$\$(.+?)\$\$|\\begin\{(\w+\*?)\}.+?\\end\{\2\}", re.S)
#: What :func:`fdi_lib.exercises.check` says to a correct answer: only a solution prints it.
CORRECT_MESSAGE = re.compile(r"[a-z]+-\d+: correct \(tolerance")


def _squeeze(text: str) -> str:
    """``text`` without spaces or backticks: code reads the same in a source, a notebook and a
    page (whose text has the code's tokens apart and its inline-code marks gone)."""
    return re.sub(r"[\s`]+", "", text)


def _runs(text: str) -> set[tuple[str, ...]]:
    """The runs of :data:`SHINGLE` words of ``text``, words of three letters or more (the
    letters of formulas, "h p h t r", would match anywhere), MyST roles left out (a page shows
    the value of ``{glue:text}`name```, not the words of its name)."""
    ws = [w for w in words(notebook_markdown._ROLE.sub(" ", text)) if len(w) >= 3]
    return {tuple(ws[i : i + SHINGLE]) for i in range(len(ws) - SHINGLE + 1)}


def _distinctive(value: float, scale: float) -> bool:
    """Whether an answer can be told from the numbers a page prints anyway: not numerically zero,
    not a whole number below 1000, not a round number of two significant digits (0.75, 1.2)."""
    if abs(value) <= 1e-9 * scale or (value == round(value) and abs(value) < 1000):
        return False
    return not math.isclose(value, float(f"{value:.2g}"), rel_tol=1e-6)


def printed_numbers(text: str) -> list[tuple[float, float]]:
    """The numbers printed in ``text`` with at least :data:`SIGNIFICANT` significant digits, as
    ``(value, half a unit of their last digit)``: ``"0.59915"`` -> ``(0.59915, 5e-06)``."""
    out = []
    for m in _NUMBER.finditer(text):
        mantissa, exponent = m.group(1), int(m.group(2) or 0)
        digits = mantissa.replace(".", "").lstrip("0")
        if (
            len(digits) < SIGNIFICANT or abs(exponent) > 300
        ):  # beyond a float (1e-400 in code): no answer
            continue
        decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
        out.append((float(mantissa) * 10.0**exponent, 0.5 * 10.0 ** (exponent - decimals)))
    return out


def _matches(numbers: list[tuple[float, float]], values: np.ndarray) -> set[float]:
    """The ``values`` equal to one of ``numbers`` to that number's last digit (signs ignored)."""
    if not len(values) or not numbers:
        return set()
    printed = np.array(numbers)
    hit = np.abs(np.abs(values)[:, None] - printed[None, :, 0]) <= printed[None, :, 1] * (1 + 1e-9)
    return set(values[hit.any(axis=1)].tolist())


@dataclass
class SolutionMaterial:
    """What the student edition must not contain, read from the full book's chapters.

    Attributes
    ----------
    fingerprints : set
        Runs of :data:`SHINGLE` words of the solutions' text that occur nowhere else in the book.
    code : dict
        Lines of solution code (without spaces) -> the line, for lines of at least
        :data:`MIN_CODE` characters found in no other cell or text of the book.
    maths : dict
        Display maths of the solutions (without spaces) -> the formula, for formulas found
        nowhere else in the book.
    answers : dict
        Distinctive reference answers -> the exercise: values of the checkable exercises that are
        neither numerically zero nor whole numbers below 1000 and that the book does not print
        outside the solutions (in its text, the exercises' data or the glued values
        ``printed``) to :data:`SIGNIFICANT` digits.
    references : set
        Names of the functions that compute the reference answers.
    """

    fingerprints: set = field(default_factory=set)
    code: dict = field(default_factory=dict)
    maths: dict = field(default_factory=dict)
    answers: dict = field(default_factory=dict)
    references: set = field(default_factory=set)


def solution_material(
    book: Path = REPO / "book", printed: str = "", answers_of: tuple[str, ...] | None = None
) -> SolutionMaterial:
    """The :class:`SolutionMaterial` of the chapters under ``book``; ``printed`` is more text the
    student edition shows legitimately (the student build's glued values); ``answers_of`` limits
    the reference answers to these exercises (default: every exercise of the chapters)."""
    from fdi_lib.exercises import EXERCISES, exercise_data

    material = SolutionMaterial()
    solutions, visible, ids = [], [printed], []
    for path in sorted(book.rglob("*.md")):
        full = path.read_text()
        visible.append(strip_solutions(full))
        solutions += [ex.solution for ex in parse_chapter(full)]
        ids += [ex.id for ex in parse_chapter(full)]
    visible_text = "\n".join(visible)
    visible_runs = _runs(visible_text)
    squeezed = _squeeze(visible_text)
    for solution in solutions:
        material.fingerprints |= _runs(solution) - visible_runs
        for cell in code_cells(solution):
            for line in cell.splitlines():
                key = _squeeze(line)
                if len(key) >= MIN_CODE and key not in squeezed:
                    material.code[key] = line.strip()
        for m in _DISPLAY_MATH.finditer(solution):
            key = _squeeze(m.group(1) or m.group(0))
            if key not in squeezed:
                material.maths[key] = " ".join((m.group(1) or m.group(0)).split())
    checkable = [
        EXERCISES[i]
        for i in ids
        if i in EXERCISES and EXERCISES[i].checkable and (answers_of is None or i in answers_of)
    ]
    shown = printed_numbers(visible_text + "\n".join(str(exercise_data(e.id)) for e in checkable))
    for e in checkable:
        ref = reference_answer(e.id).ravel()
        scale = np.abs(ref).max(initial=0.0)
        for v in ref:
            if _distinctive(v, scale) and not _matches(shown, np.array([v])):
                material.answers[float(v)] = e.id
        name = getattr(REFERENCES[e.id].answer, "__name__", "<lambda>")
        if name.isidentifier():
            material.references.add(name)
    return material


def scan_text(text: str, material: SolutionMaterial) -> list[str]:
    """The kinds of solution material found in ``text`` (a page's or notebook's text)."""
    found = []
    runs = _runs(text) & material.fingerprints
    if runs:
        found.append(f"{len(runs)} runs of solution text, e.g. {' '.join(sorted(runs)[0])!r}")
    squeezed = _squeeze(text)
    code = [line for key, line in material.code.items() if key in squeezed]
    if code:
        found.append(f"{len(code)} lines of solution code, e.g. {code[0]!r}")
    maths = [tex for key, tex in material.maths.items() if key in squeezed]
    if maths:
        found.append(f"{len(maths)} formulas of the solutions, e.g. {maths[0]!r}")
    values = np.array(sorted(material.answers))
    hits = _matches(printed_numbers(text), values)
    if hits:
        v = min(hits)
        found.append(f"{len(hits)} reference answers, e.g. {v!r} ({material.answers[v]})")
    if CORRECT_MESSAGE.search(text):
        found.append(f"the output of a solution ({CORRECT_MESSAGE.search(text).group(0)!r}...)")
    return found


def printed_by_the_book(executed: Path) -> str:
    """What the student build's executed notebooks (``executed``, myst-nb's ``jupyter_execute``)
    print outside their Exercises sections: the glued values and the outputs of the chapters'
    cells. They come from the stripped sources, so an answer among them is one the chapter prints
    itself (sig-5's slope in the claims ledger), not a leak; the outputs of the exercises'
    starter cells are not in it."""
    import nbformat

    parts = [p.read_text() for p in sorted(executed.rglob("*.glue.json"))]
    for path in sorted(executed.rglob("*.ipynb")):
        for cell in nbformat.read(path, as_version=4).cells:
            if cell.cell_type == "markdown" and re.search(r"^## Exercises\s*$", cell.source, re.M):
                break
            for output in cell.get("outputs", []):
                data = output.get("data", {})
                parts += [output.get("text", "")] + [
                    v for k, v in data.items() if k.startswith("text/")
                ]
    return "\n".join(p if isinstance(p, str) else "".join(p) for p in parts)


def _page_text(path: Path) -> tuple[str, list[str]]:
    """Visible text of an HTML page, and the solution blocks it has (by their class)."""
    from bs4 import BeautifulSoup

    soup = BeautifulSoup(path.read_text(errors="replace"), "html.parser")
    blocks = [" ".join(tag.get("class", [])) for tag in soup.select('[class*="solution"]')]
    for tag in soup(["script", "style"]):
        tag.decompose()
    return soup.get_text(" "), [f"a solution block (class {b!r})" for b in blocks]


def _names_solution(metadata: Any) -> bool:
    """Whether notebook metadata marks something as a solution: a key (``nbgrader``'s
    ``"solution": true``) or a tag naming one (not any value: a figure may be named
    ``fig-bz-solution1``)."""
    if isinstance(metadata, dict):
        tagged = any("solution" in str(t).lower() for t in metadata.get("tags", []))
        return tagged or any(
            "solution" in str(k).lower() or _names_solution(v) for k, v in metadata.items()
        )
    return isinstance(metadata, list) and any(_names_solution(v) for v in metadata)


def _notebook_text(path: Path) -> tuple[str, list[str]]:
    """A notebook's text (sources and outputs) and what a student notebook must not have:
    solution markup, outputs, metadata that names a solution."""
    import nbformat

    nb = nbformat.read(path, as_version=4)
    found = []
    parts = []
    for i, cell in enumerate(nb.cells):
        parts.append(cell.source)
        if cell.cell_type == "code":
            for out in cell.get("outputs", []):
                parts.append(json.dumps(out.get("text", out.get("data", {})), ensure_ascii=False))
            if cell.get("outputs"):
                found.append(f"cell {i} has outputs (a student notebook is not executed)")
        if _names_solution(cell.metadata):
            found.append(f"cell {i} has metadata naming a solution: {json.dumps(cell.metadata)}")
    text = "\n".join(parts)
    if re.search(r"solution-start|\{solution\}|\*\*Solution of exercise", text):
        found.append("a solution block")
    if _names_solution(nb.metadata):
        found.append("notebook metadata naming a solution")
    return text, found


def _pdf_text(path: Path) -> str:
    """Text of a PDF (``pdftotext``, poppler-utils); a solution shows as its text only."""
    return subprocess.run(
        ["pdftotext", "-enc", "UTF-8", str(path), "-"], capture_output=True, text=True, check=True
    ).stdout


#: Kinds of :func:`scan_text` finding that the library's code in the wheel shares with the solutions.
_LIBRARY_TEXT = ("runs of solution text", "lines of solution code", "the output of a solution")


def _wheel_problems(wheel: Path, material: SolutionMaterial) -> list[str]:
    """Reference code and answers in the student package (every text file of the wheel)."""
    import zipfile

    found = []
    with zipfile.ZipFile(wheel) as z:
        for name in z.namelist():
            try:
                text = z.read(name).decode("utf-8")
            except UnicodeDecodeError:
                continue  # compiled or binary: the sources are what a student reads
            defined = sorted(
                n for n in material.references if re.search(rf"\bdef {re.escape(n)}\(", text)
            )
            if defined:
                found.append(
                    f"{wheel.name}:{name}: defines the reference code {', '.join(defined)}"
                )
            # the library's own code is what the solutions call: its words, lines and check's
            # messages are not leaks; answers printed in it are
            found += [
                f"{wheel.name}:{name}: {f}"
                for f in scan_text(text, material)
                if not any(kind in f for kind in _LIBRARY_TEXT)
            ]
    return found


def verify(
    out: Path, book: Path = REPO / "book", material: SolutionMaterial | None = None
) -> list[str]:
    """Problems found in the student edition under ``out`` (empty when it holds no solution
    material of the chapters under ``book``): solution blocks, runs of solution text, lines of
    solution code, solution-only formulas, distinctive reference answers, the output of a
    solution, outputs or solution metadata in the notebooks, reference code or answers in the
    student wheel (``out/dist/*.whl``, when built) and the student PDF (``out/pdf``, when built).
    ``material`` defaults to :func:`solution_material` of ``book``, the student build's glued
    values being printed."""
    if material is None:
        executed = out / "build" / "_build" / "jupyter_execute"
        material = solution_material(book, printed=printed_by_the_book(executed))
    problems = []
    n_exercises = sum(len(parse_chapter(p.read_text())) for p in chapters(book))
    pages = {p.relative_to(book).with_suffix("").as_posix() for p in chapters(book)}
    html_files = sorted(
        p for p in (out / "html").rglob("*") if p.suffix in (".html", ".md", ".txt")
    )
    notebooks = sorted((out / "notebooks").rglob("*.ipynb"))
    downloads = sorted((out / "html").rglob("*.ipynb"))
    if not html_files:
        problems.append(f"no HTML pages under {out / 'html'}")
    if len(notebooks) != len(pages):
        problems.append(
            f"expected {len(pages)} notebooks under {out / 'notebooks'}, found {len(notebooks)}"
        )
    seen_exercises = 0
    for path in html_files:
        text, found = (
            _page_text(path) if path.suffix == ".html" else (path.read_text(errors="replace"), [])
        )
        found += scan_text(text, material)
        if (out / "html" / "book" / "api") in path.parents:
            # the library reference is the wheel's docstrings on a page: as in the wheel, the
            # library's own words and code are not leaks; answers printed in them are
            found = [f for f in found if not any(kind in f for kind in _LIBRARY_TEXT)]
        problems += [f"{path}: {f}" for f in found]
    for path in notebooks + downloads:
        text, found = _notebook_text(path)
        if path in downloads:  # the executed notebook of a page: its outputs are the page's
            found = [f for f in found if "has outputs" not in f]
        problems += [f"{path}: {f}" for f in found + scan_text(text, material)]
        if path in notebooks:
            seen_exercises += text.count("**Exercise ")
    for path in sorted((out / "pdf").glob("*.pdf")):
        problems += [f"{path}: {f}" for f in scan_text(_pdf_text(path), material)]
    if seen_exercises != n_exercises:
        problems.append(
            f"the notebooks hold {seen_exercises} exercises, the chapters {n_exercises}"
        )
    for wheel in sorted((out / "dist").glob("*.whl")):
        problems += _wheel_problems(wheel, material)
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
        print(
            f"student edition verified: no solution material in {out / 'html'}, {out / 'notebooks'}"
            f"{', ' + str(out / 'dist') if list((out / 'dist').glob('*.whl')) else ''}"
            f"{' or ' + str(out / 'pdf') if list((out / 'pdf').glob('*.pdf')) else ''}"
        )
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
