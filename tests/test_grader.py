"""The instructor's grader (issue 30) on the synthetic class of tools/make_synthetic_class.py.

One chapter (zb2014/glr) for 16 students, two kernels at once (about 3 minutes on 2 cores): the
reference solutions, a verbatim copy and a student with a helper function get full marks; the
untouched starters and the cheater 0; each attack on the grader 0 on the attacked exercise with
the attempt named in the log, and full marks elsewhere; the hang is killed; the corrupt notebook
is logged; every student gets a feedback file; a re-run resumes.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import nbformat
import numpy as np
import pytest

from fdi_lib.exercises import CELL_KEY, exercise_data, exercise_ids, reference_answer
from fdi_lib.exercises._reference import REFERENCES

TOOLS = Path(__file__).resolve().parents[1] / "tools"
sys.path.insert(0, str(TOOLS))

import grader  # noqa: E402
import make_synthetic_class as synth  # noqa: E402

CHAPTER = "zb2014/glr"
IDS = [i for i in exercise_ids(checkable=True) if i.startswith("glr-")]
FULL = sum(grader.POINTS.values())

#: What the log must say of each attack (the attempt named).
NAMED = {
    "import-reference": "reading " + str(grader.REPO),
    "wrapped": "calling fdi_lib.glr.quadratic_form",
    "reload": "re-executing the library's code",
    "read-environment": "/environ (another process)",
    "read-grader": "tools/grader.py (the grader's or the repository's files)",
    "patch-check": "an assignment to check",
    "write-gradebook": "writing ",
    "prints-correct": "the answer is missing",
    "fork": "starting a process",
    "hang": "a cell ran over its time limit; the kernel's process group was killed",
}


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    root = tmp_path_factory.mktemp("synthetic")
    out = root / "class"
    synth.write_class(out, [CHAPTER])
    book = synth.gradebook(out)
    limits = grader.Limits(cell=15, student=400, memory_mb=3072)
    grader.grade(out, book, limits=limits, secret="test-secret", jobs=2, chapters=[CHAPTER])
    with book.open() as f:
        rows = {r["student"]: r for r in csv.DictReader(f)}
    return rows, book, limits


def _log_section(book: Path, student: str) -> str:
    text = book.with_suffix(".log").read_text()
    return text.split(f"== {student}:", 1)[1].split("\n== ", 1)[0]


@pytest.mark.slow
def test_every_student_has_a_row_and_a_feedback_file(graded):
    rows, book, _ = graded
    assert sorted(rows) == sorted(synth.STUDENTS)
    header = list(next(iter(rows.values())))
    assert header[: len(IDS) + 1] == ["student", *IDS]
    assert f"{CHAPTER} (/{FULL * len(IDS)})" in header and "rubric glr-6" in header
    for student in synth.STUDENTS:
        text = (book.with_suffix(".feedback") / f"{student}.md").read_text()
        assert f"Total: {rows[student]['total']} / {FULL * len(IDS)}" in text
        assert "test-secret" not in text
    assert "test-secret" not in book.with_suffix(".log").read_text()
    assert all(r["rubric glr-6"] == "" for r in rows.values())


@pytest.mark.slow
@pytest.mark.parametrize("student", ["reference", "copier", "helper"])
def test_full_marks(graded, student):
    rows, _, _ = graded
    assert all(rows[student][i] == str(FULL) for i in IDS), rows[student]


@pytest.mark.slow
@pytest.mark.parametrize("student", ["starter", "cheater", "corrupt"])
def test_zero(graded, student):
    rows, book, _ = graded
    assert rows[student]["total"] == "0", rows[student]
    if student == "corrupt":
        assert "unreadable notebook (NotJSONError" in _log_section(book, student)


@pytest.mark.slow
@pytest.mark.parametrize("attack", sorted(synth.ATTACKS))
def test_each_attack_scores_zero_and_is_named(graded, attack):
    rows, book, _ = graded
    assert rows[attack][synth.ATTACKED] == "0", rows[attack]
    assert NAMED[attack] in _log_section(book, attack)
    if attack != "import-reference":  # it purges the kernel's library: its later cells fail
        others = [i for i in IDS if i != synth.ATTACKED]
        assert all(rows[attack][i] == str(FULL) for i in others), rows[attack]


@pytest.mark.slow
def test_the_gradebook_was_not_written_by_the_attack(graded):
    _, book, _ = graded
    assert "write-gradebook,99" not in book.read_text()


@pytest.mark.slow
def test_the_similarity_report_flags_the_verbatim_copy(graded):
    _, book, _ = graded
    with book.with_suffix(".similarity.csv").open() as f:
        groups = [
            r
            for r in csv.DictReader(f)
            if r["exercise"] == synth.ATTACKED and r["kind"] == "verbatim"
        ]
    assert any({"copier", "reference"} <= set(r["students"].split()) for r in groups)


@pytest.mark.slow
def test_canvas_export(graded):
    rows, book, _ = graded
    with book.with_suffix(".canvas.csv").open() as f:
        table = list(csv.reader(f))
    assert table[0] == ["Student", "ID", "SIS User ID", "SIS Login ID", "Section", CHAPTER]
    assert table[1][0] == "Points Possible" and table[1][-1] == str(FULL * len(IDS))
    assert {r[2]: r[-1] for r in table[2:]} == {s: r["total"] for s, r in rows.items()}


@pytest.mark.slow
def test_a_rerun_resumes_and_skips_graded_students(graded, tmp_path):
    rows, book, limits = graded
    before = book.read_text()
    again = grader.grade(
        book.with_suffix(""), book, limits=limits, secret="test-secret", jobs=1, chapters=[CHAPTER]
    )
    assert book.read_text() == before and len(again) == len(rows)


def test_a_hang_that_swallows_interrupts_is_killed(tmp_path):
    """The kernel's process group is killed at the cell limit, the next exercise still runs, and
    so does the student's next notebook (all of a student's notebooks share a kernel until a
    kill: a fresh one runs the next notebook's set-up cells before its exercises)."""
    out = tmp_path / "class"
    folder = out / "hang"
    folder.mkdir(parents=True)
    text = (grader.REPO / "book" / f"{CHAPTER}.md").read_text()
    import jupytext

    from fdi_lib.exercises import tag_exercise_cells

    nb = jupytext.reads(synth.submission(text, "hang", out), fmt="md:myst")
    tag_exercise_cells(nb)
    nb.cells = [c for c in nb.cells if c.metadata[CELL_KEY]["exercise"] in (None, "glr-1", "glr-2")]
    jupytext.write(nb, folder / "glr.ipynb")
    pipeline = "zb2014/pipeline"
    nb = jupytext.reads(
        synth.submission((grader.REPO / "book" / f"{pipeline}.md").read_text(), "reference", out),
        fmt="md:myst",
    )
    tag_exercise_cells(nb)
    nb.cells = [c for c in nb.cells if c.metadata[CELL_KEY]["exercise"] in (None, "pipe-1")]
    jupytext.write(nb, folder / "pipeline.ipynb")
    limits = grader.Limits(cell=20, student=200)
    rows = grader.grade(
        out, tmp_path / "g.csv", limits=limits, secret="s", chapters=[CHAPTER, pipeline]
    )
    assert rows[0]["glr-2"] == "0" and rows[0]["glr-1"] == str(FULL)
    assert rows[0]["pipe-1"] == str(FULL)
    assert "a cell ran over its time limit" in (tmp_path / "g.log").read_text()


def test_plan_attributes_cells_by_metadata():
    new = nbformat.v4
    cells = [
        new.new_code_cell("import numpy as np"),
        new.new_code_cell("def helper(x):\n    return 2 * x"),
        new.new_code_cell("x = np.ones(3).sum()  # the chapter's body: not run"),
        new.new_markdown_cell("**Exercise glr-1**"),
        new.new_code_cell('data = exercise_data("glr-1")\nanswer = None'),
        new.new_code_cell("answer = helper(1)"),  # added by the student
        new.new_markdown_cell("**Exercise glr-6**"),
        new.new_code_cell("answer = -1  # a challenge: not graded"),
    ]
    for cell, ex in zip(cells, [None, None, None, "glr-1", "glr-1", None, "glr-6", "glr-6"]):
        if not (cell.cell_type == "code" and cell.source.startswith("answer = helper")):
            cell.metadata[CELL_KEY] = {"exercise": ex}
    # the graded-mode attempts the saved outputs show (a glr-6 cell's output is not glr-1's)
    cells[4].outputs = [
        new.new_output("execute_result", {"text/plain": "glr-1: attempt 4: accepted."})
    ]
    cells[5].outputs = [
        new.new_output("stream", name="stdout", text="glr-1: attempt 3: not accepted.\n")
    ]
    cells[7].outputs = [
        new.new_output("stream", name="stdout", text="glr-1: attempt 9: accepted.\n")
    ]
    plan = grader.plan_notebook(new.new_notebook(cells=cells))
    assert plan.setup == ["import numpy as np", "def helper(x):\n    return 2 * x"]
    assert plan.exercises == {
        "glr-1": ['data = exercise_data("glr-1")\nanswer = None', "answer = helper(1)"]
    }
    assert plan.attempts == {"glr-1": 4}


def test_student_notebook_tags_follow_the_chapter():
    import jupytext

    from fdi_lib.exercises import tag_exercise_cells

    nb = jupytext.read(grader.REPO / "book" / f"{CHAPTER}.md")
    tag_exercise_cells(nb)
    tags = [c.metadata[CELL_KEY]["exercise"] for c in nb.cells]
    assert [t for t in dict.fromkeys(tags) if t] == [f"glr-{i}" for i in range(1, 7)]
    assert tags[0] is None and all(t is None for t in tags[: tags.index("glr-1")])


@pytest.mark.parametrize("exercise_id", sorted(synth.ONE_CALL))
def test_the_cheaters_library_calls_would_pass_if_not_blocked(exercise_id):
    """The cheater's zero comes from the grader, not from a wrong call: unblocked, each one-call
    snippet gives the reference on the student's data."""
    namespace = {"data": exercise_data(exercise_id, "cheater")}
    exec(synth.ONE_CALL[exercise_id], namespace)
    np.testing.assert_allclose(
        np.asarray(namespace["answer"], dtype=float),
        reference_answer(exercise_id, "cheater"),
        rtol=1e-9,
    )
    names = {
        line.split(" import ")[1].split(",")[0].strip()
        for line in synth.ONE_CALL[exercise_id].splitlines()
        if " import " in line
    }
    assert {n.rsplit(".", 1)[1] for n in REFERENCES[exercise_id].one_call} & names


def test_the_attacks_would_get_the_answer_if_not_stopped():
    """The wrapped call gives the reference (its zero is the grader's doing)."""
    data = exercise_data(synth.ATTACKED, "wrapped")
    namespace = {"data": data}
    exec(synth.ATTACKS["wrapped"], namespace)
    np.testing.assert_allclose(
        namespace["answer"], reference_answer(synth.ATTACKED, "wrapped"), rtol=1e-9
    )


def test_hidden_data_need_the_secret():
    assert grader.hidden_student("alice", "s1") != grader.hidden_student("alice", "s2")
    assert grader.hidden_student("alice", "s1") != grader.hidden_student("bob", "s1")
    assert "alice" not in grader.hidden_student("alice", "s1")


def test_similarity_flags_verbatim_and_renamed_copies():
    code = (
        "def f(a, b):\n    s = 0\n    for x in a:\n        s += x * b\n    return s / len(a)\n"
        "answer = f(data, 3)"
    )
    renamed = code.replace("s", "total").replace("f(", "g(")
    other = (
        "import numpy as np\nanswer = float(np.mean(np.asarray(data) * 3) + 0 * np.pi ** 2 - 1 + 1)"
    )
    codes = {
        "a": {"glr-1": [code]},
        "b": {"glr-1": ["# mine\n" + code]},
        "c": {"glr-1": [renamed]},
        "d": {"glr-1": [other]},
    }
    rows = grader.similarity(codes, {})
    assert {"exercise": "glr-1", "students": "a b", "kind": "verbatim", "jaccard": "1.000"} in rows
    similar = {r["students"] for r in rows if r["kind"] == "similar"}
    assert "a c" in similar and not any("d" in s.split() for s in similar)
