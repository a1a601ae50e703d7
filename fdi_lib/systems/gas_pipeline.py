"""Surrogate LPV model of the gas pipeline of Zhang & Basseville (2014), Section 6.2, eq. (53).

::

    X_{k+1} = (F0 + Fp p_k) X_k + (G0 + Gp p_k) U_k + W_k        W_k ~ N(0, Q)
    Y_k     = (H0 + Hp p_k) X_k + (J0 + Jp p_k) U_k + V_k        V_k ~ N(0, R)

``U_k`` is the input mass flow, ``Y_k`` the output mass flow (Nm3/h: the paper
prints "Nm3"), ``X_k`` two states (mass flow and pressure drop in the first pipe
section, in the arbitrary basis of an identified model), ``p_k`` the pressure
(scheduling parameter, here in MPa), sampling period ``Ts = 2 min``.

**This is a surrogate.** The identified matrices, the pressure record and the
input record of Lopes dos Santos et al. (2011) are not public. We keep every
value the papers state and choose the others by explicit criteria:

Stated values, kept exactly
    ``G0(1) = -7.8297e-4``, ``Gp(1) = +3.8290e-5``; ``Q`` and ``R`` of Section 6.2;
    ``Ts = 2 min``; a record of 1000 min (``N = 500`` samples); the faults of
    Table 1 at 600 min; the output leak of ``-43980`` at 700 min, 10 % of the mean
    output flow, hence a mean flow of 439800.

``Q`` (projected)
    The printed ``Q`` is symmetric but, rounded to four decimals, very slightly
    indefinite (``det Q < 0``, smallest eigenvalue about ``-2.5e-5``), which
    :func:`fdi_lib.models.ltv_model` rightly rejects. :func:`projected_q` returns the
    nearest symmetric PSD matrix in Frobenius norm (eigenvalue clipping, Higham
    1988): a rank-one matrix that differs from the printed one by ``2.5e-5``.

``G0(2)``, ``Gp(2)``: criterion "``Q`` is rank one"
    A rank-one ``Q = q q^T`` with ``q`` proportional to ``[1, Q12/Q11]`` is what an
    identified model produces when the state noise is an error on the measured
    input flow passing through ``G``. We therefore take ``G(2) = (Q12/Q11) G(1)``
    for both ``G0`` and ``Gp`` (the input and its noise enter along one direction).

``F0``, ``Fp = 0``: criteria "stable for every pressure" and "physical time constants"
    ``F`` lower triangular and constant, with time constants of 10 min (flow in the
    first section) and 400 min (line pack, hours in transmission pipelines), and a
    coupling ``F(2,1) = 0.3`` from the flow to the pressure drop. A constant ``F``
    is stable whatever the schedule. The coupling is chosen so that the
    input-end faults of Table 1 stay "hardly visible" on the innovation, as the
    paper states: their steady effect on the innovation is below two standard
    deviations (see :func:`design_report`).

``H0``, ``Hp = 0``: criterion "both noise sources visible"
    The outlet flow is read through the pressure drop, ``H = [0, h2]``, with ``h2``
    such that the stationary output variance due to ``W`` equals ``R`` at the
    nominal pressure (an identification method only separates ``Q`` from ``R``
    when both are visible at the output). The sign of ``h2`` makes a depression
    of ``G(1)`` *reduce* the steady outlet flow, so that it is a leak.

``J0``, ``Jp``: criterion "mass balance"
    ``J(p) = 1 - H (I - F)^{-1} G(p)`` is affine in ``p`` (``F``, ``H`` constant), so
    ``J0 = 1 - H (I-F)^{-1} G0`` and ``Jp = -H (I-F)^{-1} Gp`` make the steady-state
    gain from input to output flow exactly one at every frozen pressure.
    Consequence, and a known imperfection of the surrogate: ``J(p)`` is about 1.6,
    so an input step first over-shoots at the outlet and then relaxes through the
    line pack. With ``H = [0, h2]``, ``J < 1`` needs ``F(2,1) < 0.12``, which makes
    fault 1 a step of about 4.5 innovation standard deviations, clearly visible,
    against the paper's statement; we kept the paper's statement.

Pressure ``p_k`` and input ``U_k``: criterion "a daily pattern"
    The record starts at 06:00 of the second day. Demand has a morning and an
    evening peak; the input flow follows it (:func:`pipeline_input`, +-12 %,
    scaled so that the mean noise-free *output* flow over the record is exactly
    439800); the pressure is high at
    night and drawn down in the afternoon (:func:`pipeline_schedule`,
    5.5 +- 0.6 MPa, i.e. 49 to 61 bar).

Initial state: ``X_0`` has mean the steady state for ``U_0``, ``p_0`` and covariance
the stationary Kalman prediction covariance (``F``, ``H``, ``Q``, ``R`` are constant,
so the Kalman filter is stationary from ``k = 0``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.models import FaultFamily, LTVModel, lpv_model, step_family
from fdi_lib.simulate import Noise, simulate

__all__ = [
    "TS_MIN", "RECORD_MIN", "N_STEPS", "G0_1", "GP_1", "Q_PRINTED", "R", "MEAN_FLOW",
    "FAULT_ONSET_MIN", "FAULT1_DELTA", "FAULT2_DELTA", "FAULT1_DOUBLED_DELTA",
    "LEAK_ONSET_MIN", "LEAK_SIZE", "WINDOW", "THRESHOLD", "DISABLED_MIN",
    "projected_q", "pipeline_schedule", "pipeline_input", "PipelineMatrices", "pipeline_matrices",
    "pipeline_model", "input_fault_psi", "input_fault_family", "output_leak_family",
    "minutes_to_index", "index_to_minutes", "design_report", "noise_free_output",
]

#: Sampling period (min).
TS_MIN = 2.0
#: Record length (min) and number of samples.
RECORD_MIN = 1000.0
N_STEPS = 500
#: Stated nominal values (Table 1).
G0_1 = -7.8297e-4
GP_1 = +3.8290e-5
#: Noise covariances as printed in Section 6.2 (``Q_PRINTED`` is slightly indefinite, see :func:`projected_q`).
Q_PRINTED = np.array([[100.2766, -66.1165], [-66.1165, 43.5933]])
R = np.array([[3.0273e5]])
#: Output leak of -43980, "10 % of the average output mass flow".
LEAK_SIZE = -43980.0
MEAN_FLOW = 439800.0
#: Faults of Table 1 (increments of G0(1), Gp(1)) and of Fig 6, onset 600 min.
FAULT_ONSET_MIN = 600.0
FAULT1_DELTA = -2e-5
FAULT2_DELTA = -1e-5
FAULT1_DOUBLED_DELTA = -4e-5
LEAK_ONSET_MIN = 700.0
#: GLR settings of Section 6.2: window w = 160 samples, threshold 50, disabled for 320 min.
WINDOW = 160
THRESHOLD = 50.0
DISABLED_MIN = 320.0

#: Surrogate choices (see the module docstring).
NOMINAL_PRESSURE = 5.5          # MPa
PRESSURE_SWING = 0.6            # MPa
FLOW_SWING = 0.12               # relative, daily harmonic
FLOW_SWING_2 = 0.05             # relative, half-day harmonic
START_HOUR = 6.0                # the record starts at 06:00
TAU_FLOW_MIN = 10.0
TAU_LINEPACK_MIN = 400.0
COUPLING = 0.3


def minutes_to_index(minutes: float) -> int:
    """Sample index ``k`` of a time in minutes (``t = k Ts``); must fall on a sample."""
    k = minutes / TS_MIN
    if not np.isclose(k, round(k)):
        raise ModelError(f"minutes: expected a multiple of Ts = {TS_MIN} min, got {minutes!r}")
    return int(round(k))


def index_to_minutes(k: np.ndarray | int) -> np.ndarray:
    """Time in minutes of sample index ``k`` (``-1``, "no alarm", maps to ``nan``)."""
    k = np.asarray(k)
    return np.where(k >= 0, k * TS_MIN, np.nan)


def projected_q(Q: np.ndarray = Q_PRINTED) -> np.ndarray:
    """Nearest symmetric PSD matrix to ``Q`` in Frobenius norm (eigenvalue clipping).

    Parameters
    ----------
    Q : numpy.ndarray
        Symmetric matrix ``(n, n)``; default the printed ``Q`` of Section 6.2.

    Returns
    -------
    numpy.ndarray
        ``V max(Lambda, 0) V^T`` (Higham 1988), exactly symmetric.
    """
    Q = np.asarray(Q, dtype=float)
    if Q.ndim != 2 or Q.shape[0] != Q.shape[1]:
        raise ShapeError(f"Q: expected a square matrix, got shape {Q.shape}")
    lam, V = np.linalg.eigh(0.5 * (Q + Q.T))
    out = (V * np.clip(lam, 0.0, None)) @ V.T
    return 0.5 * (out + out.T)


def _hours(n_steps: int) -> np.ndarray:
    return START_HOUR + np.arange(n_steps) * TS_MIN / 60.0


def pipeline_schedule(n_steps: int = N_STEPS, *, fast_swing: float = 0.0,
                      fast_period_min: float = 60.0) -> np.ndarray:
    """Pressure schedule ``p_k`` (MPa), shape ``(n_steps,)``.

    ``p_k = 5.5 + 0.6 cos(2 pi (h_k - 3) / 24)`` with ``h_k`` the hour of day
    (record from 06:00): highest at 03:00 when the line pack is refilled, lowest
    at 15:00 after the daytime draw-down.

    Parameters
    ----------
    n_steps : int
        Number of samples.
    fast_swing : float
        Amplitude (MPa) of an optional faster oscillation ``fast_swing sin(2 pi t / fast_period_min)``
        (default 0: the surrogate's schedule). Used to study how the variation of ``p_k``
        within an hour or two governs fault isolation.
    fast_period_min : float
        Its period in minutes (> 0).
    """
    _check_steps(n_steps)
    if not fast_period_min > 0:
        raise ModelError(f"fast_period_min: expected a positive number, got {fast_period_min!r}")
    t_min = np.arange(n_steps) * TS_MIN
    return (NOMINAL_PRESSURE + PRESSURE_SWING * np.cos(2 * np.pi * (_hours(n_steps) - 3.0) / 24.0)
            + fast_swing * np.sin(2 * np.pi * t_min / fast_period_min))


def pipeline_input(n_steps: int = N_STEPS) -> np.ndarray:
    """Input mass flow ``U_k`` (Nm3/h), shape ``(n_steps,)``: a daily demand pattern.

    A daily harmonic peaking at 09:00 (+-12 %) and a half-day harmonic peaking at
    07:00 and 19:00 (+-5 %), rescaled so that the mean of the noise-free *output*
    flow over the record is exactly ``MEAN_FLOW = 439800`` (the paper: the leak of
    43980 is 10 % of the average output flow). The model is linear in ``U`` (the
    initial state is the steady state of ``U_0``), so one noise-free run fixes the scale.
    """
    _check_steps(n_steps)
    h = _hours(n_steps)
    shape = (1.0 + FLOW_SWING * np.cos(2 * np.pi * (h - 9.0) / 24.0)
             + FLOW_SWING_2 * np.cos(4 * np.pi * (h - 7.0) / 24.0))
    return MEAN_FLOW * shape / noise_free_output(shape, pipeline_schedule(n_steps)).mean()


def noise_free_output(u: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Outlet flow of the fault-free surrogate without noise, started at the steady state of ``u[0]``.

    Parameters
    ----------
    u : numpy.ndarray
        Inlet flow ``U_k``, shape ``(N,)``.
    p : numpy.ndarray
        Pressure schedule ``p_k``, shape ``(N,)``.

    Returns
    -------
    numpy.ndarray
        ``Y_k`` without noise, shape ``(N,)`` (used to scale the input to the stated mean flow).
    """
    u = np.asarray(u, dtype=float)
    model = pipeline_model(u.shape[0], schedule=p, u=u)  # x0 is the steady state of U_0, p_0
    zero = Noise(x0=model.x0, w=np.zeros((model.n_steps, model.n)), v=np.zeros((model.n_steps, model.p)))
    return simulate(model, noise=zero, u=u).y[:, 0]


def _check_steps(n_steps: int) -> None:
    if not isinstance(n_steps, (int, np.integer)) or n_steps < 1:
        raise ModelError(f"n_steps: expected a positive integer, got {n_steps!r}")


@dataclass(frozen=True)
class PipelineMatrices:
    """The affine LPV matrices of eq. (53) of the surrogate (all ``(rows, cols)`` arrays)."""

    F0: np.ndarray
    Fp: np.ndarray
    G0: np.ndarray
    Gp: np.ndarray
    H0: np.ndarray
    Hp: np.ndarray
    J0: np.ndarray
    Jp: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    P0: np.ndarray


def pipeline_matrices() -> PipelineMatrices:
    """Compute the surrogate's matrices from the criteria of the module docstring.

    Returns
    -------
    PipelineMatrices
        ``F0`` ``(2, 2)`` (``Fp = 0``), ``G0``, ``Gp`` ``(2, 1)``, ``H0`` ``(1, 2)`` (``Hp = 0``),
        ``J0``, ``Jp`` ``(1, 1)``, the projected ``Q``, ``R`` and the stationary prediction
        covariance ``P0`` (discrete algebraic Riccati equation, solved by scipy).
    """
    Q = projected_q()
    ratio = Q_PRINTED[0, 1] / Q_PRINTED[0, 0]
    G0 = np.array([[G0_1], [ratio * G0_1]])
    Gp = np.array([[GP_1], [ratio * GP_1]])
    F0 = np.array([[np.exp(-TS_MIN / TAU_FLOW_MIN), 0.0],
                   [COUPLING, np.exp(-TS_MIN / TAU_LINEPACK_MIN)]])
    # Stationary state covariance under W alone: scipy solves the Lyapunov equation.
    X = scipy.linalg.solve_discrete_lyapunov(F0, Q)
    inv = np.linalg.inv(np.eye(2) - F0)
    h2 = np.sqrt(R[0, 0] / X[1, 1])
    # Leak sign: d(steady output)/d G(1) = H (I-F)^{-1} e1 must be > 0.
    h2 *= np.sign(inv[1, 0])
    H0 = np.array([[0.0, h2]])
    J0 = 1.0 - H0 @ inv @ G0
    Jp = -(H0 @ inv @ Gp)
    # Stationary Kalman prediction covariance (scipy's DARE solver does the hard part).
    P0 = scipy.linalg.solve_discrete_are(F0.T, H0.T, Q, R)
    P0 = 0.5 * (P0 + P0.T)
    return PipelineMatrices(F0=F0, Fp=np.zeros((2, 2)), G0=G0, Gp=Gp, H0=H0, Hp=np.zeros((1, 2)),
                            J0=J0, Jp=Jp, Q=Q, R=R.copy(), P0=P0)


def pipeline_model(n_steps: int = N_STEPS, *, schedule: np.ndarray | None = None,
                   u: np.ndarray | None = None) -> LTVModel:
    """The fault-free surrogate LPV pipeline model (53) as an :class:`~fdi_lib.models.LTVModel`.

    Parameters
    ----------
    n_steps : int
        Horizon ``N`` (default 500 = 1000 min at 2 min).
    schedule : numpy.ndarray, optional
        Pressure ``p_k`` ``(n_steps,)``; default :func:`pipeline_schedule`.
    u : numpy.ndarray, optional
        Input flow ``(n_steps,)`` used only for the initial-state mean (steady state
        for ``U_0``, ``p_0``); default :func:`pipeline_input`.

    Returns
    -------
    LTVModel
        ``n = 2``, ``l = 1``, ``p = 1``.

    Examples
    --------
    >>> m = pipeline_model()
    >>> (m.n, m.l, m.p, m.n_steps)
    (2, 1, 1, 500)
    >>> float(m.G[0, 0, 0] - 3.8290e-5 * pipeline_schedule()[0])  # G0(1)
    -0.00078297
    """
    _check_steps(n_steps)
    p = pipeline_schedule(n_steps) if schedule is None else np.asarray(schedule, dtype=float)
    if p.shape != (n_steps,):
        raise ShapeError(f"schedule: expected shape ({n_steps},), got {p.shape}")
    uu = pipeline_input(n_steps) if u is None else np.asarray(u, dtype=float)
    if uu.ndim != 1 or uu.shape[0] != n_steps:
        raise ShapeError(f"u: expected shape ({n_steps},), got {uu.shape}")
    mats = pipeline_matrices()
    G_first = mats.G0 + mats.Gp * p[0]
    x0 = np.linalg.solve(np.eye(2) - mats.F0, G_first[:, 0] * uu[0])
    return lpv_model(scheduling=p, F0=mats.F0, Fp=mats.Fp, G0=mats.G0, Gp=mats.Gp, H0=mats.H0,
                     Hp=mats.Hp, J0=mats.J0, Jp=mats.Jp, Q=mats.Q, R=mats.R, x0=x0, P0=mats.P0)


def input_fault_psi(n_steps: int = N_STEPS, *, schedule: np.ndarray | None = None,
                    u: np.ndarray | None = None) -> np.ndarray:
    """Input-end fault profile ``Psi~_k = [[U_k, p_k U_k], [0, 0]]`` of Section 6.2, ``(N, 2, 2)``.

    ``theta = [dG0(1), dGp(1)]``: the increments of ``G0(1)`` and ``Gp(1)``
    (fault 1: ``theta = [-2e-5, 0]``, fault 2: ``theta = [0, -1e-5]``).
    """
    p = pipeline_schedule(n_steps) if schedule is None else np.asarray(schedule, dtype=float)
    uu = pipeline_input(n_steps) if u is None else np.asarray(u, dtype=float)
    if p.shape != (n_steps,) or uu.shape != (n_steps,):
        raise ShapeError(f"schedule, u: expected shape ({n_steps},), got {p.shape} and {uu.shape}")
    psi = np.zeros((n_steps, 2, 2))
    psi[:, 0, 0] = uu
    psi[:, 0, 1] = p * uu
    return psi


def input_fault_family(model: LTVModel, *, schedule: np.ndarray | None = None,
                       u: np.ndarray | None = None) -> FaultFamily:
    """Step family (eq. 4) of the input-end leaks: ``Psi_k(r) = Psi~_k 1{k >= r}``, ``m = 2``."""
    return step_family(model, Psi=input_fault_psi(model.n_steps, schedule=schedule, u=u))


def output_leak_family(model: LTVModel) -> FaultFamily:
    """Step family of the output-end leak: ``Phi_k(r) = 1{k >= r}`` (``m = 1``, ``theta`` = leak size)."""
    return step_family(model, Phi=np.ones((model.p, 1)))


def design_report(model: LTVModel | None = None) -> dict[str, float]:
    """Numbers that check the surrogate's design criteria (used by the tests and the book).

    Returns
    -------
    dict
        ``eig_F`` (largest modulus of the eigenvalues of ``F``), ``dc_gain_min``/``max``
        (steady input-to-output gain over the schedule, should be 1),
        ``J_min``/``J_max``, ``leak_gain`` (``H (I-F)^{-1} e1``, > 0 for a leak),
        ``output_std_from_W`` and ``sqrt_R``, ``sqrt_Sigma`` (stationary innovation
        standard deviation), ``fault1_leak_fraction``/``fault2_leak_fraction``
        (steady outlet flow lost / mean flow), ``fault1_innovation_shift_sd``
        (stationary innovation mean of fault 1 in innovation standard deviations),
        ``q_min_eig_printed``.
    """
    mats = pipeline_matrices()
    p = pipeline_schedule()
    inv = np.linalg.inv(np.eye(2) - mats.F0)
    G = mats.G0[None] + mats.Gp[None] * p[:, None, None]
    J = mats.J0[None] + mats.Jp[None] * p[:, None, None]
    dc = (mats.H0 @ inv @ G + J)[:, 0, 0]
    X = scipy.linalg.solve_discrete_lyapunov(mats.F0, mats.Q)
    Sigma = float((mats.H0 @ mats.P0 @ mats.H0.T + mats.R)[0, 0])
    K = mats.P0 @ mats.H0.T / Sigma
    A = mats.F0 @ (np.eye(2) - K @ mats.H0)
    leak_gain = float((mats.H0 @ inv)[0, 0])
    shift = mats.H0 @ np.linalg.solve(np.eye(2) - A, np.array([MEAN_FLOW * FAULT1_DELTA, 0.0]))
    return {
        "eig_F": float(np.max(np.abs(np.linalg.eigvals(mats.F0)))),
        "dc_gain_min": float(dc.min()), "dc_gain_max": float(dc.max()),
        "J_min": float(J.min()), "J_max": float(J.max()),
        "leak_gain": leak_gain,
        "output_std_from_W": float(np.sqrt(mats.H0 @ X @ mats.H0.T)[0, 0]),
        "sqrt_R": float(np.sqrt(mats.R[0, 0])),
        "sqrt_Sigma": float(np.sqrt(Sigma)),
        "fault1_leak_fraction": float(-leak_gain * FAULT1_DELTA),
        "fault2_leak_fraction": float(-leak_gain * FAULT2_DELTA * NOMINAL_PRESSURE),
        "fault1_innovation_shift_sd": float(shift[0] / np.sqrt(Sigma)),
        "q_min_eig_printed": float(np.linalg.eigvalsh(Q_PRINTED)[0]),
    }
