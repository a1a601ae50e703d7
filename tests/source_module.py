"""Import a file of the repository that is not in a package (the book's Sphinx extension
``_ext/fdi_book.py``, the scripts in ``tools/``) under a name of the test's choosing."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType


def load(name: str, path: Path) -> ModuleType:
    """The module at ``path``, executed as ``name``."""
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
