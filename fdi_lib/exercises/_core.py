"""Types of the exercise registry, its errors (defined in :mod:`fdi_lib.errors`), the per-student
seed.

Shipped in the student package: nothing here knows a reference answer.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from fdi_lib.errors import AnswerError, ReferenceNotShippedError, UnknownExerciseError

__all__ = [
    "DIFFICULTIES",
    "CHAPTERS",
    "STUDENT_ENV",
    "UnknownExerciseError",
    "AnswerError",
    "ReferenceNotShippedError",
    "Exercise",
    "ExerciseData",
    "CheckResult",
    "student_id",
    "student_seed",
    "student_rng",
    "uniform",
    "rounded_normal",
]

#: Difficulty labels, in increasing order.
DIFFICULTIES = ("warm-up", "core", "challenge")

#: Chapters with exercises: document path under ``book/`` -> title (as in the table of contents).
CHAPTERS = {
    "zb2014/signature": "Fault signature on the Kalman innovation",
    "zb2014/glr": "GLR and minmax tests",
    "zb2014/pipeline": "Leak detection on a gas pipeline",
    "zhang2021/sparse": "Sparse fault isolation",
    "bz/parametric-nonparametric": "Parametric and non-parametric faults",
    "rosa2013/svo": "Set-valued observers",
    "windturbine/benchmark": "Four methods on the wind-turbine benchmark",
}

#: Environment variable holding a student's identifier: when set (and no ``student`` argument is
#: given), :func:`~fdi_lib.exercises.exercise_data` and :func:`~fdi_lib.exercises.check` work on
#: that student's data. The grader sets it in the kernel that runs a submission.
STUDENT_ENV = "FDI_STUDENT_ID"


@dataclass(frozen=True)
class Exercise:
    """One exercise of the book: what the student sees (no reference answer).

    Attributes
    ----------
    id : str
        Identifier, ``"<chapter prefix>-<number>"``; the exercise's label in the chapter is
        ``"ex-" + id``.
    chapter : str
        Document path under ``book/`` (a key of :data:`CHAPTERS`).
    title : str
        Title printed in the chapter.
    difficulty : str
        One of :data:`DIFFICULTIES`.
    minutes : int
        Estimated working time for a student who has read the chapter.
    answer : str or None
        What :func:`~fdi_lib.exercises.check` expects (e.g. ``"array of shape (2,): [eps_0,
        eps_1]"``); ``None`` for an exercise whose answer is an explanation (not checkable).
    rtol, atol : float
        Tolerance of the check: ``|answer - reference| <= atol + rtol |reference|`` entrywise.
    data : callable or None
        ``rng -> dict``: the exercise's data; ``rng`` is ``None`` for the book's data, a
        :class:`numpy.random.Generator` seeded by :func:`student_seed` for a student's own.
    time_keys : tuple of str
        Keys of the data that are time indices (a shift by one of these is an "index shift").
    """

    id: str
    chapter: str
    title: str
    difficulty: str
    minutes: int
    answer: str | None = None
    rtol: float = 1e-6
    atol: float = 0.0
    data: Callable[[np.random.Generator | None], dict] | None = field(
        default=None, repr=False, compare=False
    )
    time_keys: tuple[str, ...] = ()

    @property
    def checkable(self) -> bool:
        """Whether :func:`~fdi_lib.exercises.check` can verify an answer."""
        return self.answer is not None

    @property
    def integer(self) -> bool:
        """Whether the answer is a count (integers): tolerance ``rtol = 0, atol = 0.5``."""
        return self.rtol == 0 and self.atol == 0.5

    @property
    def tolerance(self) -> str:
        """The tolerance in words."""
        if self.rtol == 0 and self.atol == 0:
            return "exact"
        if self.integer:
            return "exact (integers)"
        parts = []
        if self.rtol:
            parts.append(f"relative {self.rtol:g}")
        if self.atol:
            parts.append(f"absolute {self.atol:g}")
        return " + ".join(parts)


class ExerciseData(dict):
    """The data of an exercise: a dict whose display lists ``name = value`` lines."""

    def __repr__(self) -> str:
        lines = []
        for key, val in self.items():
            if hasattr(val, "n_steps"):  # a model: its dimensions, not its matrices
                text = f"{type(val).__name__}(n={val.n}, p={val.p}, N={val.n_steps})"
            elif isinstance(val, np.ndarray):
                text = np.array2string(val, precision=6, suppress_small=False, separator=", ")
                text = text.replace("\n", "\n" + " " * (len(key) + 3))
            else:
                text = repr(val)
            lines.append(f"{key} = {text}")
        return "\n".join(lines)


@dataclass(frozen=True)
class CheckResult:
    """Outcome of :func:`~fdi_lib.exercises.check`; true when the answer is accepted, displayed as
    its message."""

    exercise_id: str
    passed: bool
    message: str

    def __bool__(self) -> bool:
        return self.passed

    def __repr__(self) -> str:
        return self.message

    __str__ = __repr__


def student_id(student: str | None = None) -> str | None:
    """The student whose data are meant: ``student`` if given, else the environment variable
    :data:`STUDENT_ENV`, else ``None`` (the book's data). An empty string means ``None``."""
    if student is None:
        student = os.environ.get(STUDENT_ENV)
    if student is not None and not isinstance(student, str):
        raise TypeError(f"student: expected a string identifier, got {type(student).__name__}")
    return student.strip() or None if student is not None else None


def student_seed(exercise_id: str, student: str) -> int:
    """The seed of a student's data: the first 8 bytes (little-endian) of
    ``sha256("fdi-book/<exercise id>/<student id>")``.

    A stable hash (not Python's salted ``hash``): the same on every machine and run, different
    for neighbours and for each exercise of one student.
    """
    digest = hashlib.sha256(f"fdi-book/{exercise_id}/{student}".encode()).digest()
    return int.from_bytes(digest[:8], "little")


def student_rng(exercise_id: str, student: str | None) -> np.random.Generator | None:
    """The generator a data function draws a student's variant from (``None``: the book's data)."""
    return None if student is None else np.random.default_rng(student_seed(exercise_id, student))


def uniform(rng: np.random.Generator, low: float, high: float, decimals: int = 2) -> float:
    """A value drawn uniformly in ``[low, high]``, rounded (data a student can read and type)."""
    return round(float(rng.uniform(low, high)), decimals)


def rounded_normal(
    rng: np.random.Generator, shape: Any, scale: float = 1.0, decimals: int = 2
) -> np.ndarray:
    """Standard normal entries times ``scale``, rounded to ``decimals`` (a readable array)."""
    return np.round(scale * rng.standard_normal(shape), decimals)
