r"""Surrogate LPV models of the gas pipeline of Zhang & Basseville (2014), Section 6.2, eq. (53).

.. math::

    \begin{aligned}
    X_{k+1} &= (F_0 + F_p p_k) X_k + (G_0 + G_p p_k) U_k + W_k, & W_k &\sim \mathcal N(0, Q), \\
    Y_k &= (H_0 + H_p p_k) X_k + (J_0 + J_p p_k) U_k + V_k, & V_k &\sim \mathcal N(0, R).
    \end{aligned}

``U_k`` is the input mass flow and ``Y_k`` the output mass flow (Nm3/h: the paper
prints "Nm3"; a normal cubic metre is a quantity of gas, proportional to its mass), ``X_k`` the mass flow and the
pressure drop in the first pipe section, ``p_k`` the scheduling parameter, sampling
period ``Ts = 2 min``. The identified matrices, the pressure record and the input
record of Lopes dos Santos et al. (IEEE TCST 19(1), 2011) are not public, so the book
uses a **surrogate**. Two are provided (argument ``variant``):

``variant="physical"`` (the default): a lumped pipe section
    Derived from the isothermal gas equations (Osiadacz 1987; Menon 2005)
    lumped over one section of length ``L``: the section stores gas in one capacity
    ``C = A L / c^2`` (mass balance) and carries it through one inertance ``I = L / A``
    with the friction drop linearised at the operating point (momentum):

    .. math::

        \begin{aligned}
        C \frac{d\,\delta p}{dt} &= U - q, &
        I \frac{dq}{dt} &= \delta p - R(\bar p)\, q, \\
        R(\bar p) &= \frac{\lambda L c^2 \bar q}{D A^2 \bar p} &
        &\text{(from } p_{\mathrm{in}}^2 - p_{\mathrm{out}}^2
            = \lambda L c^2 q^2 / (D A^2)\text{)}
        \end{aligned}

    with :math:`q` the mass flow through the section, :math:`\delta p` (``dp``) the pressure
    drop across it (the outlet pressure is held by the downstream network) and :math:`Y = q`.
    The friction resistance falls as the mean pressure :math:`\bar p` (``pbar``) rises, which
    is what schedules the model. It is discretised exactly (zero-order hold, matrix
    exponential) at ``Ts = 2 min`` and linearised in ``p_k`` (first-order Taylor
    expansion at ``p_k = 0``), which gives the affine structure (53).

    ``p_k`` is, as in the model source, a *deviation* signal: the variation of the
    mean pressure (equivalently of the line pack, to which it is proportional)
    around its daily mean, zero on average over a day. Each state and ``p_k`` are
    defined by an identified model only up to a scale (and sign): rescaling a state,
    or ``p_k``, while rescaling the matrices leaves the input-output behaviour
    unchanged. The stated values fix these scales exactly:

    * ``X1 = s1 q`` with ``s1 = G0(1) / g1``, ``g1`` the physical gain from ``U`` to
      ``q`` in one step: ``G0(1) = -7.8297e-4`` exactly. (``s1 < 0``: with the
      paper's sign the first state is oriented against the flow.)
    * ``p_k = -(pbar_k - mean) / beta`` with ``beta`` (bar per unit of ``p_k``) such
      that ``Gp(1) / G0(1) = d ln g1 / d p_k``: ``Gp(1) = +3.8290e-5`` exactly. (The
      stated signs make ``p_k`` grow when the pressure *falls*.)
    * ``X2 = s2 dp``: the printed ``Q`` is rank one (up to rounding), so the state
      noise acts along one direction, ``[1, Q12 / Q11]`` in ``X``; the unit ``s2`` of
      the pressure-drop state decides how that noise splits between the flow and the
      stored gas. ``s2 = k s2*`` with ``s2*`` the scale for which ``G0(2) / G0(1) =
      Q12 / Q11`` (``k = 1``: the noise is an error on the input flow, passing through
      ``G``) and ``k = state2_scale`` calibrated in :data:`CALIBRATION` (``k = 10``:
      most of the noise acts on the flow; see the criterion recorded there).

    Then ``Fp``, ``Gp(2)`` follow from the physics, ``H0 = [1 / s1, 0]``,
    ``Hp = 0``, ``J0 = Jp = 0`` (the output is the flow leaving the section).
    Physical constants (module constants, each with its source): speed of sound
    ``c = 350 m/s`` (natural gas at 15 degC, ``c^2 = Z R T / M``), normal density
    0.75 kg/Nm3, diameter 0.7 m, wall roughness 0.02 mm (new steel line pipe), mean
    pressure 60 bar, viscosity 1.1e-5 Pa s, the Darcy friction factor from the
    Colebrook-White equation at the operating point (Menon 2005).

    Three constants are left free by physics and fixed by the declared calibration
    :data:`CALIBRATION` (see :func:`calibrate`): the section length ``L`` (target:
    the Fig 9 level, ``l_k`` about 50 times the threshold), the daily swing of the
    mean pressure (target: fault 2 detected in every run; the fit asks for a quarter
    of the mean pressure, which is large) and ``state2_scale`` (by a stated criterion:
    the smallest scale of a half-decade grid whose fitted swing is within 5 % of the
    least; both targets hold at every scale, :func:`calibration_for`, so the criterion,
    not the targets, picks it, and the book publishes the sensitivity of every
    prediction to it). Every other number the book reports on this surrogate is a
    prediction. Two consequences, measured and reported in the
    book: with the stated signs a depression of ``G0(1)`` raises the steady outlet
    flow slightly (``X1`` is oriented against the flow), and the Kalman filter does
    not absorb the output leak of Fig 9 (the paper's innovation returns to its
    level; ours stays shifted by the leak).

    Limits, measured by :func:`design_report`: both time constants of the lumped
    section (``~ I / R`` and ``~ R C``) are shorter than the 2 min sample, so the
    surrogate has no slow line-pack mode; and ``p_k`` only schedules the friction
    resistance: the gas that a daily swing of the mean pressure stores in and draws
    from the section (``C d pbar / dt``) is not in its mass balance, which keeps the
    steady outlet flow equal to the inlet flow at every pressure.

``variant="designed"``: the book's first surrogate (kept for comparison)
    Matrices chosen by criteria rather than derived: ``F`` constant lower triangular
    with time constants 10 and 400 min and coupling ``F(2,1) = 0.3``, ``H = [0, h2]``
    with ``h2`` making ``W`` and ``V`` equally visible at the output, ``G(2) = (Q12 /
    Q11) G(1)``, ``J0``, ``Jp`` fixing a unit steady-state gain, and ``p_k`` an
    *absolute* pressure, 5.5 +- 0.6 MPa. Its two fault columns ``U_k`` and
    ``p_k U_k`` are then nearly collinear over the samples between an onset and an
    alarm, so the GLR is flat across candidate onsets and the minmax tests can hardly
    tell the faults apart; see the book's pipeline chapter.

Common to both
    Stated values kept exactly: ``G0(1) = -7.8297e-4``, ``Gp(1) = +3.8290e-5``;
    ``Q`` and ``R`` of Section 6.2; ``Ts = 2 min``; a record of 1000 min (``N = 500``);
    the faults of Table 1 at 600 min; the output leak of ``-43980`` at 700 min, 10 % of
    the mean output flow, hence a mean flow of 439800. The printed ``Q`` is very
    slightly indefinite (rounded to four decimals); :func:`projected_q` returns the
    nearest PSD matrix (Higham 1988). The input ``U_k`` is a daily demand pattern
    (:func:`pipeline_input`, record from 06:00 of the second day), scaled so that the
    mean noise-free output over the record is exactly 439800. ``X_0`` has mean the
    steady state for ``U_0``, ``p_0`` and covariance the stationary Kalman prediction
    covariance of ``F0`` (discrete algebraic Riccati equation).
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.stats

from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.models import FaultFamily, LTVModel, lpv_model, step_family
from fdi_lib.simulate import Noise, simulate

if TYPE_CHECKING:
    from fdi_lib.filters import KalmanGains

__all__ = [
    "TS_MIN",
    "RECORD_MIN",
    "N_STEPS",
    "G0_1",
    "GP_1",
    "Q_PRINTED",
    "R",
    "MEAN_FLOW",
    "FAULT_ONSET_MIN",
    "FAULT1_DELTA",
    "FAULT2_DELTA",
    "FAULT1_DOUBLED_DELTA",
    "LEAK_ONSET_MIN",
    "LEAK_SIZE",
    "WINDOW",
    "THRESHOLD",
    "DISABLED_MIN",
    "VARIANTS",
    "CALIBRATION",
    "PhysicalSection",
    "physical_section",
    "calibrate",
    "calibration_targets",
    "calibration_for",
    "select_state2_scale",
    "surrogate",
    "filtered_surrogate",
    "surrogate_limits",
    "projected_q",
    "pipeline_schedule",
    "pipeline_input",
    "PipelineMatrices",
    "pipeline_matrices",
    "pipeline_model",
    "input_fault_psi",
    "input_fault_family",
    "output_leak_family",
    "minutes_to_index",
    "index_to_minutes",
    "design_report",
    "noise_free_output",
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

#: The two surrogates: derived from a lumped pipe section (default) or designed by criteria.
VARIANTS = ("physical", "designed")

# Physical constants of the "physical" surrogate (sources in the module docstring).
SOUND_SPEED = 350.0  # m/s, isothermal, natural gas at 15 degC (Osiadacz 1987)
NORMAL_DENSITY = 0.75  # kg/Nm3, natural gas (Menon 2005)
DIAMETER = 0.7  # m, a 28-inch transmission line (Menon 2005)
ROUGHNESS = 2e-5  # m, new steel line pipe (Menon 2005)
VISCOSITY = 1.1e-5  # Pa s, natural gas (Menon 2005)
MEAN_PRESSURE_BAR = 60.0  # bar, a typical transmission operating pressure (Menon 2005)
#: Peak of the daily mean-pressure cycle (hour of day): the line is packed at night.
PRESSURE_PEAK_HOUR = 3.0

# Surrogate choices of the "designed" variant.
NOMINAL_PRESSURE = 5.5  # MPa
PRESSURE_SWING = 0.6  # MPa
TAU_FLOW_MIN = 10.0
TAU_LINEPACK_MIN = 400.0
COUPLING = 0.3

# Shared: the daily demand pattern.
FLOW_SWING = 0.12  # relative, daily harmonic
FLOW_SWING_2 = 0.05  # relative, half-day harmonic
START_HOUR = 6.0  # the record starts at 06:00

#: The declared calibration of the physical surrogate. ``targets``: the paper observations
#: used (and nothing else); ``free``: what they fix; ``fitted``: the result of
#: :func:`calibrate`, computed once and recorded here (a test checks that the fit reproduces
#: it). ``not_used``: the paper numbers that are predictions, never fitted.
CALIBRATION = {
    "targets": {
        "fig9_level_over_threshold": {
            "value": 50.0,
            "paper": "Fig 9: after the alarm l_k stays at about 50 times the threshold",
            "computed_as": "median over k = 351..499 of (1 + lambda_k) / 50, lambda_k the "
            "non-centrality of the GLR for the output leak with the onset known",
        },
        "fault2_miss_probability": {
            "value": 1e-3,
            "paper": "Fig 7: fault 2 is detected in every one of 1000 runs",
            "computed_as": "P(chi2(2, lambda) <= 50) at k = 459, the last sample whose window "
            "still holds the true onset (a bound on the miss rate)",
        },
    },
    "free": {
        "section_length_km": "fixed by fig9_level_over_threshold",
        "pressure_swing_bar": "fixed by fault2_miss_probability",
        "state2_scale": "fixed by the criterion of CALIBRATION['state2_scale']",
    },
    "state2_scale": {
        "grid": [1.0, 3.0, 10.0, 30.0, 100.0],
        "tolerance": 0.05,
        "criterion": "the smallest value of the grid (half-decade steps) whose fitted swing is within "
        "5 % of the swing at the largest value: the fault 2 target then asks for about "
        "the least swing any scale allows, i.e. the state noise acts mostly on the flow. "
        "Stated after the value 10 was chosen; the book publishes the sensitivity of "
        "every prediction to it",
        # section length and swing fitted at each grid value (_fit_length_and_swing), recorded
        # so that the criterion and the book's sensitivity table need no refit; tests refit some
        "fits": {
            1.0: (43.67765844, 52.00357037),
            3.0: (18.94085875, 19.24090093),
            10.0: (15.14551644, 15.19536685),
            30.0: (14.5378379, 14.71995906),
            100.0: (14.35169323, 14.58700266),
        },
    },
    "fitted": {
        "section_length_km": 15.14551644124154,
        "state2_scale": 10.0,
        "pressure_swing_bar": 15.19536685052103,
    },
    "not_used": [
        "Fig 5-6 alarm, onset and delay",
        "Fig 7 delays, onset errors, false alarms",
        "Fig 8 type I and type II rates",
        "Zhang 2021 Example 2 support",
    ],
}


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


def _check_variant(variant: str) -> None:
    if variant not in VARIANTS:
        raise ModelError(f"variant: expected one of {VARIANTS}, got {variant!r}")


def _check_steps(n_steps: int) -> None:
    if not isinstance(n_steps, (int, np.integer)) or n_steps < 1:
        raise ModelError(f"n_steps: expected a positive integer, got {n_steps!r}")


def _hours(n_steps: int) -> np.ndarray:
    return START_HOUR + np.arange(n_steps) * TS_MIN / 60.0


# ----------------------------------------------------------------------------- physics
@dataclass(frozen=True)
class PhysicalSection:
    """The lumped pipe section of the physical surrogate and its derived quantities.

    Attributes
    ----------
    length_km : float
        Section length ``L``.
    area, velocity, reynolds, friction_factor : float
        Cross-section (m2), mean gas velocity (m/s), Reynolds number and Darcy friction
        factor (Colebrook-White) at the operating point.
    resistance, inertance, capacity : float
        ``R`` (Pa per kg/s), ``I = L / A`` (1/m), ``C = A L / c^2`` (kg/Pa) at the mean pressure.
    tau_slow_min, tau_fast_s : float
        Time constants of the two modes (``~ R C`` and ``~ I / R``).
    g1 : float
        Gain from ``U`` to ``q`` in one sample (dimensionless) at ``p_k = 0``.
    bar_per_unit : float
        ``beta``: mean-pressure change (bar) per unit of ``-p_k``.
    s1, s2 : float
        State scales: ``X1 = s1 q`` (``q`` in Nm3/h), ``X2 = s2 dp`` (``dp`` in bar).
    F0, Fp, G0, Gp : numpy.ndarray
        Affine discrete-time matrices in the scaled state.
    """

    length_km: float
    area: float
    velocity: float
    reynolds: float
    friction_factor: float
    resistance: float
    inertance: float
    capacity: float
    tau_slow_min: float
    tau_fast_s: float
    g1: float
    bar_per_unit: float
    s1: float
    s2: float
    F0: np.ndarray
    Fp: np.ndarray
    G0: np.ndarray
    Gp: np.ndarray


def _colebrook(reynolds: float, rel_roughness: float) -> float:
    """Darcy friction factor from the Colebrook-White equation (fixed-point iteration)."""
    x = 0.02**-0.5
    for _ in range(50):
        x = -2.0 * np.log10(rel_roughness / 3.7 + 2.51 * x / reynolds)
    return float(x**-2)


def _section_zoh(length_m: float, pressure_bar: float, lam: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact ZOH discretisation, physical state ``(q [Nm3/h], dp [bar])``, input ``U`` [Nm3/h]."""
    c2 = SOUND_SPEED**2
    area = np.pi * DIAMETER**2 / 4
    q_kg = MEAN_FLOW * NORMAL_DENSITY / 3600.0
    res = lam * length_m * c2 * q_kg / (DIAMETER * area**2 * pressure_bar * 1e5)
    ind, cap = length_m / area, area * length_m / c2
    # SI state (q [kg/s], dp [Pa]), input U [kg/s].
    Ac = np.array([[-res / ind, 1.0 / ind], [-1.0 / cap, 0.0]])
    Bc = np.array([[0.0], [1.0 / cap]])
    M = np.zeros((3, 3))
    M[:2, :2], M[:2, 2:] = Ac * TS_MIN * 60.0, Bc * TS_MIN * 60.0
    E = scipy.linalg.expm(M)
    kappa = NORMAL_DENSITY / 3600.0  # kg/s per Nm3/h
    T = np.diag([1.0 / kappa, 1e-5])  # SI -> (Nm3/h, bar)
    return T @ E[:2, :2] @ np.linalg.inv(T), T @ E[:2, 2:] * kappa


@functools.lru_cache(maxsize=256)
def physical_section(
    length_km: float | None = None, state2_scale: float | None = None
) -> PhysicalSection:
    """Derive the physical surrogate's matrices for a section of ``length_km`` km.

    Parameters
    ----------
    length_km : float, optional
        Section length; default the calibrated one (``CALIBRATION["fitted"]``).
    state2_scale : float, optional
        ``s2`` relative to the scale that puts the rank-one state noise exactly along
        ``G0`` (1: the state noise is an error on the input flow); default the calibrated one.

    Returns
    -------
    PhysicalSection
    """
    L_km = CALIBRATION["fitted"]["section_length_km"] if length_km is None else float(length_km)
    k2 = CALIBRATION["fitted"]["state2_scale"] if state2_scale is None else float(state2_scale)
    if not L_km > 0:
        raise ModelError(f"length_km: expected a positive number, got {length_km!r}")
    L = 1e3 * L_km
    area = np.pi * DIAMETER**2 / 4
    q_kg = MEAN_FLOW * NORMAL_DENSITY / 3600.0
    rho = MEAN_PRESSURE_BAR * 1e5 / SOUND_SPEED**2
    velocity = q_kg / (rho * area)
    reynolds = 4 * q_kg / (np.pi * DIAMETER * VISCOSITY)
    lam = _colebrook(reynolds, ROUGHNESS / DIAMETER)
    res = lam * L * SOUND_SPEED**2 * q_kg / (DIAMETER * area**2 * MEAN_PRESSURE_BAR * 1e5)
    ind, cap = L / area, area * L / SOUND_SPEED**2
    F, G = _section_zoh(L, MEAN_PRESSURE_BAR, lam)
    # d/d(pbar) by central differences (the matrices are smooth in pbar; step 1e-3 bar).
    h = 1e-3
    Fu, Gu = _section_zoh(L, MEAN_PRESSURE_BAR + h, lam)
    Fd, Gd = _section_zoh(L, MEAN_PRESSURE_BAR - h, lam)
    dF, dG = (Fu - Fd) / (2 * h), (Gu - Gd) / (2 * h)
    g1 = float(G[0, 0])
    beta = -(GP_1 / G0_1) / (dG[0, 0] / g1)  # bar per unit of -p_k
    # p_k = -(pbar - mean) / beta  =>  d/dp_k = -beta d/dpbar.
    dF_dp, dG_dp = -beta * dF, -beta * dG
    s1 = G0_1 / g1
    s2 = k2 * (Q_PRINTED[0, 1] / Q_PRINTED[0, 0]) * G0_1 / float(G[1, 0])
    S = np.diag([s1, s2])
    Si = np.diag([1.0 / s1, 1.0 / s2])
    eig = np.sort(np.abs(np.linalg.eigvals(F)))
    G0s, Gps = S @ G, S @ dG_dp
    G0s[0, 0], Gps[0, 0] = G0_1, GP_1  # equal by construction up to rounding: make them exact
    return PhysicalSection(
        length_km=L_km,
        area=area,
        velocity=velocity,
        reynolds=reynolds,
        friction_factor=lam,
        resistance=res,
        inertance=ind,
        capacity=cap,
        tau_slow_min=float(-TS_MIN / np.log(eig[1])),
        tau_fast_s=float(-TS_MIN * 60.0 / np.log(eig[0])),
        g1=g1,
        bar_per_unit=float(beta),
        s1=float(s1),
        s2=float(s2),
        F0=S @ F @ Si,
        Fp=S @ dF_dp @ Si,
        G0=G0s,
        Gp=Gps,
    )


# ----------------------------------------------------------------------------- signals
def pipeline_schedule(
    n_steps: int = N_STEPS,
    *,
    variant: str = "physical",
    fast_swing: float = 0.0,
    fast_period_min: float = 60.0,
    pressure_swing_bar: float | None = None,
) -> np.ndarray:
    """Scheduling parameter ``p_k``, shape ``(n_steps,)``.

    ``physical``: the daily cycle of the mean pressure, ``pbar_k - mean = a cos(2 pi (h_k - 3)
    / 24)`` with ``h_k`` the hour of day (record from 06:00), highest at 03:00 when the line
    is packed, lowest at 15:00; ``p_k = -(pbar_k - mean) / beta`` (deviation signal, unit
    and sign fixed by the stated ``Gp(1)``, see the module docstring), ``a`` the calibrated
    swing. ``designed``: the absolute pressure ``5.5 + 0.6 cos(...)`` MPa.

    Parameters
    ----------
    n_steps : int
        Number of samples.
    variant : {"physical", "designed"}
        Which surrogate.
    fast_swing : float
        Amplitude (in units of ``p_k``) of an optional faster oscillation
        ``fast_swing sin(2 pi t / fast_period_min)`` (default 0).
    fast_period_min : float
        Its period in minutes (> 0).
    pressure_swing_bar : float, optional
        ``a`` (physical variant only); default the calibrated value.
    """
    _check_steps(n_steps)
    _check_variant(variant)
    if not fast_period_min > 0:
        raise ModelError(f"fast_period_min: expected a positive number, got {fast_period_min!r}")
    t_min = np.arange(n_steps) * TS_MIN
    daily = np.cos(2 * np.pi * (_hours(n_steps) - PRESSURE_PEAK_HOUR) / 24.0)
    if variant == "physical":
        a = (
            CALIBRATION["fitted"]["pressure_swing_bar"]
            if pressure_swing_bar is None
            else pressure_swing_bar
        )
        base = -a * daily / physical_section().bar_per_unit
    else:
        base = NOMINAL_PRESSURE + PRESSURE_SWING * daily
    return base + fast_swing * np.sin(2 * np.pi * t_min / fast_period_min)


def _demand_shape(n_steps: int) -> np.ndarray:
    h = _hours(n_steps)
    return (
        1.0
        + FLOW_SWING * np.cos(2 * np.pi * (h - 9.0) / 24.0)
        + FLOW_SWING_2 * np.cos(4 * np.pi * (h - 7.0) / 24.0)
    )


def pipeline_input(n_steps: int = N_STEPS, *, variant: str = "physical") -> np.ndarray:
    """Input mass flow ``U_k`` (Nm3/h), shape ``(n_steps,)``: a daily demand pattern.

    A daily harmonic peaking at 09:00 (+-12 %) and a half-day harmonic peaking at
    07:00 and 19:00 (+-5 %), rescaled so that the mean of the noise-free *output*
    flow over the record is exactly ``MEAN_FLOW = 439800`` (the paper: the leak of
    43980 is 10 % of the average output flow). The model is linear in ``U`` (the
    initial state is the steady state of ``U_0``), so one noise-free run fixes the scale.

    Parameters
    ----------
    n_steps : int
        Number of samples.
    variant : {"physical", "designed"}
        Which surrogate.
    """
    _check_steps(n_steps)
    _check_variant(variant)
    shape = _demand_shape(n_steps)
    y = noise_free_output(shape, pipeline_schedule(n_steps, variant=variant), variant=variant)
    return MEAN_FLOW * shape / y.mean()


def noise_free_output(u: np.ndarray, p: np.ndarray, *, variant: str = "physical") -> np.ndarray:
    """Outlet flow of the fault-free surrogate without noise, started at the steady state of ``u[0]``.

    Parameters
    ----------
    u : numpy.ndarray
        Inlet flow ``U_k``, shape ``(N,)``.
    p : numpy.ndarray
        Scheduling parameter ``p_k``, shape ``(N,)``.
    variant : {"physical", "designed"}
        Which surrogate.

    Returns
    -------
    numpy.ndarray
        ``Y_k`` without noise, shape ``(N,)`` (used to scale the input to the stated mean flow).
    """
    u = np.asarray(u, dtype=float)
    model = pipeline_model(u.shape[0], variant=variant, schedule=p, u=u)
    zero = Noise(
        x0=model.x0, w=np.zeros((model.n_steps, model.n)), v=np.zeros((model.n_steps, model.p))
    )
    return simulate(model, noise=zero, u=u).y[:, 0]


# ----------------------------------------------------------------------------- matrices and model
@dataclass(frozen=True)
class PipelineMatrices:
    """The affine LPV matrices of eq. (53) of a surrogate (all ``(rows, cols)`` arrays)."""

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


def _designed_matrices() -> PipelineMatrices:
    Q = projected_q()
    ratio = Q_PRINTED[0, 1] / Q_PRINTED[0, 0]
    G0 = np.array([[G0_1], [ratio * G0_1]])
    Gp = np.array([[GP_1], [ratio * GP_1]])
    F0 = np.array(
        [[np.exp(-TS_MIN / TAU_FLOW_MIN), 0.0], [COUPLING, np.exp(-TS_MIN / TAU_LINEPACK_MIN)]]
    )
    X = scipy.linalg.solve_discrete_lyapunov(F0, Q)
    inv = np.linalg.inv(np.eye(2) - F0)
    h2 = np.sqrt(R[0, 0] / X[1, 1]) * np.sign(inv[1, 0])
    H0 = np.array([[0.0, h2]])
    J0 = 1.0 - H0 @ inv @ G0
    Jp = -(H0 @ inv @ Gp)
    P0 = scipy.linalg.solve_discrete_are(F0.T, H0.T, Q, R)
    return PipelineMatrices(
        F0=F0,
        Fp=np.zeros((2, 2)),
        G0=G0,
        Gp=Gp,
        H0=H0,
        Hp=np.zeros((1, 2)),
        J0=J0,
        Jp=Jp,
        Q=Q,
        R=R.copy(),
        P0=0.5 * (P0 + P0.T),
    )


def _physical_matrices(
    length_km: float | None = None, state2_scale: float | None = None
) -> PipelineMatrices:
    sec = physical_section(length_km, state2_scale)
    Q = projected_q()
    H0 = np.array([[1.0 / sec.s1, 0.0]])
    P0 = scipy.linalg.solve_discrete_are(sec.F0.T, H0.T, Q, R)
    return PipelineMatrices(
        F0=sec.F0,
        Fp=sec.Fp,
        G0=sec.G0,
        Gp=sec.Gp,
        H0=H0,
        Hp=np.zeros((1, 2)),
        J0=np.zeros((1, 1)),
        Jp=np.zeros((1, 1)),
        Q=Q,
        R=R.copy(),
        P0=0.5 * (P0 + P0.T),
    )


def pipeline_matrices(variant: str = "physical") -> PipelineMatrices:
    """The surrogate's affine matrices (see the module docstring for where each comes from).

    Parameters
    ----------
    variant : {"physical", "designed"}
        Which surrogate.

    Returns
    -------
    PipelineMatrices
        ``F0``, ``Fp`` ``(2, 2)``, ``G0``, ``Gp`` ``(2, 1)``, ``H0``, ``Hp`` ``(1, 2)``,
        ``J0``, ``Jp`` ``(1, 1)``, the projected ``Q``, ``R`` and the stationary prediction
        covariance ``P0`` of ``F0`` (discrete algebraic Riccati equation, scipy).
    """
    _check_variant(variant)
    return _physical_matrices() if variant == "physical" else _designed_matrices()


def _model_from(mats: PipelineMatrices, p: np.ndarray, uu: np.ndarray) -> LTVModel:
    F_first = mats.F0 + mats.Fp * p[0]
    G_first = mats.G0 + mats.Gp * p[0]
    x0 = np.linalg.solve(np.eye(2) - F_first, G_first[:, 0] * uu[0])
    return lpv_model(
        scheduling=p,
        F0=mats.F0,
        Fp=mats.Fp,
        G0=mats.G0,
        Gp=mats.Gp,
        H0=mats.H0,
        Hp=mats.Hp,
        J0=mats.J0,
        Jp=mats.Jp,
        Q=mats.Q,
        R=mats.R,
        x0=x0,
        P0=mats.P0,
    )


def pipeline_model(
    n_steps: int = N_STEPS,
    *,
    variant: str = "physical",
    schedule: np.ndarray | None = None,
    u: np.ndarray | None = None,
) -> LTVModel:
    """The fault-free surrogate LPV pipeline model (53) as an :class:`~fdi_lib.models.LTVModel`.

    Parameters
    ----------
    n_steps : int
        Horizon ``N`` (default 500 = 1000 min at 2 min).
    variant : {"physical", "designed"}
        Which surrogate (default the physical one).
    schedule : numpy.ndarray, optional
        ``p_k`` ``(n_steps,)``; default :func:`pipeline_schedule` of the variant.
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
    _check_variant(variant)
    p = (
        pipeline_schedule(n_steps, variant=variant)
        if schedule is None
        else np.asarray(schedule, dtype=float)
    )
    if p.shape != (n_steps,):
        raise ShapeError(f"schedule: expected shape ({n_steps},), got {p.shape}")
    uu = pipeline_input(n_steps, variant=variant) if u is None else np.asarray(u, dtype=float)
    if uu.ndim != 1 or uu.shape[0] != n_steps:
        raise ShapeError(f"u: expected shape ({n_steps},), got {uu.shape}")
    return _model_from(pipeline_matrices(variant), p, uu)


def input_fault_psi(
    n_steps: int = N_STEPS,
    *,
    schedule: np.ndarray | None = None,
    u: np.ndarray | None = None,
    variant: str = "physical",
) -> np.ndarray:
    """Input-end fault profile ``Psi~_k = [[U_k, p_k U_k], [0, 0]]`` of Section 6.2, ``(N, 2, 2)``.

    ``theta = [dG0(1), dGp(1)]``: the increments of ``G0(1)`` and ``Gp(1)``
    (fault 1: ``theta = [-2e-5, 0]``, fault 2: ``theta = [0, -1e-5]``). ``schedule`` and
    ``u`` default to those of ``variant``.
    """
    p = (
        pipeline_schedule(n_steps, variant=variant)
        if schedule is None
        else np.asarray(schedule, dtype=float)
    )
    uu = pipeline_input(n_steps, variant=variant) if u is None else np.asarray(u, dtype=float)
    if p.shape != (n_steps,) or uu.shape != (n_steps,):
        raise ShapeError(f"schedule, u: expected shape ({n_steps},), got {p.shape} and {uu.shape}")
    psi = np.zeros((n_steps, 2, 2))
    psi[:, 0, 0] = uu
    psi[:, 0, 1] = p * uu
    return psi


def input_fault_family(
    model: LTVModel,
    *,
    schedule: np.ndarray | None = None,
    u: np.ndarray | None = None,
    variant: str = "physical",
) -> FaultFamily:
    """Step family (eq. 4) of the input-end leaks: ``Psi_k(r) = Psi~_k 1{k >= r}``, ``m = 2``."""
    return step_family(
        model, Psi=input_fault_psi(model.n_steps, schedule=schedule, u=u, variant=variant)
    )


def output_leak_family(model: LTVModel) -> FaultFamily:
    """Step family of the output-end leak: ``Phi_k(r) = 1{k >= r}`` (``m = 1``, ``theta`` = leak size)."""
    return step_family(model, Phi=np.ones((model.p, 1)))


# ----------------------------------------------------------------------------- calibration
def surrogate(
    section_length_km: float, state2_scale: float, pressure_swing_bar: float
) -> tuple[LTVModel, np.ndarray, np.ndarray]:
    """The physical surrogate for given free constants: model, input flow and schedule.

    With the calibrated constants (:data:`CALIBRATION` ``["fitted"]``) this is
    :func:`pipeline_model`, :func:`pipeline_input` and :func:`pipeline_schedule` of the
    physical variant; other constants give the surrogates of the calibration and of its
    sensitivity (:func:`calibration_for`).

    Parameters
    ----------
    section_length_km, state2_scale, pressure_swing_bar : float
        Section length, scale of the pressure-drop state, daily swing of the mean pressure
        (the keys of ``CALIBRATION["fitted"]`` and of :func:`calibration_for`).

    Returns
    -------
    tuple
        ``(model, u, p)``: :class:`~fdi_lib.models.LTVModel` over ``N_STEPS`` samples, ``U_k``
        (scaled to the stated mean outlet flow) and ``p_k``, each ``(N_STEPS,)``.
    """
    sec = physical_section(section_length_km, state2_scale)
    mats = _physical_matrices(section_length_km, state2_scale)
    shape = _demand_shape(N_STEPS)
    daily = np.cos(2 * np.pi * (_hours(N_STEPS) - PRESSURE_PEAK_HOUR) / 24.0)
    p = -pressure_swing_bar * daily / sec.bar_per_unit
    y = _model_from(mats, p, shape)
    zero = Noise(x0=y.x0, w=np.zeros((N_STEPS, 2)), v=np.zeros((N_STEPS, 1)))
    u = MEAN_FLOW * shape / simulate(y, noise=zero, u=shape).y[:, 0].mean()
    return _model_from(mats, p, u), u, p


def filtered_surrogate(
    section_length_km: float, state2_scale: float, pressure_swing_bar: float
) -> tuple[LTVModel, np.ndarray, np.ndarray, KalmanGains]:
    """:func:`surrogate` and the Kalman gains of its model, computed once per process and constants.

    The calibration targets (:func:`calibration_targets`) and the set-up of the reproductions
    (:func:`fdi_lib.reproduce.zb2014_pipeline.pipeline_setup`) of one surrogate share them, the
    constants given by position or by keyword. Every array is read-only, so a caller cannot change
    what the next one reads.

    Returns
    -------
    tuple
        ``(model, u, p, gains)``: those of :func:`surrogate` and
        :func:`fdi_lib.filters.kalman_gains` of ``model``.
    """
    return _filtered_surrogate(
        float(section_length_km), float(state2_scale), float(pressure_swing_bar)
    )


@functools.lru_cache(maxsize=8)
def _filtered_surrogate(
    section_length_km: float, state2_scale: float, pressure_swing_bar: float
) -> tuple[LTVModel, np.ndarray, np.ndarray, KalmanGains]:
    from fdi_lib.filters import kalman_gains

    model, u, p = surrogate(section_length_km, state2_scale, pressure_swing_bar)
    gains = kalman_gains(model)
    arrays = [getattr(obj, f.name) for obj in (model, gains) for f in dataclasses.fields(obj)]
    for a in (*arrays, u, p):
        if isinstance(a, np.ndarray):
            a.flags.writeable = False
    return model, u, p, gains


def calibration_targets(
    length_km: float, state2_scale: float, pressure_swing_bar: float
) -> dict[str, float]:
    """The two calibration quantities of :data:`CALIBRATION` for given free constants.

    Closed forms (no Monte Carlo), with the filter and signatures of
    :mod:`fdi_lib.filters` and :mod:`fdi_lib.signatures`: the non-centrality
    ``lambda_k = theta^T C_k(r) theta`` of the GLR with the true onset ``r``.

    Parameters
    ----------
    length_km : float
        Section length.
    state2_scale : float
        Scale of the pressure-drop state (see :func:`physical_section`).
    pressure_swing_bar : float
        Amplitude of the daily mean-pressure cycle.

    Returns
    -------
    dict
        ``fig9_level_over_threshold`` and ``fault2_miss_probability`` (as in ``CALIBRATION``).
    """
    from fdi_lib.isolation import information
    from fdi_lib.signatures import fault_signature

    model, u, p, gains = filtered_surrogate(length_km, state2_scale, pressure_swing_bar)
    leak_on = minutes_to_index(LEAK_ONSET_MIN)
    sig = fault_signature(model, gains, output_leak_family(model).profile(leak_on)).on_innovation
    # lambda_k = theta^2 sum_{j=r}^{k} rho_j^2 / Sigma_j (p = 1), for k = r+1 .. N-1.
    lam = LEAK_SIZE**2 * np.cumsum(sig[leak_on:, 0, 0] ** 2 / gains.Sigma[leak_on:, 0, 0])[1:]
    level = float(np.median((1.0 + lam) / THRESHOLD))
    onset = minutes_to_index(FAULT_ONSET_MIN)
    fam = step_family(model, Psi=input_fault_psi(N_STEPS, schedule=p, u=u))
    sig2 = fault_signature(model, gains, fam.profile(onset)).on_innovation
    C, _ = information(np.zeros((N_STEPS, 1)), sig2, gains, onset, onset + WINDOW)
    th = np.array([0.0, FAULT2_DELTA])
    miss = float(scipy.stats.ncx2.cdf(THRESHOLD, 2, float(th @ C @ th)))
    return {"fig9_level_over_threshold": level, "fault2_miss_probability": miss}


def _fit_length_and_swing(k2: float) -> tuple[float, float]:
    """For a given ``state2_scale``: the length meeting the Fig 9 target and the swing meeting fault 2's.

    Alternating Brent root findings (each target is monotone in its own constant, so this
    finds the right branch from any start) to a relative change of ``1e-3``, then
    Gauss-Newton steps on both log-residuals together (scipy ``least_squares``), which
    converge quadratically where the alternation is only linear (about 10 s instead of 35 s).
    """
    tgt = CALIBRATION["targets"]
    level, miss = tgt["fig9_level_over_threshold"]["value"], tgt["fault2_miss_probability"]["value"]

    def residuals(L: float, a: float) -> np.ndarray:
        t = calibration_targets(L, k2, a)
        return np.log(
            [
                t["fig9_level_over_threshold"] / level,
                max(t["fault2_miss_probability"], 1e-300) / miss,
            ]
        )

    L, a = 20.0, 10.0
    for _ in range(30):
        L_new = scipy.optimize.brentq(lambda x: residuals(x, a)[0], 2.0, 300.0, rtol=1e-4)
        a_new = scipy.optimize.brentq(lambda x: residuals(L_new, x)[1], 0.5, 60.0, rtol=1e-4)
        done = abs(L_new - L) < 1e-3 * L and abs(a_new - a) < 1e-3 * a
        L, a = L_new, a_new
        if done:
            break
    sol = scipy.optimize.least_squares(
        lambda z: residuals(*np.exp(z)), np.log([L, a]), xtol=1e-15, ftol=1e-15, gtol=1e-15
    )
    if not (sol.success and np.max(np.abs(sol.fun)) < 1e-8):
        raise ModelError(
            f"state2_scale: expected both calibration targets to be met at {k2!r}, "
            f"got log-residuals {sol.fun.tolist()}"
        )
    L, a = np.exp(sol.x)
    return float(L), float(a)


def select_state2_scale(swings: dict[float, float], tolerance: float | None = None) -> float:
    """The criterion of ``CALIBRATION["state2_scale"]``: the smallest scale whose swing is near the least.

    Parameters
    ----------
    swings : dict
        ``{state2_scale: fitted pressure swing (bar)}`` over a grid.
    tolerance : float, optional
        Relative excess allowed over the swing at the largest scale (default 5 %).

    Returns
    -------
    float
        The smallest ``state2_scale`` whose swing is at most ``(1 + tolerance)`` times the
        swing at the largest scale of the grid.
    """
    tol = CALIBRATION["state2_scale"]["tolerance"] if tolerance is None else float(tolerance)
    if not swings:
        raise ModelError("swings: expected at least one (state2_scale, swing) pair, got none")
    limit = swings[max(swings)]
    return float(min(k for k, a in swings.items() if a <= (1.0 + tol) * limit))


@functools.lru_cache(maxsize=16)
def calibration_for(state2_scale: float | None = None) -> dict[str, float]:
    """The free constants of the physical surrogate calibrated with a given ``state2_scale``.

    The two targets of :data:`CALIBRATION` are met whatever ``state2_scale``; the section
    length and the swing then follow (:func:`_fit_length_and_swing`). Values of the grid of
    ``CALIBRATION["state2_scale"]`` are read from their recorded fits; any other value is
    fitted here (about 10 s).

    Parameters
    ----------
    state2_scale : float, optional
        Default: the calibrated one (``CALIBRATION["fitted"]``).

    Returns
    -------
    dict
        ``section_length_km``, ``state2_scale``, ``pressure_swing_bar`` (the keywords of
        :func:`surrogate`).
    """
    if state2_scale is None:
        return dict(CALIBRATION["fitted"])
    k2 = float(state2_scale)
    if not (np.isfinite(k2) and k2 > 0):
        raise ModelError(f"state2_scale: expected a positive number, got {state2_scale!r}")
    if k2 == CALIBRATION["fitted"]["state2_scale"]:
        return dict(CALIBRATION["fitted"])
    fits = CALIBRATION["state2_scale"]["fits"]
    L, a = fits[k2] if k2 in fits else _fit_length_and_swing(k2)
    return {"section_length_km": float(L), "state2_scale": k2, "pressure_swing_bar": float(a)}


def calibrate() -> dict[str, float]:
    """Perform the declared calibration of the physical surrogate once (see :data:`CALIBRATION`).

    ``state2_scale`` by the criterion of ``CALIBRATION["state2_scale"]`` applied to the
    recorded fits of its grid (:func:`select_state2_scale`; the tests refit grid values);
    then, for that scale, the section length by the Fig 9 target and the pressure swing by
    the fault 2 target (:func:`_fit_length_and_swing`). The result is recorded in
    ``CALIBRATION["fitted"]``; the tests check that this function reproduces it.

    Returns
    -------
    dict
        ``section_length_km``, ``state2_scale``, ``pressure_swing_bar``.
    """
    k2 = select_state2_scale({k: a for k, (_, a) in CALIBRATION["state2_scale"]["fits"].items()})
    L, a = _fit_length_and_swing(k2)
    return {"section_length_km": float(L), "state2_scale": k2, "pressure_swing_bar": float(a)}


# ----------------------------------------------------------------------------- report
def surrogate_limits(state2_scale: float | None = None) -> dict[str, float]:
    """What the physical surrogate leaves out, measured (the book states these limits).

    Parameters
    ----------
    state2_scale : float, optional
        Surrogate calibrated with this scale (:func:`calibration_for`); default the calibrated one.

    Returns
    -------
    dict
        ``tau_fast_s``, ``tau_slow_s`` (time constants of the two modes of the section) and
        ``sample_s`` (``Ts``); ``eig_F0`` (the two eigenvalue moduli of ``F0``, ascending: the
        fraction of each mode left after one sample); ``linepack_imbalance`` (largest rate
        ``C |d pbar / dt|`` at which the daily swing of the mean pressure stores gas in the
        section, as a fraction of the mean flow: the imbalance between inlet and outlet flow
        that the surrogate's mass balance leaves out); ``linepack_imbalance_sd`` (the same
        flow in stationary innovation standard deviations).
    """
    cal = calibration_for(state2_scale)
    sec = physical_section(cal["section_length_km"], cal["state2_scale"])
    mats = _physical_matrices(cal["section_length_km"], cal["state2_scale"])
    sigma = float(np.sqrt((mats.H0 @ mats.P0 @ mats.H0.T + mats.R)[0, 0]))
    # pbar - mean = a cos(2 pi t / 1 day): largest |d pbar / dt| = a 2 pi / day (Pa/s)
    rate_kg = sec.capacity * cal["pressure_swing_bar"] * 1e5 * 2 * np.pi / 86400.0
    q_kg = MEAN_FLOW * NORMAL_DENSITY / 3600.0
    return {
        "tau_fast_s": sec.tau_fast_s,
        "tau_slow_s": 60.0 * sec.tau_slow_min,
        "sample_s": 60.0 * TS_MIN,
        "eig_F0": np.sort(np.abs(np.linalg.eigvals(sec.F0))).tolist(),
        "linepack_imbalance": float(rate_kg / q_kg),
        "linepack_imbalance_sd": float(rate_kg / q_kg * MEAN_FLOW / sigma),
    }


def design_report(model: LTVModel | None = None, *, variant: str = "physical") -> dict[str, float]:
    """Numbers that check the surrogate's design (used by the tests and the book).

    Parameters
    ----------
    model : LTVModel, optional
        Unused (kept for compatibility); the report is computed for ``variant``.
    variant : {"physical", "designed"}
        Which surrogate.

    Returns
    -------
    dict
        ``eig_F`` (largest eigenvalue modulus of ``F_k`` over the record), ``dc_gain_min``/``max``
        (steady input-to-output gain at each frozen ``p_k`` of the record),
        ``J_min``/``J_max``, ``leak_gain`` (``H (I-F0)^{-1} e1``), ``sqrt_R``,
        ``sqrt_Sigma`` (stationary innovation standard deviation), ``fault1_leak_fraction``
        and ``fault2_leak_fraction`` (steady outlet flow change / flow; fault 2 at the
        largest ``|p_k|``), ``fault1_innovation_shift_sd`` (stationary innovation mean of
        fault 1, in innovation standard deviations), ``fault1_gain_change`` and
        ``fault2_gain_change_max`` (relative change of ``G(1)``), ``q_min_eig_printed``,
        ``output_std_from_W``, ``p_min``/``p_max``.
    """
    _check_variant(variant)
    mats = pipeline_matrices(variant)
    p = pipeline_schedule(variant=variant)
    F = mats.F0[None] + mats.Fp[None] * p[:, None, None]
    G = mats.G0[None] + mats.Gp[None] * p[:, None, None]
    J = mats.J0[None] + mats.Jp[None] * p[:, None, None]
    dc = np.array(
        [(mats.H0 @ np.linalg.solve(np.eye(2) - F[k], G[k]) + J[k])[0, 0] for k in range(p.size)]
    )
    X = scipy.linalg.solve_discrete_lyapunov(mats.F0, mats.Q)
    Sigma = float((mats.H0 @ mats.P0 @ mats.H0.T + mats.R)[0, 0])
    K = mats.P0 @ mats.H0.T / Sigma
    A = mats.F0 @ (np.eye(2) - K @ mats.H0)
    inv = np.linalg.inv(np.eye(2) - mats.F0)
    leak_gain = float((mats.H0 @ inv)[0, 0])
    shift = mats.H0 @ np.linalg.solve(np.eye(2) - A, np.array([MEAN_FLOW * FAULT1_DELTA, 0.0]))
    G1 = mats.G0[0, 0] + mats.Gp[0, 0] * p
    p_ext = float(p[np.argmax(np.abs(p))])
    return {
        "eig_F": float(max(np.max(np.abs(np.linalg.eigvals(Fk))) for Fk in F)),
        "dc_gain_min": float(dc.min()),
        "dc_gain_max": float(dc.max()),
        "J_min": float(J.min()),
        "J_max": float(J.max()),
        "leak_gain": leak_gain,
        "output_std_from_W": float(np.sqrt(mats.H0 @ X @ mats.H0.T)[0, 0]),
        "sqrt_R": float(np.sqrt(mats.R[0, 0])),
        "sqrt_Sigma": float(np.sqrt(Sigma)),
        "fault1_leak_fraction": float(-leak_gain * FAULT1_DELTA),
        "fault2_leak_fraction": float(-leak_gain * FAULT2_DELTA * p_ext),
        "fault1_innovation_shift_sd": float(shift[0] / np.sqrt(Sigma)),
        "fault1_gain_change": float(FAULT1_DELTA / np.mean(G1)),
        "fault2_gain_change_max": float(np.max(np.abs(FAULT2_DELTA * p / G1))),
        "q_min_eig_printed": float(np.linalg.eigvalsh(Q_PRINTED)[0]),
        "p_min": float(p.min()),
        "p_max": float(p.max()),
    }
