"""Grade a class: run every submitted notebook on the student's own data and on hidden data.

    python tools/grader.py SUBMISSIONS OUT.csv [--log OUT.log] [--timeout 120] [--jobs 1]
    make grade SUBMISSIONS=<dir> OUT=<csv>

``SUBMISSIONS`` holds one folder per student, named by the student id, with that student's
notebooks (``*.ipynb``, any names: the exercises are found by their identifiers). ``OUT.csv``
gets one row per student: the points of every checkable exercise, the total and the maximum;
``OUT.log`` (default: beside the CSV) says what failed and why.

How a submission is graded
--------------------------
1. The student package is staged (``tools/student_package.py``: ``fdi_lib`` without
   ``exercises._reference``) and the submission runs against it, in one Jupyter kernel per
   student, in a scratch directory: no reference answer or reference code is importable there.
2. Of each notebook only the import cells before the first exercise and the cells of the
   checkable exercises run (the cells from an exercise's ``exercise_data("<id>")`` to the next
   exercise). They run twice: once with the student's own data (``FDI_STUDENT_ID`` = the
   folder's name) and once with hidden data (a student id derived from a grading secret the
   student does not know), so the cells must compute the answer, not hold it.
3. During both runs ``tools/grader_kernel.py`` makes the library functions that answer the
   exercise in one call raise (``Reference.one_call`` in ``fdi_lib.exercises._reference``) and
   turns ``check`` into a stub without feedback; ``answer`` is recorded after each run.
   The submissions' code runs as the user who runs the grader, without a container: grade on
   an account or machine meant for it.
4. Hidden tests compare each recorded ``answer`` with the reference recomputed here for the same
   data, with the exercise's tolerance: one point for the student's own data, one for the
   hidden data.

Why otter-grader's test format and our own execution: the hidden tests are otter-grader
exception-based test files (:class:`otter.test_files.ExceptionTestFile`, plain Python test
functions with points and a ``hidden`` flag, whose results otter scores). otter is a maintained
autograder, needs no course database or release/collect workflow (nbgrader does: a SQL
gradebook, a course directory layout, and hidden tests written into the source notebook, which
the student edition would then have to strip again). Its own ``otter grade`` runs submissions in
Docker containers and ``otter run`` needs an autograder zip that installs requirements, which this
machine (no container, no network) cannot do; and neither can run the same cells twice on two
data sets with library functions blocked in between, which is the point of the hidden tests. So
the notebooks are executed here with nbclient (the executor Jupyter Book also uses) and only the
scoring is otter's.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import os
import re
import secrets
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
TOOLS = Path(__file__).resolve().parent
for path in (REPO, TOOLS):
    if str(path) not in sys.path:
        sys.path.insert(0, str(path))

from fdi_lib.exercises import exercise_ids, get_exercise, reference_answer  # noqa: E402
from fdi_lib.exercises._reference import REFERENCES  # noqa: E402
from fdi_lib.exercises.checker import close  # noqa: E402

#: Points of a checkable exercise: the student's own data, then the hidden data.
POINTS = {"own": 1, "hidden": 1}

_TEST_TEMPLATE = '''
from otter.test_files import test_case

name = {id!r}

@test_case(name={id!r} + ": answer on the student's own data", points={own}, hidden=True)
def own_data(accepted, own, ref_own):
    assert accepted(own, ref_own), "the answer on the student's own data is " + accepted.why(own, ref_own)

@test_case(name={id!r} + ": the same cells on hidden data", points={hidden}, hidden=True)
def hidden_data(accepted, hidden, ref_hidden):
    assert accepted(hidden, ref_hidden), "the answer on hidden data is " + accepted.why(hidden, ref_hidden)
'''

_START = re.compile(r"\{exercise-start\}\s+([a-z]+-\d+)")
_DATA = re.compile(r"""exercise_data\(\s*["']([a-z]+-\d+)["']""")


class _Accepted:
    """``answer`` within the exercise's tolerance of ``ref`` (the test files' ``accepted``)."""

    def __init__(self, exercise_id: str):
        self.ex = get_exercise(exercise_id)

    def why(self, answer, ref) -> str:
        if answer is None:
            return "missing (no `answer`, or the cells failed before setting it)"
        a = np.asarray(answer, dtype=float)
        if a.size == 1 and ref.size == 1:
            a = a.reshape(ref.shape)
        if a.shape != ref.shape:
            return f"of shape {a.shape}, expected {ref.shape}"
        if self.ex.integer and not np.all(a == np.round(a)):
            return "not a whole number"
        return "outside the tolerance" if not np.all(close(a, ref, self.ex)) else "accepted"

    def __call__(self, answer, ref) -> bool:
        return self.why(answer, ref) == "accepted"


@dataclass
class Plan:
    """Which cells of a notebook run: the import cells, then each checkable exercise's cells."""

    imports: list[str] = field(default_factory=list)
    exercises: dict[str, list[str]] = field(default_factory=dict)


def plan_notebook(nb) -> Plan:
    """Split a submitted notebook into its import cells and the cells of each exercise."""
    import ast

    plan, current = Plan(), None
    for cell in nb.cells:
        source = cell.source if isinstance(cell.source, str) else "".join(cell.source)
        marker = _START.search(source) if cell.cell_type == "markdown" else _DATA.search(source)
        if marker and marker.group(1) != current:
            current = marker.group(1)
        if cell.cell_type != "code":
            continue
        if current is None:
            try:
                body = ast.parse(source).body
            except SyntaxError:
                continue
            if body and all(isinstance(node, (ast.Import, ast.ImportFrom)) for node in body):
                plan.imports.append(source)
        elif current in REFERENCES:
            plan.exercises.setdefault(current, []).append(source)
    return plan


def hidden_student(student: str, secret: str) -> str:
    """The id of a student's hidden data: not guessable without the grading secret."""
    return f"hidden-{hashlib.sha256(f'{secret}/{student}'.encode()).hexdigest()[:16]}"


def _grading_notebook(plans: list[Plan], student: str, hidden: str, record: Path):
    import nbformat

    cells = [nbformat.v4.new_code_cell("import grader_kernel as _fdi_grader")]
    for plan in plans:
        cells.append(nbformat.v4.new_code_cell("%reset -f\nimport grader_kernel as _fdi_grader"))
        cells += [nbformat.v4.new_code_cell(src) for src in plan.imports]
        for exercise_id, sources in plan.exercises.items():
            one_call = list(REFERENCES[exercise_id].one_call)
            for run, key in (("own", student), ("hidden", hidden)):
                cells.append(nbformat.v4.new_code_cell(
                    f"_fdi_grader.begin({exercise_id!r}, {key!r}, {one_call!r}, {str(record)!r})",
                    metadata={"grader": {"exercise": exercise_id, "run": run, "hook": True}}))
                cells += [nbformat.v4.new_code_cell(src, metadata={"grader": {"exercise": exercise_id,
                                                                               "run": run}})
                          for src in sources]
                cells.append(nbformat.v4.new_code_cell(
                    f"_fdi_grader.end({exercise_id!r}, {run!r})",
                    metadata={"grader": {"exercise": exercise_id, "run": run, "hook": True}}))
    return nbformat.v4.new_notebook(cells=cells)


def run_student(folder: Path, package: Path, secret: str, timeout: int) -> tuple[dict, list[str]]:
    """Execute one student's notebooks; returns ({(exercise, run): answer}, log lines)."""
    import nbclient
    import nbformat

    student = folder.name
    log: list[str] = []
    plans = []
    for path in sorted(folder.rglob("*.ipynb")):
        try:
            plans.append(plan_notebook(nbformat.read(path, as_version=4)))
        except Exception as exc:  # noqa: BLE001 -- an unreadable notebook is the student's, logged
            log.append(f"{path.name}: unreadable notebook ({type(exc).__name__}: {exc})")
    if not any(p.exercises for p in plans):
        log.append("no checkable exercise found in the submission")
        return {}, log
    with tempfile.TemporaryDirectory(prefix=f"grade-{student}-") as scratch:
        record = Path(scratch) / "answers.jsonl"
        nb = _grading_notebook(plans, student, hidden_student(student, secret), record)
        env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(package), str(TOOLS)]))
        try:
            client = nbclient.NotebookClient(nb, timeout=timeout, kernel_name="python3", allow_errors=True,
                                             interrupt_on_timeout=True,
                                             resources={"metadata": {"path": scratch}})
            client.execute(env=env)   # passed on to the kernel manager's start_kernel
        except Exception as exc:  # noqa: BLE001 -- a dead kernel fails this student, not the class
            log.append(f"kernel failed: {type(exc).__name__}: {exc}")
        for cell in nb.cells:
            where = cell.metadata.get("grader")
            for out in cell.get("outputs", []):
                if out.get("output_type") == "error" and where:
                    log.append(f"{where['exercise']} ({where['run']} data): {out['ename']}: {out['evalue']}")
        answers = {}
        if record.exists():
            for line in record.read_text().splitlines():
                rec = json.loads(line)
                answers[rec["exercise"], rec["run"]] = rec["answer"]
                if rec.get("unreadable"):
                    log.append(f"{rec['exercise']} ({rec['run']} data): answer unreadable ({rec['unreadable']})")
    return answers, log


def score(exercise_id: str, answers: dict, student: str, hidden: str) -> tuple[float, list[str]]:
    """Points of one exercise from otter's test file, and the failed tests' messages."""
    from otter.test_files import ExceptionTestFile

    test = ExceptionTestFile.from_string(_TEST_TEMPLATE.format(id=exercise_id, **POINTS),
                                         path=f"hidden/{exercise_id}.py")
    env = {"accepted": _Accepted(exercise_id),
           "own": answers.get((exercise_id, "own")), "hidden": answers.get((exercise_id, "hidden")),
           "ref_own": reference_answer(exercise_id, student), "ref_hidden": reference_answer(exercise_id, hidden)}
    test.run(env)
    failed = [r.message.splitlines()[-1] for r in test.test_case_results if not r.passed]
    return test.score, failed


def grade(submissions: Path, out: Path, log_path: Path, timeout: int = 120, secret: str | None = None,
          jobs: int = 1) -> list[dict]:
    """Grade every student folder of ``submissions``; writes the CSV and the log, returns the rows.

    ``jobs`` kernels run at once (threads driving separate kernel processes); the gradebook is
    the same for any ``jobs``.
    """
    from concurrent.futures import ThreadPoolExecutor

    import student_package

    secret = secret or os.environ.get("FDI_GRADER_SECRET") or secrets.token_hex(16)
    ids = exercise_ids(checkable=True)
    rows, log = [], [f"grading secret (hidden data): {secret}", ""]
    folders = sorted(p for p in submissions.iterdir() if p.is_dir())
    with tempfile.TemporaryDirectory(prefix="fdi-student-package-") as tmp:
        package = student_package.stage(Path(tmp) / "package", with_digests=False)
        with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
            runs = list(pool.map(lambda folder: run_student(folder, package, secret, timeout), folders))
        for folder, (answers, notes) in zip(folders, runs):
            student = folder.name
            hidden = hidden_student(student, secret)
            row = {"student": student}
            for exercise_id in ids:
                points, failed = score(exercise_id, answers, student, hidden)
                row[exercise_id] = points
                notes += [f"{exercise_id}: {m}" for m in failed if (exercise_id, "own") in answers]
            row["total"] = sum(row[i] for i in ids)
            row["possible"] = sum(POINTS.values()) * len(ids)
            rows.append(row)
            missing = [i for i in ids if (i, "own") not in answers]
            log.append(f"== {student}: {row['total']:g} / {row['possible']}")
            if missing:
                log.append(f"not submitted: {', '.join(missing)}")
            log += sorted(set(notes), key=notes.index)
            log.append("")
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=["student", *ids, "total", "possible"])
        writer.writeheader()
        writer.writerows({k: (f"{v:g}" if isinstance(v, float) else v) for k, v in row.items()} for row in rows)
    log_path.write_text("\n".join(log) + "\n")
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("submissions", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--log", type=Path)
    parser.add_argument("--timeout", type=int, default=120, help="seconds per cell")
    parser.add_argument("--jobs", type=int, default=1, help="kernels at once (one per student)")
    args = parser.parse_args(argv)
    if not args.submissions.is_dir():
        parser.error(f"SUBMISSIONS: expected a folder of student folders, got {args.submissions}")
    log = args.log or args.out.with_suffix(".log")
    rows = grade(args.submissions, args.out, log, args.timeout, jobs=args.jobs)
    print(f"{len(rows)} students graded: {args.out} (what failed: {log})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
