"""The runnable examples in the core modules' docstrings are correct."""

import doctest
import importlib

import pytest

CORE = ["fdi_lib.models", "fdi_lib.filters", "fdi_lib.signatures", "fdi_lib.glr", "fdi_lib.isolation",
        "fdi_lib.simulate", "fdi_lib.montecarlo", "fdi_lib.calibration"]


@pytest.mark.parametrize("name", CORE)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.failed == 0, f"{result.failed} doctest(s) failed in {name}"
