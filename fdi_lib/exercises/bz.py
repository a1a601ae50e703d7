"""Exercises of "Parametric and non-parametric faults" (bz/parametric-nonparametric): statements
and data.

A student's variant draws the RLS step's numbers, the noise levels of the designed model
(:func:`student_model`), the impulse time and the level, the sample ``k`` and the innovation, and
the energy test's window, dimension and level.
"""

from __future__ import annotations

import numpy as np

from fdi_lib.exercises._core import Exercise, rounded_normal, uniform

CHAPTER = "bz/parametric-nonparametric"


def student_model(n_steps: int, rng: np.random.Generator | None):
    """The designed example (:func:`fdi_lib.systems.bz_example.bz_model`); ``rng`` given: its
    noise covariances ``Q`` (and ``P_0 = Q``) and ``R`` scaled by factors drawn on a continuum in
    [0.5, 2], so the gains, and the answers that depend on them, differ between classmates while
    the structure (``H = I``, ``E = e_1``) the exercises' lessons rest on stays."""
    from fdi_lib.models import ltv_model
    from fdi_lib.systems import bz_example as ex

    if rng is None:
        return ex.bz_model(n_steps)
    Q, R = rng.uniform(0.5, 2.0) * ex.Q, rng.uniform(0.5, 2.0) * ex.R
    return ltv_model(F=ex.F_k, G=ex.G, H=ex.H, Q=Q, R=R, n_steps=n_steps, P0=Q)


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

    if rng is None:
        return {"model": ex.bz_model(200), "E": ex.E.copy(), "impulse_at": 100, "level": 1e-6}
    # the impulse anywhere on the record, a level with two significant digits between 1e-8 and
    # 1e-4, the model's noise levels: the samples affected differ between classmates
    level = float(f"{10 ** rng.uniform(-8.0, -4.0):.1e}")
    return {
        "model": student_model(200, rng),
        "E": ex.E.copy(),
        "impulse_at": int(rng.integers(20, 181)),
        "level": level,
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
    k += rng is not None and k >= 10  # never the book's k = 10
    return {"model": student_model(20, rng), "E": ex.E.copy(), "k": k}


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
        answer="array of shape (2, 2): first and last samples affected, "
        "[[first, last] Kitanidis, [first, last] Kalman]",
        rtol=0.0,
        atol=0.5,
        data=_bz2_data,
        time_keys=("impulse_at",),
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
