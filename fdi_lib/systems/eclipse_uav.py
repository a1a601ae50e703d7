r"""The Eclipse UAV longitudinal model of Rosa & Silvestre (2013), §5-§6, eqs. (14)-(16), Table 3.

The paper gives the LPV model (15)-(16) (airspeed-scheduled stability derivatives) but not the
full nonlinear aerodynamic model used in its simulations. Choices made here (documented in
the book chapter as well):

* :math:`M_u` **reading.** The OCR prints ``M_u = 0.2.6146 V^2 - 0.003426 V - 0.1425``. We read the
  quadratic coefficient as ``2.6146e-5`` (the ":math:`\times 10^{-5}`" lost, as it is printed for :math:`Z_u`);
  see :data:`MU_READING`.
* **Elevator unit.** The paper does not say in which unit :math:`\eta` enters (16). Read per
  radian, Table 3's :math:`M_\eta = 0.287\ \mathrm{s^{-2}}` at 37 m/s is 0.7 % of
  :math:`|M_\alpha| = |M_w| V`: an elevator with almost no pitch authority. Read per degree
  (:math:`X_\eta, Z_\eta, M_\eta` per degree of deflection), :math:`M_\eta / M_\alpha = -0.43`,
  the usual order for a conventional aircraft. The default :data:`ETA_UNIT` is "deg"; the input
  :math:`\eta` of every function is in radians either way
  (:func:`pitch_authority` computes the ratios).
* **Coordinates.** Deviations from the trim point :math:`x^* = (V \cos a, V \sin a, a, 0)`
  with :math:`V = 37` m/s and :math:`a = 0.01` rad (level flight, :math:`\theta^* = \alpha^*`);
  inputs are deviations of the elevator :math:`\eta` (rad) and of the thrust variable
  :math:`\tau` from their (unstated) trim values.
* **Where the faults act** (:data:`FAULT_MODES`). "deviation" (default): the elevator loss
  scales the deviation :math:`\eta`, and the :math:`M_u` change multiplies the speed deviation
  :math:`u`, as the LPV model (16) written in deviations suggests. "total": the loss scales the
  total deflection :math:`\eta^* + \eta` (:math:`\eta^*` = :data:`ETA_TRIM`, an assumption: the
  paper gives no trim deflection) and the :math:`M_u` change multiplies the total axial speed
  :math:`u^* + u`, which adds the moment :math:`0.3 M_u u^*` at the onset.
* **Nonlinear stand-in plant** (:func:`plant_derivative`): the LPV model (15) with the
  airspeed evaluated on the *true* state, :math:`V_{AS}(x) = \sqrt{u^2 + w^2}` of (14), plus
  the two terms of (14) that a linearisation drops: the Coriolis product :math:`-q w` in the
  axial equation and the exact gravity term :math:`X_\theta \sin\theta` instead of
  :math:`X_\theta \theta`. The outputs are the nonlinear airspeed and angle of attack
  :math:`\alpha = \arctan(w/u)` of (14).
* **Sensors.** Airspeed, angle of attack, pitch angle and pitch rate, with bounded noise
  (:data:`NOISE_BOUND`).
* **Disturbances.** Band-limited, bounded accelerations on u, w and q (:data:`DIST_ACCEL`):
  a first-order low-pass filter driven by uniform noise is a convex combination of values in
  [-1, 1], so it never leaves the bound.
* **Excitation.** A known multisine is added to the LQG command on both inputs (the paper
  does not describe its manoeuvre) so that elevator and :math:`M_u` faults have an effect to detect.
* **Manoeuvre envelope** (:data:`ENVELOPE_AIRSPEED`). The SVO models' margins
  (:data:`SVO_NOISE_MARGIN`, :data:`SVO_DIST_MARGIN`, :data:`SVO_V_MARGIN`) cover the sensor
  linearisation and the neglected nonlinear terms only for moderate manoeuvres: with larger airspeed
  commands (the ``amplitude`` of :func:`simulate`) the true state leaves the nominal SVO's sets and a
  healthy record can raise an alarm. Measured on healthy 3 s runs
  (:func:`fdi_lib.reproduce.rosa2013_studies.envelope_study`, seeds 0-9, square-wave commands of 1 to 7 m/s,
  90 runs per reading): with ±7 m/s commands the true state left the set in 3 to 40 of 301 samples
  per run (elevator read per degree). Over the runs that lost it, the smallest airspeed deviation
  reached up to the loss was 4.19 m/s per degree and 2.96 m/s per radian; runs reached up to
  5.54 m/s and 2.43 m/s without a loss. The envelope is the measured airspeed deviation
  :math:`|y_V(k)| \le 4` m/s (per degree) and 2.5 m/s (per radian), the largest multiples of 0.5 m/s below
  those losses; :func:`svo_models` issues an :class:`~fdi_lib.errors.EnvelopeWarning` for a record
  that leaves it (:func:`envelope_exceedance`). The study's records (no extra command) stay well
  inside (below 0.8 m/s at seed 2013, healthy or faulty), except with the "total" :math:`M_u` fault read
  per radian (13 m/s: the fault itself drives the airspeed away, and the SVO detects it).
* **Discretisation.** :math:`T_s` = 10 ms, zero-order hold: python-control's ``c2d`` for the
  controller design; the per-step SVO models use the same ZOH formula with a vectorised matrix
  exponential (cross-checked against ``c2d`` and ``scipy.linalg.expm`` in the tests) because they
  are rebuilt at every sample.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Mapping, Sequence

import numpy as np
from scipy.linalg import expm

import warnings

from fdi_lib.errors import EnvelopeWarning, ModelError, ShapeError
from fdi_lib.threads import single_threaded_blas

__all__ = [
    "TABLE3",
    "V_TRIM",
    "ALPHA_TRIM",
    "TS",
    "MU_READING",
    "NOISE_BOUND",
    "DIST_ACCEL",
    "ETA_UNITS",
    "ETA_UNIT",
    "FAULT_MODES",
    "ETA_TRIM",
    "RHO",
    "pitch_authority",
    "FAULTS",
    "SCENARIOS",
    "lpv_matrices",
    "zoh",
    "discretize",
    "measurement_matrix",
    "trim_state",
    "measure",
    "plant_derivative",
    "simulate_many",
    "LQG",
    "design_lqg",
    "fault_profile",
    "UAVRun",
    "simulate",
    "svo_models",
    "svo_model_bank",
    "svo_scale",
    "discretize_many",
    "excitation",
    "ENVELOPE_AIRSPEED",
    "envelope_exceedance",
]

#: Table 3 of the paper (SI units). Only documentary: the LPV model (16) already folds them in.
TABLE3 = {"S": 2.365, "c": 1.34, "aspect_ratio": 2.047, "m": 39.7, "x_cg": 1.217, "I_y": 10.43}
V_TRIM = 37.0  #: trim airspeed (m/s), §6
ALPHA_TRIM = 0.01  #: trim angle of attack (rad), §6
TS = 0.01  #: sampling period (s), §6
MU_READING = 2.6146e-5  #: our reading of the garbled quadratic coefficient of :math:`M_u` (eq. 16)
#: sensor noise bounds :math:`|n_i|` <= ``NOISE_BOUND[i]``: airspeed (m/s), :math:`\alpha` (rad),
#: :math:`\theta` (rad), :math:`q` (rad/s)
NOISE_BOUND = np.array([0.1, np.deg2rad(0.2), np.deg2rad(0.02), np.deg2rad(0.02)])
#: disturbance accelerations bounds on :math:`(u, w, q)`: :math:`\mathrm{m/s^2}`, :math:`\mathrm{m/s^2}`,
#: :math:`\mathrm{rad/s^2}`
DIST_ACCEL = np.array([0.2, 0.2, 0.002])
FAULTS = ("alpha", "elevator", "dynamics")  #: FDI #1, #2, #3 of §6
SCENARIOS = ("step", "hard", "soft")  #: §6.1, §6.2, §6.3
ONSET = 0.5  #: fault onset time (s)
ETA_UNITS = (
    "deg",
    "rad",
)  #: readings of the elevator coefficients of (16): per degree or per radian
ETA_UNIT = "deg"  #: default reading (see the module docstring and :func:`pitch_authority`)
#: where the elevator and :math:`M_u` faults act (module docstring)
FAULT_MODES = ("deviation", "total")
ETA_TRIM = np.deg2rad(-2.0)  #: assumed trim elevator deflection (rad) of the "total" fault mode
#: air density (:math:`\mathrm{kg/m^3}`, sea level) for the coefficient form of
#: :math:`M_\eta, M_w`
RHO = 1.225


def _check_eta_unit(eta_unit: str) -> float:
    """Factor turning the printed elevator coefficients into per-radian ones."""
    if eta_unit not in ETA_UNITS:
        raise ModelError(f"eta_unit: expected one of {ETA_UNITS}, got {eta_unit!r}")
    return float(np.rad2deg(1.0)) if eta_unit == "deg" else 1.0


def _coefficients(V: float, mu_scale: float = 1.0) -> dict[str, float]:
    """Stability and control derivatives of eq. (16) at airspeed V (m/s)."""
    return {
        "Xu": -0.00102 * V - 0.009115,
        "Xw": 0.00018 * V**2 + 0.025 * V - 1.0499,
        "Xth": -9.67,
        "Xq": -0.00166 * V**2 + 0.2308 * V - 10.037,
        "Xeta": 0.026,
        "Xtau": 24.76,
        "Zu": -8.66e-5 * V**2 + 0.01249 * V - 0.5699,
        "Zw": -0.08199 * V - 0.10375,
        "Zth": -0.001358 * V**2 + 0.1679 * V - 5.4519,
        "Zq": 1.012 * V - 0.77,
        "Zeta": 0.0001159 * V**2 + 4.04e-5 * V - 0.001415,
        "Mu": mu_scale * (MU_READING * V**2 - 0.003426 * V - 0.1425),
        "Mw": -0.02817 * V + 0.001135,
        "Mth": -0.0001475 * V**2 + 0.01824 * V - 0.5922,
        "Mq": 0.04614 * V - 0.08368,
        "Meta": 0.00021 * V**2 - 0.00015 * V + 0.005065,
        "Mtau": -0.294,
    }


def lpv_matrices(
    V: float, mu_scale: float = 1.0, elevator_eff: float = 1.0, eta_unit: str = ETA_UNIT
) -> tuple[np.ndarray, np.ndarray]:
    r"""Continuous-time :math:`A(V_{AS}), B(V_{AS})` of eqs. (15)-(16), state
    :math:`(u, w, \theta, q)`, input :math:`(\eta, \tau)`.

    Parameters
    ----------
    V : float
        Airspeed :math:`V_{AS}` (m/s).
    mu_scale : float
        Multiplier of :math:`M_u` (dynamics fault: 1.3 = +30 %).
    elevator_eff : float
        Elevator effectiveness (actuator fault: 0.5 = 50 %).
    eta_unit : {"deg", "rad"}
        Unit of the printed elevator coefficients :math:`X_\eta, Z_\eta, M_\eta`; the input
        :math:`\eta` is in rad.

    Returns
    -------
    A : ndarray, shape (4, 4)
    B : ndarray, shape (4, 2)
    """
    if not np.isfinite(V) or V <= 0:
        raise ModelError(f"V: expected a positive finite airspeed, got {V!r}")
    g = _check_eta_unit(eta_unit) * elevator_eff
    c = _coefficients(float(V), mu_scale)
    A = np.array(
        [
            [c["Xu"], c["Xw"], c["Xth"], c["Xq"]],
            [c["Zu"], c["Zw"], c["Zth"], c["Zq"]],
            [0.0, 0.0, 0.0, 1.0],
            [c["Mu"], c["Mw"], c["Mth"], c["Mq"]],
        ]
    )
    B = np.array(
        [[c["Xeta"] * g, c["Xtau"]], [c["Zeta"] * g, 0.0], [0.0, 0.0], [c["Meta"] * g, c["Mtau"]]]
    )
    return A, B


def pitch_authority(
    eta_unit: str = ETA_UNIT, V: float = V_TRIM, rho: float = RHO
) -> dict[str, float]:
    r"""Pitch-moment coefficients of the elevator and of the angle of attack at airspeed V.

    :math:`M_\alpha = M_w V` (a change of :math:`\alpha` is a change of :math:`w = V \alpha`); the
    coefficient form divides a moment derivative by :math:`\bar q S c / I_y` (Table 3,
    :math:`\bar q = \rho V^2 / 2`), the ratio does not need it.

    Returns
    -------
    dict with keys ``M_eta`` (:math:`\mathrm{s^{-2}}` per rad), ``M_alpha``
    (:math:`\mathrm{s^{-2}}` per rad), ``Cm_eta``, ``Cm_alpha`` (per rad) and ``ratio``
    (:math:`C_{m\eta} / |C_{m\alpha}|`).
    """
    A, B = lpv_matrices(V, eta_unit=eta_unit)
    M_eta, M_alpha = float(B[3, 0]), float(A[3, 1] * V)
    k = 0.5 * rho * V**2 * TABLE3["S"] * TABLE3["c"] / TABLE3["I_y"]
    return {
        "M_eta": M_eta,
        "M_alpha": M_alpha,
        "Cm_eta": M_eta / k,
        "Cm_alpha": M_alpha / k,
        "ratio": abs(M_eta / M_alpha),
    }


def zoh(A: np.ndarray, B: np.ndarray, Ts: float = TS) -> tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold discretisation via the matrix exponential of [[A, B], [0, 0]] Ts."""
    n, m = B.shape
    E = np.zeros((n + m, n + m))
    E[:n, :n], E[:n, n:] = A, B
    F = expm(E * Ts)
    return F[:n, :n], F[:n, n:]


@lru_cache(maxsize=4096)
def _discretize_cached(V: float, mu_scale: float, elevator_eff: float, Ts: float, eta_unit: str):
    return zoh(*lpv_matrices(V, mu_scale, elevator_eff, eta_unit), Ts)


def discretize(
    V: float,
    mu_scale: float = 1.0,
    elevator_eff: float = 1.0,
    Ts: float = TS,
    eta_unit: str = ETA_UNIT,
) -> tuple[np.ndarray, np.ndarray]:
    """:math:`(A_d, B_d)` of the LPV model (15)-(16) at airspeed V (m/s), zero-order hold with
    period :math:`T_s` (s).

    Results are memoised (least-recently-used cache) because every SVO of a bank asks for the
    same airspeeds at the same sample.
    """
    return _discretize_cached(float(V), float(mu_scale), float(elevator_eff), float(Ts), eta_unit)


def discretize_many(
    V: np.ndarray,
    mu_scale: float = 1.0,
    elevator_eff: float = 1.0,
    Ts: float = TS,
    eta_unit: str = ETA_UNIT,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`discretize` for an array of airspeeds at once (one batched matrix exponential,
    :func:`_expm_many`).

    Returns :math:`A_d` of shape (len(V), 4, 4) and :math:`B_d` of shape (len(V), 4, 2).
    """
    V = np.asarray(V, dtype=float).reshape(-1)
    if not np.all(np.isfinite(V)) or np.any(V <= 0):
        raise ModelError(f"V: expected positive finite airspeeds, got min {V.min()!r}")
    P = _polynomial(float(mu_scale), float(elevator_eff), eta_unit)
    E = np.zeros((V.size, 6, 6))
    E[:, :4, :] = P[0][None] + V[:, None, None] * P[1][None] + V[:, None, None] ** 2 * P[2][None]
    F = _expm_many(E * Ts)
    return F[:, :4, :4], F[:, :4, 4:]


def _expm_many(E: np.ndarray) -> np.ndarray:
    """Matrix exponentials of a stack E (b, m, m), vectorised: scaling and squaring with a degree-16
    Taylor polynomial. Each matrix is scaled by 2^-s (its own s) to an infinity norm <= 1/4, where
    the truncation error is below 0.25^17 / 17! ~ 2e-25 (relative to 1), then squared s times;
    each result depends on its own matrix only. Agrees with :func:`scipy.linalg.expm` to rounding
    (tested); scipy's version loops over the stack in Python, 100x slower for the UAV's records.
    """
    norm = np.abs(E).sum(axis=2).max(axis=1)
    s = np.maximum(0, np.ceil(np.log2(np.maximum(norm, 1e-300) / 0.25))).astype(int)
    X = E * (0.5**s)[:, None, None]
    eye = np.eye(E.shape[1])
    # Horner: I + X (I + X/2 (I + X/3 (...))), in two buffers. Its first step I + (X I)/16 is
    # I + X/16 (X I = X exactly but for the sign of a zero, which adding I makes + in both); a
    # division by a power of 2 is the product by its inverse (the same rounding of the same
    # number), and one by 1 is nothing
    F = X * (1.0 / 16)
    F += eye
    T = np.empty_like(F)
    for k in range(15, 0, -1):
        np.matmul(X, F, out=T)
        if k & (k - 1):
            T /= k
        elif k > 1:
            T *= 1.0 / k
        T += eye
        F, T = T, F
    for j in range(int(s.max(initial=0))):
        sq = j < s
        if sq.all():
            np.matmul(F, F, out=T)
            F, T = T, F
        else:
            F[sq] = F[sq] @ F[sq]
    return F


@lru_cache(maxsize=64)
def _polynomial(mu_scale: float, elevator_eff: float, eta_unit: str) -> tuple[np.ndarray, ...]:
    """[A B](V) = P0 + V P1 + V^2 P2 (every entry of (16) is a polynomial of degree <= 2 in V)."""
    f = [np.hstack(lpv_matrices(v, mu_scale, elevator_eff, eta_unit)) for v in (1.0, 2.0, 3.0)]
    P2 = (f[2] - 2 * f[1] + f[0]) / 2
    P1 = f[1] - f[0] - 3 * P2
    P0 = f[0] - P1 - P2
    return P0, P1, P2


#: trim (u*, w*) of :func:`trim_state`, as plain floats for the inner loop of the simulation
_TRIM_UW = (V_TRIM * math.cos(ALPHA_TRIM), V_TRIM * math.sin(ALPHA_TRIM))


def measurement_matrix(V: float = V_TRIM, alpha: float = ALPHA_TRIM) -> np.ndarray:
    """Linearised C of the sensors (airspeed, alpha, theta, q) about the trim point, shape (4, 4)."""
    ca, sa = np.cos(alpha), np.sin(alpha)
    return np.array([[ca, sa, 0, 0], [-sa / V, ca / V, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1.0]])


def trim_state(V: float = V_TRIM, alpha: float = ALPHA_TRIM) -> np.ndarray:
    """Absolute trim state (u, w, theta, q) for level flight: (V cos a, V sin a, a, 0)."""
    return np.array([V * np.cos(alpha), V * np.sin(alpha), alpha, 0.0])


def measure(x: np.ndarray) -> np.ndarray:
    """Noise-free nonlinear sensor outputs (deviations): airspeed, alpha = arctan(w/u), theta, q.

    ``x`` has shape (..., 4) (deviations from trim); returns the same shape.
    """
    xs = trim_state()
    u = xs[0] + x[..., 0]
    w = xs[1] + x[..., 1]
    return np.stack(
        [np.hypot(u, w) - V_TRIM, np.arctan2(w, u) - ALPHA_TRIM, x[..., 2], x[..., 3]], axis=-1
    )


def plant_derivative(
    x: np.ndarray,
    delta: np.ndarray,
    dist: np.ndarray,
    mu_scale: float = 1.0,
    elevator_eff: float = 1.0,
    eta_unit: str = ETA_UNIT,
    fault_mode: str = "deviation",
) -> np.ndarray:
    r"""Right-hand side of the nonlinear stand-in plant (deviations from trim), eqs. (14)-(16):

    .. math::

        \dot x &= A(V_{AS}(x))\, x + B(V_{AS}(x))\, \delta \\
               &\quad + [-q w + X_\theta (\sin\theta - \theta), 0, 0, 0]^\top \\
               &\quad + [a_u, a_w, 0, a_q]^\top \odot d, \\
        V_{AS}(x) &= |(u^*, w^*) + (u, w)|,

    with :math:`d` the disturbance ``dist``, plus, when ``fault_mode="total"``, the faults'
    action on the trim values: :math:`(\epsilon - 1)\, b_\eta \eta^*` and
    :math:`(\mu - 1)\, M_u u^* e_q` (:math:`\epsilon` = ``elevator_eff``, :math:`\mu` =
    ``mu_scale``).

    Parameters
    ----------
    x : ndarray, shape (4,)
        :math:`(u, w, \theta, q)` deviations (m/s, m/s, rad, rad/s).
    delta : ndarray, shape (2,)
        :math:`(\eta, \tau)` deviations.
    dist : ndarray, shape (3,)
        Normalised disturbances in [-1, 1] on (u, w, q).
    mu_scale, elevator_eff : float
        Fault parameters (as in :func:`lpv_matrices`).
    eta_unit : {"deg", "rad"}
        Reading of the elevator coefficients.
    fault_mode : {"deviation", "total"}
        Where the faults act (:data:`FAULT_MODES`).
    """
    _check_eta_unit(eta_unit)
    if fault_mode not in FAULT_MODES:
        raise ModelError(f"fault_mode: expected one of {FAULT_MODES}, got {fault_mode!r}")
    one = np.ones(1)
    return _derivative(
        np.asarray(x, dtype=float)[None],
        np.asarray(delta, dtype=float)[None],
        np.asarray(dist, dtype=float)[None],
        one * mu_scale,
        one * elevator_eff,
        _polynomial(1.0, 1.0, eta_unit),
        fault_mode == "total",
    )[0]


def _derivative(
    x: np.ndarray,
    delta: np.ndarray,
    dist: np.ndarray,
    mu: np.ndarray,
    eff: np.ndarray,
    P: tuple,
    total: bool,
) -> np.ndarray:
    """:func:`plant_derivative` for a batch of b plants: x (b, 4), delta (b, 2), dist (b, 3), mu, eff (b,).

    ``P`` is the healthy polynomial of :func:`_polynomial`; M_u and the elevator column are linear in
    the fault parameters, so the faulty [A B](V) is the healthy one with entry (3, 0) times mu and
    column 4 times eff. Elementwise products and short sums only: each plant's result does not
    depend on the batch it is computed in.
    """
    u_star, w_star = _TRIM_UW
    P0, P1, P2 = P
    V = np.hypot(u_star + x[:, 0], w_star + x[:, 1])[:, None, None]
    AB = P0 + V * (P1 + V * P2)  # healthy [A B](V), shape (b, 4, 6)
    if total:  # its elevator column and M_u, before the faults scale them
        H_eta, H_mu = AB[:, :, 4].copy(), AB[:, 3, 0].copy()
    AB[:, 3, 0] *= mu
    AB[:, :, 4] *= eff[:, None]
    dx = (AB[:, :, :4] * x[:, None, :]).sum(axis=2) + (AB[:, :, 4:] * delta[:, None, :]).sum(axis=2)
    dx[:, 0] += (
        DIST_ACCEL[0] * dist[:, 0] - x[:, 3] * x[:, 1] + AB[:, 0, 2] * (np.sin(x[:, 2]) - x[:, 2])
    )
    dx[:, 1] += DIST_ACCEL[1] * dist[:, 1]
    dx[:, 3] += DIST_ACCEL[2] * dist[:, 2]
    if total:
        dx += ((eff - 1.0) * ETA_TRIM)[:, None] * H_eta
        dx[:, 3] += (mu - 1.0) * H_mu * u_star
    return dx


@dataclass(frozen=True)
class LQG:
    r"""Discrete LQG controller (predictor form) designed at V = 37 m/s, :math:`\alpha` = 0.01 rad.

    Attributes
    ----------
    K : ndarray, shape (2, 4)
        State-feedback gain (python-control ``dlqr``), :math:`u = -K \hat x`.
    L : ndarray, shape (4, 4)
        Estimator gain (python-control ``dlqe``),
        :math:`\hat x^+ = A \hat x + B u + L (y - C \hat x)`.
    A, B, C : ndarray
        Design model (python-control ``c2d``, ZOH, :math:`T_s` = 10 ms).
    """

    K: np.ndarray
    L: np.ndarray
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray


@lru_cache(maxsize=2)
def design_lqg(eta_unit: str = ETA_UNIT) -> LQG:
    """LQR + Kalman estimator for the trim model (python-control ``c2d``, ``dlqr``, ``dlqe``).

    ``eta_unit`` selects the reading of the elevator coefficients (the controller is designed on
    the same model as the plant). Bryson weights: states (1 m/s, 1 m/s, 2 deg, 5 deg/s), inputs (5 deg, 0.05); estimator with
    process noise ``DIST_ACCEL * Ts`` and measurement noise ``NOISE_BOUND`` (as standard
    deviations).
    """
    import control

    A, B = lpv_matrices(V_TRIM, eta_unit=eta_unit)
    C = measurement_matrix()
    sysd = control.c2d(control.ss(A, B, C, np.zeros((4, 2))), TS, method="zoh")
    Ad, Bd = np.asarray(sysd.A), np.asarray(sysd.B)
    Q = np.diag(1.0 / np.array([1.0, 1.0, np.deg2rad(2), np.deg2rad(5)]) ** 2)
    R = np.diag(1.0 / np.array([np.deg2rad(5), 0.05]) ** 2)
    K, _, _ = control.dlqr(Ad, Bd, Q, R)
    G = np.eye(4)
    QN = np.diag((np.r_[DIST_ACCEL[:2], 1e-4, DIST_ACCEL[2]] * TS) ** 2)
    RN = np.diag(NOISE_BOUND**2)
    L, _, _ = control.dlqe(Ad, G, C, QN, RN)
    return LQG(np.asarray(K), np.asarray(L), Ad, Bd, C)


def fault_profile(t: np.ndarray, scenario: str, onset: float = ONSET) -> np.ndarray:
    """Fault activation in [0, 1]: step at ``onset`` (§6.1), 1 s ramp ("hard", §6.2), 4 s ramp ("soft", §6.3)."""
    if scenario not in SCENARIOS:
        raise ModelError(f"scenario: expected one of {SCENARIOS}, got {scenario!r}")
    t = np.asarray(t, dtype=float)
    if scenario == "step":
        return (t >= onset - 1e-12).astype(float)
    TR = 1.0 if scenario == "hard" else 4.0
    return np.clip((t - onset) / TR, 0.0, 1.0)


def _fault_size(fault: str, scenario: str) -> float:
    if fault == "alpha":
        return np.deg2rad(3.0 if scenario == "step" else 5.0)  # §6.1: 3 deg; §6.2-6.3: A = 5 deg
    if fault == "elevator":
        return 0.5  # effectiveness 100 % -> 50 %
    return 0.3  # M_u +30 %


@dataclass(frozen=True)
class UAVRun:
    """One closed-loop simulation.

    Attributes
    ----------
    t : ndarray, shape (K+1,)
        Sample times (s).
    x : ndarray, shape (K+1, 4)
        True state deviations (u, w, theta, q).
    y : ndarray, shape (K+1, 4)
        Measurements (deviations of airspeed, alpha, theta, q), faulty sensor included.
    u : ndarray, shape (K, 2)
        Applied input deviations (eta, tau) = LQG command + excitation (held over each period).
    fault, scenario : str
    onset_step : int
        First sample at which the fault is active (t >= 0.5 s).
    eta_unit : str
        Reading of the elevator coefficients used by the plant (the SVO models follow it).
    fault_mode : str
        Where the fault acted (:data:`FAULT_MODES`).
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    u: np.ndarray
    fault: str
    scenario: str
    onset_step: int
    eta_unit: str = ETA_UNIT
    fault_mode: str = "deviation"


def _bounded_lowpass(rng: np.random.Generator, K: int, dim: int, a: float) -> np.ndarray:
    """Band-limited noise in [-1, 1]: z_k = a z_{k-1} + (1 - a) w_k, w_k ~ U[-1, 1] (convex combination),
    z_0 = w_0. The recursion is SciPy's first-order filter from the state ``a z_0``: each sample the
    same two products and one sum as the loop it replaces, the same bits (tested)."""
    from scipy.signal import lfilter

    w = rng.uniform(-1.0, 1.0, size=(K, dim))
    z = np.empty_like(w)
    z[0] = w[0]
    z[1:] = lfilter([1.0 - a], [1.0, -a], w[1:], axis=0, zi=(a * w[0])[None, :])[0]
    return z / max(1.0, float(np.abs(z).max()))


def excitation(t: np.ndarray) -> np.ndarray:
    """Known multisine added to the LQG command: (eta, tau), shape (len(t), 2)."""
    eta = np.deg2rad(4.0) * (np.sin(2 * np.pi * 0.7 * t) + 0.5 * np.sin(2 * np.pi * 1.9 * t + 1.0))
    tau = 0.03 * np.sin(2 * np.pi * 0.35 * t)
    return np.column_stack([eta, tau])


@single_threaded_blas
def simulate(
    fault: str = "none",
    scenario: str = "step",
    *,
    rng: np.random.Generator,
    duration: float = 6.0,
    substeps: int = 2,
    eta_unit: str = ETA_UNIT,
    fault_mode: str = "deviation",
    amplitude: float = 0.0,
) -> UAVRun:
    """Closed-loop simulation of the nonlinear stand-in plant with the LQG controller.

    Parameters
    ----------
    fault : {"none", "alpha", "elevator", "dynamics"}
        §6: additive alpha-sensor fault, elevator loss of effectiveness, :math:`M_u` increase.
    scenario : {"step", "hard", "soft"}
        Fault shape (:func:`fault_profile`), onset at 0.5 s.
    rng : numpy.random.Generator
        Source of the disturbances and the sensor noise.
    duration : float
        Simulated time (s).
    substeps : int
        RK4 sub-steps per sampling period (2: 5 ms steps; the outputs then differ from those of a
        much finer integration by about 1e-6 noise bounds, checked in the tests).
    eta_unit : {"deg", "rad"}
        Reading of the elevator coefficients (:data:`ETA_UNIT`).
    fault_mode : {"deviation", "total"}
        Where the elevator and :math:`M_u` faults act (:data:`FAULT_MODES`).
    amplitude : float
        Extra airspeed command (m/s): a 0.25 Hz square wave of this amplitude is added to the
        LQG's state reference of u (0: the manoeuvre of the study). Used to test containment under
        a larger manoeuvre.

    Returns
    -------
    UAVRun
    """
    return simulate_many(
        [(fault, scenario)],
        [rng],
        duration=duration,
        substeps=substeps,
        eta_unit=eta_unit,
        fault_mode=fault_mode,
        amplitude=amplitude,
    )[0]


@single_threaded_blas
def simulate_many(
    cases: Sequence[tuple[str, str]],
    rngs: Sequence[np.random.Generator],
    *,
    duration: float = 6.0,
    substeps: int = 2,
    eta_unit: str = ETA_UNIT,
    fault_mode: str = "deviation",
    amplitude: float | Sequence[float] = 0.0,
) -> list[UAVRun]:
    """:func:`simulate` for several (fault, scenario) cases at once, stepped together (vectorised).

    Run i uses ``rngs[i]``, draws exactly what :func:`simulate` draws from it, and gets the same
    result as ``simulate(*cases[i], rng=rngs[i], ...)`` whatever the other cases (the batch only
    shares the loop over time). ``amplitude`` is one value for every case or one per case; other
    parameters as in :func:`simulate`.
    """
    if len(cases) != len(rngs):
        raise ShapeError(f"rngs: expected one generator per case ({len(cases)}), got {len(rngs)}")
    for fault, scenario in cases:
        if fault not in ("none",) + FAULTS:
            raise ModelError(f"fault: expected 'none' or one of {FAULTS}, got {fault!r}")
        fault_profile(np.zeros(1), scenario)
    _check_eta_unit(eta_unit)
    if fault_mode not in FAULT_MODES:
        raise ModelError(f"fault_mode: expected one of {FAULT_MODES}, got {fault_mode!r}")
    amp = np.asarray(amplitude, dtype=float)
    if amp.shape not in ((), (len(cases),)):
        raise ShapeError(
            f"amplitude: expected one value or one per case ({len(cases)}), got shape {amp.shape}"
        )
    if not np.all(np.isfinite(amp)) or np.any(amp < 0):
        raise ModelError(
            f"amplitude: expected finite non-negative airspeeds (m/s), got {amplitude!r}"
        )
    for rng in rngs:
        if not isinstance(rng, np.random.Generator):
            raise TypeError(f"rng: expected numpy.random.Generator, got {type(rng).__name__}")
    nb = len(cases)
    K = int(round(duration / TS))
    t = np.arange(K + 1) * TS
    lqg = design_lqg(eta_unit)
    P = _polynomial(1.0, 1.0, eta_unit)
    total = fault_mode == "total"
    dist = np.empty((nb, K, 3))
    noise = np.empty((nb, K + 1, 4))
    for b, rng in enumerate(rngs):
        dist[b] = _bounded_lowpass(rng, K, 3, 0.9)
        noise[b] = _bounded_lowpass(rng, K + 1, 4, 0.5) * NOISE_BOUND
    # fault activation times size, per case: alpha offset, M_u scale, elevator effectiveness
    act = np.array(
        [fault_profile(t, sc) * (_fault_size(f, sc) if f != "none" else 0.0) for f, sc in cases]
    )
    kinds = np.array([f for f, _ in cases])
    alpha_off = act * (kinds == "alpha")[:, None]
    mu_all = 1.0 + act * (kinds == "dynamics")[:, None]
    eff_all = 1.0 - act * (kinds == "elevator")[:, None]
    exc = excitation(t[:-1])
    x = np.zeros((nb, K + 1, 4))
    y = np.zeros((nb, K + 1, 4))
    u = np.zeros((nb, K, 2))
    xhat = np.zeros((nb, 4))
    ref = np.zeros((nb, 4))  # the state reference of each case: its airspeed command
    h = TS / substeps
    Kg, Ae, Be, Le, Ce = lqg.K, lqg.A, lqg.B, lqg.L, lqg.C

    def mv(M: np.ndarray, v: np.ndarray) -> np.ndarray:  # rows of v times M^T, batch-independent
        return (M[None, :, :] * v[:, None, :]).sum(axis=2)

    for k in range(K + 1):
        y[:, k] = measure(x[:, k]) + noise[:, k]
        y[:, k, 1] += alpha_off[:, k]
        if k == K:
            break
        ref[:, 0] = amp * np.sign(np.sin(2 * np.pi * 0.25 * t[k]))
        uk = -mv(Kg, xhat - ref) + exc[k]
        u[:, k] = uk
        xhat = mv(Ae, xhat) + mv(Be, uk) + mv(Le, y[:, k] - mv(Ce, xhat))
        mu, eff, dk = mu_all[:, k], eff_all[:, k], dist[:, k]
        xi = x[:, k]
        for _ in range(substeps):  # RK4 with zero-order-hold input and disturbance
            k1 = _derivative(xi, uk, dk, mu, eff, P, total)
            k2 = _derivative(xi + h / 2 * k1, uk, dk, mu, eff, P, total)
            k3 = _derivative(xi + h / 2 * k2, uk, dk, mu, eff, P, total)
            k4 = _derivative(xi + h * k3, uk, dk, mu, eff, P, total)
            xi = xi + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        x[:, k + 1] = xi
        bad = ~np.all(np.isfinite(xi), axis=1) | (np.abs(xi).max(axis=1) > 1e3)
        if bad.any():
            raise ModelError(
                f"simulate: the closed loop of case {cases[int(np.argmax(bad))]} diverged at "
                f"t = {t[k + 1]:.2f} s"
            )
    out = []
    for b, (fault, scenario) in enumerate(cases):
        p = act[b] > 0
        onset = int(np.argmax(p)) if p.any() else K + 1
        out.append(UAVRun(t, x[b], y[b], u[b], fault, scenario, onset, eta_unit, fault_mode))
    return out


#: margins of the SVO models over the simulation bounds (all documented in the book)
SVO_V_MARGIN = 0.05  # airspeed scheduling margin (m/s)
SVO_NOISE_MARGIN = np.array([0.05, np.deg2rad(0.06), 1e-5, 1e-5])  # linearisation of the sensors
SVO_DIST_MARGIN = np.array([2e-3, 1e-3, 2e-6, 2e-5])  # per-step: nonlinear terms, ZOH


#: Manoeuvre envelope of the SVO margins (module docstring): the largest measured airspeed deviation
#: :math:`|y_V(k)|` (m/s) per reading of the elevator coefficients, a multiple of 0.5 m/s below the smallest
#: deviation at which the true state was seen outside the nominal SVO's set
#: (:func:`fdi_lib.reproduce.rosa2013_studies.envelope_study`; a test keeps the two consistent).
ENVELOPE_AIRSPEED = {"deg": 4.0, "rad": 2.5}


def envelope_exceedance(run: UAVRun) -> np.ndarray:
    """Samples k of ``run`` whose measured airspeed deviation :math:`|y_V(k)|` exceeds the
    manoeuvre envelope :data:`ENVELOPE_AIRSPEED` of its elevator reading (empty: the record stays
    inside)."""
    return np.flatnonzero(np.abs(run.y[:, 0]) > ENVELOPE_AIRSPEED[run.eta_unit])


def svo_scale() -> np.ndarray:
    r"""State scaling for the SVOs (argument ``scale`` of :func:`fdi_lib.sets.svo.run_svo`).

    Half-widths of the box that the measurement strip alone allows, :math:`|C^{-1}| (\bar n +
    \text{margin})`: about 0.16, 0.16 m/s on :math:`u, w` and :math:`3.6 \cdot 10^{-4}` rad, rad/s
    on :math:`\theta, q`. In these units the SVO sets are round.
    """
    return np.abs(np.linalg.inv(measurement_matrix())) @ (NOISE_BOUND + SVO_NOISE_MARGIN)


def svo_models(
    run: UAVRun,
    kind: str = "nominal",
    *,
    dist_scale: float = 1.0,
    noise_scale: float = 1.0,
    alpha_slack_deg: float = 0.0,
):
    r"""Per-step SVO models (a :class:`fdi_lib.sets.svo.ModelSequence`, callable k -> SVOModel) for the
    nominal plant or a fault hypothesis.

    Parameters
    ----------
    run : UAVRun
        Supplies the measured airspeed used for scheduling (``V_hat = V_TRIM + y[k, 0]``) and the
        reading of the elevator coefficients (``run.eta_unit``).
    kind : {"nominal", "alpha", "elevator", "dynamics", "global"}
        SVO #1 (nominal), #2 (alpha-sensor noise bound enlarged by 5 deg), #3 (elevator
        effectiveness in [0.5, 1]: :math:`B + B_1 \Delta`, §2), #4 (:math:`M_u` scale in [1, 1.3]:
        :math:`A + A_2 \Delta`),
        or the Global SVO of Architecture II (all three at once).
    dist_scale : float
        Multiplier of the whole per-step disturbance bound L (simulation bound plus margin);
        1 is the design value. Used by the sensitivity study of the book (bound vs detection);
        values below 1 assume less than the simulation injects, so false alarms become possible.
    noise_scale : float
        Multiplier of the sensor noise bounds (noise bound plus margin, before the alpha-fault
        enlargement of SVO #2), likewise.
    alpha_slack_deg : float
        Degrees added to the angle-of-attack noise bound of this observer only (0: the design
        bound). The book's hypothesis on the paper's 3.5 s isolation of a soft alpha fault
        loosens the elevator and :math:`M_u` observers (#3, #4) this way
        (:func:`fdi_lib.reproduce.rosa2013_uav.uav_study`).

    Warns
    -----
    EnvelopeWarning
        When the record leaves the manoeuvre envelope (:func:`envelope_exceedance`): the margins
        may then fail to cover the nonlinear terms, the sets may lose the true state, and an empty
        set is no longer a proof of a fault.

    Notes
    -----
    Airspeed uncertainty: :math:`V \in [\hat V - \delta V, \hat V + \delta V]`,
    :math:`\delta V` = noise bound + margin, gives the parametric uncertainty
    :math:`A_1 = (A_d(V^+) - A_d(V^-)) / 2` (:math:`n_A = 1`) and :math:`B_1` likewise.
    """
    return _model_bank(run, {kind: alpha_slack_deg}, dist_scale, noise_scale)[kind]


def svo_model_bank(
    run: UAVRun, kinds: Mapping[str, float], *, dist_scale: float = 1.0, noise_scale: float = 1.0
) -> dict:
    r""":func:`svo_models` of several kinds on one record: ``kinds`` maps each kind to its
    ``alpha_slack_deg``. The same models, bit for bit; the discretisations that kinds share (those
    of the nominal and alpha SVOs, :math:`A_d, B_d` at :math:`\hat V \pm \delta V`) are computed
    once.

    Returns
    -------
    dict
        kind -> :class:`fdi_lib.sets.svo.ModelSequence`, in the order of ``kinds``.
    """
    return _model_bank(run, kinds, dist_scale, noise_scale)


def _model_bank(
    run: UAVRun, kinds: Mapping[str, float], dist_scale: float, noise_scale: float
) -> dict:
    """:func:`svo_model_bank` (its warning is the caller's caller's: ``stacklevel=3``)."""
    from fdi_lib.sets.svo import ModelSequence

    for kind in kinds:
        if kind not in ("nominal", "global") + FAULTS:
            raise ModelError(f"kind: expected 'nominal', 'global' or one of {FAULTS}, got {kind!r}")
    for name, val in (
        ("dist_scale", dist_scale),
        ("noise_scale", noise_scale),
        *(("alpha_slack_deg", v) for v in kinds.values()),
    ):
        if (
            not isinstance(val, (int, float, np.integer, np.floating))
            or not np.isfinite(val)
            or val < 0
        ):
            raise ModelError(f"{name}: expected a finite non-negative number, got {val!r}")
    if envelope_exceedance(run).size:
        warnings.warn(
            f"run: the measured airspeed deviation leaves the manoeuvre envelope of the SVO margins "
            f"(|y_V| <= {ENVELOPE_AIRSPEED[run.eta_unit]} m/s, eta_unit={run.eta_unit!r}); the sets may lose "
            f"the true state (see uav.envelope_exceedance)",
            EnvelopeWarning,
            stacklevel=3,
        )
    C = measurement_matrix()
    L = np.diag(
        np.r_[DIST_ACCEL[:2] * TS, 0.5 * DIST_ACCEL[2] * TS**2, DIST_ACCEL[2] * TS]
        + SVO_DIST_MARGIN
    ) * float(dist_scale)
    dV = NOISE_BOUND[0] + SVO_V_MARGIN
    Vh = V_TRIM + run.y[:, 0]
    airspeeds = {1: Vh + dV, -1: Vh - dV, 0: Vh}  # the scheduling airspeed, up, down, as measured
    done: dict = {}  # (airspeed, mu, eff) -> (A_d, B_d), for this record only

    def disc(side: int, mu: float, eff: float) -> tuple[np.ndarray, np.ndarray]:
        if (side, mu, eff) not in done:
            done[side, mu, eff] = discretize_many(airspeeds[side], mu, eff, eta_unit=run.eta_unit)
        return done[side, mu, eff]

    out = {}
    for kind, slack in kinds.items():
        noise = (NOISE_BOUND + SVO_NOISE_MARGIN) * float(noise_scale)
        if kind in ("alpha", "global"):
            noise = noise + np.r_[0.0, np.deg2rad(5.0) * 1.02, 0.0, 0.0]
        if slack:
            noise = noise + np.r_[0.0, np.deg2rad(float(slack)), 0.0, 0.0]
        mu_c, mu_r = (1.15, 0.15) if kind in ("dynamics", "global") else (1.0, 0.0)
        eff_c, eff_r = (0.75, 0.25) if kind in ("elevator", "global") else (1.0, 0.0)
        (Ap, Bp), (Am, Bm) = disc(1, mu_c, eff_c), disc(-1, mu_c, eff_c)
        A_unc = [(Ap - Am) / 2]
        B_unc = [(Bp - Bm) / 2]
        if mu_r:
            A_unc.append((disc(0, mu_c + mu_r, eff_c)[0] - disc(0, mu_c - mu_r, eff_c)[0]) / 2)
        if eff_r:
            B_unc.append((disc(0, mu_c, eff_c + eff_r)[1] - disc(0, mu_c, eff_c - eff_r)[1]) / 2)
        out[kind] = ModelSequence(
            A=(Ap + Am) / 2,
            B=(Bp + Bm) / 2,
            C=C,
            L=L,
            noise=noise,
            A_unc=np.stack(A_unc, axis=1),
            B_unc=np.stack(B_unc, axis=1),
        )
    return out
