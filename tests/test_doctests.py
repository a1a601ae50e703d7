"""The runnable examples in the core modules' docstrings are correct."""

import doctest
import importlib

import pytest

CORE = [
    "fdi_lib.models",
    "fdi_lib.filters",
    "fdi_lib.signatures",
    "fdi_lib.glr",
    "fdi_lib.isolation",
    "fdi_lib.simulate",
    "fdi_lib.montecarlo",
    "fdi_lib.calibration",
    "fdi_lib.kitanidis",
    "fdi_lib.rls",
    "fdi_lib.nonparametric",
    "fdi_lib.sparse",
    "fdi_lib.validation",
    "fdi_lib.windturbine",
]


@pytest.mark.parametrize("name", CORE)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0, f"{name} has no runnable example (the test would pass vacuously)"
    assert result.failed == 0, f"{result.failed} doctest(s) failed in {name}"


#: Modules whose every exported function has a runnable example and names the chapter that
#: explains it (issue 34).
EXAMPLED = [
    "fdi_lib.models",
    "fdi_lib.filters",
    "fdi_lib.signatures",
    "fdi_lib.glr",
    "fdi_lib.isolation",
    "fdi_lib.simulate",
    "fdi_lib.montecarlo",
    "fdi_lib.calibration",
    "fdi_lib.kitanidis",
    "fdi_lib.rls",
    "fdi_lib.nonparametric",
    "fdi_lib.sparse",
    "fdi_lib.validation",
]


@pytest.mark.parametrize("name", EXAMPLED)
def test_every_exported_function_has_an_example_and_a_chapter(name):
    import inspect
    import re

    module = importlib.import_module(name)
    missing = []
    for attr in module.__all__:
        obj = getattr(module, attr)
        if inspect.isfunction(obj):
            doc = obj.__doc__ or ""
            if ">>>" not in doc or not re.search(r":doc:`/book/[\w/-]+`", doc):
                missing.append(attr)
    assert not missing, f"{name}: no example or no chapter link in {missing}"
