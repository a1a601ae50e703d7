"""``tools/execute_book.py`` (``make book``'s parallel execution of the chapters): on a small book
of three notebooks, the glued values are those of a serial execution, each chapter's Monte Carlo
ran on its share of the cores, the claims ledger ran after the chapters whose results it reads,
the jupyter-cache gives every chapter's outputs back to myst-nb, another edition reuses the
chapters whose code is unchanged (``--reuse``), and a cell error fails the run."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import nbformat
import pytest

from source_module import load as _load

ROOT = Path(__file__).resolve().parents[1]
TOOL = _load("fdi_execute_book", ROOT / "tools" / "execute_book.py")

HEADER = textwrap.dedent("""\
    ---
    jupytext:
      text_representation:
        extension: .md
        format_name: myst
    kernelspec:
      display_name: Python 3
      language: python
      name: python3
    ---

    # {title}

    """)

#: A chapter: a Monte Carlo asked for 2 jobs; glues its result, the processes it may use and
#: leaves a mark in the results folder that the ledger counts.
CHAPTER = """```{{code-cell}} ipython3
import functools, os
from pathlib import Path

import numpy as np
from myst_nb import glue

from fdi_lib.montecarlo import effective_jobs, run_monte_carlo


def chunk(seeds):
    return {{"x": np.array([np.random.default_rng(s).standard_normal() for s in seeds])}}


out = run_monte_carlo(chunk, 64, seed={seed}, jobs=2, chunk_size=8)
glue("{name}_sum", float(out["x"].sum()), display=False)
glue("{name}_jobs", effective_jobs(2), display=False)
Path(os.environ["FDI_TEST_RESULTS"], "{name}").write_text("done")
```
"""

LEDGER = """```{code-cell} ipython3
import os
from myst_nb import glue

glue("ledger_seen", sorted(os.listdir(os.environ["FDI_TEST_RESULTS"])), display=False)
```
"""


def _book(root: Path, *, failing: bool = False) -> Path:
    (root / "book").mkdir(parents=True)
    (root / "_config.yml").write_text(
        "execute:\n  execute_notebooks: force\n  timeout: 120\n"
        "  allow_errors: false\n  run_in_temp: false\n"
    )
    (root / "_toc.yml").write_text(
        "format: jb-book\nroot: book/intro\nchapters:\n"
        "  - file: book/a\n  - file: book/zz-ledger\n  - file: book/b\n"
    )
    (root / "book" / "intro.md").write_text("# A book\n\nNo code here.\n")
    for name, seed in (("a", 1), ("b", 2)):
        body = CHAPTER.format(name=name, seed=seed)
        if failing and name == "b":
            body += "```{code-cell} ipython3\nraise ValueError('a broken cell')\n```\n"
        (root / "book" / f"{name}.md").write_text(HEADER.format(title=name) + body)
    (root / "book" / "zz-ledger.md").write_text(HEADER.format(title="Ledger") + LEDGER)
    return root


def _run(
    root: Path, cache: Path, jobs: int, results: Path, *extra: str
) -> subprocess.CompletedProcess:
    results.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "FDI_TEST_RESULTS": str(results)}
    env.pop("FDI_CORES", None)
    cmd = [
        sys.executable,
        str(ROOT / "tools" / "execute_book.py"),
        "--root",
        str(root),
        "--cache",
        str(cache),
        "--jobs",
        str(jobs),
        "--report",
        str(root / "none.json"),
        "--config-out",
        str(root / "_build" / "_config_book.yml"),
        *extra,
    ]
    return subprocess.run(cmd, env=env, capture_output=True, text=True)


def _glued(cache: Path, source: Path) -> dict:
    """The glued values of ``source`` as myst-nb takes them from the jupyter-cache."""
    from jupyter_cache import get_cache
    from myst_nb.ext.glue import extract_glue_data

    _, nb = get_cache(str(cache)).merge_match_into_notebook(TOOL.read_notebook(source))
    data = extract_glue_data(nb, [0] * len(nb.cells), None)
    return {k: v["data"]["text/plain"] for k, v in data.items()}


@pytest.mark.slow
def test_parallel_execution_glues_what_a_serial_one_does(tmp_path, monkeypatch):
    import joblib

    if joblib.cpu_count() < 2:
        pytest.skip("one core: no chapters side by side")
    book = _book(tmp_path / "src")
    glued = {}
    for jobs in (1, 2):
        cache = tmp_path / f"cache-{jobs}"
        done = _run(book, cache, jobs, tmp_path / f"results-{jobs}")
        assert done.returncode == 0, done.stderr
        assert "book/a.md: Executed notebook in" in done.stdout
        assert "book/zz-ledger.md: Executed notebook in" in done.stdout
        glued[jobs] = {
            doc: _glued(cache, book / "book" / f"{doc}.md") for doc in ("a", "b", "zz-ledger")
        }
    serial, parallel = glued[1], glued[2]
    cores = min(2, joblib.cpu_count())
    for doc in ("a", "b"):
        assert serial[doc][f"{doc}_sum"] == parallel[doc][f"{doc}_sum"]  # the same repr
        assert serial[doc][f"{doc}_jobs"] == str(cores)  # alone: every core
        assert parallel[doc][f"{doc}_jobs"] == "1"  # beside another chapter: its share
    # the ledger ran after both chapters in both runs (it is listed between them in the TOC)
    assert serial["zz-ledger"] == parallel["zz-ledger"] == {"ledger_seen": "['a', 'b']"}
    # the build's configuration reads that cache
    config = (book / "_build" / "_config_book.yml").read_text()
    assert "execute_notebooks: cache" in config and str((tmp_path / "cache-2").resolve()) in config
    # another edition whose chapter b changed (the student edition): a and the ledger are reused
    b = book / "book" / "b.md"
    b.write_text(b.read_text().replace("seed=2", "seed=3"))
    done = _run(
        book, tmp_path / "cache-3", 2, tmp_path / "results-3", "--reuse", str(tmp_path / "cache-2")
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    executed = [line.split(":")[0] for line in lines if "Executed notebook in" in line]
    reused = [line.split(":")[0] for line in lines if "outputs reused" in line]
    assert executed == ["book/b.md"] and sorted(reused) == ["book/a.md", "book/zz-ledger.md"]
    assert _glued(tmp_path / "cache-3", book / "book" / "a.md") == parallel["a"]
    assert _glued(tmp_path / "cache-3", book / "book" / "b.md")["b_sum"] != parallel["b"]["b_sum"]


@pytest.mark.slow
def test_a_cell_error_fails_the_run_with_its_traceback(tmp_path):
    book = _book(tmp_path / "src", failing=True)
    done = _run(book, tmp_path / "cache", 2, tmp_path / "results")
    assert done.returncode == 1
    assert "a broken cell" in done.stderr and "Execution failed: book/b.md" in done.stderr
    assert not (book / "_build" / "_config_book.yml").exists()  # no build configuration: no build


def test_chapters_are_the_toc_notebooks_with_code_longest_first(tmp_path):
    book = _book(tmp_path / "src")
    assert TOOL.toc_documents(book / "_toc.yml") == [
        "book/intro",
        "book/a",
        "book/zz-ledger",
        "book/b",
    ]
    found = TOOL.chapters(book, book / "_toc.yml", {"book/b.md": 9.0, "book/a.md": 1.0})
    assert [c.doc for c in found] == ["book/a", "book/zz-ledger", "book/b"]  # intro has no code
    assert {c.doc: c.weight for c in found}["book/b"] == 9.0
    nb = found[0].notebook
    assert isinstance(nb, nbformat.NotebookNode) and nb.metadata.kernelspec.name == "python3"
    assert json.dumps(TOOL.AFTER_ALL) == '["book/zz-ledger"]'
