"""Shared test helpers."""

from __future__ import annotations

import pytest
from hypothesis import settings

# Property tests draw their examples deterministically: CI runs are reproducible.
settings.register_profile("fdi", derandomize=True, deadline=None)
settings.load_profile("fdi")

from fdi_lib.systems.random_ltv import random_ltv_model

make_random_ltv = random_ltv_model


@pytest.fixture
def random_ltv():
    return random_ltv_model


@pytest.fixture(autouse=True)
def _close_figures():
    """Close the figures a test opened (pyplot keeps them alive otherwise)."""
    yield
    import matplotlib.pyplot as plt

    plt.close("all")
