"""References of the zb2014/pipeline exercises (instructor only)."""

from __future__ import annotations

import math

import numpy as np

from fdi_lib.exercises._reference import Mistake, Reference
from fdi_lib.exercises._reference.glr import chi2_ppf


def _pipe2_ref(d: dict) -> np.ndarray:
    from fdi_lib.systems import gas_pipeline as gp

    mats = gp.pipeline_matrices("designed")
    # J0 = 1 - H (I - F)^{-1} G0 and Jp = -H (I - F)^{-1} Gp are affine in G0, Gp: a student's
    # data scale G0 and Gp (exercises.pipeline.pipe2_gain_factors), the library gives the rest
    a = d["G0"][0, 0] / mats.G0[0, 0]
    b = d["Gp"][0, 0] / mats.Gp[0, 0]
    return np.array([1.0 - a * (1.0 - mats.J0[0, 0]), b * mats.Jp[0, 0]])


def pipe3_answer(d: dict, extra: int) -> float:
    S = d["signature"][d["first"] : d["last"] + 1 + extra]
    W = np.linalg.inv(d["Sigma"][d["first"] : d["last"] + 1 + extra])
    F = np.einsum("kpi,kpq,kqj->ij", S, W, S)
    return float(1.0 - F[0, 1] ** 2 / (F[0, 0] * F[1, 1]))


def _pipe4_ref(d: dict) -> np.ndarray:
    from fdi_lib.reproduce import zb2014_pipeline as zp

    pw = zp.known_onset_isolation_power(
        start=d["start"], stop=d["stop"], alpha_threshold=d["threshold"]
    )["2"]
    return np.array([pw["noncentrality"], pw["power"]])


def _pipe4_no_rejection(d: dict) -> np.ndarray:
    import scipy.stats

    S = d["signature"][d["start"] : d["stop"]]
    W = np.linalg.inv(d["Sigma"][d["start"] : d["stop"]])
    F = np.einsum("kpi,kpq,kqj->ij", S, W, S)
    lam = float(d["theta"][1] ** 2 * F[1, 1])
    return np.array([lam, float(scipy.stats.ncx2.sf(d["threshold"], 1, lam))])


def _pipe5_ref(d: dict) -> np.ndarray:
    from fdi_lib.montecarlo import binomial_ci

    return np.array(binomial_ci(d["false_alarms"], d["runs"]))


def _pipe5_wald(d: dict) -> np.ndarray:
    p = d["false_alarms"] / d["runs"]
    h = 1.959963984540054 * math.sqrt(p * (1 - p) / d["runs"])
    return np.array([p - h, p + h])


REFERENCES = {
    "pipe-1": Reference(
        lambda d: chi2_ppf(1 - d["alpha"], d["dim_theta_a"]),
        (
            Mistake(
                lambda d: chi2_ppf(1 - d["alpha"], 2),
                "This is the chi2(2) quantile, the paper text's slip: each minmax test focuses on "
                "dim theta_a = 1 component.",
            ),
        ),
    ),
    "pipe-2": Reference(_pipe2_ref, one_call=("fdi_lib.systems.gas_pipeline.pipeline_matrices",)),
    "pipe-3": Reference(
        lambda d: pipe3_answer(d, 0),
        (
            Mistake(
                lambda d: pipe3_answer(d, 1),
                "Off by one: k = first, ..., last includes both ends, the slice [first:last + 1].",
            ),
        ),
    ),
    "pipe-4": Reference(
        _pipe4_ref,
        (
            Mistake(
                _pipe4_no_rejection,
                "This uses F_aa: the minmax test only keeps the information "
                "F_a* = F_aa - F_ab^2 / F_bb left after rejecting the nuisance.",
            ),
        ),
        one_call=("fdi_lib.reproduce.zb2014_pipeline.known_onset_isolation_power",),
    ),
    "pipe-5": Reference(
        _pipe5_ref,
        (
            Mistake(lambda d: 100 * _pipe5_ref(d), "These look like percentages: give fractions."),
            Mistake(
                _pipe5_wald,
                "This is the normal (Wald) approximation, poor for a few events: use "
                "the exact Clopper-Pearson interval.",
            ),
        ),
        one_call=("fdi_lib.montecarlo.binomial_ci",),
    ),
}
