"""Example 1 of Zhang (2021), eqs. (40)-(42)."""

import numpy as np
import pytest

from fdi_lib.errors import ModelError
from fdi_lib.kitanidis import kitanidis_gains
from fdi_lib.montecarlo import trial_rngs, trial_seeds
from fdi_lib.systems import zhang2021_example1 as ex


def test_matrices_of_eq_41_42():
    A = ex.state_matrices(4)
    k = 3
    np.testing.assert_allclose(
        A[k],
        [[-0.8, 0.7, 0.1 * np.exp(-k)], [-0.6, 0, 0.1 * np.cos(k)], [0.1 * np.sin(k), -0.5, -0.4]],
    )
    m = ex.example1_model(r=20.0)
    assert (m.n, m.p, m.n_steps) == (3, 2, 101)
    np.testing.assert_allclose(m.R[50], 20.0 * np.eye(2))
    np.testing.assert_allclose(m.Q[0], np.eye(3))
    assert np.linalg.matrix_rank(ex.C @ ex.E) == 1  # assumption (iv)
    kitanidis_gains(m, ex.E)  # no RankConditionError
    with pytest.raises(ModelError, match="r: expected a positive noise factor"):
        ex.example1_model(r=0.0)


def test_trials_are_reproducible_and_have_the_stated_distributions():
    m = ex.example1_model()
    t1 = ex.draw_trials(m, trial_rngs(trial_seeds(3, 40)), q=7)
    t2 = ex.draw_trials(m, trial_rngs(trial_seeds(3, 40)[20:]), q=7)
    np.testing.assert_array_equal(t1.Psi[20:], t2.Psi)  # trial i depends on its own stream only
    assert np.all(t1.theta.sum(1) == 7) and set(np.unique(t1.theta)) == {0.0, 1.0}
    assert np.abs(t1.Psi).max() <= ex.PSI_HALF_WIDTH
    assert abs(t1.Psi.std() - ex.PSI_HALF_WIDTH / np.sqrt(3)) < 0.1  # uniform: sd = a / sqrt(3)
    eps = t1.d[..., 0] - 10 * np.sin(0.1 * np.arange(101)) - 100
    assert abs(eps.mean()) < 0.05 and abs(eps.std() - 1) < 0.05
    with pytest.raises(ModelError, match=r"q: expected an integer in \[0, 50\]"):
        ex.draw_trial(m, np.random.default_rng(0), q=51)


@pytest.mark.parametrize("r", [0.5, 200.0])
def test_batched_draws_are_bit_for_bit_those_of_each_generator_alone(r):
    """The batch loop only draws; its affine maps must give exactly what each generator gives
    through the plain calls: choice, uniform, normal for d_k, then draw_noise's normals."""
    from fdi_lib.simulate import draw_noise

    m = ex.example1_model(r=r)
    t = ex.draw_trials(m, trial_rngs(trial_seeds(11, 6)), q=4)
    for b, rng in enumerate(trial_rngs(trial_seeds(11, 6))):
        theta = np.zeros(ex.N_PARAMS)
        theta[rng.choice(ex.N_PARAMS, size=4, replace=False)] = 1.0
        Psi = rng.uniform(-ex.PSI_HALF_WIDTH, ex.PSI_HALF_WIDTH, size=(m.n_steps, 3, ex.N_PARAMS))
        d = 10.0 * np.sin(0.1 * np.arange(m.n_steps)) + rng.standard_normal(m.n_steps) + 100.0
        noise = draw_noise(m, rng)
        for ours, ref in (
            (t.theta[b], theta),
            (t.Psi[b], Psi),
            (t.d[b, :, 0], d),
            (t.noise.x0[b], noise.x0),
            (t.noise.w[b], noise.w),
            (t.noise.v[b], noise.v),
        ):
            np.testing.assert_array_equal(ours, ref)


def test_simulation_matches_a_plain_loop():
    m = ex.example1_model()
    t = ex.draw_trials(m, trial_rngs(trial_seeds(1, 2)), q=5)
    y = ex.simulate_trials(m, t)
    b = 1
    x = t.noise.x0[b].copy()
    A = ex.state_matrices(101)
    for k in range(101):
        np.testing.assert_allclose(y[b, k], ex.C @ x + t.noise.v[b, k], rtol=1e-10, atol=1e-8)
        x = A[k] @ x + ex.E[:, 0] * t.d[b, k, 0] + t.noise.w[b, k] + t.Psi[b, k] @ t.theta[b]
