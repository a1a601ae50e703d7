r"""Example 1 of Zhang (2021), eqs. (40)-(42): a 3-state LTV system with an unknown input.

.. math::

    X_{k+1} = A_k X_k + E d_k + W_k + \Psi_k \theta, \qquad Y_k = C X_k + V_k,

.. math::

    A_k = \begin{bmatrix} -0.8 & 0.7 & 0.1 e^{-k} \\ -0.6 & 0 & 0.1 \cos k \\
        0.1 \sin k & -0.5 & -0.4 \end{bmatrix}, \qquad
    C = \begin{bmatrix} 1 & 0 & 0 \\ 0 & 0 & 1 \end{bmatrix}, \qquad
    E = \begin{bmatrix} -1 \\ 0 \\ 0 \end{bmatrix},

.. math::

    \begin{aligned}
    Q &= I_3, & R &= r I_2 \ (r = 0.5), \\
    d_k &= 10 \sin(0.1 k) + \epsilon_k + 100, & \epsilon_k &\sim \mathcal N(0, 1) \text{ white},
    \end{aligned}

:math:`\Psi_k` (the paper's :math:`\Phi_k`, 3 x 50) has i.i.d. entries uniform on ``[-17.3, 17.3]``,
drawn anew in every trial; ``theta`` has ``q`` components equal to 1 at random positions.
Data ``k = 1 .. N`` with ``N = 100`` are used (the model horizon is ``N + 1`` steps,
``k = 0 .. N``). Not stated in the paper, our choices: ``X_0 ~ N(0, I_3)`` (so the filter's
``x0 = 0``, ``P0 = I_3`` are exact), and the known input ``B u = 0`` is omitted as in the paper.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdi_lib.errors import ModelError
from fdi_lib.models import LTVModel, ltv_model
from fdi_lib.simulate import Noise, noise_from_standard, simulate

__all__ = [
    "N_DATA",
    "N_PARAMS",
    "PSI_HALF_WIDTH",
    "E",
    "C",
    "state_matrices",
    "example1_model",
    "Example1Trial",
    "draw_trial",
    "draw_trials",
    "simulate_trials",
]

N_DATA = 100
N_PARAMS = 50
PSI_HALF_WIDTH = 17.3
E = np.array([[-1.0], [0.0], [0.0]])
C = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def state_matrices(n_steps: int) -> np.ndarray:
    """``A_k`` of eq. (41) for ``k = 0 .. n_steps-1``, shape ``(n_steps, 3, 3)``."""
    k = np.arange(n_steps, dtype=float)
    A = np.zeros((n_steps, 3, 3))
    A[:, 0, 0], A[:, 0, 1], A[:, 0, 2] = -0.8, 0.7, 0.1 * np.exp(-k)
    A[:, 1, 0], A[:, 1, 2] = -0.6, 0.1 * np.cos(k)
    A[:, 2, 0], A[:, 2, 1], A[:, 2, 2] = 0.1 * np.sin(k), -0.5, -0.4
    return A


def example1_model(*, r: float = 0.5, n_data: int = N_DATA) -> LTVModel:
    """The fault-free model (40)-(42) (no unknown-input term) on ``k = 0 .. n_data``.

    Parameters
    ----------
    r : float
        Output-noise factor, ``R = r I_2`` (Table II); 0.5 elsewhere.
    n_data : int
        ``N``; the horizon has ``N + 1`` steps.
    """
    if not np.isfinite(r) or r <= 0:
        raise ModelError(f"r: expected a positive noise factor, got {r!r}")
    n = int(n_data) + 1
    return ltv_model(
        F=state_matrices(n),
        H=C,
        Q=np.eye(3),
        R=r * np.eye(2),
        n_steps=n,
        x0=np.zeros(3),
        P0=np.eye(3),
    )


@dataclass(frozen=True)
class Example1Trial:
    """Random ingredients of trials (leading axis: trials).

    Attributes
    ----------
    Psi : numpy.ndarray
        ``(B, N+1, 3, m)`` uniform on ``[-17.3, 17.3]``.
    theta : numpy.ndarray
        ``(B, m)``, ``q`` ones.
    d : numpy.ndarray
        Unknown input ``(B, N+1, 1)``.
    noise : Noise
        ``X_0``, ``W_k``, ``V_k``.
    """

    Psi: np.ndarray
    theta: np.ndarray
    d: np.ndarray
    noise: Noise

    @property
    def support(self) -> list[np.ndarray]:
        return [np.flatnonzero(t) for t in self.theta]


def draw_trial(
    model: LTVModel, rng: np.random.Generator, *, q: int, m: int = N_PARAMS
) -> Example1Trial:
    """Draw one trial (batch of 1): support of ``theta``, ``Psi_k``, ``d_k`` and the noise, in that order."""
    return draw_trials(model, [rng], q=q, m=m)


def draw_trials(
    model: LTVModel, rngs: list[np.random.Generator], *, q: int, m: int = N_PARAMS
) -> Example1Trial:
    """One trial per generator, stacked: trial ``i`` depends on ``rngs[i]`` only.

    Each generator draws, in this order, the support of ``theta`` (``q`` of ``m`` components,
    without replacement), ``Psi_k`` (uniform on ``[-17.3, 17.3]``), the white part ``eps_k`` of
    ``d_k`` and the noise (the standard normal draws of :func:`fdi_lib.simulate.draw_noise`). The
    loop over generators only draws, into preallocated arrays; the noise covariance roots are
    applied to the whole batch (:func:`fdi_lib.simulate.noise_from_standard`). The covariances of
    Example 1 are multiples of the identity, whose roots are diagonal: each trial is then bit for
    bit the one its generator gives alone (:func:`draw_trial`, or ``draw_noise`` for the noise).
    """
    if isinstance(q, bool) or not isinstance(q, (int, np.integer)) or not 0 <= q <= m:
        raise ModelError(f"q: expected an integer in [0, {m}], got {q!r}")
    N, n, p, B = model.n_steps, model.n, model.p, len(rngs)
    theta = np.zeros((B, m))
    Psi = np.empty((B, N, 3, m))  # each trial's draws contiguous, scaled while in cache
    eps = np.empty((B, N))
    z0, zw, zv = np.empty((B, n)), np.empty((B, N, n)), np.empty((B, N, p))
    span = PSI_HALF_WIDTH - (-PSI_HALF_WIDTH)
    for b, rng in enumerate(rngs):
        theta[b, rng.choice(m, size=int(q), replace=False)] = 1.0
        P = Psi[b]
        # rng.uniform(low, high) is low + (high - low) U for these U, bit for bit:
        rng.random(out=P)
        P *= span
        P += -PSI_HALF_WIDTH
        rng.standard_normal(out=eps[b])
        for z in (z0[b], zw[b], zv[b]):  # the draws of fdi_lib.simulate.draw_noise, in its order
            rng.standard_normal(out=z)
    d = 10.0 * np.sin(0.1 * np.arange(N)) + eps + 100.0
    return Example1Trial(
        Psi=Psi,
        theta=theta,
        d=d[:, :, None],
        noise=noise_from_standard(model, z0, zw, zv),
    )


def simulate_trials(
    model: LTVModel, trials: Example1Trial, *, theta_scale: float = 1.0
) -> np.ndarray:
    """Outputs ``Y_k`` of (40), shape ``(B, N+1, 2)``, vectorised over trials.

    :func:`fdi_lib.simulate.simulate` does the recursion: the unknown input and the
    per-trial fault term enter as extra "inputs" ``[d_k, Psi_k theta]`` with input matrix
    ``[E, I_3]`` (the filters never see them).
    """
    N = model.n_steps
    fault = np.einsum("bkim,bm->bki", trials.Psi, theta_scale * trials.theta)
    G = np.concatenate([E, np.eye(3)], axis=1)
    sim_model = ltv_model(
        F=model.F, G=G, H=model.H, Q=model.Q, R=model.R, n_steps=N, x0=model.x0, P0=model.P0
    )
    u = np.concatenate([trials.d, fault], axis=2)
    return simulate(sim_model, noise=trials.noise, u=u).y
