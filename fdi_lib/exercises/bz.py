"""Exercises of "Parametric and non-parametric faults" (bz/parametric-nonparametric): statements
and data.

A student's variant draws the RLS step's numbers, the impulse time and the level, the sample ``k`` and the
innovation, and the energy test's window, dimension and level.
"""

from __future__ import annotations

import numpy as np

from fdi_lib.exercises._core import Exercise, rounded_normal, uniform

CHAPTER = "bz/parametric-nonparametric"


def _bz1_data(rng):
    if rng is None:
        return {
            "M": np.array([[1.0, 0.5], [0.0, 2.0]]),
            "Sigma": 0.5 * np.eye(2),
            "P0": np.eye(2),
            "lam": 0.9,
            "eps": np.array([0.3, -0.4]),
        }
    M = np.array([[uniform(rng, 0.5, 1.5), uniform(rng, -1, 1)], [0.0, uniform(rng, 1.0, 2.5)]])
    return {
        "M": M,
        "Sigma": 0.5 * np.eye(2),
        "P0": np.eye(2),
        "lam": uniform(rng, 0.8, 0.89),
        "eps": rounded_normal(rng, 2, 0.4),
    }


def _bz2_data(rng):
    from fdi_lib.systems import bz_example as ex

    return {
        "model": ex.bz_model(200),
        "E": ex.E.copy(),
        "impulse_at": 100 if rng is None else int(rng.integers(60, 141)),
        "level": 1e-6 if rng is None else float(rng.choice((1e-4, 1e-5, 1e-7, 1e-8))),
    }


def _bz3_data(rng):
    from fdi_lib.kitanidis import kitanidis_gains
    from fdi_lib.systems import bz_example as ex

    m = ex.bz_model(20)
    kg = kitanidis_gains(m, ex.E)
    k = 10 if rng is None else int(rng.integers(4, 16))
    eps = np.array([0.05, -0.02, 0.04]) if rng is None else rounded_normal(rng, 3, 0.05, 3)
    return {
        "Sigma": kg.Sigma[k],
        "HE": m.H[k] @ ex.E,
        "eps": eps,
        "model": m,
        "E": ex.E.copy(),
        "k": k,
    }


def _bz4_data(rng):
    from fdi_lib.systems import bz_example as ex

    k = 10 if rng is None else int(rng.integers(3, 16))
    return {"model": ex.bz_model(20), "E": ex.E.copy(), "k": k + (rng is not None and k >= 10)}


def _bz5_data(rng):
    if rng is None:
        return {"window": 20, "p_reduced": 2, "alpha": 1e-4}
    return {
        "window": int(rng.integers(10, 41)),
        "p_reduced": int(rng.integers(1, 4)),
        "alpha": float(rng.choice((1e-5, 1e-3, 1e-2))),
    }  # never the book's 1e-4


EXERCISES = [
    Exercise(
        "bz-1",
        CHAPTER,
        "One RLS step by hand",
        "warm-up",
        10,
        answer="array of shape (2,): theta_hat_1",
        rtol=1e-9,
        data=_bz1_data,
    ),
    Exercise(
        "bz-2",
        CHAPTER,
        "How long an impulse of f stays on the innovation",
        "warm-up",
        10,
        answer="array of shape (2,): samples affected [Kitanidis, Kalman]",
        rtol=0.0,
        atol=0.5,
        data=_bz2_data,
    ),
    Exercise(
        "bz-3",
        CHAPTER,
        "The whitened rejection",
        "core",
        15,
        answer="a number: ||T_k eps||^2",
        rtol=1e-8,
        data=_bz3_data,
    ),
    Exercise(
        "bz-4",
        CHAPTER,
        "Lag-one covariance of the Kitanidis innovation",
        "core",
        15,
        answer="array of shape (3, 3): Cov(eps_11, eps_10)",
        rtol=1e-8,
        atol=1e-14,
        data=_bz4_data,
        time_keys=("k",),
    ),
    Exercise(
        "bz-5",
        CHAPTER,
        "The threshold of the energy test",
        "warm-up",
        5,
        answer="a number: the chi-square threshold",
        rtol=1e-8,
        data=_bz5_data,
    ),
    Exercise("bz-6", CHAPTER, "As many sensors as unknown inputs", "challenge", 25),
]
