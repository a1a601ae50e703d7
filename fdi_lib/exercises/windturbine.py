"""Exercises of "Four methods on the wind-turbine benchmark" (windturbine/benchmark): statements
and data.

A student's variant draws the information and threshold of the GLR (wt-1) and the noise bound,
sensor count and record length of the SVO (wt-2) in ranges that leave out the book's values.
"""

from __future__ import annotations

from fdi_lib.exercises._core import Exercise, uniform

CHAPTER = "windturbine/benchmark"


def _wt1_data(rng):
    # information of one pitch-sensor offset over the GLR's window (per deg^2) and the threshold:
    # the chapter's design at the benchmark's noise, rounded to the digits a student types
    if rng is None:
        return {"information_per_deg2": 241.4, "threshold": 36.61}
    return {
        "information_per_deg2": uniform(rng, 120.0, 220.0, 1),
        "threshold": uniform(rng, 20.0, 34.0),
    }


def _wt2_data(rng):
    if rng is None:
        return {"k_sigma": 5.0, "sensors": 11, "hours": 1.0, "sample_rate_hz": 100.0}
    return {
        "k_sigma": uniform(rng, 3.5, 4.8, 1),
        "sensors": int(rng.integers(6, 11)),
        "hours": float(rng.integers(2, 6)),
        "sample_rate_hz": 100.0,
    }


EXERCISES = [
    Exercise(
        "wt-1",
        CHAPTER,
        "The smallest pitch-sensor offset the GLR sees",
        "warm-up",
        10,
        answer="a number: the smallest offset (deg) whose mean GLR statistic reaches the threshold",
        rtol=1e-6,
        data=_wt1_data,
    ),
    Exercise(
        "wt-2",
        CHAPTER,
        "How often Gaussian noise leaves the SVO's bounds",
        "core",
        15,
        answer="a number: the expected count of noise samples beyond k sigma in the record",
        rtol=1e-6,
        data=_wt2_data,
    ),
    Exercise("wt-3", CHAPTER, "Why nobody sees the drive-train fault", "core", 20),
    Exercise("wt-4", CHAPTER, "Trading the SVO's bound against its false alarms", "challenge", 30),
]
