"""Exercises of "Fault signature on the Kalman innovation" (zb2014/signature): statements and data.

A student's variant (``rng`` given) keeps the structure of the book's data and draws the
numbers: the unstable example with another noise level (``R``), another initial state and
measurements, another bias profile.
"""

from __future__ import annotations

import numpy as np

from fdi_lib.exercises._core import Exercise, rounded_normal, uniform

CHAPTER = "zb2014/signature"


def unstable_model(n_steps: int, rng: np.random.Generator | None):
    """The unstable example of Section 6.1 (``rng`` given: ``F`` scaled by a factor in [1.01, 1.1]
    and the measurement noise ``R`` by a factor in [0.5, 2], drawn on a continuum (not rounded:
    the data are a model, not numbers to type), so the gains and the growth rate differ between
    classmates)."""
    from fdi_lib.models import ltv_model
    from fdi_lib.systems import zb2014_unstable as ex

    if rng is None:
        return ex.unstable_model(n_steps)
    F = rng.uniform(1.01, 1.1) * ex.F
    R = rng.uniform(0.5, 2.0) * ex.R
    return ltv_model(F=F, G=ex.G, H=ex.H, Q=ex.Q, R=R, n_steps=n_steps, P0=ex.Q)


def _sig1_data(rng):
    from fdi_lib.systems import zb2014_unstable as ex

    x0, y = np.array([0.05, 0.1]), np.array([0.12, 0.31])
    if rng is not None:
        x0, y = rounded_normal(rng, 2, 0.1), np.round(y + rounded_normal(rng, 2, 0.1), 2)
    return {
        "F": ex.F.copy(),
        "H": ex.H.copy(),
        "Q": ex.Q.copy(),
        "R": ex.R.copy(),
        "P0": ex.Q.copy(),
        "x0": x0,
        "y": y,
    }


def _sig2_data(rng):
    Psi = np.eye(2) if rng is None else np.eye(2) + rounded_normal(rng, (2, 2), 0.3, 1)
    return {"model": unstable_model(4, rng), "Psi": Psi, "k": 3}


def _sig3_data(rng):
    Phi = np.ones((1, 1)) if rng is None else np.array([[uniform(rng, 1.1, 2.0)]])
    return {"model": unstable_model(5, rng), "Phi": Phi, "k_max": 4}


def _sig4_data(rng):
    return {"model": unstable_model(500, rng), "Psi": np.eye(2)}


def _sig5_data(rng):
    return {"model": unstable_model(500, rng), "onset": 101, "k_first": 300, "k_last": 499}


EXERCISES = [
    Exercise(
        "sig-1",
        CHAPTER,
        "Kalman innovation by hand",
        "warm-up",
        10,
        answer="array of shape (2,): [eps_0, eps_1]",
        rtol=1e-9,
        data=_sig1_data,
    ),
    Exercise(
        "sig-2",
        CHAPTER,
        "The signature recursion for a constant bias",
        "warm-up",
        10,
        answer="array of shape (2, 2): Gamma_3",
        rtol=1e-9,
        data=_sig2_data,
        time_keys=("k",),
    ),
    Exercise(
        "sig-3",
        CHAPTER,
        "A sensor bias",
        "core",
        15,
        answer="array of shape (5,): H_k Gamma_k + Phi_k for k = 0..4",
        rtol=1e-9,
        data=_sig3_data,
    ),
    Exercise(
        "sig-4",
        CHAPTER,
        "What one sensor sees of two faults",
        "core",
        15,
        answer="array of shape (2,): the steady-state row vector v",
        rtol=1e-6,
        data=_sig4_data,
    ),
    Exercise(
        "sig-5",
        CHAPTER,
        "How fast the Willsky-Jones matrix grows",
        "core",
        10,
        answer="a number: the slope of log10 ||alpha_k(101)|| per sample",
        rtol=1e-4,
        data=_sig5_data,
    ),
    Exercise("sig-6", CHAPTER, "The identity with the wrong gains", "challenge", 25),
]
