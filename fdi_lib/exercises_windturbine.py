"""Exercises of the wind-turbine chapter (``book/windturbine/benchmark``), self-contained.

Built with the :class:`~fdi_lib.exercises.Exercise` and :class:`~fdi_lib.exercises.Mistake` classes
of :mod:`fdi_lib.exercises`; :func:`register` adds them (and the chapter) to its registry, so that
``check`` and ``exercise_data`` find them. The chapter calls :func:`register` once. (Meant to move
into the exercises registry itself, which is being reorganised: then :func:`register` goes.)
"""

from __future__ import annotations

import numpy as np
import scipy.stats

from fdi_lib.exercises import Exercise, Mistake

__all__ = ["CHAPTER", "CHAPTER_TITLE", "WINDTURBINE_EXERCISES", "register"]

CHAPTER = "windturbine/benchmark"
CHAPTER_TITLE = "Four methods on the wind-turbine benchmark"


def _wt1_data() -> dict:
    # information of one pitch-sensor offset over the GLR's window (per deg^2) and the threshold:
    # the values of the chapter's design at the benchmark's noise (rounded)
    return {"information_per_deg2": 241.4, "threshold": 36.61}


def _wt2_data() -> dict:
    return {"k_sigma": 5.0, "sensors": 11, "hours": 1.0, "sample_rate_hz": 100.0}


def _wt2_ref(d: dict, tails: int = 2) -> float:
    p = tails * scipy.stats.norm.sf(d["k_sigma"])
    return float(p * d["sensors"] * d["hours"] * 3600.0 * d["sample_rate_hz"])


WINDTURBINE_EXERCISES = (
    Exercise(id="wt-1", chapter=CHAPTER, title="The smallest pitch-sensor offset the GLR sees", difficulty="warm-up",
             minutes=10, answer="a number: the smallest offset (deg) whose mean GLR statistic reaches the threshold",
             rtol=1e-6, data=_wt1_data, reference=lambda d: float(np.sqrt(d["threshold"] / d["information_per_deg2"])),
             mistakes=(Mistake(lambda d: d["threshold"] / d["information_per_deg2"],
                               "The statistic grows with the square of the offset: undo the square."),
                       Mistake(lambda d: float(np.sqrt(d["information_per_deg2"] / d["threshold"])),
                               "This is the inverse: a larger information must make the smallest "
                               "visible offset smaller."))),
    Exercise(id="wt-2", chapter=CHAPTER, title="How often Gaussian noise leaves the SVO's bounds", difficulty="core",
             minutes=15, answer="a number: the expected count of noise samples beyond k sigma in the record",
             rtol=1e-6, data=_wt2_data, reference=_wt2_ref,
             mistakes=(Mistake(lambda d: _wt2_ref(d, tails=1),
                               "A sample leaves the band on either side: count both tails."),)),
    Exercise(id="wt-3", chapter=CHAPTER, title="Why nobody sees the drive-train fault", difficulty="core", minutes=20),
    Exercise(id="wt-4", chapter=CHAPTER, title="Trading the SVO's bound against its false alarms",
             difficulty="challenge", minutes=30),
)


def register() -> None:
    """Add the chapter and its exercises to :mod:`fdi_lib.exercises` (idempotent)."""
    from fdi_lib import exercises as ex

    ex.CHAPTERS.setdefault(CHAPTER, CHAPTER_TITLE)
    for e in WINDTURBINE_EXERCISES:
        if e.id not in ex.EXERCISES:
            ex._LIST.append(e)
            ex.EXERCISES[e.id] = e
