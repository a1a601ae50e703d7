"""Wind-turbine FDI benchmark (Odgaard, Stoustrup & Kinnaert 2009/2013): the model's published behaviour.

References computed independently of the module: scipy's matrix exponential and grid interpolator,
closed-form second-order step responses, hand-evaluated constants, finite differences, and the
controller's switching rule re-evaluated on the recorded signals.
"""

from __future__ import annotations

import dataclasses
import doctest
import math

import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator
from scipy.integrate import solve_ivp
from scipy.linalg import expm
from scipy.signal import welch

from fdi_lib.errors import FDIError, ModelError, ShapeError
from fdi_lib.systems import wind_turbine as wt

P = wt.PARAMS
#: the benchmark's parameters without sensor noise: exact checks of the fault models
QUIET = dataclasses.replace(
    P, std_beta=0.0, std_omega_r=0.0, std_omega_g=0.0, std_tau_g=0.0, std_p_g=0.0
)
#: the same with the jump-free reading of the actuator faults (physical parameters change, pitch
#: continuous)
JUMP_FREE = dataclasses.replace(QUIET, actuator_faults="jump_free")


def shifted(fault: wt.Fault, start: float) -> wt.Fault:
    """``fault`` moved to start at ``start`` (same duration and ramp)."""
    return dataclasses.replace(fault, start_s=start, stop_s=start + fault.stop_s - fault.start_s)


def fault(i: int) -> wt.Fault:
    return next(f for f in wt.FAULTS if f.id == i)


def turbulent(mean: float, duration_s: float, seed: int) -> np.ndarray:
    """Kaimal-turbulent wind around a constant ``mean`` (the module's turbulence, rescaled)."""
    t = np.arange(0.0, duration_s, P.ts)
    return mean * wt.wind_speed(t, seed=seed) / wt.wind_speed(t, seed=seed, model="mean")


# --------------------------------------------------------------------------------------------- constants
def test_constants_against_hand_values():
    # K_opt = 0.5 rho pi R^5 eta_dt Cp_max / (N_g lambda_opt)^3 by hand: 57.5^5 = 115^5 / 32 =
    # 628 549 121.09375; 0.6125 pi 57.5^5 = 1.209473e9; x 0.97 x 0.4554 = 5.342703e8; / 760^3 = 1.217082
    assert P.K_opt == pytest.approx(1.21708, rel=1e-5)
    # noise: the script's sigma_* are the Simulink blocks' variances (module docstring, disagreement 1)
    np.testing.assert_allclose(
        P.noise_std**2, [0.2] * 6 + [0.004 * 2 * math.pi] * 2 + [0.05] * 2 + [90.0, 1e3], rtol=1e-12
    )
    assert (
        P.omega_n,
        P.zeta,
        P.omega_n_pressure_drop,
        P.zeta_pressure_drop,
        P.omega_n_air,
        P.zeta_air,
    ) == (11.11, 0.6, 5.73, 0.45, 3.42, 0.9)


def test_cq_table_spot_values_and_cp_maximum():
    # values of code/AeroDynamics.mat, copied by hand: Cq(lambda=8, beta=0), Cq(1, -2), Cq(13, 95)
    assert wt.CQ_TABLE.shape == (25, 33)
    assert wt.torque_coefficient(8.0, 0.0) == 0.0567
    assert wt.torque_coefficient(1.0, -2.0) == 0.0117
    cp = wt.LAMBDA_GRID[:, None] * wt.CQ_TABLE
    i, j = np.unravel_index(np.argmax(cp), cp.shape)
    assert (wt.LAMBDA_GRID[i], cp[i, j]) == (8.0, pytest.approx(0.4536, abs=1e-12))
    assert float(wt.power_coefficient(8.0, 0.0)) == pytest.approx(0.4536, abs=1e-12)


def test_interpolation_matches_scipy_and_extrapolates_linearly():
    rng = np.random.default_rng(0)
    lam = rng.uniform(1.0, 13.0, 500)
    beta = rng.uniform(-2.0, 95.0, 500)
    ref = RegularGridInterpolator((wt.LAMBDA_GRID, wt.BETA_GRID_DEG), wt.CQ_TABLE, method="linear")
    np.testing.assert_allclose(wt.torque_coefficient(lam, beta), ref(np.c_[lam, beta]), atol=1e-14)
    # beyond the last tip-speed ratio: the line through the last two rows (Simulink's extrapolation)
    row12, row13 = wt.CQ_TABLE[-2, 6], wt.CQ_TABLE[-1, 6]
    assert float(wt.torque_coefficient(14.0, 0.0)) == pytest.approx(
        row13 + 2 * (row13 - row12), abs=1e-14
    )


# ------------------------------------------------------------------------------------------ steady states
def test_region2_steady_state_is_rated_power_and_speed():
    for v in (14.0, 16.0, 20.0, 24.0):
        op = wt.operating_point(v)
        assert op.region == 2
        assert op.omega_g == pytest.approx(P.omega_nom, rel=1e-12)
        assert op.p_g == pytest.approx(P.P_r, rel=1e-12)
        assert 0.0 < op.beta < 30.0
    # the closed loop with noise settles there: means over the last 100 s of a 200 s run at 16 m/s
    run = wt.simulate(seed=7, faults=(), duration_s=200.0, wind=16.0)
    last = slice(10_000, None)
    assert np.all(run.region == 2)
    assert run.p_g[last].mean() == pytest.approx(P.P_r, rel=2e-3)
    assert run.omega_g[last].mean() == pytest.approx(P.omega_nom, abs=0.3)
    assert run.beta[last].mean() == pytest.approx(wt.operating_point(16.0).beta, abs=0.1)


def test_equilibria_solve_the_linear_drive_train_balance():
    """The operating point is a zero of the continuous drive-train + generator dynamics (solved with numpy)."""
    for v in (8.0, 16.0):
        op = wt.operating_point(v)
        A, B = wt._drive_train_continuous(P, P.eta_dt)
        tau_a = float(wt.aero_torque(v, op.omega_r, np.full(3, op.beta)))
        x = np.linalg.solve(A, -B @ np.array([tau_a, op.tau_g, 0.0]))
        np.testing.assert_allclose(x, [op.omega_r, op.omega_g, op.theta_delta, op.tau_g], rtol=1e-9)
    # the noise-free closed loop started there does not move
    for v in (8.0, 16.0):
        run = wt.simulate(seed=0, faults=(), duration_s=30.0, wind=v, params=QUIET)
        np.testing.assert_allclose(
            run.state,
            np.broadcast_to(wt.operating_point(v).state, run.state.shape),
            rtol=1e-9,
            atol=1e-9,
        )


def test_region1_tracks_the_optimal_tip_speed_ratio():
    # without friction losses and with K_opt built on the table's own Cp maximum (0.4536 at lambda = 8),
    # the optimal-torque law has its equilibrium at lambda_opt: Cp(lambda)/lambda^3 = Cp_max/lambda_opt^3
    ideal = dataclasses.replace(P, B_r=0.0, B_g=0.0, eta_dt=1.0, cp_max=0.4536)
    for v in (6.0, 8.0, 10.0):
        op = wt.operating_point(v, params=ideal)
        assert op.region == 1 and op.beta == 0.0
        assert op.lam == pytest.approx(8.0, abs=1e-9)
        assert op.cp == pytest.approx(0.4536, abs=1e-9)
    # with the benchmark's friction (B_g omega_g is 30 % of the generator torque) the rotor runs slower:
    # lambda 6.8-7.4, still within 5 % of the best power coefficient at beta = 0
    cp_best = float(wt.power_coefficient(8.0, 0.0))
    for v in (6.0, 8.0, 10.0, 12.0):
        op = wt.operating_point(v)
        assert op.region == 1 and 6.7 < op.lam < 7.5
        assert op.cp > 0.95 * cp_best
    # the closed loop with noise at 8 m/s keeps that tip-speed ratio on average
    run = wt.simulate(seed=3, faults=(), duration_s=200.0, wind=8.0)
    lam = run.omega_r[10_000:] * P.radius / 8.0
    assert lam.mean() == pytest.approx(wt.operating_point(8.0).lam, abs=0.01)
    assert np.all(run.region == 1)


def test_rated_wind_speed_separates_the_regions():
    v_rated = wt.rated_wind_speed()
    assert 12.0 < v_rated < 14.0
    below = wt.operating_point(v_rated - 1e-6)
    assert below.region == 1 and below.p_g == pytest.approx(P.P_r, rel=1e-6)  # the switch on power
    assert below.omega_g < P.omega_nom
    above = wt.operating_point(v_rated + 0.05)
    assert above.region == 2 and 0.0 < above.beta < 0.5
    # between them, a band of 0.02 m/s where the region-2 pitch saturates with too little torque
    with pytest.raises(ModelError, match="no region-2 equilibrium"):
        wt.operating_point(v_rated + 0.01)
    with pytest.raises(ModelError, match="no region-2 equilibrium"):
        wt.operating_point(5.0, region=2)
    assert wt.operating_point(v_rated + 0.01, region=1).region == 1


def test_torque_balance_has_the_bits_of_the_array_torque():
    """The root searches' balance computes the three blades' torque on floats (_cq_three): the same
    bits as the array path _aero_torque, over the table, outside it (extrapolation) and at a zero
    coefficient (whose sign numpy's sum of three drops)."""
    rng = np.random.default_rng(11)
    points = [(v, w, b) for v, w, b in rng.uniform([2.0, 0.05, -4.0], [30.0, 2.5, 50.0], (400, 3))]
    points += [(8.0, 8.0 * 8.0 / P.radius, float(b)) for b in wt.BETA_GRID_DEG]  # on the grid
    for v, w, b in points:
        tau_a = float(wt._aero_torque(np.asarray(v), np.asarray(w), np.full(3, b), P))
        want = P.eta_dt * (tau_a - P.B_r * w) / P.N_g - P.B_g * P.N_g * w - 1e4
        assert wt._torque_balance(v, w, b, 1e4, P).hex() == want.hex(), (v, w, b)
    grid = np.array([0.0, 2.0])  # a table of -0.0: numpy's sum of three is +0.0
    cq = wt._cq_three(1.0, 0.0, grid, grid - 1.0, np.full((2, 2), -0.0))
    assert math.copysign(1.0, cq) == 1.0


# ---------------------------------------------------------------------------------- pitch actuators
@pytest.mark.parametrize(
    "wn, zeta",
    [(11.11, 0.6), (5.73, 0.45), (3.42, 0.9)],
    ids=["nominal", "pressure_drop", "high_air_content"],
)
def test_actuator_step_response_is_the_closed_form_second_order(wn, zeta):
    ts = 1e-4
    phi, gam = wt.pitch_discretisation(wn, zeta, ts=ts)
    A = np.array([[0.0, 1.0], [-(wn**2), -2 * zeta * wn]])
    M = expm(np.block([[A, np.array([[0.0], [wn**2]])], [np.zeros((1, 3))]]) * ts)
    np.testing.assert_allclose(phi, M[:2, :2], rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(gam, M[:2, 2:], rtol=1e-10, atol=1e-16)
    n = int(3.0 / ts)
    x = np.zeros(2)
    beta = np.empty(n)
    for k in range(n):
        beta[k] = x[0]
        x = phi @ x + gam[:, 0]
    t = np.arange(n) * ts
    wd = wn * math.sqrt(1 - zeta**2)
    closed = 1 - np.exp(-zeta * wn * t) * (
        np.cos(wd * t) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t)
    )
    np.testing.assert_allclose(beta, closed, atol=1e-10)
    overshoot = beta.max() - 1.0
    assert overshoot == pytest.approx(math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2)), abs=1e-6)
    assert t[np.argmax(beta)] == pytest.approx(math.pi / wd, abs=ts)


def test_sample_and_hold_of_the_aerodynamic_torque_is_accurate():
    """One sample of plant_step against scipy's DOP853 on the continuous plant (references and wind held)."""
    A, B = wt._drive_train_continuous(P, P.eta_dt)

    def f(_t, x, beta_r, tau_g_r, v):
        dx = np.empty(10)
        for b in range(3):
            dx[2 * b] = x[2 * b + 1]
            dx[2 * b + 1] = -2 * P.zeta * P.omega_n * x[2 * b + 1] + P.omega_n**2 * (
                beta_r - x[2 * b]
            )
        tau = float(wt.aero_torque(v, x[6], x[[0, 2, 4]]))
        dx[6:] = A @ x[6:] + B @ np.array([tau, tau_g_r, 0.0])
        return dx

    for mean in (8.0, 16.0):
        run = wt.simulate(seed=2, faults=(), duration_s=60.0, wind=turbulent(mean, 60.0, 2))
        for k in range(500, 6000, 500):
            x = run.state[k]
            args = (run.beta_r[k], run.tau_g_r[k], run.v[k])
            ref = solve_ivp(
                f, (0.0, P.ts), x, args=args, method="DOP853", rtol=1e-12, atol=1e-12
            ).y[:, -1]
            got = wt.plant_step(x, beta_r=args[0], tau_g_r=args[1], v=args[2])[0]
            np.testing.assert_allclose(got[:6], ref[:6], atol=1e-9)
            assert abs(got[6] - ref[6]) < 2e-5 * ref[6] and abs(got[7] - ref[7]) < 1e-6 * ref[7]


@pytest.mark.parametrize(
    "c0, c1", [(50.0, 30.0), (25.0, 10.0), (4.0, 1.0)], ids=["over", "critical", "under"]
)
def test_pitch_closed_form_exponential_in_every_damping_regime(c0, c1):
    out = np.empty(9)
    wt._pitch_zoh(c0, c1, 7.0, 0.01, out)
    A = np.array([[0.0, 1.0], [-c0, -c1]])
    M = expm(np.block([[A, np.array([[0.0], [7.0]])], [np.zeros((1, 3))]]) * 0.01)
    np.testing.assert_allclose(out[3:7].reshape(2, 2), M[:2, :2], rtol=1e-12)
    np.testing.assert_allclose(out[7:9], M[:2, 2], rtol=1e-10)


def _one_step_pitch(
    run: wt.WindTurbineRun, blade: int, wn2: float, tzw: float, feedback: float = 1.0
) -> np.ndarray:
    """Residual of the pitch update of ``blade`` against the exact model with ``(omega_n^2, 2 zeta omega_n)``."""
    wn, zeta = math.sqrt(wn2), tzw / (2 * math.sqrt(wn2))
    phi, gam = wt.pitch_discretisation(wn, zeta, feedback=feedback)
    x = run.state[:, 2 * blade : 2 * blade + 2]
    return x[1:] - (x[:-1] @ phi.T + run.beta_r[:-1, None] * gam[:, 0])


def test_actuator_faults_change_the_dynamics_on_schedule():
    f6, f7 = shifted(fault(6), 20.0), shifted(fault(7), 20.0)  # 100 s each
    nominal = (P.omega_n**2, 2 * P.zeta * P.omega_n)
    run = wt.simulate(
        seed=1, faults=(f6,), duration_s=140.0, wind=turbulent(16.0, 140.0, 1), params=JUMP_FREE
    )
    assert np.all(run.region == 2)
    k_on, k_off = 2000, 12000
    faulty = (5.73**2, 2 * 0.45 * 5.73)
    res_nom = np.abs(_one_step_pitch(run, 1, *nominal)).max(axis=1)
    res_f = np.abs(_one_step_pitch(run, 1, *faulty)).max(axis=1)
    assert res_nom[:k_on].max() < 1e-12 and res_nom[k_off:].max() < 1e-12
    assert res_f[k_on:k_off].max() < 1e-12
    assert res_nom[k_on:k_off].max() > 1e-6  # the faulty dynamics differ visibly from the nominal
    assert np.abs(_one_step_pitch(run, 0, *nominal)).max() < 1e-12  # the other blades are untouched
    # fault 7: mixed parameters along the 30 s ramps (p = j / 3000), full fault in the middle
    run = wt.simulate(
        seed=1, faults=(f7,), duration_s=140.0, wind=turbulent(16.0, 140.0, 1), params=JUMP_FREE
    )
    air = (3.42**2, 2 * 0.9 * 3.42)
    for k, p in ((2000, 0.0), (2000 + 1500, 0.5), (2000 + 5000, 1.0), (2000 + 9999 - 600, 0.2)):
        mixed = tuple((1 - p) * a + p * b for a, b in zip(nominal, air))
        assert np.abs(_one_step_pitch(run, 2, *mixed)[k]).max() < 1e-12
    np.testing.assert_allclose(
        run.fault_active[[2000, 3500, 7000, 11_399], 0], [0.0, 0.5, 1.0, 0.2], atol=1e-12
    )


def test_simulink_actuator_faults_scale_the_pitch_at_each_parameter_change():
    """The benchmark's Simulink realisation (output omega_n^2 x_2 of a canonical state): at F6's
    onset the blade's pitch is the healthy update times (5.73 / 11.11)^2 (about 27 %), at its end
    the faulty update divided by it; in between the faulty dynamics; before the onset the jump-free
    run is the same."""
    f6 = shifted(fault(6), 20.0)
    wind = turbulent(16.0, 140.0, 1)
    run = wt.simulate(seed=1, faults=(f6,), duration_s=140.0, wind=wind, params=QUIET)
    free = wt.simulate(seed=1, faults=(f6,), duration_s=140.0, wind=wind, params=JUMP_FREE)
    assert QUIET.actuator_faults == "simulink" == P.actuator_faults
    k_on, k_off = 2000, 12000
    ratio = (5.73 / 11.11) ** 2
    assert ratio == pytest.approx(0.266, abs=1e-3)
    np.testing.assert_array_equal(run.state[:k_on], free.state[:k_on])
    nominal = (P.omega_n**2, 2 * P.zeta * P.omega_n)
    faulty = (5.73**2, 2 * 0.45 * 5.73)
    x = run.state[:, 2:4]
    res_nom = _one_step_pitch(run, 1, *nominal)  # residual of the transition k -> k + 1
    res_f = _one_step_pitch(run, 1, *faulty)
    pred_on = x[k_on] - res_nom[k_on - 1]  # the healthy update into the onset sample
    np.testing.assert_allclose(x[k_on], ratio * pred_on, rtol=1e-12)
    pred_off = x[k_off] - res_f[k_off - 1]
    np.testing.assert_allclose(x[k_off], pred_off / ratio, rtol=1e-12)
    assert np.abs(res_f[k_on : k_off - 1]).max() < 1e-9
    assert run.beta[k_on, 1] < 0.3 * run.beta[k_on - 1, 1]  # the drop the benchmark's users saw
    with pytest.raises(ModelError, match="actuator_faults: expected one of"):
        dataclasses.replace(P, actuator_faults="smooth")


# -------------------------------------------------------------------------------------- controller
def test_region_switch_follows_the_stated_rule():
    t = np.arange(0.0, 900.0, P.ts)
    wind = np.interp(t, [0.0, 400.0, 500.0, 900.0], [9.0, 16.0, 16.0, 9.0])
    run = wt.simulate(seed=11, faults=(), duration_s=900.0, wind=wind)
    z, w, pg = run.region, run.omega_g_m[:, 0], run.p_g_m
    prev, now = z[:-1], z[1:]
    up = (pg[1:] >= P.P_r) | (w[1:] >= P.omega_nom)
    down = w[1:] < P.omega_nom - P.omega_delta
    np.testing.assert_array_equal(now[prev == 1], np.where(up[prev == 1], 2, 1))
    np.testing.assert_array_equal(now[prev == 2], np.where(down[prev == 2], 1, 2))
    assert np.any((prev == 1) & (now == 2)) and np.any((prev == 2) & (now == 1))
    # the references follow the region's law, computed from the recorded measurements
    r1, r2 = z == 1, z == 2
    np.testing.assert_allclose(run.tau_g_r[r1], P.K_opt * w[r1] ** 2, rtol=1e-12)
    np.testing.assert_allclose(run.tau_g_r[r2], P.P_r / (P.eta_gc * w[r2]), rtol=1e-12)
    assert np.all(run.beta_r[r1] == 0.0)
    assert np.all((run.beta_r >= P.beta_min) & (run.beta_r <= P.beta_max))
    # the first switch to full load happens near the rated wind speed (the rise is slow: 17.5 mm/s^2)
    k_up = int(np.argmax(z == 2))
    assert wind[k_up] == pytest.approx(wt.rated_wind_speed(), abs=0.6)


# --------------------------------------------------------------------------------------- sensors
def test_sensor_noise_standard_deviations_from_fault_free_data():
    run = wt.simulate(seed=5, faults=(), duration_s=300.0, wind=16.0)
    true = np.column_stack(
        [
            run.beta[:, [0, 0, 1, 1, 2, 2]],
            run.omega_r,
            run.omega_r,
            run.omega_g,
            run.omega_g,
            run.tau_g,
            run.p_g,
        ]
    )
    err = run.y - true
    n = err.shape[0]
    np.testing.assert_allclose(
        err.std(axis=0), P.noise_std, rtol=4 / math.sqrt(2 * n)
    )  # 4 sigma of a std
    np.testing.assert_allclose(err.mean(axis=0) / P.noise_std, 0.0, atol=4 / math.sqrt(n))
    corr = np.corrcoef(err.T)
    assert np.abs(corr - np.eye(12)).max() < 4 / math.sqrt(n)  # independent sensors
    doubled = dataclasses.replace(P, std_tau_g=2 * P.std_tau_g)
    run2 = wt.simulate(seed=5, faults=(), duration_s=100.0, wind=16.0, params=doubled)
    assert (run2.tau_g_m - run2.tau_g).std() == pytest.approx(2 * P.std_tau_g, rel=0.03)


def test_pitch_sensor_noise_reaches_the_blades_through_the_internal_loop():
    run = wt.simulate(seed=5, faults=(), duration_s=100.0, wind=16.0)
    quiet = wt.simulate(
        seed=5, faults=(), duration_s=100.0, wind=16.0, params=dataclasses.replace(P, std_beta=0.0)
    )
    spread = (run.beta[:, 0] - run.beta[:, 1]).std()
    assert spread > 0.05 and (quiet.beta[:, 0] - quiet.beta[:, 1]).std() < 1e-9


# ------------------------------------------------------------------------------------------ faults
def test_scenario_schedule_matches_the_benchmark():
    ids = [f.id for f in wt.FAULTS]
    assert ids == list(range(1, 10))
    times = {f.id: (f.start_s, f.stop_s) for f in wt.FAULTS}
    assert times == {
        1: (2000, 2100),
        2: (2300, 2400),
        3: (2600, 2700),
        4: (1500, 1600),
        5: (1000, 1100),
        6: (2900, 3000),
        7: (3400, 3500),
        8: (3800, 3900),
        9: (4000, 4200),
    }
    req = {f.id: f.required_detection_s for f in wt.FAULTS}
    assert req == {
        1: 0.1,
        2: 0.1,
        3: 0.1,
        4: 0.1,
        5: 0.1,
        6: pytest.approx(0.08),
        7: pytest.approx(6.0),
        8: pytest.approx(0.03),
        9: None,
    }
    prof = wt.fault_profiles(wt.FAULTS, 440_000)
    for j, f in enumerate(wt.FAULTS):
        on = np.flatnonzero(prof[:, j] > 0)
        first = int(round(f.start_s / P.ts)) + (1 if f.ramp_s else 0)
        last = int(round(f.stop_s / P.ts)) - 1 - (1 if f.ramp_s else 0)
        assert (on[0], on[-1]) == (first, last)
    # fault 7: the benchmark's D_Fault7, 30 s up (0, 1/3000, ...), 40 s at 1, 30 s down (..., 1/3000, 0)
    p7 = prof[340_000:350_000, 6]
    np.testing.assert_allclose(p7[:3000], np.arange(3000) / 3000, atol=1e-15)
    assert np.all(p7[3000:7000] == 1.0)
    np.testing.assert_allclose(p7[7000:], np.arange(2999, -1, -1) / 3000, atol=1e-15)


def _exact_sensor_run(f: wt.Fault, wind: float) -> tuple[wt.WindTurbineRun, slice, np.ndarray]:
    g = dataclasses.replace(f, start_s=10.0, stop_s=20.0)
    run = wt.simulate(seed=2, faults=(g,), duration_s=30.0, wind=wind, params=QUIET)
    return run, slice(1000, 2000), run.fault_active[:, 0] > 0


@pytest.mark.parametrize(
    "fid, wind, channels",
    [
        (1, 16.0, {0: ("fixed", 5.0)}),
        (2, 16.0, {3: ("gain", 1.2)}),
        (3, 16.0, {4: ("fixed", 10.0)}),
        (4, 8.0, {6: ("fixed", 1.4)}),
        (5, 8.0, {7: ("gain", 1.1), 9: ("gain", 0.9)}),
    ],
)
def test_sensor_faults_act_on_their_sensor_at_their_time(fid, wind, channels):
    run, window, on = _exact_sensor_run(fault(fid), wind)
    assert np.array_equal(np.flatnonzero(on), np.arange(1000, 2000))
    true = np.column_stack(
        [
            run.beta[:, [0, 0, 1, 1, 2, 2]],
            run.omega_r,
            run.omega_r,
            run.omega_g,
            run.omega_g,
            run.tau_g,
            run.p_g,
        ]
    )
    for ch in range(12):
        if ch in channels:
            kind, m = channels[ch]
            expect = np.full(on.sum(), m) if kind == "fixed" else m * true[on, ch]
            np.testing.assert_allclose(run.y[on, ch], expect, rtol=1e-12)
            assert np.abs(run.y[~on, ch] - true[~on, ch]).max() < 1e-9 * max(
                1.0, np.abs(true[:, ch]).max()
            )
        else:
            np.testing.assert_allclose(run.y[:, ch], true[:, ch], rtol=1e-12, atol=1e-12)


def test_stuck_pitch_sensor_moves_the_true_pitch():
    # internal loop with beta_1,m1 stuck at 5: u = beta_r + beta_1 - (5 + beta_1)/2, so at rest
    # beta_1 = 2 beta_r - 5 (noise-free); the controller keeps beta_r near its equilibrium meanwhile
    run, window, on = _exact_sensor_run(fault(1), 16.0)
    k = 1999
    assert run.beta[k, 0] == pytest.approx(2 * run.beta_r[k] - 5.0, abs=0.2)
    assert abs(run.beta[k, 0] - run.beta[k, 1]) > 1.0


def test_converter_and_drive_train_faults():
    run = wt.simulate(
        seed=2, faults=(shifted(fault(8), 10.0),), duration_s=30.0, wind=16.0, params=QUIET
    )
    on = run.fault_active[:, 0] > 0
    np.testing.assert_allclose(run.tau_g[on] - run.state[on, 9], 100.0, rtol=1e-12)
    np.testing.assert_allclose(run.tau_g[~on], run.state[~on, 9], rtol=1e-15)
    np.testing.assert_allclose(run.tau_g_m[on], run.state[on, 9] + 100.0, rtol=1e-12)
    # drive-train efficiency 0.92 on schedule: one-step update of (omega_r, omega_g, theta, tau_gc)
    run = wt.simulate(
        seed=2, faults=(shifted(fault(9), 10.0),), duration_s=40.0, wind=8.0, params=QUIET
    )
    on = run.fault_active[:-1, 0] > 0
    x, u = (
        run.state[:, 6:],
        np.column_stack([run.tau_aero, run.tau_g_r, np.zeros_like(run.tau_aero)]),
    )
    for eta, sel in ((0.92, on), (P.eta_dt, ~on)):
        phi, gam = wt.drive_train_discretisation(P, eta_dt=eta)
        pred = x[:-1] @ phi.T + u[:-1] @ gam.T
        np.testing.assert_allclose(x[1:][sel], pred[sel], rtol=1e-12, atol=1e-9)
    assert (
        run.omega_g[2999] < run.omega_g[999] - 1.0
    )  # less torque reaches the generator: it slows down


def test_faults_show_up_in_the_full_scenario():
    """Each fault changes the signal it acts on, at its scheduled time, in the default 4400 s scenario."""
    run = wt.simulate(seed=4)
    on = run.fault_active > 0
    y, b = run.y, run.beta
    assert (
        np.all(y[on[:, 0], 0] == 5.0)
        and np.all(y[on[:, 2], 4] == 10.0)
        and np.all(y[on[:, 3], 6] == 1.4)
    )
    f2 = on[:, 1]
    assert y[f2, 3].mean() / y[f2, 2].mean() == pytest.approx(1.2, rel=0.02)
    f5 = on[:, 4]
    assert y[f5, 7].mean() / y[f5, 6].mean() == pytest.approx(1.1, rel=0.01)
    assert y[f5, 9].mean() / y[f5, 8].mean() == pytest.approx(0.9, rel=0.01)
    before = slice(330_000, 340_000)
    full7 = run.fault_active[:, 6] == 1.0
    assert (b[full7, 2] - b[full7, 0]).std() > 2 * (b[before, 2] - b[before, 0]).std()
    res = run.tau_g_m - run.tau_g_r
    assert res[on[:, 7]].mean() - res[370_000:380_000].mean() == pytest.approx(100.0, abs=5.0)
    # F6 (Simulink reading): blade 2's pitch drops to about 27 % at the onset sample
    k6 = int(np.argmax(on[:, 5]))
    assert run.beta[k6, 1] == pytest.approx((5.73 / 11.11) ** 2 * run.beta[k6 - 1, 1], abs=0.01)


def test_fault_validation_messages():
    f = fault(1)
    with pytest.raises(ModelError, match="kind expected one of"):
        dataclasses.replace(f, kind="sensor_offset")
    with pytest.raises(ModelError, match="component expected names"):
        dataclasses.replace(f, component=("beta_4_m1",))
    with pytest.raises(ModelError, match="expected start_s < stop_s"):
        dataclasses.replace(f, stop_s=1000.0)
    with pytest.raises(ModelError, match="drive-train fault is abrupt"):
        dataclasses.replace(fault(9), ramp_s=1.0)
    both = (
        f,
        wt.Fault(
            10,
            "beta_1,m2 stuck",
            "sensor_fixed",
            ("beta_1_m2",),
            2050.0,
            2150.0,
            (3.0,),
            None,
            "test",
        ),
    )
    with pytest.raises(ModelError, match="both pitch sensors of blade 1 stuck"):
        wt.simulate(seed=0, faults=both, duration_s=1.0)
    with pytest.raises(ShapeError, match="wind: expected a number"):
        wt.simulate(seed=0, duration_s=1.0, wind=np.full(7, 10.0))
    with pytest.raises(ModelError, match=r"wind: expected wind speeds in \[2, 35\] m/s"):
        wt.simulate(seed=0, duration_s=1.0, wind=0.0)


# ---------------------------------------------------------------------------------- reproducibility
def test_seeded_runs_are_reproducible_and_batch_consistent():
    a = wt.simulate(seed=42, duration_s=5.0)
    b = wt.simulate(seed=42, duration_s=5.0)
    np.testing.assert_array_equal(a.y, b.y)
    np.testing.assert_array_equal(a.v, b.v)
    batch = wt.simulate(seed=42, duration_s=5.0, n_realisations=3)
    assert batch.y.shape == (3, 500, 12) and batch.region.shape == (3, 500)
    np.testing.assert_array_equal(batch.y[0], a.y)  # realisation 0 = the single run
    seeds = np.random.SeedSequence(42).spawn(3)
    again = wt.simulate(seed=seeds, duration_s=5.0)
    twice = wt.simulate(seed=seeds, duration_s=5.0)  # the seed sequences are not consumed
    np.testing.assert_array_equal(again.y, batch.y)
    np.testing.assert_array_equal(twice.y, batch.y)
    assert not np.array_equal(batch.y[1], batch.y[2])
    small = wt.simulate(seed=42, duration_s=5.0, dtype=np.float32)
    assert small.y.dtype == np.float32
    np.testing.assert_allclose(small.y, a.y, rtol=1e-6)


def _same_runs(a: wt.WindTurbineRun, b: wt.WindTurbineRun) -> None:
    for name in ("v", "state", "y", "u", "tau_aero", "tau_g", "p_g", "region", "fault_active"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.faults == b.faults and a.y.dtype == b.y.dtype


@pytest.mark.parametrize(
    ("start", "chunk", "dtype"),
    [
        (3.0, None, np.float64),
        (3.0, 70, np.float32),
        (2.5, 50, np.float64),
        (0.0, None, np.float64),
    ],
)
def test_twin_is_the_fault_free_run_bit_for_bit(monkeypatch, start, chunk, dtype):
    """simulate_with_twin: the faulty run and the fault-free one of two simulate calls, to the last
    bit, with the fork inside a chunk, on a chunk boundary (2.5 s = 250 samples, chunks of 50), at
    the first sample, in float32; faults starting after the run leave the twin equal to the run."""
    if chunk is not None:
        monkeypatch.setattr(wt, "_CHUNK", chunk)
    seeds = np.random.SeedSequence(7).spawn(2)
    faults = (shifted(fault(1), start), shifted(fault(8), start + 0.5))
    kw = dict(seed=seeds, duration_s=5.0, dtype=dtype)
    run, twin = wt.simulate_with_twin(faults=faults, **kw)
    _same_runs(run, wt.simulate(faults=faults, **kw))
    _same_runs(twin, wt.simulate(faults=(), **kw))
    assert not np.array_equal(run.y, twin.y)  # the faults show
    late = (shifted(fault(1), 9.0),)
    run, twin = wt.simulate_with_twin(faults=late, **kw)
    _same_runs(run, wt.simulate(faults=late, **kw))
    _same_runs(twin, wt.simulate(faults=(), **kw))


# ---------------------------------------------------------------------------------- linearisation
@pytest.mark.parametrize("v", [8.0, 16.0], ids=["region1", "region2"])
def test_linearisation_matches_finite_differences(v):
    lin = wt.linearise(v)
    x0 = lin.x0
    beta0, tau0 = lin.u0

    def step(x=x0, beta_r=beta0, tau_g_r=tau0, wind=v):
        return wt.plant_step(x, beta_r=beta_r, tau_g_r=tau_g_r, v=wind)[0]

    np.testing.assert_allclose(
        step(), x0, rtol=1e-10, atol=1e-10
    )  # the operating point is a fixed point
    # forward differences: inside a cell of the table the step is linear in each state and reference
    # (the region-1 pitch, 0 deg, lies on a grid line: the linearisation takes the cell above it)
    scale = np.array([1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-5, 1e-3, 1e-7, 1.0])
    A_fd = np.column_stack([(step(x=x0 + h * e) - step()) / h for h, e in zip(scale, np.eye(10))])
    np.testing.assert_allclose(lin.A, A_fd, rtol=1e-5, atol=1e-9)
    B_fd = np.column_stack(
        [(step(beta_r=beta0 + 1e-3) - step()) / 1e-3, (step(tau_g_r=tau0 + 1.0) - step())]
    )
    np.testing.assert_allclose(lin.B, B_fd, rtol=1e-6, atol=1e-12)
    G_fd = (step(wind=v + 1e-4) - step(wind=v - 1e-4)) / 2e-4
    np.testing.assert_allclose(lin.G[:, 0], G_fd, rtol=1e-5, atol=1e-12)
    # aerodynamic partials against differences of aero_torque
    op = lin.point

    def tau(om=op.omega_r, b=op.beta, wind=v):
        return float(wt.aero_torque(wind, om, np.array([b, op.beta, op.beta])))

    assert lin.d_tau_d_omega_r == pytest.approx(
        (tau(om=op.omega_r + 1e-6) - tau()) / 1e-6, rel=1e-5
    )
    assert lin.d_tau_d_beta == pytest.approx((tau(b=op.beta + 1e-4) - tau()) / 1e-4, rel=1e-5)
    assert lin.d_tau_d_v == pytest.approx(
        (tau(wind=v + 1e-5) - tau(wind=v - 1e-5)) / 2e-5, rel=1e-6
    )
    # measurement map: P_g = eta_gc omega_g tau_g
    y = lambda x: np.r_[x[[0, 0, 2, 2, 4, 4, 6, 6, 7, 7, 9]], P.eta_gc * x[7] * x[9]]  # noqa: E731
    C_fd = np.column_stack([(y(x0 + e) - y(x0 - e)) / 2 for e in np.eye(10)])
    np.testing.assert_allclose(lin.C, C_fd, rtol=1e-9)
    np.testing.assert_allclose(lin.y0, y(x0), rtol=1e-12)


def test_lpv_schedule_reproduces_the_pointwise_linearisations():
    sched = wt.lpv_schedule(n_grid=25)
    lo, hi = wt.WIND_PROFILE[:, 1].min(), wt.WIND_PROFILE[:, 1].max()
    assert sched.v_grid[0] == pytest.approx(lo * 0.64)
    assert sched.v_grid[-1] == pytest.approx(hi * 1.36)
    np.testing.assert_array_equal(
        sched.region, np.where(sched.v_grid > wt.rated_wind_speed(), 2, 1)
    )
    for i in (0, 12, 24):
        lin = wt.linearise(float(sched.v_grid[i]))
        A, G = sched.matrices(sched.rho[i])
        np.testing.assert_allclose(A, lin.A, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(G, lin.G, rtol=1e-12, atol=1e-15)
    for g in (1, 2):
        inside = sched.rho[sched.region == g]
        assert np.all(inside >= sched.box[g][0]) and np.all(inside <= sched.box[g][1])
        assert sched.vertices[g].shape == (8, 3)


# ------------------------------------------------------------------------------------------------ wind
def test_wind_profile_and_kaimal_turbulence():
    t = np.arange(0.0, wt.SCENARIO_S, P.ts)
    mean = wt.wind_speed(t, seed=0, model="mean")
    np.testing.assert_allclose(mean, np.interp(t, wt.WIND_PROFILE[:, 0], wt.WIND_PROFILE[:, 1]))
    v = wt.wind_speed(t, seed=9)
    np.testing.assert_array_equal(v, wt.wind_speed(t, seed=9))
    u = (v / mean - 1) / wt.TURBULENCE_INTENSITY
    assert u.std() == pytest.approx(1.0, rel=0.15)
    assert abs(u.mean()) < 0.15
    # spectrum (scipy's Welch estimate, 10 seeds of 1310 s) against Kaimal at the mean speed, 0.005-1 Hz
    ts = t[:131_072]
    mean_s = mean[:131_072]
    V = mean_s.mean()
    seg = 2**16
    psd = np.mean(
        [
            welch(
                (wt.wind_speed(ts, seed=s) / mean_s - 1) / wt.TURBULENCE_INTENSITY,
                fs=1 / P.ts,
                nperseg=seg,
            )[1]
            for s in range(10)
        ],
        axis=0,
    )
    f = np.fft.rfftfreq(seg, P.ts)
    band = (f > 0.005) & (f < 1.0)
    kaimal = (4 * wt.LENGTH_SCALE_M / V) / (1 + 6 * f[band] * wt.LENGTH_SCALE_M / V) ** (5 / 3)
    assert np.exp(np.mean(np.log(psd[band] / kaimal))) == pytest.approx(1.0, abs=0.1)


def test_wind_of_a_stretch_shares_its_cached_spectrum():
    """Realisations of one stretch (the same times, a seed each) take the spectral factor from the
    cache (_kaimal_scale, read-only): the same bits as the spectral synthesis written out."""
    from scipy.fft import irfft, next_fast_len, rfft, rfftfreq

    t = 2000.0 + np.arange(2700) * P.ts
    mean = np.interp(t, wt.WIND_PROFILE[:, 0], wt.WIND_PROFILE[:, 1])
    L, V, dt = wt.LENGTH_SCALE_M, float(mean.mean()), float(np.diff(t).mean())
    n_fft = next_fast_len(t.size + int(np.ceil(10 * L / V / dt)), real=True)
    f = rfftfreq(n_fft, dt)
    scale = np.sqrt((4 * L / V) / (1 + 6 * f * L / V) ** (5.0 / 3.0) / (2 * dt))
    wt._kaimal_scale.cache_clear()
    for seed in (3, 4, 3):
        shaped = rfft(np.random.default_rng(seed).standard_normal(n_fft)) * scale
        shaped[0] = 0.0
        want = mean * (1 + wt.TURBULENCE_INTENSITY * irfft(shaped, n_fft)[: t.size])
        assert wt.wind_speed(t, seed=seed).tobytes() == want.tobytes()
    assert wt._kaimal_scale.cache_info().hits == 2
    assert not wt._kaimal_scale(n_fft, dt, L, V).flags.writeable


def test_wind_has_no_jump_beyond_its_turbulence():
    """The wind's increments per sample (what drives ``tau_a``'s, the SVO's ``dtau_bound``) are
    those of a continuous wind: the mean profile moves by at most 8.2e-4 m/s per sample over the
    scenario (its steepest ramp, 4.5 m/s in 55 s), a hundredth of the turbulence's, the
    turbulence's increments have the standard deviation of the Kaimal spectrum's structure
    function at one sample (to 3 %, 20 segments of 37 s at 10 and 16.5 m/s) and the largest is
    within the Gaussian tail (6 standard deviations over 74,000 increments: a join or a step of
    the synthesis would stand far beyond)."""
    whole = wt.wind_speed(np.arange(0.0, wt.SCENARIO_S, P.ts), seed=0, model="mean")
    assert np.abs(np.diff(whole)).max() < 8.2e-4
    for start in (2073.0, 4173.0):  # F1's and F9's segments (partial and full load)
        t = start + np.arange(3700) * P.ts
        mean = wt.wind_speed(t, seed=0, model="mean")
        V, L = mean.mean(), wt.LENGTH_SCALE_M
        f = np.linspace(0.0, 0.5 / P.ts, 2_000_001)
        S = (4 * L / V) / (1 + 6 * f * L / V) ** (5 / 3)
        sigma = math.sqrt(2 * np.trapezoid(S * (1 - np.cos(2 * np.pi * f * P.ts)), f))
        u = np.array([wt.wind_speed(t, seed=s) / mean - 1 for s in range(20)])
        du = np.diff(u / wt.TURBULENCE_INTENSITY, axis=1)
        assert du.std() == pytest.approx(sigma, rel=0.03)
        assert np.abs(du).max() < 6 * sigma


def test_module_examples():
    result = doctest.testmod(wt, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


# ------------------------------------------------------------------------ the benchmark's scenario
def test_every_fault_falls_in_the_benchmarks_operating_region():
    """The benchmark schedule puts each fault where the benchmark's own simulations show it
    (BENCHMARK_REGIONS, read from the thesis's figures), over 4 realisations; the designed schedule
    moves F1 to full load and F9 to partial load (the faults in other operating conditions)."""
    run = wt.simulate(seed=2026, n_realisations=4, dtype=np.float32)
    reg = wt.fault_regions(run)
    assert sorted(reg) == [f"F{i}" for i in range(1, 10)]
    assert all(e["matches"] for e in reg.values()), {
        k: e for k, e in reg.items() if not e["matches"]
    }
    # the criteria, recomputed by hand for F1 (zero pitch, partial load) and F4 (>= 3 sigma)
    on = run.fault_active > 0
    assert (run.region[:, on[:, 0]] == 1).mean() > 0.9
    k1 = int(np.argmax(on[:, 0]))
    assert abs(run.beta[:, k1 - 1000 : k1].mean()) < 0.1
    wr = run.omega_r[:, on[:, 3]].mean()
    assert reg["F4"]["offset_sigma"] == pytest.approx((1.4 - wr) / P.std_omega_r, rel=1e-5)
    assert reg["F4"]["offset_sigma"] >= 3.0
    assert (run.region[:, on[:, 8]] == 2).mean() > 0.8 and run.beta[:, on[:, 8]].mean() > 3.0
    other = wt.fault_regions(
        wt.simulate(seed=2026, n_realisations=2, dtype=np.float32, schedule="designed")
    )
    assert other["F1"]["region"] == 2 and other["F9"]["region"] == 1 and not other["F1"]["matches"]
    with pytest.raises(ModelError, match="schedule: expected one of"):
        wt.wind_speed(np.arange(0.0, 1.0, 0.01), seed=0, schedule="measured")


def test_noise_readings_change_the_fault_sizes_in_sigma():
    """F4 and F8 in noise standard deviations under the two readings of the script's sigma_*."""
    var = wt.benchmark_params()
    std = wt.benchmark_params(noise_reading="std")
    assert var == P
    assert std.std_tau_g == 90.0 and std.std_omega_r == pytest.approx(0.004 * 2 * math.pi)
    f4, f8 = fault(4), fault(8)
    sizes = {}
    for name, p in (("variance", var), ("std", std)):
        run = wt.simulate(
            seed=5,
            faults=(shifted(f4, 30.0), shifted(f8, 140.0)),
            duration_s=250.0,
            wind=turbulent(7.0, 250.0, 5) * np.r_[np.ones(11_000), np.full(14_000, 16.0 / 7.0)],
            params=p,
        )
        sizes[name] = wt.fault_regions(run)
    # the converter offset: 100 N m over sqrt(90) = 10.5 sigma, or over 90 = 1.1 sigma
    assert sizes["variance"]["F8"]["offset_sigma"] == pytest.approx(100 / math.sqrt(90), rel=1e-12)
    assert sizes["std"]["F8"]["offset_sigma"] == pytest.approx(100 / 90, rel=1e-12)
    # the rotor-speed sensor: read as standard deviations, sigma is 6.3 times smaller
    ratio = sizes["std"]["F4"]["offset_sigma"] / sizes["variance"]["F4"]["offset_sigma"]
    assert ratio == pytest.approx(1 / math.sqrt(0.004 * 2 * math.pi), rel=0.02)
    with pytest.raises(ModelError, match="noise_reading: expected one of"):
        wt.benchmark_params(noise_reading="sigma")


# ----------------------------------------------------------------------------------- accommodation
def test_accommodation_switches_the_controller_to_the_healthy_twin():
    """Switched off before it fails, a stuck pitch sensor no longer reaches the plant: the states
    equal those of the fault-free run with the same sensor switched off (same wind, same noise);
    switched off later, the states are the faulty run's up to the switch. F5's faulty sensors are
    not read by the controller (it reads omega_g,m1), so F5 leaves the plant untouched."""
    f1 = shifted(fault(1), 20.0)
    wind = turbulent(9.0, 60.0, 3)
    kw = dict(seed=3, duration_s=60.0, wind=wind)
    free_off = wt.simulate(faults=(), **kw)
    faulty = wt.simulate(faults=(f1,), **kw)
    early = wt.simulate(faults=(f1,), accommodation={1: 0.0}, **kw)
    late = wt.simulate(faults=(f1,), accommodation={1: 25.0}, **kw)
    # the fault-free run reading only beta_1,m2 from t = 0 (the fault "accommodated" before it acts)
    f1_never = dataclasses.replace(f1, start_s=59.0, stop_s=59.5)
    free_m2 = wt.simulate(faults=(f1_never,), accommodation={1: 0.0}, **kw)
    np.testing.assert_array_equal(early.state[:5900], free_m2.state[:5900])
    assert not np.array_equal(early.state, free_off.state)  # m2's noise alone, not the mean
    np.testing.assert_array_equal(late.state[:2501], faulty.state[:2501])
    dev_faulty = np.abs(faulty.beta[3000:4000, 0] - free_off.beta[3000:4000, 0]).mean()
    dev_late = np.abs(late.beta[3000:4000, 0] - free_off.beta[3000:4000, 0]).mean()
    assert dev_faulty > 1.0 and dev_late < 0.2 * dev_faulty
    f5 = shifted(fault(5), 20.0)
    np.testing.assert_array_equal(wt.simulate(faults=(f5,), **kw).state, free_off.state)
    # per-realisation times, NaN = not isolated (that realisation keeps the faulty sensor)
    twice = [np.random.SeedSequence(3)] * 2
    both = wt.simulate(
        seed=twice,
        faults=(f1,),
        duration_s=60.0,
        wind=wind,
        accommodation={1: np.array([25.0, np.nan])},
    )
    alone = wt.simulate(seed=twice[:1], faults=(f1,), duration_s=60.0, wind=wind)
    np.testing.assert_array_equal(both.state[1], alone.state[0])


def test_accommodation_refuses_what_it_cannot_do():
    kw = dict(seed=0, duration_s=1.0, wind=10.0)
    for acc, match in (
        ({8: 0.0}, "no healthy redundant sensor"),
        ({6: 0.0}, "no healthy redundant"),
        ({7: 0.0}, "not in the run's faults"),
        ({1: -1.0}, "isolation times >= 0"),
        ({1: np.inf}, "isolation times >= 0"),
        ([1, 2], "expected a mapping"),
    ):
        with pytest.raises(ModelError, match=match):
            wt.simulate(faults=(fault(1), fault(6), fault(8)), accommodation=acc, **kw)
    m2 = wt.Fault(
        10, "beta_1,m2 x2", "sensor_gain", ("beta_1_m2",), 2500.0, 2600.0, (2.0,), None, "test"
    )
    with pytest.raises(ModelError, match="both beta_1_m1 and beta_1_m2 would be switched off"):
        wt.simulate(faults=(fault(1), m2), accommodation={1: 0.0, 10: 0.0}, **kw)


# ----------------------------------------------------------------------------- limits, typed errors
def test_plant_api_limits_and_typed_errors():
    from fdi_lib.errors import ResourceError

    for v in (1e-6, 1.0, 36.0, 1e4):
        with pytest.raises(ModelError, match=r"v: expected wind speeds in \[2, 35\]"):
            wt.operating_point(v)
        with pytest.raises(ModelError, match=r"wind: expected wind speeds in \[2, 35\]"):
            wt.simulate(seed=0, duration_s=1.0, wind=v)
    assert wt.operating_point(2.0).lam >= 1.0 and wt.operating_point(35.0).beta < 45.0
    with pytest.raises(ModelError, match=r"wind \(the schedule's turbulent wind\): expected"):
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(wt, "TURBULENCE_INTENSITY", 0.12)
            mp.setitem(wt.WIND_SCHEDULES, "benchmark", np.array([[0.0, 34.0], [4400.0, 34.0]]))
            wt.simulate(seed=0, duration_s=100.0)
    # sizes: refused with the estimate before anything is allocated
    with pytest.raises(
        ResourceError, match=r"n_realisations: 1000000 realisation\(s\) .* GB, over the budget"
    ):
        wt.simulate(seed=0, n_realisations=10**6)
    with pytest.raises(ResourceError, match="over the budget"):
        wt.simulate(seed=0, duration_s=1e6)
    assert wt.simulation_bytes(440_000, 1) == pytest.approx(116e6, rel=0.2)  # the docstring's
    for bad, match in (
        (dict(duration_s=-1.0), "duration_s"),
        (dict(duration_s=np.nan), "duration_s"),
        (dict(n_realisations=0), "n_realisations"),
        (dict(n_realisations=2.5), "n_realisations"),
        (dict(dtype="int8"), "dtype"),
        (dict(dtype="no such type"), "dtype"),
        (dict(schedule="calm"), "schedule"),
        (dict(seed=-1), "seed"),
    ):
        with pytest.raises(FDIError, match=match):
            wt.simulate(**{"seed": 0, "duration_s": 1.0, "wind": 10.0, **bad})


def test_duplicate_faults_are_refused():
    """Listing a gain or converter fault twice used to compound it silently (F2, F5, F8)."""
    for i in (2, 5, 8, 1, 6, 9):
        with pytest.raises(ModelError, match=rf"each fault once, got fault id\(s\) \[{i}\]"):
            wt.simulate(seed=0, duration_s=1.0, wind=10.0, faults=(fault(i), fault(i)))
    other = dataclasses.replace(fault(2), id=12, start_s=2350.0, stop_s=2450.0)
    with pytest.raises(ModelError, match="faults 2 and 12 both act on beta_2_m2 over overlapping"):
        wt.simulate(seed=0, duration_s=1.0, wind=10.0, faults=(fault(2), other))
    later = dataclasses.replace(fault(2), id=12, start_s=2400.0, stop_s=2500.0)  # back to back
    wt.simulate(seed=0, duration_s=1.0, wind=10.0, faults=(fault(2), later))


def test_method_settings_are_validated():
    from fdi_lib import windturbine as W

    for bad, match in (
        (dict(pre_s=-1.0), "pre_s"),
        (dict(post_s=0.0), "post_s"),
        (dict(window=0), "window"),
        (dict(window=2.5), "window"),
        (dict(isolation_alpha=1.0), "isolation_alpha"),
        (dict(warmup_s=7.0), "warmup_s: expected less than pre_s"),
        (dict(svo_sigmas=float("nan")), "svo_sigmas"),
        (dict(isolation_extra=-1), "isolation_extra"),
        (dict(false_alarms_per_hour=0.0), "false_alarms_per_hour"),
    ):
        with pytest.raises(FDIError, match=match):
            W.Settings(**bad)
    assert W.Settings() == W.Settings(pre_s=7.0)
