"""The runnable examples in the core modules' docstrings are correct."""

import doctest
import importlib

import pytest

CORE = ["fdi_lib.models", "fdi_lib.filters", "fdi_lib.signatures", "fdi_lib.glr", "fdi_lib.isolation",
        "fdi_lib.simulate", "fdi_lib.montecarlo", "fdi_lib.calibration", "fdi_lib.kitanidis", "fdi_lib.rls",
        "fdi_lib.nonparametric", "fdi_lib.sparse", "fdi_lib.validation"]


@pytest.mark.parametrize("name", CORE)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0, f"{name} has no runnable example (the test would pass vacuously)"
    assert result.failed == 0, f"{result.failed} doctest(s) failed in {name}"
