"""The wind-turbine benchmark's second half: accommodating the sensor faults once isolated.

The benchmark (Odgaard, Stoustrup & Kinnaert 2009; 2013) is a fault-tolerant control benchmark:
after detection and isolation, the controller should keep the turbine producing as if nothing had
failed. For a fault on a duplicated sensor the natural accommodation is to stop reading the faulty
sensor and to read its healthy redundant twin (:func:`fdi_lib.systems.wind_turbine.simulate`,
argument ``accommodation``). :func:`accommodation` measures, per sensor fault F1-F5 and
realisation, the effect of the fault on the generator power, the pitch and the generator speed
against a fault-free twin (same wind, same noise), without and with the switch made at the time one
of the book's methods isolates the fault (:data:`fdi_lib.windturbine.METHODS`, on the same
record).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from fdi_lib import windturbine as W
from fdi_lib.errors import ModelError
from fdi_lib.montecarlo import run_monte_carlo
from fdi_lib.reproduce.registry import ReproductionResult, register
from fdi_lib.reproduce.windturbine import PAPER, calibrated_design, check_trials

__all__ = ["ACCOMMODATED", "METRICS", "accommodation", "accommodation_chunk"]

#: The sensor faults accommodated by switching to the redundant sensor.
ACCOMMODATED = (1, 2, 3, 4, 5)
#: Seconds simulated after the fault's end (the plant's recovery is part of the effect).
AFTER_S = 20.0
#: Settling time dropped at the start of each run (as :func:`fdi_lib.windturbine.fault_records`).
SETTLE_S = 20.0
#: The effects measured of each run against its fault-free twin (RMS change; headline keys).
METRICS = ("power_kw", "pitch_deg", "speed_rad_s")
#: Realisations per chunk (:func:`accommodation_chunk`, a batch of records for the methods): the
#: book's count in one chunk. The methods' per-sample recursions and per-call set-up cost about
#: the same for 2 records as for 5, so the default chunks (2, 2, 1) took 1.4-1.9x the CPU, for a
#: peak of 86 MB instead of 50 (tracemalloc, the book's 5 realisations). The results do not depend
#: on it (each record is computed alone: the same bits).
CHUNK_REALISATIONS = 5


def _effects(run: Any, free: Any, sl: slice) -> np.ndarray:
    """``(R, 3)``: RMS over the samples ``sl`` of the generator power (kW), the true pitch (deg,
    largest over the blades) and the generator speed (rad/s) minus the fault-free twin's."""
    dp = (run.p_g[:, sl] - free.p_g[:, sl]) / 1e3
    db = run.beta[:, sl] - free.beta[:, sl]
    dw = run.omega_g[:, sl] - free.omega_g[:, sl]
    rms = lambda a, axis: np.sqrt(np.mean(a**2, axis=axis))  # noqa: E731
    return np.stack([rms(dp, 1), rms(db, 1).max(axis=-1), rms(dw, 1)], axis=-1)


def _switchable(isolated: np.ndarray, fault: Any) -> np.ndarray:
    """``(B,)``: the isolated set names every faulty sensor and none of their redundant twins (the
    controller can then read the twins; other candidates it names cannot be switched and are
    ignored).
    """
    faulty = [W.CANDIDATES.index(c) for c in W.expected_candidates(fault)]
    twins = [
        W.CANDIDATES.index(c[:-1] + ("2" if c.endswith("1") else "1"))
        for c in W.expected_candidates(fault)
    ]
    return isolated[:, faulty].all(axis=1) & ~isolated[:, twins].any(axis=1)


def accommodation_chunk(
    seeds: list, *, seed: int, method: str, settings: W.Settings = W.Settings()
) -> dict[str, np.ndarray]:
    """Monte Carlo chunk: for each fault of :data:`ACCOMMODATED` and each seed, the fault-free,
    faulty and accommodated runs of the fault's stretch, the isolation time and the effects."""
    from fdi_lib.systems import wind_turbine as wt

    d = calibrated_design(seed, settings)
    p = d.constants.params
    n, F = len(seeds), len(ACCOMMODATED)
    out = {
        "isolation_s": np.full((n, F), np.nan),
        "faulty": np.zeros((n, F, 3)),
        "accommodated": np.zeros((n, F, 3)),
        "energy_faulty_kwh": np.zeros((n, F)),
        "energy_accommodated_kwh": np.zeros((n, F)),
    }
    for j, fid in enumerate(ACCOMMODATED):
        fault = next(f for f in wt.FAULTS if f.id == fid)
        t0 = SETTLE_S + settings.pre_s
        duration = t0 + (fault.stop_s - fault.start_s) + AFTER_S
        t_abs = fault.start_s - t0 + np.arange(int(round(duration / p.ts))) * p.ts
        wind = np.stack([wt.wind_speed(t_abs, seed=wt._child(s, 0)) for s in seeds])
        moved = W._shifted(fault, t0)
        kw = dict(seed=list(seeds), duration_s=duration, params=p, wind=wind)
        faulty, free = wt.simulate_with_twin(faults=(moved,), **kw)  # the twin from the fault on
        i0 = int(round(SETTLE_S / p.ts))
        rec = W.records(faulty, i0, i0 + d.N)
        outcomes = (
            list(W.run_methods(d, rec.y, rec.u).values())
            if method == "first"
            else [W.METHODS[method].diagnose(d, W.MethodInputs(d, rec.y, rec.u))]
        )
        steps = [
            np.where((o.isolate_step >= 0) & _switchable(o.isolated, fault), o.isolate_step, np.inf)
            for o in outcomes
        ]
        first = np.min(steps, axis=0)  # the earliest switchable isolation
        t_iso = np.where(np.isfinite(first), (i0 + first) * p.ts, np.nan)
        out["isolation_s"][:, j] = t_iso - t0
        acc = wt.simulate(faults=(moved,), accommodation={fid: t_iso}, **kw)
        sl = slice(int(round(t0 / p.ts)), None)
        out["faulty"][:, j] = _effects(faulty, free, sl)
        out["accommodated"][:, j] = _effects(acc, free, sl)
        out["energy_faulty_kwh"][:, j] = (
            (faulty.p_g[:, sl] - free.p_g[:, sl]).sum(axis=1) * p.ts / 3.6e6
        )
        out["energy_accommodated_kwh"][:, j] = (
            (acc.p_g[:, sl] - free.p_g[:, sl]).sum(axis=1) * p.ts / 3.6e6
        )
    return out


def _fault_summaries(x: dict[str, np.ndarray]) -> dict[str, dict[str, Any]]:
    """The headline's ``faults``: per accommodated fault, the means of :func:`accommodation_chunk`'s
    results over the realisations (see :func:`accommodation`)."""
    from fdi_lib.systems import wind_turbine as wt

    faults = {}
    for j, fid in enumerate(ACCOMMODATED):
        fault = next(f for f in wt.FAULTS if f.id == fid)
        iso = x["isolation_s"][:, j]
        hit = ~np.isnan(iso)
        faults[f"F{fid}"] = {
            "name": fault.name,
            "isolated": int(hit.sum()),
            "isolation_time_mean_s": float(iso[hit].mean()) if hit.any() else None,
            "faulty": {
                **{m: float(x["faulty"][:, j, i].mean()) for i, m in enumerate(METRICS)},
                "energy_kwh": float(x["energy_faulty_kwh"][:, j].mean()),
            },
            "accommodated": {
                **{m: float(x["accommodated"][:, j, i].mean()) for i, m in enumerate(METRICS)},
                "energy_kwh": float(x["energy_accommodated_kwh"][:, j].mean()),
            },
        }
    return faults


#: Seconds of one core per realisation (the book's count: about 2 s of CPU with the four methods),
#: the estimate with which a too large ``trials`` is refused (the scoreboard's ``check_trials``).
SECONDS_PER_REALISATION = 2.0


@register(
    "windturbine-accommodation",
    plot="fdi_lib.reproduce.views.windturbine.plot_accommodation",
    paper=PAPER,
    default_trials=5,  # the book's count: SECONDS_PER_REALISATION
    default_seed=2009,
    title="Wind-turbine benchmark: sensor faults accommodated after isolation",
    chapter="windturbine/benchmark",
    chapter_seed=True,
)
def accommodation(
    *, seed: int, trials: int | None, jobs: int, method: str = "first"
) -> ReproductionResult:
    """Accommodation of the sensor faults F1-F5: switch to the redundant sensor once isolated.

    For each fault of :data:`ACCOMMODATED` and each of ``trials`` seeded realisations (wind and
    noise, the benchmark schedule), three runs of the fault's stretch (from 27 s before its start to
    :data:`AFTER_S` after its end; the first 20 s dropped): fault-free, faulty, and faulty with the
    controller switched to the healthy redundant sensor from the time ``method`` (a key of
    :data:`fdi_lib.windturbine.METHODS`, or ``"first"``: the earliest of them; ``--option
    method=...``) isolates the faulty sensors on the run's record (the scoreboard's 10 s segment): its isolated set names them
    and not their twins (other candidates it names cannot be switched and are ignored; otherwise no
    switch).

    Headline keys
    -------------
    realisations : int
        ``trials``.
    method : str
        The method whose isolation triggers the switch (``"first"``: the earliest of the four).
    faults : dict
        ``F<id>`` -> ``name``, ``isolated`` (realisations switched), ``isolation_time_mean_s`` (from
        the fault's start, over the switched realisations; ``None`` if none), ``faulty`` and
        ``accommodated`` -> ``power_kw``, ``pitch_deg``, ``speed_rad_s``: the mean over realisations
        of the RMS change from the fault's start to :data:`AFTER_S` after its end against the
        fault-free twin (power; true pitch, the largest over the blades; generator speed), and
        ``energy_kwh`` (mean energy change over that stretch, kWh; negative: lost).
    """
    if method not in (*W.METHODS, "first"):
        raise ModelError(f"method: expected 'first' or one of {tuple(W.METHODS)}, got {method!r}")
    n_acc = len(ACCOMMODATED)  # the chunk's results: isolation time, two energies, 2 x metrics
    trials = check_trials(
        trials,
        jobs,
        seconds_per_realisation=SECONDS_PER_REALISATION,
        bytes_per_realisation=8.0 * n_acc * (3 + 2 * len(METRICS)),
    )
    settings = W.Settings()
    x = run_monte_carlo(
        functools.partial(accommodation_chunk, seed=seed, method=method, settings=settings),
        trials,
        seed=seed,
        jobs=jobs,
        chunk_size=CHUNK_REALISATIONS,
        description="wind-turbine accommodation",
    )
    headline = {"realisations": trials, "method": method, "faults": _fault_summaries(x)}
    settings_out = {
        "seed": seed,
        "trials": trials,
        "method": method,
        "after_s": AFTER_S,
        "faults": list(ACCOMMODATED),
        "schedule": "benchmark",
    }
    return ReproductionResult(
        id="windturbine-accommodation",
        headline=headline,
        paper={},
        settings=settings_out,
        data={"raw": x},
    )
