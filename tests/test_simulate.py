import numpy as np
import pytest

from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.models import fault_profile, ltv_model
from fdi_lib.simulate import draw_noise, pi_controller, simulate
from fdi_lib.systems import zb2014_unstable as ex


def test_open_loop_matches_a_direct_loop(random_ltv):
    rng = np.random.default_rng(1)
    m = random_ltv(rng, n=3, p=2, l=1, n_steps=30)
    u = rng.standard_normal((30, 1))
    prof = fault_profile(
        m, Psi=rng.standard_normal((30, 3, 2)), Phi=rng.standard_normal((30, 2, 2))
    )
    theta = np.array([0.3, -0.2])
    sim = simulate(m, rng=np.random.default_rng(2), u=u, fault=prof, theta=theta)
    x = sim.noise.x0.copy()
    for k in range(30):
        y = m.H[k] @ x + m.J[k] @ u[k] + sim.noise.v[k] + prof.Phi[k] @ theta
        np.testing.assert_allclose(sim.y[k], y, rtol=1e-12, atol=1e-12)
        x = m.F[k] @ x + m.G[k] @ u[k] + sim.noise.w[k] + prof.Psi[k] @ theta
    np.testing.assert_allclose(sim.x[-1], x, rtol=1e-12, atol=1e-12)


def test_noise_has_the_model_covariances():
    m = ltv_model(F=np.eye(2), H=[[1.0, 0.0]], Q=[[2.0, 0.6], [0.6, 0.5]], R=0.3, n_steps=20)
    nz = draw_noise(m, np.random.default_rng(0), size=4000)
    w = nz.w.reshape(-1, 2)
    # 80 000 samples: the sample covariance is within ~2 % (5 standard errors) of Q.
    np.testing.assert_allclose(np.cov(w.T), [[2.0, 0.6], [0.6, 0.5]], atol=0.05)
    np.testing.assert_allclose(nz.v.var(), 0.3, rtol=0.03)


def test_shared_noise_roots_change_no_draw():
    from fdi_lib.simulate import noise_from_standard, noise_roots

    m = ltv_model(
        F=np.eye(2),
        H=[[1.0, 0.0]],
        Q=[[2.0, 0.6], [0.6, 0.5]],
        R=0.3,
        n_steps=20,
        P0=[[1.0, 0.2], [0.2, 0.4]],
    )
    a = draw_noise(m, np.random.default_rng(5), size=3)
    b = draw_noise(m, np.random.default_rng(5), size=3, roots=noise_roots(m))
    rng = np.random.default_rng(5)
    z0, zw, zv = (
        rng.standard_normal((3, 2)),
        rng.standard_normal((3, 20, 2)),
        rng.standard_normal((3, 20, 1)),
    )
    c = noise_from_standard(m, z0, zw, zv)
    for x, y, z in ((a.x0, b.x0, c.x0), (a.w, b.w, c.w), (a.v, b.v, c.v)):
        np.testing.assert_array_equal(x, y)
        np.testing.assert_array_equal(x, z)
    roots = noise_roots(m)  # square roots of the covariances
    np.testing.assert_allclose(roots.Q[7] @ roots.Q[7].T, [[2.0, 0.6], [0.6, 0.5]], rtol=1e-12)
    np.testing.assert_allclose(roots.P0 @ roots.P0.T, [[1.0, 0.2], [0.2, 0.4]], rtol=1e-12)
    np.testing.assert_allclose(a.x0, m.x0 + z0 @ roots.P0.T, rtol=1e-12)


def test_rank_one_process_noise_is_supported():
    q = np.array([[1.0, 1.0], [1.0, 1.0]])  # singular PSD
    m = ltv_model(F=np.eye(2), H=[[1.0, 0.0]], Q=q, R=1.0, n_steps=10)
    nz = draw_noise(m, np.random.default_rng(0))
    np.testing.assert_allclose(nz.w[:, 0], nz.w[:, 1], atol=1e-12)


def test_replay_and_batch_consistency():
    m = ex.unstable_model(50)
    batch = simulate(m, rng=np.random.default_rng(3), size=3, controller=ex.controller())
    single = simulate(
        m,
        noise=type(batch.noise)(batch.noise.x0[1], batch.noise.w[1], batch.noise.v[1]),
        controller=ex.controller(),
    )
    np.testing.assert_allclose(batch.y[1], single.y, rtol=0, atol=1e-13)


def test_pi_controller_is_the_transfer_function():
    c = pi_controller(0.2, 0.01, setpoint=1.0)
    y = np.array([0.0, 0.5, 1.5, 1.0])
    u = [float(c(k, np.array([yk]))[0]) for k, yk in enumerate(y)]
    e = 1.0 - y
    expected = [0.2 * e[k] + 0.01 * e[:k].sum() for k in range(4)]  # kp + ki / (z - 1)
    np.testing.assert_allclose(u, expected)


def test_closed_loop_tracks_the_setpoint():
    m = ex.unstable_model(500)
    sim = simulate(m, rng=np.random.default_rng(0), controller=ex.controller(), size=200)
    assert abs(sim.y[:, 300:, 0].mean() - ex.SETPOINT) < 0.05
    assert np.abs(sim.x).max() < 10  # the PI loop stabilises the unstable plant


def test_bad_arguments():
    m = ex.unstable_model(10)
    with pytest.raises(ModelError, match="exactly one of rng"):
        simulate(m)
    with pytest.raises(ShapeError, match=r"u: expected shape \(\.\.\., 10, 1\), got \(9, 1\)"):
        simulate(m, rng=np.random.default_rng(0), u=np.zeros((9, 1)))
    with pytest.raises(ModelError, match="not both"):
        simulate(m, rng=np.random.default_rng(0), u=np.zeros(10), controller=ex.controller())
    with pytest.raises(ModelError, match="rng: expected a numpy.random.Generator"):
        draw_noise(m, 3)
    prof = fault_profile(m, Psi=np.eye(2))
    with pytest.raises(ShapeError, match=r"theta: expected shape \(2,\), got \(3,\)"):
        simulate(m, rng=np.random.default_rng(0), fault=prof, theta=[1.0, 2.0, 3.0])
