"""References of the zb2014/signature exercises (instructor only)."""

from __future__ import annotations

from typing import Callable

import numpy as np

from fdi_lib.exercises._reference import Mistake, Reference


def _ltv(**kw):
    from fdi_lib.models import ltv_model

    return ltv_model(**kw)


def gains(model):
    from fdi_lib.filters import kalman_gains

    return kalman_gains(model)


def signature(model, **profile) -> np.ndarray:
    from fdi_lib.models import fault_profile
    from fdi_lib.signatures import fault_signature

    return fault_signature(model, gains(model), fault_profile(model, **profile))


def _sig1_model(d: dict):
    return _ltv(F=d["F"], H=d["H"], Q=d["Q"], R=d["R"], P0=d["P0"], x0=d["x0"], n_steps=2)


def _sig1_ref(d: dict) -> np.ndarray:
    from fdi_lib.filters import kalman_filter

    return kalman_filter(_sig1_model(d), d["y"][:, None]).innovations[:, 0]


def _sig1_no_f(d: dict) -> np.ndarray:
    g = gains(_sig1_model(d))
    eps0 = d["y"][0] - d["H"] @ d["x0"]
    x1 = d["x0"] + g.K[0] @ eps0  # the update, but no propagation by F_0
    return np.array([eps0[0], (d["y"][1] - d["H"] @ x1)[0]])


def _sig1_prior_gain(d: dict) -> np.ndarray:
    # gain from P0 with F_0 K_0 replaced by K_0 in the predictor
    g = gains(_sig1_model(d))
    eps0 = d["y"][0] - d["H"] @ d["x0"]
    x1 = d["F"] @ d["x0"] + g.K[0] @ eps0
    return np.array([eps0[0], (d["y"][1] - d["H"] @ x1)[0]])


def _sig2_ref(d: dict) -> np.ndarray:
    return signature(d["model"], Psi=d["Psi"]).Gamma[d["k"]]


def _sig2_open_loop(d: dict) -> np.ndarray:
    F = d["model"].F[0]
    G = np.zeros((2, 2))
    for _ in range(d["k"]):
        G = F @ G + d["Psi"]
    return G


def _sig3_ref(d: dict) -> np.ndarray:
    return signature(d["model"], Phi=d["Phi"]).on_innovation[: d["k_max"] + 1, 0, 0]


def _sig3_no_fk(d: dict) -> np.ndarray:
    return np.full(d["k_max"] + 1, d["Phi"][0, 0])


def _sig4_ref(d: dict) -> np.ndarray:
    return signature(d["model"], Psi=d["Psi"]).on_innovation[-1, 0]


def _sig4_open_loop(d: dict) -> np.ndarray:
    m = d["model"]
    return (m.H[0] @ np.linalg.inv(np.eye(2) - m.F[0]))[0]


def _sig5_slope(d: dict, log: Callable[[np.ndarray], np.ndarray]) -> float:
    from fdi_lib.signatures import willsky_jones

    m = d["model"]
    alpha = willsky_jones(m, gains(m), d["onset"]).alpha
    k = np.arange(d["k_first"], d["k_last"] + 1)
    norms = np.linalg.norm(alpha[k], ord=2, axis=(1, 2))
    return float(np.polyfit(k, log(norms), 1)[0])


_SIGNATURE = ("fdi_lib.signatures.fault_signature",)

REFERENCES = {
    "sig-1": Reference(
        _sig1_ref,
        (
            Mistake(
                _sig1_no_f,
                "eps_1 looks like the prediction skipped F_0: the predictor is "
                "X_1 = F_0 (X_0 + K_0 eps_0).",
            ),
            Mistake(
                _sig1_prior_gain,
                "eps_1 looks like the predictor X_1 = F_0 X_0 + K_0 eps_0: the "
                "gain of the predictor is F_0 K_0, not K_0.",
            ),
        ),
        one_call=("fdi_lib.filters.kalman_filter",),
    ),
    "sig-2": Reference(
        _sig2_ref,
        (
            Mistake(
                _sig2_open_loop,
                "This is the recursion with F_k in place of F_k (I - K_k H_k): "
                "the signature filter runs on the closed-loop predictor.",
            ),
        ),
        one_call=_SIGNATURE,
    ),
    "sig-3": Reference(
        _sig3_ref,
        (
            Mistake(
                _sig3_no_fk,
                "This ignores the term -F_k K_k Phi_k of Proposition 2: the filter "
                "partly absorbs a sensor bias into its state estimate.",
            ),
        ),
        one_call=_SIGNATURE,
    ),
    "sig-4": Reference(
        _sig4_ref,
        (
            Mistake(
                _sig4_open_loop,
                "This uses (I - F)^{-1}: the steady state of the signature "
                "filter involves the closed-loop matrix A = F (I - K H).",
            ),
        ),
        one_call=_SIGNATURE,
    ),
    "sig-5": Reference(
        lambda d: _sig5_slope(d, np.log10),
        (
            Mistake(
                lambda d: _sig5_slope(d, np.log),
                "This is the slope of the natural logarithm; the figure uses log10.",
            ),
        ),
    ),
}
