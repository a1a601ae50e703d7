"""The book's API reference (book/api/) documents every public module of the library."""

import pkgutil
import re
from pathlib import Path

import fdi_lib

ROOT = Path(__file__).resolve().parents[1]
#: Not part of the reference: the student-facing exercise package (its answers are not shipped,
#: its pages are the chapters' exercises) and ``python -m fdi_lib``'s entry module.
EXCLUDED = re.compile(r"fdi_lib\.(exercises(\..*)?|__main__)$")


def _documented() -> list[str]:
    text = "\n".join(p.read_text() for p in sorted((ROOT / "book" / "api").glob("*.md")))
    return re.findall(r"^\.\. automodule:: (\S+)$", text, re.M)


def _public_modules() -> set[str]:
    names = {"fdi_lib"}
    for info in pkgutil.walk_packages(fdi_lib.__path__, "fdi_lib."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.add(info.name)
    return {n for n in names if not EXCLUDED.match(n)}


def test_every_public_module_has_a_reference_section():
    missing = _public_modules() - set(_documented())
    assert not missing, f"modules without an automodule in book/api/: {sorted(missing)}"


def test_no_module_is_documented_twice_or_unknown():
    documented = _documented()
    assert len(documented) == len(set(documented)), "a module is documented on two pages"
    unknown = set(documented) - _public_modules()
    assert not unknown, f"book/api/ documents modules that do not exist: {sorted(unknown)}"


def test_reference_pages_are_in_the_table_of_contents():
    toc = (ROOT / "_toc.yml").read_text()
    for page in sorted((ROOT / "book" / "api").glob("*.md")):
        assert f"book/api/{page.stem}" in toc, page.name
