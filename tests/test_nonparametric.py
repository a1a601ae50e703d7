"""Tests of fdi_lib.nonparametric (Basseville & Zhang): Prop. 1, the Kitanidis predictor form,
the rejection projection, the whiteness claims and solution 1."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.stats

from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.filters import kalman_filter, kalman_gains
from fdi_lib.kitanidis import kitanidis_filter, kitanidis_gains
from fdi_lib.models import fault_profile, ltv_model
from fdi_lib.nonparametric import (
    energy_statistic,
    energy_threshold,
    innovation_split,
    kitanidis_lag_covariance,
    kitanidis_predictor_gains,
    nonparametric_signature,
    reduce_residual,
    rejection_projection,
    solution1,
    solution1_glr,
)
from fdi_lib.simulate import simulate
from fdi_lib.systems import bz_example as ex

N = 120


@pytest.fixture(scope="module")
def setting():
    model = ex.bz_model(N)
    kg = kitanidis_gains(model, ex.E)
    return model, kalman_gains(model), kg, kitanidis_predictor_gains(model, ex.E, kg)


def _pair(model, rng, f, th, size=3):
    prof = fault_profile(model, Psi=ex.state_disturbance(f, th))
    s0 = simulate(model, rng=rng, controller=ex.controller(), size=size)
    s1 = simulate(model, noise=s0.noise, controller=ex.controller(), fault=prof, theta=[1.0])
    return s0, s1


def _bz_predictor_form(model, E):
    """Independent brute-force loop of Basseville & Zhang (27)-(28) as reconstructed in the book:
    L_k = K_k + (I - K_k H_k) E_{k-1} (E_{k-1}^T H_k^T S^-1 H_k E_{k-1})^-1 E_{k-1}^T H_k^T S^-1,
    P_{k+1} = F (I - L H) P (I - L H)^T F^T + F L R L^T F^T + Q (explicit inverses on purpose)."""
    n = model.n
    P = model.P0.copy()
    Ls, Ps = [], [P]
    for k in range(model.n_steps):
        F, H, R, Q = model.F[k], model.H[k], model.R[k], model.Q[k]
        S = H @ P @ H.T + R
        Si = np.linalg.inv(S)
        K = P @ H.T @ Si
        if k == 0:
            L = K
        else:
            HE = H @ E
            L = K + (np.eye(n) - K @ H) @ E @ np.linalg.inv(HE.T @ Si @ HE) @ HE.T @ Si
        IL = np.eye(n) - L @ H
        P = F @ IL @ P @ IL.T @ F.T + F @ L @ R @ L.T @ F.T + Q
        Ls.append(L)
        Ps.append(P)
    return np.array(Ls), np.array(Ps)


def test_bz_form_27_28_agrees_with_zhang_2021_form_24(setting):
    model, _, kg, kpred = setting
    L, P = _bz_predictor_form(model, ex.E)
    assert np.allclose(kpred.K, L, rtol=0, atol=1e-11)
    assert np.allclose(kpred.P, P, rtol=1e-9, atol=1e-13)
    # (I - L_k H_k) E_{k-1} = 0: the gain rejects E (eq. 30 of Zhang 2021)
    rej = (np.eye(model.n) - kpred.K[1:] @ model.H[1:]) @ ex.E
    assert np.abs(rej).max() < 1e-12


def test_predictor_innovation_equals_kitanidis_filter_innovation(setting):
    model, _, kg, kpred = setting
    _, s1 = _pair(
        model,
        np.random.default_rng(3),
        ex.nonparametric_profile(N, size=0.2, onset=30),
        ex.parametric_path(N, theta=[0.05, 0.02], onset=60),
    )
    a = kalman_filter(model, s1.y, s1.u, gains=kpred)
    b = kitanidis_filter(model, s1.y, s1.u, gains=kg)
    assert np.abs(a.innovations - b.innovations).max() < 1e-13
    # the BZ prediction is F Xhat_{k|k} + G U of the 2021 form
    assert np.abs(a.x_pred - b.x_pred).max() < 1e-12


@pytest.mark.parametrize("which", ["kalman", "kitanidis"])
def test_prop1_split_is_exact(setting, which):
    model, kal, _, kpred = setting
    gains = kal if which == "kalman" else kpred
    f = ex.nonparametric_profile(N, size=0.2, onset=20)
    th = ex.drift_path(N, delta=1e-3, onset=10) + ex.parametric_path(
        N, theta=[0.05, -0.03], onset=70
    )
    s0, s1 = _pair(model, np.random.default_rng(11), f, th)
    e1 = kalman_filter(model, s1.y, s1.u, gains=gains).innovations
    e0 = kalman_filter(model, s0.y, s0.u, gains=gains).innovations
    sp = innovation_split(model, gains, e1, e0, Psi=ex.PSI, theta_path=th, E=ex.E, f=f)
    scale = np.abs(e1 - e0).max()
    assert scale > 0.05 and np.abs(sp.drift).max() > 1e-3 and np.abs(sp.nonparametric).max() > 0.05
    assert np.abs(sp.residual).max() < 1e-12 * max(1.0, scale) * 100


def test_zeta_with_kitanidis_gain_is_E_f_delayed_not_zero(setting):
    """The paper's H zeta = 0 does not hold: zeta_k = E_{k-1} f_{k-1} (one-step, no dynamics)."""
    model, _, _, kpred = setting
    f = np.random.default_rng(0).normal(size=(N, 1))
    z = nonparametric_signature(model, kpred, ex.E, f)
    expected = np.zeros_like(z)
    expected[1:] = f @ ex.E.T
    assert np.abs(z - expected).max() < 1e-12
    assert np.abs(model.H @ z[:N, :, None]).max() > 0.5


def test_projection_rejects_f_and_whitens(setting):
    model, _, kg, kpred = setting
    T = rejection_projection(model, kg)
    HE = model.H[1:] @ ex.E
    assert np.abs(T[1:] @ HE).max() < 1e-10
    TST = T @ kg.Sigma @ np.swapaxes(T, 1, 2)
    assert np.allclose(TST, np.eye(2), atol=1e-10)
    rng = np.random.default_rng(5)
    s0, s1 = _pair(model, rng, ex.nonparametric_profile(N, size=0.5, onset=10), np.zeros((N, 2)))
    r0 = reduce_residual(model, kg, kalman_filter(model, s0.y, s0.u, gains=kpred).innovations, T)
    r1 = reduce_residual(model, kg, kalman_filter(model, s1.y, s1.u, gains=kpred).innovations, T)
    assert np.abs(r1.residuals - r0.residuals).max() < 1e-11


def test_lag_covariance_closed_form_matches_monte_carlo_and_is_nonzero():
    """Prop. 2 fails for the innovation: seeded Monte Carlo agrees with -H F D Sigma."""
    model = ex.bz_model(60)
    kg = kitanidis_gains(model, ex.E)
    kpred = kitanidis_predictor_gains(model, ex.E, kg)
    sim = simulate(model, rng=np.random.default_rng(2024), controller=ex.controller(), size=4000)
    eps = kalman_filter(model, sim.y, sim.u, gains=kpred).innovations
    lag1 = kitanidis_lag_covariance(model, kg, 1)
    lag2 = kitanidis_lag_covariance(model, kg, 2)
    ks = np.arange(30, 58)
    emp1 = np.einsum("bki,bkj->kij", eps[:, ks + 1], eps[:, ks]) / eps.shape[0]
    emp2 = np.einsum("bki,bkj->kij", eps[:, ks + 2], eps[:, ks]) / eps.shape[0]
    se = 4 * kg.Sigma[ks].max() / np.sqrt(eps.shape[0] * ks.size)  # pooled over k
    assert np.abs(emp1.mean(0) - lag1[ks].mean(0)).max() < se
    assert np.abs(emp2.mean(0) - lag2[ks].mean(0)).max() < se
    assert np.abs(lag1[ks].mean(0)).max() > 5 * se  # clearly not white
    # Kalman innovation is white: same formula with D = 0 would give exactly zero
    kal = kalman_gains(model)
    e_k = kalman_filter(model, sim.y, sim.u, gains=kal).innovations
    emp_k = np.einsum("bki,bkj->kij", e_k[:, ks + 1], e_k[:, ks]) / e_k.shape[0]
    assert np.abs(emp_k.mean(0)).max() < se


def test_projected_residual_passes_ljung_box_at_fixed_seed():
    from statsmodels.stats.diagnostic import acorr_ljungbox

    model = ex.bz_model(400)
    kg = kitanidis_gains(model, ex.E)
    kpred = kitanidis_predictor_gains(model, ex.E, kg)
    s0, s1 = _pair(
        model,
        np.random.default_rng(7),
        ex.nonparametric_profile(400, size=0.2, onset=0),
        np.zeros((400, 2)),
        size=40,
    )
    red = reduce_residual(model, kg, kalman_filter(model, s1.y, s1.u, gains=kpred).innovations)
    pv = np.array(
        [
            [
                acorr_ljungbox(red.residuals[i, 50:, j], lags=[10])["lb_pvalue"].iloc[0]
                for j in range(2)
            ]
            for i in range(40)
        ]
    )
    assert scipy.stats.kstest(pv.ravel(), "uniform").pvalue > 0.01
    assert np.mean(pv < 0.05) < 0.15


def test_energy_statistic_matches_loop_and_threshold():
    rng = np.random.default_rng(1)
    L = np.linalg.cholesky(np.array([[2.0, 0.3], [0.3, 1.0]]))
    Ls = np.broadcast_to(L, (30, 2, 2))
    r = rng.normal(size=(4, 30, 2))
    e = energy_statistic(r, Ls, 5)
    S_inv = np.linalg.inv(L @ L.T)
    for k in range(30):
        if k < 4:
            assert np.all(np.isnan(e[:, k]))
        else:
            brute = sum(
                np.einsum("bi,ij,bj->b", r[:, j], S_inv, r[:, j]) for j in range(k - 4, k + 1)
            )
            assert np.allclose(e[:, k], brute, rtol=1e-12)
    assert energy_threshold(5, 2, 0.05) == pytest.approx(scipy.stats.chi2.ppf(0.95, 10))


def test_energy_statistic_whitens_by_each_samples_own_factor():
    """Time-varying factors whose off-diagonal entries exceed the diagonal (where a general solve
    pivots), three components, a batch and a missing sample: against a loop of triangular solves."""
    rng = np.random.default_rng(4)
    N, p, w = 40, 3, 6
    L = np.tril(rng.normal(scale=3.0, size=(N, p, p)), -1) + np.einsum(
        "ni,ij->nij", rng.uniform(0.1, 1.0, size=(N, p)), np.eye(p)
    )
    r = rng.normal(size=(2, N, p))
    r[:, 17] = np.nan  # missing in both realisations: out of its windows
    e = energy_statistic(r, L, w)
    terms = np.array(
        [
            [
                0.0
                if k == 17
                else float(np.sum(scipy.linalg.solve_triangular(L[k], r[b, k], lower=True) ** 2))
                for k in range(N)
            ]
            for b in range(2)
        ]
    )
    brute = np.array(
        [[terms[b, k - w + 1 : k + 1].sum() for k in range(w - 1, N)] for b in range(2)]
    )
    assert np.all(np.isnan(e[:, : w - 1]))
    np.testing.assert_allclose(e[:, w - 1 :], brute, rtol=1e-12)


def test_bad_inputs_raise_typed_errors(setting):
    model, kal, kg, _ = setting
    with pytest.raises(ModelError, match=r"window: expected an integer in \[1, 30\], got 0"):
        energy_statistic(np.zeros((30, 2)), np.broadcast_to(np.eye(2), (30, 2, 2)), 0)
    with pytest.raises(ModelError, match="alpha: expected a probability"):
        energy_threshold(5, 2, 1.5)
    with pytest.raises(ShapeError, match=r"f: expected shape \(\.\.\., 120, 1\)"):
        nonparametric_signature(model, kal, ex.E, np.zeros((N, 2)))
    with pytest.raises(ShapeError, match="gains: expected KalmanGains"):
        nonparametric_signature(model, kg, ex.E, np.zeros((N, 1)))
    with pytest.raises(ModelError, match="lag: expected an integer"):
        kitanidis_lag_covariance(model, kg, 0)
    square = ltv_model(F=0.5 * np.eye(2), H=np.eye(2), Q=np.eye(2), R=np.eye(2), n_steps=10)
    with pytest.raises(ModelError, match="E: the rejection leaves p - q = 0"):
        rejection_projection(square, kitanidis_gains(square, np.eye(2)))


def test_solution1_detects_isolates_theta_and_ignores_f(setting):
    model, kal, kg, _ = setting
    rng = np.random.default_rng(9)
    f = ex.nonparametric_profile(N, size=0.3, onset=20)
    th = ex.parametric_path(N, theta=[0.08, 0.0], onset=60)
    s0 = simulate(model, rng=rng, controller=ex.controller(), size=20)
    kw = dict(
        E=ex.E,
        Psi=ex.PSI,
        window=30,
        glr_threshold=23.0,
        energy_window=20,
        energy_alpha=1e-4,
        kgains=kg,
        kalman=kal,
    )
    res = {}
    for name, ff, tt in (
        ("none", 0 * f, 0 * th),
        ("f", f, 0 * th),
        ("theta", 0 * f, th),
        ("both", f, th),
    ):
        prof = fault_profile(model, Psi=ex.state_disturbance(ff, tt))
        s = simulate(model, noise=s0.noise, controller=ex.controller(), fault=prof, theta=[1.0])
        res[name] = solution1(model, s.y, s.u, **kw)
    # f is rejected exactly: the GLR statistic is the same with and without f
    assert np.allclose(res["f"].glr.statistic, res["none"].glr.statistic, equal_nan=True, atol=1e-9)
    assert np.allclose(
        res["both"].glr.statistic, res["theta"].glr.statistic, equal_nan=True, atol=1e-9
    )
    assert np.mean(res["theta"].glr_alarm >= 60) >= 0.9
    det = res["theta"].glr_alarm >= 60
    assert np.mean(res["theta"].isolation[det, 0] & ~res["theta"].isolation[det, 1]) >= 0.8
    assert np.mean(res["f"].nonparametric_alarm >= 20) >= 0.9
    assert np.all(res["none"].energy_alarm < 0)
    # unbatched record works too
    one = solution1(model, s0.y[0], s0.u[0], **kw)
    assert one.glr_alarm.shape == () and one.isolation.shape == (2,)
    # the GLR's noise-independent arrays built once (solution1_glr) and reused: the same bits
    glr = solution1_glr(model, E=ex.E, Psi=ex.PSI, window=30, kgains=kg)
    for y, u, ref in ((s.y, s.u, res["both"]), (s0.y[0], s0.u[0], one)):
        again = solution1(model, y, u, glr=glr, **kw)
        for name in ("statistic", "onset", "C_hat", "d_hat"):
            np.testing.assert_array_equal(getattr(again.glr, name), getattr(ref.glr, name))
        np.testing.assert_array_equal(again.isolation, ref.isolation)
        np.testing.assert_array_equal(again.glr_alarm, ref.glr_alarm)


def test_solution2_rls_converges_to_constant_theta_on_the_example(setting):
    """Section 4 with theta_k constant and no f: RLS on (47) converges; a fast f raises the energy."""
    from fdi_lib.nonparametric import solution2

    model, kal, _, _ = setting
    rng = np.random.default_rng(21)
    theta = np.array([0.06, -0.04])
    th = np.broadcast_to(theta, (N, 2))
    s0, s1 = _pair(model, rng, np.zeros((N, 1)), th, size=30)
    res = solution2(
        model,
        s1.y,
        s1.u,
        Psi=ex.PSI,
        lam=0.99,
        energy_window=20,
        energy_alpha=1e-4,
        start=30,
        kalman=kal,
    )
    err = np.abs(res.rls.theta_hat[:, -1] - theta).mean(axis=0)
    assert np.all(err < 0.015)
    assert np.mean(res.energy_alarm >= 0) <= 0.1
    f = ex.nonparametric_profile(N, size=0.3, onset=60)
    prof = fault_profile(model, Psi=ex.state_disturbance(f, th))
    s2 = simulate(model, noise=s0.noise, controller=ex.controller(), fault=prof, theta=[1.0])
    res_f = solution2(
        model,
        s2.y,
        s2.u,
        Psi=ex.PSI,
        lam=0.99,
        energy_window=20,
        energy_alpha=1e-4,
        start=30,
        kalman=kal,
    )
    assert np.mean(res_f.energy_alarm >= 60) >= 0.9
