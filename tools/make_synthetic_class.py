"""A synthetic class of three submissions, to test the grader (``tools/grader.py``):

    python tools/make_synthetic_class.py OUT [--chapters zb2014/glr ...]

* ``OUT/reference``: the student notebooks with the book's solution cells written into each
  exercise, after its starter cell (what a student who solved everything hands in);
* ``OUT/starter``: the student notebooks untouched;
* ``OUT/cheater``: the student notebooks with a cell per checkable exercise that prints
  "correct" and takes the answer from the library: the function that answers in one call where
  there is one, else ``reference_answer`` (not shipped to students) and, failing that, the book's
  own answer typed in (as copied from the instructor's edition or a neighbour).

The notebooks are written as ``tools/student_edition.py`` writes the student edition's
(jupytext, from the chapters with the solutions stripped).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
for path in (REPO, REPO / "tools"):
    if str(path) not in sys.path:
        sys.path.insert(0, str(path))

from fdi_lib.exercises import (CHAPTERS, EXERCISES, code_cells, parse_chapter,  # noqa: E402
                               reference_answer, strip_solutions)

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


def _cell(source: str) -> str:
    return f"```{{code-cell}} ipython3\n{source.rstrip()}\n```\n\n"


def _cheat(exercise_id: str) -> str:
    book = reference_answer(exercise_id).tolist()   # the instructor's edition shows it
    take = ONE_CALL.get(exercise_id, f"from fdi_lib.exercises import reference_answer\n"
                                     f"answer = reference_answer({exercise_id!r})")
    return (f"print({exercise_id + ': correct (tolerance: relative 1e-06).'!r})\n"
            f"try:\n" + "".join(f"    {line}\n" for line in take.splitlines()) +
            f"except Exception:\n    answer = {book!r}\n")


def submission(text: str, kind: str) -> str:
    """A chapter's student MyST text as the ``kind`` student ("reference", "starter" or
    "cheater") hands it in."""
    stripped = strip_solutions(text)
    if kind == "starter":
        return stripped
    for ex in parse_chapter(text):
        if not EXERCISES[ex.id].checkable:
            continue
        extra = code_cells(ex.solution) if kind == "reference" else [_cheat(ex.id)]
        body = ex.exercise.rstrip("\n") + "\n\n" + "".join(_cell(c) for c in extra)
        stripped = stripped.replace(ex.exercise, body, 1)
    return stripped


def write_class(out: Path, chapters: list[str] | None = None) -> list[Path]:
    """Write the three submissions under ``out``; returns the student folders."""
    import jupytext

    folders = []
    for kind in ("reference", "starter", "cheater"):
        folder = out / kind
        folder.mkdir(parents=True, exist_ok=True)
        for chapter in chapters or list(CHAPTERS):
            text = (REPO / "book" / f"{chapter}.md").read_text()
            nb = jupytext.reads(submission(text, kind), fmt="md:myst")
            jupytext.write(nb, folder / f"{chapter.replace('/', '-')}.ipynb")
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
