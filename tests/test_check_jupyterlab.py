"""``tests/browser/check_jupyterlab.py`` (``make browser-notebooks``) can fail, and blames the
notebook that has the problem: a notebook with a raw role and an undefined macro, then a clean one,
in one JupyterLab. Before each notebook was opened in a reset workspace, JupyterLab restored the
last one, and the clean notebook was reported with the other's two problems. Needs headless
Chromium (``make system-deps``); skipped without it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[1]
CHECK = ROOT / "tests" / "browser" / "check_jupyterlab.py"
sys.path.insert(0, str(ROOT / "tests" / "browser"))
from check_book import CHROMIUM  # noqa: E402  (the browser the check launches)


def _notebook(path: Path, markdown: str) -> None:
    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {
        "name": "python3",
        "display_name": "Python 3",
        "language": "python",
    }
    nb.cells = [nbformat.v4.new_markdown_cell(markdown), nbformat.v4.new_code_cell("1 + 1")]
    nbformat.write(nb, path)


@pytest.mark.slow
@pytest.mark.skipif(not Path(CHROMIUM).exists(), reason="no headless Chromium (make system-deps)")
def test_each_notebook_is_checked_alone(tmp_path):
    _notebook(tmp_path / "bad.ipynb", "# Bad\n\nSee {numref}`fig-x` and $\\T x$.\n")
    _notebook(tmp_path / "good.ipynb", "# Good\n\nMaths $x^2$.\n")
    workspaces = Path.home() / ".jupyter" / "lab" / "workspaces"  # JupyterLab's default
    before = sorted(workspaces.glob("*")) if workspaces.is_dir() else []
    done = subprocess.run(
        [sys.executable, str(CHECK), "--notebooks", str(tmp_path), "bad.ipynb", "good.ipynb"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 1, done.stdout + done.stderr
    rows = [line.split(" | ") for line in done.stdout.splitlines() if " | " in line]
    assert sorted((r[0], r[1]) for r in rows) == [("bad.ipynb", "macro"), ("bad.ipynb", "role")]
    assert "good.ipynb: 0 failures" in done.stderr
    # the workspaces stay in the test's temporary settings, not in the user's home
    assert (sorted(workspaces.glob("*")) if workspaces.is_dir() else []) == before
