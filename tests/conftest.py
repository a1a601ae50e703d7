"""Shared test helpers."""

from __future__ import annotations

import pytest

from fdi_lib.systems.random_ltv import random_ltv_model

make_random_ltv = random_ltv_model


@pytest.fixture
def random_ltv():
    return random_ltv_model
