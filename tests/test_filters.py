import numpy as np
import pytest
import scipy.linalg
from filterpy.kalman import KalmanFilter

from fdi_lib.errors import CovarianceError, NonFiniteError, ShapeError
from fdi_lib.filters import kalman_filter, kalman_gains, predictor_recursion
from fdi_lib.models import ltv_model
from fdi_lib.simulate import simulate
from fdi_lib.validation import cho_solve, cholesky, solve_triangular


def test_against_filterpy_on_a_random_ltv_system(random_ltv):
    """Innovations, gains and covariances equal filterpy's predict/update loop (independent code)."""
    rng = np.random.default_rng(7)
    m = random_ltv(rng, n=3, p=2, l=1, n_steps=40)
    u = rng.standard_normal((40, 1))
    sim = simulate(m, rng=rng, u=u)
    res = kalman_filter(m, sim.y, u)
    kf = KalmanFilter(dim_x=3, dim_z=2, dim_u=1)
    kf.x = m.x0.copy()
    kf.P = m.P0.copy()
    for k in range(40):
        kf.H, kf.R = m.H[k], m.R[k]
        kf.update(sim.y[k] - m.J[k] @ u[k])
        np.testing.assert_allclose(res.innovations[k], kf.y, rtol=1e-9, atol=1e-11)
        np.testing.assert_allclose(res.gains.K[k], kf.K, rtol=1e-9, atol=1e-11)
        np.testing.assert_allclose(res.gains.Sigma[k], kf.S, rtol=1e-9, atol=1e-11)
        np.testing.assert_allclose(res.x_filt[k], kf.x, rtol=1e-9, atol=1e-11)
        kf.F, kf.B, kf.Q = m.F[k], m.G[k], m.Q[k]
        kf.predict(u=u[k])
        np.testing.assert_allclose(res.x_pred[k + 1], kf.x, rtol=1e-9, atol=1e-11)
        np.testing.assert_allclose(res.gains.P[k + 1], kf.P, rtol=1e-9, atol=1e-11)


def test_steady_state_gain_solves_the_dare():
    F = np.array([[0.5, 1.0], [0.0, 1.2]])
    H = np.array([[1.0, 0.0]])
    Q, R = 0.0025 * np.eye(2), np.array([[0.0025]])
    g = kalman_gains(ltv_model(F=F, H=H, Q=Q, R=R, n_steps=300))
    P = scipy.linalg.solve_discrete_are(F.T, H.T, Q, R)  # the predictor Riccati equation
    np.testing.assert_allclose(g.P[-1], P, rtol=1e-10)
    np.testing.assert_allclose(g.K[-1], P @ H.T @ np.linalg.inv(H @ P @ H.T + R), rtol=1e-10)
    assert max(abs(np.linalg.eigvals(g.A[-1]))) < 1  # F(I - KH) is stable although F is not


def test_steady_state_against_python_control():
    control = pytest.importorskip("control")
    F = np.array([[0.9, 0.2], [0.0, 1.1]])
    H = np.array([[1.0, 1.0]])
    Q, R = np.diag([0.1, 0.2]), np.array([[0.5]])
    g = kalman_gains(ltv_model(F=F, H=H, Q=Q, R=R, n_steps=400))
    L, P, _ = control.dlqe(F, np.eye(2), H, Q, R)  # predictor form: L = F P H^T (H P H^T + R)^{-1}
    np.testing.assert_allclose(g.FK[-1], L, rtol=1e-8)
    np.testing.assert_allclose(g.P[-1], P, rtol=1e-8)


def test_innovations_are_white_with_covariance_sigma(random_ltv):
    m = random_ltv(np.random.default_rng(3), n=2, p=1, n_steps=50)
    sim = simulate(m, rng=np.random.default_rng(4), size=4000)
    res = kalman_filter(m, sim.y, sim.u)
    z = res.gains.whiten(res.innovations)[..., 0]  # (4000, 50), N(0, 1) iid in theory
    assert abs(z.mean()) < 0.01
    assert abs(z.var() - 1.0) < 0.02
    lag1 = np.mean(z[:, 1:] * z[:, :-1])
    assert abs(lag1) < 0.01


def test_batch_equals_single(random_ltv):
    m = random_ltv(np.random.default_rng(5), n=3, p=2, n_steps=20)
    sim = simulate(m, rng=np.random.default_rng(6), size=3, u=np.ones((20, 1)))
    batch = kalman_filter(m, sim.y, np.ones((20, 1)))
    one = kalman_filter(m, sim.y[2], np.ones((20, 1)))
    np.testing.assert_allclose(batch.innovations[2], one.innovations, rtol=0, atol=1e-13)


def test_bad_outputs():
    m = ltv_model(F=[[0.9]], H=[[1.0]], Q=1.0, R=1.0, n_steps=5)
    with pytest.raises(ShapeError, match=r"y: expected shape \(\.\.\., 5, 1\), got \(4,\)"):
        kalman_filter(m, np.zeros(4))
    y = np.zeros(5)
    y[3] = np.inf
    with pytest.raises(
        NonFiniteError,
        match=r"y: expected finite values or NaN \(missing\), got inf at index \(3, 0\)",
    ):
        kalman_filter(m, y)


def _predictor_reference(m, y, u, K, skip):
    """The recursion of ``predictor_recursion`` step by step on the records' own layout."""
    batch, N, n = y.shape[:-2], m.n_steps, m.n
    xh = np.empty((*batch, N + 1, n))
    xh[..., 0, :] = m.x0
    eps, xf = np.empty(y.shape), np.empty((*batch, N, n))
    Gu = np.broadcast_to(np.einsum("kij,...kj->...ki", m.G, u), (*batch, N, n))
    ybar = y - np.einsum("kij,...kj->...ki", m.J, u)
    for k in range(N):
        if skip[k]:
            eps[..., k, :] = np.nan
            xf[..., k, :] = xh[..., k, :]
        else:
            e = ybar[..., k, :] - xh[..., k, :] @ m.H[k].T
            eps[..., k, :] = e
            xf[..., k, :] = xh[..., k, :] + e @ K[k].T
        xh[..., k + 1, :] = xf[..., k, :] @ m.F[k].T + Gu[..., k, :]
    upd = np.where(skip[:, None], np.nan, ybar - np.einsum("kij,...kj->...ki", m.H, xf))
    return eps, xh, xf, upd


@pytest.mark.parametrize("batch", [(), (1,), (4,), (3, 2)])
@pytest.mark.parametrize("shared_u", [False, True])
def test_predictor_recursion_bits_of_the_step_by_step_loop(random_ltv, batch, shared_u):
    """The sample-major loop gives the bits of the step-by-step one on the records' layout (missing
    samples, batches of any rank, inputs per record or shared), in C-ordered arrays of its shapes."""
    rng = np.random.default_rng(11)
    m = random_ltv(rng, n=3, p=2, l=1, n_steps=30)
    y = rng.standard_normal((*batch, 30, 2))
    u = rng.standard_normal((30, 1) if shared_u else (*batch, 30, 1))
    K = kalman_gains(m).K
    skip = np.zeros(30, dtype=bool)
    skip[[4, 17]] = True
    got = predictor_recursion(m, y, u, K, skip)
    for a, b in zip(got, _predictor_reference(m, y, u, K, skip)):
        assert a.shape == b.shape and a.flags.c_contiguous
        np.testing.assert_array_equal(a, b)


def test_recursion_solves_are_scipys_bits():
    """``cholesky``, ``cho_solve`` and ``solve_triangular`` of :mod:`fdi_lib.validation` call LAPACK
    as scipy does: the same bits for factors in C and Fortran order, both triangles, transposed or
    not, vector and matrix right-hand sides."""
    rng = np.random.default_rng(3)
    for p in (1, 2, 5):
        A = rng.standard_normal((p, p))
        S = A @ A.T + p * np.eye(p)
        c = cholesky(S, step=0, what="test")
        ref = scipy.linalg.cho_factor(S, lower=True, check_finite=False)
        np.testing.assert_array_equal(np.tril(c[0]), np.tril(ref[0]))
        assert c[1] is True
        for b in (rng.standard_normal(p), rng.standard_normal((p, 3))):
            np.testing.assert_array_equal(cho_solve(c[0], b), scipy.linalg.cho_solve(ref, b))
            for a in (np.tril(A), np.triu(A), np.asfortranarray(np.tril(A))):
                lower = bool(np.array_equal(a, np.tril(a)))
                for trans in (False, True):
                    np.testing.assert_array_equal(
                        solve_triangular(a, b, lower=lower, trans=trans),
                        scipy.linalg.solve_triangular(a, b, lower=lower, trans=int(trans)),
                    )
    with pytest.raises(CovarianceError, match="step 4"):
        cholesky(-np.eye(2), step=4, what="test")
