"""The student package (issue 22, item 3): no reference answers, feedback from digests, graded mode.

The package is staged as ``make student`` stages it (tools/student_package.py) and imported in a
separate interpreter with the staged copy first on the path, as a student's pip install would be.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from fdi_lib.exercises import exercise_ids, get_exercise, reference_answer

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tools"))
sys.path.insert(0, str(REPO / "tests"))

import student_package  # noqa: E402
import test_feedback  # noqa: E402

_DRIVER = """
import json, sys
import numpy as np
import fdi_lib.exercises as E
out = {"file": E.__file__}
try:
    E.reference_answer("glr-1")
except E.ReferenceNotShippedError as exc:
    out["reference"] = str(exc)
try:
    import fdi_lib.exercises._reference
    out["reference_module"] = True
except ImportError:
    out["reference_module"] = False
out["messages"] = [E.check(i, a if a is None else np.array(a), graded=g).message
                   for i, a, g in json.load(sys.stdin)]
print(json.dumps(out))
"""


@pytest.fixture(scope="module")
def staged(tmp_path_factory):
    return student_package.stage(tmp_path_factory.mktemp("student") / "package")


def run_student(root: Path, calls: list) -> dict:
    env = dict(os.environ, PYTHONPATH=str(root), FDI_STUDENT_ID="")
    proc = subprocess.run(
        [sys.executable, "-c", _DRIVER],
        input=json.dumps(calls),
        env=env,
        cwd=root,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(proc.stdout)


def _as_list(a):
    return np.asarray(a, dtype=float).tolist()


def test_student_package_has_no_reference_and_checks_with_digests(staged):
    calls = [(i, _as_list(reference_answer(i)), False) for i in exercise_ids(checkable=True)]
    calls += [(i, _as_list(w()), False) for i, _, w, _ in test_feedback.WRONG]
    out = run_student(staged, calls)
    assert out["file"].startswith(str(staged))
    assert not out["reference_module"]
    assert "not shipped" in out["reference"]
    n = len(exercise_ids(checkable=True))
    assert all(": correct" in m for m in out["messages"][:n]), out["messages"][:n]
    for (exercise_id, what, _, expected), message in zip(test_feedback.WRONG, out["messages"][n:]):
        assert message.startswith(f"{exercise_id}: not yet.") and expected in message, (
            what,
            message,
        )
    assert not list(staged.rglob("_reference"))


def test_graded_mode_says_only_pass_or_fail_and_counts_attempts(staged):
    ref = reference_answer("pipe-3")
    wrong = [0.5 * ref, 0.999 * ref, 1.001 * ref, 2.0 * ref, None, ref]
    out = run_student(staged, [("pipe-3", None if w is None else _as_list(w), True) for w in wrong])
    assert out["messages"] == [
        "pipe-3: attempt 1: not accepted.",
        "pipe-3: attempt 2: not accepted.",
        "pipe-3: attempt 3: not accepted.",
        "pipe-3: attempt 4: not accepted.",
        "pipe-3: no answer yet. Replace `answer = None` by a number: 1 - cos^2 "
        "over k = first..last.",
        "pipe-3: attempt 5: accepted.",
    ]


def test_no_direction_near_the_answer(staged):
    """Bisection needs "too large" / "too small": the package's messages for answers on either side
    of every scalar reference are the same sentence (counts excepted: one more or one fewer is the
    off-by-one mistake, a pattern the check names on purpose)."""
    scalars = [
        i
        for i in exercise_ids(checkable=True)
        if reference_answer(i).size == 1 and not get_exercise(i).integer
    ]
    calls = [
        (i, float(f * reference_answer(i)), False) for i in scalars for f in (0.9, 1.1, 0.99, 1.01)
    ]
    messages = run_student(staged, calls)["messages"]
    for k, exercise_id in enumerate(scalars):
        group = set(messages[4 * k : 4 * k + 4])
        assert len(group) == 1, (exercise_id, group)
        assert not any(w in m for m in group for w in ("large", "small", "close", "sign"))


@pytest.mark.slow
def test_wheel_builds_and_installs_without_the_repository(tmp_path):
    wheel = student_package.build(tmp_path / "student")
    assert student_package.problems(wheel) == []
    with zipfile.ZipFile(wheel) as zf:
        names = zf.namelist()
    assert "fdi_lib/exercises/_digests.json" in names and "fdi_lib/exercises/checker.py" in names
    assert not any("_reference" in n for n in names)
    target = tmp_path / "site"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "--quiet",
            "--no-deps",
            "--no-index",
            "--target",
            str(target),
            str(wheel),
        ],
        check=True,
    )
    out = run_student(target, [("glr-5", 98.0, False)])
    assert out["file"].startswith(str(target)) and out["messages"] == [
        "glr-5: correct (tolerance: exact (integers))."
    ]
