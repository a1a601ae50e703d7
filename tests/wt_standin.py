"""A tiny stand-in of :mod:`fdi_lib.systems.wind_turbine` for the method tests (same API, crude
aerodynamics): pitch servos and drive train as in the benchmark, integrated by Euler sub-steps,
a PI pitch loop, constant-power torque, an aerodynamic torque quadratic in the wind."""

from __future__ import annotations

from dataclasses import dataclass, replace
from types import SimpleNamespace

import numpy as np


@dataclass(frozen=True)
class WindTurbineParams:
    Ts: float = 0.01
    pitch_wn: float = 11.11
    pitch_zeta: float = 0.6
    pitch_wn_faults: tuple = (5.73, 3.42)
    pitch_zeta_faults: tuple = (0.45, 0.9)
    J_r: float = 55e6
    J_g: float = 390.0
    K_dt: float = 2.7e9
    B_dt: float = 945e3
    B_r: float = 27.8e3
    B_g: float = 3.034
    N_g: float = 95.0
    eta_dt: float = 0.97
    alpha_gc: float = 50.0
    sigma_beta: float = 0.2
    sigma_omega_r: float = 0.025
    sigma_omega_g: float = 0.2
    sigma_tau_g: float = 90.0


@dataclass(frozen=True)
class Fault:
    id: int
    name: str
    kind: str
    component: str
    start_s: float
    stop_s: float
    magnitude: float
    required_detection_s: float
    source: str


FAULTS = (
    Fault(1, "pitch sensor fixed value", "fixed", "beta1_m1", 40.0, 50.0, 5.0, 0.1, "stand-in"),
    Fault(2, "pitch sensor gain", "gain", "beta2_m2", 40.0, 50.0, 1.2, 0.1, "stand-in"),
    Fault(4, "rotor speed fixed value", "fixed", "omega_r_m1", 40.0, 50.0, 1.4, 0.1, "stand-in"),
    Fault(6, "pitch actuator pressure drop", "dynamics", "actuator2", 40.0, 50.0, 0.0, 0.08, "stand-in"),
    Fault(8, "converter offset", "offset", "converter", 40.0, 50.0, 100e3, 0.03, "stand-in"),
)


def wind_speed(t, *, seed, mean=15.0, intensity=0.1):
    rng = np.random.default_rng(seed)
    t = np.asarray(t, dtype=float)
    a = np.exp(-0.01 / 5.0)
    e = rng.standard_normal(t.size) * np.sqrt(1 - a * a) * intensity * mean
    v = np.empty(t.size)
    v[0] = e[0] / np.sqrt(1 - a * a)
    for k in range(1, t.size):
        v[k] = a * v[k - 1] + e[k]
    return mean + v


def simulate(*, seed, faults=FAULTS, duration_s=60.0, params=WindTurbineParams(), wind=None, n_realisations=None):
    p = params
    R = 1 if n_realisations is None else int(n_realisations)
    N = int(round(duration_s / p.Ts))
    t = np.arange(N) * p.Ts
    rng = np.random.default_rng(seed)
    seeds = rng.integers(0, 2**31, size=R)
    v = (np.stack([wind_speed(t, seed=int(s)) for s in seeds]) if wind is None
         else np.broadcast_to(np.asarray(wind, float), (R, N)))
    sub = 10
    h = p.Ts / sub
    wr0, beta0 = 1.7, 8.0
    tau_g0 = 2.9e6 * p.eta_dt / p.N_g
    beta = np.full((R, 3), beta0)
    dbeta = np.zeros((R, 3))
    wr = np.full(R, wr0)
    wg = np.full(R, wr0 * p.N_g)
    th = np.full(R, 2.9e6 / p.K_dt)
    tg = np.full(R, tau_g0)
    integ = np.zeros(R)
    out = {k: np.empty((R, N) + s) for k, s in (("beta_m", (3, 2)), ("omega_r_m", (2,)), ("omega_g_m", (2,)),
                                                 ("tau_g_m", ()), ("beta_ref", (3,)), ("tau_g_ref", ()),
                                                 ("beta", (3,)), ("beta_dot", (3,)), ("omega_r", ()),
                                                 ("omega_g", ()), ("theta_delta", ()), ("tau_g", ()),
                                                 ("tau_aero", ()))}
    active = lambda f, tk: f.start_s <= tk < f.stop_s  # noqa: E731
    for k in range(N):
        tk = t[k]
        bm = beta[:, :, None] + p.sigma_beta * rng.standard_normal((R, 3, 2))
        wrm = wr[:, None] + p.sigma_omega_r * rng.standard_normal((R, 2))
        wgm = wg[:, None] + p.sigma_omega_g * rng.standard_normal((R, 2))
        tgm = tg + p.sigma_tau_g * rng.standard_normal(R)
        wn = np.full(3, p.pitch_wn)
        z = np.full(3, p.pitch_zeta)
        offset = 0.0
        for f in faults:
            if not active(f, tk):
                continue
            c = f.component
            if c.startswith("beta"):
                i, j = int(c[4]) - 1, int(c[-1]) - 1
                bm[:, i, j] = f.magnitude if f.kind == "fixed" else bm[:, i, j] * f.magnitude
            elif c.startswith("omega"):
                arr = wrm if c.startswith("omega_r") else wgm
                j = int(c[-1]) - 1
                arr[:, j] = f.magnitude if f.kind == "fixed" else arr[:, j] * f.magnitude
            elif c.startswith("actuator"):
                i = int(c[-1]) - 1
                wn[i], z[i] = p.pitch_wn_faults[0], p.pitch_zeta_faults[0]
            elif c == "converter":
                offset = f.magnitude
        err = wrm[:, 1] - wr0
        integ += err * p.Ts
        bref = np.clip(beta0 + 10.0 * err + 3.0 * integ, -2.0, 90.0)
        tref = np.full(R, tau_g0)
        tau_a = 2.9e6 * (v[:, k] / 15.0) ** 2 * (1 - 0.06 * (beta.mean(axis=1) - beta0))
        for key, val in (("beta_m", bm), ("omega_r_m", wrm), ("omega_g_m", wgm), ("tau_g_m", tgm),
                         ("beta_ref", np.repeat(bref[:, None], 3, axis=1)), ("tau_g_ref", tref), ("beta", beta),
                         ("beta_dot", dbeta), ("omega_r", wr), ("omega_g", wg), ("theta_delta", th),
                         ("tau_g", tg), ("tau_aero", tau_a)):
            out[key][:, k] = val
        for _ in range(sub):
            # semi-implicit Euler: velocities first, then positions with the new velocities
            dbeta = dbeta + h * (-wn ** 2 * (beta - bref[:, None]) - 2 * z * wn * dbeta)
            beta = beta + h * dbeta
            dwr = (tau_a - p.K_dt * th - (p.B_dt + p.B_r) * wr + p.B_dt / p.N_g * wg) / p.J_r
            dwg = (p.eta_dt * p.K_dt / p.N_g * th + p.eta_dt * p.B_dt / p.N_g * wr
                   - (p.eta_dt * p.B_dt / p.N_g ** 2 + p.B_g) * wg - tg) / p.J_g
            tg = tg + h * (-p.alpha_gc * tg + p.alpha_gc * (tref + offset))
            wr, wg = wr + h * dwr, wg + h * dwg
            th = th + h * (wr - wg / p.N_g)
    return SimpleNamespace(t=t, v=v, **out)


def shifted(fault, start_s):
    return replace(fault, start_s=start_s, stop_s=start_s + (fault.stop_s - fault.start_s))
