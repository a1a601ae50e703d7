"""Exercises of "Sparse fault isolation" (zhang2021/sparse): statements and data.

A student's variant draws the number of candidate faults, the filter's matrices and the seed
and support of the regression (still ``N = 40`` samples of ``p = 2`` sensors, ``m = 8`` faults).
"""

from __future__ import annotations

import numpy as np

from fdi_lib.exercises._core import Exercise, uniform

CHAPTER = "zhang2021/sparse"


def _sparse1_data(rng):
    if rng is None:
        return {"m": 50, "q_max": 5}
    m = int(rng.integers(30, 80))
    return {"m": m + (m >= 50), "q_max": int(rng.integers(3, 7))}  # never the book's m = 50


def _sparse2_data(rng):
    F, E = np.array([[0.8, 0.2], [0.0, 0.6]]), np.array([[1.0], [0.5]])
    if rng is not None:
        F = np.array(
            [[uniform(rng, 0.5, 0.75), uniform(rng, -0.3, 0.3)], [0.0, uniform(rng, 0.4, 0.8)]]
        )
        E = np.array([[1.0], [uniform(rng, -1.0, 1.0)]])
    return {
        "F": F,
        "H": np.eye(2),
        "Q": 0.1 * np.eye(2),
        "R": 0.2 * np.eye(2),
        "P0": np.eye(2),
        "E": E,
        "k": 1,
    }


def regression(rng) -> dict:
    """The regression of sparse-3 and sparse-5 (faults 2 and 5 present in the book's data)."""
    N, p, m = 40, 2, 8
    if rng is None:
        rng, support, values = np.random.default_rng(2021), [2, 5], [1.0, -0.7]
    else:
        support = sorted(int(i) for i in rng.choice(m, size=2, replace=False))
        values = [uniform(rng, 0.6, 1.2), -uniform(rng, 0.6, 1.2)]
    X = rng.standard_normal((N * p, m))
    theta = np.zeros(m)
    theta[support] = values
    y = X @ theta + 0.5 * rng.standard_normal(N * p)
    return {"X": X, "y": y, "n_samples": N}


def _sparse4_data(rng):
    from fdi_lib.sparse import lasso_path

    d = regression(rng)
    path = lasso_path(d["X"], d["y"], n_samples=d["n_samples"])
    # the regression stays in the data: the reference recomputes the path from it
    return {
        "lambdas": path.lambdas,
        "sizes": path.support_sizes(),
        "lambda_ratio": 1e-4,
        "max_size": d["X"].shape[1] // 2,
        **d,
    }


EXERCISES = [
    Exercise(
        "sparse-1",
        CHAPTER,
        "How many hypotheses without the Lasso?",
        "warm-up",
        10,
        answer="an integer: supports of size at most q_max",
        rtol=0.0,
        atol=0.5,
        data=_sparse1_data,
    ),
    Exercise(
        "sparse-2",
        CHAPTER,
        "The Kitanidis gain at k = 1",
        "warm-up",
        15,
        answer="array of shape (2, 2): K-bar_1",
        rtol=1e-8,
        data=_sparse2_data,
        time_keys=("k",),
    ),
    Exercise(
        "sparse-3",
        CHAPTER,
        "The λ above which the Lasso is zero, and the normalisation",
        "core",
        10,
        answer="a number: lambda_max in the normalisation of (39)",
        rtol=1e-8,
        data=regression,
    ),
    Exercise(
        "sparse-4",
        CHAPTER,
        "The flat-range rule on a given path",
        "core",
        20,
        answer="a number: the lambda chosen by the rule (log width)",
        rtol=1e-8,
        data=_sparse4_data,
    ),
    Exercise(
        "sparse-5",
        CHAPTER,
        "Undo the shrinkage",
        "core",
        15,
        answer="array of shape (8,): least squares on the selected support, zeros elsewhere",
        rtol=1e-8,
        data=regression,
    ),
    Exercise("sparse-6", CHAPTER, "Greedy selection instead of the Lasso", "challenge", 30),
]
