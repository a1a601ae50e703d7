"""Smoke and consistency tests of the Rosa & Silvestre (2013) reproductions (reduced sizes)."""

from __future__ import annotations

import json

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

from fdi_lib.reproduce import get, reproduce
from fdi_lib.reproduce import rosa2013 as R


def test_fig1_two_projection_routes_agree():
    res = reproduce("rosa2013-fig1")
    assert res.headline["max_support_gap"] < 1e-9
    assert res.headline["area_fourier_motzkin"] == pytest.approx(res.headline["area_vertex"], rel=1e-9)
    get("rosa2013-fig1").plot(res)


def test_fig2_hull_contains_union_and_our_set_contains_hull():
    res = reproduce("rosa2013-fig2")
    h = res.headline
    assert h["hull_area"] >= h["union_area"] - 1e-12
    assert h["sound_hull_area"] >= h["hull_area"] - 1e-12
    assert set(h) >= {"hull_area", "union_area", "vertices"}
    json.loads(res.to_json())
    get("rosa2013-fig2").plot(res)


def test_fig8_step_fault_detected_in_one_sample():
    res = reproduce("rosa2013-fig8", seed=1)
    assert res.headline["detection_time_ms"] == pytest.approx(10.0)
    get("rosa2013-fig8").plot(res)


def test_study_smoke_and_summary_keys():
    run = R._one_uav_run("alpha", "hard", seed=2, duration=1.8)
    assert run["detection"] is not None and run["isolated"] == "alpha"
    runs = (run, {"fault": "none", "scenario": "step", "onset": 601, "detection": None, "isolation": None,
                  "isolated": None})
    det = R._summarise(runs, "detection")
    assert det["alpha"]["hard"] == pytest.approx((run["detection"] - run["onset"] + 1) * 10.0)
    assert det["elevator"]["step"] is None


def test_step_times_keys():
    out = R.step_times(1, seed=0, duration=0.2)
    assert out["empty_at"] is None and out["median_ms"] > 0 and out["max_facets"] <= 20
