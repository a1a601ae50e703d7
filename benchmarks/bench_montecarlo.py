"""Benchmark: Figs 7 and 8 of Zhang & Basseville 2014 (gas pipeline) at the paper's full trial count.

Targets: Figs 7 and 8 together, 2 x 1000 runs, N = 500, w = 160, in at most 20 s wall on this
2-core machine (issue 3); two jobs faster than one (issue 16). Timed in this run:

* the vectorised Monte Carlo engine (``reproduce("zb2014-fig7")`` then ``"zb2014-fig8"``, which
  reuses the same runs), with 2 jobs (first with the worker start-up, then warm) and with 1 job
  (cache cleared before each). Wall times: on a machine shared with other busy sessions (Linux
  gives each session a fair share of the cores), a second process cannot add CPU, so compare
  with the load average printed;
* the baseline: a per-realisation loop of the foundation's single-run detector (draw the
  noise, simulate, Kalman filter, :func:`fdi_lib.glr.glr_window` on one record, first alarm,
  two minmax tests), timed on a few realisations and scaled to 2000;
* peak memory: ``tracemalloc`` peak of one chunk of 250 realisations (what each worker holds)
  and the maximum resident set size of this process after the 1-job run.

Run: .venv/bin/python benchmarks/bench_montecarlo.py [--baseline-runs 6]
"""

from __future__ import annotations

import argparse
import os
import resource
import time
import tracemalloc

import numpy as np
from _record import record

from fdi_lib.filters import kalman_filter
from fdi_lib.glr import first_alarm, glr_window
from fdi_lib.isolation import minmax_statistic
from fdi_lib.montecarlo import trial_seeds
from fdi_lib.reproduce import reproduce
from fdi_lib.reproduce import zb2014_pipeline as zp
from fdi_lib.simulate import draw_noise, simulate
from fdi_lib.systems import gas_pipeline as gp

TRIALS = 1000  # per fault, as in the paper


def figs_7_8(jobs: int) -> float:
    zp._MC_CACHE.clear()
    t0 = time.perf_counter()
    reproduce("zb2014-fig7", trials=TRIALS, jobs=jobs)
    reproduce("zb2014-fig8", trials=TRIALS, jobs=jobs)
    return time.perf_counter() - t0


def baseline_per_realisation(n: int) -> float:
    """Seconds per realisation of the unbatched single-run detector (setup excluded, as for the engine)."""
    st = zp.pipeline_setup()
    seeds = trial_seeds(0, n)
    t0 = time.perf_counter()
    for i, s in enumerate(seeds):
        fault = 1 + i % 2
        noise = draw_noise(st.model, np.random.default_rng(s))
        sim = simulate(
            st.model,
            noise=noise,
            u=st.u,
            fault=st.input_family.profile(zp.FAULT_ONSET),
            theta=zp.fault_theta(fault),
        )
        eps = kalman_filter(st.model, sim.y, st.u, gains=st.gains).innovations
        res = glr_window(eps, st.model, st.gains, st.input_family, gp.WINDOW)
        k = int(first_alarm(res.statistic, gp.THRESHOLD, start=zp.GLR_START))
        if k >= 0:
            minmax_statistic(res.C_hat[k], res.d_hat[k], [0])
            minmax_statistic(res.C_hat[k], res.d_hat[k], [1])
    return (time.perf_counter() - t0) / n


def chunk_peak_mib() -> float:
    seeds = trial_seeds(1, 250)
    tracemalloc.start()
    zp.detection_chunk(seeds, fault=1)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak / 2**20


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline-runs", type=int, default=6)
    args = parser.parse_args()
    zp.pipeline_setup()  # shared setup (model, gains), paid once by both paths
    t2_cold = figs_7_8(jobs=2)
    t1 = figs_7_8(jobs=1)
    t2 = figs_7_8(jobs=2)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    per = baseline_per_realisation(args.baseline_runs)
    base = per * 2 * TRIALS
    print(
        f"Figs 7+8, 2 x {TRIALS} runs, N = {gp.N_STEPS}, w = {gp.WINDOW}; "
        f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} (others share the machine)"
    )
    print(f"  engine, 2 jobs, cold    : {t2_cold:7.2f} s   (worker start-up included)")
    print(f"  engine, 2 jobs, warm    : {t2:7.2f} s")
    print(f"  engine, 1 job           : {t1:7.2f} s")
    print(
        f"  per-realisation loop    : {per * 1e3:7.1f} ms/run x {2 * TRIALS} = {base:7.1f} s "
        f"(timed on {args.baseline_runs} runs)"
    )
    print(f"  speed-up vs loop        : {base / t2:7.1f}x (2 jobs), {base / t1:7.1f}x (1 job)")
    print(
        f"  peak memory, one chunk  : {chunk_peak_mib():7.1f} MiB (tracemalloc, 250 realisations)"
    )
    print(f"  max RSS of this process : {rss:7.1f} MiB")
    record(
        f"Figs 7+8 of Zhang & Basseville 2014, 2 x {TRIALS} runs, 2 jobs (start-up included)",
        t2_cold,
        "s",
        20.0,
        baseline="per-realisation loop, scaled",
        speedup=base / t2_cold,
    )
    record(
        "Figs 7+8, one job / two jobs (warm workers)",
        t1 / t2,
        "x",
        1.0,
        higher_is_better=True,
        note=f"1 job {t1:.2f} s, 2 jobs {t2:.2f} s wall, load average {os.getloadavg()[0]:.1f}",
    )


if __name__ == "__main__":
    main()
