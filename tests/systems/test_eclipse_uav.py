"""Eclipse UAV model of Rosa & Silvestre (2013), eqs. (14)-(16): discretisation, LQG loop, SVO bounds."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.sets.svo import run_svo
from fdi_lib.systems import eclipse_uav as uav
from fdi_lib.reproduce.rosa2013 import UAV_X0


def test_matrices_at_trim_against_hand_values():
    """Entries of (16) at 37 m/s, evaluated by hand (not with the module's formulas)."""
    A, B = uav.lpv_matrices(37.0, eta_unit="rad")
    assert A[3, 0] == pytest.approx(-0.2334681, abs=1e-6)  # M_u: 0.0357939 - 0.126762 - 0.1425
    assert A[3, 1] == pytest.approx(-1.041155, abs=1e-6)  # M_w
    assert A[1, 3] == pytest.approx(36.674, abs=1e-9)  # Z_q
    assert B[3, 0] == pytest.approx(0.287005, abs=1e-6)  # M_eta: 0.28749 - 0.00555 + 0.005065
    assert B[0, 1] == 24.76 and B[3, 1] == -0.294
    Ad, Bd = uav.lpv_matrices(37.0, eta_unit="deg")
    np.testing.assert_array_equal(Ad, A)
    np.testing.assert_allclose(Bd[:, 0], B[:, 0] * 180 / np.pi, rtol=1e-14)
    np.testing.assert_array_equal(Bd[:, 1], B[:, 1])
    A2, B2 = uav.lpv_matrices(37.0, mu_scale=1.3, elevator_eff=0.5, eta_unit="rad")
    assert A2[3, 0] == pytest.approx(1.3 * -0.2334681, abs=1e-6)
    assert B2[3, 0] == pytest.approx(0.5 * 0.287005, abs=1e-6)


def test_pitch_authority_of_both_readings():
    """C_m_eta / |C_m_alpha| = M_eta / |M_w V|: 0.287005 / 38.5227 per rad, 57.2958 times that per deg."""
    rad, deg = uav.pitch_authority("rad"), uav.pitch_authority("deg")
    assert rad["ratio"] == pytest.approx(0.287005 / 38.522735, rel=1e-5)
    assert deg["ratio"] == pytest.approx(0.287005 * 57.29578 / 38.522735, rel=1e-5)
    qbar_sc_over_iy = 0.5 * 1.225 * 37.0**2 * 2.365 * 1.34 / 10.43
    assert deg["Cm_eta"] == pytest.approx(16.44418 / qbar_sc_over_iy, rel=1e-5)
    assert rad["Cm_alpha"] == pytest.approx(-38.522735 / qbar_sc_over_iy, rel=1e-6)


def test_fast_paths_match_direct_formulas():
    """Batched discretisation and the polynomial plant derivative against the direct routes."""
    import control

    V = np.array([25.0, 37.0, 48.5])
    for unit in uav.ETA_UNITS:
        Ad, Bd = uav.discretize_many(V, 1.15, 0.75, eta_unit=unit)
        for i, v in enumerate(V):
            A, B = uav.lpv_matrices(v, 1.15, 0.75, eta_unit=unit)
            sysd = control.c2d(control.ss(A, B, np.eye(4), np.zeros((4, 2))), uav.TS, method="zoh")
            np.testing.assert_allclose(Ad[i], sysd.A, atol=1e-12)
            np.testing.assert_allclose(Bd[i], sysd.B, atol=1e-12)
    rng = np.random.default_rng(0)
    x, d, e = rng.normal(0, 0.3, 4), rng.normal(0, 0.05, 2), rng.uniform(-1, 1, 3)
    xs = uav.trim_state()
    Vx = np.hypot(xs[0] + x[0], xs[1] + x[1])
    A, B = uav.lpv_matrices(Vx, 1.3, 0.5)
    expected = A @ x + B @ d + np.r_[-x[3] * x[1] + A[0, 2] * (np.sin(x[2]) - x[2]), 0, 0, 0]
    expected[[0, 1, 3]] += uav.DIST_ACCEL * e
    np.testing.assert_allclose(
        uav.plant_derivative(x, d, e, 1.3, 0.5), expected, rtol=1e-12, atol=1e-14
    )
    # "total" mode: the loss also removes half of the trim deflection's effect, the M_u change acts on u*
    A1, B1 = uav.lpv_matrices(Vx)
    total = expected - 0.5 * B1[:, 0] * uav.ETA_TRIM
    total[3] += 0.3 * A1[3, 0] * xs[0]
    np.testing.assert_allclose(
        uav.plant_derivative(x, d, e, 1.3, 0.5, fault_mode="total"), total, rtol=1e-12, atol=1e-14
    )


def test_zoh_matches_python_control():
    import control

    A, B = uav.lpv_matrices(35.0)
    sysd = control.c2d(control.ss(A, B, np.eye(4), np.zeros((4, 2))), uav.TS, method="zoh")
    Ad, Bd = uav.zoh(A, B)
    np.testing.assert_allclose(Ad, sysd.A, atol=1e-12)
    np.testing.assert_allclose(Bd, sysd.B, atol=1e-12)


def test_lqg_closed_loop_is_stable():
    lqg = uav.design_lqg()
    assert max(abs(np.linalg.eigvals(lqg.A - lqg.B @ lqg.K))) < 1.0
    assert max(abs(np.linalg.eigvals(lqg.A - lqg.L @ lqg.C))) < 1.0
    assert max(abs(np.linalg.eigvals(lqg.A))) > 1.0  # the open loop of (16) is unstable


@pytest.mark.parametrize("seed", [3, 11])
def test_containment_under_a_larger_manoeuvre(seed):
    """+-3.6 m/s airspeed commands (3 s): the true state stays in every nominal SVO set (eta per degree)."""
    run = uav.simulate("none", "step", rng=np.random.default_rng(seed), duration=3.0, amplitude=3.6)
    assert np.ptp(run.y[:, 0]) > 5.0  # the manoeuvre is large: > 5 m/s of airspeed swing
    res = run_svo(uav.svo_models(run, "nominal"), run.u, run.y, UAV_X0, keep_sets=True)
    assert res.empty_at is None
    assert all(S.contains(run.x[k], 1e-7) for k, S in enumerate(res.sets))


def test_fault_profiles():
    t = np.array([0.0, 0.49, 0.5, 1.0, 1.5, 4.5, 5.0])
    np.testing.assert_allclose(uav.fault_profile(t, "step"), [0, 0, 1, 1, 1, 1, 1])
    np.testing.assert_allclose(uav.fault_profile(t, "hard"), [0, 0, 0, 0.5, 1, 1, 1])
    np.testing.assert_allclose(uav.fault_profile(t, "soft"), [0, 0, 0, 0.125, 0.25, 1, 1])


def test_alpha_step_fault_is_detected_in_one_sample():
    run = uav.simulate("alpha", "step", rng=np.random.default_rng(4), duration=0.8)
    assert run_svo(uav.svo_models(run, "nominal"), run.u, run.y, UAV_X0).empty_at == run.onset_step


def test_bad_inputs():
    with pytest.raises(ModelError, match="fault: expected 'none' or one of"):
        uav.simulate("rudder", rng=np.random.default_rng(0))
    with pytest.raises(ModelError, match="scenario: expected one of"):
        uav.simulate("alpha", "abrupt", rng=np.random.default_rng(0))
    with pytest.raises(TypeError, match="rng: expected numpy.random.Generator"):
        uav.simulate("alpha", rng=0)
    with pytest.raises(ModelError, match="V: expected a positive finite airspeed"):
        uav.lpv_matrices(-1.0)
    with pytest.raises(ModelError, match="eta_unit: expected one of"):
        uav.lpv_matrices(37.0, eta_unit="grad")
    with pytest.raises(ModelError, match="fault_mode: expected one of"):
        uav.simulate("elevator", rng=np.random.default_rng(0), fault_mode="trim")
    with pytest.raises(ModelError, match="kind: expected"):
        uav.svo_models(uav.simulate(rng=np.random.default_rng(0), duration=0.05), "rudder")


def test_elevator_and_mu_faults_reach_the_plant():
    """Same seed: identical before the onset, then a pitch-rate difference (in noise bounds)."""
    h = uav.simulate("none", "step", rng=np.random.default_rng(5), duration=1.0)
    for fault, mode, least in (
        ("elevator", "deviation", 5),
        ("dynamics", "deviation", 1),
        ("dynamics", "total", 50),
    ):
        f = uav.simulate(fault, "step", rng=np.random.default_rng(5), duration=1.0, fault_mode=mode)
        k = f.onset_step
        np.testing.assert_array_equal(f.y[: k + 1], h.y[: k + 1])  # the fault acts from u(k) on
        assert np.abs(f.y[k + 1 :, 3] - h.y[k + 1 :, 3]).max() > least * uav.NOISE_BOUND[3]
        assert np.all(np.abs(f.y[k + 1 :, 3] - h.y[k + 1 :, 3]) > 0)
    # total speed: one sample after the onset, 0.3 M_u u* Ts of pitch rate (the LQG has not reacted yet)
    f = uav.simulate(
        "dynamics", "step", rng=np.random.default_rng(5), duration=0.6, fault_mode="total"
    )
    k = f.onset_step
    assert f.y[k + 1, 3] - h.y[k + 1, 3] == pytest.approx(
        0.3 * -0.2334681 * 36.998 * uav.TS, rel=0.05
    )


def test_svo_model_scales():
    run = uav.simulate(rng=np.random.default_rng(0), duration=0.05)
    m1, m2 = uav.svo_models(run)(0), uav.svo_models(run, dist_scale=0.25, noise_scale=0.5)(0)
    np.testing.assert_allclose(m2.L, 0.25 * m1.L)
    np.testing.assert_allclose(m2.noise, 0.5 * m1.noise)
    np.testing.assert_allclose(m2.A, m1.A)
    for bad in (-1.0, np.nan, "1"):
        with pytest.raises(ModelError, match="dist_scale: expected a finite non-negative number"):
            uav.svo_models(run, dist_scale=bad)
    with pytest.raises(ModelError, match="noise_scale"):
        uav.svo_models(run, noise_scale=np.inf)


def test_integration_step_is_fine_enough():
    """The default RK4 step (2 per sample) against 10 per sample: outputs within 1e-5 noise bounds."""
    a = uav.simulate("elevator", "hard", rng=np.random.default_rng(1), duration=2.0)
    b = uav.simulate("elevator", "hard", rng=np.random.default_rng(1), duration=2.0, substeps=10)
    assert np.all(np.abs(a.y - b.y).max(axis=0) < 1e-5 * uav.NOISE_BOUND)


def _reference_loop(fault, scenario, rng, duration, substeps=2):
    """The closed loop written out one run at a time with matrix products and plant_derivative."""
    K = int(round(duration / uav.TS))
    t = np.arange(K + 1) * uav.TS
    lqg = uav.design_lqg()
    dist = uav._bounded_lowpass(rng, K, 3, 0.9)
    noise = uav._bounded_lowpass(rng, K + 1, 4, 0.5) * uav.NOISE_BOUND
    p = uav.fault_profile(t, scenario) * uav._fault_size(fault, scenario)
    exc = uav.excitation(t[:-1])
    x, xhat, h = np.zeros(4), np.zeros(4), uav.TS / substeps
    ys = []
    for k in range(K + 1):
        y = uav.measure(x) + noise[k] + np.r_[0.0, p[k] * (fault == "alpha"), 0.0, 0.0]
        ys.append(y)
        if k == K:
            break
        uk = -lqg.K @ xhat + exc[k]
        xhat = lqg.A @ xhat + lqg.B @ uk + lqg.L @ (y - lqg.C @ xhat)
        mu = 1.0 + p[k] * (fault == "dynamics")
        eff = 1.0 - p[k] * (fault == "elevator")

        def f(z):
            return uav.plant_derivative(z, uk, dist[k], mu, eff)

        for _ in range(substeps):
            k1 = f(x)
            k2 = f(x + h / 2 * k1)
            k3 = f(x + h / 2 * k2)
            k4 = f(x + h * k3)
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return np.array(ys)


def test_simulate_many_matches_one_run_loops_and_is_batch_independent():
    cases = [("none", "step"), ("alpha", "hard"), ("elevator", "step"), ("dynamics", "soft")]
    seeds = np.random.SeedSequence(11).spawn(len(cases))
    runs = uav.simulate_many(cases, [np.random.default_rng(s) for s in seeds], duration=0.8)
    for (fault, scenario), s, r in zip(cases, seeds, runs):
        ref = _reference_loop(fault, scenario, np.random.default_rng(s), 0.8)
        assert np.all(np.abs(r.y - ref) <= 1e-9 * uav.NOISE_BOUND)
        one = uav.simulate(fault, scenario, rng=np.random.default_rng(s), duration=0.8)
        np.testing.assert_array_equal(one.y, r.y)
        np.testing.assert_array_equal(one.x, r.x)
        assert (one.fault, one.scenario, one.onset_step) == (r.fault, r.scenario, r.onset_step)
    with pytest.raises(ShapeError, match="rngs"):
        uav.simulate_many(cases, [np.random.default_rng(0)])


def test_simulate_many_takes_one_amplitude_per_case():
    """Per-case airspeed commands (the envelope study simulates its amplitudes together): each run
    the same, bit for bit, as simulated alone with its amplitude."""
    amps = [0.0, 3.0, 7.0]
    rngs = [np.random.default_rng(1) for _ in amps]
    runs = uav.simulate_many([("none", "step")] * 3, rngs, duration=0.6, amplitude=amps)
    for a, r in zip(amps, runs):
        one = uav.simulate("none", "step", rng=np.random.default_rng(1), duration=0.6, amplitude=a)
        np.testing.assert_array_equal(one.x, r.x)
        np.testing.assert_array_equal(one.u, r.u)
    assert np.abs(runs[2].y[:, 0] - runs[0].y[:, 0]).max() > 0.1
    cases, rngs = [("none", "step")] * 3, [np.random.default_rng(0)] * 3
    with pytest.raises(ShapeError, match="amplitude: expected one value or one per case"):
        uav.simulate_many(cases, rngs, duration=0.1, amplitude=[1.0, 2.0])
    with pytest.raises(ModelError, match="amplitude: expected finite non-negative"):
        uav.simulate_many(cases, rngs, duration=0.1, amplitude=[1.0, -2.0, 0.0])


def test_svo_model_bank_is_svo_models_of_each_kind():
    """The bank shares the discretisations of its kinds (nominal and alpha: the same A_d, B_d):
    each model bit for bit the one svo_models builds alone."""
    run = uav.simulate("elevator", "hard", rng=np.random.default_rng(3), duration=0.6)
    kinds = {"nominal": 0.0, "alpha": 0.0, "elevator": 4.0, "dynamics": 4.0, "global": 1.0}
    bank = uav.svo_model_bank(run, kinds, dist_scale=0.5)
    assert list(bank) == list(kinds)
    for kind, slack in kinds.items():
        one = uav.svo_models(run, kind, alpha_slack_deg=slack, dist_scale=0.5)
        for name in ("A", "B", "C", "L", "noise", "A_unc", "B_unc"):
            np.testing.assert_array_equal(getattr(bank[kind], name), getattr(one, name))
    with pytest.raises(ModelError, match="alpha_slack_deg: expected a finite non-negative"):
        uav.svo_model_bank(run, {"nominal": 0.0, "elevator": -1.0})
    with pytest.raises(ModelError, match="kind: expected"):
        uav.svo_model_bank(run, {"rudder": 0.0})


def test_batched_expm_against_scipy():
    """The vectorised exponential against scipy.linalg.expm on random stacks of several norms
    (zero, small, and large enough to need squaring), and batch independence."""
    from scipy.linalg import expm

    rng = np.random.default_rng(3)
    E = (
        rng.normal(size=(12, 6, 6))
        * np.array([0, 1e-3, 0.1, 0.5, 1, 2, 4, 8, 0.01, 0.2, 3, 6])[:, None, None]
    )
    F = uav._expm_many(E)
    for e, f in zip(E, F):
        ref = expm(e)
        assert np.abs(f - ref).max() <= 1e-12 * (1.0 + np.abs(ref).max())
    np.testing.assert_array_equal(uav._expm_many(E[3:5]), F[3:5])


def test_batched_expm_has_the_bits_of_the_plain_recursion():
    """The buffered recursion of _expm_many (first Horner step I + X/16, products for the divisions
    by powers of 2, squaring in place or of the rows that need it) gives the bits of the plain
    one, F = I + (X @ F) / k from F = I, squared
    by np.where: on the UAV's discretisations, on random stacks whose matrices need different
    numbers of squarings, and on zeros (signed)."""

    def plain(E):
        norm = np.abs(E).sum(axis=2).max(axis=1)
        s = np.maximum(0, np.ceil(np.log2(np.maximum(norm, 1e-300) / 0.25))).astype(int)
        X = E * (0.5**s)[:, None, None]
        eye = np.eye(E.shape[1])
        F = np.broadcast_to(eye, E.shape).copy()
        for k in range(16, 0, -1):
            F = eye + (X @ F) / k
        for j in range(int(s.max(initial=0))):
            F = np.where((j < s)[:, None, None], F @ F, F)
        return F

    rng = np.random.default_rng(5)
    P = uav._polynomial(1.15, 0.75, "deg")
    V = uav.V_TRIM + rng.uniform(-4.0, 4.0, 300)
    E_uav = np.zeros((V.size, 6, 6))
    E_uav[:, :4, :] = P[0] + V[:, None, None] * P[1] + V[:, None, None] ** 2 * P[2]
    E_mix = rng.normal(size=(40, 6, 6)) * rng.choice([0.0, 1e-3, 0.3, 2.0, 9.0], 40)[:, None, None]
    E_mix[0] = -0.0
    for E in (E_uav * uav.TS, E_mix, E_mix[:0]):
        assert uav._expm_many(E).tobytes() == plain(E).tobytes()


@pytest.mark.parametrize("eta_unit,seed,amplitude", [("deg", 3, 5.0), ("rad", 3, 3.0)])
def test_envelope_lies_below_the_measured_loss_of_the_true_state(eta_unit, seed, amplitude):
    """The runs of the envelope study that lost the true state at the smallest airspeed deviation:
    the envelope is the largest multiple of 0.5 m/s below it (4.19 -> 4, 2.97 -> 2.5 measured)."""
    from fdi_lib.reproduce.rosa2013_studies import containment_check

    c = containment_check(eta_unit, seed, amplitude=amplitude)
    assert c["outside"] > 0
    assert (
        uav.ENVELOPE_AIRSPEED[eta_unit]
        < c["loss_airspeed"]
        <= uav.ENVELOPE_AIRSPEED[eta_unit] + 0.5
    )


def test_svo_models_warn_when_a_record_leaves_the_envelope():
    from fdi_lib.errors import EnvelopeWarning

    big = uav.simulate("none", "step", rng=np.random.default_rng(0), duration=1.5, amplitude=7.0)
    assert uav.envelope_exceedance(big).size > 0
    with pytest.warns(EnvelopeWarning, match=r"\|y_V\| <= 4.0 m/s"):
        uav.svo_models(big)
    calm = uav.simulate("none", "step", rng=np.random.default_rng(0), duration=1.5)
    assert uav.envelope_exceedance(calm).size == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error", EnvelopeWarning)
        uav.svo_models(calm)


@pytest.mark.parametrize("K, dim, a", [(600, 3, 0.9), (601, 4, 0.5), (2, 1, 0.3), (1, 2, 0.9)])
def test_bounded_lowpass_is_the_recursion_bit_for_bit(K, dim, a):
    """The filtered noise is z_k = a z_{k-1} + (1 - a) w_k from z_0 = w_0, written as a loop, bit
    for bit, scaled into [-1, 1]."""
    for seed in range(20):
        w = np.random.default_rng(seed).uniform(-1.0, 1.0, size=(K, dim))
        z = w.copy()
        for k in range(1, K):
            z[k] = a * z[k - 1] + (1.0 - a) * w[k]
        ref = z / max(1.0, float(np.abs(z).max()))
        got = uav._bounded_lowpass(np.random.default_rng(seed), K, dim, a)
        assert got.tobytes() == ref.tobytes()
        assert np.abs(got).max() <= 1.0
