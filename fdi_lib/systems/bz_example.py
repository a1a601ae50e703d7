r"""Designed example for Basseville & Zhang (parametric and non-parametric faults).

The paper has no numerical example; this one extends the unstable system of
Zhang & Basseville (2014), Section 6.1 (:mod:`fdi_lib.systems.zb2014_unstable`):

.. math::

    \begin{aligned}
    X_{k+1} &= F_k X_k + G U_k + W_k + E f_k + \Psi \theta_k, \\
    Y_k &= X_k + V_k \qquad (H = I_3),
    \end{aligned}

.. math::

    F_k = \begin{bmatrix} a_k & 1 & 0 \\ 0 & 1.2 & 0 \\ 0 & 0.3 & 0.8 \end{bmatrix}, \qquad
    a_k = 0.5 + 0.1 \sin(2\pi k / 60),

.. math::

    G = \begin{bmatrix} 0 \\ 1 \\ 0 \end{bmatrix}, \quad
    E = \begin{bmatrix} 1 \\ 0 \\ 0 \end{bmatrix}, \quad
    \Psi = \begin{bmatrix} 0 & 0 \\ 1 & 0 \\ 0 & 1 \end{bmatrix},

.. math::

    Q = 0.0025\, I_3, \quad R = 0.0025\, I_3, \quad P_0 = Q,

closed by the PI controller of Section 6.1 on :math:`Y^{(1)}` (set-point 1).

Every choice, and why:

* **States 1-2** are the Section 6.1 system (with its printed matrix, eigenvalues
  0.5 and 1.2, unstable). The entry ``a_k`` oscillates by +-0.1 around the printed
  0.5 so that the model is genuinely time varying (LTV) while the closed loop
  stays stable.
* **State 3** (stable pole 0.8, driven by ``x_2``) is added so that the parametric
  fault can have two components (``m = 2``) that the minmax test can isolate.
* **All three states are measured** (``H = I_3``): the Kitanidis filter rejects
  ``E f_k`` by spending ``q = dim f = 1`` output direction, so detecting a
  two-component parametric fault needs ``p >= q + m = 3``. ``H E = e_1`` has full
  column rank, as the Kitanidis filter requires.
* **Non-parametric fault** ``E f_k`` enters the first state (a disturbance on the
  fast state with no model at all). Default profile: a sinusoid of amplitude
  ``size`` and period 25 samples switched on at ``onset_f``
  (:func:`nonparametric_profile`); any other profile can be used.
* **Parametric fault** ``Psi theta_k``: ``theta^(1)`` is an additive actuator fault
  (same channel as ``U``), ``theta^(2)`` a fault on the third state. Solution 1 uses
  a jump (eq. 4 of Zhang & Basseville 2014); solution 2 a slow ramp with increment
  ``|e_k| <= delta`` (eqs. 20-21), see :func:`parametric_path`.
* Noise levels, ``P_0`` and the controller are those of Section 6.1.
* Horizon ``N = 400`` samples (long enough for the onsets 150-250 used below).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from fdi_lib.errors import ModelError
from fdi_lib.models import LTVModel, ltv_model
from fdi_lib.simulate import pi_controller
from fdi_lib.systems.zb2014_unstable import KI, KP, SETPOINT

__all__ = [
    "N_STEPS",
    "G",
    "H",
    "E",
    "PSI",
    "Q",
    "R",
    "F_k",
    "bz_model",
    "controller",
    "nonparametric_profile",
    "parametric_path",
    "drift_path",
    "DRIFT_DIRECTION",
    "state_disturbance",
]

N_STEPS = 400
G = np.array([[0.0], [1.0], [0.0]])
H = np.eye(3)
#: Incidence matrix of the non-parametric fault ``E f_k`` (``n x q``, ``q = 1``).
E = np.array([[1.0], [0.0], [0.0]])
#: Profile matrix of the parametric fault ``Psi theta_k`` (``n x m``, ``m = 2``).
PSI = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
Q = 0.0025 * np.eye(3)
R = 0.0025 * np.eye(3)
#: Period (samples) of the default sinusoidal non-parametric fault.
F_PERIOD = 25


def F_k(k: int) -> np.ndarray:
    """The state matrix at step ``k`` (``a_k = 0.5 + 0.1 sin(2 pi k / 60)``)."""
    a = 0.5 + 0.1 * np.sin(2.0 * np.pi * k / 60.0)
    return np.array([[a, 1.0, 0.0], [0.0, 1.2, 0.0], [0.0, 0.3, 0.8]])


def bz_model(n_steps: int = N_STEPS) -> LTVModel:
    """The fault-free LTV model (``P_0 = Q``) on ``n_steps`` samples."""
    if not isinstance(n_steps, (int, np.integer)) or n_steps < 2:
        raise ModelError(f"n_steps: expected an integer >= 2, got {n_steps!r}")
    return ltv_model(F=F_k, G=G, H=H, Q=Q, R=R, n_steps=int(n_steps), P0=Q)


def controller() -> Callable[[int, np.ndarray], np.ndarray]:
    """A fresh PI controller of Zhang & Basseville (2014), Section 6.1, acting on ``Y^(1)``."""
    return pi_controller(KP, KI, SETPOINT)


def nonparametric_profile(
    n_steps: int, *, size: float, onset: int, period: float = F_PERIOD
) -> np.ndarray:
    """``f_k = size * sin(2 pi (k - onset) / period) 1{k >= onset}``, shape ``(n_steps, 1)``.

    Any bounded signal would do: the point of a non-parametric fault is that the
    detectors never use its shape.
    """
    if period <= 0:
        raise ModelError(f"period: expected a positive number of samples, got {period!r}")
    k = np.arange(n_steps)
    return (size * np.sin(2.0 * np.pi * (k - onset) / period) * (k >= onset))[:, None]


def parametric_path(n_steps: int, *, theta: np.ndarray, onset: int, ramp: int = 0) -> np.ndarray:
    """``theta_k`` ``(n_steps, m)``: zero before ``onset``, then a ramp of ``ramp`` samples to ``theta``.

    ``ramp = 0`` gives the jump of solution 1; ``ramp > 0`` a slowly varying fault
    with increments ``|e_k| = |theta| / ramp`` (eq. 21's ``delta``) during the ramp.
    """
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    if ramp < 0:
        raise ModelError(f"ramp: expected a non-negative number of samples, got {ramp!r}")
    k = np.arange(n_steps)
    frac = np.clip((k - onset + 1) / ramp, 0.0, 1.0) if ramp > 0 else (k >= onset).astype(float)
    return frac[:, None] * theta[None, :]


#: Direction of the slow drift of solution 2 (both components move, at different speeds).
DRIFT_DIRECTION = np.array([1.0, -0.5])


def drift_path(
    n_steps: int, *, delta: float, onset: int, direction: np.ndarray = DRIFT_DIRECTION
) -> np.ndarray:
    """Slowly varying ``theta_k = delta (k - onset)_+ d / ||d||_inf``, shape ``(n_steps, m)``.

    The increments satisfy ``||e_k||_inf = delta`` after ``onset`` (eqs. 20-21 with the
    infinity norm), zero before.
    """
    d = np.asarray(direction, dtype=float)
    if delta < 0:
        raise ModelError(f"delta: expected a non-negative drift speed, got {delta!r}")
    k = np.arange(n_steps)
    return delta * np.maximum(k - onset, 0)[:, None] * (d / np.abs(d).max())[None, :]


def state_disturbance(f: np.ndarray, theta_path: np.ndarray) -> np.ndarray:
    """Total additive state fault ``E f_k + Psi theta_k``, shape ``(N, n, 1)``.

    Passed to :func:`fdi_lib.simulate.simulate` as a one-column profile with ``theta = [1]``.
    """
    d = np.asarray(f, dtype=float) @ E.T + np.asarray(theta_path, dtype=float) @ PSI.T
    return d[:, :, None]
