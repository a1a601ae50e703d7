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


def test_explanation_scale_healthy_and_faulty():
    """Healthy data are explained within the bounds (s <= 1); the elevator step fault too (the
    book's finding: no SVO on these bounds can detect it), but it needs more disturbance."""
    from fdi_lib.systems import eclipse_uav as uav

    h = uav.simulate("none", "step", rng=np.random.default_rng(2013), duration=1.5)
    f = uav.simulate("elevator", "step", rng=np.random.default_rng(2013), duration=1.5)
    sh, sf = R.explanation_scale(h), R.explanation_scale(f)
    assert 0.0 <= sh <= 1.0 and sh < sf <= 1.0
    # the first faulty sample (20 ms after onset) is explained exactly as the healthy one
    k = f.onset_step + 1
    assert R.explanation_scale(f, stop=k) == pytest.approx(R.explanation_scale(h, stop=k), abs=1e-9)
    # the noise is explained at the same scale (the realised noise), whatever the fault
    assert R.explanation_scale(f, scale="noise") == pytest.approx(R.explanation_scale(h, scale="noise"), abs=1e-3)
    # a bias far outside the alpha bound cannot be explained by the disturbance bound
    y = f.y.copy()
    y[20:, 1] += np.deg2rad(10.0)
    biased = uav.UAVRun(f.t, f.x, y, f.u, "alpha", "step", 20)
    assert R.explanation_scale(biased, stop=40) > 1.0


def test_explanation_scale_bad_inputs():
    from fdi_lib.errors import ModelError
    from fdi_lib.systems import eclipse_uav as uav

    run = uav.simulate("none", "step", rng=np.random.default_rng(0), duration=0.1)
    with pytest.raises(ModelError, match="scale: expected 'disturbance' or 'noise'"):
        R.explanation_scale(run, scale="both")
    with pytest.raises(ModelError, match="start, stop: expected"):
        R.explanation_scale(run, start=5, stop=5)
    with pytest.raises(ModelError, match="start, stop: expected"):
        R.explanation_scale(run, stop=100)


def test_hidden_fault_study_is_consistent():
    out = R.hidden_fault_study(7, duration=1.2)
    for f in ("elevator", "dynamics"):
        assert out["effect"][f]["q"] > 1.0 > out["effect"][f]["alpha"]
        times = sorted(out["explanation"][f])
        vals = [out["explanation"][f][t] for t in times]
        assert all(b >= a - 1e-9 for a, b in zip(vals, vals[1:]))        # longer window, larger scale
        assert out["width"][f]["w"] > out["width_needed"][f] > 0
    assert out["template"][1.0]["none"] is None                            # no false alarm at the design bounds
