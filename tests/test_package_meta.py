"""The package's citation and licence metadata agree with pyproject.toml (issue 34)."""

import re
import tomllib
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]


def _project() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]


def test_citation_version_and_licence_match_pyproject():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0"
    assert cff["version"] == _project()["version"]
    assert cff["license"] == _project()["license"]


def test_citation_cites_the_four_papers():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    titles = [ref["title"] for ref in cff["references"]]
    for words in (
        "additive faults in linear time-varying",
        "sparseness assumption",
        "parametric and non-parametric",
        "set-valued observers",
    ):
        assert any(words in t for t in titles), words


def test_licence_file_is_the_declared_licence():
    assert _project()["license"] == "BSD-3-Clause"
    assert (ROOT / "LICENSE").read_text().startswith("BSD 3-Clause License")


def test_changelog_has_the_current_version():
    versions = re.findall(r"^## \[([^\]]+)\]", (ROOT / "CHANGELOG.md").read_text(), re.M)
    assert versions[0] == "Unreleased"
    assert _project()["version"] in versions
