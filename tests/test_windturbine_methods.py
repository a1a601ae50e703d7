"""The four methods on the wind-turbine benchmark (fdi_lib.windturbine) and the scoreboard's contract."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("numba")

from fdi_lib import windturbine as W  # noqa: E402
from fdi_lib.errors import ModelError  # noqa: E402
from fdi_lib.systems import wind_turbine as wt  # noqa: E402

FAULTS = {f.id: f for f in wt.FAULTS}
SETTINGS = W.Settings(pre_s=5.0, post_s=3.0, warmup_s=2.0, window=30)


@pytest.fixture(scope="module")
def design():
    c = W.plant_constants()
    seeds = np.random.SeedSequence([11, 1]).spawn(2)
    recs = [W.fault_records(FAULTS[i], seeds, settings=SETTINGS, faulty=False) for i in (1, 5, 8)]
    rec = W.Records(
        recs[0].t,
        *(np.concatenate([getattr(r, k) for r in recs]) for k in ("y", "u", "x", "tau_a", "v")),
    )
    return W.design(c, W.calibrate(c, rec), rec.x.reshape(-1, 10).mean(axis=0), SETTINGS)


def _run(design, fault_ids, seed, faulty=True, n=3):
    seeds = np.random.SeedSequence(seed).spawn(n)
    recs = [W.fault_records(FAULTS[i], seeds, settings=SETTINGS, faulty=faulty) for i in fault_ids]
    y = np.concatenate([r.y for r in recs])
    u = np.concatenate([r.u for r in recs])
    return W.run_methods(design, y, u)


def _one_step_error(faulty: bool) -> dict[str, float]:
    c = W.plant_constants()
    rec = W.fault_records(
        FAULTS[1], np.random.SeedSequence(3).spawn(1), settings=SETTINGS, faulty=faulty
    )
    out = {}
    for s in W.subsystems(c):
        x = rec.x[..., list(s.states)]
        pred = x[:, :-1] @ s.F.T + rec.u[:, :-1, list(s.inputs)] @ s.G.T
        if s.E is not None:
            pred = pred + rec.tau_a[:, :-1, None] * s.E[:, 0]
        out[s.name] = float(np.abs(x[:, 1:] - pred).max() / (np.abs(x).max() + 1.0))
    return out


def test_window_correlations_are_the_bits_of_the_einsum():
    """The Lasso test's compiled window sums (W._window_correlations) against the einsum on the
    sliding windows that they replace, bit for bit (sizes of the blades and the drive train)."""
    rng = np.random.default_rng(4)
    for B, N, p, w, m in ((3, 120, 2, 30, 3), (2, 90, 5, 50, 7), (1, 40, 1, 40, 2)):
        r = rng.standard_normal((B, N, p))
        kern = rng.standard_normal((w, p, m))
        ref = np.einsum(
            "bkpw,wpm->bkm", np.lib.stride_tricks.sliding_window_view(r, w, axis=1), kern
        )
        out = W._window_correlations(np.ascontiguousarray(np.swapaxes(r, 1, 2)), kern)
        assert np.ascontiguousarray(np.swapaxes(out, 1, 2)).tobytes() == ref.tobytes()


def test_subsystem_models_reproduce_the_simulator():
    """Independent check against the simulator's true states: with healthy sensors every
    subsystem's one-step prediction is exact to rounding; a stuck pitch sensor (the servo's loop
    closes on the measured pitch, whose gain changes) leaves a small discretisation error on its
    blade only (relative to the largest state: 2.8e-3 measured, bound 1e-2), the other subsystems
    stay exact."""
    healthy = _one_step_error(faulty=False)
    assert max(healthy.values()) < 1e-9, healthy
    faulty = _one_step_error(faulty=True)
    assert 1e-9 < faulty["blade1"] < 1e-2, faulty
    assert max(v for k, v in faulty.items() if k != "blade1") < 1e-9, faulty


def test_records_of_a_window_equal_the_window_of_the_records():
    """records(run, i0, i1) converts only the window's samples: the same arrays, bit for bit, as
    the whole run's records cut afterwards."""
    run = wt.simulate(seed=np.random.SeedSequence(4).spawn(2), faults=(), duration_s=3.0)
    whole = W.records(run)
    for i0, i1 in ((0, None), (50, 120), (100, 300)):
        got, ref = W.records(run, i0, i1), whole.window(i0, i1)
        for key in ("t", "y", "u", "x", "tau_a", "v", "region"):
            np.testing.assert_array_equal(getattr(got, key), getattr(ref, key), err_msg=key)
    assert W.records(run, 100, 300).y.shape[1] == 200


def test_zhang2021_reuses_the_blades_kalman_run_bit_for_bit(design):
    """Without an unknown input the residual filter is the Kalman filter (one model, one set of
    gains in the design): run_methods' shared Kalman runs give Zhang 2021 the blades' updated
    residuals, the same bits as its own runs."""
    for sd in design.subs.values():
        assert (sd.kit is sd.kf and sd.kit_gains is sd.kf_gains) == (sd.sub.E is None)
    seeds = np.random.SeedSequence(22).spawn(2)
    recs = [W.fault_records(FAULTS[i], seeds, settings=SETTINGS) for i in (1, 8)]
    y = np.concatenate([r.y for r in recs])
    u = np.concatenate([r.u for r in recs])
    kalman = W._kalman_runs(design, y, u)
    shared, alone = W._residuals(design, y, u, kalman), W._residuals(design, y, u)
    for name in design.subs:
        for a, b in zip(shared[name], alone[name]):
            np.testing.assert_array_equal(a, b)
    got, ref = W.run_zhang2021(design, y, u, kalman), W.run_zhang2021(design, y, u)
    for key in ("false_alarm", "detect", "isolated", "isolate_step", "peak"):
        np.testing.assert_array_equal(getattr(got, key), getattr(ref, key))


def test_bz_and_zhang2021_share_the_kitanidis_run_bit_for_bit(design):
    """The drive train's Kitanidis filter, run once per batch (MethodInputs.kitanidis): its residuals
    are Zhang 2021's, its innovations those Basseville & Zhang project, the same bits as each
    method's own run (the Kalman predictor with the Kitanidis gains for BZ)."""
    kpred, _ = design.subs["drive_train"].bz_red
    assert kpred.K is design.subs["drive_train"].kit_gains.K
    seeds = np.random.SeedSequence(23).spawn(2)
    recs = [W.fault_records(FAULTS[i], seeds, settings=SETTINGS) for i in (5, 8)]
    y = np.concatenate([r.y for r in recs])
    u = np.concatenate([r.u for r in recs])
    inputs = W.MethodInputs(design, y, u)
    assert list(inputs.kitanidis) == ["drive_train"]
    shared = W._bz_stats(design, y, u, inputs.innovations, inputs.kitanidis)
    alone = W._bz_stats(design, y, u, inputs.innovations)
    for a, b in zip(shared, alone):
        for x, z in zip(a, b):
            assert np.asarray(x).tobytes() == np.asarray(z).tobytes()
    shared = W._residuals(design, y, u, inputs.kalman, inputs.kitanidis)
    alone = W._residuals(design, y, u)
    for name in design.subs:
        for a, b in zip(shared[name], alone[name]):
            assert a.tobytes() == b.tobytes()


def test_innovations_are_white_with_unit_variance_on_fault_free_data(design):
    """The Kalman filters match the plant: whitened innovations have unit variance (within 10 %)
    and no lag-1 correlation beyond 0.1 after the warm-up."""
    seeds = np.random.SeedSequence(21).spawn(3)
    recs = [W.fault_records(FAULTS[i], seeds, settings=SETTINGS, faulty=False) for i in (2, 6)]
    y = np.concatenate([r.y for r in recs])
    u = np.concatenate([r.u for r in recs])
    eps = W._innovations(design, y, u)
    for name, e in eps.items():
        z = design.subs[name].kf_gains.whiten(e)[:, design.warmup :]
        std = z.std(axis=(0, 1))
        assert np.all(np.abs(std - 1) < 0.1), (name, std)
        r1 = np.mean(z[:, 1:] * z[:, :-1], axis=(0, 1)) / z.var(axis=(0, 1))
        assert np.all(np.abs(r1) < 0.1), (name, r1)


def test_no_method_alarms_on_fault_free_data(design):
    """Fixed seeds, the fault-free twins of three segments: the stated budget (1 false alarm per
    hour and subsystem, nominal) makes an alarm in these few minutes unlikely; none is raised."""
    out = _run(design, (1, 5, 8), seed=31, faulty=False)
    for name, o in out.items():
        assert not o.false_alarm.any(), name
        assert (o.detect < 0).all(), name  # nor after the (absent) onset


@pytest.mark.parametrize(
    "fault_id, methods",
    [
        (1, ("zb2014", "zhang2021", "bz", "rosa2013")),  # pitch sensor stuck at 5 deg
        (
            8,
            ("zb2014", "zhang2021", "bz", "rosa2013"),
        ),  # converter offset, seen by the torque sensor
    ],
)
def test_methods_detect_the_faults_they_should(design, fault_id, methods):
    out = _run(design, (fault_id,), seed=41 + fault_id)
    for name in methods:
        o = out[name]
        assert (o.detect >= design.onset).all(), (name, o.detect - design.onset)
        assert not o.false_alarm.any(), name


def test_svo_isolates_the_stuck_pitch_sensor(design):
    """Architecture I names one hypothesis or none (not yet isolated in the 3 s): the stuck sensor."""
    out = _run(design, (1,), seed=42)["rosa2013"]
    named = out.isolated.any(axis=1)
    assert named.sum() >= 2
    assert (out.isolated[named, W.CANDIDATES.index("beta1_m1")]).all()
    assert out.isolated.sum(axis=1).max() == 1


def test_expected_candidates_cover_every_fault():
    assert W.expected_candidates(FAULTS[5]) == ("omega_r_m2", "omega_g_m2")
    assert W.expected_candidates(FAULTS[6]) == ("actuator2",)
    for f in wt.FAULTS:
        assert set(W.expected_candidates(f)) <= set(W.CANDIDATES)


def test_min_detectable_drive_train_torque_is_far_above_the_converter(design):
    """The measured reason of the drive-train miss: a generator-side torque alone (not seen by the
    torque sensor) is confounded with the aerodynamic torque, the converter offset is not."""
    md = W.min_detectable(design)
    for m in ("zb2014", "zhang2021"):
        assert md[m]["drive_train"] > 100 * md[m]["converter"], m


def test_scoreboard_json_has_every_fault_and_method():
    from fdi_lib.reproduce import reproduce

    r = reproduce("windturbine-scoreboard", trials=2)
    doc = json.loads(r.to_json())
    h = doc["headline"]
    assert set(h["faults"]) == {f"F{f.id}" for f in wt.FAULTS}
    for fid, e in h["faults"].items():
        assert set(e["methods"]) == set(W.METHODS)
        for name, v in e["methods"].items():
            if v["detected"]:
                assert v["detection_time_mean_s"] > 0, (fid, name)
            if v["detected"] < 2:
                reason = v["reason"]
                assert reason is not None and reason["effect_sigma_max"] >= 0, (fid, name)
                assert name == "rosa2013" or reason["peak_over_threshold"] is not None, (fid, name)
    assert set(h["false_alarms"]) == set(W.METHODS)
    for fid, e in h[
        "faults"
    ].items():  # up to the deadline the effect is at most the whole record's
        if e["required_detection_s"] is None:
            assert e["effect_sigma_at_requirement_median"] is None, fid
        else:
            assert 0 <= e["effect_sigma_at_requirement_median"] <= e["effect_sigma_median"], fid
    assert doc["paper"]["required_detection_s"]["F1"] == "<= 0.1"
    # the fastest method: among those detecting in every realisation, the smallest mean (brute force)
    for fid, e in h["faults"].items():
        full = {
            m: v["detection_time_mean_s"] for m, v in e["methods"].items() if v["detected"] == 2
        }
        fast = h["fastest_method"][fid]
        if not full:
            assert fast is None, fid
        else:
            assert fast["detection_time_mean_s"] == min(full.values()), fid
            assert full[fast["method"]] == fast["detection_time_mean_s"], fid
    # the published delays of another method: in the paper block, and in the ledger beside ours
    from fdi_lib.reproduce.ledger_claims import NOT_REPRODUCIBLE
    from fdi_lib.reproduce.ledger import build_ledger
    from fdi_lib.reproduce.windturbine import PUBLISHED_DELAYS

    pub = doc["paper"]["published_detection_s"]
    assert pub == PUBLISHED_DELAYS and pub["cohal_mirea_2017"]["certain"]["F1"] == 3.21
    rows = [
        row
        for row in build_ledger({r.id: r}, strict=True).rows
        if row.path[0] == "published_detection_s"
    ]
    assert len(rows) == sum(len(v) for v in PUBLISHED_DELAYS["cohal_mirea_2017"].values())
    for row in rows:
        assert (
            row.status == NOT_REPRODUCIBLE
            and row.paper == pub["cohal_mirea_2017"][row.path[2]][row.path[3]]
        )
        fast = h["fastest_method"][row.path[3]]
        assert row.ours == (
            "no method detects it in every realisation"
            if fast is None
            else fast["detection_time_mean_s"]
        )
        assert f"fault {row.path[3]}" in row.label and "{" not in row.label


def test_separability_is_the_sine_of_the_principal_angle(design):
    """Against scipy's principal angles between a candidate's whitened signature and the span of
    the others'; the converter's signature is the drive-train torque's plus the torque sensor's in
    the model itself, so the three have separability 0."""
    import scipy.linalg

    from fdi_lib.signatures import fault_signature

    sep = W.separability(design)
    assert set(sep) == set(W.CANDIDATES)
    d = design
    n = min(d.settings.window + d.settings.isolation_extra, d.N - d.onset)
    for sd in d.subs.values():
        sig = fault_signature(sd.kf, sd.kf_gains, sd.family.profile(d.onset)).on_innovation
        Sw = np.linalg.solve(
            sd.kf_gains.Sigma_chol[d.onset : d.onset + n], sig[d.onset : d.onset + n]
        )
        X = Sw.reshape(-1, Sw.shape[-1])
        for i, j in enumerate(sd.sub.candidates):
            angle = scipy.linalg.subspace_angles(X[:, [i]], np.delete(X, i, axis=1))[0]
            assert sep[W.CANDIDATES[j]] == pytest.approx(np.sin(angle), abs=1e-6), W.CANDIDATES[j]
    s = W.subsystems(W.plant_constants())[3]
    assert np.array_equal(s.Psi[:, 5], s.Psi[:, 6]) and s.Phi[4, 5] == 1.0
    for c in ("converter", "drive_train", "tau_g_m"):
        assert sep[c] == 0.0, c
    assert 0.1 < sep["omega_g_m2"] < sep["omega_r_m2"] <= 1.0


def test_every_set_a_method_names_is_in_its_vocabulary(design):
    """``Method.nameable`` describes what each method's isolation can output: every set named on
    faulty records is in it, and the sets the chapter explains by it are not."""
    res = _run(design, (1, 5, 8), seed=5)
    for name, o in res.items():
        for row in o.isolated:
            named = frozenset(W.CANDIDATES[j] for j in np.flatnonzero(row))
            if named:
                assert W.METHODS[name].nameable(named), (name, sorted(named))
    f5 = frozenset(W.expected_candidates(FAULTS[5]))
    f8 = frozenset(W.expected_candidates(FAULTS[8]))
    assert [m for m in W.METHODS if not W.METHODS[m].nameable(f5)] == ["bz", "rosa2013"]
    assert [m for m in W.METHODS if not W.METHODS[m].nameable(f8)] == ["bz"]


def test_fault_record_pair_is_two_fault_records_bit_for_bit():
    """The scoreboard's record and fault-free twin from one wind draw (and the simulator's cached
    initial equilibria) are the records of two separate calls, to the last bit; the fault shows."""
    seeds = np.random.SeedSequence(21).spawn(2)
    rec, twin = W.fault_record_pair(FAULTS[9], seeds, settings=SETTINGS)
    for got, faulty in ((rec, True), (twin, False)):
        ref = W.fault_records(FAULTS[9], seeds, settings=SETTINGS, faulty=faulty)
        for key in ("t", "y", "u", "x", "tau_a", "v", "region"):
            assert np.array_equal(getattr(got, key), getattr(ref, key)), key
    assert not np.array_equal(rec.y, twin.y)


def test_servo_gains_are_the_l1_norms_of_the_servo_impulse_response():
    """The pitch and rate gains of the envelope (SciPy's impulse response) against the state
    recursion ``Phi^k Gam`` summed by a plain loop, and the pitch gain against a closed-form lower
    bound: the l1 norm of an impulse response is at least the absolute sum of its samples, the DC
    gain (1 for the servo's unit-gain pitch, 0 for its rate)."""
    from fdi_lib.systems.wind_turbine import pitch_discretisation

    c = W.plant_constants()
    g_beta, g_rate = W._servo_gains(c)
    Phi, Gam = pitch_discretisation(c.params.omega_n, c.params.zeta, ts=c.Ts)
    g, acc = Gam[:, 0], np.zeros(2)
    for _ in range(int(np.ceil(60.0 / c.Ts))):
        acc += np.abs(g)
        g = Phi @ g
    assert (g_beta, g_rate) == pytest.approx(tuple(acc), rel=1e-12)
    assert g_beta >= 1.0 - 1e-9 and g_rate > 0.0


def test_operating_envelope_contains_every_simulated_state():
    """The SVO's prior set (:func:`fdi_lib.windturbine.operating_envelope`) holds the true state
    and ``tau_a`` at every sample of fault-free segments of every fault of the scenario (low-wind
    starts included: its lower speed faces are 0), and each face is where its criterion puts it:
    the speeds from 0, the converter torque up to the controller's largest reference, the pitch
    within the servo's reach of the reference limits."""
    c = W.plant_constants()
    env = W.operating_envelope(c, 5.0)
    seeds = np.random.SeedSequence(2009).spawn(8)
    for f in wt.FAULTS:
        rec = W.fault_records(f, seeds, faulty=False)
        x = rec.x.reshape(-1, 10)
        assert ((x >= env.x[0]) & (x <= env.x[1])).all(), f.id
        assert ((rec.tau_a >= env.tau[0]) & (rec.tau_a <= env.tau[1])).all(), f.id
    p = c.params
    assert env.x[0, [6, 7, 9]].tolist() == [0.0, 0.0, 0.0] and env.tau[0] == 0.0
    tgc = p.P_r / (p.eta_gc * (p.omega_nom - p.omega_delta)) / 1e3
    assert env.x[1, 9] == pytest.approx(tgc)
    assert env.x[0, 0] < p.beta_min and env.x[1, 0] > p.beta_max
    assert env.x[1, 7] == pytest.approx(p.N_g * env.x[1, 6])
    with pytest.raises(ModelError):
        W.operating_envelope(c, -1.0)
