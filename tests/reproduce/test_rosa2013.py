"""Smoke and consistency tests of the Rosa & Silvestre (2013) reproductions (reduced sizes)."""

from __future__ import annotations

import json

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

from fdi_lib.errors import ModelError
from fdi_lib.reproduce import get, reproduce
from fdi_lib.reproduce import rosa2013 as R
from fdi_lib.reproduce import rosa2013_studies as RS
from fdi_lib.reproduce import rosa2013_uav as RU
from fdi_lib.systems import eclipse_uav as uav


def test_fig1_two_projection_routes_agree():
    res = reproduce("rosa2013-fig1")
    assert res.headline["max_support_gap"] < 1e-9
    assert res.headline["area_fourier_motzkin"] == pytest.approx(
        res.headline["area_vertex"], rel=1e-9
    )
    get("rosa2013-fig1").plot(res)


def test_fig2_areas_against_sampling():
    """Areas of the hull and of the union of the two vertex sets, checked by seeded point sampling."""
    res = reproduce("rosa2013-fig2")
    h, d = res.headline, res.data
    P, Q = d["per_vertex"]
    V = np.vstack([P.vertices(), Q.vertices(), d["ours"].vertices()])
    lo, hi = V.min(axis=0), V.max(axis=0)
    pts = np.random.default_rng(0).uniform(lo, hi, size=(200_000, 2))
    box = float(np.prod(hi - lo))

    def inside(S):
        return np.all(pts @ S.M.T <= S.m, axis=1)

    union = np.mean(inside(P) | inside(Q)) * box
    assert h["union_area"] == pytest.approx(union, rel=0.02)
    assert h["hull_area"] == pytest.approx(np.mean(inside(d["hull"])) * box, rel=0.02)
    assert h["sound_hull_area"] == pytest.approx(np.mean(inside(d["ours"])) * box, rel=0.02)
    json.loads(res.to_json())
    get("rosa2013-fig2").plot(res)


def test_fig8_step_fault_detected_in_one_sample():
    res = reproduce("rosa2013-fig8", seed=1)
    assert res.headline["detection_time_ms"] == pytest.approx(10.0)
    get("rosa2013-fig8").plot(res)


def test_study_smoke_and_summary_keys():
    run = RU._one_uav_run("alpha", "hard", seed=2, duration=1.8)
    assert run["detection"] is not None and run["isolated"] == "alpha"
    runs = (
        run,
        {
            "fault": "none",
            "scenario": "step",
            "onset": 601,
            "detection": None,
            "isolation": None,
            "isolated": None,
        },
    )
    det = RU._summarise(runs, "detection")
    assert det["alpha"]["hard"] == pytest.approx((run["detection"] - run["onset"] + 1) * 10.0)
    assert det["elevator"]["step"] is None


def test_step_times_keys():
    out = R.step_times(1, seed=0, duration=0.2)
    assert out["empty_at"] is None and out["median_ms"] > 0 and out["max_facets"] <= 20


def test_the_timed_run_is_simulated_once_and_read_only():
    """step_times and exact_step_times time their updates on one shared healthy run (its
    simulation is not timed): the run of uav.simulate, its arrays read-only."""
    run = R._healthy_run(0, 0.2)
    assert R._healthy_run(0, 0.2) is run
    ref = uav.simulate("none", "step", rng=np.random.default_rng(0), duration=0.2)
    np.testing.assert_array_equal(run.y, ref.y)
    assert not any(a.flags.writeable for a in (run.t, run.x, run.y, run.u))


def test_exact_step_times_keys():
    """The exact rule's timing of rosa2013-timing (one update here: its sets grow tenfold per update)."""
    out = R.exact_step_times(1, 0, steps=1)
    assert set(out) == {"ms", "vertices", "empty_at"}
    assert (
        len(out["ms"]) == 1
        and out["ms"][0] > 0
        and out["vertices"][0] >= 5
        and out["empty_at"] is None
    )


def test_timing_reports_the_exact_rule_per_horizon(monkeypatch):
    """rosa2013-timing's headline: the template keys plus the exact rule's, per N, each documented.
    The step timers are shortened here (one exact update, 0.1 s of template updates)."""
    import re

    short, exact = R.step_times, R.exact_step_times
    monkeypatch.setattr(R, "step_times", lambda N, seed: short(N, seed, duration=0.1))
    monkeypatch.setattr(R, "exact_step_times", lambda N, seed: exact(N, seed, steps=1))
    h = R.timing(seed=0, trials=None, jobs=1).headline
    for key in (
        "step_ms",
        "step_ms_exact",
        "step_ms_exact_each",
        "vertices_exact",
        "exact_within_ts",
    ):
        assert set(h[key]) == {1, 2, 3}, key
    assert h["exact_steps"] == R.EXACT_TIMED_STEPS
    assert all(h["step_ms_exact"][N] == h["step_ms_exact_each"][N][0] for N in (1, 2, 3))
    documented = set(re.findall(r"^    (\w+(?:, \w+)*) :", R.timing.__doc__, flags=re.M))
    assert set(h) == {k for entry in documented for k in entry.split(", ")}


def test_explanation_scale_agrees_with_the_svo():
    """Two independent routes to (in)consistency: the LP (frozen parameters) and the SVO (all of them).

    Healthy data are explained within the bounds (s <= 1). When the nominal SVO becomes empty at
    sample k, no admissible explanation exists up to k, so the LP, which allows less, needs s > 1.
    """
    from fdi_lib.sets.svo import run_svo
    from fdi_lib.systems import eclipse_uav as uav

    h = uav.simulate("none", "step", rng=np.random.default_rng(2013), duration=1.0)
    assert 0.0 <= RS.explanation_scale(h) <= 1.0
    f = uav.simulate("elevator", "step", rng=np.random.default_rng(2013), duration=1.0)
    k = run_svo(uav.svo_models(f, "nominal"), f.u, f.y, R.UAV_X0).empty_at
    assert k is not None
    assert RS.explanation_scale(f, stop=k) > 1.0
    # a bias far outside the alpha bound cannot be explained by the disturbance bound
    y = f.y.copy()
    y[20:, 1] += np.deg2rad(10.0)
    biased = uav.UAVRun(f.t, f.x, y, f.u, "alpha", "step", 20)
    assert RS.explanation_scale(biased, stop=40) > 1.0


def test_explanation_scale_bad_inputs():
    from fdi_lib.errors import ModelError
    from fdi_lib.systems import eclipse_uav as uav

    run = uav.simulate("none", "step", rng=np.random.default_rng(0), duration=0.1)
    with pytest.raises(ModelError, match="scale: expected 'disturbance' or 'noise'"):
        RS.explanation_scale(run, scale="both")
    with pytest.raises(ModelError, match="start, stop: expected"):
        RS.explanation_scale(run, start=5, stop=5)
    with pytest.raises(ModelError, match="start, stop: expected"):
        RS.explanation_scale(run, stop=100)


def test_hidden_fault_study_effect_sizes():
    """Effect ratios recomputed from the two records; the healthy run raises no alarm."""
    from fdi_lib.systems import eclipse_uav as uav

    out = RS.hidden_fault_study(7, duration=1.2)
    h = uav.simulate("none", "step", rng=np.random.default_rng(7), duration=1.2)
    f = uav.simulate("dynamics", "step", rng=np.random.default_rng(7), duration=1.2)
    q = np.abs(f.y[:, 3] - h.y[:, 3]).max() / (uav.NOISE_BOUND[3] + uav.SVO_NOISE_MARGIN[3])
    assert out["effect"]["dynamics"]["q"] == pytest.approx(q, rel=1e-12)
    assert out["template"][1.0]["none"] is None  # no false alarm at the design bounds


def test_isolation_lags_on_synthetic_runs():
    runs = (
        {
            "fault": "alpha",
            "scenario": "soft",
            "detection": 80,
            "onset": 51,
            "empty_at": {"nominal": 80, "alpha": None, "elevator": 85, "dynamics": 80},
        },
        {
            "fault": "alpha",
            "scenario": "soft",
            "detection": None,
            "onset": 51,
            "empty_at": {"nominal": None},
        },
        {
            "fault": "elevator",
            "scenario": "soft",
            "detection": 90,
            "onset": 51,
            "empty_at": {"nominal": 90, "alpha": 91, "elevator": None, "dynamics": 99},
        },
    )
    lags = RS.isolation_lags(runs)
    assert lags == {
        "alpha": [None],
        "elevator": [pytest.approx(50.0)],
        "dynamics": [pytest.approx(0.0)],
    }


def test_total_speed_mu_fault_is_seen_at_once_and_the_deviation_one_is_not():
    """0.3 M_u u* Ts on the pitch rate is about 74 noise bounds: the nominal set must empty at the
    first sample after the onset (20 ms); on the speed deviation the same fault stays hidden."""
    total = RU.study_headline(RU.uav_study(2013, 1, duration=0.8, fault_mode="total"))
    dev = RU.study_headline(RU.uav_study(2013, 1, duration=0.8))
    assert total["detected_runs"]["dynamics"]["step"] == 1
    assert total["detection_time_ms"]["dynamics"]["step"] == pytest.approx(20.0)
    assert dev["detected_runs"]["dynamics"]["step"] == 0
    # the alpha faults and the healthy runs do not depend on where the other faults act
    assert total["detection_time_ms"]["alpha"] == dev["detection_time_ms"]["alpha"]
    assert total["false_alarms"] == dev["false_alarms"]


def test_alpha_slack_loosens_only_the_elevator_and_mu_observers():
    """The option adds its degrees to the alpha bound of SVOs #3 and #4 only; 0 is the design."""
    run = uav.simulate("none", "step", rng=np.random.default_rng(0), duration=0.1)
    for kind in ("nominal", "alpha", "elevator", "dynamics"):
        base = uav.svo_models(run, kind)
        assert np.array_equal(uav.svo_models(run, kind, alpha_slack_deg=0.0).noise, base.noise)
        loose = uav.svo_models(run, kind, alpha_slack_deg=4.0).noise
        np.testing.assert_allclose(
            loose - base.noise, [0.0, np.deg2rad(4.0), 0.0, 0.0], rtol=0, atol=1e-15
        )
    with pytest.raises(ModelError, match="alpha_slack_deg"):
        uav.svo_models(run, "elevator", alpha_slack_deg=-1.0)
    with pytest.raises(ModelError, match="alpha_slack_deg"):
        RU.fig12(seed=0, trials=1, jobs=1, alpha_slack_deg="4")
    with pytest.raises(ModelError, match="fault_mode"):
        RU.fig11(seed=0, trials=1, jobs=1, fault_mode="totl")


def test_a_looser_alpha_bound_delays_isolation_and_never_detection():
    """The nominal SVO is untouched, so detections are identical; a 3 deg alpha step that stays
    inside a 4 deg slack keeps the elevator and M_u hypotheses alive, so it is not isolated, where
    the design bound isolates it at the first faulty sample."""
    base = RU.study_headline(RU.uav_study(5, 1, duration=1.0))
    loose = RU.study_headline(RU.uav_study(5, 1, duration=1.0, alpha_slack_deg=4.0))
    assert loose["detection_time_ms"] == base["detection_time_ms"]
    assert loose["false_alarms"] == base["false_alarms"]
    assert base["correctly_isolated_runs"]["alpha"]["step"] == 1
    assert loose["correctly_isolated_runs"]["alpha"]["step"] == 0


def test_uav_study_streams_are_independent_across_seeds():
    """Seeds 0 and 1 share no realisation (spawned streams, not seed + i)."""
    a = np.random.SeedSequence(0).spawn(3)
    b = np.random.SeedSequence(1).spawn(3)
    draws_a = {float(np.random.default_rng(s).uniform()) for s in a}
    draws_b = {float(np.random.default_rng(s).uniform()) for s in b}
    assert not draws_a & draws_b
    run = RU._one_uav_run("none", "step", a[1], 0.3)
    assert run["detection"] is None and run["empty_at"] == {"nominal": None}
