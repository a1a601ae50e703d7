r"""Recursive least squares with a forgetting factor, for tracking :math:`\theta_k` in eq. (47).

Basseville & Zhang, Section 4 (after Ljung 1999): with the regression
:math:`\varepsilon_k = M_k \theta_k + \text{noise}` (:math:`M_k = H_k \Gamma_k`, noise
covariance :math:`\Sigma_k`) and the forgetting factor :math:`\lambda`:

.. math::

    \begin{aligned}
    S_k &= \lambda \Sigma_k + M_k P_{k-1} M_k^\T, \\
    \mathcal L_k &= P_{k-1} M_k^\T S_k^{-1}, \\
    \hat\theta_k &= \hat\theta_{k-1} + \mathcal L_k (\varepsilon_k - M_k \hat\theta_{k-1}), \\
    P_k &= \lambda^{-1} (P_{k-1} - P_{k-1} M_k^\T S_k^{-1} M_k P_{k-1}), \\
    \mathcal E_k &= \varepsilon_k - M_k \hat\theta_k && \text{(tracking error)},
    \end{aligned}

with :math:`\hat\theta_0 = 0`, :math:`P_0 = I`. This minimises
:math:`\sum_{j \le k} \lambda^{k-j} \|\varepsilon_j - M_j \theta\|^2_{\Sigma_j^{-1}}
+ \lambda^{k+1} \|\theta\|^2_{P_0^{-1}}`.
The gains :math:`\mathcal L_k` and :math:`P_k` do not depend on the data (the regressor is known
in advance), so they are computed once and shared by all realisations; only the
:math:`\hat\theta` recursion runs per realisation, vectorised.

No library is used: filterpy/padasip provide scalar-output RLS only, and the
matrix-weighted, multi-output form above is five lines of numpy (Cholesky
solves with scipy, no explicit inverse of :math:`S_k`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg

from fdi_lib.errors import NonFiniteError, ShapeError
from fdi_lib.validation import array, check_finite, cholesky, covariance, real

__all__ = ["RLSGains", "rls_gains", "RLSResult", "rls_track"]


@dataclass(frozen=True)
class RLSGains:
    """Data-independent part of the RLS: ``L`` ``(N, m, p)``, ``P`` ``(N+1, m, m)``, ``lam``."""

    L: np.ndarray
    P: np.ndarray
    lam: float


def rls_gains(regressor: Any, Sigma: Any, *, lam: float, P0: Any = None) -> RLSGains:
    """Gain and covariance recursions of the RLS with forgetting factor.

    Explained in the book: :doc:`/book/bz/parametric-nonparametric`.

    Parameters
    ----------
    regressor : array_like
        ``M_k``, shape ``(N, p, m)``.
    Sigma : array_like
        Noise covariances ``Sigma_k``, ``(N, p, p)``, symmetric positive definite.
    lam : float
        Forgetting factor, ``0 < lam <= 1`` (``1``: ordinary RLS, no forgetting).
    P0 : array_like, optional
        ``(m, m)``, default identity (the paper's choice).

    Examples
    --------
    >>> import numpy as np
    >>> g = rls_gains(np.ones((100, 1, 1)), np.ones((100, 1, 1)), lam=0.9)
    >>> round(float(g.P[-1, 0, 0]), 4)                     # steady state 1 - lambda
    0.1
    """
    M = array(regressor, "regressor")
    S_all = array(Sigma, "Sigma")
    if M.ndim != 3:
        raise ShapeError(f"regressor: expected shape (N, p, m), got {M.shape}")
    N, p, m = M.shape
    if S_all.shape != (N, p, p):
        raise ShapeError(f"Sigma: expected shape ({N}, {p}, {p}), got {S_all.shape}")
    covariance(S_all, "Sigma", definite=True)
    lam = real(lam, "lam", low=0.0, high=1.0, low_open=True, what="a forgetting factor")
    P = np.empty((N + 1, m, m))
    P0a = np.eye(m) if P0 is None else array(P0, "P0")
    if P0a.shape != (m, m):
        raise ShapeError(f"P0: expected shape ({m}, {m}), got {np.shape(P0)}")
    covariance(P0a[None], "P0", definite=False)
    P[0] = P0a
    L = np.empty((N, m, p))
    for k in range(N):
        Pk, Mk = P[k], M[k]
        S = lam * S_all[k] + Mk @ Pk @ Mk.T
        c = cholesky(0.5 * (S + S.T), step=k, what="the RLS gain recursion", name="Sigma")
        Lk = scipy.linalg.cho_solve(c, Mk @ Pk, check_finite=False).T  # P M^T S^{-1} (S finite)
        Pn = (Pk - Lk @ Mk @ Pk) / lam
        L[k], P[k + 1] = Lk, 0.5 * (Pn + Pn.T)
    if not np.all(np.isfinite(P)):
        k = int(np.argwhere(~np.isfinite(P))[0, 0])
        raise NonFiniteError(
            f"lam: the RLS covariance diverged (non-finite P_k at step {k}; regressor "
            f"not persistently exciting for lam = {lam}?)"
        )
    return RLSGains(L=L, P=P, lam=lam)


@dataclass(frozen=True)
class RLSResult:
    """Output of :func:`rls_track`.

    Attributes
    ----------
    theta_hat : numpy.ndarray
        ``theta_k^``, ``(*batch, N, m)``.
    errors : numpy.ndarray
        Tracking errors ``E_k = eps_k - M_k theta_k^``, ``(*batch, N, p)``.
    prior_errors : numpy.ndarray
        ``eps_k - M_k theta_{k-1}^``, ``(*batch, N, p)``.
    gains : RLSGains
    """

    theta_hat: np.ndarray
    errors: np.ndarray
    prior_errors: np.ndarray
    gains: RLSGains


def rls_track(
    innovations: Any,
    regressor: Any,
    Sigma: Any,
    *,
    lam: float,
    P0: Any = None,
    theta0: Any = None,
    gains: RLSGains | None = None,
) -> RLSResult:
    """Track ``theta_k`` in ``eps_k = M_k theta_k + noise`` (eq. 47) by RLS with forgetting.

    Explained in the book: :doc:`/book/bz/parametric-nonparametric`.

    Parameters
    ----------
    innovations : array_like
        ``eps_k``, ``(*batch, N, p)``.
    regressor, Sigma, lam, P0
        As in :func:`rls_gains`.
    theta0 : array_like, optional
        ``theta_0^`` ``(m,)``, default zero.

    A NaN innovation (missing sample) is an error here: the gains are computed in advance
    for every sample (:mod:`fdi_lib.validation`).
    gains : RLSGains, optional
        Precomputed gains (shared across chunks).

    Returns
    -------
    RLSResult

    Examples
    --------
    >>> import numpy as np
    >>> M = np.ones((200, 1, 1)); S = np.ones((200, 1, 1))
    >>> r = rls_track(2.0 * np.ones((200, 1)), M, S, lam=0.95)
    >>> round(float(r.theta_hat[-1, 0]), 4)   # the prior term lambda^(k+1) |theta|^2 has faded
    2.0
    """
    g = rls_gains(regressor, Sigma, lam=lam, P0=P0) if gains is None else gains
    M = array(regressor, "regressor")
    if M.ndim != 3:
        raise ShapeError(f"regressor: expected shape (N, p, m), got {M.shape}")
    N, p, m = M.shape
    if np.shape(getattr(g, "L", None)) != (N, m, p):
        raise ShapeError(
            f"gains: expected RLSGains with L of shape {(N, m, p)}, "
            f"got {np.shape(getattr(g, 'L', None))}"
        )
    eps = array(innovations, "innovations", finite=False)
    if eps.ndim < 2 or eps.shape[-2:] != (N, p):
        raise ShapeError(f"innovations: expected shape (..., {N}, {p}), got {eps.shape}")
    check_finite(eps, "innovations")  # RLS cannot skip a missing sample (fdi_lib.validation)
    batch = eps.shape[:-2]
    if theta0 is None:
        th = np.zeros((*batch, m))
    else:
        th0 = array(theta0, "theta0")
        if th0.shape != (m,):
            raise ShapeError(f"theta0: expected shape ({m},), got {th0.shape}")
        th = np.broadcast_to(th0, (*batch, m))
    theta = np.empty((*batch, N, m))
    prior = np.empty(eps.shape)
    for k in range(N):
        e = eps[..., k, :] - th @ M[k].T
        prior[..., k, :] = e
        th = th + e @ g.L[k].T
        theta[..., k, :] = th
    errors = eps - np.einsum("kpm,...km->...kp", M, theta)
    return RLSResult(theta_hat=theta, errors=errors, prior_errors=prior, gains=g)
