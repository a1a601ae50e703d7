"""The book's exercises: a registry, the data each one gives, and a checker students can call.

Every exercise of the book has an entry here (:data:`EXERCISES`): its identifier (``"glr-3"``),
the chapter that states it, a title, a difficulty (``"warm-up"``, ``"core"`` or
``"challenge"``), an estimated time, and, for a *checkable* exercise, what to hand in and the
tolerance used. The chapters call

>>> from fdi_lib.exercises import check, exercise_data
>>> data = exercise_data("glr-1")       # the numbers the exercise works on
>>> check("glr-1", None)                # a starter cell: nothing computed yet
glr-1: no answer yet. Replace `answer = None` by the 1 - alpha quantile of chi2(m) (a number).

:func:`check` (:mod:`fdi_lib.exercises.checker`) compares an answer with a reference and explains
what is wrong without revealing the answer: the shape, a transpose, swapped entries, a constant
factor or a unit slip, an index shift, which entries are off, or a known mistake of that exercise
(wrong degrees of freedom, off-by-one window, missing transpose, ...). An unknown identifier
raises :class:`UnknownExerciseError`, an answer that is not a finite real number or array raises
:class:`AnswerError`.

**Per-student data.** ``exercise_data(id, student="s123")`` (or the environment variable
``FDI_STUDENT_ID=s123``) gives that student's variant of the exercise, drawn from the seed
:func:`student_seed` (``sha256("fdi-book/<exercise id>/<student id>")``): neighbours get
different numbers, and the grader (``tools/grader.py``) recomputes the reference for each.
Without a student id the data are the book's, identical on every call.

**Layout.** One module per chapter holds its exercises' statements and data
(:mod:`~fdi_lib.exercises.signature`, ``glr``, ``pipeline``, ``sparse``, ``bz``, ``svo``,
``windturbine``);
:mod:`~fdi_lib.exercises.checker` holds :func:`check`; :mod:`~fdi_lib.exercises.book` the
instructor's tables, the course plans (:data:`COURSE_PLANS`) and the chapter parsing. The reference answers, the known mistakes and the
list of library calls the grader forbids live in ``fdi_lib.exercises._reference``, which the
student package (``make student``) leaves out: there :func:`reference_answer` raises
:class:`ReferenceNotShippedError` and :func:`check` compares with digests.
"""

from __future__ import annotations

import difflib

import numpy as np

from fdi_lib.errors import ModelError
from fdi_lib.exercises import bz, glr, pipeline, signature, sparse, svo, windturbine
from fdi_lib.exercises._core import (
    CHAPTERS,
    DIFFICULTIES,
    STUDENT_ENV,
    AnswerError,
    CheckResult,
    Exercise,
    ExerciseData,
    ReferenceNotShippedError,
    UnknownExerciseError,
    student_id,
    student_rng,
    student_seed,
)
from fdi_lib.exercises.book import (
    CELL_KEY,
    COURSE_PLANS,
    HAND_GRADED,
    WRITE_UP_MINUTES,
    ChapterExercise,
    PlanWeek,
    code_cells,
    counts_table,
    exercise_table,
    exercises_section,
    homework_minutes,
    parse_chapter,
    plan_table,
    solution_fingerprints,
    strip_solutions,
    tag_exercise_cells,
    words,
)
from fdi_lib.exercises.checker import attempts, check

__all__ = [
    "Exercise",
    "CheckResult",
    "ExerciseData",
    "EXERCISES",
    "CHAPTERS",
    "DIFFICULTIES",
    "STUDENT_ENV",
    "UnknownExerciseError",
    "AnswerError",
    "ReferenceNotShippedError",
    "get_exercise",
    "exercises",
    "exercise_ids",
    "exercise_data",
    "check",
    "attempts",
    "reference_answer",
    "student_id",
    "student_seed",
    "student_rng",
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

_LIST = [
    e
    for module in (signature, glr, pipeline, sparse, bz, svo, windturbine)
    for e in module.EXERCISES
]

#: All exercises, by identifier, in book order.
EXERCISES: dict[str, Exercise] = {e.id: e for e in _LIST}


def get_exercise(exercise_id: str) -> Exercise:
    """The :class:`Exercise` registered as ``exercise_id``.

    Raises
    ------
    UnknownExerciseError
        With the closest registered identifiers.
    """
    if not isinstance(exercise_id, str):
        raise UnknownExerciseError(
            f"exercise_id: expected a string such as 'glr-3', "
            f"got {type(exercise_id).__name__} {exercise_id!r}"
        )
    if exercise_id not in EXERCISES:
        close = difflib.get_close_matches(exercise_id, list(EXERCISES), n=3)
        hint = f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""
        raise UnknownExerciseError(
            f"exercise_id: no exercise {exercise_id!r}{hint} (known: {', '.join(EXERCISES)})"
        )
    return EXERCISES[exercise_id]


def exercises(chapter: str | None = None) -> list[Exercise]:
    """All exercises, or those of one chapter (a key of :data:`CHAPTERS`), in book order."""
    if chapter is not None and chapter not in CHAPTERS:
        raise ModelError(f"chapter: expected one of {list(CHAPTERS)}, got {chapter!r}")
    return [e for e in _LIST if chapter is None or e.chapter == chapter]


def exercise_ids(checkable: bool | None = None) -> list[str]:
    """Identifiers in book order: all, or only the checkable ones (``True``) or the others."""
    return [e.id for e in _LIST if checkable is None or e.checkable == checkable]


def exercise_data(exercise_id: str, student: str | None = None) -> ExerciseData:
    """The data an exercise works on (a fresh copy).

    Parameters
    ----------
    exercise_id : str
    student : str, optional
        A student's identifier: that student's variant, drawn from :func:`student_seed`
        (identical on every call and machine). Default: the environment variable
        ``FDI_STUDENT_ID`` if set, else the book's data.

    Returns an empty :class:`ExerciseData` for an exercise that brings no data of its own.
    """
    ex = get_exercise(exercise_id)
    raw = ex.data(student_rng(exercise_id, student_id(student))) if ex.data is not None else {}
    return ExerciseData(
        {k: np.array(v) if isinstance(v, np.ndarray) else v for k, v in raw.items()}
    )


def reference_answer(exercise_id: str, student: str | None = None) -> np.ndarray:
    """The reference answer of a checkable exercise, for the book's data or a student's
    (instructor package only).

    Raises
    ------
    ReferenceNotShippedError
        In the student package, which holds no reference answer and no reference code.
    ModelError
        The exercise is not checkable.
    """
    try:
        from fdi_lib.exercises._reference import reference_answer as answer
    except ImportError:
        get_exercise(exercise_id)
        raise ReferenceNotShippedError(
            f"reference_answer: reference answers are not shipped in the student package "
            f"(asked for {exercise_id!r}); the instructor's grader holds them"
        ) from None
    return answer(exercise_id, student)
