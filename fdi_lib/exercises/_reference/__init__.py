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

from fdi_lib.errors import FDIError, ModelError

__all__ = ["Mistake", "Reference", "REFERENCES", "reference_answer", "feedback_candidates"]


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
        raise ModelError(f"exercise_id: {exercise_id!r} has no checkable answer (it asks for an "
                         "explanation): compare with its solution")
    return _answers(exercise_id, student_id(student))


@functools.lru_cache(maxsize=256)
def _answers(exercise_id: str, student: str | None) -> np.ndarray:
    from fdi_lib.exercises import exercise_data

    return _frozen(REFERENCES[exercise_id].answer(exercise_data(exercise_id, student=student)))


def _frozen(value: Any) -> np.ndarray:
    arr = np.array(value, dtype=float)
    arr.setflags(write=False)
    return arr


def feedback_candidates(exercise_id: str, student: str | None = None
                        ) -> tuple[np.ndarray, tuple[tuple[str, np.ndarray], ...]]:
    """The reference and the wrong answers :func:`~fdi_lib.exercises.check` recognises, in the
    order it tries them: the exercise's own mistakes, the generic transformations of the
    reference (:func:`fdi_lib.exercises.checker.generic_candidates`) and the index shifts (the
    reference recomputed with a time index of the data moved by one sample).

    Candidates that equal the reference within the tolerance, or have another shape, or are not
    finite, are left out.
    """
    from fdi_lib.exercises._core import student_id

    return _feedback_candidates(exercise_id, student_id(student))


@functools.lru_cache(maxsize=256)
def _feedback_candidates(exercise_id: str, student: str | None
                         ) -> tuple[np.ndarray, tuple[tuple[str, np.ndarray], ...]]:
    from fdi_lib.exercises import exercise_data, get_exercise
    from fdi_lib.exercises.checker import close, generic_candidates

    ex = get_exercise(exercise_id)
    ref = _answers(exercise_id, student)
    out = [(m.hint, np.array(m.answer(exercise_data(exercise_id, student=student)), dtype=float))
           for m in REFERENCES[exercise_id].mistakes]
    out += generic_candidates(ex, ref)
    for key in ex.time_keys:
        for step, word in ((1, "one larger"), (-1, "one smaller")):
            data = exercise_data(exercise_id, student=student)
            data[key] = data[key] + step
            try:
                shifted = np.array(REFERENCES[exercise_id].answer(data), dtype=float)
            except (FDIError, ValueError, IndexError):   # the shifted index leaves the horizon
                continue
            out.append((f"This is the answer with `{key}` {word}: an index shift (off by one in "
                        "time); count the samples as the exercise does.", shifted))
    return ref, tuple((hint, _frozen(value)) for hint, value in out
                      if value.shape == ref.shape and np.all(np.isfinite(value))
                      and not np.all(close(value, ref, ex)))
