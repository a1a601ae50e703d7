"""The surrogate gas pipeline model of Zhang & Basseville (2014), Section 6.2."""

import numpy as np
import pytest
import scipy.linalg

from fdi_lib.errors import CovarianceError, ModelError, ShapeError
from fdi_lib.filters import kalman_gains
from fdi_lib.models import ltv_model
from fdi_lib.simulate import simulate
from fdi_lib.systems import gas_pipeline as gp


@pytest.fixture(scope="module")
def model():
    return gp.pipeline_model()


def test_stated_values_are_kept(model):
    p = gp.pipeline_schedule()
    mats = gp.pipeline_matrices()
    assert mats.G0[0, 0] == -7.8297e-4
    assert mats.Gp[0, 0] == 3.8290e-5
    np.testing.assert_allclose(model.G[:, 0, 0], -7.8297e-4 + 3.8290e-5 * p, rtol=0, atol=1e-18)
    assert model.R[0, 0, 0] == 3.0273e5
    assert model.n_steps == 500 and gp.N_STEPS * gp.TS_MIN == gp.RECORD_MIN == 1000.0
    # Q: the printed matrix up to its rounding (entries given to 4 decimals).
    np.testing.assert_allclose(model.Q[0], gp.Q_PRINTED, rtol=0, atol=1e-4)
    assert gp.LEAK_SIZE == -0.1 * gp.MEAN_FLOW


def test_printed_q_is_indefinite_and_rejected_projection_is_nearest_psd():
    assert np.linalg.det(gp.Q_PRINTED) < 0
    with pytest.raises(CovarianceError, match="positive semi-definite"):
        ltv_model(F=np.eye(2) * 0.5, H=[[1.0, 0.0]], Q=gp.Q_PRINTED, R=1.0, n_steps=3)
    Qp = gp.projected_q()
    assert np.linalg.eigvalsh(Qp)[0] >= -1e-12
    # Nearest PSD in Frobenius norm: the distance equals |negative eigenvalue| (Higham).
    neg = np.linalg.eigvalsh(gp.Q_PRINTED)[0]
    assert np.linalg.norm(Qp - gp.Q_PRINTED) == pytest.approx(abs(neg), rel=1e-6)
    # Any other PSD candidate (random rank-one perturbations) is farther away.
    rng = np.random.default_rng(1)
    for _ in range(50):
        v = rng.standard_normal(2)
        cand = Qp + 1e-4 * np.outer(v, v)
        assert np.linalg.norm(cand - gp.Q_PRINTED) >= np.linalg.norm(Qp - gp.Q_PRINTED) - 1e-12
    with pytest.raises(ShapeError, match="Q: expected a square matrix"):
        gp.projected_q(np.ones((2, 3)))


def test_stable_and_observable(model):
    assert np.max(np.abs(np.linalg.eigvals(model.F))) < 1.0
    O = np.vstack([model.H[0], model.H[0] @ model.F[0]])
    assert np.linalg.matrix_rank(O) == 2
    # Controllable from the (rank-one) noise direction, as the Kalman theory assumes.
    q = scipy.linalg.sqrtm(model.Q[0]).real @ np.ones(2)
    C = np.column_stack([q, model.F[0] @ q])
    assert np.linalg.matrix_rank(C, tol=1e-8 * np.linalg.norm(C)) == 2


def test_mass_balance_and_leak_direction():
    rep = gp.design_report()
    assert rep["dc_gain_min"] == pytest.approx(1.0, abs=1e-12)
    assert rep["dc_gain_max"] == pytest.approx(1.0, abs=1e-12)
    assert rep["leak_gain"] > 0                       # depressing G(1) loses gas
    assert 0 < rep["fault1_leak_fraction"] < rep["fault2_leak_fraction"] < 0.2
    assert abs(rep["fault1_innovation_shift_sd"]) < 2.0     # "hardly visible"
    assert rep["output_std_from_W"] == pytest.approx(rep["sqrt_R"], rel=1e-9)


def test_input_and_schedule_patterns():
    u, p = gp.pipeline_input(), gp.pipeline_schedule()
    assert u.shape == p.shape == (500,)
    assert np.all(u > 0) and 0.75 < u.min() / u.max() < 0.95
    assert 4.8 < p.min() and p.max() < 6.2
    # Noise-free output mean is the paper's 439800 (independent loop with the LTV arrays).
    m = gp.pipeline_model()
    x = m.x0.copy()
    y = []
    for k in range(m.n_steps):
        y.append(m.H[k] @ x + m.J[k] @ [u[k]])
        x = m.F[k] @ x + m.G[k] @ [u[k]]
    assert np.mean(y) == pytest.approx(gp.MEAN_FLOW, rel=1e-12)


def test_stationary_kalman_and_simulation(model):
    g = kalman_gains(model)
    np.testing.assert_allclose(g.P[-1], g.P[0], rtol=1e-8)
    sim = simulate(model, rng=np.random.default_rng(3), u=gp.pipeline_input(), size=20)
    rel = np.abs(sim.y.mean(axis=(0, 1))[0] / gp.MEAN_FLOW - 1)
    assert rel < 0.01


def test_fault_profiles(model):
    psi = gp.input_fault_psi()
    assert psi.shape == (500, 2, 2)
    np.testing.assert_array_equal(psi[:, 0, 0], gp.pipeline_input())
    np.testing.assert_allclose(psi[:, 0, 1], gp.pipeline_schedule() * gp.pipeline_input())
    assert not psi[:, 1].any()
    fam = gp.input_fault_family(model)
    prof = fam.profile(300)
    assert not prof.Psi[:300].any() and np.array_equal(prof.Psi[300:], psi[300:])
    leak = gp.output_leak_family(model).profile(350)
    assert leak.Phi[349, 0, 0] == 0 and leak.Phi[350, 0, 0] == 1
    # A depression of G(1) by theta via Psi equals the same change in the model's G.
    th = np.array([gp.FAULT1_DELTA, 0.0])
    faulty = gp.pipeline_model()
    sim_a = simulate(faulty, rng=np.random.default_rng(0), u=gp.pipeline_input(),
                     fault=fam.profile(0), theta=th)
    G_changed = np.array(faulty.G)
    G_changed[:, 0, 0] += gp.FAULT1_DELTA
    m2 = ltv_model(F=faulty.F, G=G_changed, H=faulty.H, J=faulty.J, Q=faulty.Q, R=faulty.R,
                   n_steps=500, x0=faulty.x0, P0=faulty.P0)
    sim_b = simulate(m2, noise=sim_a.noise, u=gp.pipeline_input())
    np.testing.assert_allclose(sim_a.y, sim_b.y, rtol=1e-12)


def test_bad_inputs():
    with pytest.raises(ModelError, match="n_steps: expected a positive integer"):
        gp.pipeline_model(0)
    with pytest.raises(ShapeError, match=r"schedule: expected shape \(500,\)"):
        gp.pipeline_model(schedule=np.ones(10))
    with pytest.raises(ModelError, match="minutes: expected a multiple"):
        gp.minutes_to_index(601.0)
    assert gp.minutes_to_index(600.0) == 300


def test_noise_free_output_equals_a_direct_recursion():
    import numpy as np

    from fdi_lib import systems

    gp = systems.gas_pipeline
    u, p = gp.pipeline_input(), gp.pipeline_schedule()
    mats = gp.pipeline_matrices()
    x = np.linalg.solve(np.eye(2) - mats.F0, (mats.G0[:, 0] + mats.Gp[:, 0] * p[0]) * u[0])
    expected = np.empty(u.shape)
    for k in range(u.shape[0]):  # eq. (53) without noise, written out
        expected[k] = mats.H0[0] @ x + (mats.J0[0, 0] + mats.Jp[0, 0] * p[k]) * u[k]
        x = mats.F0 @ x + (mats.G0[:, 0] + mats.Gp[:, 0] * p[k]) * u[k]
    np.testing.assert_allclose(gp.noise_free_output(u, p), expected, rtol=1e-12)
    assert abs(gp.noise_free_output(u, p).mean() - gp.MEAN_FLOW) < 1e-6 * gp.MEAN_FLOW
