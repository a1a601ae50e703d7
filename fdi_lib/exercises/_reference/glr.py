"""References of the zb2014/glr exercises (instructor only)."""

from __future__ import annotations

import numpy as np

from fdi_lib.exercises._reference import Mistake, Reference
from fdi_lib.exercises._reference.signature import gains, signature


def chi2_ppf(q: float, dof: float) -> float:
    import scipy.stats

    return float(scipy.stats.chi2.ppf(q, dof))


def _glr2_ref(d: dict) -> np.ndarray:
    from fdi_lib.glr import quadratic_form

    stat, theta = quadratic_form(d["C"], d["d"])
    return np.concatenate([[stat], theta])


def _glr2_no_inverse(d: dict) -> np.ndarray:
    return np.concatenate([[d["d"] @ d["C"] @ d["d"]], d["C"] @ d["d"]])


def glr3_answer(d: dict, dof: int) -> np.ndarray:
    import scipy.stats

    from fdi_lib.glr import glr_known_profile

    m = d["model"]
    S = signature(m, Psi=d["Psi"]).on_innovation
    C = glr_known_profile(np.zeros((m.n_steps, m.p)), gains(m), S).C[-1]
    lam = float(d["theta"] @ C @ d["theta"])
    threshold = chi2_ppf(1 - d["alpha"], dof)
    return np.array([lam, float(scipy.stats.ncx2.sf(threshold, dof, lam))])


def _glr4_ref(d: dict) -> float:
    from fdi_lib.isolation import minmax_statistic

    return float(minmax_statistic(d["F"], d["zeta"], d["a"]))


def _glr5_count(d: dict, extra: int) -> int:
    # eq. (37): candidate onsets k - w + 1 <= r <= k - s
    return int(np.arange(d["k"] - d["w"] + 1, d["k"] - d["s"] + 1 + extra).size)


DOF_HINT = (
    "This is the quantile for another number of degrees of freedom: count the components tested."
)
_OFF_BY_ONE = "Off by one: the candidates are k - w + 1 <= r <= k - s, both ends included."

REFERENCES = {
    "glr-1": Reference(
        lambda d: chi2_ppf(1 - d["alpha"], d["m"]),
        (
            Mistake(lambda d: chi2_ppf(1 - d["alpha"], d["m"] - 1), DOF_HINT),
            Mistake(lambda d: chi2_ppf(1 - d["alpha"], d["m"] + 1), DOF_HINT),
            Mistake(
                lambda d: chi2_ppf(d["alpha"], d["m"]),
                "This is the lower quantile: the false alarms are the upper tail, "
                "P(l > threshold) = alpha.",
            ),
        ),
    ),
    "glr-2": Reference(
        _glr2_ref,
        (
            Mistake(
                _glr2_no_inverse,
                "This uses C where C^{-1} belongs: l = d^T C^{-1} d and theta_hat = C^{-1} d.",
            ),
        ),
        one_call=("fdi_lib.glr.quadratic_form",),
    ),
    "glr-3": Reference(
        lambda d: glr3_answer(d, 2),
        (
            Mistake(
                lambda d: glr3_answer(d, 1),
                "The detection probability uses 1 degree of "
                "freedom: the GLR tests all m = 2 components.",
            ),
        ),
    ),
    "glr-4": Reference(
        _glr4_ref,
        (
            Mistake(
                lambda d: d["zeta"][0] ** 2 / d["F"][0, 0],
                "This is zeta_a^2 / F_aa: the nuisance was set to zero instead of being regressed out.",
            ),
            Mistake(
                lambda d: d["zeta"] @ np.linalg.solve(d["F"], d["zeta"]),
                "This is the GLR for the whole of theta: the minmax statistic subtracts the part "
                "explained by theta_b.",
            ),
        ),
        one_call=("fdi_lib.isolation.minmax_statistic",),
    ),
    "glr-5": Reference(
        lambda d: _glr5_count(d, 0),
        (
            Mistake(lambda d: _glr5_count(d, 1), _OFF_BY_ONE),
            Mistake(lambda d: _glr5_count(d, -1), _OFF_BY_ONE),
        ),
    ),
}
