"""References of the bz/parametric-nonparametric exercises (instructor only)."""

from __future__ import annotations

import numpy as np

from fdi_lib.exercises._reference import Mistake, Reference
from fdi_lib.exercises._reference.glr import chi2_ppf
from fdi_lib.exercises._reference.signature import gains


def _bz1_answer(d: dict, lam: float) -> np.ndarray:
    from fdi_lib.rls import rls_track

    return rls_track(d["eps"][None], d["M"][None], d["Sigma"][None], lam=lam, P0=d["P0"]).theta_hat[
        0
    ]


def _bz2_ref(d: dict) -> np.ndarray:
    from fdi_lib.nonparametric import kitanidis_predictor_gains, nonparametric_signature

    m = d["model"]
    f = np.zeros((m.n_steps, 1))
    f[d["impulse_at"]] = 1.0
    out = []
    for g in (kitanidis_predictor_gains(m, d["E"]), gains(m)):
        z = nonparametric_signature(m, g, d["E"], f)
        hit = np.flatnonzero(np.abs(z).max(axis=1) > d["level"])
        out.append([hit[0], hit[-1]])
    return np.array(out)


def _bz_gains(d: dict):
    from fdi_lib.kitanidis import kitanidis_gains

    return kitanidis_gains(d["model"], d["E"])


def _bz3_ref(d: dict) -> float:
    from fdi_lib.nonparametric import rejection_projection

    T = rejection_projection(d["model"], _bz_gains(d))[d["k"]]
    return float(np.sum((T @ d["eps"]) ** 2))


def _bz3_unwhitened(d: dict) -> float:
    import scipy.linalg

    Nk = scipy.linalg.null_space(d["HE"].T)
    return float(np.sum((Nk.T @ d["eps"]) ** 2))


def _bz4_ref(d: dict) -> np.ndarray:
    from fdi_lib.nonparametric import kitanidis_lag_covariance

    return kitanidis_lag_covariance(d["model"], _bz_gains(d), 1)[d["k"]]


def _bz5_ref(d: dict) -> float:
    from fdi_lib.nonparametric import energy_threshold

    return energy_threshold(d["window"], d["p_reduced"], d["alpha"])


_WINDOW_DOF = "Degrees of freedom: the window sums w vectors of p components each."

REFERENCES = {
    "bz-1": Reference(
        lambda d: _bz1_answer(d, d["lam"]),
        (
            Mistake(
                lambda d: _bz1_answer(d, 1.0),
                "This is the step without forgetting: S_1 = lambda Sigma_1 + M_1 P_0 M_1^T.",
            ),
        ),
        one_call=("fdi_lib.rls.rls_track",),
    ),
    "bz-2": Reference(_bz2_ref),
    "bz-3": Reference(
        _bz3_ref,
        (
            Mistake(
                _bz3_unwhitened,
                "This projection is not whitened: T_k must also satisfy T_k Sigma_k T_k^T = I.",
            ),
        ),
        one_call=("fdi_lib.nonparametric.rejection_projection",),
    ),
    "bz-4": Reference(_bz4_ref, one_call=("fdi_lib.nonparametric.kitanidis_lag_covariance",)),
    "bz-5": Reference(
        _bz5_ref,
        (
            Mistake(lambda d: chi2_ppf(1 - d["alpha"], d["window"]), _WINDOW_DOF),
            Mistake(lambda d: chi2_ppf(1 - d["alpha"], d["p_reduced"]), _WINDOW_DOF),
        ),
        one_call=("fdi_lib.nonparametric.energy_threshold",),
    ),
}
