"""The wind-turbine scoreboard's logic on hand-built alarm sequences (issue 36, point 3).

Every expectation here is written out by hand from the benchmark's reading of an alarm sequence:
an alarm before the fault's start is a false alarm and never a detection, every alarm in a
fault-free stretch is counted, a detection or isolation at the fault's first sample takes one
sample.
"""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

from fdi_lib import windturbine as W
from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.montecarlo import run_monte_carlo
from fdi_lib.reproduce import windturbine as RW
from fdi_lib.reproduce import windturbine_streams as RS

TS = 0.01


def _alarms(n: int, at: list[int]) -> np.ndarray:
    a = np.zeros(n, dtype=bool)
    a[at] = True
    return a


def test_alarm_onsets_are_upcrossings_and_the_detector_rearms():
    over = np.array([0, 1, 1, 1, 0, 0, 1, 0, 1, 1], dtype=bool)
    assert W.alarm_onsets(over, 0).nonzero()[0].tolist() == [1, 6, 8]
    # a statistic already above its threshold when scoring starts is an alarm there, once
    assert W.alarm_onsets(over, 2).nonzero()[0].tolist() == [2, 6, 8]
    assert W.alarm_onsets(over, 10).sum() == 0
    # per record, on a batch
    both = W.alarm_onsets(np.stack([over, ~over]), 0)
    assert both[1].nonzero()[0].tolist() == [0, 4, 7]


def test_a_false_alarm_before_the_onset_is_never_a_detection():
    """An alarm at 3 whose statistic stays above its threshold past the onset (5): one false alarm,
    no detection (the detector has not re-armed); a fresh alarm after re-arming is the detection."""
    stat = np.array([0, 0, 0, 9, 9, 9, 9, 0, 0, 0], dtype=float)
    edges = W.alarm_onsets(stat > 1.0, 1)
    count, fa, det = W.score_alarms(edges, onset=5, start=1)
    assert (int(count), bool(fa), int(det)) == (1, True, -1)
    stat[8] = 9.0
    count, fa, det = W.score_alarms(W.alarm_onsets(stat > 1.0, 1), onset=5, start=1)
    assert (int(count), bool(fa), int(det)) == (1, True, 8)


def test_every_alarm_in_a_fault_free_stretch_is_counted():
    n, onset, start = 40, 30, 5
    for at in ([5], [29], [5, 10, 29], list(range(5, 30, 2))):
        count, fa, det = W.score_alarms(_alarms(n, at), onset=onset, start=start)
        assert int(count) == len(at) and bool(fa) and int(det) == -1, at
    # alarms before the scored stretch (the warm-up) are not counted; at the onset it is a detection
    count, fa, det = W.score_alarms(_alarms(n, [0, 4, 30]), onset=onset, start=start)
    assert (int(count), bool(fa), int(det)) == (0, False, 30)
    # a whole fault-free record (onset at its end): every alarm is a false alarm
    count, fa, det = W.score_alarms(_alarms(n, [6, 7, 39]), onset=n, start=start)
    assert (int(count), bool(fa), int(det)) == (3, True, -1)


def test_combine_reads_each_subsystem_and_names_the_first(monkeypatch):
    """The methods' combination of subsystem statistics: a pre-onset alarm on one subsystem is a false
    alarm; the detection is the earliest fresh alarm after the onset on any subsystem."""

    class D:
        warmup, onset = 2, 6

    a = np.array([[0, 0, 0, 5, 5, 5, 5, 5, 5, 5.0]])  # false alarm at 3, still over after the onset
    b = np.array([[0, 0, 0, 0, 0, 0, 0, 0, 5, 5.0]])  # a fresh alarm at 8
    fa, det, which, peak = W._combine(D, [a, b], [1.0, 1.0])
    assert fa.tolist() == [True] and det.tolist() == [8] and which.tolist() == [1]
    assert peak.tolist() == [5.0]
    fa, det, which, _ = W._combine(D, [b, b], [1.0, 1.0])
    assert fa.tolist() == [False] and det.tolist() == [8] and which.tolist() == [0]
    fa, det, which, _ = W._combine(D, [np.zeros((1, 10)), np.zeros((1, 10))], [1.0, 1.0])
    assert fa.tolist() == [False] and det.tolist() == [-1] and which.tolist() == [-1]


def test_delays_count_the_first_faulty_sample():
    np.testing.assert_allclose(
        W.delays(np.array([100, 109, 100 + 4999]), 100, TS), [0.01, 0.10, 50.0]
    )
    assert np.isnan(W.delays(np.array([-1]), 100, TS)).all()


def test_score_method_on_hand_built_outcomes():
    """Four realisations, onset 100, requirement 0.1 s (10 samples): detected at 100, 109, 150, never;
    isolations: exactly right at 120, right at 200, a wrong one, none."""
    onset = 100
    exp = {"beta1_m1"}
    j, k = W.CANDIDATES.index("beta1_m1"), W.CANDIDATES.index("beta2_m1")
    iso = np.zeros((4, len(W.CANDIDATES)), dtype=bool)
    iso[0, j] = iso[1, j] = iso[2, k] = True
    iso[3, j] = True  # named by a record that never detected
    e = RW.score_method(
        np.array([100, 109, 150, -1]), iso, np.array([120, 200, 160, 130]), exp, 0.1, onset, TS
    )
    assert e["detected"] == 3 and e["missed"] == 1
    assert e["within_requirement"] == 0.5  # 0.01 s and 0.10 s; 0.51 s is late
    np.testing.assert_allclose(e["detection_time_mean_s"], (0.01 + 0.10 + 0.51) / 3)
    assert e["isolation_correct"] == 0.5 and e["wrong_isolations"] == 1 and e["not_isolated"] == 0
    np.testing.assert_allclose(e["isolation_time_mean_s"], (0.21 + 1.01) / 2)
    lo, hi = e["within_requirement_ci"]
    assert lo < 0.5 < hi
    assert e["isolated_mode"] == "beta1_m1"
    none = RW.score_method(np.full(4, -1), np.zeros_like(iso), np.full(4, -1), exp, None, onset, TS)
    assert (
        none["detected"] == 0
        and none["within_requirement"] is None
        and none["isolation_time_mean_s"] is None
    )
    assert none["isolation_correct"] == 0.0 and none["isolated_mode"] is None


def _slow_chunks(seeds):
    """Chunks slow enough for a pool to deliver them out of order: the earlier a chunk, the slower
    (0.1 to 0.8 s). Each trial carries its index, the process that ran it and when its chunk
    finished."""
    idx = np.array([s.spawn_key[-1] for s in seeds])
    time.sleep(0.1 * max(1, 8 - int(idx[0]) // 2))
    return {
        "detect": np.where(idx % 3 == 0, -1, 100 + idx),
        "idx": idx,
        "pid": np.full(len(seeds), os.getpid()),
        "done": np.full(len(seeds), time.monotonic_ns()),
    }


def _check_order(one: dict, two: dict) -> None:
    assert (two["pid"] != os.getpid()).any()  # another process ran some chunks
    assert (np.diff(two["done"][::2]) < 0).any()  # ... and delivered them out of trial order
    assert two["idx"].tolist() == list(range(16)) == one["idx"].tolist()
    np.testing.assert_array_equal(one["detect"], two["detect"])
    # the scoreboard's summary reads the same realisations whichever run it is given
    iso = np.zeros((16, len(W.CANDIDATES)), dtype=bool)
    a = RW.score_method(one["detect"], iso, one["detect"], {"converter"}, 0.1, 100, TS)
    b = RW.score_method(two["detect"], iso, two["detect"], {"converter"}, 0.1, 100, TS)
    assert a == b


def test_trial_order_does_not_depend_on_which_worker_finishes_first():
    """Two jobs (this process from the front, a worker from the back) and an executor of two
    processes (chunks 1, 2, ... submitted in order, the earlier slower: they finish in reverse)."""
    import concurrent.futures

    from joblib.externals.loky import get_reusable_executor

    one = run_monte_carlo(_slow_chunks, 16, seed=5, jobs=1, chunk_size=2)
    # the pool that jobs=2 reuses, started and its imports done first: its start-up (seconds on a
    # loaded machine) would let this process compute every chunk itself
    warm = [np.random.SeedSequence(0, spawn_key=(15,))]
    get_reusable_executor(max_workers=1, timeout=600).submit(_slow_chunks, warm).result()
    _check_order(one, run_monte_carlo(_slow_chunks, 16, seed=5, jobs=2, chunk_size=2))
    with concurrent.futures.ProcessPoolExecutor(2) as pool:
        _check_order(one, run_monte_carlo(_slow_chunks, 16, seed=5, chunk_size=2, executor=pool))


@pytest.mark.parametrize(
    "trials, why",
    [
        (10**12, r"would need about .* of memory"),
        # 10**6 realisations x SECONDS_PER_REALISATION s / 2 processes, in hours
        (
            10**6,
            rf"would take about {10**6 * RW.SECONDS_PER_REALISATION / 2 / 3600:.3g} h on 2 processes",
        ),
    ],
)
def test_scoreboard_refuses_a_budget_breaking_trials_count_before_simulating(
    trials, why, monkeypatch
):
    """``--trials`` beyond the time or memory budget: a ResourceError with the estimate, before any
    simulation (a simulation here would fail the test)."""
    import fdi_lib.montecarlo as mc
    from fdi_lib.errors import ResourceError
    from fdi_lib.reproduce import list_reproductions, reproduce

    # every reproduction module imported before the stub below: one imported under it (the
    # accommodation's, by the registry's first lookup) would keep the stub after the test
    list_reproductions()
    monkeypatch.setattr(mc, "available_memory", lambda: 16 * 10**9)
    monkeypatch.setattr(mc, "effective_jobs", lambda jobs, n_tasks=None: 2)
    monkeypatch.setattr(
        RW, "calibrated_design", lambda *a, **k: pytest.fail("simulated before the check")
    )
    with pytest.raises(
        ResourceError,
        match=rf"trials: {trials} realisations \(about {RW.SECONDS_PER_REALISATION:g} s of a core .*{why}",
    ):
        reproduce("windturbine-scoreboard", trials=trials, jobs=2)
    assert RW.check_trials(100, 1) == 100
    # the limit itself: the largest count accepted on two processes, and one more refused
    n = int(2 * RW.MAX_RUN_S // RW.SECONDS_PER_REALISATION)
    assert RW.check_trials(n, 2) == n
    with pytest.raises(ResourceError, match=r"limit is 24 h \(MAX_RUN_S\)"):
        RW.check_trials(n + 1, 2)


# ----------------------------------------------------------------------------- long streams
@pytest.fixture(scope="module")
def stream():
    pytest.importorskip("numba")
    from fdi_lib.systems import wind_turbine as wt

    d, start = RS.stream_design(2009)
    healthy = W.records(
        wt.simulate(seed=np.random.SeedSequence(77).spawn(1), faults=(), duration_s=100.0)
    )
    f8 = next(f for f in wt.FAULTS if f.id == 8)
    import dataclasses

    fault = dataclasses.replace(f8, start_s=50.0, stop_s=70.0)
    faulty = W.records(
        wt.simulate(seed=np.random.SeedSequence(77).spawn(1), faults=(fault,), duration_s=100.0)
    )
    return d, start, healthy, faulty


def test_stream_windows_tile_the_stream_and_batches_do_not_change_the_counts(stream):
    d, start, healthy, faulty = stream
    n = healthy.y.shape[1]
    step = d.N - start
    one = W.stream_counts(d, faulty.y[0], faulty.u[0], start, batch=1)
    many = W.stream_counts(d, faulty.y[0], faulty.u[0], start, batch=3)
    windows = one.pop("per_window")
    assert {
        m: {t: c.tolist() for t, c in tc.items()} for m, tc in many.pop("per_window").items()
    } == {m: {t: c.tolist() for t, c in tc.items()} for m, tc in windows.items()}
    assert one == many
    n_windows = one["samples"] // step
    for m, tc in windows.items():  # one count per window, adding up to the test's
        for t, c in tc.items():
            assert c.shape == (n_windows,) and c.sum() == one["by_test"][m][t], (m, t)
    assert one["samples"] == ((n - d.N) // step + 1) * step and one["samples"] > n - d.N
    assert one["tests"] == {"zb2014": 4, "zhang2021": 4, "bz": 8, "rosa2013": 1}
    subs = ["blade1", "blade2", "blade3", "drive_train"]
    assert {m: list(v) for m, v in one["by_test"].items()} == {
        "zb2014": subs,
        "zhang2021": subs,
        "bz": [f"{s} parametric" for s in subs] + [f"{s} energy" for s in subs],
        "rosa2013": ["bank"],
    }
    for m in W.METHODS:  # the tests' counts add up to the method's
        assert sum(one["by_test"][m].values()) == one[m], m
    # a statistical test counted alone: its statistic's onsets over the threshold, window by window
    inputs = W.MethodInputs(d, faulty.y[0][None, : d.N], faulty.u[0][None, : d.N])
    st = W._zb_glr(d, inputs.innovations, estimates=False)["drive_train"].statistic[0]
    over = np.nan_to_num(st, nan=-np.inf) > d.subs["drive_train"].glr_threshold
    first = sum(over[k] and not over[k - 1] for k in range(start, d.N))
    window = W.stream_alarms(d, faulty.y[0][None, : d.N], faulty.u[0][None, : d.N], start)
    assert window["by_test"]["zb2014"]["drive_train"][0] == first


def test_a_method_whose_alarms_do_not_match_its_tests_is_refused(stream, monkeypatch):
    import dataclasses

    d, start, healthy, _ = stream
    bad = dataclasses.replace(W.METHODS["rosa2013"], tests=("bank", "extra"))
    monkeypatch.setitem(W.METHODS, "rosa2013", bad)
    with pytest.raises(
        ModelError, match=r"METHODS\['rosa2013'\]\.alarms: expected counts of shape"
    ):
        W.stream_alarms(d, healthy.y[:, : d.N], healthy.u[:, : d.N], start, ["rosa2013"])


def test_stream_counts_split_by_the_kind_of_window_add_up(stream):
    """With the regions, each window is of one kind (a brute-force loop over the windows' scored
    samples) and the split counts add up to the totals; a stream in one region puts every window
    and alarm in that region's kind; a region of the wrong length or value is refused."""
    d, start, healthy, faulty = stream
    y, u, region = faulty.y[0], faulty.u[0], faulty.region[0]
    got = W.stream_counts(d, y, u, start, batch=2, region=region)
    plain = W.stream_counts(d, y, u, start, batch=2)
    del plain["per_window"]
    assert {k: got[k] for k in (*W.METHODS, "tests", "by_test", "samples")} == plain
    step = d.N - start
    kinds = []
    for w in range(got["samples"] // step):
        r = region[w * step + start : w * step + d.N]
        kinds.append("switch" if len(set(r)) > 1 else "full_load" if r[0] == 2 else "partial_load")
    assert got["windows"] == {k: kinds.count(k) for k in ("switch", "full_load", "partial_load")}
    assert [W.WINDOW_KINDS[k] for k in got["window_kinds"]] == kinds
    for m in W.METHODS:
        assert sum(got["by_region"][m].values()) == got[m], m
    full = W.stream_counts(d, y, u, start, region=np.full(region.shape, 2))
    assert full["windows"]["full_load"] == len(kinds)
    assert all(full["by_region"][m]["full_load"] == full[m] for m in W.METHODS)
    with pytest.raises(ShapeError, match="region"):
        W.stream_counts(d, y, u, start, region=region[:-1])
    bad = region.copy()
    bad[[7, 9]] = [0, 3]
    with pytest.raises(ModelError, match=r"region: .* got 0(\.0)? at index 7 \(2 such samples\)"):
        W.stream_counts(d, y, u, start, region=bad)


def test_stream_detectors_alarm_on_a_fault_and_count_it_once_per_test(stream):
    """A converter offset for 20 s in the middle of a 100 s stream: every method alarms; a
    statistical test whose statistic stays over its threshold across a window boundary counts one
    alarm (so at most a few per test, not one per window); the fault-free twin raises fewer."""
    d, start, healthy, faulty = stream
    on = W.stream_counts(d, faulty.y[0], faulty.u[0], start)
    off = W.stream_counts(d, healthy.y[0], healthy.u[0], start)
    for m in W.METHODS:
        assert on[m] >= 1, m
        assert off[m] < on[m], m
    for m in ("zb2014", "zhang2021", "bz"):
        assert on[m] <= 2 * on["tests"][m], (m, on[m])


def test_false_alarm_study_json_and_its_exact_poisson_bounds(monkeypatch):
    """The study on two short streams (the scenario cut to 60 s here): keys, hours, and the exact
    Poisson interval checked against its definition (P(X >= a) = 2.5 % at the lower end, P(X <= a)
    = 2.5 % at the upper)."""
    pytest.importorskip("numba")
    import scipy.stats

    from fdi_lib.systems import wind_turbine as wt

    monkeypatch.setattr(wt, "SCENARIO_S", 60.0)
    r = RS.false_alarms(seed=2009, trials=2, jobs=1)
    h = r.headline
    d, start = RS.stream_design(2009)
    per_stream = ((6000 - d.N) // (d.N - start) + 1) * (d.N - start)
    assert h["streams"] == 2 and h["hours"] == pytest.approx(2 * per_stream * 0.01 / 3600)
    assert set(h["methods"]) == set(W.METHODS)
    assert sum(h["windows_by_region"].values()) * (d.N - start) == 2 * per_stream
    for m, v in h["methods"].items():
        assert sum(v["alarms_by_region"].values()) == v["alarms"]
        exposure = h["hours"] * v["tests"]
        assert v["rate_per_test_hour"] == pytest.approx(v["alarms"] / exposure)
        lo, hi = v["rate_per_test_hour_ci"]
        assert scipy.stats.poisson.cdf(v["alarms"], hi * exposure) == pytest.approx(0.025, abs=1e-9)
        if v["alarms"]:
            assert scipy.stats.poisson.sf(v["alarms"] - 1, lo * exposure) == pytest.approx(
                0.025, abs=1e-9
            )
        assert v["below_nominal"] == (hi < v["nominal_per_test_hour"])
        assert sum(v["alarms_by_test"].values()) == v["alarms"]
        assert list(v["alarms_by_test"]) == list(W.METHODS[m].tests)
    # the torque's increments per region, by a loop over the two streams' samples
    inc = h["tau_a_increments"]
    assert inc["filter_variance"] == d.calibration.q_tau
    sq, n = {1: 0.0, 2: 0.0}, {1: 0, 2: 0}
    for s in np.random.SeedSequence(2009).spawn(2):
        rec = W.records(wt.simulate(seed=[s], faults=(), duration_s=60.0))
        tau, region = rec.tau_a[0], rec.region[0]
        for k in range(1, len(tau)):
            sq[region[k]] += (tau[k] - tau[k - 1]) ** 2
            n[region[k]] += 1
    assert inc["samples_by_region"] == {"partial_load": n[1], "full_load": n[2]}
    by_alarm = inc["full_load_windows_by_drive_train_alarm"]
    assert list(by_alarm) == ["zb2014", "zhang2021", "bz"]  # the SVO bank has no drive-train test
    full = sum(v["windows"] for v in by_alarm["zb2014"].values())
    assert all(sum(v["windows"] for v in e.values()) == full for e in by_alarm.values())
    assert full == h["windows_by_region"]["full_load"]
    for name, code in (("partial_load", 1), ("full_load", 2)):
        if n[code]:
            ms = sq[code] / n[code]
            assert inc["mean_square_by_region"][name] == pytest.approx(ms, rel=1e-9)
            assert inc["ratio_by_region"][name] == pytest.approx(ms / d.calibration.q_tau, rel=1e-9)
        else:
            assert inc["mean_square_by_region"][name] is None
    # 0 alarms over 1 h gives an upper bound of 3.69 per hour: what "can test 1 per hour" needs
    assert RW._poisson_ci(0, 1.0)[1] == pytest.approx(-np.log(0.025))


def test_full_load_windows_split_by_a_drive_train_alarm_by_a_loop_over_samples():
    """The torque's squared increments over the scored samples of the full-load windows, split by
    whether a method's drive-train test(s) alarmed there: a loop over windows and samples on a
    hand-built stream (5 windows; the SVO bank, without a drive-train test, stays at zero)."""
    rng = np.random.default_rng(3)
    step, start, N = 7, 3, 10
    K = 5
    dtau = rng.standard_normal(K * step + start + 2)
    kinds = np.array([1, 1, 0, 1, 2])  # full, full, switch, full, partial
    drive = {"zb2014": [2, 0, 1, 0, 0], "zhang2021": [0, 0, 0, 0, 3]}
    per_window = {m: {t: np.zeros(K, int) for t in W.METHODS[m].tests} for m in W.METHODS}
    per_window["zb2014"]["drive_train"][:] = drive["zb2014"]
    per_window["zb2014"]["blade1"][:] = [0, 1, 0, 1, 0]  # not a drive-train test
    per_window["zhang2021"]["drive_train"][:] = drive["zhang2021"]
    per_window["bz"]["drive_train energy"][:] = [0, 0, 0, 1, 0]
    per_window["bz"]["drive_train parametric"][:] = [0, 1, 0, 0, 0]
    drive["bz"] = [0, 1, 0, 1, 0]
    out = {
        k: np.zeros((1, len(W.METHODS), 2), dtype=float if "sq" in k else np.int64)
        for k in ("dtau_sq_full_by_alarm", "full_windows_by_alarm")
    }
    RS._full_load_windows(
        out, 0, {"window_kinds": kinds, "per_window": per_window}, dtau, step, start, N
    )
    for m, name in enumerate(W.METHODS):
        want = np.zeros((3, 2))
        for w in range(K):
            if kinds[w] != 1 or name not in drive:
                continue
            j = int(drive[name][w] > 0)
            for k in range(w * step + start, w * step + N):
                want[0, j] += dtau[k - 1] ** 2
                want[1, j] += 1
            want[2, j] += 1
        got = [out[k][0, m] for k in out]
        np.testing.assert_allclose(got[0], want[0], rtol=1e-12, err_msg=name)
        assert got[1].tolist() == want[2].tolist(), name
        assert (want[1] == want[2] * step).all()  # each window scores step samples


def test_false_alarm_study_is_registered_with_ten_hours_by_default_and_one_stream_in_the_book():
    """``windturbine-false-alarms`` in the registry: the command line's default covers at least 10
    scored hours (what testing the nominal rate of a test without alarms needs), the book runs
    :data:`BOOK_STREAMS` and its catalogue command says so; a run too long for
    :data:`~fdi_lib.reproduce.windturbine.MAX_RUN_S` is refused before anything is simulated."""
    from fdi_lib.errors import ResourceError
    from fdi_lib.reproduce import get
    from fdi_lib.reproduce.book import book_argv, book_settings
    from fdi_lib.systems import wind_turbine as wt

    rep = get("windturbine-false-alarms")
    d, start = RS.stream_design(2009)
    n = int(round(wt.SCENARIO_S / d.constants.Ts))
    per_stream_h = ((n - d.N) // (d.N - start) + 1) * (d.N - start) * d.constants.Ts / 3600
    assert rep.default_trials * per_stream_h >= 10.0 > (rep.default_trials - 1) * per_stream_h
    assert book_settings(rep.id).trials == RS.BOOK_STREAMS < rep.default_trials
    assert book_argv(rep.id)[-3:] == ["--trials", str(RS.BOOK_STREAMS), "--json"]
    with pytest.raises(ResourceError, match="trials"):
        rep(seed=2009, trials=10**5, jobs=1)


# ----------------------------------------------------------------------------- the SVO's assumptions
def test_the_svo_prior_contains_a_low_wind_start_and_raises_no_false_alarm():
    """Realisation 0 of seed 2009, fault F5's stretch: a low-wind start (rotor speed 0.125-0.183
    rad/s in the 8 such stretches of the 100-trial scoreboard) that lay below the former prior set
    (the calibration runs' state range widened 1.5x, lower face 0.239 rad/s): the nominal set was
    empty at its first sample, a false alarm on fault-free data. The prior set is now the plant's
    operating envelope (:func:`fdi_lib.windturbine.operating_envelope`): it contains that state,
    no assumption of the sets is broken and the SVO raises no alarm (Proposition 3)."""
    pytest.importorskip("numba")
    from fdi_lib.systems import wind_turbine as wt

    d = RW.calibrated_design(2009)
    seeds = np.random.SeedSequence(2009).spawn(2)
    _, twin = W.fault_record_pair(next(f for f in wt.FAULTS if f.id == 5), seeds)
    s = d.subs["drive_train"].sub
    start = np.r_[twin.x[0, d.warmup, list(s.states)], twin.tau_a[0, d.warmup]]
    assert start[0] < 0.239  # the low-wind start the former prior missed
    assert W.svo_priors(d)["drive_train"].contains(start)
    assert RW._bound_violation(d, twin).tolist() == [False, False]
    assert W.run_svo_bank(d, twin.y, twin.u).false_alarm.tolist() == [False, False]


def test_the_banks_run_on_the_detected_records_only_with_the_whole_banks_outcome(monkeypatch):
    """run_svo_bank runs the fault hypotheses' SVOs only where the nominal set empties: its outcome
    is the one of the banks run on every record (forced here by a stand-in that reports every
    nominal set empty), on records with a detection and an isolation (F1), a detection alone (F2)
    and neither (F4)."""
    pytest.importorskip("numba")
    from fdi_lib.sets.svo import SVOBatchRun
    from fdi_lib.systems import wind_turbine as wt

    d = RW.calibrated_design(2009)
    seeds = np.random.SeedSequence(2009).spawn(2)
    recs = [W.fault_records(f, seeds) for f in wt.FAULTS if f.id in (1, 2, 4)]
    y, u = (np.concatenate([getattr(r, k) for r in recs]) for k in ("y", "u"))
    lazy = W.run_svo_bank(d, y, u)
    monkeypatch.setattr(W, "run_svo_many", lambda models, *a, **k: SVOBatchRun((0,) * len(models)))
    whole = W.run_svo_bank(d, y, u)
    for key in ("false_alarm", "detect", "subsystem", "isolated", "isolate_step"):
        np.testing.assert_array_equal(getattr(lazy, key), getattr(whole, key), err_msg=key)
    assert (lazy.detect < 0).any() and (lazy.isolate_step >= 0).any()
    assert ((lazy.detect >= 0) & (lazy.isolate_step < 0)).any()  # detected, not isolated
