"""Hand grading: a rubric for every hand-graded item, in the instructor's edition only, and the
course plans of the instructor page (``fdi_lib.exercises.COURSE_PLANS``, book/instructor.md)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from fdi_lib.errors import ModelError
from fdi_lib.exercises import (
    CHAPTERS,
    COURSE_PLANS,
    EXERCISES,
    HAND_GRADED,
    WRITE_UP_MINUTES,
    PlanWeek,
    UnknownExerciseError,
    exercise_ids,
    homework_minutes,
    parse_chapter,
    plan_table,
    strip_solutions,
)

BOOK = Path(__file__).resolve().parents[1] / "book"
_RUBRIC = re.compile(
    r"^\*\*Rubric\*\* \(instructor's edition only; hand-graded, (\d+) points\): "
    r"((?:[^\n]+\n)*?[^\n]+)\n\n"
    r"(?P<criteria>(?:\* .+\n(?:  .+\n)*)+)\n\*Model answer:\* \S",
    re.M,
)
_POINTS = re.compile(r"^\* \*\*(\d+)\*\* points?: ", re.M)


@pytest.fixture(scope="module")
def solutions() -> dict[str, str]:
    return {
        ex.id: ex.solution
        for chapter in CHAPTERS
        for ex in parse_chapter((BOOK / f"{chapter}.md").read_text())
    }


def test_every_hand_graded_item_has_one_rubric_with_its_points(solutions):
    hand = set(HAND_GRADED) | {e.id for e in EXERCISES.values() if not e.checkable}
    assert len(hand) == 22 and set(HAND_GRADED) <= {e.id for e in EXERCISES.values() if e.checkable}
    for exercise_id, solution in solutions.items():
        rubrics = list(_RUBRIC.finditer(solution))
        assert len(rubrics) == (exercise_id in hand), exercise_id
        assert solution.count("**Rubric**") == len(rubrics), exercise_id  # none malformed
        for m in rubrics:
            points = [int(p) for p in _POINTS.findall(m["criteria"])]
            assert len(points) >= 2 and sum(points) == int(m.group(1)), exercise_id
            assert int(m.group(1)) == (
                10 if EXERCISES[exercise_id].difficulty == "challenge" else 3
            )


def test_the_student_edition_has_no_rubric():
    for chapter in CHAPTERS:
        text = (BOOK / f"{chapter}.md").read_text()
        assert "**Rubric**" in text and "**Rubric**" not in strip_solutions(text)
        assert "Model answer" not in strip_solutions(text)


def _hours(week: PlanWeek) -> float:
    """Hours of homework of a week, recomputed from the registry's estimates (an independent sum)."""
    minutes = week.reading + sum(m for _, m in week.other)
    for i in week.exercises:
        minutes += EXERCISES[i].minutes + (
            WRITE_UP_MINUTES if EXERCISES[i].difficulty == "challenge" else 0
        )
    challenges = [e.minutes for e in EXERCISES.values() if e.difficulty == "challenge"]
    minutes += {"": 0, "experiment": max(challenges), "write-up": WRITE_UP_MINUTES}[
        week.own_challenge
    ]
    return minutes / 60


def test_the_plans_are_the_ten_and_six_week_courses():
    assert list(COURSE_PLANS) == ["10 weeks", "6 weeks"]


@pytest.mark.parametrize("name", list(COURSE_PLANS))
def test_plans_give_two_to_four_hours_a_week(name):
    plan = COURSE_PLANS[name]
    assert len(plan) == int(name.split()[0])  # the name says how many weeks
    rendered = plan_table(plan)
    assert [label for label, _ in rendered.rows] == [f"week {n}" for n in range(1, len(plan) + 1)]
    assert rendered.columns[-1] == "homework (h)"
    for week, (_label, cells) in zip(plan, rendered.rows):
        assert 2 <= _hours(week) <= 4, week.topic
        assert homework_minutes(week) == pytest.approx(60 * _hours(week), abs=1e-9)
        assert float(cells[-1]) == pytest.approx(_hours(week), abs=0.05), week.topic
        assert cells[2] == (
            ", ".join(i for i in week.exercises if EXERCISES[i].checkable) or "none"
        )


@pytest.mark.parametrize("name", list(COURSE_PLANS))
def test_plans_set_known_exercises_at_most_once(name):
    ids = [i for week in COURSE_PLANS[name] for i in week.exercises]
    assert set(ids) <= set(exercise_ids())
    assert len(ids) == len(set(ids))
    assert all(week.chapter in CHAPTERS for week in COURSE_PLANS[name])


def test_what_each_plan_covers():
    """What the instructor page says of each plan."""
    ten, six = COURSE_PLANS["10 weeks"], COURSE_PLANS["6 weeks"]
    assert sorted(i for week in ten for i in week.exercises) == sorted(exercise_ids())
    weeks = [sum(w.chapter == c for w in ten) for c in CHAPTERS]
    assert weeks == [2, 2, 2, 1, 1, 1, 1]  # ZB2014's chapters two weeks each, then one each
    for n, week in enumerate(
        ten
    ):  # a chapter's exercises in its week(s), its challenge up to a week later
        for i in week.exercises:
            first = next(m for m, w in enumerate(ten) if w.chapter == EXERCISES[i].chapter)
            assert first <= n <= first + weeks[list(CHAPTERS).index(EXERCISES[i].chapter)], i
    papers = {week.chapter for week in six}  # the six chapters of the papers, one a week
    assert len(papers) == len(six) == 6 and "windturbine/benchmark" not in papers
    assert sorted(i for week in six for i in week.exercises) == sorted(
        e.id for e in EXERCISES.values() if e.difficulty != "challenge" and e.chapter in papers
    )
    assert [w.own_challenge for w in six][-2:] == ["experiment", "write-up"]


def test_a_plan_with_an_unknown_or_repeated_exercise_fails():
    week = COURSE_PLANS["6 weeks"][0]
    with pytest.raises(UnknownExerciseError, match="sig-99"):
        plan_table((PlanWeek(week.topic, week.chapter, week.sections, 60, ("sig-1", "sig-99")),))
    with pytest.raises(ModelError, match=r"at most once.*\['sig-2'\]"):
        plan_table((week, PlanWeek("again", "zb2014/glr", "the whole chapter", 60, ("sig-2",))))
    with pytest.raises(ModelError, match="chapter: expected one of"):
        PlanWeek("x", "zb2014/nowhere", "the whole chapter", 60, ())
    with pytest.raises(ModelError, match="own_challenge: expected one of"):
        PlanWeek("x", "zb2014/glr", "the whole chapter", 60, (), own_challenge="essay")
