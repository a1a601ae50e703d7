"""The wind-turbine benchmark's false-alarm study: hours of fault-free operation, in constant memory.

:func:`false_alarms` runs the four methods of :mod:`fdi_lib.windturbine` over whole fault-free
scenarios of the benchmark (:data:`~fdi_lib.systems.wind_turbine.SCENARIO_S` seconds each), each as one
continuous stream scored in overlapping windows (:func:`fdi_lib.windturbine.stream_counts`), and
counts their alarms per hour and per test-hour against the design's nominal rate. The scoreboard
(:mod:`fdi_lib.reproduce.windturbine`) counts false alarms too, over the short fault-free stretch
before each fault.
"""

from __future__ import annotations

import functools

import numpy as np
import scipy.stats

from fdi_lib import windturbine as W
from fdi_lib.montecarlo import run_monte_carlo
from fdi_lib.reproduce.registry import ReproductionResult, register
from fdi_lib.reproduce.windturbine import (
    CALIBRATION_RUNS,
    PAPER,
    _calibration,
    _poisson_ci,
    check_trials,
)
from fdi_lib.threads import single_threaded_blas

__all__ = [
    "false_alarms",
    "FALSE_ALARM_STREAMS",
    "BOOK_STREAMS",
    "SECONDS_PER_STREAM",
    "stream_chunk",
    "stream_design",
    "STREAM_WINDOW_S",
    "STREAM_OVERLAP_S",
    "STREAM_BATCH",
]


#: The false-alarm study's windows (:func:`fdi_lib.windturbine.stream_counts`): each window scores
#: ``STREAM_WINDOW_S`` seconds after an overlap of ``STREAM_OVERLAP_S`` with the previous one (the
#: filters' warm-up and one test window, :class:`~fdi_lib.windturbine.Settings`, plus 0.5 s).
STREAM_WINDOW_S = 20.0
STREAM_OVERLAP_S = 4.0
#: Windows scored as one batch of records by the false-alarm study (``stream_counts``'s ``batch``):
#: the memory unit, whatever the stream's length. The filters', the SVO bank's and the GLR's
#: per-sample steps cost nearly the same for more records: 32 windows run about 3x faster per
#: sample than 8, 64 about 1.25x faster than 32 (the four methods over the book's 4400 s stream:
#: 6.4-7.4 s of CPU against 8.2-9.3; 96: 5.6 s) for a peak of about 170 MB (tracemalloc, a 2000 s
#: stream; 110 MB with 32, 220 MB with 96). The same alarm counts (each window is computed alone).
STREAM_BATCH = 64


def stream_design(seed: int) -> tuple[W.Design, int]:
    """The methods' design for the false-alarm study's windows and the sample at which each window's
    scoring starts: the calibration of :func:`calibrated_design` (shared), windows of
    ``STREAM_OVERLAP_S + STREAM_WINDOW_S`` seconds."""
    c, cal, x0 = _calibration(int(seed), W.Settings(), "benchmark")
    n = int(round((STREAM_OVERLAP_S + STREAM_WINDOW_S) / c.Ts))
    settings = W.Settings(pre_s=(n - 1) * c.Ts, post_s=c.Ts)
    return _stream_design(int(seed), settings), int(round(STREAM_OVERLAP_S / c.Ts))


@functools.lru_cache(maxsize=2)
@single_threaded_blas
def _stream_design(seed: int, settings: W.Settings) -> W.Design:
    return W.design(*_calibration(seed, W.Settings(), "benchmark"), settings)


def stream_chunk(seeds: list, *, seed: int) -> dict[str, np.ndarray]:
    """Monte Carlo chunk of the false-alarm study: per seed, the benchmark's whole fault-free
    scenario (:data:`~fdi_lib.systems.wind_turbine.SCENARIO_S` seconds, its wind and noise from the
    seed) run as one continuous stream, and the alarms of each method over it
    (:func:`fdi_lib.windturbine.stream_counts`)."""
    from fdi_lib.systems import wind_turbine as wt

    d, start = stream_design(seed)
    n, M = len(seeds), len(W.METHODS)
    K = len(W.WINDOW_KINDS)
    out = {
        "alarms": np.zeros((n, M), dtype=np.int64),
        "tests": np.zeros((n, M), dtype=np.int64),
        "samples": np.zeros(n, dtype=np.int64),
        "alarms_by_region": np.zeros((n, M, K), dtype=np.int64),
        "windows_by_region": np.zeros((n, K), dtype=np.int64),
        "dtau_sq_by_region": np.zeros((n, len(REGIONS))),
        "dtau_n_by_region": np.zeros((n, len(REGIONS)), dtype=np.int64),
        # full-load windows with and without an alarm of a method's drive-train test(s): [without, with]
        "dtau_sq_full_by_alarm": np.zeros((n, M, 2)),
        "full_windows_by_alarm": np.zeros((n, M, 2), dtype=np.int64),
    }
    for i, s in enumerate(seeds):
        rec = W.records(wt.simulate(seed=[s], faults=(), duration_s=wt.SCENARIO_S))
        counts = W.stream_counts(
            d, rec.y[0], rec.u[0], start, batch=STREAM_BATCH, region=rec.region[0]
        )
        out["alarms"][i] = [counts[m] for m in W.METHODS]
        out["tests"][i] = [counts["tests"][m] for m in W.METHODS]
        out["samples"][i] = counts["samples"]
        out["alarms_by_region"][i] = [
            [counts["by_region"][m][k] for k in W.WINDOW_KINDS] for m in W.METHODS
        ]
        out["windows_by_region"][i] = [counts["windows"][k] for k in W.WINDOW_KINDS]
        for m in W.METHODS:
            out.setdefault(f"alarms_by_test_{m}", np.zeros((n, len(counts["by_test"][m])), int))
            out[f"alarms_by_test_{m}"][i] = list(counts["by_test"][m].values())
        dtau, region = np.diff(rec.tau_a[0]), rec.region[0][1:]
        for r, code in enumerate(REGIONS.values()):
            out["dtau_sq_by_region"][i, r] = float(np.sum(dtau[region == code] ** 2))
            out["dtau_n_by_region"][i, r] = int(np.sum(region == code))
        _full_load_windows(out, i, counts, dtau, d.N - start, start, d.N)
    return out


def _full_load_windows(
    out: dict[str, np.ndarray],
    i: int,
    counts: dict,
    dtau: np.ndarray,
    step: int,
    start: int,
    N: int,
) -> None:
    """Fill row ``i`` of :func:`stream_chunk`'s ``*_full_by_alarm`` arrays: over the full-load
    windows of a stream's :func:`~fdi_lib.windturbine.stream_counts` ``counts``, split by whether
    a method's drive-train test(s) alarmed in the window, the sum of the squared increments of
    ``tau_a`` (``dtau[k - 1]`` for the window's ``step`` scored samples ``k``) and the windows'
    number. A method without a drive-train test leaves its row at zero."""
    full = counts["window_kinds"] == W.WINDOW_KINDS.index("full_load")
    first = np.arange(full.size) * step + start  # each window's first scored sample
    cum = np.r_[0.0, np.cumsum(dtau**2)]
    sq = cum[first + step - 1] - cum[first - 1]  # dtau[first - 1 : first + step - 1]
    for m, name in enumerate(W.METHODS):
        tests = W.METHODS[name].tests_on("drive_train")
        if not tests:
            continue
        alarmed = np.sum([counts["per_window"][name][t] for t in tests], axis=0) > 0
        for j, sel in enumerate((full & ~alarmed, full & alarmed)):
            out["dtau_sq_full_by_alarm"][i, m, j] = float(sq[sel].sum())
            out["full_windows_by_alarm"][i, m, j] = int(sel.sum())


#: The controller's operating regions by their code in :attr:`~fdi_lib.windturbine.Records.region`.
REGIONS = {"partial_load": 1, "full_load": 2}


#: Continuous fault-free scenarios of :func:`false_alarms` by default: 9 x 4400 s, 10.95 scored
#: hours, enough for an interval that can test the nominal rate of a test that raises no alarm.
FALSE_ALARM_STREAMS = 9
#: The book's count (one scenario, 1.22 scored hours): the default's 9 would take the chapter
#: about 1 min of a core (:data:`SECONDS_PER_STREAM`).
BOOK_STREAMS = 1
#: Seconds of one core per stream (the simulation and the four methods over one 4400 s scenario,
#: measured as the second of two streams at ``--jobs 1``, user CPU: about 6.1 s on the book's 2-core
#: machine), rounded up: the estimate with which a too large ``trials`` is refused
#: (:func:`check_trials`).
SECONDS_PER_STREAM = 7.0


def _alarm_rates(x: dict[str, np.ndarray], hours: float, nominal: float) -> dict[str, dict]:
    """The headline's ``methods`` of :func:`false_alarms`: each method's alarms over ``hours``
    of streams, per hour and per test-hour, against the ``nominal`` rate of each test, and split
    by the kind of window (:data:`~fdi_lib.windturbine.WINDOW_KINDS`)."""
    methods = {}
    kind_hours = x["windows_by_region"].sum(axis=0) * STREAM_WINDOW_S / 3600.0
    for m, name in enumerate(W.METHODS):
        a = int(x["alarms"][:, m].sum())
        k = int(x["tests"][0, m])
        ci = _poisson_ci(a, hours * k)
        by = x["alarms_by_region"][:, m].sum(axis=0)
        methods[name] = {
            "alarms": a,
            "tests": k,
            "rate_per_hour": a / hours,
            "rate_per_hour_ci": _poisson_ci(a, hours),
            "rate_per_test_hour": a / (hours * k),
            "rate_per_test_hour_ci": ci,
            "nominal_per_test_hour": nominal,
            "p_value_nominal": float(scipy.stats.poisson.sf(a - 1, nominal * hours * k)),
            "below_nominal": bool(ci[1] < nominal),
            "alarms_by_region": {kind: int(c) for kind, c in zip(W.WINDOW_KINDS, by)},
            "rate_per_test_hour_by_region": {
                kind: float(c / (h * k)) if h > 0 else None
                for kind, c, h in zip(W.WINDOW_KINDS, by, kind_hours)
            },
            "alarms_by_test": dict(
                zip(W.METHODS[name].tests, map(int, x[f"alarms_by_test_{name}"].sum(axis=0)))
            ),
        }
    return methods


def _headline(x: dict[str, np.ndarray], seed: int, nominal: float) -> dict:
    """The headline of :func:`false_alarms` from its chunks' arrays ``x``."""
    d, start = stream_design(seed)
    hours = float(x["samples"].sum() * d.constants.Ts / 3600.0)
    return {
        "streams": int(x["samples"].shape[0]),
        "hours": hours,
        "windows_by_region": dict(
            zip(W.WINDOW_KINDS, map(int, x["windows_by_region"].sum(axis=0)))
        ),
        "methods": _alarm_rates(x, hours, nominal),
        "tau_a_increments": _tau_a_increments(x, d.calibration.q_tau, d.N - start),
    }


def _tau_a_increments(x: dict[str, np.ndarray], q_tau: float, step: int) -> dict:
    """The headline's ``tau_a_increments`` of :func:`false_alarms`: the mean square of the
    aerodynamic torque's increments per sample in each operating region over the streams, against
    the variance ``q_tau`` of the Kalman filter's random walk (:class:`~fdi_lib.windturbine.Calibration`),
    windows of ``step`` scored samples."""
    sq, n = x["dtau_sq_by_region"].sum(axis=0), x["dtau_n_by_region"].sum(axis=0)
    fsq, fw = x["dtau_sq_full_by_alarm"].sum(axis=0), x["full_windows_by_alarm"].sum(axis=0)
    fn = fw * step  # the scored samples of those windows
    by_alarm = {
        name: {
            key: {
                "windows": int(fw[m, j]),
                "ratio": float(fsq[m, j] / fn[m, j] / q_tau) if fn[m, j] else None,
            }
            for j, key in enumerate(("without_alarm", "with_alarm"))
        }
        for m, name in enumerate(W.METHODS)
        if W.METHODS[name].tests_on("drive_train")
    }
    return {
        "filter_variance": q_tau,
        "mean_square_by_region": {
            r: float(a / b) if b else None for r, a, b in zip(REGIONS, sq, n)
        },
        "ratio_by_region": {
            r: float(a / b / q_tau) if b else None for r, a, b in zip(REGIONS, sq, n)
        },
        "samples_by_region": dict(zip(REGIONS, map(int, n))),
        "full_load_windows_by_drive_train_alarm": by_alarm,
    }


@register(
    "windturbine-false-alarms",
    paper=PAPER,
    default_trials=FALSE_ALARM_STREAMS,
    book_trials=BOOK_STREAMS,
    min_trials=1,  # exact Poisson intervals: one stream has one
    default_seed=2009,
    title="Wind-turbine benchmark: false alarms over hours of continuous fault-free operation",
    chapter="windturbine/benchmark",
    chapter_seed=True,
)
def false_alarms(*, seed: int, trials: int | None, jobs: int) -> ReproductionResult:
    """False alarms of the four methods over ``trials`` continuous fault-free runs of the
    benchmark's whole scenario (:data:`~fdi_lib.systems.wind_turbine.SCENARIO_S` = 4400 s each,
    seeded wind and noise; 9 runs: 10.95 scored hours), each run as one stream scored in overlapping windows in
    constant memory (:func:`fdi_lib.windturbine.stream_counts`, :data:`STREAM_WINDOW_S`,
    :data:`STREAM_OVERLAP_S`): the statistical tests re-arm when their statistic falls below its
    threshold, the SVO bank at every window.

    The book runs :data:`BOOK_STREAMS`: the default's :data:`FALSE_ALARM_STREAMS` would take the
    chapter about 1 min of a core (:data:`SECONDS_PER_STREAM`; each method's samples per second
    and its memory, flat in the stream's length, in ``benchmarks/bench_windturbine_stream.py``).

    Headline keys
    -------------
    streams : int
        ``trials``.
    hours : float
        Scored hours over all streams (the first window's overlap of each stream is its warm-up).
    windows_by_region : dict
        The scored windows (:data:`STREAM_WINDOW_S` each) whose samples switch between the
        controller's operating regions (``switch``), stay in full load (``full_load``) or in
        partial load (``partial_load``).
    methods : dict
        Method key -> ``alarms`` (count over all streams), ``tests`` (statistical tests it runs at
        once: one per subsystem; Basseville & Zhang two; the SVO bank one, at most one alarm per
        window), ``rate_per_hour`` and ``rate_per_hour_ci`` (the method's alarms per hour, exact
        Poisson 95 %), ``rate_per_test_hour`` and ``rate_per_test_hour_ci`` (per test),
        ``nominal_per_test_hour`` (the design's budget, :class:`~fdi_lib.windturbine.Settings`
        ``false_alarms_per_hour``),
        ``p_value_nominal`` (the probability of this many alarms or more if each test raised the
        nominal rate: exact Poisson), ``below_nominal`` (the interval's upper end under the
        budget), ``alarms_by_region`` and ``rate_per_test_hour_by_region`` (the alarms in each
        kind of window of ``windows_by_region`` and their rate per test over those windows' hours;
        ``None`` without such windows), ``alarms_by_test`` (test name of
        :attr:`~fdi_lib.windturbine.Method.tests` -> its alarms).
    tau_a_increments : dict
        The drive train's Kalman filter's model of the aerodynamic torque against the streams'
        torque: ``filter_variance`` (its random walk's variance per sample, MN² m²,
        :class:`~fdi_lib.windturbine.Calibration` ``q_tau``), ``mean_square_by_region`` and
        ``ratio_by_region`` (the true torque's mean square increment per sample in partial and full
        load, and over ``filter_variance``), ``samples_by_region``, and
        ``full_load_windows_by_drive_train_alarm``: per method with a drive-train test, the
        full-load windows ``without_alarm`` and ``with_alarm`` of it, each with its ``windows`` and
        ``ratio`` (the same ratio over their scored samples; ``None`` without such windows).
    """
    settings = W.Settings()
    trials = check_trials(
        FALSE_ALARM_STREAMS if trials is None else trials,
        jobs,
        seconds_per_realisation=SECONDS_PER_STREAM,
        bytes_per_realisation=8.0 * (2 * len(W.METHODS) + 1),
    )
    x = run_monte_carlo(
        functools.partial(stream_chunk, seed=seed),
        trials,
        seed=seed,
        jobs=jobs,
        chunk_size=1,
        description="wind-turbine false alarms",
    )
    nominal = settings.false_alarms_per_hour
    from fdi_lib.systems import wind_turbine as wt

    settings_out = {
        "seed": seed,
        "trials": trials,
        "scenario_s": wt.SCENARIO_S,
        "window_s": STREAM_WINDOW_S,
        "overlap_s": STREAM_OVERLAP_S,
        "false_alarms_per_hour": nominal,
        "calibration_runs": CALIBRATION_RUNS,
    }
    return ReproductionResult(
        id="windturbine-false-alarms",
        headline=_headline(x, seed, nominal),
        paper={},
        settings=settings_out,
        data={"raw": x},
    )
