"""Hand grading: a rubric for every hand-graded item, in the instructor's edition only, and the
six- and ten-week plans of the instructor page (book/instructor.md)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from fdi_lib.exercises import CHAPTERS, EXERCISES, code_cells, parse_chapter, strip_solutions

BOOK = Path(__file__).resolve().parents[1] / "book"
_RUBRIC = re.compile(r"^\*\*Rubric\*\* \(instructor's edition only; hand-graded, (\d+) points\): "
                     r"((?:[^\n]+\n)*?[^\n]+)\n\n"
                     r"(?P<criteria>(?:\* .+\n(?:  .+\n)*)+)\n\*Model answer:\* \S", re.M)
_POINTS = re.compile(r"^\* \*\*(\d+)\*\* points?: ", re.M)


@pytest.fixture(scope="module")
def plans() -> dict:
    """The namespace of the instructor page's plan cell."""
    ns: dict = {}
    exec(next(c for c in code_cells((BOOK / "instructor.md").read_text()) if "PLAN_10" in c), ns)
    return ns


@pytest.fixture(scope="module")
def solutions() -> dict[str, str]:
    return {ex.id: ex.solution for chapter in CHAPTERS
            for ex in parse_chapter((BOOK / f"{chapter}.md").read_text())}


def test_every_hand_graded_item_has_one_rubric_with_its_points(plans, solutions):
    hand = set(plans["HAND_GRADED"]) | {e.id for e in EXERCISES.values() if not e.checkable}
    assert len(hand) == 22 and set(plans["HAND_GRADED"]) <= {e.id for e in EXERCISES.values() if e.checkable}
    for exercise_id, solution in solutions.items():
        rubrics = list(_RUBRIC.finditer(solution))
        assert len(rubrics) == (exercise_id in hand), exercise_id
        assert solution.count("**Rubric**") == len(rubrics), exercise_id   # none malformed
        for m in rubrics:
            points = [int(p) for p in _POINTS.findall(m["criteria"])]
            assert len(points) >= 2 and sum(points) == int(m.group(1)), exercise_id
            assert int(m.group(1)) == (10 if EXERCISES[exercise_id].difficulty == "challenge" else 3)


def test_the_student_edition_has_no_rubric():
    for chapter in CHAPTERS:
        text = (BOOK / f"{chapter}.md").read_text()
        assert "**Rubric**" in text and "**Rubric**" not in strip_solutions(text)
        assert "Model answer" not in strip_solutions(text)


@pytest.mark.parametrize("plan, weeks", [("PLAN_10", 10), ("PLAN_6", 6)])
def test_plans_give_two_to_four_hours_a_week(plans, plan, weeks):
    assert len(plans[plan]) == weeks
    for week in plans[plan]:
        assert 120 <= plans["homework"](week) <= 240, week[0]
    assert len(plans["week_plan"](plans[plan]).rows) == weeks


def test_plans_set_each_exercise_once(plans):
    ten = [i for week in plans["PLAN_10"] for i in week[4]]
    assert sorted(ten) == sorted(EXERCISES)
    six = [i for week in plans["PLAN_6"] for i in week[4]]
    papers = {chapter for _topic, chapter, *_ in plans["PLAN_6"]}   # the six chapters of the papers
    assert len(papers) == 6
    assert sorted(six) == sorted(e.id for e in EXERCISES.values()
                                 if e.difficulty != "challenge" and e.chapter in papers)
    for plan in ("PLAN_10", "PLAN_6"):
        for _topic, chapter, *_ in plans[plan]:
            assert chapter in CHAPTERS
