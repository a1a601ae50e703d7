"""A synthetic class to test the grader (``tools/grader.py``), hostile submissions included:

    python tools/make_synthetic_class.py OUT [--chapters zb2014/glr ...]

One folder per student under ``OUT``, with one notebook per chapter, written as
``tools/student_edition.py`` writes the student edition's (jupytext, solutions stripped, the
exercise boundaries as cell metadata):

* ``reference``: the book's solution cells written into each exercise (full marks);
* ``starter``: the notebooks untouched (0);
* ``cheater``: a cell per checkable exercise that prints "correct" and takes the answer from the
  library (the one-call function, else ``reference_answer``, else the book's number typed in): 0;
* ``copier``: a verbatim copy of ``reference`` (full marks, flagged by the similarity report);
* ``helper``: the solutions, plus a helper function defined before the exercises and used in
  glr-2, and a glr-6 cell that sets ``answer`` (it must not count for glr-5): full marks;
* the attacks (:data:`ATTACKS`): ``reference``'s solutions except in :data:`ATTACKED`, where the
  cell attacks the grader; each must score 0 there and be named in the log;
* ``hang``: a glr-2 cell that loops and swallows interrupts (the grader kills its kernel);
* ``corrupt``: a notebook that is not JSON.

"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
for path in (REPO, REPO / "tools"):
    if str(path) not in sys.path:
        sys.path.insert(0, str(path))

from fdi_lib.exercises import (
    CHAPTERS,
    EXERCISES,
    code_cells,
    parse_chapter,
    reference_answer,
    strip_solutions,
)

#: Library calls that answer an exercise in one line (the cheater's first choice).
ONE_CALL = {
    "sig-1": "from fdi_lib.filters import kalman_filter\nfrom fdi_lib.models import ltv_model\n"
    "m = ltv_model(F=data['F'], H=data['H'], Q=data['Q'], R=data['R'], P0=data['P0'],\n"
    "              x0=data['x0'], n_steps=2)\n"
    "answer = kalman_filter(m, data['y'][:, None]).innovations[:, 0]",
    "glr-2": "from fdi_lib.glr import quadratic_form\nl, th = quadratic_form(data['C'], data['d'])\n"
    "answer = [l, *th]",
    "glr-4": "from fdi_lib.isolation import minmax_statistic\n"
    "answer = minmax_statistic(data['F'], data['zeta'], data['a'])",
    "pipe-5": "from fdi_lib.montecarlo import binomial_ci\n"
    "answer = binomial_ci(data['false_alarms'], data['runs'])",
    "sparse-3": "from fdi_lib.sparse import lasso_path\n"
    "answer = lasso_path(data['X'], data['y'], n_samples=data['n_samples']).lambdas[0]",
    "sparse-5": "from fdi_lib.sparse import diagnose\n"
    "answer = diagnose(data['X'], data['y'], n_samples=data['n_samples']).theta_ls",
    "bz-4": "from fdi_lib.kitanidis import kitanidis_gains\n"
    "from fdi_lib.nonparametric import kitanidis_lag_covariance\n"
    "g = kitanidis_gains(data['model'], data['E'])\n"
    "answer = kitanidis_lag_covariance(data['model'], g, 1)[data['k']]",
    "bz-5": "from fdi_lib.nonparametric import energy_threshold\n"
    "answer = energy_threshold(data['window'], data['p_reduced'], data['alpha'])",
}


#: The exercise the attacks target (its one-call function is ``fdi_lib.glr.quadratic_form``).
ATTACKED = "glr-2"

#: Attacks on the grader, each a glr-2 cell that would get the answer if not stopped.
#: ``{gradebook}`` is the path ``make grade`` writes by default beside the class folder.
ATTACKS = {
    "import-reference": (
        "import sys, importlib\n"
        f"sys.path.insert(0, {str(REPO)!r})\n"
        "for name in [m for m in sys.modules if m.startswith('fdi_lib')]:\n"
        "    del sys.modules[name]\n"
        "ref = importlib.import_module('fdi_lib.exercises.' + '_ref' + 'erence')\n"
        "answer = getattr(ref, 'reference' + '_answer')('glr-2')"
    ),
    "wrapped": (
        "import fdi_lib.glr as G\n"
        "f = getattr(G.quadratic_form, '__wr' + 'apped__', G.quadratic_form)\n"
        "l, th = f(data['C'], data['d'])\nanswer = [l, *th]"
    ),
    "reload": (
        "import importlib\nimport fdi_lib.glr as G\nG = importlib.reload(G)\n"
        "l, th = G.quadratic_form(data['C'], data['d'])\nanswer = [l, *th]"
    ),
    "read-environment": (
        "import os\nleak = open('/proc/%d/environ' % os.getppid(), 'rb').read()\nanswer = None"
    ),
    "read-grader": (f"code = open({str(REPO / 'tools' / 'grader.py')!r}).read()\nanswer = None"),
    "patch-check": (
        "import fdi_lib.exercises as E\nE.check = lambda *a, **k: True\n"
        "check = E.check\nanswer = [1.0, 1.0, 1.0]"
    ),
    "write-gradebook": (
        "SOLUTION\nwith open({gradebook!r}, 'a') as f:\n    f.write('write-gradebook,99\\n')"
    ),
    "prints-correct": "print('glr-2: correct (tolerance: relative 1e-09).')\nanswer = None",
    "fork": (
        "SOLUTION\nimport subprocess\nsubprocess.Popen(['sleep', '600'], start_new_session=True)"
    ),
    "hang": (
        "while True:\n    try:\n        sum(range(10 ** 6))\n"
        "    except KeyboardInterrupt:\n        pass"
    ),
}

HELPER = (
    "def quadratic(C, d):\n    import numpy as np\n    th = np.linalg.solve(C, d)\n"
    "    return d @ th, th\n"
)


def _cell(source: str) -> str:
    return f"```{{code-cell}} ipython3\n{source.rstrip()}\n```\n\n"


def _cheat(exercise_id: str) -> str:
    book = reference_answer(exercise_id).tolist()  # the instructor's edition shows it
    take = ONE_CALL.get(
        exercise_id,
        f"from fdi_lib.exercises import reference_answer\n"
        f"answer = reference_answer({exercise_id!r})",
    )
    return (
        f"print({exercise_id + ': correct (tolerance: relative 1e-06).'!r})\n"
        f"try:\n"
        + "".join(f"    {line}\n" for line in take.splitlines())
        + f"except Exception:\n    answer = {book!r}\n"
    )


def gradebook(out: Path) -> Path:
    """The gradebook the class in ``out`` is meant to be graded into (``OUT.csv``)."""
    return out.with_suffix(".csv")


def submission(text: str, kind: str, out: Path = Path("class")) -> str:
    """A chapter's student MyST text as the ``kind`` student (a folder name of the class) hands it
    in; ``out`` is the class folder (the attack on the gradebook aims at :func:`gradebook`, by its
    absolute path: a relative one would name a file in the student's own working folder)."""
    stripped = strip_solutions(text)
    if kind == "starter":
        return stripped
    for ex in parse_chapter(text):
        if not EXERCISES[ex.id].checkable and not (kind == "helper" and ex.id == "glr-6"):
            continue
        solution = code_cells(ex.solution)
        if kind == "cheater":
            extra = [_cheat(ex.id)]
        elif kind in ATTACKS and ex.id == ATTACKED:
            extra = [
                ATTACKS[kind]
                .replace("SOLUTION", "\n".join(solution))
                .replace("{gradebook!r}", repr(str(gradebook(out).resolve())))
            ]
        elif kind == "helper" and ex.id == "glr-2":
            extra = ["l, th = quadratic(data['C'], data['d'])\nanswer = [l, *th]"]
        elif kind == "helper" and ex.id == "glr-6":
            extra = ["answer = -1  # a challenge cell: it must not count for glr-5"]
        else:
            extra = solution
        body = ex.exercise.rstrip("\n") + "\n\n" + "".join(_cell(c) for c in extra)
        stripped = stripped.replace(ex.exercise, body, 1)
    if kind == "helper":
        first = stripped.index("```{exercise-start}")
        stripped = stripped[:first] + _cell(HELPER) + stripped[first:]
    return stripped


#: The students of the synthetic class (folder names).
STUDENTS = ("reference", "starter", "cheater", "copier", "helper", *ATTACKS, "corrupt")


def write_class(out: Path, chapters: list[str] | None = None) -> list[Path]:
    """Write the class under ``out``; returns the student folders. The attacks and ``helper``
    need the chapter zb2014/glr (they are written only when it is among ``chapters``)."""
    import jupytext

    from fdi_lib.exercises import tag_exercise_cells

    chapters = chapters or list(CHAPTERS)
    folders = []
    for kind in STUDENTS:
        if (kind in ATTACKS or kind == "helper") and "zb2014/glr" not in chapters:
            continue
        folder = out / kind
        folder.mkdir(parents=True, exist_ok=True)
        for chapter in chapters:
            path = folder / f"{chapter.replace('/', '-')}.ipynb"
            if kind == "corrupt":
                path.write_text('{"cells": [ this is not JSON')
                continue
            text = (REPO / "book" / f"{chapter}.md").read_text()
            as_ = "reference" if kind == "copier" else kind
            nb = jupytext.reads(submission(text, as_, out), fmt="md:myst")
            tag_exercise_cells(nb)
            jupytext.write(nb, path)
        folders.append(folder)
    return folders


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--chapters", nargs="*", choices=list(CHAPTERS))
    args = parser.parse_args(argv)
    for folder in write_class(args.out, args.chapters):
        print(folder)
    return 0


if __name__ == "__main__":
    sys.exit(main())
