"""The wind-turbine FDI benchmark (Odgaard, Stoustrup & Kinnaert 2009; 2013): the four methods' scoreboard.

:func:`scoreboard` runs the four methods of :mod:`fdi_lib.windturbine` on seeded realisations of
the segment around each fault of the benchmark scenario (:data:`fdi_lib.systems.wind_turbine.FAULTS`)
with the Monte Carlo engine (:func:`fdi_lib.montecarlo.run_monte_carlo`: results independent of
``jobs``), and scores detection time, isolation and false alarms against the benchmark's required
detection times, and sets next to them the per-fault detection delays published for another method
on this benchmark (:data:`PUBLISHED_DELAYS`). The other published results we looked for could not be
reached from this machine (:data:`PUBLISHED`): the ledger lists them as not reproducible, with the reason.

.. rubric:: A fault's entry in the scoreboard

The headline's ``faults`` of :func:`scoreboard` maps each ``F<id>`` to a dictionary with the keys
``name``, ``required_detection_s`` (the benchmark's, ``None`` where not stated),
``effect_sigma_median`` (median over realisations of the fault's largest effect on a measurement, in
noise standard deviations), ``effect_sigma_at_requirement_median`` (the same over the fault's first
samples up to its required detection time only: what any detector can have seen by then; ``None``
without a requirement) and ``methods`` -> method key (``zb2014``, ``zhang2021``, ``bz``,
``rosa2013``) -> ``detected`` (count), ``detection_rate`` and its ``detection_rate_ci`` (95 %, exact
binomial), ``detection_time_mean_s`` over the detected realisations (one sample = 0.01 s: detected
at the fault's first sample), its ``detection_time_ci`` (95 % t-interval of the mean) and
``detection_time_spread95`` (2.5-97.5 percentiles over realisations), ``within_requirement``
(fraction of realisations detected within the requirement), ``isolation_correct`` (fraction
isolating exactly the faulty components), ``isolation_contains`` (fraction whose isolated set
contains them), ``isolated_mode`` (the most frequent isolated set), ``reason`` (for a miss:
``peak_over_threshold``, the largest statistic over its threshold after the onset in the missed
realisations; ``effect_sigma_max``, the fault's largest effect on a measurement in noise standard
deviations; ``svo_noise_bound_sigma``; ``torque_effect_kNm`` for the drive-train fault, the
generator-side torque its efficiency drop removes), ``None`` when every realisation detects;
``isolation_reason`` (when some detected realisations are not isolated exactly: ``failed``, their
count; ``nameable``, whether the method's isolation can name the faulty set at all,
:attr:`fdi_lib.windturbine.Method.nameable`; ``separability_min``, the smallest
:func:`fdi_lib.windturbine.separability` of the faulty candidates;
``effect_variation_sigma_median``, the median over realisations of the standard deviation of the
fault's effect on a measurement over the samples the isolation reads, in noise standard deviations,
the largest over the measurements: 0 for a step), ``None`` otherwise. Per fault also
``full_load_share`` (the share of its scored samples in full load, mean over realisations),
``region`` (2 if at least one half, else 1), ``benchmark_region`` (the benchmark's,
:data:`fdi_lib.systems.wind_turbine.BENCHMARK_REGIONS`) and ``region_matches``.
"""

from __future__ import annotations

import collections
import functools
from typing import Any

import numpy as np
import scipy.stats

from fdi_lib.errors import ModelError, ResourceError
from fdi_lib.montecarlo import binomial_ci, run_monte_carlo
from fdi_lib.reproduce.ledger_claims import BY_TOLERANCE, NOT_CHECKABLE, Claim
from fdi_lib.reproduce.registry import ReproductionResult, register
from fdi_lib.sets.svo import ROUNDOFF_MARGIN
from fdi_lib.threads import single_threaded_blas
from fdi_lib import windturbine as W

__all__ = [
    "scoreboard",
    "chunk",
    "score_method",
    "check_trials",
    "SECONDS_PER_REALISATION",
    "MAX_RUN_S",
    "calibrated_design",
    "CALIBRATION_RUNS",
    "PUBLISHED",
    "PUBLISHED_DELAYS",
]

PAPER = "Odgaard, Stoustrup & Kinnaert benchmark"
#: Fault-free realisations (one per fault segment) of the calibration run (:func:`fdi_lib.windturbine.calibrate`).
CALIBRATION_RUNS = 4
#: Published results we looked for and could not reach (the ledger's rows say so).
PUBLISHED = {
    "competition_2012": "detection times of the entries of the benchmark's FDI competition "
    "(Odgaard & Stoustrup, results of a wind turbine FDI competition, Safeprocess 2012)",
    "casau_2015": "detection and isolation times of the set-valued FDI of Casau, Rosa, Tabatabaeipour, "
    "Silvestre & Stoustrup (IEEE TCST 2015) on this benchmark",
}
#: Detection delays (s) published for another method on this benchmark, per source and fault.
#: ``cohal_mirea_2017``: Cohal & Mirea (2017), Table 1, the mean over "several tests" of the
#: benchmark's Simulink model (its measured wind) of the delay from the fault's start to the alarm;
#: ``first`` when one of their two window tests fires (the "uncertain" state, faults 1, 3, 4 only),
#: ``certain`` when both do (faults 1, 3, 4: a 5-sample mean test and a 512-sample spectrum test) or
#: when the fault's single test does (fault 5: autocorrelations over 100 samples; fault 8: a
#: converter observer with a low-pass filter). Faults 2, 6, 7 and 9 are not treated there.
#: Read from the paper's PDF in the repository named in :data:`fdi_lib.systems.wind_turbine`'s sources
#: (``documentation/PaperCEAI2017-FaultDetectionAndIsolationOfAWindTurbine.pdf``).
PUBLISHED_DELAYS = {
    "cohal_mirea_2017": {
        "first": {"F1": 0.21, "F3": 0.21, "F4": 0.21},
        "certain": {"F1": 3.21, "F3": 3.53, "F4": 2.73, "F5": 1.1, "F8": 3.56},
    },
}


def calibrated_design(
    seed: int, settings: W.Settings = W.Settings(), schedule: str = "benchmark"
) -> W.Design:
    """The methods' design (:func:`fdi_lib.windturbine.design`) calibrated on :data:`CALIBRATION_RUNS`
    fault-free realisations of every fault's segment under the wind ``schedule``
    (:data:`~fdi_lib.systems.wind_turbine.WIND_SCHEDULES`), seeded by ``SeedSequence([seed, 1])``
    (never the scored realisations). Cached per process, whether ``settings`` is passed or
    defaulted."""
    return _calibrated_design(int(seed), settings, schedule)


@functools.lru_cache(maxsize=4)
@single_threaded_blas
def _calibration(
    seed: int, settings: W.Settings, schedule: str
) -> tuple[W.PlantConstants, W.Calibration, np.ndarray]:
    """The plant's constants, the calibration and the filters' prior mean of
    :func:`calibrated_design`."""
    from fdi_lib.systems import wind_turbine as wt

    c = W.plant_constants()
    seeds = np.random.SeedSequence([seed, 1]).spawn(CALIBRATION_RUNS)
    recs = [
        W.fault_records(f, seeds, settings=settings, faulty=False, schedule=schedule)
        for f in wt.FAULTS
    ]
    rec = W.Records(
        recs[0].t,
        *(np.concatenate([getattr(r, k) for r in recs]) for k in ("y", "u", "x", "tau_a", "v")),
    )
    return c, W.calibrate(c, rec), rec.x.reshape(-1, rec.x.shape[-1]).mean(axis=0)


@functools.lru_cache(maxsize=4)
@single_threaded_blas
def _calibrated_design(seed: int, settings: W.Settings, schedule: str) -> W.Design:
    return W.design(*_calibration(seed, settings, schedule), settings)


def _empty_chunk(n: int) -> dict[str, np.ndarray]:
    """The arrays of :func:`chunk` for ``n`` realisations, before they are filled."""
    from fdi_lib.systems import wind_turbine as wt

    F, M = len(wt.FAULTS), len(W.METHODS)
    return {
        "detect": np.full((n, F, M), -1),
        "false_alarm": np.zeros((n, F, M), dtype=bool),
        "isolated": np.zeros((n, F, M, len(W.CANDIDATES)), dtype=bool),
        "isolate_step": np.full((n, F, M), -1),
        "peak": np.full((n, F, M), np.nan),
        "effect_sigma": np.zeros((n, F)),
        "effect_sigma_req": np.full((n, F), np.nan),
        "bound_violation": np.zeros((n, F), dtype=bool),
        "torque_effect_kNm": np.full((n, F), np.nan),
        "effect_variation_sigma": np.zeros((n, F)),
        "full_load_share": np.zeros((n, F)),
    }


#: Seconds of one core that one realisation of the scoreboard (every fault's segment and its
#: fault-free twin, the four methods) takes with the default :class:`~fdi_lib.windturbine.Settings`:
#: the process time of 6 realisations less that of 2, over 4 (1.09 s on the book's 2-core machine,
#: the design cached, before the compiled SVO steps; 0.63 of that after them, both measured in one
#: run): the estimate with which a too large ``trials`` is refused.
SECONDS_PER_REALISATION = 0.7
#: The longest scoreboard run accepted (s, estimated with :data:`SECONDS_PER_REALISATION` over the
#: jobs).
MAX_RUN_S = 24 * 3600.0


def check_trials(
    trials: int,
    jobs: int = 1,
    *,
    seconds_per_realisation: float = SECONDS_PER_REALISATION,
    bytes_per_realisation: float | None = None,
) -> int:
    """``trials`` of the scoreboard, refused with a :class:`~fdi_lib.errors.ResourceError` that
    gives the estimated time and memory when the run would take longer than :data:`MAX_RUN_S` on
    ``jobs`` processes (capped at the cores) or its results would not fit in the available memory;
    nothing is simulated before the check. Another study passes its own cost per realisation (core
    seconds, bytes of results; default: the scoreboard's)."""
    import warnings

    from fdi_lib.errors import JobsCappedWarning
    from fdi_lib.montecarlo import _bytes_text, check_memory, effective_jobs
    from fdi_lib.validation import integer

    trials = integer(trials, "trials", low=1)
    with warnings.catch_warnings():  # the run itself warns about a capped request
        warnings.simplefilter("ignore", JobsCappedWarning)
        workers = effective_jobs(jobs)
    per = (
        sum(a.nbytes for a in _empty_chunk(1).values())
        if bytes_per_realisation is None
        else bytes_per_realisation
    )
    memory = 2.0 * per * trials  # the chunks' arrays and their concatenation
    seconds = trials * seconds_per_realisation / workers
    what = (
        f"{trials} realisations (about {seconds_per_realisation:g} s of a core and "
        f"{_bytes_text(per)} of results each)"
    )
    check_memory(memory, "trials", what)
    if seconds > MAX_RUN_S:
        raise ResourceError(
            f"trials: {what} would take about {seconds / 3600:.3g} h on {workers} "
            f"process{'es' * (workers > 1)} and need about {_bytes_text(memory)} "
            f"of memory; "
            f"the limit is {MAX_RUN_S / 3600:g} h (MAX_RUN_S): use fewer"
        )
    return trials


def chunk(
    seeds: list, *, seed: int, settings: W.Settings = W.Settings(), schedule: str = "benchmark"
) -> dict[str, np.ndarray]:
    """Monte Carlo chunk: every fault's segment for each seed under the wind ``schedule``, the
    methods of :data:`fdi_lib.windturbine.METHODS`, and what explains a miss (the fault's largest
    effect on the measurements in noise standard deviations, from a fault-free twin with the same
    wind and noise; whether the fault-free stretch broke the SVO's bounds), a failed isolation (how
    much the fault's effect varies over the samples the isolation reads: a step it is not) and
    where the fault happens (the share of its scored samples in full load)."""
    from fdi_lib.systems import wind_turbine as wt

    d = calibrated_design(seed, settings, schedule)
    n_iso = min(settings.window + settings.isolation_extra, d.N - d.onset)
    n, F = len(seeds), len(wt.FAULTS)
    out = _empty_chunk(n)
    ys, us = [], []
    for f, fault in enumerate(wt.FAULTS):
        rec, twin = W.fault_record_pair(fault, seeds, settings=settings, schedule=schedule)
        ys.append(rec.y)
        us.append(rec.u)
        dy = np.abs(rec.y[:, d.onset :] - twin.y[:, d.onset :]) / d.constants.sigma
        change = (rec.y - twin.y)[:, d.onset : d.onset + n_iso] / d.constants.sigma
        out["effect_variation_sigma"][:, f] = change.std(axis=1).max(axis=-1)
        out["full_load_share"][:, f] = (rec.region[:, d.onset :] == 2).mean(axis=1)
        out["effect_sigma"][:, f] = dy.max(axis=(1, 2))
        if (
            fault.required_detection_s is not None
        ):  # what a detector can have seen by the requirement
            n_req = int(round(fault.required_detection_s / d.constants.Ts))
            out["effect_sigma_req"][:, f] = dy[:, :n_req].max(axis=(1, 2))
        out["bound_violation"][:, f] = _bound_violation(d, twin)
        if (
            fault.kind == "drive_train"
        ):  # the generator-side torque the efficiency drop removes (kNm)
            p = d.constants.params
            shaft = p.K_dt * rec.x[:, d.onset :, 8] * 1e-3 / p.N_g / 1e3
            out["torque_effect_kNm"][:, f] = (p.eta_dt - fault.magnitude[0]) * shaft.mean(axis=1)
    res = W.run_methods(d, np.concatenate(ys), np.concatenate(us))
    for m, name in enumerate(W.METHODS):
        o = res[name]
        for key in ("detect", "false_alarm", "isolate_step", "peak"):
            out[key][:, :, m] = getattr(o, key).reshape(F, n).T
        out["isolated"][:, :, m] = np.swapaxes(o.isolated.reshape(F, n, -1), 0, 1)
    return out


def _bound_violation(d: W.Design, rec: W.Records) -> np.ndarray:
    """Whether a fault-free record breaks an assumption of the SVO's nominal sets before the
    onset, where an empty set is a false alarm: exactly what those sets integrate
    (:func:`fdi_lib.windturbine.run_svo_bank`, from the end of the warm-up ``d.warmup``). The true
    state at ``d.warmup`` (with ``tau_a`` for the drive train) outside its prior set
    (:func:`fdi_lib.windturbine.svo_priors`); then, from ``d.warmup`` to the onset, a sensor noise
    sample beyond ``svo_sigmas`` standard deviations, a one-step model error of a state
    ``x_{k+1} - F x_k - G u_k - E tau_a,k`` beyond its calibrated bound
    (:class:`~fdi_lib.windturbine.Calibration` ``bound``) by more than the round-off guard the
    sets add at every step (:data:`fdi_lib.sets.svo.ROUNDOFF_MARGIN` times ``1 + |x_{k+1}|``:
    the model is the simulator's exact discretisation, so these bounds and errors are rounding,
    some 1e-15) or an increment of ``tau_a`` beyond ``dtau_bound``. Samples before ``d.warmup``
    are not integrated (the sets start there)."""
    sl = slice(d.warmup, d.onset)
    clean = rec.x[:, sl][..., [0, 0, 2, 2, 4, 4, 6, 6, 7, 7, 9]]
    noise = np.abs(rec.y[:, sl] - clean) / d.constants.sigma
    tau = rec.tau_a[:, sl]
    out = (noise.max(axis=(1, 2)) > d.settings.svo_sigmas) | (
        np.abs(np.diff(tau, axis=1)).max(axis=1) > d.calibration.dtau_bound
    )
    for name, X0 in W.svo_priors(d).items():
        s = d.subs[name].sub
        x = rec.x[:, sl][..., list(s.states)]
        pred = x[:, :-1] @ s.F.T + rec.u[:, sl][:, :-1][..., list(s.inputs)] @ s.G.T
        start = x[:, 0]
        if s.E is not None:
            pred = pred + tau[:, :-1, None] * s.E[:, 0]
            start = np.column_stack([start, tau[:, 0]])
        tol = d.calibration.bound[name] + ROUNDOFF_MARGIN * (1.0 + np.abs(x[:, 1:]))
        out |= (np.abs(x[:, 1:] - pred) > tol).any(axis=(1, 2))
        out |= (start @ X0.M.T > X0.m).any(axis=1)
    return out


def _method_entry(
    x: dict[str, np.ndarray], d: W.Design, f: int, m: int, sep: dict[str, float], trials: int
) -> dict[str, Any]:
    """The scoreboard's entry of method ``m`` on fault ``f`` (:func:`score_method`), with what
    explains its misses (``reason``) and its failed isolations (``isolation_reason``)."""
    from fdi_lib.systems import wind_turbine as wt

    fault, name = wt.FAULTS[f], list(W.METHODS)[m]
    exp = set(W.expected_candidates(fault))
    entry = score_method(
        x["detect"][:, f, m],
        x["isolated"][:, f, m],
        x["isolate_step"][:, f, m],
        exp,
        fault.required_detection_s,
        d.onset,
        d.constants.Ts,
    )
    k = entry["detected"]
    hit = x["detect"][:, f, m] >= 0
    if k < trials:  # a miss: measured, never assumed
        peak = x["peak"][~hit, f, m]
        entry["reason"] = {
            "peak_over_threshold": float(np.nanmax(peak)) if np.isfinite(peak).any() else None,
            "effect_sigma_max": float(x["effect_sigma"][~hit, f].max()),
            "svo_noise_bound_sigma": d.settings.svo_sigmas if W.METHODS[name].bounded else None,
            "torque_effect_kNm": (
                float(np.nanmax(x["torque_effect_kNm"][:, f]))
                if fault.kind == "drive_train"
                else None
            ),
        }
    failed = k - int(round(entry["isolation_correct"] * trials))
    if failed:  # detected and not isolated exactly: measured, never assumed
        entry["isolation_reason"] = {
            "failed": failed,
            "nameable": W.METHODS[name].nameable(frozenset(exp)),
            "separability_min": min(sep[c] for c in exp),
            "effect_variation_sigma_median": float(np.median(x["effect_variation_sigma"][:, f])),
        }
    return entry


def _false_alarm_summary(x: dict[str, np.ndarray], d: W.Design, trials: int) -> dict[str, Any]:
    """Per method, the false alarms over the scoreboard's fault-free stretches."""
    from fdi_lib.systems import wind_turbine as wt

    n_stretch = trials * len(wt.FAULTS)
    stretch_h = (d.onset - d.warmup) * d.constants.Ts / 3600.0
    hours = n_stretch * stretch_h
    fa: dict[str, Any] = {}
    for m, name in enumerate(W.METHODS):
        a = int(x["false_alarm"][:, :, m].sum())
        fa[name] = {
            "alarms": a,
            "stretches": n_stretch,
            "hours": hours,
            "rate_per_hour": a / hours,
            "rate_per_hour_ci": _poisson_ci(a, hours),
        }
    return fa


def _summary(x: dict[str, np.ndarray], d: W.Design, trials: int) -> dict[str, Any]:
    from fdi_lib.systems import wind_turbine as wt

    faults: dict[str, Any] = {}
    met: dict[str, list[int]] = {m: [] for m in W.METHODS}
    best: dict[str, Any] = {}
    fastest: dict[str, Any] = {}
    sep = W.separability(d)
    for f, fault in enumerate(wt.FAULTS):
        req = fault.required_detection_s
        per = {name: _method_entry(x, d, f, m, sep, trials) for m, name in enumerate(W.METHODS)}
        full = {name: e for name, e in per.items() if e["detected"] == trials}
        for name, e in full.items():
            if req is not None and e["within_requirement"] == 1.0:
                met[name].append(fault.id)
        # the smallest 97.5th percentile; the smallest mean (a tie: the first method)
        best[f"F{fault.id}"] = min(
            (e["detection_time_spread95"][1] for e in full.values()), default=None
        )
        first = min(full, key=lambda n: full[n]["detection_time_mean_s"], default=None)
        fastest[f"F{fault.id}"] = (
            None
            if first is None
            else {"method": first, "detection_time_mean_s": full[first]["detection_time_mean_s"]}
        )
        faults[f"F{fault.id}"] = {
            "name": fault.name,
            "required_detection_s": req,
            "methods": per,
            "effect_sigma_median": float(np.median(x["effect_sigma"][:, f])),
            "effect_sigma_at_requirement_median": (
                float(np.median(x["effect_sigma_req"][:, f])) if req is not None else None
            ),
            **_region(x["full_load_share"][:, f], fault.id),
        }
    bounded = [m for m, method in enumerate(W.METHODS.values()) if method.bounded]
    svo_fa = x["false_alarm"][:, :, bounded].any(axis=-1)
    viol = x["bound_violation"]
    return {
        "faults": faults,
        "false_alarms": _false_alarm_summary(x, d, trials),
        "requirement_met": met,
        "best_detection_upper_s": best,
        "fastest_method": fastest,
        "bound_violations": int(viol.sum()),
        "svo_false_alarms_with_violation": int((svo_fa & viol).sum()),
        "svo_false_alarms_without_violation": int((svo_fa & ~viol).sum()),
    }


def _region(share: np.ndarray, fault_id: int) -> dict[str, Any]:
    """Where a fault's scored samples happen: ``full_load_share`` (mean over realisations), its
    ``region`` (2 if at least one half, else 1), the benchmark's (``benchmark_region``,
    :data:`fdi_lib.systems.wind_turbine.BENCHMARK_REGIONS`; ``None``: not stated) and whether they
    agree (``region_matches``; ``None`` without a benchmark region)."""
    from fdi_lib.systems import wind_turbine as wt

    mean = float(share.mean())
    region = 2 if mean >= 0.5 else 1
    ref = (wt.BENCHMARK_REGIONS.get(fault_id) or {}).get("region")
    return {
        "full_load_share": mean,
        "region": region,
        "benchmark_region": ref,
        "region_matches": None if ref is None else region == ref,
    }


def score_method(
    detect: np.ndarray,
    isolated: np.ndarray,
    isolate_step: np.ndarray,
    expected: set[str],
    required_s: float | None,
    onset: int,
    ts: float,
) -> dict[str, Any]:
    """One method's score on one fault over ``R`` realisations.

    ``detect`` ``(R,)``: the detection sample (first alarm at or after ``onset``, ``-1``: none,
    :func:`fdi_lib.windturbine.score_alarms`); ``isolated`` ``(R, len(CANDIDATES))`` bool: the
    candidates named; ``isolate_step`` ``(R,)``: the sample of that decision; ``expected``: the
    faulty candidates; ``required_s``: the benchmark's required detection time (``None``: not
    stated). Times are :func:`fdi_lib.windturbine.delays` from the fault's start; the isolation time
    is that of the realisations isolating exactly ``expected``.
    """
    detect = np.asarray(detect)
    trials = detect.shape[0]
    hit = detect >= 0
    k = int(hit.sum())
    t = W.delays(detect[hit], onset, ts)
    sets = [frozenset(W.CANDIDATES[j] for j in np.flatnonzero(row)) for row in np.asarray(isolated)]
    correct = np.array([hit[i] and s == expected for i, s in enumerate(sets)], dtype=bool)
    contains = [hit[i] and expected <= s for i, s in enumerate(sets)]
    wrong = int(sum(hit[i] and bool(s) and s != expected for i, s in enumerate(sets)))
    t_iso = W.delays(np.asarray(isolate_step)[correct], onset, ts)
    labels = [", ".join(sorted(s)) or "none" for i, s in enumerate(sets) if hit[i]]
    # the most frequent set; a tie goes to the one seen first (in realisation order), never to
    # the iteration order of a set of strings, which changes with the process's hash seed
    mode = collections.Counter(labels).most_common(1)[0][0] if labels else None
    within = (
        int(np.sum(hit & (W.delays(detect, onset, ts) <= required_s + 1e-12)))
        if required_s is not None
        else None
    )
    n_iso = int(correct.sum())
    return {
        "detected": k,
        "detection_rate": k / trials,
        "detection_rate_ci": list(binomial_ci(k, trials)),
        "missed": trials - k,
        "detection_time_mean_s": float(t.mean()) if k else None,
        "detection_time_ci": _mean_ci(t),
        "detection_time_spread95": _spread(t),
        "within_requirement": within / trials if within is not None else None,
        "within_requirement_ci": list(binomial_ci(within, trials)) if within is not None else None,
        "isolation_correct": float(np.mean(correct)),
        "isolation_correct_ci": list(binomial_ci(n_iso, trials)),
        "isolation_contains": float(np.mean(contains)),
        "wrong_isolations": wrong,
        "not_isolated": int(sum(hit[i] and not s for i, s in enumerate(sets))),
        "isolation_time_mean_s": float(t_iso.mean()) if n_iso else None,
        "isolation_time_ci": _mean_ci(t_iso),
        "isolation_time_spread95": _spread(t_iso),
        "isolated_mode": mode,
        "reason": None,
        "isolation_reason": None,
    }


def _spread(t: np.ndarray) -> list[float] | None:
    """2.5 and 97.5 percentiles of ``t`` (``None`` if empty)."""
    return [float(np.percentile(t, 2.5)), float(np.percentile(t, 97.5))] if t.size else None


def _mean_ci(t: np.ndarray) -> list[float] | None:
    if t.size < 2:
        return None
    h = scipy.stats.t.ppf(0.975, t.size - 1) * t.std(ddof=1) / np.sqrt(t.size)
    return [float(t.mean() - h), float(t.mean() + h)]


def _paper() -> dict[str, Any]:
    from fdi_lib.systems import wind_turbine as wt

    return {
        "required_detection_s": {
            f"F{f.id}": (
                f"<= {f.required_detection_s:g}"
                if f.required_detection_s is not None
                else "not stated"
            )
            for f in wt.FAULTS
        },
        "published": dict(PUBLISHED),
        "published_detection_s": {
            src: {k: dict(v) for k, v in d.items()} for src, d in PUBLISHED_DELAYS.items()
        },
    }


def _scoreboard_settings(seed: int, trials: int, settings: W.Settings, schedule: str) -> dict:
    """The settings of :func:`scoreboard`'s result."""
    from fdi_lib.systems import wind_turbine as wt

    return {
        "seed": seed,
        "trials": trials,
        "pre_s": settings.pre_s,
        "post_s": settings.post_s,
        "warmup_s": settings.warmup_s,
        "window": settings.window,
        "false_alarms_per_hour": settings.false_alarms_per_hour,
        "svo_sigmas": settings.svo_sigmas,
        "calibration_runs": CALIBRATION_RUNS,
        "faults": [f.id for f in wt.FAULTS],
        "schedule": schedule,
    }


@register(
    "windturbine-scoreboard",
    plot="fdi_lib.reproduce.views.windturbine.plot_scoreboard",
    paper=PAPER,
    default_trials=100,
    default_seed=2009,
    title="Wind-turbine FDI benchmark: four methods, nine faults (scoreboard)",
    chapter="windturbine/benchmark",
    chapter_seed=True,
    claims={
        "required_detection_s/*": Claim(
            location="benchmark requirements (Odgaard et al. 2013), fault {0}",
            label="required detection time (ours: the fastest method's 97.5th percentile)",
            units="s",
            test=BY_TOLERANCE,
            ours=lambda h, p: h["best_detection_upper_s"].get(p[-1]),
            explain="sec-wt-scoreboard",
            missing="no method detects it in every realisation within the 10 s after its start",
            cause="sec-wt-reasons",
            cause_glue=("wt-{0}-*",),
            cause_text="each miss and each late detection is measured against the fault's "
            "effect on the measurements and the smallest step each detector sees",
        ),
        "published/*": Claim(
            location="published results on this benchmark: {0}",
            units="",
            test=NOT_CHECKABLE,
            ours=lambda h, p: None,
            reason="their tables are not reachable from this machine (at most an abstract in "
            "the search corpora); no number is guessed",
        ),
        "published_detection_s/cohal_mirea_2017/*/*": Claim(
            location="Cohal & Mirea 2017, Table 1, delay to the {1} alarm on fault {2}",
            units="s",
            label="ours: the fastest method detecting in every realisation, its mean",
            test=NOT_CHECKABLE,
            ours=lambda h, p: (h["fastest_method"][p[-1]] or {}).get("detection_time_mean_s"),
            explain="sec-wt-published",
            missing="no method detects it in every realisation",
            reason="another method's result (window statistics, on the benchmark's measured "
            "wind, which is not public): not ours to reproduce; our four methods' "
            "delays on the substitute wind are set beside it",
        ),
    },
)
def scoreboard(
    *, seed: int, trials: int | None, jobs: int, schedule: str = "benchmark"
) -> ReproductionResult:
    """The scoreboard: every fault of the benchmark scenario x the methods of
    :data:`fdi_lib.windturbine.METHODS`.

    ``trials`` seeded realisations (wind turbulence and sensor noise) of each fault's segment
    (7 s before its start, 10 s after; the first 3 s are the filters' warm-up), the methods as
    designed in :mod:`fdi_lib.windturbine`, the wind's mean profile the named ``schedule``
    (:data:`~fdi_lib.systems.wind_turbine.WIND_SCHEDULES`: ``"benchmark"``, the faults in the
    benchmark's operating regions; ``"designed"``, in other conditions; ``--option
    schedule=designed``), which the calibration follows too.

    Headline keys
    -------------
    realisations : int
        ``trials``.
    faults : dict
        ``F<id>`` -> the fault's entry (keys: *A fault's entry in the scoreboard*, above).
    false_alarms : dict
        method -> ``alarms`` over the fault-free stretches (4 s before each fault, after the
        warm-up), ``stretches``, ``hours``, ``rate_per_hour`` and ``rate_per_hour_ci`` (exact Poisson).
    requirement_met : dict
        method -> the fault ids detected in every realisation within the benchmark's requirement.
    best_detection_upper_s : dict
        ``F<id>`` -> the smallest, over the methods detecting in every realisation, 97.5th
        percentile of the detection time (``None``: no method detects in every realisation).
    fastest_method : dict
        ``F<id>`` -> ``method`` (key) and its ``detection_time_mean_s``: among the methods detecting
        in every realisation, the one with the smallest mean detection time (``None``: no method
        detects in every realisation). Compared in the ledger with :data:`PUBLISHED_DELAYS`.
    min_detectable : dict
        ``zb2014`` / ``zhang2021`` -> candidate -> the smallest step (deg, rad/s or kNm) the GLR / the
        Lasso test sees within the window (:func:`fdi_lib.windturbine.min_detectable`).
    separability : dict
        Candidate -> the sine of the angle between its signature and those of the other candidates
        of its subsystem (:func:`fdi_lib.windturbine.separability`; 0: no test can tell it from a
        combination of them).
    bound_violations, svo_false_alarms_with_violation, svo_false_alarms_without_violation : int
        Fault-free stretches that break an assumption of the SVO's sets (``_bound_violation``:
        prior set, noise, model error, ``tau_a``'s increments), and the SVO's false alarms with
        and without such a violation.

    Paper keys
    ----------
    required_detection_s : dict
        ``F<id>`` -> the benchmark's requirement as ``"<= seconds"`` (``"not stated"`` for F9).
    published : dict
        Published results looked for and not reachable here (:data:`PUBLISHED`), as text.
    published_detection_s : dict
        Source -> ``first`` / ``certain`` -> ``F<id>`` -> another method's published detection
        delay in seconds (:data:`PUBLISHED_DELAYS`).
    """
    from fdi_lib.systems.wind_turbine import WIND_SCHEDULES

    if schedule not in WIND_SCHEDULES:
        raise ModelError(f"schedule: expected one of {tuple(WIND_SCHEDULES)}, got {schedule!r}")
    settings = W.Settings()
    trials = check_trials(trials, jobs)
    d = calibrated_design(seed, settings, schedule)
    x = run_monte_carlo(
        functools.partial(chunk, seed=seed, settings=settings, schedule=schedule),
        trials,
        seed=seed,
        jobs=jobs,
        description="wind-turbine scoreboard",
    )
    headline = {
        "realisations": trials,
        **_summary(x, d, trials),
        "min_detectable": W.min_detectable(d),
        "separability": W.separability(d),
    }
    return ReproductionResult(
        id="windturbine-scoreboard",
        headline=headline,
        paper=_paper(),
        settings=_scoreboard_settings(seed, trials, settings, schedule),
        data={"raw": x, "onset": d.onset, "Ts": d.constants.Ts},
    )


def _poisson_ci(alarms: int, exposure: float) -> list[float]:
    """Exact (Garwood) 95 % interval of a Poisson rate: ``alarms`` events over ``exposure``."""
    lo = scipy.stats.chi2.ppf(0.025, 2 * alarms) / 2 if alarms else 0.0
    hi = scipy.stats.chi2.ppf(0.975, 2 * alarms + 2) / 2
    return [float(lo / exposure), float(hi / exposure)]
