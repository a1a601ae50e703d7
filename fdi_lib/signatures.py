r"""Fault signatures on the Kalman innovation.

Zhang & Basseville (2014), Proposition 1 / eqs. (11)-(12) and Proposition 2 /
eqs. (45)-(46):

.. math::

    \begin{aligned}
    \varepsilon_k &= \varepsilon^0_k + (H_k \Gamma_k + \Phi_k) \theta, \\
    \Gamma_{k+1} &= F_k (I - K_k H_k) \Gamma_k + \Psi_k - F_k K_k \Phi_k, \qquad \Gamma_0 = 0,
    \end{aligned}

and, for the comparison of Appendix A, the Willsky-Jones recursions (A.6)-(A.8)
(whose :math:`\alpha_k(r)` grows without bound when :math:`F_k` is unstable) and the
revisited recursion (A.17), which coincides with :math:`\Gamma_k` for an impulsive fault.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.filters import KalmanGains
from fdi_lib.models import FaultProfile, LTVModel

__all__ = ["Signature", "fault_signature", "WillskyJones", "willsky_jones", "revisited_gamma"]


@dataclass(frozen=True)
class Signature:
    """Fault signature on the innovation.

    Attributes
    ----------
    Gamma : numpy.ndarray
        ``Gamma_k`` for ``k = 0 .. N``, shape ``(N+1, n, m)``, eq. (12) or (46).
    on_innovation : numpy.ndarray
        ``H_k Gamma_k + Phi_k`` for ``k = 0 .. N-1``, shape ``(N, p, m)``: the regressor of
        ``theta`` in eq. (11)/(45).
    """

    Gamma: np.ndarray
    on_innovation: np.ndarray


def _check_gains(model: LTVModel, gains: KalmanGains) -> None:
    if gains.K.shape != (model.n_steps, model.n, model.p):
        raise ShapeError(
            f"gains: expected gains of shape {(model.n_steps, model.n, model.p)} "
            f"for this model, got {gains.K.shape}"
        )


def fault_signature(model: LTVModel, gains: KalmanGains, fault: FaultProfile) -> Signature:
    """Recursive fault-signature filter, eq. (12) (eq. (46) with an output profile ``Phi_k``).

    Explained in the book: :doc:`/book/zb2014/signature`.

    Parameters
    ----------
    model : LTVModel
    gains : KalmanGains
        From :func:`fdi_lib.filters.kalman_gains` on the fault-free model, with the missing
        samples of the record (``missing=``): there ``K_k = 0``, so ``Gamma_{k+1} = F_k Gamma_k +
        Psi_k``, the fault effect the filter did not correct. Gains of the complete record would
        give the signature of updates that did not happen.
    fault : FaultProfile
        ``Psi_k`` ``(N, n, m)`` and ``Phi_k`` ``(N, p, m)``.

    Returns
    -------
    Signature

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model, fault_profile
    >>> from fdi_lib.filters import kalman_gains
    >>> m = ltv_model(F=[[1.1]], H=[[1.0]], Q=0.1, R=0.1, n_steps=50)
    >>> sig = fault_signature(m, kalman_gains(m), fault_profile(m, Psi=[[1.0]]))
    >>> sig.Gamma.shape, bool(np.all(np.abs(sig.Gamma) < 2.0))  # bounded although F = 1.1
    ((51, 1, 1), True)
    """
    _check_gains(model, gains)
    N = model.n_steps
    if fault.Psi.shape[:2] != (N, model.n) or fault.Phi.shape[:2] != (N, model.p):
        raise ShapeError(
            f"fault: expected Psi ({N}, {model.n}, m) and Phi ({N}, {model.p}, m), "
            f"got {fault.Psi.shape} and {fault.Phi.shape}"
        )
    drive = fault.Psi - gains.FK @ fault.Phi  # Psi_k - F_k K_k Phi_k
    Gamma = np.zeros((N + 1, model.n, fault.m))
    for k in range(N):
        Gamma[k + 1] = gains.A[k] @ Gamma[k] + drive[k]
    return Signature(Gamma=Gamma, on_innovation=model.H @ Gamma[:N] + fault.Phi)


@dataclass(frozen=True)
class WillskyJones:
    """The original Willsky-Jones matrices for an impulsive fault at time ``r`` (eq. (A.1)).

    Attributes
    ----------
    alpha : numpy.ndarray
        ``alpha_k(r)`` (effect on the state), shape ``(N+1, n, n)``, eq. (A.6).
    xi : numpy.ndarray
        ``xi_k(r)`` (effect on the updated estimate), shape ``(N, n, n)``, eq. (A.7).
    rho : numpy.ndarray
        ``rho_k(r)`` (effect on the innovation), shape ``(N, p, n)``, eq. (A.8).
    """

    alpha: np.ndarray
    xi: np.ndarray
    rho: np.ndarray


def _check_onset(onset: int, N: int) -> int:
    if not isinstance(onset, (int, np.integer)) or not 0 <= onset < N:
        raise ModelError(f"onset: expected an integer in [0, {N - 1}], got {onset!r}")
    return int(onset)


def willsky_jones(model: LTVModel, gains: KalmanGains, onset: int) -> WillskyJones:
    """Willsky-Jones recursions (A.6)-(A.8) for a jump ``delta_{r,k+1} theta`` in the state.

    For ``model`` with the Kalman ``gains`` of its fault-free version, jump time ``onset`` = ``r``.

    Initial conditions ``alpha_r(r) = I``, ``xi_r(r) = K_r H_r``, ``rho_r(r) = H_r``;
    all matrices vanish before ``r``. ``alpha`` obeys ``alpha_{k+1} = F_k alpha_k`` and
    therefore diverges when ``F_k`` is unstable, although ``rho_k(r) = H_k Gamma_k(r)``
    stays bounded in exact arithmetic (Appendix A.3).

    Explained in the book: :doc:`/book/zb2014/signature`.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> from fdi_lib.filters import kalman_gains
    >>> m = ltv_model(F=[[1.1, 0.3], [0.0, 0.7]], H=[[1.0, 0.5]], Q=0.1 * np.eye(2), R=0.1, n_steps=30)
    >>> g = kalman_gains(m)
    >>> wj = willsky_jones(m, g, onset=10)
    >>> bool(np.allclose(wj.rho, m.H @ revisited_gamma(m, g, onset=10)[:-1]))  # rho_k = H_k Gamma_k
    True
    >>> round(float(np.abs(wj.alpha).max()), 1)        # the state effect grows (F is unstable)
    6.7
    """
    _check_gains(model, gains)
    N, n, p = model.n_steps, model.n, model.p
    r = _check_onset(onset, N)
    alpha = np.zeros((N + 1, n, n))
    xi = np.zeros((N, n, n))
    rho = np.zeros((N, p, n))
    alpha[r] = np.eye(n)
    xi[r] = gains.K[r] @ model.H[r]
    rho[r] = model.H[r]
    for k in range(r, N):
        alpha[k + 1] = model.F[k] @ alpha[k]
        if k + 1 < N:
            rho[k + 1] = model.H[k + 1] @ (alpha[k + 1] - model.F[k] @ xi[k])
            xi[k + 1] = model.F[k] @ xi[k] + gains.K[k + 1] @ rho[k + 1]
    return WillskyJones(alpha=alpha, xi=xi, rho=rho)


def revisited_gamma(model: LTVModel, gains: KalmanGains, onset: int) -> np.ndarray:
    """Revisited Willsky-Jones recursion (A.17): ``gamma_{k+1} = F_k (I - K_k H_k) gamma_k``, ``gamma_r = I``.

    For ``model`` and its Kalman ``gains``, ``onset`` = ``r``.
    Returns ``gamma_k(r)`` for ``k = 0 .. N``, shape ``(N+1, n, n)`` (zero before ``r``);
    it equals ``Gamma_k`` of eq. (12) for ``Psi_k = delta_{r,k+1} I``.

    Explained in the book: :doc:`/book/zb2014/signature`.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> from fdi_lib.filters import kalman_gains
    >>> m = ltv_model(F=[[0.9]], H=[[1.0]], Q=0.1, R=0.1, n_steps=30)
    >>> G = revisited_gamma(m, kalman_gains(m), onset=10)
    >>> G.shape, float(abs(G[:10]).max())            # zero before the jump
    ((31, 1, 1), 0.0)
    """
    _check_gains(model, gains)
    N, n = model.n_steps, model.n
    r = _check_onset(onset, N)
    gamma = np.zeros((N + 1, n, n))
    gamma[r] = np.eye(n)
    for k in range(r, N):
        gamma[k + 1] = gains.A[k] @ gamma[k]
    return gamma
