"""Benchmark of the sparse-isolation Monte Carlo of Zhang (2021), Example 1.

Prints, for the same trials (q = 5, r = 0.5):

* the time per trial of our pipeline (shared Kitanidis gains, batched filter and signature,
  exact LARS-Lasso path + flat-range rule), and of a full column of 1000 trials on ``--jobs``;
* the baseline: solving the Lasso (39) with cvxpy on a grid of ``--grid`` lambdas per trial
  (what one would do without the exact path), timed on a few trials and scaled to 1000;
* the ratio baseline / ours.

Run: ``.venv/bin/python benchmarks/bench_sparse.py [--jobs 2] [--grid 50] [--baseline-trials 3]``.
"""

from __future__ import annotations

import argparse
import time
from functools import partial

import numpy as np

from fdi_lib.montecarlo import run_monte_carlo, trial_rngs, trial_seeds
from fdi_lib.reproduce.zhang2021 import example1_chunk, example1_regression
from fdi_lib.sparse import lasso_cvxpy, lasso_path
from fdi_lib.systems import zhang2021_example1 as ex


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--grid", type=int, default=50)
    ap.add_argument("--baseline-trials", type=int, default=3)
    args = ap.parse_args()

    fn = partial(example1_chunk, q=5, r=0.5)
    fn(trial_seeds(0, 4))  # warm-up (imports)
    t = time.perf_counter()
    fn(trial_seeds(0, 200))
    ours_single = (time.perf_counter() - t) / 200
    t = time.perf_counter()
    res = run_monte_carlo(fn, 1000, seed=0, jobs=args.jobs)
    first = time.perf_counter() - t
    t = time.perf_counter()
    run_monte_carlo(fn, 1000, seed=1, jobs=args.jobs)  # workers already started
    column = time.perf_counter() - t
    print(f"ours: {1e3 * ours_single:.2f} ms per trial (1 process); one column of 1000 trials on "
          f"{args.jobs} jobs: {first:.1f} s with worker start-up, {column:.1f} s warm "
          f"(success rate {res['success_log'].mean():.3f}); a 21-column table: ~{first + 20 * column:.0f} s")

    model = ex.example1_model()
    trials = ex.draw_trials(model, trial_rngs(trial_seeds(0, args.baseline_trials)), q=5)
    reg, _ = example1_regression(trials)
    lasso_cvxpy(reg.X[0], reg.y[0], 1.0, n_samples=reg.n_samples)  # warm-up
    t = time.perf_counter()
    for b in range(args.baseline_trials):
        lam_max = lasso_path(reg.X[b], reg.y[b], n_samples=reg.n_samples).lambdas[0]
        for lam in np.geomspace(lam_max, 1e-4 * lam_max, args.grid):
            lasso_cvxpy(reg.X[b], reg.y[b], lam, n_samples=reg.n_samples)
    base = (time.perf_counter() - t) / args.baseline_trials
    print(f"baseline (cvxpy on a {args.grid}-point lambda grid): {base:.2f} s per trial, "
          f"~{1000 * base / args.jobs:.0f} s per 1000-trial column on {args.jobs} jobs (scaled from "
          f"{args.baseline_trials} trials)")
    print(f"ratio baseline / ours (per trial, 1 process): {base / ours_single:.0f}x")


if __name__ == "__main__":
    main()
