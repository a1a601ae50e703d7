"""Exercises of "GLR and minmax tests" (zb2014/glr): statements and data.

A student's variant draws the level, the matrices, the seed of the random model and the window.
"""

from __future__ import annotations

import numpy as np

from fdi_lib.exercises._core import Exercise, rounded_normal, uniform

CHAPTER = "zb2014/glr"


def _glr1_data(rng):
    # m stays 2: the exercise's closed form is that of chi2(2); alpha is drawn on a continuum
    # (four decimals, never the book's 0.01) so that classmates' thresholds differ
    return {"alpha": 0.01 if rng is None else uniform(rng, 0.011, 0.1, 4), "m": 2}


def _glr2_data(rng):
    if rng is None:
        return {"C": np.array([[4.0, 1.0], [1.0, 2.0]]), "d": np.array([2.0, -1.0])}
    B = rounded_normal(rng, (2, 2), 1.0, 1)
    return {"C": B @ B.T + np.eye(2), "d": rounded_normal(rng, 2, 1.0, 1)}


def _glr3_data(rng):
    from fdi_lib.systems.random_ltv import random_ltv_model

    theta = np.array([0.5, 0.0]) if rng is None else np.array([uniform(rng, 0.55, 0.8), 0.0])
    rng = np.random.default_rng(2015) if rng is None else rng
    model = random_ltv_model(rng, n=3, p=1, n_steps=60)
    return {"model": model, "Psi": rng.standard_normal((60, 3, 2)), "theta": theta, "alpha": 0.05}


def _glr4_data(rng):
    rng = np.random.default_rng(41) if rng is None else rng
    B = rng.standard_normal((3, 3))
    return {"F": B @ B.T + np.eye(3), "zeta": 2.0 * rng.standard_normal(3), "a": [0]}


def _glr5_data(rng):
    if rng is None:
        return {"k": 150, "w": 100, "s": 2}
    # w - s spans hundreds of counts (classmates' answers differ), never the book's 98
    w, s = int(rng.integers(40, 401)), int(rng.integers(1, 21))
    w += w - s == 98
    return {"k": w + int(rng.integers(10, 100)), "w": w, "s": s}


EXERCISES = [
    Exercise(
        "glr-1",
        CHAPTER,
        "A threshold for a false-alarm probability",
        "warm-up",
        5,
        answer="the 1 - alpha quantile of chi2(m) (a number)",
        rtol=1e-6,
        data=_glr1_data,
    ),
    Exercise(
        "glr-2",
        CHAPTER,
        "GLR statistic and estimate by hand",
        "warm-up",
        10,
        answer="array of shape (3,): [l, theta_hat_1, theta_hat_2]",
        rtol=1e-9,
        data=_glr2_data,
    ),
    Exercise(
        "glr-3",
        CHAPTER,
        "Non-centrality and detection probability",
        "core",
        20,
        answer="array of shape (2,): [non-centrality, detection probability]",
        rtol=1e-6,
        data=_glr3_data,
    ),
    Exercise(
        "glr-4",
        CHAPTER,
        "The minmax statistic by the explicit regression",
        "core",
        15,
        answer="a number: l_a",
        rtol=1e-9,
        data=_glr4_data,
    ),
    Exercise(
        "glr-5",
        CHAPTER,
        "Counting the candidate onsets",
        "warm-up",
        5,
        answer="an integer: the number of candidate onsets r at time k",
        rtol=0.0,
        atol=0.5,
        data=_glr5_data,
        time_keys=("k", "w", "s"),
    ),
    Exercise("glr-6", CHAPTER, "Why the windowed statistic is not chi-square", "challenge", 30),
]
