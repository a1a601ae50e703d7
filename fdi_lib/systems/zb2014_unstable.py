r"""The unstable example of Zhang & Basseville (2014), Section 6.1, eqs. (51)-(52).

.. math::

    \begin{aligned}
    X_{k+1} &= \begin{bmatrix} 0.5 & 1 \\ 0 & 1.2 \end{bmatrix} X_k
        + \begin{bmatrix} 0 \\ 1 \end{bmatrix} U_k + W_k + \delta_{r,k+1} \theta, \\
    Y_k &= \begin{bmatrix} 1 & 0 \end{bmatrix} X_k + V_k,
    \qquad Q = 0.0025\, I, \quad R = 0.0025, \quad T_s = 1\ \mathrm{s},
    \end{aligned}

closed by the PI controller ``C(z) = 0.209 + 0.0011 / (z - 1)`` with set-point 1.

Choices the paper leaves open (documented in the book):

* The paper quotes an unstable eigenvalue 1.2808, but the printed (triangular)
  matrix has eigenvalues 0.5 and 1.2. We use the printed matrix (see
  :data:`QUOTED_UNSTABLE_EIGENVALUE`); the point of the example, an unstable
  ``F``, holds either way.
* The OCR reads the controller as "0.209 + 0.0011/z - 1"; we read the usual PI form
  ``kp + ki / (z - 1)`` with ``kp = 0.209``, ``ki = 0.0011`` acting on ``1 - Y_k``.
* Initial state: ``X_0 ~ N(0, P_0)`` with ``P_0 = Q`` (state known at start up to
  the process-noise level); the Kalman filter starts from the same ``P_0``.
* Horizon ``N = 500`` samples (the figures show onsets up to 301 and a window of 100).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from fdi_lib.models import LTVModel, ltv_model
from fdi_lib.simulate import pi_controller

__all__ = [
    "F",
    "G",
    "H",
    "Q",
    "R",
    "KP",
    "KI",
    "SETPOINT",
    "N_STEPS",
    "QUOTED_UNSTABLE_EIGENVALUE",
    "unstable_model",
    "controller",
]

F = np.array([[0.5, 1.0], [0.0, 1.2]])
G = np.array([[0.0], [1.0]])
H = np.array([[1.0, 0.0]])
Q = 0.0025 * np.eye(2)
R = np.array([[0.0025]])
KP, KI, SETPOINT = 0.209, 0.0011, 1.0
N_STEPS = 500
#: The eigenvalue quoted in the text, which the printed matrix does not have.
QUOTED_UNSTABLE_EIGENVALUE = 1.2808


def unstable_model(n_steps: int = N_STEPS) -> LTVModel:
    """The fault-free model (51)-(52) on ``n_steps`` samples (``P_0 = Q``)."""
    return ltv_model(F=F, G=G, H=H, Q=Q, R=R, n_steps=n_steps, P0=Q)


def controller() -> Callable[[int, np.ndarray], np.ndarray]:
    """A fresh PI controller of Section 6.1 (state starts at zero)."""
    return pi_controller(KP, KI, SETPOINT)
