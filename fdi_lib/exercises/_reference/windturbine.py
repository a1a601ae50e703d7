"""References of the windturbine/benchmark exercises (instructor only)."""

from __future__ import annotations

import numpy as np
import scipy.stats

from fdi_lib.exercises._reference import Mistake, Reference


def _wt2_answer(d: dict, tails: int = 2) -> float:
    p = tails * scipy.stats.norm.sf(d["k_sigma"])
    return float(p * d["sensors"] * d["hours"] * 3600.0 * d["sample_rate_hz"])


REFERENCES = {
    "wt-1": Reference(
        lambda d: float(np.sqrt(d["threshold"] / d["information_per_deg2"])),
        (
            Mistake(
                lambda d: d["threshold"] / d["information_per_deg2"],
                "The statistic grows with the square of the offset: undo the square.",
            ),
            Mistake(
                lambda d: float(np.sqrt(d["information_per_deg2"] / d["threshold"])),
                "This is the inverse: a larger information must make the smallest visible offset "
                "smaller.",
            ),
        ),
    ),
    "wt-2": Reference(
        _wt2_answer,
        (
            Mistake(
                lambda d: _wt2_answer(d, tails=1),
                "A sample leaves the band on either side: count both tails.",
            ),
        ),
    ),
}
