"""Instructor side of the exercises: reference answers, known mistakes, and the library calls
that answer an exercise in one line.

This sub-package is what the student package leaves out (``tools/student_package.py``): without
it, :func:`fdi_lib.exercises.reference_answer` raises
:class:`~fdi_lib.exercises.ReferenceNotShippedError` and :func:`fdi_lib.exercises.check`
compares with salted digests instead (:mod:`fdi_lib.exercises.checker`). One module per
chapter, beside the chapter's statement module of the same name.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from fdi_lib.errors import ModelError

__all__ = ["Mistake", "Reference", "REFERENCES", "reference_answer"]


@dataclass(frozen=True)
class Mistake:
    """A typical wrong answer of one exercise and the hint shown when a student gives it.

    Attributes
    ----------
    answer : callable
        ``data -> value``: the wrong answer, computed from the exercise data like the reference.
    hint : str
        What went wrong, without the correct value.
    """

    answer: Callable[[dict], Any]
    hint: str


@dataclass(frozen=True)
class Reference:
    """How to answer one checkable exercise.

    Attributes
    ----------
    answer : callable
        ``data -> value``: the reference answer, by library code (never typed).
    mistakes : tuple of Mistake
        Known wrong answers, each with its hint.
    one_call : tuple of str
        Dotted names of library functions that return the answer (or all of its hard part) in
        one call; the grader makes them raise inside the student's code
        (``tools/grader.py``). Functions the book's own solution calls are not listed.
    """

    answer: Callable[[dict], Any]
    mistakes: tuple[Mistake, ...] = ()
    one_call: tuple[str, ...] = ()


def _collect() -> dict[str, Reference]:
    from fdi_lib.exercises._reference import bz, glr, pipeline, signature, sparse, svo, windturbine

    out: dict[str, Reference] = {}
    for module in (signature, glr, pipeline, sparse, bz, svo, windturbine):
        out.update(module.REFERENCES)
    return out


#: Reference of every checkable exercise, by identifier.
REFERENCES: dict[str, Reference] = _collect()


def reference_answer(exercise_id: str, student: str | None = None) -> np.ndarray:
    """The reference answer of a checkable exercise on the book's data or on ``student``'s data
    (a read-only float array, cached)."""
    from fdi_lib.exercises import get_exercise
    from fdi_lib.exercises._core import student_id

    ex = get_exercise(exercise_id)
    if not ex.checkable:
        raise ModelError(
            f"exercise_id: {exercise_id!r} has no checkable answer (it asks for an "
            "explanation): compare with its solution"
        )
    return _answers(exercise_id, student_id(student))


@functools.lru_cache(maxsize=256)
def _answers(exercise_id: str, student: str | None) -> np.ndarray:
    from fdi_lib.exercises import exercise_data

    answer = _frozen(REFERENCES[exercise_id].answer(exercise_data(exercise_id, student=student)))
    if not np.all(np.isfinite(answer)):  # a numerical failure is never a reference to grade by
        raise ModelError(
            f"reference_answer: the reference of {exercise_id!r} for student {student!r} is not "
            f"finite ({answer.tolist()}): the exercise's data for this student are degenerate"
        )
    return answer


def _frozen(value: Any) -> np.ndarray:
    arr = np.array(value, dtype=float)
    arr.setflags(write=False)
    return arr
