"""Grade a class: run every submitted notebook on the student's own data and on hidden data.

    python tools/grader.py SUBMISSIONS OUT.csv [--jobs 2] [--cell-timeout 60]
                           [--student-timeout 600] [--memory-mb 3072] [--chapters ...]
    make grade SUBMISSIONS=<dir> OUT=<csv>

``SUBMISSIONS`` holds one folder per student, named by the student id, with that student's
notebooks (``*.ipynb``, any names). Beside ``OUT.csv`` the grader writes:

* ``OUT.csv``, the gradebook: one row per student, written (and fsynced) as soon as the student
  is graded; a re-run with the same ``OUT`` resumes and skips the students already in it. Columns:
  the points of every checkable exercise, each chapter's points with its points possible in the
  header (``zb2014/glr (/10)``), the total and the points possible of the graded chapters, then
  one empty ``rubric <id>`` column per hand-graded item for the instructor;
* ``OUT.canvas.csv``: the same totals in Canvas's gradebook-import layout (columns ``Student``,
  ``ID``, ``SIS User ID``, ``SIS Login ID``, ``Section``, then one assignment column per chapter;
  a second row ``Points Possible``);
* ``OUT.log``: the class log (what failed for whom; never the grading secret);
* ``OUT.feedback/<student>.md``: one file per student to hand back (points per exercise, what
  failed, the attempts the grader stopped);
* ``OUT.similarity.csv``: the students whose code for an exercise is a verbatim copy of each
  other's (identical once comments and blank lines are dropped; one row per group) or nearly so
  once names and numbers are normalised (:func:`similarity`), for the instructor to look at;
* ``OUT.secret`` (mode 0600): the grading secret the hidden data derive from, kept so that a
  re-run grades the remaining students on the same hidden data (``FDI_GRADER_SECRET`` overrides).

How a submission is graded
--------------------------
1. **Isolation.** Each student's notebooks run, one after the other, in a fresh Jupyter kernel
   of that student alone (a new one after a kill; never shared between students) started in a
   scratch folder that holds the student package (``tools/student_package.py``: ``fdi_lib`` without
   ``exercises._reference``) and ``grader_kernel.py``; its import path is that folder and the
   pinned environment, its environment a short allow-list (no secret, no repository path), its
   arguments the kernel's own. The kernel never sees an expected answer: it reports the
   notebook's ``answer`` values and the grader compares them here with the reference it
   recomputes from the student's seed (:func:`accepted`, the same tolerance function as the
   checker's, :func:`fdi_lib.exercises.checker.close`). ``grader_kernel.py`` says what the
   kernel's hooks stop and report (one-call library answers, reading the repository or the
   grader's files or environment, writing outside the scratch folder, processes, ...); a
   violation, or a name of :data:`SUSPICIOUS` in the exercise's code (scanned here, not in the
   kernel), scores the exercise 0 and is named in the log and the feedback.
2. **Limits.** The kernel runs in its own session (process group) under rlimits (address space
   ``--memory-mb``, CPU seconds = the student's time budget, hard), every cell under
   ``--cell-timeout`` and the student under ``--student-timeout`` of wall time. A cell over its
   limit, or a dead kernel, gets the kernel's whole process group killed (SIGKILL: a loop that
   swallows interrupts included); the grader then starts a fresh kernel and goes on with the
   next exercise. A student over the budget gets 0 on what did not run.
3. **Exercise boundaries** come from the cells' metadata ``fdi_book.exercise`` (written by
   ``tools/student_edition.py`` into every student notebook:
   :func:`fdi_lib.exercises.tag_exercise_cells`);
   a cell without it (added by the student) belongs to the exercise of the cell before it. Cells
   outside the exercises run as set-up only when they hold nothing but imports, definitions and
   literal assignments (a helper defined before the exercises), or carry ``fdi_book.setup``.
4. **Two runs** of each checkable exercise's cells: on the student's own data and on hidden data
   (a student id derived from the grading secret); one point each.

Why no otter-grader: the grader used only otter's test-file format (``ExceptionTestFile``) for a
two-line comparison; ``otter grade`` needs Docker and ``otter run`` an autograder zip, neither of
which runs the same cells twice on two data sets. The dependency is dropped (issue 30).
"""

from __future__ import annotations

import argparse
import ast
import csv
import hashlib
import io
import itertools
import os
import re
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import tokenize
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
TOOLS = Path(__file__).resolve().parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from fdi_lib.exercises import (
    CHAPTERS,
    EXERCISES,
    HAND_GRADED,
    exercise_ids,
    get_exercise,
    reference_answer,
)
from fdi_lib.exercises._reference import REFERENCES
from fdi_lib.exercises.book import CELL_KEY
from fdi_lib.exercises.checker import close

#: Points of a checkable exercise: the student's own data, then the hidden data.
POINTS = {"own": 1, "hidden": 1}
RUNS = tuple(POINTS)

#: Names whose presence in an exercise's code scores it 0 (scanned in the grader's process): the
#: means of the attacks on the kernel's hooks, the reference package, the grader's own module.
SUSPICIOUS = (
    "_reference",
    "reference_answer",
    "grader_kernel",
    "__wrapped__",
    "__code__",
    "__closure__",
    "cell_contents",
    "getprofile",
    "setprofile",
    "settrace",
    "addaudithook",
    "ctypes",
    "get_objects",
    "get_referrers",
    "dup2",
    "FDI_GRADER_SECRET",
    "/proc/",
    "_fdi_grader",
)

#: Environment variables a kernel inherits (everything else is dropped: no secret, no path).
ENV_KEEP = ("PATH", "LANG", "LC_ALL", "TZ")

KERNEL_MIME = "application/vnd.fdi-grader+json"

_DATA = re.compile(r"""exercise_data\(\s*["']([a-z]+-\d+)["']""")


# ----------------------------------------------------------------------------- scoring
def accepted(answer, ref: np.ndarray, exercise_id: str) -> str:
    """``"accepted"``, or why ``answer`` is not within the exercise's tolerance of ``ref`` (the
    checker's :func:`~fdi_lib.exercises.checker.close`: one tolerance for wheel and grader)."""
    ex = get_exercise(exercise_id)
    if answer is None:
        return "missing (no `answer`, or the cells failed before setting it)"
    a = np.asarray(answer, dtype=float)
    if a.size == 1 and ref.size == 1:
        a = a.reshape(ref.shape)
    if a.shape != ref.shape:
        return f"of shape {a.shape}, expected {ref.shape}"
    if ex.integer and not np.all(a == np.round(a)):
        return "not a whole number"
    return "accepted" if np.all(close(a, ref, ex)) else "outside the tolerance"


def hidden_student(student: str, secret: str) -> str:
    """The id of a student's hidden data: not guessable without the grading secret."""
    return f"hidden-{hashlib.sha256(f'{secret}/{student}'.encode()).hexdigest()[:16]}"


# ----------------------------------------------------------------------------- planning
@dataclass
class Plan:
    """Which cells of a notebook run: set-up cells, then each checkable exercise's cells."""

    setup: list[str] = field(default_factory=list)
    exercises: dict[str, list[str]] = field(default_factory=dict)
    #: The highest graded-mode attempt number (``check(id, answer, graded=True)``: "attempt N")
    #: that each exercise's saved outputs show: what the student's own session counted, as
    #: handed in (a student can edit outputs: for the instructor's information, never a grade).
    attempts: dict[str, int] = field(default_factory=dict)


def _is_setup(source: str) -> bool:
    """A cell outside the exercises that runs as set-up: imports, definitions, literal
    assignments only (never the chapter's computations)."""
    try:
        body = ast.parse(source).body
    except SyntaxError:
        return False

    def ok(node) -> bool:
        if isinstance(
            node, (ast.Import, ast.ImportFrom, ast.FunctionDef, ast.ClassDef, ast.AsyncFunctionDef)
        ):
            return True
        if isinstance(node, (ast.Assign, ast.AnnAssign)) and node.value is not None:
            try:
                ast.literal_eval(node.value)
            except ValueError:
                return False
            return True
        return False

    return bool(body) and all(ok(n) for n in body)


def plan_notebook(nb) -> Plan:
    """Split a submitted notebook into set-up cells and the cells of each exercise, by the cells'
    ``fdi_book`` metadata; a notebook without any (not from the student edition) by its
    ``exercise_data("<id>")`` calls."""
    plan, current = Plan(), None
    tagged = any(CELL_KEY in c.get("metadata", {}) for c in nb.cells)
    for cell in nb.cells:
        source = cell.source if isinstance(cell.source, str) else "".join(cell.source)
        meta = cell.get("metadata", {}).get(CELL_KEY)
        if isinstance(meta, dict):
            current = meta.get("exercise") if isinstance(meta.get("exercise"), str) else None
        elif not tagged and cell.cell_type == "code" and (m := _DATA.search(source)):
            current = m.group(1)
        if cell.cell_type != "code":
            continue
        if current is None:
            if _is_setup(source) or (isinstance(meta, dict) and meta.get("setup") is True):
                plan.setup.append(source)
        elif current in REFERENCES:
            plan.exercises.setdefault(current, []).append(source)
            shown = re.compile(rf"{re.escape(current)}: attempt (\d+): (?:accepted|not accepted)")
            for n in shown.findall(_output_text(cell)):
                plan.attempts[current] = max(plan.attempts.get(current, 0), int(n))
    return plan


def _output_text(cell) -> str:
    """The text a code cell's saved outputs show (streams and plain-text results)."""
    parts = []
    for out in cell.get("outputs", []):
        text = out.get("text") if out.get("output_type") == "stream" else None
        text = text if text is not None else out.get("data", {}).get("text/plain", "")
        parts.append(text if isinstance(text, str) else "".join(text))
    return "\n".join(parts)


def suspicious(sources: list[str]) -> list[str]:
    """The :data:`SUSPICIOUS` names in an exercise's code, and assignments to ``check``."""
    text = "\n".join(sources)
    found = [name for name in SUSPICIOUS if name in text]
    for src in sources:
        try:
            tree = ast.parse(src)
        except SyntaxError:
            continue
        for node in ast.walk(tree):
            targets = node.targets if isinstance(node, ast.Assign) else []
            if any(getattr(t, "id", getattr(t, "attr", None)) == "check" for t in targets):
                found.append("an assignment to check")
    return sorted(set(found))


# ----------------------------------------------------------------------------- execution
@dataclass
class Limits:
    """Per-cell and per-student wall time (s), memory (MiB) of a kernel."""

    cell: float = 60.0
    student: float = 600.0
    memory_mb: int = 3072


def _kernel_env(scratch: Path) -> dict:
    env = {k: os.environ[k] for k in ENV_KEEP if k in os.environ}
    env.update(
        PYTHONPATH=str(scratch / "lib"),
        HOME=str(scratch),
        TMPDIR=str(scratch),
        IPYTHONDIR=str(scratch / "ipython"),
        MPLCONFIGDIR=str(scratch / "mpl"),
        MPLBACKEND="Agg",
        OMP_NUM_THREADS="1",
        OPENBLAS_NUM_THREADS="1",
        MKL_NUM_THREADS="1",
        PYTHONDONTWRITEBYTECODE="1",
        PYDEVD_DISABLE_FILE_VALIDATION="1",
    )
    return env


def _rlimits(memory_mb: int, cpu_s: int):
    def apply():  # in the child, before exec: hard limits the kernel cannot raise
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (memory_mb << 20, memory_mb << 20))
        resource.setrlimit(resource.RLIMIT_CPU, (cpu_s, cpu_s + 5))
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))

    return apply


def _kill_group(client) -> None:
    """SIGKILL the kernel's whole process group (its own session)."""
    km = getattr(client, "km", None)
    prov = getattr(km, "provisioner", None)
    pgid = getattr(prov, "pgid", None)
    if pgid:
        try:
            os.killpg(pgid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass


@dataclass
class Run:
    """One run of one exercise: the answer reported, the violations, the errors, a limit hit."""

    answer: object = None
    reported: bool = False
    unreadable: str = ""
    violations: list[str] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    stopped: str = ""


def _outputs(cell) -> tuple[list[dict], list[str]]:
    reports, errors = [], []
    for out in cell.get("outputs", []):
        shown = out.get("output_type") in ("display_data", "execute_result")
        data = out.get("data", {}) if shown else {}
        if KERNEL_MIME in data and isinstance(data[KERNEL_MIME], dict):
            reports.append(data[KERNEL_MIME])
        if out.get("output_type") == "error":
            errors.append(f"{out.get('ename')}: {out.get('evalue')}")
    return reports, errors


#: Folder of the staged package that holds matplotlib's font cache (:func:`font_cache`).
FONT_CACHE = "mpl"


def font_cache(package: Path) -> None:
    """Build matplotlib's font cache once, in ``package / FONT_CACHE``, for every kernel to copy:
    built in a fresh ``MPLCONFIGDIR`` it runs ``fc-list`` in a process (a violation inside a
    kernel, see ``grader_kernel.install``) and costs each kernel the scan of the system's fonts."""
    env = {k: os.environ[k] for k in ENV_KEEP if k in os.environ}
    env.update(MPLCONFIGDIR=str(package / FONT_CACHE), MPLBACKEND="Agg")
    subprocess.run(
        [sys.executable, "-c", "import matplotlib.font_manager"],
        env=env,
        check=True,
        capture_output=True,
        timeout=300,
    )


def run_student(
    folder: Path, package: Path, secret: str, limits: Limits, denied: list[Path]
) -> tuple[dict[tuple[str, str], Run], dict[str, list[str]], list[str]]:
    """Execute one student's notebooks; returns ({(exercise, run): Run}, {exercise: code}, log)."""
    import nbformat

    student = folder.name
    log: list[str] = []
    plans = []
    for path in sorted(folder.rglob("*.ipynb")):
        try:
            plans.append(plan_notebook(nbformat.read(path, as_version=4)))
        except Exception as exc:  # noqa: BLE001 -- an unreadable notebook is the student's, logged
            log.append(f"{path.name}: unreadable notebook ({type(exc).__name__}: {str(exc)[:200]})")
    runs: dict[tuple[str, str], Run] = {}
    code = {ex: src for plan in plans for ex, src in plan.exercises.items()}
    tries = {ex: n for plan in plans for ex, n in plan.attempts.items()}
    if tries:
        log.append(
            "graded-mode attempts the submitted outputs show (as handed in): "
            + ", ".join(f"{ex} {n}" for ex, n in tries.items())
        )
    if not code:
        log.append("no checkable exercise found in the submission")
        return runs, code, log
    keys = {"own": student, "hidden": hidden_student(student, secret)}
    deadline = time.monotonic() + limits.student
    with tempfile.TemporaryDirectory(prefix="grade-") as tmp:
        scratch = Path(tmp)
        shutil.copytree(package / "fdi_lib", scratch / "lib" / "fdi_lib")
        if (package / FONT_CACHE).is_dir():
            shutil.copytree(package / FONT_CACHE, scratch / "mpl")
        shutil.copy2(TOOLS / "grader_kernel.py", scratch / "lib" / "grader_kernel.py")
        config = {"scratch": str(scratch), "denied_read": [str(p) for p in denied]}
        # one kernel for all the student's notebooks (a fresh one only after a kill): a kernel's
        # start, hooks and imports cost about a tenth of a student's time (issue 30.2)
        todo = [
            (i, ex, run) for i, plan in enumerate(plans) for ex in plan.exercises for run in RUNS
        ]
        while todo:
            if time.monotonic() >= deadline:
                for _, ex, run in todo:
                    runs.setdefault(
                        (ex, run), Run()
                    ).stopped = "the student's time budget was used up"
                log.append(f"student time limit ({limits.student:g} s) reached")
                break
            todo = _run_kernel(plans, todo, keys, config, scratch, limits, deadline, runs, log)
    return runs, code, log


def _run_kernel(
    plans: list[Plan],
    todo: list,
    keys: dict,
    config: dict,
    scratch: Path,
    limits: Limits,
    deadline: float,
    runs: dict,
    log: list,
) -> list:
    """Run ``todo`` (notebook index, exercise, run) triples in one kernel until done or the kernel
    is lost, each notebook's set-up cells before its first exercise; returns what is left."""
    import nbclient
    import nbformat
    from nbclient.exceptions import CellTimeoutError, DeadKernelError

    new = nbformat.v4.new_code_cell
    nb = nbformat.v4.new_notebook()
    client = nbclient.NotebookClient(
        nb,
        timeout=limits.cell,
        kernel_name="python3",
        allow_errors=True,
        interrupt_on_timeout=False,
        startup_timeout=120,
        resources={"metadata": {"path": str(scratch)}},
    )
    cpu = int(max(1.0, deadline - time.monotonic())) + 1
    started, set_up = False, set()

    def execute(source: str) -> list[dict]:
        cell = new(source)
        nb.cells.append(cell)
        client.timeout = max(1, int(min(limits.cell, deadline - time.monotonic())))
        client.execute_cell(cell, len(nb.cells) - 1)
        return cell

    try:
        with client.setup_kernel(
            env=_kernel_env(scratch),
            cwd=str(scratch),
            stderr=subprocess.DEVNULL,
            preexec_fn=_rlimits(limits.memory_mb, cpu),
        ):
            install = execute(
                f"import grader_kernel as _fdi_grader\n_fdi_grader.install({config!r})"
            )
            if _outputs(install)[1]:
                raise RuntimeError(f"grader hooks failed: {_outputs(install)[1]}")
            while todo:
                i, ex, run = todo[0]
                if i not in set_up:
                    started = False
                    for src in plans[i].setup:
                        execute(src)
                    set_up.add(i)
                started = True
                result = runs.setdefault((ex, run), Run())
                current = [
                    execute(
                        f"_fdi_grader.begin({ex!r}, {run!r}, {keys[run]!r}, "
                        f"{list(REFERENCES[ex].one_call)!r})"
                    )
                ]
                try:
                    for src in plans[i].exercises[ex]:
                        current.append(execute(src))
                    current.append(execute(f"_fdi_grader.end({ex!r}, {run!r})"))
                finally:
                    _collect(current, ex, run, result)
                todo = todo[1:]
    except (CellTimeoutError, DeadKernelError, RuntimeError, TimeoutError) as exc:
        _kill_group(client)
        i, ex, run = todo[0]
        what = (
            "a cell ran over its time limit"
            if isinstance(exc, CellTimeoutError)
            else f"the kernel died or failed ({type(exc).__name__}: {str(exc)[:120]})"
        )
        # the same cells would hang or crash on the other data too: the exercise is stopped;
        # a kernel lost before the exercises (set-up cells, hooks) stops the notebook
        lost = [(j, e, r) for j, e, r in todo if j == i and (e == ex or not started)]
        for _, e, r in lost:
            runs.setdefault((e, r), Run()).stopped = what
        log.append(
            f"{ex if started else 'set-up'} ({run} data): {what}; the kernel's process "
            "group was killed"
        )
        return [t for t in todo if t not in lost]
    finally:
        _kill_group(client)
    return todo


def _collect(cells: list, ex: str, run: str, result: Run) -> None:
    for cell in cells:
        reports, errors = _outputs(cell)
        result.errors += errors
        for rep in reports:
            if rep.get("kind") == "violation":
                result.violations.append(str(rep.get("what")))
            elif (rep.get("kind"), rep.get("run"), rep.get("exercise")) == (
                "answer",
                f"{ex}/{run}",
                ex,
            ):
                result.answer, result.reported = rep.get("answer"), True
                result.unreadable = str(rep.get("unreadable") or "")


# ----------------------------------------------------------------------------- similarity
def _normalised(source: str) -> tuple[str, list[str]]:
    """(the code without comments and blank lines, its tokens with names and numbers replaced)."""
    kept, tokens = [], []
    try:
        for tok in tokenize.generate_tokens(io.StringIO(source).readline):
            if tok.type in (
                tokenize.COMMENT,
                tokenize.NL,
                tokenize.NEWLINE,
                tokenize.INDENT,
                tokenize.DEDENT,
                tokenize.ENDMARKER,
            ):
                continue
            kept.append(tok.string)
            tokens.append(
                "N"
                if tok.type == tokenize.NAME and tok.string not in _KEYWORDS
                else "0"
                if tok.type == tokenize.NUMBER
                else tok.string
            )
    except (tokenize.TokenError, IndentationError, SyntaxError):
        kept = tokens = source.split()
    return " ".join(kept), tokens


_KEYWORDS = set(__import__("keyword").kwlist)


def similarity(
    codes: dict[str, dict[str, list[str]]],
    starters: dict[str, set[str]],
    threshold: float = 0.9,
    min_tokens: int = 20,
) -> list[dict]:
    """Groups of students whose own code for an exercise (the starter cells left out) is a verbatim
    copy (``"verbatim"``: identical once comments and layout are dropped), and pairs outside such
    a group that share at least ``threshold`` of their 5-token shingles once names and numbers are
    normalised (``"similar"``, with the Jaccard index).

    Hand-written rather than copydetect (on PyPI): the submissions are short Python cells, the
    tokenizer of the standard library normalises them, and the pairwise Jaccard of shingles is a
    dozen lines; copydetect would add a dependency and an HTML report for the same decision.
    """
    out = []
    for ex in sorted({e for c in codes.values() for e in c}):
        mine = {}
        for student, per in codes.items():
            own = [s for s in per.get(ex, []) if s.strip() not in starters.get(ex, set())]
            text, tokens = _normalised("\n".join(own))
            if len(tokens) >= min_tokens:
                mine[student] = (text, {tuple(tokens[i : i + 5]) for i in range(len(tokens) - 4)})
        groups: dict[str, list[str]] = {}
        for student in sorted(mine):
            groups.setdefault(mine[student][0], []).append(student)
        out += [
            {"exercise": ex, "students": " ".join(g), "kind": "verbatim", "jaccard": "1.000"}
            for g in groups.values()
            if len(g) > 1
        ]
        for a, b in itertools.combinations(sorted(mine), 2):
            (ta, sa), (tb, sb) = mine[a], mine[b]
            jac = len(sa & sb) / len(sa | sb)
            if ta != tb and jac >= threshold:
                out.append(
                    {
                        "exercise": ex,
                        "students": f"{a} {b}",
                        "kind": "similar",
                        "jaccard": f"{jac:.3f}",
                    }
                )
    return out


def starter_cells() -> dict[str, set[str]]:
    """The starter code cells of every exercise (what every student's notebook holds)."""
    from fdi_lib.exercises import code_cells, parse_chapter, strip_solutions

    out: dict[str, set[str]] = {}
    for chapter in CHAPTERS:
        text = strip_solutions((REPO / "book" / f"{chapter}.md").read_text())
        for ex in parse_chapter(text):
            out[ex.id] = {c.strip() for c in code_cells(ex.exercise)}
    return out


# ----------------------------------------------------------------------------- gradebook
def columns(chapters: list[str]) -> tuple[list[str], dict[str, str]]:
    """The gradebook's columns for the graded ``chapters``, and each chapter's column name."""
    ids = [i for i in exercise_ids(checkable=True) if EXERCISES[i].chapter in chapters]
    full = sum(POINTS.values())
    names = {c: f"{c} (/{full * sum(EXERCISES[i].chapter == c for i in ids)})" for c in chapters}
    rubric = [
        f"rubric {e.id}"
        for e in EXERCISES.values()
        if e.chapter in chapters and (e.id in HAND_GRADED or not e.checkable)
    ]
    return ["student", *ids, *names.values(), "total", "possible", *rubric], names


def score_student(
    student: str, secret: str, runs: dict, code: dict, ids: list[str]
) -> tuple[dict, list[str], dict[str, list[str]]]:
    """Points per exercise, the log lines and, per exercise, what failed (the feedback)."""
    hidden = hidden_student(student, secret)
    row, log, why = {}, [], {}
    for ex in ids:
        flags = suspicious(code.get(ex, []))
        notes, points = [], 0
        if ex not in code:
            row[ex] = 0
            continue
        for run, key in (("own", student), ("hidden", hidden)):
            r = runs.get((ex, run), Run())
            if r.stopped:
                notes.append(f"{run} data: stopped, {r.stopped}")
            elif r.violations:
                seen = list(dict.fromkeys(r.violations))
                notes += [f"{run} data: attempt stopped: {v}" for v in seen[:3]]
                notes += [f"{run} data: and {len(seen) - 3} more attempts"] if len(seen) > 3 else []
            elif flags:
                notes.append(
                    f"{run} data: not graded, the code holds {', '.join(flags)} (not "
                    "allowed in a graded exercise)"
                )
            else:
                verdict = (
                    "answer unreadable (" + r.unreadable + ")"
                    if r.unreadable
                    else accepted(r.answer, reference_answer(ex, key), ex)
                )
                if verdict == "accepted":
                    points += POINTS[run]
                else:
                    notes.append(
                        f"{run} data: the answer is {verdict}"
                        + (
                            f" (error: {r.errors[-1][:160]})"
                            if r.errors and r.answer is None
                            else ""
                        )
                    )
        row[ex] = points
        why[ex] = notes
        log += [f"{ex}: {n}" for n in notes]
    return row, log, why


def feedback(student: str, row: dict, why: dict, ids: list[str], notes: list[str]) -> str:
    lines = [
        f"# Feedback for {student}",
        "",
        f"Total: {row['total']:g} / {row['possible']:g}",
        "",
        "| exercise | points | what failed |",
        "|---|---|---|",
    ]
    full = sum(POINTS.values())
    for ex in ids:
        what = "; ".join(why.get(ex, [])) or ("not submitted" if ex not in why else "")
        lines.append(f"| {ex} | {row[ex]:g} / {full} | {what.replace('|', '/')} |")
    if notes:
        lines += ["", "Notes:", *[f"- {n}" for n in notes]]
    return "\n".join(lines) + "\n"


def _append_row(path: Path, header: list[str], row: dict) -> None:
    new = not path.exists() or path.stat().st_size == 0
    with path.open("a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=header)
        if new:
            writer.writeheader()
        writer.writerow({k: (f"{v:g}" if isinstance(v, float) else v) for k, v in row.items()})
        f.flush()
        os.fsync(f.fileno())


def _graded_students(path: Path, header: list[str]) -> set[str]:
    if not path.exists() or path.stat().st_size == 0:
        return set()
    with path.open(newline="") as f:
        reader = csv.DictReader(f)
        if reader.fieldnames != header:
            raise SystemExit(
                f"OUT: {path} has other columns than this grading (other chapters?): "
                "grade into a new file"
            )
        return {r["student"] for r in reader}


def canvas_export(gradebook: Path, names: dict[str, str], out: Path) -> None:
    """Canvas's gradebook-import CSV of ``gradebook``: Student, ID, SIS User ID, SIS Login ID,
    Section, one column per chapter, and the ``Points Possible`` row."""
    with gradebook.open(newline="") as f:
        rows = list(csv.DictReader(f))
    head = ["Student", "ID", "SIS User ID", "SIS Login ID", "Section", *names]
    with out.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(head)
        possible = [n.rsplit("/", 1)[1].rstrip(")") for n in names.values()]
        w.writerow(["Points Possible", "", "", "", "", *possible])
        for r in rows:
            points = [r[n] for n in names.values()]
            w.writerow([r["student"], "", r["student"], r["student"], "", *points])


def _secret(out: Path, given: str | None) -> str:
    path = out.with_suffix(".secret")
    if given:
        return given
    if path.exists():
        return path.read_text().strip()
    value = secrets.token_hex(16)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "w") as f:
        f.write(value + "\n")
    return value


def grade(
    submissions: Path,
    out: Path,
    log_path: Path | None = None,
    limits: Limits | None = None,
    secret: str | None = None,
    jobs: int = 1,
    chapters: list[str] | None = None,
) -> list[dict]:
    """Grade every student folder of ``submissions`` not yet in ``out``; returns all rows.

    ``jobs`` kernels run at once (one per student); the gradebook is the same for any ``jobs``
    (rows are appended as students finish: their order may differ)."""
    from concurrent.futures import ThreadPoolExecutor, as_completed
    from threading import Lock

    import student_package

    submissions, out = submissions.resolve(), out.resolve()
    limits = limits or Limits()
    out.parent.mkdir(parents=True, exist_ok=True)
    secret = _secret(out, secret or os.environ.get("FDI_GRADER_SECRET"))
    log_path = log_path or out.with_suffix(".log")
    fb_dir = out.with_suffix(".feedback")
    fb_dir.mkdir(exist_ok=True)
    chapters = chapters or list(CHAPTERS)
    header, names = columns(chapters)
    ids = [h for h in header if h in EXERCISES]
    done = _graded_students(out, header)
    folders = sorted(p for p in submissions.iterdir() if p.is_dir() and p.name not in done)
    denied = [REPO, submissions, out.parent]
    lock, codes = Lock(), {}

    def one(folder: Path, package: Path):
        t0 = time.monotonic()
        runs, code, notes = run_student(folder, package, secret, limits, denied)
        row, lines, why = score_student(folder.name, secret, runs, code, ids)
        row = {"student": folder.name, **row}
        for chapter, name in names.items():
            row[name] = sum(row[i] for i in ids if EXERCISES[i].chapter == chapter)
        row["total"] = sum(row[i] for i in ids)
        row["possible"] = sum(POINTS.values()) * len(ids)
        with lock:
            _append_row(out, header, row)
            (fb_dir / f"{folder.name}.md").write_text(feedback(folder.name, row, why, ids, notes))
            with log_path.open("a") as f:
                f.write(
                    "\n".join(
                        [
                            f"== {folder.name}: {row['total']:g} / {row['possible']} "
                            f"({time.monotonic() - t0:.1f} s)",
                            *notes,
                            *lines,
                            "",
                        ]
                    )
                    + "\n"
                )
            codes[folder.name] = code
        return row

    with tempfile.TemporaryDirectory(prefix="fdi-student-package-") as tmp:
        package = student_package.stage(Path(tmp) / "package", with_digests=False)
        font_cache(package)
        with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
            for fut in as_completed([pool.submit(one, f, package) for f in folders]):
                fut.result()
    canvas_export(out, names, out.with_suffix(".canvas.csv"))
    pairs = similarity(codes, starter_cells())
    with out.with_suffix(".similarity.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["exercise", "students", "kind", "jaccard"])
        w.writeheader()
        w.writerows(pairs)
    with out.open(newline="") as f:
        return list(csv.DictReader(f))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("submissions", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--log", type=Path)
    parser.add_argument("--cell-timeout", type=float, default=60.0, help="wall seconds per cell")
    parser.add_argument(
        "--student-timeout", type=float, default=600.0, help="wall seconds per student"
    )
    parser.add_argument("--memory-mb", type=int, default=3072, help="address space of a kernel")
    parser.add_argument("--jobs", type=int, default=1, help="kernels at once (one per student)")
    parser.add_argument("--chapters", nargs="*", choices=list(CHAPTERS), help="the graded chapters")
    args = parser.parse_args(argv)
    if not args.submissions.is_dir():
        parser.error(f"SUBMISSIONS: expected a folder of student folders, got {args.submissions}")
    limits = Limits(args.cell_timeout, args.student_timeout, args.memory_mb)
    rows = grade(
        args.submissions, args.out, args.log, limits, jobs=args.jobs, chapters=args.chapters
    )
    print(
        f"{len(rows)} students in {args.out} (log: {args.out.with_suffix('.log')}, feedback: "
        f"{args.out.with_suffix('.feedback')}/, Canvas: {args.out.with_suffix('.canvas.csv')}, "
        f"similarity: {args.out.with_suffix('.similarity.csv')})"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
