"""Tests of fdi_lib.rls: RLS with forgetting factor (Basseville & Zhang, Section 4)."""

from __future__ import annotations

import numpy as np
import pytest

from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.rls import rls_gains, rls_track


def _problem(rng, N=150, p=3, m=2):
    M = rng.normal(size=(N, p, m))
    A = rng.normal(size=(N, p, p))
    Sigma = A @ np.swapaxes(A, 1, 2) + 0.5 * np.eye(p)
    return M, Sigma


def test_rls_equals_weighted_least_squares_closed_form():
    """theta_k = argmin sum_j lam^(k-j) ||eps_j - M_j theta||^2_{Sigma_j^-1} + lam^(k+1) ||theta||^2 (P_0 = I)."""
    rng = np.random.default_rng(0)
    M, Sigma = _problem(rng)
    eps = rng.normal(size=(2, 150, 3))
    lam = 0.93
    res = rls_track(eps, M, Sigma, lam=lam)
    Si = np.linalg.inv(Sigma)
    for k in (0, 5, 60, 149):
        w = lam ** (k - np.arange(k + 1))
        A = lam ** (k + 1) * np.eye(2) + np.einsum(
            "j,jpi,jpq,jqk->ik", w, M[: k + 1], Si[: k + 1], M[: k + 1]
        )
        b = np.einsum("j,jpi,jpq,...jq->...i", w, M[: k + 1], Si[: k + 1], eps[:, : k + 1])
        theta = np.linalg.solve(A, b[..., None])[..., 0]
        assert np.allclose(res.theta_hat[:, k], theta, rtol=1e-8, atol=1e-10)
        assert np.allclose(res.gains.P[k + 1], np.linalg.inv(A), rtol=1e-8, atol=1e-12)
        # tracking error with the closed-form estimate (not the library's own theta_hat)
        np.testing.assert_allclose(
            res.errors[:, k], eps[:, k] - theta @ M[k].T, rtol=1e-8, atol=1e-10
        )
        if k > 0:  # prior error: the estimate of k-1 from the same closed form
            w1 = lam ** (k - 1 - np.arange(k))
            A1 = lam**k * np.eye(2) + np.einsum("j,jpi,jpq,jqk->ik", w1, M[:k], Si[:k], M[:k])
            b1 = np.einsum("j,jpi,jpq,...jq->...i", w1, M[:k], Si[:k], eps[:, :k])
            prior = eps[:, k] - np.linalg.solve(A1, b1[..., None])[..., 0] @ M[k].T
            np.testing.assert_allclose(res.prior_errors[:, k], prior, rtol=1e-8, atol=1e-10)


def test_rls_converges_to_constant_theta_without_nonparametric_fault():
    rng = np.random.default_rng(1)
    M, Sigma = _problem(rng, N=600)
    theta = np.array([0.7, -1.2])
    Lc = np.linalg.cholesky(Sigma)
    noise = np.einsum("kij,bkj->bki", Lc, rng.normal(size=(50, 600, 3)))
    eps = np.einsum("kpm,m->kp", M, theta) + noise
    res = rls_track(eps, M, Sigma, lam=0.99)
    err = np.abs(res.theta_hat[:, -1] - theta)
    assert err.mean() < 0.05
    # with lam = 1 (no forgetting) the error keeps shrinking
    res1 = rls_track(eps, M, Sigma, lam=1.0)
    assert np.abs(res1.theta_hat[:, -1] - theta).mean() < err.mean()


def test_rls_tracks_a_slow_ramp_better_with_forgetting():
    rng = np.random.default_rng(2)
    M, Sigma = _problem(rng, N=500)
    theta = np.linspace(0, 2, 500)[:, None] * np.array([1.0, -1.0])
    eps = np.einsum("kpm,km->kp", M, theta) + 0.1 * rng.normal(size=(500, 3))
    lag_err = [
        np.abs(rls_track(eps, M, Sigma, lam=lam).theta_hat[400:] - theta[400:]).mean()
        for lam in (0.9, 1.0)
    ]
    assert lag_err[0] < 0.5 * lag_err[1]


def test_bad_inputs():
    M = np.ones((10, 1, 1))
    S = np.ones((10, 1, 1))
    with pytest.raises(ModelError, match=r"lam: expected a forgetting factor in \(0, 1\], got 1.5"):
        rls_gains(M, S, lam=1.5)
    with pytest.raises(ModelError, match="lam: expected a forgetting factor"):
        rls_gains(M, S, lam=0.0)
    with pytest.raises(ShapeError, match=r"Sigma: expected shape \(10, 1, 1\)"):
        rls_gains(M, np.ones((9, 1, 1)), lam=0.9)
    with pytest.raises(ShapeError, match=r"regressor: expected shape \(N, p, m\)"):
        rls_gains(np.ones((10, 1)), S, lam=0.9)
    with pytest.raises(ShapeError, match=r"innovations: expected shape \(\.\.\., 10, 1\)"):
        rls_track(np.ones((10, 2)), M, S, lam=0.9)
