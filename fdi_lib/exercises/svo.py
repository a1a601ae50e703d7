"""Exercises of "Set-valued observers" (rosa2013/svo): statements and data.

A student's variant draws the dynamics, the measurement, the shear of the two images and the
counts, to four decimals (so classmates' answers differ), inside ranges where every set of the exercise stays non-empty and that leave out the book's
values (a student's answer is never the book's).
"""

from __future__ import annotations

import numpy as np

from fdi_lib.exercises._core import Exercise, uniform

CHAPTER = "rosa2013/svo"


def _svo1_data(rng):
    A, y = np.array([[0.9, 0.5], [0.0, 0.8]]), np.array([1.2])
    if rng is not None:
        A = np.array(
            [[uniform(rng, 0.7, 1.0), uniform(rng, 0.3, 0.7)], [0.0, uniform(rng, 0.6, 0.9)]]
        )
        y = np.array([uniform(rng, 0.6, 1.15)])
    return {
        "X_lower": np.array([-1.0, -1.0]),
        "X_upper": np.array([1.0, 1.0]),
        "A": A,
        "L": 0.1 * np.eye(2),
        "C": np.array([[1.0, 0.0]]),
        "noise": 0.1,
        "y_next": y,
    }


def _svo2_data(rng):
    if rng is None:
        return {
            "x_lower": 0.99,
            "x_upper": 1.01,
            "A": 1.0,
            "A_unc": 0.5,
            "noise": 0.1,
            "y0": 1.0,
            "y_next": 1.3,
        }
    return {
        "x_lower": 0.99,
        "x_upper": 1.01,
        "A": 1.0,
        "A_unc": uniform(rng, 0.3, 0.45, 4),
        "noise": 0.1,
        "y0": 1.0,
        "y_next": uniform(rng, 1.1, 1.3, 4),
    }


def _svo3_data(rng):
    s = 0.5 if rng is None else uniform(rng, 0.55, 0.85, 4)
    return {
        "square_lower": np.array([-1.0, -1.0]),
        "square_upper": np.array([1.0, 1.0]),
        "A_plus": np.array([[1.0, 0.0], [s, 1.0]]),
        "A_minus": np.array([[1.0, 0.0], [-s, 1.0]]),
    }


def _svo4_data(rng):
    if rng is None:
        return {"x_lower": -0.2, "x_upper": 0.2, "A": 0.9, "L": 0.05, "noise": 0.1}
    return {
        "x_lower": -0.2,
        "x_upper": 0.2,
        "A": uniform(rng, 0.5, 0.85, 4),
        "L": uniform(rng, 0.02, 0.1, 4),
        "noise": uniform(rng, 0.05, 0.2, 4),
    }


def _svo5_data(rng):
    if rng is None:
        return {"N": 3, "n_A": 2, "T": 100}
    # the run's length T spreads the count over hundreds of values (classmates' answers differ)
    return {
        "N": int(rng.integers(4, 6)),
        "n_A": int(rng.integers(1, 4)),
        "T": int(rng.integers(100, 1001)),
    }


EXERCISES = [
    Exercise(
        "svo-1",
        CHAPTER,
        "One SVO step on a box",
        "warm-up",
        15,
        answer="array of shape (4,): [x1 min, x1 max, x2 min, x2 max]",
        rtol=1e-6,
        atol=1e-8,
        data=_svo1_data,
    ),
    Exercise(
        "svo-2",
        CHAPTER,
        "Hull first, then strip",
        "warm-up",
        10,
        answer="array of shape (2,): [lower, upper] of the set X(k+1)",
        rtol=1e-6,
        atol=1e-8,
        data=_svo2_data,
    ),
    Exercise(
        "svo-3",
        CHAPTER,
        "The price of convexification",
        "core",
        15,
        answer="a number: area of the hull minus area of the union",
        rtol=1e-6,
        data=_svo3_data,
    ),
    Exercise(
        "svo-4",
        CHAPTER,
        "The smallest jump seen in one step",
        "core",
        15,
        answer="a number: the smallest y(k+1) > 0 that empties the set",
        rtol=1e-6,
        data=_svo4_data,
    ),
    Exercise(
        "svo-5",
        CHAPTER,
        "How many vertex propagations",
        "warm-up",
        5,
        answer="an integer: the number of Delta-vertex sequences over T steps",
        rtol=0.0,
        atol=0.5,
        data=_svo5_data,
    ),
    Exercise("svo-6", CHAPTER, "Which true Delta breaks the paper's order?", "challenge", 25),
]
