"""The checker: :func:`check` with its feedback patterns and its graded mode.

Two sources of truth, one message logic:

* **Instructor package** (the repository, the full book): the reference answers are computed by
  :mod:`fdi_lib.exercises._reference`, and a wrong answer gets the full self-study diagnosis
  (which entries, the sign, the order of magnitude, "close but outside the tolerance").
* **Student package** (the wheel of ``make student``): ``_reference`` is not shipped. The wheel
  holds instead ``_digests.json``, written when the wheel is staged
  (``tools/student_package.py``): for the book's data of every checkable exercise, the reference
  and each recognised wrong answer as salted, slow (PBKDF2) hashes of tolerance buckets, entry by
  entry. :func:`check` hashes the student's entries the same way and compares. It can say
  "correct", name a recognised mistake, a swap, a shift, or which entries are off, but it has no
  number to compare with, so it gives no direction (no "too large", no "close"): nothing to
  bisect on. The trade-offs, stated plainly:

  - a bucket is accepted with its neighbours, so the wheel accepts answers up to about twice the
    exercise's tolerance (the instructor's grader applies the exact tolerance);
  - the digests protect the *values*, not the exercise: anyone can hash guesses offline, at about
    a millisecond per guess and entry (PBKDF2, 1000 rounds). A scalar known to a few digits is
    found by search, a 1e-6 bucket of an unknown number is not (millions of guesses per decade).
    The answers that count for a grade are on each student's own data (:func:`exercise_data`
    with a student id), whose digests the wheel does not hold, and are graded by
    ``tools/grader.py`` with hidden runs.

The graded mode (``check(id, answer, graded=True)``) says only accepted / not accepted with the
attempt number, the same sentence for every wrong answer, in both packages.
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import json
import math
from dataclasses import dataclass
from importlib import resources
from typing import Any

import numpy as np

from fdi_lib.errors import FDIError, ModelError
from fdi_lib.exercises._core import (
    AnswerError,
    CheckResult,
    Exercise,
    ReferenceNotShippedError,
    student_id,
)

__all__ = [
    "check",
    "generic_candidates",
    "feedback_candidates",
    "close",
    "zero_floor",
    "attempts",
    "entry_keys",
    "entry_digest",
    "DIGEST_ROUNDS",
    "DIGESTS_FILE",
]

#: The student package's reference digests (a file of the package, absent from the repository).
DIGESTS_FILE = "_digests.json"
#: PBKDF2-SHA256 rounds of an entry digest: about a millisecond per guess.
DIGEST_ROUNDS = 1000

_ATTEMPTS: dict[tuple[str, str | None], int] = {}


def attempts(exercise_id: str, student: str | None = None) -> int:
    """How many graded-mode answers (not ``None``) this session has checked for ``exercise_id``."""
    return _ATTEMPTS.get((exercise_id, student_id(student)), 0)


# ----------------------------------------------------------------------------- generic patterns
#: Constant factors a wrong answer often carries, with what they usually mean.
FACTORS: tuple[tuple[float, str], ...] = (
    (-1.0, "The sign is wrong."),
    (
        2.0,
        "It is twice the expected value: a factor 2 (a term counted twice, a two-sided bound for "
        "a one-sided one, or a 1/2 dropped).",
    ),
    (
        0.5,
        "It is half the expected value: a factor 1/2 (a 1/2 too many, or a one-sided bound for a "
        "two-sided one).",
    ),
    (100.0, "It looks like a percentage where a fraction is expected (a factor 100)."),
    (0.01, "It looks like a fraction where a percentage is expected (a factor 1/100)."),
    (1000.0, "It is off by a factor 1000: a unit slip (ms for s, m for km, ...)?"),
    (0.001, "It is off by a factor 1/1000: a unit slip (s for ms, km for m, ...)?"),
    (180.0 / math.pi, "It looks like degrees where radians are expected."),
    (math.pi / 180.0, "It looks like radians where degrees are expected."),
    (60.0, "It is off by a factor 60: minutes and seconds (or hours and minutes) mixed up?"),
    (
        1.0 / 60.0,
        "It is off by a factor 1/60: minutes and seconds (or hours and minutes) mixed up?",
    ),
    (math.log(10.0), "It is off by a factor ln 10: a natural logarithm where log10 is meant?"),
    (
        1.0 / math.log(10.0),
        "It is off by a factor 1/ln 10: log10 where a natural logarithm is meant?",
    ),
)


def generic_candidates(ex: Exercise, ref: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """Wrong answers recognised in every exercise, computed from the reference: constant factors
    (:data:`FACTORS`), squares and square roots, a probability replaced by its complement, and a
    count off by one."""
    out = [(hint, factor * ref) for factor, hint in FACTORS]
    if np.all(ref > 0):
        out.append(
            (
                "It looks like the square of the expected value (a variance for a standard "
                "deviation, ||.||^2 for ||.||)?",
                ref**2,
            )
        )
        out.append(
            (
                "It looks like the square root of the expected value (a standard deviation for "
                "a variance, ||.|| for ||.||^2)?",
                np.sqrt(ref),
            )
        )
    prob = (ref > 0) & (ref < 1)
    if np.any(prob) and not ex.integer:
        out.append(
            (
                "A probability is replaced by its complement 1 - p (a miss probability for a "
                "power, a lower tail for an upper tail)?",
                np.where(prob, 1.0 - ref, ref),
            )
        )
    if ex.integer:
        for step in (1, -1):
            out.append(
                ("Off by one: check whether both ends (or the empty case) are counted.", ref + step)
            )
    return out


def _permutations(shape: tuple[int, ...]) -> list[tuple[str, np.ndarray]]:
    """Index maps of entries in the wrong place: ``a.ravel()[j]`` is reference entry ``perm[j]``."""
    n = int(np.prod(shape))
    flat = np.arange(n)
    out = []
    if len(shape) == 2 and shape[0] == shape[1] > 1:
        out.append(
            (
                "It matches the transpose of the expected matrix: look for a missing or extra "
                "transpose.",
                flat.reshape(shape).T.ravel(),
            )
        )
    for i, j in itertools.combinations(range(n), 2):
        perm = flat.copy()
        perm[[i, j]] = perm[[j, i]]
        where = [_index_text(tuple(int(v) for v in np.unravel_index(k, shape))) for k in (i, j)]
        out.append(
            (
                f"Entries {where[0]} and {where[1]} are swapped: check the order the exercise "
                "asks for.",
                perm,
            )
        )
    if len(shape) == 1 and n >= 3:
        out.append(("The entries are in reverse order.", flat[::-1].copy()))
    return out


def zero_floor(ref: np.ndarray, ex: Exercise) -> float:
    """How far from an exact zero of ``ref`` an answer may be: ``rtol`` times the array's scale
    (its largest ``|entry|`` rounded up to a power of 10), so that a zero computed as 1e-17 is
    zero; 0 for an all-zero reference. Rounded to a decade: the student package stores it."""
    top = float(np.max(np.abs(ref))) if np.size(ref) else 0.0
    return 0.0 if top == 0 or not np.isfinite(top) else ex.rtol * 10.0 ** math.ceil(math.log10(top))


def close(a: np.ndarray, ref: np.ndarray, ex: Exercise, floor: float | None = None) -> np.ndarray:
    """Entrywise ``|a - ref| <= atol + rtol |ref|``, or both ``|a|`` and ``|ref|`` at most
    ``floor`` (:func:`zero_floor` of the whole reference: both numerically zero, such as an exact
    zero computed as 1e-17). The one tolerance of the exercises: the checker, its digests
    (:func:`entry_keys`) and the grader all use it."""
    ref = np.asarray(ref, dtype=float)
    floor = zero_floor(ref, ex) if floor is None else floor
    with np.errstate(
        over="ignore", invalid="ignore"
    ):  # |a - ref| beyond the float range: not close
        return (np.abs(a - ref) <= ex.atol + ex.rtol * np.abs(ref)) | (
            (np.abs(ref) <= floor) & (np.abs(a) <= floor)
        )


# ----------------------------------------------------------------------------- digests
#: Buckets per tolerance width: a bucket is an eighth of the tolerance.
FINE = 8


def _bucket(value: float, ex: Exercise, floor: float) -> str:
    """The key of the bucket of ``value``."""
    if abs(value) <= floor:
        return "z"
    if ex.atol > 0 and abs(value) <= ex.atol / ex.rtol:
        return f"l{math.floor(value / (ex.atol / FINE))}"
    k = math.floor(math.log(max(abs(value), 5e-324)) / (math.log1p(ex.rtol) / FINE))
    return f"+{k}" if value > 0 else f"-{k}"


def _buckets_meeting(lo: float, hi: float, ex: Exercise):
    """``(key, low edge, high edge)`` of the linear and logarithmic buckets meeting ``[lo, hi]``."""
    split = ex.atol / ex.rtol if ex.atol > 0 else 0.0
    if split > 0 and lo <= split and hi >= -split:
        h = ex.atol / FINE
        for k in range(math.floor(max(lo, -split) / h), math.floor(min(hi, split) / h) + 1):
            yield f"l{k}", k * h, (k + 1) * h
    w = math.log1p(ex.rtol) / FINE
    for sign, a, b in ((1, max(lo, split), hi), (-1, max(-hi, split), -lo)):
        if b > split and b >= a and b > 0:
            first, last = math.floor(math.log(max(a, 5e-324)) / w), math.floor(math.log(b) / w)
            for k in range(first, last + 1):
                e0, e1 = math.exp(k * w), math.exp((k + 1) * w)
                yield (f"+{k}", e0, e1) if sign > 0 else (f"-{k}", -e1, -e0)


def entry_keys(value: float, ex: Exercise, *, around: bool = False, floor: float = 0.0) -> set[str]:
    """Tolerance buckets of one entry: the bucket of ``value`` or, with ``around``, every bucket
    that lies wholly within the tolerance of ``value`` (:func:`close`, with the reference's
    :func:`zero_floor` ``floor``).

    Integers are their own bucket, an exact exercise its ``repr``. A bucket is an eighth of the
    tolerance: intervals of width ``atol / 8`` where the absolute tolerance dominates (``|v| <=
    atol / rtol``), logarithmic buckets of width ``log(1 + rtol) / 8`` beyond, ``"z"`` within
    ``floor`` of zero. As only buckets wholly within the tolerance are stored, the student
    package never accepts an answer the grader rejects; it rejects an answer within an eighth of
    the tolerance's edge that the grader accepts.
    """
    if ex.integer:
        return {f"i{round(value)}"}
    if ex.rtol == 0:
        return {repr(float(value))}
    if not around:
        return {_bucket(value, ex, floor)}
    if abs(value) <= floor:  # numerically zero: so is every answer within the floor
        return {"z"}
    tol = ex.atol + ex.rtol * abs(value)
    ref = np.array([value])
    keys = set()
    for key, lo, hi in _buckets_meeting(value - tol, value + tol, ex):
        edges = np.array([lo, np.nextafter(hi, lo)])
        if (abs(lo) > floor or abs(hi) > floor) and np.all(close(edges, ref, ex, floor)):
            keys.add(key)
    return keys


def entry_digest(salt: str, exercise_id: str, student: str, index: int, key: str) -> str:
    """Salted PBKDF2 digest of one entry's bucket (hex, 16 characters)."""
    return hashlib.pbkdf2_hmac(
        "sha256",
        f"{exercise_id}|{student}|{index}|{key}".encode(),
        bytes.fromhex(salt),
        DIGEST_ROUNDS,
    )[:8].hex()


@dataclass(frozen=True)
class _Digests:
    """What the student package knows of one exercise for one student."""

    salt: str
    student: str
    shape: tuple[int, ...]
    floor: float
    reference: list[set[str]]
    candidates: list[tuple[str, list[set[str]]]]


def _load_digests() -> dict | None:
    try:
        text = resources.files("fdi_lib.exercises").joinpath(DIGESTS_FILE).read_text()
    except (FileNotFoundError, OSError):
        return None
    return json.loads(text)


# ----------------------------------------------------------------------------- oracles
class _Values:
    """Compares with values (instructor package); the wrong answers it recognises are computed
    on the first wrong answer only (a correct answer costs one reference)."""

    exact = True

    def __init__(self, ex: Exercise, ref: np.ndarray, student: str | None):
        self.ex, self.ref, self.shape, self.student = ex, ref, ref.shape, student

    @functools.cached_property
    def candidates(self) -> list[tuple[str, np.ndarray]]:
        return [
            (hint, value.ravel())
            for hint, value in feedback_candidates(self.ex.id, self.student)[1]
        ]

    def match(
        self, which: int | None, flat: np.ndarray, perm: np.ndarray | None = None
    ) -> np.ndarray:
        target = self.ref.ravel() if which is None else self.candidates[which][1]
        return close(flat, target if perm is None else target[perm], self.ex)


class _Hashes:
    """Compares with digests (student package)."""

    exact = False

    def __init__(self, ex: Exercise, d: _Digests):
        self.ex, self.d, self.shape = ex, d, d.shape
        self.candidates = d.candidates
        self._memo: dict[tuple[int, float], str] = {}

    def _digest(self, index: int, value: float) -> str:
        if (index, value) not in self._memo:
            (key,) = entry_keys(value, self.ex, floor=self.d.floor)
            self._memo[index, value] = entry_digest(
                self.d.salt, self.ex.id, self.d.student, index, key
            )
        return self._memo[index, value]

    def match(
        self, which: int | None, flat: np.ndarray, perm: np.ndarray | None = None
    ) -> np.ndarray:
        sets = self.d.reference if which is None else self.candidates[which][1]
        idx = np.arange(flat.size) if perm is None else perm
        return np.array([self._digest(int(i), float(v)) in sets[int(i)] for v, i in zip(flat, idx)])


def _oracle(ex: Exercise, student: str | None):
    """The comparison source: values when the reference modules are installed, else digests
    (``None`` when the package has no digests for this student)."""
    try:
        from fdi_lib.exercises._reference import reference_answer
    except ImportError:
        pass
    else:
        return _Values(ex, reference_answer(ex.id, student), student)
    table = _load_digests()
    if table is None and student is not None:
        return None  # a student's data: the grader's, never the package's
    if table is None:
        raise ReferenceNotShippedError(
            "check: this package has neither the reference answers nor "
            f"their digests ({DIGESTS_FILE}); reinstall the student package"
        )
    rec = table["students"].get(student or "", {}).get(ex.id)
    if rec is None:
        return None
    as_sets = lambda entries: [set(e) for e in entries]  # noqa: E731
    return _Hashes(
        ex,
        _Digests(
            salt=table["salt"],
            student=student or "",
            shape=tuple(rec["shape"]),
            floor=float(rec.get("floor", 0.0)),
            reference=as_sets(rec["reference"]),
            candidates=[(c["hint"], as_sets(c["entries"])) for c in rec["candidates"]],
        ),
    )


# ----------------------------------------------------------------------------- check
def _as_answer(answer: Any, exercise_id: str) -> np.ndarray:
    if isinstance(answer, (str, bytes, dict, set)):
        raise AnswerError(
            f"answer: expected a real number or array for {exercise_id!r}, "
            f"got {type(answer).__name__}"
        )
    try:
        arr = np.array(answer)
    except (TypeError, ValueError) as exc:
        raise AnswerError(
            f"answer: expected a real number or array for {exercise_id!r}, "
            f"got {type(answer).__name__} that numpy cannot read ({exc})"
        ) from None
    if arr.dtype == object or arr.dtype.kind not in "biuf":
        raise AnswerError(
            f"answer: expected real numbers for {exercise_id!r}, got an array of "
            f"{'complex numbers' if arr.dtype.kind == 'c' else arr.dtype}"
        )
    arr = arr.astype(float)
    if not np.all(np.isfinite(arr)):
        idx = tuple(int(i) for i in np.argwhere(~np.isfinite(arr))[0]) if arr.ndim else ()
        where = f" at index {list(idx)}" if idx else ""
        raise AnswerError(
            f"answer: expected finite numbers for {exercise_id!r}, got "
            f"{float(arr[idx]) if idx else float(arr)}{where}"
        )
    return arr


def _scalar_diagnosis(a: float, ref: float, ex: Exercise) -> str:
    if ref != 0 and a != 0 and np.sign(a) != np.sign(ref):
        return "it has the wrong sign"
    if a == 0:
        return "it is zero, and should not be"
    if ref == 0:
        return "it should be zero"
    # the ratio's decades as a difference of logarithms: a / ref itself under- or overflows for
    # answers such as 5e-324 or 1e308 (the smallest subnormal, the largest decade of a double)
    decades = math.log10(abs(a)) - math.log10(abs(ref))
    if abs(decades) >= 0.95:
        word = "large" if decades > 0 else "small"
        return f"it is too {word} by about a factor 10^{abs(round(decades))}"
    ratio = abs(a / ref)
    if abs(ratio - 1) <= 0.1:
        return f"it is close (within 10 %) but outside the tolerance ({ex.tolerance})"
    return (
        f"it is too {'large' if ratio > 1 else 'small'}, with the right sign and order of magnitude"
    )


def _index_text(idx: tuple[int, ...]) -> str:
    return "[" + ", ".join(str(i) for i in idx) + "]"


def check(
    exercise_id: str, answer: Any, *, student: str | None = None, graded: bool = False
) -> CheckResult:
    """Check a student's answer to a checkable exercise.

    Parameters
    ----------
    exercise_id : str
        E.g. ``"glr-3"``; :data:`~fdi_lib.exercises.EXERCISES` lists them.
    answer : float, array_like or None
        The student's result. ``None`` (the starter cells' placeholder) is accepted and
        reported as "no answer yet".
    student : str, optional
        Whose data the answer is for (default: the environment variable ``FDI_STUDENT_ID``,
        else the book's data), as in :func:`~fdi_lib.exercises.exercise_data`.
    graded : bool
        Graded mode: the message is only "accepted" or "not accepted" with the attempt number,
        the same for every wrong answer (no hint, no direction); attempts are counted per
        exercise and student in this session (:func:`attempts`).

    Returns
    -------
    CheckResult
        True when every entry is within the exercise's tolerance of the reference; its message
        says what is wrong otherwise (shape, transpose, swapped entries, a constant factor or a
        unit slip, an index shift, a known mistake of the exercise, which entries are off and,
        in the instructor package, the sign and order of magnitude), never the reference value.

    Raises
    ------
    UnknownExerciseError
        ``exercise_id`` is not registered.
    ModelError
        The exercise is not checkable (its answer is an explanation).
    AnswerError
        ``answer`` is not a finite real number or array.

    Examples
    --------
    >>> check("glr-5", 98)
    glr-5: correct (tolerance: exact (integers)).
    >>> check("glr-5", 99)
    glr-5: not yet. Off by one: the candidates are k - w + 1 <= r <= k - s, both ends included.
    """
    from fdi_lib.exercises import get_exercise

    ex = get_exercise(exercise_id)
    if not ex.checkable:
        raise ModelError(
            f"exercise_id: {exercise_id!r} has no checkable answer (it asks for an "
            "explanation): compare with its solution"
        )
    student = student_id(student)
    if answer is None:
        return CheckResult(
            exercise_id,
            False,
            f"{exercise_id}: no answer yet. Replace `answer = None` by {ex.answer}.",
        )
    a = _as_answer(answer, exercise_id)
    oracle = _oracle(ex, student)
    fail = lambda msg: CheckResult(exercise_id, False, f"{exercise_id}: not yet. {msg}")  # noqa: E731
    if oracle is None:
        return fail(
            f"This package holds no reference for student {student!r}: your instructor's grader "
            f"checks answers on your own data (here the expected form is {ex.answer})."
        )
    if graded:
        n = _ATTEMPTS[exercise_id, student] = _ATTEMPTS.get((exercise_id, student), 0) + 1
        ok = (
            a.size == int(np.prod(oracle.shape))
            and (a.size == 1 or a.shape == oracle.shape)
            and bool(np.all(oracle.match(None, a.ravel())))
        )
        return CheckResult(
            exercise_id, ok, f"{exercise_id}: attempt {n}: {'accepted' if ok else 'not accepted'}."
        )
    shape = oracle.shape
    if a.size == 1 and int(np.prod(shape)) == 1:
        a = a.reshape(shape)
    if a.shape != shape:
        msg = f"Expected {ex.answer}; got shape {a.shape}."
        if a.ndim == 2 and a.T.shape == shape and np.all(oracle.match(None, a.T.ravel())):
            msg += " It matches once transposed: look for a missing or extra transpose."
        elif a.size == int(np.prod(shape)) and np.all(oracle.match(None, a.ravel())):
            msg += f" The numbers are right: reshape to {shape}."
        return fail(msg)
    if ex.integer and not np.all(a == np.round(a)):
        idx = tuple(int(i) for i in np.argwhere(a != np.round(a))[0])
        where = f" (entry {_index_text(idx)})" if a.ndim else ""
        return fail(
            f"Expected {ex.answer}; got {float(a[idx])!r}{where}, which is not a whole number "
            "(a count is an integer)."
        )
    flat = a.ravel()
    ok = oracle.match(None, flat)
    if np.all(ok):
        return CheckResult(
            exercise_id, True, f"{exercise_id}: correct (tolerance: {ex.tolerance})."
        )
    for which, (hint, _) in enumerate(oracle.candidates):
        if np.all(oracle.match(which, flat)):
            return fail(hint)
    for hint, perm in _permutations(shape):
        if np.all(oracle.match(None, flat, perm)):
            return fail(hint)
    if a.size > 2:  # the right numbers in some other order (a perfect matching of entries)
        import scipy.optimize

        hits = np.array([oracle.match(None, np.full(a.size, v), np.arange(a.size)) for v in flat])
        rows, cols = scipy.optimize.linear_sum_assignment(hits, maximize=True)
        if hits[rows, cols].all():
            return fail(
                "These are the right numbers in another order: check the order the exercise "
                "asks for."
            )
    if a.ndim == 1 and a.size >= 3:
        n = a.size
        if np.all(oracle.match(None, flat[1:], np.arange(n - 1))):
            return fail(
                "The series is one sample late: its entry [k] is the expected entry [k - 1] "
                "(an index shift; the first entry is k = 0)."
            )
        if np.all(oracle.match(None, flat[:-1], np.arange(1, n))):
            return fail(
                "The series is one sample early: its entry [k] is the expected entry [k + 1] "
                "(an index shift; the first entry is k = 0)."
            )
    bad = [tuple(int(i) for i in np.unravel_index(j, shape)) for j in np.flatnonzero(~ok)]
    where = ", ".join(_index_text(i) for i in bad[:4]) + (", ..." if len(bad) > 4 else "")
    if a.size > 1:  # the entries that are off match a known mistake or pattern, the rest is right
        for which, (hint, _) in enumerate(oracle.candidates):
            if np.all(oracle.match(which, flat[~ok], np.flatnonzero(~ok))):
                return fail(
                    f"{'Entry' if len(bad) == 1 else 'Entries'} {where} (the rest matches): {hint}"
                )
    if not oracle.exact:
        if a.size == 1:
            return fail("The value is off, and it is none of the mistakes this check knows.")
        return fail(f"{len(bad)} of {a.size} entries are off: {where}.")
    ref = oracle.ref
    if ref.size == 1:
        return fail(
            f"The value is off: {_scalar_diagnosis(float(flat[0]), float(ref.ravel()[0]), ex)}."
        )
    if len(bad) == 1:
        idx = bad[0]
        why = _scalar_diagnosis(float(a[idx]), float(ref[idx]), ex)
        return fail(f"Entry {_index_text(idx)} is off ({why}); the rest matches.")
    return fail(f"{len(bad)} of {a.size} entries are off: {where} (tolerance: {ex.tolerance}).")


def feedback_candidates(
    exercise_id: str, student: str | None = None
) -> tuple[np.ndarray, tuple[tuple[str, np.ndarray], ...]]:
    """The reference and the wrong answers :func:`~fdi_lib.exercises.check` recognises, in the
    order it tries them: the exercise's own mistakes, the generic transformations of the
    reference (:func:`fdi_lib.exercises.checker.generic_candidates`) and the index shifts (the
    reference recomputed with a time index of the data moved by one sample).

    Candidates that equal the reference within the tolerance, or have another shape, or are not
    finite, are left out.
    """
    return _feedback_candidates(exercise_id, student_id(student))


@functools.lru_cache(maxsize=256)
def _feedback_candidates(
    exercise_id: str, student: str | None
) -> tuple[np.ndarray, tuple[tuple[str, np.ndarray], ...]]:
    from fdi_lib.exercises import exercise_data, get_exercise
    from fdi_lib.exercises._reference import REFERENCES, _answers, _frozen

    ex = get_exercise(exercise_id)
    ref = _answers(exercise_id, student)
    out = [
        (m.hint, np.array(m.answer(exercise_data(exercise_id, student=student)), dtype=float))
        for m in REFERENCES[exercise_id].mistakes
    ]
    out += generic_candidates(ex, ref)
    for key in ex.time_keys:
        for step, word in ((1, "one larger"), (-1, "one smaller")):
            data = exercise_data(exercise_id, student=student)
            data[key] = data[key] + step
            try:
                shifted = np.array(REFERENCES[exercise_id].answer(data), dtype=float)
            except (FDIError, ValueError, IndexError):  # the shifted index leaves the horizon
                continue
            out.append(
                (
                    f"This is the answer with `{key}` {word}: an index shift (off by one in "
                    "time); count the samples as the exercise does.",
                    shifted,
                )
            )
    return ref, tuple(
        (hint, _frozen(value))
        for hint, value in out
        if value.shape == ref.shape
        and np.all(np.isfinite(value))
        and not np.all(close(value, ref, ex))
    )
