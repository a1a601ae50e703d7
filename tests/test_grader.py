"""The instructor's grader (issue 22, items 1 and 2) on a synthetic class of three.

The reference solutions get full marks on every checkable exercise, the untouched starters zero,
and the submission that prints "correct" and takes its answers from the library (the one-call
functions, ``reference_answer``, or the book's numbers typed in) zero. One kernel per student
(about 35 s of CPU for the class, two kernels at once).
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np
import pytest

from fdi_lib.exercises import exercise_data, exercise_ids, reference_answer
from fdi_lib.exercises._reference import REFERENCES

TOOLS = Path(__file__).resolve().parents[1] / "tools"
sys.path.insert(0, str(TOOLS))

import grader  # noqa: E402
import make_synthetic_class  # noqa: E402

IDS = exercise_ids(checkable=True)


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    root = tmp_path_factory.mktemp("class")
    make_synthetic_class.write_class(root / "submissions")
    rows = grader.grade(root / "submissions", root / "grades.csv", root / "grades.log", secret="test-secret",
                        jobs=2)
    return rows, root


@pytest.mark.slow
def test_gradebook_of_the_synthetic_class(graded):
    rows, root = graded
    with (root / "grades.csv").open() as f:
        table = list(csv.DictReader(f))
    assert list(table[0]) == ["student", *IDS, "total", "possible"]
    by = {r["student"]: r for r in table}
    assert sorted(by) == ["cheater", "reference", "starter"]
    full = sum(grader.POINTS.values())
    assert all(by["reference"][i] == str(full) for i in IDS), by["reference"]
    assert by["reference"]["total"] == by["reference"]["possible"] == str(full * len(IDS))
    for student in ("starter", "cheater"):
        assert all(by[student][i] == "0" for i in IDS), by[student]
        assert by[student]["total"] == "0"
    log = (root / "grades.log").read_text()
    n = full * len(IDS)
    assert f"== reference: {n} / {n}" in log and f"== starter: 0 / {n}" in log and f"== cheater: 0 / {n}" in log
    assert "missing (no `answer`" in log and "outside the tolerance" in log


@pytest.mark.parametrize("exercise_id", sorted(make_synthetic_class.ONE_CALL))
def test_the_cheaters_library_calls_would_pass_if_not_blocked(exercise_id):
    """The cheater's zero comes from the grader (blocked calls, hidden data), not from a wrong call:
    unblocked, each one-call snippet gives the reference on the student's data."""
    namespace = {"data": exercise_data(exercise_id, "cheater")}
    exec(make_synthetic_class.ONE_CALL[exercise_id], namespace)
    np.testing.assert_allclose(np.asarray(namespace["answer"], dtype=float),
                               reference_answer(exercise_id, "cheater"), rtol=1e-9)
    names = {line.split(" import ")[1].split(",")[0].strip() for line in
             make_synthetic_class.ONE_CALL[exercise_id].splitlines() if " import " in line}
    assert {n.rsplit(".", 1)[1] for n in REFERENCES[exercise_id].one_call} & names


def test_plan_finds_exercise_cells_and_imports():
    import nbformat

    nb = nbformat.v4.new_notebook(cells=[
        nbformat.v4.new_code_cell("import numpy as np\nfrom fdi_lib.exercises import check"),
        nbformat.v4.new_code_cell("x = 1  # chapter body: not run"),
        nbformat.v4.new_markdown_cell("```{exercise-start} glr-1 · warm-up · T\n```"),
        nbformat.v4.new_code_cell('data = exercise_data("glr-1")\nanswer = None'),
        nbformat.v4.new_code_cell("answer = 2"),
        nbformat.v4.new_code_cell('data = exercise_data("glr-6")  # not checkable: not run'),
        nbformat.v4.new_code_cell('data = exercise_data("glr-2")'),
    ])
    plan = grader.plan_notebook(nb)
    assert plan.imports == ["import numpy as np\nfrom fdi_lib.exercises import check"]
    assert plan.exercises == {"glr-1": ['data = exercise_data("glr-1")\nanswer = None', "answer = 2"],
                              "glr-2": ['data = exercise_data("glr-2")']}


def test_hidden_data_need_the_secret():
    assert grader.hidden_student("alice", "s1") != grader.hidden_student("alice", "s2")
    assert grader.hidden_student("alice", "s1") != grader.hidden_student("bob", "s1")
    assert "alice" not in grader.hidden_student("alice", "s1")
