"""The exercises in the book: the instructor's tables, the course plan, reading the gated
exercise blocks of a chapter, and the student edition's solution filter (``make student``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from fdi_lib.errors import ModelError
from fdi_lib.exercises._core import CHAPTERS, DIFFICULTIES

__all__ = ["exercise_table", "counts_table", "COURSE_PLAN", "plan_table", "strip_solutions",
           "ChapterExercise", "parse_chapter", "exercises_section", "code_cells", "words",
           "solution_fingerprints"]


# ----------------------------------------------------------------------------- book helpers
def exercise_table():
    """All exercises as a :func:`fdi_lib.report.table` (the instructor's page)."""
    from fdi_lib.exercises import exercises
    from fdi_lib.report import table

    rows = {e.id: [CHAPTERS[e.chapter], e.title, e.difficulty, f"{e.minutes} min",
                   "yes" if e.checkable else "no (explanation)"] for e in exercises()}
    return table(rows, ["chapter", "title", "difficulty", "time", "checkable"], index_header="exercise")


def counts_table():
    """Number of exercises per chapter and difficulty, checkable ones and total time (a report table)."""
    from fdi_lib.exercises import exercises
    from fdi_lib.report import table

    rows = {}
    for chapter, title in CHAPTERS.items():
        exs = exercises(chapter)
        rows[title] = ([sum(e.difficulty == d for e in exs) for d in DIFFICULTIES]
                       + [sum(e.checkable for e in exs), len(exs), f"{sum(e.minutes for e in exs)} min"])
    every = exercises()
    rows["all chapters"] = ([sum(e.difficulty == d for e in every) for d in DIFFICULTIES]
                            + [sum(e.checkable for e in every), len(every),
                               f"{sum(e.minutes for e in every)} min"])
    return table(rows, [*DIFFICULTIES, "checkable", "total", "time"], index_header="chapter")


#: A suggested course of nine weeks: (topic, chapters read, exercises set), each exercise once.
COURSE_PLAN: tuple[tuple[str, tuple[str, ...], tuple[str, ...]], ...] = (
    ("Kalman innovation and fault signatures", ("zb2014/signature",), ("sig-1", "sig-2", "sig-3")),
    ("Boundedness and identifiability", ("zb2014/signature",), ("sig-4", "sig-5", "sig-6")),
    ("GLR test with a known profile", ("zb2014/glr",), ("glr-1", "glr-2", "glr-3")),
    ("Unknown onset and minmax isolation", ("zb2014/glr",), ("glr-5", "glr-4", "glr-6")),
    ("Case study: leaks on a gas pipeline", ("zb2014/pipeline",),
     ("pipe-1", "pipe-2", "pipe-3", "pipe-4", "pipe-5", "pipe-6")),
    ("Sparse isolation with the Lasso", ("zhang2021/sparse",),
     ("sparse-1", "sparse-2", "sparse-3", "sparse-4", "sparse-5", "sparse-6")),
    ("Unknown inputs: parametric and non-parametric faults", ("bz/parametric-nonparametric",),
     ("bz-1", "bz-5", "bz-2", "bz-3", "bz-4", "bz-6")),
    ("Set membership: set-valued observers", ("rosa2013/svo",),
     ("svo-1", "svo-2", "svo-5", "svo-3", "svo-4", "svo-6")),
    ("Case study: four methods on the wind-turbine benchmark", ("windturbine/benchmark",),
     ("wt-1", "wt-2", "wt-3", "wt-4")),
)


def plan_table():
    """:data:`COURSE_PLAN` as a report table, with the estimated time of each week's exercises."""
    from fdi_lib.exercises import get_exercise
    from fdi_lib.report import table

    rows = {}
    for week, (topic, chapters, ids) in enumerate(COURSE_PLAN, start=1):
        exs = [get_exercise(i) for i in ids]
        core = sum(e.minutes for e in exs if e.difficulty != "challenge")
        extra = sum(e.minutes for e in exs if e.difficulty == "challenge")
        rows[f"week {week}"] = [topic, "; ".join(CHAPTERS[c] for c in chapters),
                                ", ".join(f"{e.id} ({e.minutes} min)" for e in exs),
                                f"{core} min", f"{extra} min"]
    return table(rows, ["topic", "chapter", "exercises (estimated time)", "warm-up and core",
                        "challenge"], index_header="week")


_FENCE = re.compile(r"^(?P<fence>`{3,}|:{3,})\{(?P<name>[a-z-]+)\}")


def strip_solutions(text: str) -> str:
    """Remove every solution from a MyST chapter: the gated blocks ``solution-start`` ...
    ``solution-end`` (with the code cells between them) and plain ``solution`` directives.

    Everything else (exercises, their starter cells) is kept byte for byte. Raises
    :class:`ModelError` on a ``solution-start`` without its ``solution-end``.
    """
    lines = text.splitlines(keepends=True)
    out: list[str] = []
    i = 0
    while i < len(lines):
        m = _FENCE.match(lines[i])
        if m and m["name"] == "solution-start":
            j = i + 1
            while j < len(lines) and not (_FENCE.match(lines[j]) and _FENCE.match(lines[j])["name"] == "solution-end"):
                j += 1
            if j == len(lines):
                raise ModelError(f"text: solution-start at line {i + 1} has no solution-end")
            fence = _FENCE.match(lines[j])["fence"]
            j += 1
            while j < len(lines) and lines[j].strip() != fence:   # the closing fence of solution-end
                j += 1
            i = j + 1
            while i < len(lines) and not lines[i].strip() and out and not out[-1].strip():
                i += 1   # no run of blank lines where the block was
            continue
        if m and m["name"] == "solution":
            fence = m["fence"]
            j = i + 1
            while j < len(lines) and lines[j].rstrip() != fence:
                j += 1
            i = j + 1
            continue
        out.append(lines[i])
        i += 1
    return "".join(out)


# ----------------------------------------------------------------------------- reading chapters
@dataclass(frozen=True)
class ChapterExercise:
    """One exercise as written in a chapter (gated syntax, title ``"<id> · <difficulty> · <title>"``,
    label ``"ex-<id>"``, unnumbered: the identifier is the exercise's name everywhere).

    Attributes
    ----------
    id : str
        The identifier of the label (``"ex-" + id``); :func:`parse_chapter` checks that the title
        starts with the same.
    difficulty : str
        The difficulty in the title.
    title : str
    exercise : str
        The MyST text between ``exercise-start`` and ``exercise-end`` (statement, starter cells).
    solution : str
        The text between ``solution-start`` and ``solution-end`` (``""`` if there is none).
    solution_options : str
        The option lines of ``solution-start`` (e.g. ``":class: dropdown"``).
    """

    id: str
    difficulty: str
    title: str
    exercise: str
    solution: str
    solution_options: str


_EXERCISE_RE = re.compile(r"^```\{exercise-start\} (?P<tid>[a-z0-9-]+) · (?P<diff>[a-z-]+) · (?P<title>[^\n]*)\n"
                          r":label: ex-(?P<id>[a-z0-9-]+)\n(?P<opts>(?::[^\n]*\n)*)```\n"
                          r"(?P<body>.*?)^```\{exercise-end\}\n```$", re.S | re.M)
_SOLUTION_RE = re.compile(r"^```\{solution-start\} ex-(?P<id>[a-z0-9-]+)\n(?P<opts>(?::[^\n]*\n)*)```\n"
                          r"(?P<body>.*?)^```\{solution-end\}\n```$", re.S | re.M)
_CELL_RE = re.compile(r"^```\{code-cell\} ipython3\n(?P<body>.*?)^```$", re.S | re.M)


def parse_chapter(text: str) -> list[ChapterExercise]:
    """The exercises of a chapter in the gated syntax, in order, each with its solution."""
    solutions = {m["id"]: m for m in _SOLUTION_RE.finditer(text)}
    out = []
    for m in _EXERCISE_RE.finditer(text):
        if m["tid"] != m["id"]:
            raise ModelError(f"text: exercise titled {m['tid']!r} has the label 'ex-{m['id']}'")
        sol = solutions.get(m["id"])
        out.append(ChapterExercise(id=m["id"], difficulty=m["diff"], title=m["title"].strip(),
                                   exercise=m["body"], solution=sol["body"] if sol else "",
                                   solution_options=sol["opts"] if sol else ""))
    return out


def exercises_section(text: str) -> str:
    """The ``## Exercises`` section of a chapter (up to the next ``## `` heading); ``""`` if none."""
    m = re.search(r"^## Exercises\n", text, re.M)
    if m is None:
        return ""
    end = re.search(r"^## ", text[m.end():], re.M)
    return text[m.start(): m.end() + end.start()] if end else text[m.start():]


def code_cells(text: str) -> list[str]:
    """The sources of the ``{code-cell}`` blocks of a MyST text, without their metadata header."""
    cells = []
    for m in _CELL_RE.finditer(text):
        body = m["body"]
        if body.startswith("---\n"):
            body = body[body.index("\n---\n", 3) + 5:]
        elif body.startswith(":"):
            body = "".join(line for line in body.splitlines(keepends=True) if not line.startswith(":"))
        cells.append(body)
    return cells


# ----------------------------------------------------------------------------- student edition checks
_MATH = re.compile(r"\$\$.*?\$\$|\$[^$\n]*\$|\\\(.*?\\\)|\\\[.*?\\\]", re.S)


def words(text: str) -> list[str]:
    """The words of a MyST source, a notebook or an HTML page's text, comparable across the three.

    Maths is dropped (``$...$`` in sources, ``\\(...\\)`` in HTML), then the alphabetic words are
    kept, lower case; code keeps its identifiers, so a code line reads the same in all three.
    """
    return re.findall(r"[a-z]+", _MATH.sub(" ", text).lower())


def _shingles(ws: list[str], n: int) -> set[tuple[str, ...]]:
    return {tuple(ws[i:i + n]) for i in range(len(ws) - n + 1)}


def solution_fingerprints(full_text: str, student_text: str, n: int = 8) -> set[tuple[str, ...]]:
    """Runs of ``n`` words that occur in the solutions of ``full_text`` and nowhere in ``student_text``.

    ``student_text`` is the same chapter after :func:`strip_solutions`. A student page or notebook
    that contains one of these runs shows solution text.
    """
    keep = _shingles(words(student_text), n)
    out: set[tuple[str, ...]] = set()
    for ex in parse_chapter(full_text):
        out |= _shingles(words(ex.solution), n) - keep
    return out
