"""The exercises in the book: the instructor's tables, the course plans, reading the gated
exercise blocks of a chapter, and the student edition's solution filter (``make student``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from fdi_lib.errors import ModelError
from fdi_lib.exercises._core import CHAPTERS, DIFFICULTIES

__all__ = [
    "exercise_table",
    "counts_table",
    "COURSE_PLANS",
    "PlanWeek",
    "HAND_GRADED",
    "WRITE_UP_MINUTES",
    "homework_minutes",
    "plan_table",
    "strip_solutions",
    "ChapterExercise",
    "parse_chapter",
    "exercises_section",
    "code_cells",
    "words",
    "solution_fingerprints",
    "CELL_KEY",
    "tag_exercise_cells",
]


# ----------------------------------------------------------------------------- book helpers
def exercise_table():
    """All exercises as a :func:`fdi_lib.report.table` (the instructor's page)."""
    from fdi_lib.exercises import exercises
    from fdi_lib.report import table

    rows = {
        e.id: [
            CHAPTERS[e.chapter],
            e.title,
            e.difficulty,
            f"{e.minutes} min",
            "yes" if e.checkable else "no (explanation)",
        ]
        for e in exercises()
    }
    return table(
        rows, ["chapter", "title", "difficulty", "time", "checkable"], index_header="exercise"
    )


def counts_table():
    """Number of exercises per chapter and difficulty, checkable ones and total time (a report table)."""
    from fdi_lib.exercises import exercises
    from fdi_lib.report import table

    rows = {}
    for chapter, title in CHAPTERS.items():
        exs = exercises(chapter)
        rows[title] = [sum(e.difficulty == d for e in exs) for d in DIFFICULTIES] + [
            sum(e.checkable for e in exs),
            len(exs),
            f"{sum(e.minutes for e in exs)} min",
        ]
    every = exercises()
    rows["all chapters"] = [sum(e.difficulty == d for e in every) for d in DIFFICULTIES] + [
        sum(e.checkable for e in every),
        len(every),
        f"{sum(e.minutes for e in every)} min",
    ]
    return table(rows, [*DIFFICULTIES, "checkable", "total", "time"], index_header="chapter")


#: Checkable exercises that also ask for an explanation, graded by hand with the rubric at the end
#: of their solution (the exercises that are not checkable are all graded by hand).
HAND_GRADED: tuple[str, ...] = (
    "sig-3",
    "sig-4",
    "sig-5",
    "glr-3",
    "pipe-1",
    "pipe-3",
    "pipe-4",
    "pipe-5",
    "sparse-1",
    "sparse-5",
    "bz-3",
    "bz-4",
    "svo-2",
    "svo-4",
)

#: Minutes a student takes to write up a challenge, on top of the challenge's own estimate.
WRITE_UP_MINUTES = 45

#: What :attr:`PlanWeek.own_challenge` may say.
OWN_CHALLENGE = ("", "experiment", "write-up")


@dataclass(frozen=True)
class PlanWeek:
    """One week of a course plan: what a student reads and does at home.

    Attributes
    ----------
    topic : str
        The week's topic.
    chapter : str
        The chapter read (a key of :data:`CHAPTERS`).
    sections : str
        The sections read, by their titles in the chapter, or ``"the whole chapter"``.
    reading : int
        Minutes to read them with the notebook open (an estimate for a graduate student who runs
        the cells).
    exercises : tuple of str
        The exercises set (identifiers of :func:`~fdi_lib.exercises.exercise_ids`); their
        minutes are the registry's estimates.
    other : tuple of (str, int)
        Other work of the week and its minutes.
    own_challenge : str
        One challenge of the student's choice (any chapter): ``"experiment"`` does it this week
        (counted at the longest challenge's estimate), ``"write-up"`` writes it up
        (:data:`WRITE_UP_MINUTES`), ``""`` neither.
    """

    topic: str
    chapter: str
    sections: str
    reading: int
    exercises: tuple[str, ...]
    other: tuple[tuple[str, int], ...] = ()
    own_challenge: str = ""

    def __post_init__(self):
        if self.chapter not in CHAPTERS:
            raise ModelError(f"chapter: expected one of {list(CHAPTERS)}, got {self.chapter!r}")
        if self.own_challenge not in OWN_CHALLENGE:
            raise ModelError(
                f"own_challenge: expected one of {OWN_CHALLENGE}, got {self.own_challenge!r}"
            )


_INSTALL = (("install the student notebooks and run one from top to bottom", 30),)

#: The suggested courses of the instructor's page, by name: each week one chapter (or part of one)
#: and its exercises, each exercise set at most once. ``"10 weeks"`` sets every exercise of the
#: book; ``"6 weeks"`` covers the papers' six chapters with their warm-up and core exercises and
#: one challenge of the student's choice. :func:`plan_table` renders them.
COURSE_PLANS: dict[str, tuple[PlanWeek, ...]] = {
    "10 weeks": (
        PlanWeek(
            "Kalman innovation and fault signatures",
            "zb2014/signature",
            "Setting; The two propositions; Numerical check to machine precision",
            90,
            ("sig-1", "sig-2", "sig-3"),
            _INSTALL,
        ),
        PlanWeek(
            "Boundedness and identifiability",
            "zb2014/signature",
            "Boundedness; Reproduction of paper Figs. 1 and 2; Persistent excitation; Explore",
            75,
            ("sig-4", "sig-5", "sig-6"),
        ),
        PlanWeek(
            "GLR test with a known profile",
            "zb2014/glr",
            "From the state-space model to a regression; GLR test with a known profile; GLR "
            "test with unknown onset",
            105,
            ("glr-1", "glr-2", "glr-3"),
        ),
        PlanWeek(
            "Unknown onset and minmax isolation",
            "zb2014/glr",
            "Reproduction of paper Figs. 3 and 4; Isolation: the minmax test; Explore",
            60,
            ("glr-5", "glr-4", "glr-6"),
        ),
        PlanWeek(
            "Leaks on a gas pipeline: model and detection",
            "zb2014/pipeline",
            "Setting and notation; Two propositions; Numerical checks; Table 1; Figs. 5 and 6; "
            "Fig. 7",
            120,
            ("pipe-1", "pipe-2", "pipe-5"),
        ),
        PlanWeek(
            "Leaks on a gas pipeline: isolation",
            "zb2014/pipeline",
            "Fig. 8; Fig. 9; What was calibrated, what was predicted; the sensitivity to the "
            "third constant; Interactive exploration",
            90,
            ("pipe-3", "pipe-4", "pipe-6"),
        ),
        PlanWeek(
            "Sparse isolation with the Lasso",
            "zhang2021/sparse",
            "the whole chapter",
            120,
            ("sparse-1", "sparse-2", "sparse-3", "sparse-4", "sparse-5"),
        ),
        PlanWeek(
            "Unknown inputs: parametric and non-parametric faults",
            "bz/parametric-nonparametric",
            "the whole chapter",
            100,
            ("bz-1", "bz-2", "bz-3", "bz-4", "bz-5", "sparse-6"),
        ),
        PlanWeek(
            "Set membership: set-valued observers",
            "rosa2013/svo",
            "the whole chapter, the subsections of The Eclipse UAV skimmed",
            100,
            ("svo-1", "svo-2", "svo-3", "svo-4", "svo-5", "bz-6"),
        ),
        PlanWeek(
            "Case study: four methods on the wind-turbine benchmark",
            "windturbine/benchmark",
            "The plant and its faults; Four designs; The scoreboard; What each kind of method buys",
            45,
            ("wt-1", "wt-2", "wt-3", "wt-4", "svo-6"),
        ),
    ),
    "6 weeks": (
        PlanWeek(
            "Kalman innovation and fault signatures",
            "zb2014/signature",
            "the whole chapter",
            120,
            ("sig-1", "sig-2", "sig-3", "sig-4", "sig-5"),
            _INSTALL,
        ),
        PlanWeek(
            "GLR and minmax tests",
            "zb2014/glr",
            "the whole chapter",
            120,
            ("glr-1", "glr-2", "glr-3", "glr-4", "glr-5"),
        ),
        PlanWeek(
            "Leaks on a gas pipeline",
            "zb2014/pipeline",
            "the whole chapter, the calibration subsections skimmed",
            120,
            ("pipe-1", "pipe-2", "pipe-3", "pipe-4", "pipe-5"),
        ),
        PlanWeek(
            "Sparse isolation with the Lasso",
            "zhang2021/sparse",
            "the whole chapter",
            120,
            ("sparse-1", "sparse-2", "sparse-3", "sparse-4", "sparse-5"),
        ),
        PlanWeek(
            "Unknown inputs: parametric and non-parametric faults",
            "bz/parametric-nonparametric",
            "the whole chapter",
            100,
            ("bz-1", "bz-2", "bz-3", "bz-4", "bz-5"),
            own_challenge="experiment",
        ),
        PlanWeek(
            "Set membership: set-valued observers",
            "rosa2013/svo",
            "the whole chapter, the subsections of The Eclipse UAV skimmed",
            100,
            ("svo-1", "svo-2", "svo-3", "svo-4", "svo-5"),
            own_challenge="write-up",
        ),
    ),
}


def _own_challenge(week: PlanWeek) -> tuple[str, int] | None:
    """The student's own challenge in ``week`` as (what, minutes), or ``None``."""
    from fdi_lib.exercises import exercises

    if week.own_challenge == "experiment":
        return (
            "the experiment of one challenge of the student's choice (any chapter)",
            max(e.minutes for e in exercises() if e.difficulty == "challenge"),
        )
    if week.own_challenge == "write-up":
        return (
            "the write-up of the chosen challenge (hand-graded with its rubric)",
            WRITE_UP_MINUTES,
        )
    return None


def homework_minutes(week: PlanWeek) -> int:
    """Minutes of homework of one week: the reading, the exercises (the registry's estimates), a
    write-up (:data:`WRITE_UP_MINUTES`) for each challenge, and the other work.

    Raises :class:`~fdi_lib.exercises.UnknownExerciseError` on an exercise that is not in the
    registry.
    """
    from fdi_lib.exercises import get_exercise

    exs = [get_exercise(i) for i in week.exercises]
    own = _own_challenge(week)
    return (
        week.reading
        + sum(e.minutes for e in exs)
        + sum(m for _, m in week.other)
        + WRITE_UP_MINUTES * sum(e.difficulty == "challenge" for e in exs)
        + (own[1] if own else 0)
    )


def plan_table(plan):
    """A course plan (a value of :data:`COURSE_PLANS`) as a report table, one row per week: the
    reading, the exercises graded by their answer and those graded by hand, the other work and
    the hours of homework (:func:`homework_minutes`).

    Raises :class:`ModelError` on an exercise set in several weeks, and
    :class:`~fdi_lib.exercises.UnknownExerciseError` on an unknown exercise.

    Examples
    --------
    >>> t = plan_table(COURSE_PLANS["6 weeks"])
    >>> t.columns[-1], t.rows[0][0], t.rows[0][1][2]
    ('homework (h)', 'week 1', 'sig-1, sig-2, sig-3, sig-4, sig-5')
    """
    from fdi_lib.exercises import get_exercise
    from fdi_lib.report import table

    ids = [i for week in plan for i in week.exercises]
    twice = sorted({i for i in ids if ids.count(i) > 1})
    if twice:
        raise ModelError(f"plan: each exercise is set at most once, got {twice} in several weeks")
    rows = {}
    for n, week in enumerate(plan, start=1):
        exs = [get_exercise(i) for i in week.exercises]
        hand = [e.id for e in exs if e.id in HAND_GRADED or not e.checkable]
        own = _own_challenge(week)
        other = [what for what, _ in week.other] + ([own[0]] if own else [])
        rows[f"week {n}"] = [
            week.topic,
            f"{CHAPTERS[week.chapter]}: {week.sections}",
            ", ".join(e.id for e in exs if e.checkable) or "none",
            ", ".join(hand) or "none",
            "; ".join(other) or "none",
            f"{homework_minutes(week) / 60:.1f}",
        ]
    return table(
        rows,
        ["topic", "reading", "checked", "hand-graded (rubric)", "other work", "homework (h)"],
        index_header="week",
    )


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
            while j < len(lines) and not (
                _FENCE.match(lines[j]) and _FENCE.match(lines[j])["name"] == "solution-end"
            ):
                j += 1
            if j == len(lines):
                raise ModelError(f"text: solution-start at line {i + 1} has no solution-end")
            fence = _FENCE.match(lines[j])["fence"]
            j += 1
            while j < len(lines) and lines[j].strip() != fence:  # the closing fence of solution-end
                j += 1
            i = j + 1
            while i < len(lines) and not lines[i].strip() and out and not out[-1].strip():
                i += 1  # no run of blank lines where the block was
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


_EXERCISE_RE = re.compile(
    r"^```\{exercise-start\} (?P<tid>[a-z0-9-]+) · (?P<diff>[a-z-]+) · (?P<title>[^\n]*)\n"
    r":label: ex-(?P<id>[a-z0-9-]+)\n(?P<opts>(?::[^\n]*\n)*)```\n"
    r"(?P<body>.*?)^```\{exercise-end\}\n```$",
    re.S | re.M,
)
_SOLUTION_RE = re.compile(
    r"^```\{solution-start\} ex-(?P<id>[a-z0-9-]+)\n(?P<opts>(?::[^\n]*\n)*)```\n"
    r"(?P<body>.*?)^```\{solution-end\}\n```$",
    re.S | re.M,
)
_CELL_RE = re.compile(r"^```\{code-cell\} ipython3\n(?P<body>.*?)^```$", re.S | re.M)


def parse_chapter(text: str) -> list[ChapterExercise]:
    """The exercises of a chapter in the gated syntax, in order, each with its solution."""
    solutions = {m["id"]: m for m in _SOLUTION_RE.finditer(text)}
    out = []
    for m in _EXERCISE_RE.finditer(text):
        if m["tid"] != m["id"]:
            raise ModelError(f"text: exercise titled {m['tid']!r} has the label 'ex-{m['id']}'")
        sol = solutions.get(m["id"])
        out.append(
            ChapterExercise(
                id=m["id"],
                difficulty=m["diff"],
                title=m["title"].strip(),
                exercise=m["body"],
                solution=sol["body"] if sol else "",
                solution_options=sol["opts"] if sol else "",
            )
        )
    return out


def exercises_section(text: str) -> str:
    """The ``## Exercises`` section of a chapter (up to the next ``## `` heading); ``""`` if none."""
    m = re.search(r"^## Exercises\n", text, re.M)
    if m is None:
        return ""
    end = re.search(r"^## ", text[m.end() :], re.M)
    return text[m.start() : m.end() + end.start()] if end else text[m.start() :]


def code_cells(text: str) -> list[str]:
    """The sources of the ``{code-cell}`` blocks of a MyST text, without their metadata header."""
    cells = []
    for m in _CELL_RE.finditer(text):
        body = m["body"]
        if body.startswith("---\n"):
            body = body[body.index("\n---\n", 3) + 5 :]
        elif body.startswith(":"):
            body = "".join(
                line for line in body.splitlines(keepends=True) if not line.startswith(":")
            )
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
    return {tuple(ws[i : i + n]) for i in range(len(ws) - n + 1)}


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


#: Key of a notebook cell's metadata that says which exercise the cell belongs to:
#: ``{"exercise": "glr-5"}`` inside an exercise (statement and starter cells), ``{"exercise":
#: None}`` outside (as nbgrader's and otter's cell metadata tag a notebook's graded parts).
CELL_KEY = "fdi_book"

_START_END = re.compile(
    r"^(?:`{3,}|:{3,})\{exercise-(?P<what>start|end)\}"
    r"(?: (?P<id>[a-z]+-\d+))?",
    re.M,
)


def tag_exercise_cells(nb) -> None:
    """Write :data:`CELL_KEY` metadata into every cell of a MyST chapter's notebook (as jupytext
    reads it, in place): a code cell belongs to the exercise open at its place, a Markdown cell to
    the exercise open at its end (one cell may close an exercise and open the next)."""
    current = None
    for cell in nb.cells:
        if cell.cell_type == "markdown":
            for m in _START_END.finditer(cell.source):
                current = m["id"] if m["what"] == "start" else None
        cell.metadata[CELL_KEY] = {"exercise": current}
