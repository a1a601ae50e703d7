"""Benchmark of the sparse-isolation Monte Carlo of Zhang (2021), Example 1 (issue 16, target 2).

Target: Tables I and II (2 x 21 columns of 1000 trials) in at most 20 s together on this machine.
Timed in this run:

* the exact Lasso paths of 250 trials (q = 5 and q = 20, r = 0.5): our homotopy batched over the
  trials (:func:`fdi_lib.sparse.lasso_paths`) against scikit-learn's ``lars_path`` called per
  trial (the route before issue 16), same window (down to 1e-4 lambda_max), CPU time per trial;
* the whole chunk (draws, shared Kitanidis gains, filter, signatures, paths, the flat-range
  rules) per trial, one process, in CPU time: 42,000 times it over two cores is what the two
  tables take on two idle cores (the wall-time figure below also counts the other sessions of a
  shared machine);
* columns of 1000 trials with ``--jobs`` workers (and one job), for a few columns of each table;
  the two tables are estimated as 21 x the mean column time of each (all columns have the same
  work, up to the path lengths);
* the old baseline, cvxpy on a lambda grid, on ``--baseline-trials`` trials.

Run: ``.venv/bin/python benchmarks/bench_sparse.py [--jobs 2] [--grid 50] [--baseline-trials 1]``.
"""

from __future__ import annotations

import argparse
import os
import time
from functools import partial

import numpy as np
from _record import record

from fdi_lib.montecarlo import run_monte_carlo, trial_rngs, trial_seeds
from fdi_lib.reproduce.zhang2021 import LAMBDA_RATIO, example1_chunk, example1_regression
from fdi_lib.sparse import lasso_cvxpy, lasso_paths
from fdi_lib.systems import zhang2021_example1 as ex


def sklearn_path(X: np.ndarray, y: np.ndarray) -> None:
    """scikit-learn's exact LARS-Lasso path of one trial, down to the same window end."""
    from sklearn.linear_model import lars_path

    alpha_min = LAMBDA_RATIO * np.abs(X.T @ y).max() / X.shape[0]
    lars_path(X, y, method="lasso", alpha_min=alpha_min)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--grid", type=int, default=50)
    ap.add_argument("--baseline-trials", type=int, default=1)
    args = ap.parse_args()
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} (the machine may be shared)")

    ratios = []
    for q in (5, 20):
        model = ex.example1_model()
        trials = ex.draw_trials(model, trial_rngs(trial_seeds(q, 250)), q=q)
        reg, _ = example1_regression(trials)
        lasso_paths(reg.X[:4], reg.y[:4], n_samples=reg.n_samples, lambda_min=LAMBDA_RATIO, max_size=25)
        t = time.process_time()
        lasso_paths(reg.X, reg.y, n_samples=reg.n_samples, lambda_min=LAMBDA_RATIO, max_size=25)
        ours = (time.process_time() - t) / 250
        t = time.process_time()
        for b in range(100):
            sklearn_path(reg.X[b], reg.y[b])
        theirs = (time.process_time() - t) / 100
        ratios.append(theirs / ours)
        print(f"  exact paths, q = {q:2d}: ours {1e3 * ours:.3f} ms/trial (batched over 250), "
              f"scikit-learn lars_path {1e3 * theirs:.3f} ms/trial (100 trials): {theirs / ours:.1f}x")
    record("exact Lasso path per trial (batched homotopy vs scikit-learn lars_path)", 1e3 * ours, "ms",
           1e3 * theirs, baseline="scikit-learn lars_path per trial (CPU time)", speedup=min(ratios),
           note="speed-up is the smaller of q = 5 and q = 20")

    fn = partial(example1_chunk, q=5, r=0.5)
    fn(trial_seeds(0, 4))  # warm-up (imports)
    t = time.process_time()
    fn(trial_seeds(0, 250))
    per_trial = (time.process_time() - t) / 250
    print(f"  whole chunk: {1e3 * per_trial:.2f} ms per trial (CPU, one process): "
          f"{42_000 * per_trial:.0f} s of CPU for the two tables")
    record("Zhang 2021 Tables I and II from CPU time: 42,000 trials x CPU per trial / 2 cores",
           42_000 * per_trial / 2, "s", 20.0,
           note="what two idle cores would take, workers' start-up excluded")

    cols = {"Table I": [(5, 0.5), (15, 0.5), (25, 0.5)], "Table II": [(5, 10.0), (5, 200.0)]}
    # start the workers
    run_monte_carlo(partial(example1_chunk, q=5, r=0.5), 8, seed=0, jobs=args.jobs, chunk_size=2)
    est = 0.0
    for name, qr in cols.items():
        times = []
        for q, r in qr:
            t = time.perf_counter()
            run_monte_carlo(partial(example1_chunk, q=q, r=r), 1000, seed=0, jobs=args.jobs)
            times.append(time.perf_counter() - t)
        print(f"  {name}: columns {qr} of 1000 trials on {args.jobs} jobs: "
              + ", ".join(f"{x:.2f} s" for x in times))
        est += 21 * float(np.mean(times))
    t = time.perf_counter()
    run_monte_carlo(partial(example1_chunk, q=5, r=0.5), 1000, seed=0, jobs=1)
    one_job = time.perf_counter() - t
    print(f"  one column on 1 job: {one_job:.2f} s")

    model = ex.example1_model()
    trials = ex.draw_trials(model, trial_rngs(trial_seeds(0, args.baseline_trials)), q=5)
    reg, _ = example1_regression(trials)
    lasso_cvxpy(reg.X[0], reg.y[0], 1.0, n_samples=reg.n_samples)  # warm-up
    t = time.perf_counter()
    for b in range(args.baseline_trials):
        lam_max = np.abs(reg.X[b].T @ reg.y[b]).max() / reg.n_samples
        for lam in np.geomspace(lam_max, LAMBDA_RATIO * lam_max, args.grid):
            lasso_cvxpy(reg.X[b], reg.y[b], lam, n_samples=reg.n_samples)
    base = (time.perf_counter() - t) / args.baseline_trials
    print(f"  cvxpy on a {args.grid}-point lambda grid: {base:.2f} s per trial "
          f"({args.baseline_trials} trial(s))")
    record(f"Zhang 2021 Tables I and II, 2 x 21 x 1000 trials, {args.jobs} jobs", est, "s", 20.0,
           baseline=f"cvxpy on a {args.grid}-point lambda grid per trial, scaled to 42,000 trials on "
                    f"{args.jobs} jobs", speedup=42_000 * base / args.jobs / est,
           note="estimated from 5 columns (21 x mean column time per table)")


if __name__ == "__main__":
    main()
