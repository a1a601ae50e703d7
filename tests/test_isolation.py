"""Minmax isolation test (41) of Zhang & Basseville (2014)."""

import numpy as np
import pytest
import scipy.stats

from fdi_lib.errors import ModelError, PersistentExcitationError, ShapeError
from fdi_lib.isolation import information, minmax_isolation, minmax_statistic


def _explicit(M, Rcov, Z, a):
    """GLR for theta_a = 0 with theta_b free, from the full stacked regression (38)-(39)."""
    Ri = np.linalg.inv(Rcov)
    b = [j for j in range(M.shape[1]) if j not in a]
    full = Z @ Ri @ M @ np.linalg.solve(M.T @ Ri @ M, M.T @ Ri @ Z)
    Mb = M[:, b]
    nuis = Z @ Ri @ Mb @ np.linalg.solve(Mb.T @ Ri @ Mb, Mb.T @ Ri @ Z) if b else 0.0
    return full - nuis


def test_minmax_equals_the_explicit_nuisance_glr():
    rng = np.random.default_rng(0)
    M = rng.standard_normal((12, 4))
    A = rng.standard_normal((12, 12))
    Rcov = A @ A.T + np.eye(12)
    Z = rng.standard_normal(12)
    Ri = np.linalg.inv(Rcov)
    F, zeta = M.T @ Ri @ M, M.T @ Ri @ Z
    for a in ([0], [2], [1, 3], [0, 1, 2, 3]):
        np.testing.assert_allclose(
            minmax_statistic(F, zeta, a), _explicit(M, Rcov, Z, a), rtol=1e-10
        )


def test_information_from_block_diagonal_residuals():
    rng = np.random.default_rng(1)
    N, p, m = 10, 2, 3
    S = rng.standard_normal((N, p, m))
    B = rng.standard_normal((N, p, p))
    Sigma = B @ np.swapaxes(B, 1, 2) + np.eye(p)

    class G:  # the two attributes `information` needs
        pass

    g = G()
    g.Sigma, g.Sigma_chol = Sigma, np.linalg.cholesky(Sigma)
    eps = rng.standard_normal((N, p))
    F, zeta = information(eps, S, g, 3, 9)
    M = np.vstack(S[3:9])
    Rcov = np.zeros((12, 12))
    for i, j in enumerate(range(3, 9)):
        Rcov[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] = Sigma[j]
    np.testing.assert_allclose(F, M.T @ np.linalg.solve(Rcov, M), rtol=1e-10)
    np.testing.assert_allclose(zeta, M.T @ np.linalg.solve(Rcov, eps[3:9].ravel()), rtol=1e-10)


@pytest.mark.parametrize("theta_b", [0.0, 3.0, -50.0])
def test_chi2_with_dim_a_degrees_of_freedom_whatever_the_nuisance(theta_b):
    rng = np.random.default_rng(2)
    M = rng.standard_normal((20, 3))
    theta = np.array([0.0, theta_b, 0.5 * theta_b])  # theta_a = theta[0] = 0
    Z = M @ theta + rng.standard_normal((5000, 20))
    F, zeta = M.T @ M, Z @ M
    stat = minmax_statistic(F, zeta, [0])
    assert scipy.stats.kstest(stat, scipy.stats.chi2(1).cdf).pvalue > 0.01
    stat2 = minmax_statistic(
        F, zeta, [0, 2]
    )  # theta_a = (theta_0, theta_2) is not zero unless theta_b = 0
    if theta_b == 0.0:
        assert scipy.stats.kstest(stat2, scipy.stats.chi2(2).cdf).pvalue > 0.01
    else:
        assert np.mean(stat2 > scipy.stats.chi2(2).ppf(0.99)) > 0.5


def test_parallel_bank_thresholds_and_decisions():
    F = np.diag([4.0, 4.0])
    zeta = np.array([[20.0, 0.0], [0.0, 0.0]])
    out = minmax_isolation(F, zeta, [[0], [1]], alpha=0.01)
    assert out[0].threshold == pytest.approx(6.6349, abs=1e-4)  # chi2(1) 99 % quantile
    np.testing.assert_array_equal(out[0].faulty, [True, False])
    np.testing.assert_array_equal(out[1].faulty, [False, False])
    both = minmax_isolation(F, zeta, [[0, 1]], alpha=0.01)[0]
    assert both.dof == 2 and both.threshold == pytest.approx(9.2103, abs=1e-4)


def test_bad_arguments():
    F = np.eye(2)
    with pytest.raises(
        ModelError, match=r"a: expected distinct component indices in \[0, 2\), got \[2\]"
    ):
        minmax_statistic(F, np.zeros(2), [2])
    with pytest.raises(ShapeError, match=r"F, zeta: expected"):
        minmax_statistic(F, np.zeros(3), [0])
    with pytest.raises(PersistentExcitationError, match="F_bb is singular"):
        minmax_statistic(np.array([[1.0, 0.0], [0.0, 0.0]]), np.zeros(2), [0])
    with pytest.raises(ModelError, match=r"thresholds: expected 2 values, got 1"):
        minmax_isolation(F, np.zeros(2), [[0], [1]], thresholds=[1.0])
    with pytest.raises(ModelError, match=r"alpha: expected a probability"):
        minmax_isolation(F, np.zeros(2), [[0]], alpha=1.5)
