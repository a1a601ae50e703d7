"""The Eclipse UAV longitudinal model of Rosa & Silvestre (2013), §5-§6, eqs. (14)-(16), Table 3.

The paper gives the LPV model (15)-(16) (airspeed-scheduled stability derivatives) but not the
full nonlinear aerodynamic model used in its simulations. Choices made here (documented in
the book chapter as well):

* **M_u reading.** The OCR prints ``M_u = 0.2.6146 V^2 - 0.003426 V - 0.1425``. We read the
  quadratic coefficient as ``2.6146e-5`` (the "x 10^-5" lost, as it is printed for Z_u);
  see :data:`MU_READING`.
* **Coordinates.** Deviations from the trim point x* = (V cos a, V sin a, a, 0) with
  V = 37 m/s and a = 0.01 rad (level flight, theta* = alpha*); inputs are deviations of the
  elevator eta (rad) and of the thrust variable tau from their (unstated) trim values.
* **Nonlinear stand-in plant** (:func:`plant_derivative`): the LPV model (15) with the
  airspeed evaluated on the *true* state, V_AS(x) = sqrt(u^2 + w^2) of (14), plus the two
  terms of (14) that a linearisation drops: the Coriolis product -q w in the axial equation
  and the exact gravity term X_theta sin(theta) instead of X_theta theta. The outputs are the
  nonlinear airspeed and angle of attack alpha = arctan(w/u) of (14).
* **Sensors.** Airspeed, angle of attack, pitch angle and pitch rate, with bounded noise
  (:data:`NOISE_BOUND`).
* **Disturbances.** Band-limited, bounded accelerations on u, w and q (:data:`DIST_ACCEL`):
  a first-order low-pass filter driven by uniform noise is a convex combination of values in
  [-1, 1], so it never leaves the bound.
* **Excitation.** A known multisine is added to the LQG command on both inputs (the paper
  does not describe its manoeuvre) so that elevator and M_u faults have an effect to detect.
* **Discretisation.** Ts = 10 ms, zero-order hold: python-control's ``c2d`` for the
  controller design; the per-step SVO models use the same ZOH formula via ``scipy.linalg.expm``
  (cross-checked against ``c2d`` in the tests) because they are rebuilt at every sample.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.linalg import expm

from fdi_lib.errors import ModelError
from fdi_lib.threads import single_threaded_blas

__all__ = ["TABLE3", "V_TRIM", "ALPHA_TRIM", "TS", "MU_READING", "NOISE_BOUND", "DIST_ACCEL",
           "FAULTS", "SCENARIOS", "lpv_matrices", "zoh", "discretize", "measurement_matrix",
           "trim_state", "measure", "plant_derivative", "LQG", "design_lqg", "fault_profile",
           "UAVRun", "simulate", "svo_models"]

#: Table 3 of the paper (SI units). Only documentary: the LPV model (16) already folds them in.
TABLE3 = {"S": 2.365, "c": 1.34, "aspect_ratio": 2.047, "m": 39.7, "x_cg": 1.217, "I_y": 10.43}
V_TRIM = 37.0          #: trim airspeed (m/s), §6
ALPHA_TRIM = 0.01      #: trim angle of attack (rad), §6
TS = 0.01              #: sampling period (s), §6
MU_READING = 2.6146e-5  #: our reading of the garbled quadratic coefficient of M_u (eq. 16)
#: sensor noise bounds |n_i| <= NOISE_BOUND[i]: airspeed (m/s), alpha (rad), theta (rad), q (rad/s)
NOISE_BOUND = np.array([0.1, np.deg2rad(0.2), np.deg2rad(0.02), np.deg2rad(0.02)])
#: disturbance accelerations bounds on (u, w, q): m/s^2, m/s^2, rad/s^2
DIST_ACCEL = np.array([0.2, 0.2, 0.002])
FAULTS = ("alpha", "elevator", "dynamics")   #: FDI #1, #2, #3 of §6
SCENARIOS = ("step", "hard", "soft")          #: §6.1, §6.2, §6.3
ONSET = 0.5                                    #: fault onset time (s)


def _coefficients(V: float, mu_scale: float = 1.0) -> dict[str, float]:
    """Stability and control derivatives of eq. (16) at airspeed V (m/s)."""
    return {
        "Xu": -0.00102 * V - 0.009115, "Xw": 0.00018 * V**2 + 0.025 * V - 1.0499, "Xth": -9.67,
        "Xq": -0.00166 * V**2 + 0.2308 * V - 10.037, "Xeta": 0.026, "Xtau": 24.76,
        "Zu": -8.66e-5 * V**2 + 0.01249 * V - 0.5699, "Zw": -0.08199 * V - 0.10375,
        "Zth": -0.001358 * V**2 + 0.1679 * V - 5.4519, "Zq": 1.012 * V - 0.77,
        "Zeta": 0.0001159 * V**2 + 4.04e-5 * V - 0.001415,
        "Mu": mu_scale * (MU_READING * V**2 - 0.003426 * V - 0.1425), "Mw": -0.02817 * V + 0.001135,
        "Mth": -0.0001475 * V**2 + 0.01824 * V - 0.5922, "Mq": 0.04614 * V - 0.08368,
        "Meta": 0.00021 * V**2 - 0.00015 * V + 0.005065, "Mtau": -0.294,
    }


def lpv_matrices(V: float, mu_scale: float = 1.0, elevator_eff: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Continuous-time A(V_AS), B(V_AS) of eqs. (15)-(16), state (u, w, theta, q), input (eta, tau).

    Parameters
    ----------
    V : float
        Airspeed V_AS (m/s).
    mu_scale : float
        Multiplier of M_u (dynamics fault: 1.3 = +30 %).
    elevator_eff : float
        Elevator effectiveness (actuator fault: 0.5 = 50 %).

    Returns
    -------
    A : ndarray, shape (4, 4)
    B : ndarray, shape (4, 2)
    """
    if not np.isfinite(V) or V <= 0:
        raise ModelError(f"V: expected a positive finite airspeed, got {V!r}")
    c = _coefficients(float(V), mu_scale)
    A = np.array([[c["Xu"], c["Xw"], c["Xth"], c["Xq"]],
                  [c["Zu"], c["Zw"], c["Zth"], c["Zq"]],
                  [0.0, 0.0, 0.0, 1.0],
                  [c["Mu"], c["Mw"], c["Mth"], c["Mq"]]])
    B = np.array([[c["Xeta"] * elevator_eff, c["Xtau"]],
                  [c["Zeta"] * elevator_eff, 0.0],
                  [0.0, 0.0],
                  [c["Meta"] * elevator_eff, c["Mtau"]]])
    return A, B


def zoh(A: np.ndarray, B: np.ndarray, Ts: float = TS) -> tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold discretisation via the matrix exponential of [[A, B], [0, 0]] Ts."""
    n, m = B.shape
    E = np.zeros((n + m, n + m))
    E[:n, :n], E[:n, n:] = A, B
    F = expm(E * Ts)
    return F[:n, :n], F[:n, n:]


@lru_cache(maxsize=4096)
def _discretize_cached(V: float, mu_scale: float, elevator_eff: float, Ts: float):
    return zoh(*lpv_matrices(V, mu_scale, elevator_eff), Ts)


def discretize(V: float, mu_scale: float = 1.0, elevator_eff: float = 1.0, Ts: float = TS
               ) -> tuple[np.ndarray, np.ndarray]:
    """(A_d, B_d) of the LPV model (15)-(16) at airspeed V (m/s), zero-order hold with period Ts (s).

    Results are memoised (least-recently-used cache) because every SVO of a bank asks for the
    same airspeeds at the same sample.
    """
    return _discretize_cached(float(V), float(mu_scale), float(elevator_eff), float(Ts))


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
    return np.stack([np.hypot(u, w) - V_TRIM, np.arctan2(w, u) - ALPHA_TRIM, x[..., 2], x[..., 3]], axis=-1)


def plant_derivative(x: np.ndarray, delta: np.ndarray, dist: np.ndarray, mu_scale: float = 1.0,
                     elevator_eff: float = 1.0) -> np.ndarray:
    """Right-hand side of the nonlinear stand-in plant (deviations from trim).

    dx/dt = A(V_AS(x)) x + B(V_AS(x)) delta + [-q w + X_theta (sin theta - theta), 0, 0, 0]
            + [a_u, a_w, 0, a_q] * dist,    V_AS(x) = |(u*, w*) + (u, w)|   (eqs. (14)-(16)).

    Parameters
    ----------
    x : ndarray, shape (4,)
        (u, w, theta, q) deviations (m/s, m/s, rad, rad/s).
    delta : ndarray, shape (2,)
        (eta, tau) deviations.
    dist : ndarray, shape (3,)
        Normalised disturbances in [-1, 1] on (u, w, q).
    """
    xs = trim_state()
    V = float(np.hypot(xs[0] + x[0], xs[1] + x[1]))
    A, B = lpv_matrices(V, mu_scale, elevator_eff)
    dx = A @ x + B @ delta
    dx[0] += -x[3] * x[1] + A[0, 2] * (np.sin(x[2]) - x[2])
    dx[[0, 1, 3]] += DIST_ACCEL * dist
    return dx


@dataclass(frozen=True)
class LQG:
    """Discrete LQG controller (predictor form) designed at V = 37 m/s, alpha = 0.01 rad.

    Attributes
    ----------
    K : ndarray, shape (2, 4)
        State-feedback gain (python-control ``dlqr``), u = -K x_hat.
    L : ndarray, shape (4, 4)
        Estimator gain (python-control ``dlqe``), x_hat+ = A x_hat + B u + L (y - C x_hat).
    A, B, C : ndarray
        Design model (python-control ``c2d``, ZOH, Ts = 10 ms).
    """

    K: np.ndarray
    L: np.ndarray
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray


@lru_cache(maxsize=1)
def design_lqg() -> LQG:
    """LQR + Kalman estimator for the trim model (python-control ``c2d``, ``dlqr``, ``dlqe``).

    Bryson weights: states (1 m/s, 1 m/s, 2 deg, 5 deg/s), inputs (5 deg, 0.05); estimator with
    process noise DIST_ACCEL * Ts and measurement noise NOISE_BOUND (as standard deviations).
    """
    import control

    A, B = lpv_matrices(V_TRIM)
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
        return np.deg2rad(3.0 if scenario == "step" else 5.0)   # §6.1: 3 deg; §6.2-6.3: A = 5 deg
    if fault == "elevator":
        return 0.5   # effectiveness 100 % -> 50 %
    return 0.3       # M_u +30 %


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
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    u: np.ndarray
    fault: str
    scenario: str
    onset_step: int


def _bounded_lowpass(rng: np.random.Generator, K: int, dim: int, a: float) -> np.ndarray:
    """Band-limited noise in [-1, 1]: z_k = a z_{k-1} + (1 - a) w_k, w_k ~ U[-1, 1] (convex combination)."""
    w = rng.uniform(-1.0, 1.0, size=(K, dim))
    z = np.empty_like(w)
    z[0] = w[0]
    for k in range(1, K):
        z[k] = a * z[k - 1] + (1.0 - a) * w[k]
    return z / max(1.0, float(np.abs(z).max()))


def excitation(t: np.ndarray) -> np.ndarray:
    """Known multisine added to the LQG command: (eta, tau), shape (len(t), 2)."""
    eta = np.deg2rad(4.0) * (np.sin(2 * np.pi * 0.7 * t) + 0.5 * np.sin(2 * np.pi * 1.9 * t + 1.0))
    tau = 0.03 * np.sin(2 * np.pi * 0.35 * t)
    return np.column_stack([eta, tau])


@single_threaded_blas
def simulate(fault: str = "none", scenario: str = "step", *, rng: np.random.Generator,
             duration: float = 6.0, substeps: int = 5) -> UAVRun:
    """Closed-loop simulation of the nonlinear stand-in plant with the LQG controller.

    Parameters
    ----------
    fault : {"none", "alpha", "elevator", "dynamics"}
        §6: additive alpha-sensor fault, elevator loss of effectiveness, M_u increase.
    scenario : {"step", "hard", "soft"}
        Fault shape (:func:`fault_profile`), onset at 0.5 s.
    rng : numpy.random.Generator
        Source of the disturbances and the sensor noise.
    duration : float
        Simulated time (s).
    substeps : int
        RK4 sub-steps per sampling period.

    Returns
    -------
    UAVRun
    """
    if fault not in ("none",) + FAULTS:
        raise ModelError(f"fault: expected 'none' or one of {FAULTS}, got {fault!r}")
    fault_profile(np.zeros(1), scenario)
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"rng: expected numpy.random.Generator, got {type(rng).__name__}")
    K = int(round(duration / TS))
    t = np.arange(K + 1) * TS
    lqg = design_lqg()
    dist = _bounded_lowpass(rng, K, 3, 0.9)
    noise = _bounded_lowpass(rng, K + 1, 4, 0.5) * NOISE_BOUND
    p = fault_profile(t, scenario) * (fault != "none")
    size = _fault_size(fault, scenario) if fault != "none" else 0.0
    exc = excitation(t[:-1])
    x = np.zeros((K + 1, 4))
    y = np.zeros((K + 1, 4))
    u = np.zeros((K, 2))
    xhat = np.zeros(4)
    h = TS / substeps
    for k in range(K + 1):
        y[k] = measure(x[k]) + noise[k]
        if fault == "alpha":
            y[k, 1] += size * p[k]
        if k == K:
            break
        uk = -lqg.K @ xhat + exc[k]
        u[k] = uk
        xhat = lqg.A @ xhat + lqg.B @ uk + lqg.L @ (y[k] - lqg.C @ xhat)
        mu = 1.0 + size * p[k] if fault == "dynamics" else 1.0
        eff = 1.0 - size * p[k] if fault == "elevator" else 1.0
        xi = x[k].copy()
        for _ in range(substeps):  # RK4 with zero-order-hold input and disturbance
            k1 = plant_derivative(xi, uk, dist[k], mu, eff)
            k2 = plant_derivative(xi + h / 2 * k1, uk, dist[k], mu, eff)
            k3 = plant_derivative(xi + h / 2 * k2, uk, dist[k], mu, eff)
            k4 = plant_derivative(xi + h * k3, uk, dist[k], mu, eff)
            xi = xi + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        x[k + 1] = xi
        if not np.all(np.isfinite(xi)) or np.abs(xi).max() > 1e3:
            raise ModelError(f"simulate: the closed loop diverged at t = {t[k + 1]:.2f} s")
    onset = int(np.argmax(p > 0)) if p.any() else K + 1
    return UAVRun(t, x, y, u, fault, scenario, onset)


#: margins of the SVO models over the simulation bounds (all documented in the book)
SVO_V_MARGIN = 0.05                       # airspeed scheduling margin (m/s)
SVO_NOISE_MARGIN = np.array([0.05, np.deg2rad(0.06), 1e-5, 1e-5])  # linearisation of the sensors
SVO_DIST_MARGIN = np.array([2e-3, 1e-3, 2e-6, 2e-5])                # per-step: nonlinear terms, ZOH


def svo_models(run: UAVRun, kind: str = "nominal", *, dist_scale: float = 1.0, noise_scale: float = 1.0):
    """Per-step SVO models (callable k -> SVOModel) for the nominal plant or a fault hypothesis.

    Parameters
    ----------
    run : UAVRun
        Supplies the measured airspeed used for scheduling (V_hat = V_TRIM + y[k, 0]).
    kind : {"nominal", "alpha", "elevator", "dynamics", "global"}
        SVO #1 (nominal), #2 (alpha-sensor noise bound enlarged by 5 deg), #3 (elevator
        effectiveness in [0.5, 1]: B + B_1 Delta, §2), #4 (M_u scale in [1, 1.3]: A + A_2 Delta),
        or the Global SVO of Architecture II (all three at once).
    dist_scale : float
        Multiplier of the whole per-step disturbance bound L (simulation bound plus margin);
        1 is the design value. Used by the sensitivity study of the book (bound vs detection);
        values below 1 assume less than the simulation injects, so false alarms become possible.
    noise_scale : float
        Multiplier of the sensor noise bounds (noise bound plus margin, before the alpha-fault
        enlargement of SVO #2), likewise.

    Notes
    -----
    Airspeed uncertainty: V in [V_hat - dV, V_hat + dV], dV = noise bound + margin, gives the
    parametric uncertainty A_1 = (A_d(V+) - A_d(V-)) / 2 (n_A = 1) and B_1 likewise.
    """
    from fdi_lib.sets.svo import SVOModel

    if kind not in ("nominal", "global") + FAULTS:
        raise ModelError(f"kind: expected 'nominal', 'global' or one of {FAULTS}, got {kind!r}")
    for name, val in (("dist_scale", dist_scale), ("noise_scale", noise_scale)):
        if not isinstance(val, (int, float, np.integer, np.floating)) or not np.isfinite(val) or val < 0:
            raise ModelError(f"{name}: expected a finite non-negative number, got {val!r}")
    C = measurement_matrix()
    noise = (NOISE_BOUND + SVO_NOISE_MARGIN) * float(noise_scale)
    if kind in ("alpha", "global"):
        noise = noise + np.r_[0.0, np.deg2rad(5.0) * 1.02, 0.0, 0.0]
    L = np.diag(np.r_[DIST_ACCEL[:2] * TS, 0.5 * DIST_ACCEL[2] * TS**2, DIST_ACCEL[2] * TS] + SVO_DIST_MARGIN) * float(dist_scale)
    dV = NOISE_BOUND[0] + SVO_V_MARGIN
    mu_c, mu_r = (1.15, 0.15) if kind in ("dynamics", "global") else (1.0, 0.0)
    eff_c, eff_r = (0.75, 0.25) if kind in ("elevator", "global") else (1.0, 0.0)

    def model(k: int) -> SVOModel:
        Vh = V_TRIM + float(run.y[k, 0])
        Ap, Bp = discretize(Vh + dV, mu_c, eff_c)
        Am, Bm = discretize(Vh - dV, mu_c, eff_c)
        A_unc = [(Ap - Am) / 2]
        B_unc = [(Bp - Bm) / 2]
        if mu_r:
            Ahi, _ = discretize(Vh, mu_c + mu_r, eff_c)
            Alo, _ = discretize(Vh, mu_c - mu_r, eff_c)
            A_unc.append((Ahi - Alo) / 2)
        if eff_r:
            _, Bhi = discretize(Vh, mu_c, eff_c + eff_r)
            _, Blo = discretize(Vh, mu_c, eff_c - eff_r)
            B_unc.append((Bhi - Blo) / 2)
        return SVOModel(A=(Ap + Am) / 2, B=(Bp + Bm) / 2, C=C, L=L, noise=noise,
                        A_unc=np.array(A_unc), B_unc=np.array(B_unc))

    return model
