"""Kitanidis filter (Zhang 2021, eqs. (24)-(30)) and the residual signatures of Props 1-2."""

import numpy as np
import pytest

from fdi_lib.errors import CovarianceError, NonFiniteError, RankConditionError, ShapeError
from fdi_lib.filters import kalman_filter, kalman_gains
from fdi_lib.kitanidis import kitanidis_filter, kitanidis_gains, residual_signature
from fdi_lib.models import fault_profile, ltv_model
from fdi_lib.simulate import draw_noise, simulate


def _with_unknown_input(rng, random_ltv, *, n=4, p=3, s=2, N=50):
    m = random_ltv(rng, n=n, p=p, l=1, n_steps=N)
    k = np.arange(N)[:, None, None]
    E = rng.standard_normal((n, s)) + 0.2 * np.sin(0.4 * k) * rng.standard_normal((1, n, s))
    return m, E


def _simulate_ui(m, E, noise, u, d, Psi=None, theta=None):
    """Simulate X_{k+1} = F X + G u + E d + W + Psi theta by augmenting the input with [d, Psi theta]."""
    N, n = m.n_steps, m.n
    state_fault = np.zeros((N, n)) if Psi is None else Psi @ theta
    G_aug = np.concatenate([m.G, E, np.broadcast_to(np.eye(n), (N, n, n))], axis=2)
    J_aug = np.concatenate([m.J, np.zeros((N, m.p, E.shape[2] + n))], axis=2)
    m_aug = ltv_model(F=m.F, G=G_aug, H=m.H, J=J_aug, Q=m.Q, R=m.R, n_steps=N, x0=m.x0, P0=m.P0)
    return simulate(m_aug, noise=noise, u=np.concatenate([u, d, state_fault], axis=1))


def _literal_kitanidis(m, E):
    """Eq. (24) transcribed literally with explicit inverses (independent second computation)."""
    N = m.n_steps
    Pf = m.P0 - m.P0 @ m.H[0].T @ np.linalg.inv(m.H[0] @ m.P0 @ m.H[0].T + m.R[0]) @ m.H[0] @ m.P0
    Ks = [m.P0 @ m.H[0].T @ np.linalg.inv(m.H[0] @ m.P0 @ m.H[0].T + m.R[0])]
    Pfs = [Pf]
    for k in range(N - 1):
        A, C, Ek = m.F[k], m.H[k + 1], E[k]
        Pp = A @ Pf @ A.T + m.Q[k]  # (24a)
        Si = np.linalg.inv(C @ Pp @ C.T + m.R[k + 1])  # (24b)
        Gam = Ek - Pp @ C.T @ Si @ C @ Ek  # (24c)
        Xi = Ek.T @ C.T @ Si @ C @ Ek  # (24d)
        Lam = Gam @ np.linalg.inv(Xi)  # (24e)
        Pf = Pp - Pp @ C.T @ Si @ C @ Pp + Lam @ Xi @ Lam.T  # (24f)
        Ks.append(Pp @ C.T @ Si + Gam @ np.linalg.inv(Xi) @ Ek.T @ C.T @ Si)  # (24g)
        Pfs.append(Pf)
    return np.array(Ks), np.array(Pfs)


def test_identity_30_and_literal_transcription(random_ltv):
    rng = np.random.default_rng(1)
    m, E = _with_unknown_input(rng, random_ltv)
    g = kitanidis_gains(m, E)
    ident = np.eye(m.n) - g.K[1:] @ m.H[1:]
    assert np.abs(ident @ E[:-1]).max() < 1e-12 * max(1.0, np.abs(E).max())
    K_lit, Pf_lit = _literal_kitanidis(m, E)
    np.testing.assert_allclose(g.K, K_lit, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(g.P_filt, Pf_lit, rtol=1e-8, atol=1e-10)


def test_predictor_form_joseph_covariance_matches_24f(random_ltv):
    """Basseville & Zhang (27)-(28): Joseph-form covariance with gain L_k = K-bar_k equals (24f)."""
    rng = np.random.default_rng(2)
    m, E = _with_unknown_input(rng, random_ltv, N=30)
    g = kitanidis_gains(m, E)
    for k in range(m.n_steps):
        IL = np.eye(m.n) - g.K[k] @ m.H[k]
        joseph = IL @ g.P[k] @ IL.T + g.K[k] @ m.R[k] @ g.K[k].T
        np.testing.assert_allclose(joseph, g.P_filt[k], rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(
            m.F[k] @ joseph @ m.F[k].T + m.Q[k], g.P[k + 1], rtol=1e-8, atol=1e-10
        )


def test_residuals_do_not_depend_on_the_unknown_input(random_ltv):
    rng = np.random.default_rng(3)
    m, E = _with_unknown_input(rng, random_ltv)
    N = m.n_steps
    noise = draw_noise(m, rng, size=3)
    u = rng.standard_normal((N, 1))
    g = kitanidis_gains(m, E)
    zero = _simulate_ui(m, E, noise, u, np.zeros((N, 2)))
    wild = _simulate_ui(m, E, noise, u, 1e3 * rng.standard_cauchy((N, 2)) + 500.0)
    r0 = kitanidis_filter(m, zero.y, u, gains=g)
    r1 = kitanidis_filter(m, wild.y, u, gains=g)
    scale = np.abs(wild.y).max()
    assert np.abs(r1.residuals - r0.residuals).max() < 1e-10 * scale
    err0, err1 = zero.x[:, :-1] - r0.x_filt, wild.x[:, :-1] - r1.x_filt  # estimation errors
    assert np.abs(err1 - err0).max() < 1e-10 * scale
    # the predictor "innovation" does see d_{k-1} (documented): make sure we are not fooled
    assert np.abs(r1.innovations - r0.innovations).max() > 1.0


def test_unbiased_minimum_variance_covariances_by_monte_carlo(random_ltv):
    """Estimation error has mean 0 and covariance P_filt; residual covariance is residual_cov."""
    rng = np.random.default_rng(4)
    m, E = _with_unknown_input(rng, random_ltv, n=3, p=2, s=1, N=20)
    g = kitanidis_gains(m, E)
    B = 20000
    noise = draw_noise(m, rng, size=B)
    d = 50.0 + 10.0 * rng.standard_normal((20, 1))
    sim = _simulate_ui(m, E, noise, np.zeros((20, 1)), d)
    res = kitanidis_filter(m, sim.y, gains=g)
    err = sim.x[:, :20] - res.x_filt
    k = 15
    se = np.sqrt(np.diag(g.P_filt[k]) / B)
    assert np.all(np.abs(err[:, k].mean(0)) < 4 * se)
    emp = np.cov(err[:, k].T)
    np.testing.assert_allclose(emp, g.P_filt[k], rtol=0.08, atol=0.03 * np.abs(g.P_filt[k]).max())
    empr = np.cov(res.residuals[:, k].T)
    np.testing.assert_allclose(
        empr, g.residual_cov[k], rtol=0.08, atol=0.03 * np.abs(g.residual_cov[k]).max()
    )


def test_reduces_to_the_kalman_filter_without_unknown_input(random_ltv):
    rng = np.random.default_rng(5)
    m = random_ltv(rng, n=3, p=2, l=1, n_steps=40)
    u = rng.standard_normal((40, 1))
    sim = simulate(m, rng=rng, u=u, size=2)
    kal = kalman_filter(m, sim.y, u)
    kit = kitanidis_filter(m, sim.y, u, E=np.zeros((3, 0)))
    np.testing.assert_allclose(kit.gains.K, kal.gains.K, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(kit.gains.P, kal.gains.P, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(kit.x_filt, kal.x_filt, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(kit.residuals, kal.updated_residuals, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(kit.innovations, kal.innovations, rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("which", ["kalman", "kitanidis"])
def test_propositions_1_and_2_residual_decomposition(random_ltv, which):
    """residual(theta) = (H Upsilon + Phi) theta + residual(0), replaying the same noise and d."""
    rng = np.random.default_rng(6)
    m, E = _with_unknown_input(rng, random_ltv, n=4, p=3, s=1)
    N, mdim = m.n_steps, 5
    Psi = rng.uniform(-2, 2, (N, m.n, mdim))
    Phi = rng.uniform(-1, 1, (N, m.p, mdim))
    theta = rng.standard_normal(mdim)
    noise = draw_noise(m, rng)
    u = rng.standard_normal((N, 1))
    if which == "kalman":
        E0 = np.zeros((N, m.n, 1))
        gains = kalman_gains(m)
        run = lambda y: kalman_filter(m, y, u, gains=gains).updated_residuals  # noqa: E731
    else:
        E0 = E
        gains = kitanidis_gains(m, E)
        run = lambda y: kitanidis_filter(m, y, u, gains=gains).residuals  # noqa: E731
    d = 30.0 + rng.standard_normal((N, 1))
    y0 = _simulate_ui(m, E0, noise, u, d).y
    y1 = _simulate_ui(m, E0, noise, u, d, Psi=Psi, theta=theta).y + Phi @ theta
    sig = residual_signature(m, gains, fault_profile(m, Psi=Psi, Phi=Phi))
    lhs = run(y1)
    rhs = sig.on_residual @ theta + run(y0)
    assert np.abs(lhs - rhs).max() < 1e-9 * np.abs(y1).max()
    # brute force: one column = response to theta = e_j of the noise-free, d-free system
    zero_noise = type(noise)(x0=m.x0, w=np.zeros_like(noise.w), v=np.zeros_like(noise.v))
    j = 2
    ej = np.eye(mdim)[j]
    yj = (
        _simulate_ui(m, E0, zero_noise, np.zeros((N, 1)), np.zeros((N, 1)), Psi=Psi, theta=ej).y
        + Phi @ ej
    )
    base = run(_simulate_ui(m, E0, zero_noise, np.zeros((N, 1)), np.zeros((N, 1))).y)
    np.testing.assert_allclose(run(yj) - base, sig.on_residual[:, :, j], atol=1e-9)


def test_batched_signature_matches_one_by_one(random_ltv):
    rng = np.random.default_rng(8)
    m, E = _with_unknown_input(rng, random_ltv, n=3, p=2, s=1, N=25)
    g = kitanidis_gains(m, E)
    Psi = rng.standard_normal((4, 25, 3, 6))
    batched = residual_signature(m, g, Psi=Psi)
    for b in range(4):
        one = residual_signature(m, g, fault_profile(m, Psi=Psi[b]))
        np.testing.assert_allclose(batched.on_residual[b], one.on_residual, rtol=1e-12, atol=1e-12)
    assert np.all(batched.Upsilon[:, 0] == 0.0)


def test_signature_without_upsilon_is_the_same_regressor(random_ltv):
    """``upsilon=False`` keeps one sample of the recursion, not ``N``: the same ``on_residual``,
    bit for bit (state and output profiles, per realisation and in another layout), no
    ``Upsilon``."""
    rng = np.random.default_rng(9)
    m, E = _with_unknown_input(rng, random_ltv, n=3, p=2, s=1, N=25)
    g = kitanidis_gains(m, E)
    Psi = rng.standard_normal((25, 3, 4, 6)).transpose(2, 0, 1, 3)  # (4, 25, 3, 6), strided
    Phi = rng.standard_normal((4, 25, 2, 6))
    for kw in ({"Psi": Psi}, {"Psi": Psi, "Phi": Phi}, {"Phi": Phi}):
        full = residual_signature(m, g, **kw)
        lean = residual_signature(m, g, **kw, upsilon=False)
        assert lean.Upsilon is None and full.Upsilon.shape == (4, 25, 3, 6)
        np.testing.assert_array_equal(lean.on_residual, full.on_residual)
        assert np.any(full.on_residual[:, -1] != 0.0)


def test_rank_condition_error_names_the_step():
    N = 10
    H = np.tile(np.array([[1.0, 0.0, 0.0]]), (N, 1, 1))
    H[6] = [[0.0, 1.0, 0.0]]
    m = ltv_model(F=0.5 * np.eye(3), H=H, Q=np.eye(3), R=1.0, n_steps=N)
    with pytest.raises(RankConditionError, match=r"at k = 5.*H_6 E_5"):
        kitanidis_gains(m, E=[[1.0], [0.0], [0.0]])
    with pytest.raises(RankConditionError, match="full column rank 2"):
        kitanidis_gains(m, E=np.eye(3)[:, :2])  # p = 1 < s = 2


def test_bad_inputs_are_rejected(random_ltv):
    rng = np.random.default_rng(9)
    m, E = _with_unknown_input(rng, random_ltv, N=20)
    with pytest.raises(ShapeError, match=r"E: expected shape \(4, s\)"):
        kitanidis_gains(m, E=np.ones((3, 1)))
    with pytest.raises(ShapeError, match="E: expected the unknown-input matrices"):
        kitanidis_filter(m, np.zeros((20, 3)))
    with pytest.raises(ShapeError, match="gains: expected gains with K of shape"):
        kitanidis_filter(
            m, np.zeros((20, 3)), gains=kalman_gains(random_ltv(rng, n=2, p=3, n_steps=20))
        )
    with pytest.raises(ShapeError, match="y: expected shape"):
        kitanidis_filter(m, np.zeros((19, 3)), E=E)
    with pytest.raises(ShapeError, match="Psi: expected shape"):
        residual_signature(m, kalman_gains(m), Psi=np.zeros((20, 3, 2)))


from hypothesis import given, reject, settings, strategies as st  # noqa: E402


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.integers(2, 6),
    extra_p=st.integers(0, 2),
    s=st.integers(1, 3),
)
def test_identity_30_on_random_dimensions(seed, n, extra_p, s):
    """(I - K_{k+1} H_{k+1}) E_k = 0 to machine precision whenever H_{k+1} E_k has full column rank."""
    s = min(s, n)
    p = min(n, s + extra_p)
    rng = np.random.default_rng(seed)
    N = 12
    k = np.arange(N)[:, None, None]
    F = rng.standard_normal((n, n)) / np.sqrt(n) + 0.1 * np.sin(k) * rng.standard_normal((1, n, n))
    H = rng.standard_normal((p, n)) + 0.1 * np.cos(k) * rng.standard_normal((1, p, n))
    A = rng.standard_normal((n, n))
    B = rng.standard_normal((p, p))
    m = ltv_model(F=F, H=H, Q=A @ A.T + 1e-3 * np.eye(n), R=B @ B.T + 0.1 * np.eye(p), n_steps=N)
    E = rng.standard_normal((N, n, s))
    try:
        g = kitanidis_gains(m, E)
    except (CovarianceError, NonFiniteError):
        # p = s leaves no output to observe the state: the covariance of an unstable system
        # diverges, and the library must stop with a typed error naming the step (checked
        # here) rather than return gains computed from a meaningless covariance.
        assert p == s
        reject()
    for j in range(1, N):
        resid = np.abs((np.eye(n) - g.K[j] @ m.H[j]) @ E[j - 1]).max()
        # square-root implementation: error ~ eps * sqrt(cond Xi) * |Gamma| (random systems may have
        # a diverging P when p = s, i.e. no output left to observe the state, hence ill-conditioning)
        gam = np.abs(E[j - 1] - g.K_kalman[j] @ m.H[j] @ E[j - 1]).max()
        scale = max(1.0, np.abs(E).max(), gam) * np.sqrt(np.linalg.cond(g.Xi[j]))
        assert resid <= 1e-13 * scale, (j, resid, scale)
