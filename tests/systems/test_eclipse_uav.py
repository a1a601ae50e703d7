"""Eclipse UAV model of Rosa & Silvestre (2013), eqs. (14)-(16): discretisation, LQG loop, SVO bounds."""

from __future__ import annotations

import numpy as np
import pytest

from fdi_lib.errors import ModelError
from fdi_lib.sets.svo import run_svo
from fdi_lib.systems import eclipse_uav as uav
from fdi_lib.reproduce.rosa2013 import UAV_X0


def test_mu_reading_and_matrices_at_trim():
    A, B = uav.lpv_matrices(37.0)
    assert A[3, 0] == pytest.approx(2.6146e-5 * 37**2 - 0.003426 * 37 - 0.1425, rel=1e-12)
    assert A[1, 3] == pytest.approx(1.012 * 37 - 0.77)
    assert B[0, 1] == 24.76 and B[3, 1] == -0.294
    A2, B2 = uav.lpv_matrices(37.0, mu_scale=1.3, elevator_eff=0.5)
    assert A2[3, 0] == pytest.approx(1.3 * A[3, 0])
    np.testing.assert_allclose(B2[:, 0], 0.5 * B[:, 0])


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
    assert max(abs(np.linalg.eigvals(lqg.A))) > 1.0     # the open loop of (16) is unstable


def test_healthy_run_respects_bounds_and_nominal_svo_stays_nonempty():
    run = uav.simulate("none", "step", rng=np.random.default_rng(3), duration=1.5)
    assert np.abs(run.x).max() < 2.0
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
    with pytest.raises(ModelError, match="kind: expected"):
        uav.svo_models(uav.simulate(rng=np.random.default_rng(0), duration=0.05), "rudder")


def test_elevator_and_mu_faults_reach_the_plant():
    """Same seed: identical before the onset, then a pitch-rate difference of many noise bounds."""
    h = uav.simulate("none", "step", rng=np.random.default_rng(5), duration=1.0)
    for fault in ("elevator", "dynamics"):
        f = uav.simulate(fault, "step", rng=np.random.default_rng(5), duration=1.0)
        k = f.onset_step
        np.testing.assert_array_equal(f.y[:k + 1], h.y[:k + 1])   # the fault acts from u(k) on
        assert np.abs(f.y[k + 1:, 3] - h.y[k + 1:, 3]).max() > 5 * uav.NOISE_BOUND[3]
        assert np.all(np.abs(f.y[k + 1:, 3] - h.y[k + 1:, 3]) > 0)


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
