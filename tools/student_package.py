"""The student package: a wheel of ``fdi_lib`` without reference answers or reference code.

    python tools/student_package.py [--out _build/student]

stages a copy of ``fdi_lib`` in ``OUT/package`` without ``fdi_lib/exercises/_reference`` (the
reference answers, the known mistakes' code, the grader's list of forbidden calls), writes
``fdi_lib/exercises/_digests.json`` in it (:mod:`fdi_lib.exercises.checker` explains what the
digests are and what they do not protect), builds the wheel into ``OUT/dist`` with
``pip wheel`` (no network, no build isolation: the build uses this environment's setuptools),
then checks the wheel: no file of ``_reference``, and the digests present (the scan of
the student edition for reference answers is ``tools/student_edition.py``'s).
``pip install OUT/dist/fdi_lib-*.whl`` installs it without the repository.

The digests are for the book's data only. Graded answers (on each student's own data and on
hidden data) are kept out of the package entirely: ``tools/grader.py`` recomputes them from each
student's seed. This rather than key stretching (issue 30): an answer known to about 1 % costs
about 1e4 guesses per entry, so one CPU-hour would need some 0.4 s of stretching per digest, and
every ``check`` a student runs would pay it too; with no graded digest in the wheel there is
nothing to recover that earns a point (the book's own answers are printed in the instructor's
edition anyway). :func:`stage` is also what ``tools/grader.py`` runs submissions against.
"""

from __future__ import annotations

import argparse
import json
import secrets
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

#: What the student package leaves out of ``fdi_lib`` (relative paths, as in the wheel).
EXCLUDED = ("fdi_lib/exercises/_reference",)

_PYPROJECT = """[build-system]
requires = ["setuptools>=61"]
build-backend = "setuptools.build_meta"

[project]
name = "fdi_lib"
version = "{version}"
description = "fdi-book's library, student edition: exercises and checker without reference answers"
requires-python = ">=3.11"
dependencies = {dependencies}

[tool.setuptools.packages.find]
include = ["fdi_lib*"]

[tool.setuptools.package-data]
"fdi_lib.exercises" = ["_digests.json"]
"""


def _project() -> dict:
    import tomllib

    return tomllib.loads((REPO / "pyproject.toml").read_text())["project"]


def digests(salt: str | None = None) -> dict:
    """The digest table of the student package: the book's data only (no graded answer)."""
    from fdi_lib.exercises import exercise_ids, get_exercise
    from fdi_lib.exercises.checker import (
        DIGEST_ROUNDS,
        entry_digest,
        entry_keys,
        feedback_candidates,
        zero_floor,
    )

    salt = salt or secrets.token_hex(16)
    table: dict = {"format": 1, "salt": salt, "rounds": DIGEST_ROUNDS, "students": {}}
    for student in (None,):
        name = ""
        per: dict = {}
        for exercise_id in exercise_ids(checkable=True):
            ex = get_exercise(exercise_id)
            ref, candidates = feedback_candidates(exercise_id, student)

            floor = zero_floor(ref, ex)

            def sets(value):
                return [
                    sorted(
                        entry_digest(salt, exercise_id, name, i, key)
                        for key in entry_keys(float(v), ex, around=True, floor=floor)
                    )
                    for i, v in enumerate(value.ravel())
                ]

            per[exercise_id] = {
                "shape": list(ref.shape),
                "floor": floor,
                "reference": sets(ref),
                "candidates": [
                    {"hint": hint, "entries": sets(value)} for hint, value in candidates
                ],
            }
        table["students"][name] = per
    return table


def stage(target: Path, *, with_digests: bool = True) -> Path:
    """Copy ``fdi_lib`` without the excluded modules to ``target`` with its digests (unless
    ``with_digests`` is false: the grader's kernels need none) and a ``pyproject.toml``; returns
    ``target``."""
    if target.exists():
        shutil.rmtree(target)
    target.mkdir(parents=True)
    shutil.copytree(
        REPO / "fdi_lib",
        target / "fdi_lib",
        ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "_digests.json"),
    )
    for rel in EXCLUDED:
        shutil.rmtree(target / rel)
    if with_digests:
        table = digests()
        (target / "fdi_lib" / "exercises" / "_digests.json").write_text(json.dumps(table))
    project = _project()
    (target / "pyproject.toml").write_text(
        _PYPROJECT.format(
            version=project["version"], dependencies=json.dumps(project["dependencies"])
        )
    )
    return target


def problems(wheel: Path) -> list[str]:
    """What is wrong with a built student wheel (empty when it ships no reference)."""
    out = []
    with zipfile.ZipFile(wheel) as zf:
        names = zf.namelist()
        out += [
            f"{wheel.name}: ships {name}"
            for name in names
            if any(name.startswith(rel + "/") for rel in EXCLUDED)
        ]
        if "fdi_lib/exercises/_digests.json" not in names:
            out.append(f"{wheel.name}: no fdi_lib/exercises/_digests.json")
    return out


def build(out: Path) -> Path:
    """Stage and build the wheel into ``out/dist``; returns the wheel's path."""
    src = stage(out / "package")
    dist = out / "dist"
    if dist.exists():
        shutil.rmtree(dist)
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--quiet",
            "--no-deps",
            "--no-build-isolation",
            "--wheel-dir",
            str(dist),
            str(src),
        ],
        check=True,
    )
    (wheel,) = dist.glob("fdi_lib-*.whl")
    return wheel


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO / "_build" / "student")
    args = parser.parse_args(argv)
    wheel = build(args.out.resolve())
    found = problems(wheel)
    for p in found:
        print("student package:", p, file=sys.stderr)
    if not found:
        print(f"student package: {wheel} (no reference modules; digests for the book's data only)")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
