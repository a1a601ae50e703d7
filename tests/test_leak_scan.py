"""The student edition's leak scan (``tools/student_edition.py verify``) on small synthetic
student editions (no book build): a clean one passes, and each kind of planted solution material
is caught: numbers, code, maths, cell outputs, cell metadata, a two-line solution, the wheel.

The clean edition is made from the real chapters with their solutions stripped: the notebooks
as ``make student`` writes them, one HTML page holding a chapter's text.
"""

from __future__ import annotations

import shutil
import sys
import zipfile
from pathlib import Path

import nbformat
import numpy as np
import pytest

from fdi_lib.exercises import parse_chapter, solution_fingerprints, strip_solutions, words

ROOT = Path(__file__).resolve().parents[1]
BOOK = ROOT / "book"
sys.path.insert(0, str(ROOT / "tools"))
import student_edition as S  # noqa: E402

#: Answers are computed for these exercises only (the others' take seconds each).
ANSWERS_OF = ("glr-2", "glr-3", "glr-4")


@pytest.fixture(scope="module")
def material():
    return S.solution_material(BOOK, answers_of=ANSWERS_OF)


@pytest.fixture(scope="module")
def clean_edition(tmp_path_factory):
    """A student edition of the real chapters: notebooks and one page, no solutions."""
    out = tmp_path_factory.mktemp("student")
    src = out / "src"
    src.mkdir()
    for name in ("_toc.yml", "_config.yml"):
        shutil.copy2(ROOT / name, src / name)
    shutil.copytree(BOOK, src / "book")
    for path in (src / "book").rglob("*.md"):
        path.write_text(strip_solutions(path.read_text()))
    S.write_notebooks(src, out)
    (out / "html").mkdir()
    chapter = strip_solutions((BOOK / "zb2014" / "glr.md").read_text())
    page = f"<html><body><div class='exercise'>{chapter}</div></body></html>"
    (out / "html" / "glr.html").write_text(page)
    return out


def _copy(edition: Path, tmp_path: Path) -> Path:
    out = tmp_path / "student"
    shutil.copytree(edition, out)
    return out


def _solution(exercise_id: str) -> str:
    chapter = (BOOK / "zb2014" / "glr.md").read_text()
    return next(ex.solution for ex in parse_chapter(chapter) if ex.id == exercise_id)


def _plant_html(out: Path, html: str) -> None:
    page = out / "html" / "glr.html"
    page.write_text(page.read_text().replace("</body>", f"{html}</body>"))


def _plant_cell(out: Path, cell) -> Path:
    path = out / "notebooks" / "zb2014" / "glr.ipynb"
    nb = nbformat.read(path, as_version=4)
    nb.cells.append(cell)
    nbformat.write(nb, path)
    return path


# ----------------------------------------------------------------------------- the clean edition
def test_a_clean_student_edition_passes(clean_edition, material):
    assert S.verify(clean_edition, material=material) == []


def test_the_material_covers_every_kind(material):
    assert len(material.fingerprints) > 1000 and len(material.code) > 100 and material.maths
    assert {"_glr2_ref", "_glr4_ref"} <= material.references
    assert set(material.answers.values()) == set(ANSWERS_OF)


# ----------------------------------------------------------------------------- planted leaks
@pytest.mark.parametrize("printed", ["{:.4g}", "{:.6f}", "{!r}", "{:.3e}"])
def test_numbers_printed_to_four_digits_or_more_are_caught(
    clean_edition, material, tmp_path, printed
):
    out = _copy(clean_edition, tmp_path)
    value = float(S.reference_answer("glr-3")[1])  # the detection probability
    _plant_html(out, f"<p>so P = {printed.format(value)}</p>")
    (problem,) = S.verify(out, material=material)
    assert "glr.html" in problem and "reference answers" in problem and "glr-3" in problem


def test_numbers_too_short_or_printed_by_the_book_are_not_answers(material):
    value = float(S.reference_answer("glr-3")[1])
    assert (
        S._matches(
            S.printed_numbers(f"{value:.2f} and {value:.3f}"), np.array(sorted(material.answers))
        )
        == set()
    )
    assert not S._distinctive(1.2000000001, 2.0) and not S._distinctive(98.0, 98.0)
    assert not S._distinctive(1e-20, 1.0) and S._distinctive(0.9721976, 1.0)
    assert S.printed_numbers("x = 0.59915, y = 1.5e-3, n = 12345, k = 98") == [
        (0.59915, 5e-06),
        (12345.0, 0.5),
    ]
    # an answer the chapter prints itself is not distinctive
    printed = S.solution_material(BOOK, printed=f"{value:.4f}", answers_of=("glr-3",))
    assert value not in printed.answers


def test_what_the_chapters_print_outside_their_exercises_is_not_a_leak(tmp_path):
    """An answer a chapter prints itself (sig-5's slope in the claims ledger) is allowed; what a
    starter cell of the Exercises section prints is not."""
    nb = nbformat.v4.new_notebook(
        cells=[
            nbformat.v4.new_code_cell(
                "slope",
                outputs=[
                    nbformat.v4.new_output(
                        "execute_result", data={"text/plain": "0.07918"}, execution_count=1
                    )
                ],
            ),
            nbformat.v4.new_markdown_cell("## Exercises"),
            nbformat.v4.new_code_cell(
                "print(data)", outputs=[nbformat.v4.new_output("stream", text="x = 3.1803\n")]
            ),
        ]
    )
    nbformat.write(nb, tmp_path / "ch.ipynb")
    (tmp_path / "ch.glue.json").write_text('{"k": {"data": {"text/plain": "17.683"}}}')
    printed = S.printed_by_the_book(tmp_path)
    assert "0.07918" in printed and "17.683" in printed and "3.1803" not in printed


def test_solution_code_is_caught(clean_edition, material, tmp_path):
    out = _copy(clean_edition, tmp_path)
    line = next(x for x in _solution("glr-2").splitlines() if x.startswith("C_inv"))
    _plant_cell(out, nbformat.v4.new_code_cell(f"# my answer\n{line}\nprint(C_inv)"))
    (problem,) = S.verify(out, material=material)
    assert "glr.ipynb" in problem and "1 lines of solution code" in problem


def test_solution_maths_is_caught(clean_edition, material, tmp_path):
    out = _copy(clean_edition, tmp_path)
    formula = next(iter(material.maths.values()))
    _plant_html(out, f'<div class="math notranslate nohighlight">\\[C^{{-1}} = {formula}\\]</div>')
    (problem,) = S.verify(out, material=material)
    assert "formulas of the solutions" in problem


def test_solution_outputs_are_caught(clean_edition, material, tmp_path):
    out = _copy(clean_edition, tmp_path)
    _plant_html(
        out,
        "<div class='cell_output'><pre>glr-5: correct (tolerance: exact (integers)).</pre></div>",
    )
    cell = nbformat.v4.new_code_cell("check('glr-5', answer)")
    cell.outputs = [nbformat.v4.new_output("stream", name="stdout", text="r from 4 to 101\n")]
    _plant_cell(out, cell)
    found = S.verify(out, material=material)
    assert any("glr.html" in p and "the output of a solution" in p for p in found)
    assert any("glr.ipynb" in p and "has outputs" in p for p in found)


def test_solution_metadata_is_caught(clean_edition, material, tmp_path):
    out = _copy(clean_edition, tmp_path)
    cell = nbformat.v4.new_code_cell("")
    cell.metadata["tags"] = ["hide-input", "solution"]
    _plant_cell(out, cell)
    (problem,) = S.verify(out, material=material)
    assert "metadata naming a solution" in problem
    _plant_cell(
        out,
        nbformat.v4.new_code_cell("", metadata={"nbgrader": {"solution": True, "grade": False}}),
    )
    assert len(S.verify(out, material=material)) == 2


def test_a_two_line_solution_is_caught(clean_edition, material, tmp_path):
    """glr-5's solution is two lines of prose, seven words outside its maths: the old scan (runs
    of eight words) could not see it."""
    out = _copy(clean_edition, tmp_path)
    prose = _solution("glr-5").split("```{code-cell}")[0].strip()
    assert len(prose.splitlines()) <= 2 and len(words(prose)) < 8
    full = (BOOK / "zb2014" / "glr.md").read_text()
    assert not any(
        tuple(words(prose)[i : i + 8]) in solution_fingerprints(full, strip_solutions(full))
        for i in range(len(words(prose)))
    )
    _plant_cell(out, nbformat.v4.new_markdown_cell(prose))
    (problem,) = S.verify(out, material=material)
    assert "runs of solution text" in problem


def test_solution_blocks_are_caught(clean_edition, material, tmp_path):
    out = _copy(clean_edition, tmp_path)
    _plant_html(out, "<div class='solution dropdown admonition'>x</div>")
    _plant_cell(out, nbformat.v4.new_markdown_cell("**Solution of exercise glr-1**"))
    found = S.verify(out, material=material)
    assert any("solution block (class 'solution dropdown admonition')" in p for p in found)
    assert any("glr.ipynb: a solution block" in p for p in found)


def _wheel(out: Path, files: dict[str, str]) -> None:
    (out / "dist").mkdir(exist_ok=True)
    with zipfile.ZipFile(out / "dist" / "fdi_lib-0.1-py3-none-any.whl", "w") as z:
        for name, text in files.items():
            z.writestr(name, text)


def test_the_wheel_is_scanned(clean_edition, material, tmp_path):
    out = _copy(clean_edition, tmp_path)
    _wheel(
        out,
        {
            "fdi_lib/exercises/glr.py": "def _glr2_data():\n    return {}\n",
            "fdi_lib-0.1.dist-info/METADATA": "Name: fdi-lib\n",
        },
    )
    assert S.verify(out, material=material) == []
    value = float(S.reference_answer("glr-4"))
    _wheel(
        out,
        {
            "fdi_lib/exercises/glr.py": "def _glr4_ref(d):\n    return 0.0\n",
            "fdi_lib/exercises/answers.json": f'{{"glr-4": {value!r}}}',
        },
    )
    found = S.verify(out, material=material)
    assert any("glr.py: defines the reference code _glr4_ref" in p for p in found)
    assert any("answers.json" in p and "glr-4" in p for p in found)
