r"""Parametric and non-parametric additive faults (Basseville & Zhang).

Model (2) of the paper, in the book's notation:

.. math::

    \begin{aligned}
    X_{k+1} &= F_k X_k + G_k U_k + W_k + E_k f_k + \Psi_k \theta_k, \\
    Y_k &= H_k X_k + J_k U_k + V_k,
    \end{aligned}

with :math:`f_k` an arbitrary unknown signal (non-parametric fault) and :math:`\theta_k` a
constant or slowly varying vector (parametric fault).

Proposition 1 (eq. 25): for *any* predictor
:math:`\hat X_{k+1} = F_k \hat X_k + G_k U_k + F_k K_k \varepsilon_k` (3) designed for the
fault-free model, the innovation splits exactly:

.. math::

    \begin{aligned}
    \varepsilon_k &= \varepsilon^0_k + H_k \Gamma_k \theta_k + H_k \zeta_k + H_k \delta_k, \\
    \Gamma_{k+1} &= A_k \Gamma_k + \Psi_k, & \Gamma_0 &= 0 && (9), \\
    \zeta_{k+1} &= A_k \zeta_k + E_k f_k, & \zeta_0 &= 0 && (15), \\
    \delta_{k+1} &= A_k \delta_k - \Gamma_{k+1} e_k, & \delta_0 &= 0 && (23),
    \end{aligned}

with :math:`e_k = \theta_{k+1} - \theta_k` and :math:`A_k = F_k (I - K_k H_k)`.
:func:`innovation_split` computes every term (:math:`\Gamma_k` through
:func:`fdi_lib.signatures.fault_signature`, the same recursion).

The Kitanidis filter (27)-(28) is the predictor (3) with the gain :math:`L_k` of
:func:`fdi_lib.kitanidis.kitanidis_gains` (one implementation for the whole book);
:func:`kitanidis_predictor_gains` repackages it as :class:`~fdi_lib.filters.KalmanGains`
so that :func:`fdi_lib.filters.kalman_filter` runs (27) and
:func:`fdi_lib.signatures.fault_signature` gives :math:`\Delta_k` (30).

Two corrections to the paper, derived and checked in the book chapter ``bz``:

* With :math:`K_k = L_k`, (15) gives :math:`\zeta_k = E_{k-1} f_{k-1}` (because
  :math:`(I - L_k H_k) E_{k-1} = 0`), so the Kitanidis *innovation* still contains
  :math:`H_k E_{k-1} f_{k-1}`: the paper's :math:`H_k \zeta_k = 0` does not hold. The fault is
  rejected by any projection :math:`T_k` with :math:`T_k H_k E_{k-1} = 0`
  (:func:`rejection_projection`).
* The Kitanidis innovation is not white in general (Prop. 2 fails): its lag-one
  covariance is :math:`-H_{k+1} F_k D_k \Sigma_k` with :math:`D_k = L_k - K^{\mathrm{Kalman}}_k`
  (:func:`kitanidis_lag_covariance`). The projected residual :math:`T_k \varepsilon_k` *is* white
  (:math:`D_k \Sigma_k T_k^\T = 0`), with unit covariance by construction.

Solution 1 (Section 3): windowed GLR + minmax on :math:`T_k \varepsilon_k` (:func:`solution1`),
plus an energy test on a parallel Kalman filter's innovation for the onset of :math:`f`.
Solution 2 (Section 4): RLS tracking of :math:`\theta_k` in (47), see :mod:`fdi_lib.rls`
and :func:`solution2`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
import scipy.linalg
import scipy.stats

from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.filters import KalmanGains, kalman_filter, kalman_gains
from fdi_lib.glr import WindowedGLR, WindowGLRResult, first_alarm, glr_window
from fdi_lib.isolation import minmax_isolation
from fdi_lib.kitanidis import KitanidisGains, as_unknown_input_matrix, kitanidis_gains
from fdi_lib.models import FaultFamily, LTVModel, fault_profile, ltv_model, step_family
from fdi_lib.rls import RLSGains, RLSResult, rls_track
from fdi_lib.signatures import fault_signature
from fdi_lib.threads import blas_single_thread
from fdi_lib.validation import array, integer, missing_samples, probability, solve_triangular

__all__ = [
    "kitanidis_predictor_gains",
    "InnovationSplit",
    "innovation_split",
    "nonparametric_signature",
    "drift_signature",
    "kitanidis_lag_covariance",
    "rejection_projection",
    "ReducedResidual",
    "reduce_residual",
    "energy_statistic",
    "energy_threshold",
    "Solution1Result",
    "solution1",
    "Solution2Result",
    "solution2",
    "solution2_tracking",
    "first_alarm_after",
]


def kitanidis_predictor_gains(
    model: LTVModel, E: Any, kgains: KitanidisGains | None = None
) -> KalmanGains:
    """The Kitanidis filter in the one-step-predictor form (27)-(28), as :class:`KalmanGains`.

    ``K = L_k`` (eq. 28, the Kitanidis gain of Zhang 2021 eq. 24g: no second Riccati
    recursion, everything comes from :func:`fdi_lib.kitanidis.kitanidis_gains`),
    ``P = P_k`` (the prior covariance), ``Sigma = H_k P_k H_k^T + R_k``,
    ``A = F_k (I - L_k H_k)`` and ``FK = F_k L_k``. :func:`fdi_lib.filters.kalman_filter`
    with these gains is recursion (27); its innovation is the paper's ``eps_k``.

    Explained in the book: :doc:`/book/bz/parametric-nonparametric`.

    Parameters
    ----------
    model : LTVModel
        Fault-free model (1).
    E : array_like or callable
        ``E_k``, ``(n, q)`` or ``(N, n, q)``.
    kgains : KitanidisGains, optional
        Precomputed gains (then ``E`` is only checked for shape).

    Returns
    -------
    KalmanGains

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> m = ltv_model(F=0.5 * np.eye(2), H=np.eye(2), Q=np.eye(2), R=np.eye(2), n_steps=5)
    >>> g = kitanidis_predictor_gains(m, E=[[1.0], [0.0]])
    >>> float(np.abs(g.A[3] @ np.array([1.0, 0.0])).max()) < 1e-14   # F (I - L H) E = 0
    True
    """
    g = kitanidis_gains(model, E) if kgains is None else kgains
    if g.K.shape != (model.n_steps, model.n, model.p):
        raise ShapeError(
            f"kgains: expected K of shape {(model.n_steps, model.n, model.p)}, got {g.K.shape}"
        )
    IKH = np.eye(model.n) - g.K @ model.H
    return KalmanGains(
        K=g.K,
        P=g.P,
        P_filt=g.P_filt,
        Sigma=g.Sigma,
        Sigma_chol=g.Sigma_chol,
        A=model.F @ IKH,
        FK=model.F @ g.K,
        missing=g.missing,
    )


def _check_gains(model: LTVModel, gains: KalmanGains) -> None:
    if not isinstance(gains, KalmanGains) or gains.K.shape != (model.n_steps, model.n, model.p):
        raise ShapeError(
            f"gains: expected KalmanGains with K of shape {(model.n_steps, model.n, model.p)}, "
            f"got {type(gains).__name__} with K {np.shape(getattr(gains, 'K', None))}"
        )


def _series(arr: Any, N: int, width: int, name: str) -> np.ndarray:
    a = array(arr, name, finite=False)
    if a.ndim == 1 and width == 1:
        a = a[:, None]
    if a.ndim < 2 or a.shape[-2:] != (N, width):
        raise ShapeError(f"{name}: expected shape (..., {N}, {width}), got {np.shape(arr)}")
    return a


def nonparametric_signature(model: LTVModel, gains: KalmanGains, E: Any, f: Any) -> np.ndarray:
    """``zeta_k`` of eq. (15): ``zeta_{k+1} = F_k (I - K_k H_k) zeta_k + E_k f_k``, ``zeta_0 = 0``.

    Explained in the book: :doc:`/book/bz/parametric-nonparametric`.

    Parameters
    ----------
    model : LTVModel
    gains : KalmanGains
        Any predictor gains (Kalman, or Kitanidis via :func:`kitanidis_predictor_gains`).
    E : array_like
        ``(n, q)`` or ``(N, n, q)``.
    f : array_like
        Non-parametric fault ``f_k``, ``(*batch, N, q)``.

    Returns
    -------
    numpy.ndarray
        ``zeta_k`` for ``k = 0 .. N``, shape ``(*batch, N+1, n)``. It depends on the unknown
        ``f``: an FDI algorithm cannot compute it (only the book does, to check eq. 25).

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> from fdi_lib.filters import kalman_gains
    >>> m = ltv_model(F=[[0.5]], H=[[1.0]], Q=1.0, R=1.0, n_steps=6)
    >>> zeta = nonparametric_signature(m, kalman_gains(m), [[1.0]], np.ones((6, 1)))  # f_k = 1
    >>> zeta.shape, zeta[:4, 0].round(4).tolist()   # zeta_0 = 0, zeta_1 = E_0 f_0
    ((7, 1), [0.0, 1.0, 1.2353, 1.2897])
    """
    _check_gains(model, gains)
    Es = as_unknown_input_matrix(model, E)
    fs = _series(f, model.n_steps, Es.shape[2], "f")
    drive = np.einsum("kij,...kj->...ki", Es, fs)
    z = np.zeros((*fs.shape[:-2], model.n_steps + 1, model.n))
    for k in range(model.n_steps):
        z[..., k + 1, :] = z[..., k, :] @ gains.A[k].T + drive[..., k, :]
    return z


def drift_signature(
    model: LTVModel, gains: KalmanGains, Gamma: np.ndarray, theta_path: Any
) -> np.ndarray:
    """``delta_k`` of eq. (23): ``delta_{k+1} = A_k delta_k - Gamma_{k+1} (theta_{k+1} - theta_k)``.

    Explained in the book: :doc:`/book/bz/parametric-nonparametric`.

    Parameters
    ----------
    model : LTVModel
        Fault-free model.
    gains : KalmanGains
        Gains of the predictor (Kalman, or Kitanidis via :func:`kitanidis_predictor_gains`).
    Gamma : numpy.ndarray
        ``Gamma_k`` of (9), ``(N+1, n, m)`` (:attr:`fdi_lib.signatures.Signature.Gamma`).
    theta_path : array_like
        ``theta_k``, ``(*batch, N, m)``; ``e_k = theta_{k+1} - theta_k`` for ``k = 0 .. N-2``.

    Returns
    -------
    numpy.ndarray
        ``delta_k`` for ``k = 0 .. N-1``, shape ``(*batch, N, n)``; bounded by a multiple of
        ``max |e_k|`` (eq. 21).

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model, fault_profile
    >>> from fdi_lib.filters import kalman_gains
    >>> from fdi_lib.signatures import fault_signature
    >>> m = ltv_model(F=[[0.5]], H=[[1.0]], Q=1.0, R=1.0, n_steps=6)
    >>> g = kalman_gains(m)
    >>> Gamma = fault_signature(m, g, fault_profile(m, Psi=[[1.0]])).Gamma
    >>> float(abs(drift_signature(m, g, Gamma, np.ones((6, 1)))).max())   # constant theta: no drift
    0.0
    """
    _check_gains(model, gains)
    N, n = model.n_steps, model.n
    if np.shape(Gamma)[:2] != (N + 1, n):
        raise ShapeError(f"Gamma: expected shape ({N + 1}, {n}, m), got {np.shape(Gamma)}")
    th = _series(theta_path, N, Gamma.shape[2], "theta_path")
    e = np.diff(th, axis=-2)
    d = np.zeros((*th.shape[:-2], N, n))
    for k in range(N - 1):
        d[..., k + 1, :] = d[..., k, :] @ gains.A[k].T - e[..., k, :] @ Gamma[k + 1].T
    return d


@dataclass(frozen=True)
class InnovationSplit:
    """The four terms of eq. (25), each ``(*batch, N, p)``.

    Attributes
    ----------
    parametric, nonparametric, drift : numpy.ndarray
        ``H_k Gamma_k theta_k``, ``H_k zeta_k`` and ``H_k delta_k``.
    residual : numpy.ndarray
        ``eps_k - eps0_k - parametric - nonparametric - drift``: zero up to rounding (Prop. 1).
    """

    parametric: np.ndarray
    nonparametric: np.ndarray
    drift: np.ndarray
    residual: np.ndarray


def innovation_split(
    model: LTVModel,
    gains: KalmanGains,
    innovations: Any,
    innovations0: Any,
    *,
    Psi: Any,
    theta_path: Any,
    E: Any,
    f: Any,
) -> InnovationSplit:
    """Check Proposition 1 (eq. 25) on a record: compute each term and what is left.

    Explained in the book: :doc:`/book/bz/parametric-nonparametric`.

    Parameters
    ----------
    model, gains
        As in :func:`drift_signature`.
    innovations, innovations0 : array_like
        ``eps_k`` of the predictor with ``gains`` on the faulty record and ``eps0_k`` on the
        fault-free record with the same noise, ``(*batch, N, p)``.
    Psi : array_like
        ``Psi_k``, ``(n, m)`` or ``(N, n, m)``.
    theta_path : array_like
        ``theta_k``, ``(*batch, N, m)``.
    E, f
        As in :func:`nonparametric_signature`.

    Returns
    -------
    InnovationSplit

    Examples
    --------
    A record with a non-parametric fault ``f`` and a parametric jump of ``theta``, and the same
    noise without them; the four terms add up to the difference of the innovations:

    >>> import numpy as np
    >>> from fdi_lib.filters import kalman_filter
    >>> from fdi_lib.models import fault_profile
    >>> from fdi_lib.simulate import simulate
    >>> from fdi_lib.systems import bz_example as ex
    >>> N = 120
    >>> model = ex.bz_model(N)
    >>> gains = kitanidis_predictor_gains(model, ex.E)
    >>> f = ex.nonparametric_profile(N, size=0.2, onset=20)
    >>> theta = ex.parametric_path(N, theta=[0.05, -0.03], onset=70)
    >>> fault = fault_profile(model, Psi=ex.state_disturbance(f, theta))
    >>> s0 = simulate(model, rng=np.random.default_rng(11), controller=ex.controller())
    >>> s1 = simulate(model, noise=s0.noise, controller=ex.controller(), fault=fault, theta=[1.0])
    >>> eps1 = kalman_filter(model, s1.y, s1.u, gains=gains).innovations
    >>> eps0 = kalman_filter(model, s0.y, s0.u, gains=gains).innovations
    >>> split = innovation_split(
    ...     model, gains, eps1, eps0, Psi=ex.PSI, theta_path=theta, E=ex.E, f=f
    ... )
    >>> float(np.abs(split.residual).max()) < 1e-10          # Proposition 1, eq. (25)
    True
    """
    _check_gains(model, gains)
    N, p = model.n_steps, model.p
    eps = _series(innovations, N, p, "innovations")
    eps0 = _series(innovations0, N, p, "innovations0")
    sig = fault_signature(model, gains, fault_profile(model, Psi=Psi))  # Gamma_k of (9)
    th = _series(theta_path, N, sig.Gamma.shape[2], "theta_path")
    par = np.einsum("kpm,...km->...kp", sig.on_innovation, th)
    zeta = nonparametric_signature(model, gains, E, f)[..., :N, :]
    non = np.einsum("kpn,...kn->...kp", model.H, zeta)
    dr = np.einsum("kpn,...kn->...kp", model.H, drift_signature(model, gains, sig.Gamma, th))
    return InnovationSplit(
        parametric=par, nonparametric=non, drift=dr, residual=eps - eps0 - par - non - dr
    )


def kitanidis_lag_covariance(model: LTVModel, kgains: KitanidisGains, lag: int = 1) -> np.ndarray:
    """Theoretical ``Cov(eps_{k+lag}, eps_k)`` of the fault-free Kitanidis innovation.

    ``E[eps_{k+j} eps_k^T] = -H_{k+j} A_{k+j-1} ... A_{k+1} F_k D_k Sigma_k`` for ``j >= 1``, with
    ``A_i = F_i (I - L_i H_i)`` and ``D_k = L_k - K^Kalman_k`` (derived in the book). It is
    zero for the Kalman filter (``D = 0``) but not for the Kitanidis filter: the paper's
    Prop. 2 (whiteness) does not hold for the innovation (27).

    Explained in the book: :doc:`/book/bz/parametric-nonparametric`.

    Parameters
    ----------
    model : LTVModel
        Fault-free model.
    kgains : KitanidisGains
        :func:`fdi_lib.kitanidis.kitanidis_gains` of ``model``.
    lag : int
        ``j``, ``1 <= j < N``.

    Returns
    -------
    numpy.ndarray
        ``(N - lag, p, p)``, entry ``k`` is ``Cov(eps_{k+lag}, eps_k)``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> from fdi_lib.kitanidis import kitanidis_gains
    >>> m = ltv_model(F=0.5 * np.eye(2), H=np.eye(2), Q=np.eye(2), R=np.eye(2), n_steps=6)
    >>> kitanidis_lag_covariance(m, kitanidis_gains(m, [[1.0], [0.0]]), lag=1).shape   # k = 0 .. N-2
    (5, 2, 2)
    """
    if not isinstance(lag, (int, np.integer)) or not 1 <= lag < model.n_steps:
        raise ModelError(f"lag: expected an integer in [1, {model.n_steps - 1}], got {lag!r}")
    g = kgains
    D = g.K - g.K_kalman
    A = model.F @ (np.eye(model.n) - g.K @ model.H)
    N = model.n_steps
    out = np.empty((N - lag, model.p, model.p))
    for k in range(N - lag):
        M = -model.F[k] @ D[k] @ g.Sigma[k]
        for i in range(k + 1, k + lag):
            M = A[i] @ M
        out[k] = model.H[k + lag] @ M
    return out


def rejection_projection(model: LTVModel, kgains: KitanidisGains) -> np.ndarray:
    """Projections ``T_k`` ``(N, p - q, p)`` with ``T_k H_k E_{k-1} = 0`` and ``T_k Sigma_k T_k^T = I``.

    ``T_k eps_k`` of the Kitanidis innovation does not depend on ``f`` (``H_k zeta_k =
    H_k E_{k-1} f_{k-1}`` is annihilated), is white with unit covariance under no
    fault, and carries ``theta`` through ``T_k H_k Delta_k``. At ``k = 0`` (no unknown
    input acts yet) ``E_0`` is used so that the dimension stays ``p - q``.

    scipy's ``null_space`` (an SVD) gives the orthonormal complement of the whitened
    ``Sigma_k^{-1/2} H_k E_{k-1}``; ``model`` is the fault-free model and ``kgains`` its
    :func:`fdi_lib.kitanidis.kitanidis_gains`.

    Explained in the book: :doc:`/book/bz/parametric-nonparametric`.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> from fdi_lib.kitanidis import kitanidis_gains
    >>> m = ltv_model(F=0.5 * np.eye(2), H=np.eye(2), Q=np.eye(2), R=np.eye(2), n_steps=6)
    >>> E = np.array([[1.0], [0.0]])
    >>> kg = kitanidis_gains(m, E)
    >>> T = rejection_projection(m, kg)
    >>> T.shape, float(abs(T[3] @ m.H[3] @ E).max()), (T[3] @ kg.Sigma[3] @ T[3].T).round(6).tolist()
    ((6, 1, 2), 0.0, [[1.0]])
    """
    with blas_single_thread():  # small matrices: BLAS threads only add synchronisation
        N, p = model.n_steps, model.p
        Es = kgains.E
        q = Es.shape[2]
        if q >= p:
            raise ModelError(
                f"E: the rejection leaves p - q = {p - q} output directions; expected q < p = {p}"
            )
        T = np.empty((N, p - q, p))
        for k in range(N):
            Lc = kgains.Sigma_chol[k]
            B = solve_triangular(Lc, model.H[k] @ Es[max(k - 1, 0)], lower=True)
            Nk = scipy.linalg.null_space(B.T)  # (p, p - q), orthonormal
            T[k] = solve_triangular(Lc, Nk, lower=True, trans=True).T  # N^T L^{-1}
        return T


@dataclass(frozen=True)
class ReducedResidual:
    """The projected Kitanidis residual ``r_k = T_k eps_k`` and what the GLR needs.

    Attributes
    ----------
    residuals : numpy.ndarray
        ``(*batch, N, p - q)``; unit covariance, white, free of ``f``.
    model : LTVModel
        ``H_k -> T_k H_k``, ``R_k -> I``: the fault-free model as seen through ``T_k``.
    gains : KalmanGains
        ``A = F_k (I - L_k H_k)``, ``Sigma = I``; ``K = L_k T_k^T`` and ``FK = F_k L_k T_k^T`` are
        only there to fill the container (the GLR on state faults uses ``A`` and ``Sigma``).
    T : numpy.ndarray
        ``(N, p - q, p)``.
    """

    residuals: np.ndarray
    model: LTVModel
    gains: KalmanGains
    T: np.ndarray


def reduce_residual(
    model: LTVModel, kgains: KitanidisGains, innovations: Any, T: np.ndarray | None = None
) -> ReducedResidual:
    """Project the Kitanidis ``innovations`` (27) with :func:`rejection_projection`.

    ``model`` and ``kgains`` as there; ``T`` is a precomputed projection ``(N, r, p)`` (default:
    computed).

    Explained in the book: :doc:`/book/bz/parametric-nonparametric`.

    Examples
    --------
    The projected residual of a record with a non-parametric fault ``f`` is that of the same noise
    without it (``f`` is rejected):

    >>> import numpy as np
    >>> from fdi_lib.filters import kalman_filter
    >>> from fdi_lib.kitanidis import kitanidis_gains
    >>> from fdi_lib.models import fault_profile
    >>> from fdi_lib.simulate import simulate
    >>> from fdi_lib.systems import bz_example as ex
    >>> N = 120
    >>> model = ex.bz_model(N)
    >>> kg = kitanidis_gains(model, ex.E)
    >>> gains = kitanidis_predictor_gains(model, ex.E, kg)
    >>> f = ex.nonparametric_profile(N, size=0.5, onset=10)
    >>> fault = fault_profile(model, Psi=ex.state_disturbance(f, np.zeros((N, 2))))
    >>> s0 = simulate(model, rng=np.random.default_rng(5), controller=ex.controller())
    >>> s1 = simulate(model, noise=s0.noise, controller=ex.controller(), fault=fault, theta=[1.0])
    >>> r0 = reduce_residual(model, kg, kalman_filter(model, s0.y, s0.u, gains=gains).innovations)
    >>> r1 = reduce_residual(model, kg, kalman_filter(model, s1.y, s1.u, gains=gains).innovations)
    >>> r1.residuals.shape, float(np.abs(r1.residuals - r0.residuals).max()) < 1e-10
    ((120, 2), True)
    """
    N, p = model.n_steps, model.p
    eps = _series(innovations, N, p, "innovations")
    T = rejection_projection(model, kgains) if T is None else np.asarray(T, dtype=float)
    r = T.shape[1]
    if T.shape != (N, r, p):
        raise ShapeError(f"T: expected shape ({N}, r, {p}), got {T.shape}")
    res = np.einsum("krp,...kp->...kr", T, eps)
    red_model = ltv_model(
        F=model.F,
        G=model.G,
        H=T @ model.H,
        Q=model.Q,
        R=np.eye(r),
        n_steps=N,
        x0=model.x0,
        P0=model.P0,
    )
    eye = np.broadcast_to(np.eye(r), (N, r, r))
    LT = kgains.K @ np.swapaxes(T, 1, 2)
    red_gains = KalmanGains(
        K=LT,
        P=kgains.P,
        P_filt=kgains.P_filt,
        Sigma=np.array(eye),
        Sigma_chol=np.array(eye),
        A=model.F @ (np.eye(model.n) - kgains.K @ model.H),
        FK=model.F @ LT,
    )
    return ReducedResidual(residuals=res, model=red_model, gains=red_gains, T=T)


def energy_statistic(residuals: Any, Sigma_chol: np.ndarray, window: int) -> np.ndarray:
    """Moving-window energy ``sum_{j=k-w+1}^{k} ||Sigma_j^{-1/2} r_j||^2`` (``nan`` for ``k < w-1``).

    Under "white Gaussian noise with covariance ``Sigma_k``" it is chi-square with
    ``w p`` degrees of freedom (:func:`energy_threshold`): the simple test of Section 3.3
    for an arbitrary signal ``f``.

    Explained in the book: :doc:`/book/bz/parametric-nonparametric`.

    Parameters
    ----------
    residuals : array_like
        ``(*batch, N, p)``; a sample with a NaN is missing and left out of its windows
        (:mod:`fdi_lib.validation`).
    Sigma_chol : numpy.ndarray
        ``(N, p, p)`` lower Cholesky factors (positive diagonal): those of the gains of the filter
        that produced ``residuals``, which know its missing samples
        (:func:`fdi_lib.filters.kalman_gains` with ``missing=``), so that every observed term is
        chi-square with ``p`` degrees of freedom also after a gap.
    window : int
        ``w``, ``1 <= w <= N``.

    Notes
    -----
    Each window is summed directly (a sliding window view), not as a difference of running
    totals, so one huge residual (a glitch) only affects the ``w`` windows that contain it.

    Examples
    --------
    >>> import numpy as np
    >>> energy_statistic(np.ones((5, 1)), np.ones((5, 1, 1)), 3).tolist()   # NaN until w samples
    [nan, nan, 3.0, 3.0, 3.0]
    """
    L = array(Sigma_chol, "Sigma_chol", ndim=3)
    N, p = L.shape[:2]
    if L.shape != (N, p, p) or N < 1 or p < 1:
        raise ShapeError(f"Sigma_chol: expected shape (N, p, p), got {L.shape}")
    diag = np.diagonal(L, axis1=-2, axis2=-1)
    if np.any(diag <= 0) or np.any(np.triu(L, 1)):
        k = int(np.argwhere((diag <= 0).any(axis=-1) | np.triu(L, 1).any(axis=(-2, -1)))[0, 0])
        raise ModelError(
            f"Sigma_chol: expected lower-triangular factors with a positive diagonal, "
            f"got {L[k].tolist()} at step {k}"
        )
    r = _series(residuals, N, p, "residuals")
    missing = missing_samples(r, "residuals")
    window = integer(window, "window", low=1, high=N)
    # Sigma_j^{-1/2} r_j by forward substitution, one component at a time for every sample at
    # once (components first: contiguous rows); a general solve per sample (LU with pivoting)
    # took 7 times as long on the wind turbine's records
    r = np.moveaxis(np.where(missing[..., None], 0.0, r), -1, 0)  # (p, *batch, N)
    energy = np.zeros(r.shape[1:])
    z = np.empty_like(r)
    for i in range(p):
        acc = r[i].copy()
        for j in range(i):
            acc -= L[:, i, j] * z[j]
        z[i] = acc / L[:, i, i]
        energy += z[i] * z[i]
    out = np.full(energy.shape, np.nan)
    out[..., window - 1 :] = np.lib.stride_tricks.sliding_window_view(energy, window, axis=-1).sum(
        axis=-1
    )
    return out


def energy_threshold(window: int, p: int, alpha: float) -> float:
    """``chi2.ppf(1 - alpha, w p)``: per-sample false-alarm probability ``alpha`` of the energy test.

    ``window`` is ``w`` and ``p`` the residual dimension (both integers >= 1).

    Explained in the book: :doc:`/book/bz/parametric-nonparametric`.

    Examples
    --------
    >>> round(energy_threshold(10, 2, 0.01), 2)     # chi-square(20) quantile 0.99
    37.57
    """
    window = integer(window, "window", low=1)
    p = integer(p, "p", low=1)
    alpha = probability(alpha, "alpha")
    return float(scipy.stats.chi2.ppf(1.0 - alpha, window * p))


def first_alarm_after(statistic: np.ndarray, threshold: float, start: int = 0) -> np.ndarray:
    """:func:`fdi_lib.glr.first_alarm` of ``statistic`` above ``threshold`` from ``start`` (``-1`` if none).

    Re-exported for the reproductions.

    Explained in the book: :doc:`/book/bz/parametric-nonparametric`.

    Examples
    --------
    >>> import numpy as np
    >>> int(first_alarm_after(np.array([0.0, 5.0, 1.0, 7.0]), 4.0, start=2))   # k = 1 is before start
    3
    """
    return first_alarm(statistic, threshold, start)


@dataclass(frozen=True)
class Solution1Result:
    """Solution 1 (Section 3) on a batch of records.

    Attributes
    ----------
    reduced : ReducedResidual
        Projected Kitanidis residual.
    glr : WindowGLRResult
        Windowed GLR for a jump of ``theta`` on ``reduced.residuals``.
    glr_alarm : numpy.ndarray
        First ``k`` with ``l_k > glr_threshold`` (``-1``: none), ``batch`` shape.
    onset_hat : numpy.ndarray
        ``r_hat`` at the GLR alarm (``-1``: none).
    isolation : numpy.ndarray
        ``(*batch, m)`` booleans: the minmax test declares ``theta^(i) != 0`` at the alarm
        (``False`` where no alarm).
    isolation_stat : numpy.ndarray
        ``(*batch, m)`` minmax statistics (``nan`` where no alarm).
    energy : numpy.ndarray
        Energy statistic of the parallel Kalman filter's innovation, ``(*batch, N)``.
    energy_alarm : numpy.ndarray
        First energy alarm (``-1``: none).
    nonparametric_alarm : numpy.ndarray
        First energy alarm while the GLR is still quiet (``energy_alarm < glr_alarm`` or no GLR
        alarm), else ``-1``: the decision "non-parametric fault" of Section 3.3.
    glr_threshold, energy_threshold : float
    """

    reduced: ReducedResidual
    glr: WindowGLRResult
    glr_alarm: np.ndarray
    onset_hat: np.ndarray
    isolation: np.ndarray
    isolation_stat: np.ndarray
    energy: np.ndarray
    energy_alarm: np.ndarray
    nonparametric_alarm: np.ndarray
    glr_threshold: float
    energy_threshold: float


def _solution1_detector(red: ReducedResidual, Psi: Any, window: int) -> WindowedGLR:
    """The windowed GLR of :func:`solution1` on the projected residual ``red`` (its model and gains
    do not depend on the record)."""
    return WindowedGLR(red.model, red.gains, step_family(red.model, Psi=Psi), window)


def solution1_glr(
    model: LTVModel,
    *,
    E: Any,
    Psi: Any,
    window: int,
    kgains: KitanidisGains | None = None,
    T: np.ndarray | None = None,
) -> WindowedGLR:
    """The noise-independent part of :func:`solution1`'s windowed GLR (signatures, informations
    and their pseudo-inverses: most of a record's cost), for ``solution1(..., glr=...)`` with the
    same arguments: it depends on the model, ``E``, ``Psi`` and the window, not on the record."""
    if kgains is None:
        kgains = kitanidis_gains(model, E)
    red = reduce_residual(model, kgains, np.zeros((model.n_steps, model.p)), T)
    return _solution1_detector(red, Psi, window)


def solution1(
    model: LTVModel,
    y: Any,
    u: Any = None,
    *,
    E: Any,
    Psi: Any,
    window: int,
    glr_threshold: float,
    energy_window: int,
    energy_alpha: float,
    isolation_alpha: float = 0.01,
    partitions: Sequence[Sequence[int]] | None = None,
    kgains: KitanidisGains | None = None,
    kalman: KalmanGains | None = None,
    T: np.ndarray | None = None,
    glr: WindowedGLR | None = None,
) -> Solution1Result:
    """Solution 1: reject ``E f``, test ``theta`` by GLR + minmax, detect ``f`` by energy.

    Steps, all vectorised over the leading axes of ``y`` (Monte Carlo realisations):

    1. Kitanidis filter (27) and projection ``r_k = T_k eps_k`` (free of ``f``, white).
    2. Windowed GLR (Zhang & Basseville 2014, eqs. 35-37) for a jump ``Psi theta 1{k >= r}`` on ``r_k``;
       alarm when ``l_k > glr_threshold``; minmax isolation (41) from ``C_k(r_hat), d_k(r_hat)``.
    3. Parallel Kalman filter (46); windowed energy of its innovation (Section 3.3), an alarm
       counts as "non-parametric" while the GLR is quiet.

    Explained in the book: :doc:`/book/bz/parametric-nonparametric`.

    Parameters
    ----------
    model : LTVModel
        Fault-free model (1).
    y, u : array_like
        Outputs ``(*batch, N, p)`` and inputs ``(*batch, N, l)`` (closed loop: per realisation).
    E, Psi : array_like
        ``E_k`` ``(n, q)`` and ``Psi_k`` ``(n, m)`` (or per step).
    window : int
        GLR window ``w``.
    glr_threshold : float
        Threshold of ``l_k``.
    energy_window : int
        Window of the energy test.
    energy_alpha : float
        Per-sample false-alarm probability of the energy test (chi-square threshold).
    isolation_alpha : float
        Level of each minmax test.
    partitions : sequence, optional
        Minmax partitions; default one test per component of ``theta``.
    kgains, kalman, T : optional
        Precomputed Kitanidis gains, Kalman gains, projection (shared across chunks).
    glr : WindowedGLR, optional
        The GLR's noise-independent arrays, :func:`solution1_glr` of the same ``model``, ``E``,
        ``Psi``, ``window``, ``kgains`` and ``T``: reused instead of computed again (e.g. by a
        widget whose record changes and whose setting does not). The results are the same.

    Returns
    -------
    Solution1Result

    Examples
    --------
    A jump of the first component of ``theta`` at ``k = 60``, on 5 realisations:

    >>> import numpy as np
    >>> from fdi_lib.models import fault_profile
    >>> from fdi_lib.simulate import simulate
    >>> from fdi_lib.systems import bz_example as ex
    >>> N = 120
    >>> model = ex.bz_model(N)
    >>> theta = ex.parametric_path(N, theta=[0.08, 0.0], onset=60)
    >>> fault = fault_profile(model, Psi=ex.state_disturbance(np.zeros((N, 1)), theta))
    >>> s = simulate(model, rng=np.random.default_rng(9), controller=ex.controller(), size=5,
    ...              fault=fault, theta=[1.0])
    >>> res = solution1(model, s.y, s.u, E=ex.E, Psi=ex.PSI, window=30, glr_threshold=23.0,
    ...                 energy_window=20, energy_alpha=1e-4)
    >>> res.glr_alarm.shape, res.isolation.shape           # per realisation; per theta component
    ((5,), (5, 2))
    >>> bool(np.all(res.glr_alarm >= 60)), res.isolation[:, 0].all()   # detected after the onset
    (True, np.True_)
    """
    if kgains is None:
        kgains = kitanidis_gains(model, E)
    kpred = kitanidis_predictor_gains(model, E, kgains)
    eps_kit = kalman_filter(model, y, u, gains=kpred).innovations  # (27)
    red = reduce_residual(model, kgains, eps_kit, T)
    if glr is None:
        glr = _solution1_detector(red, Psi, window)
    res = glr_window(red.residuals, glr.model, glr.gains, glr.family, window, shared=glr)
    fam: FaultFamily = glr.family
    glr = res
    alarm = first_alarm(glr.statistic, glr_threshold)
    batch = alarm.shape
    m = fam.m
    parts = [[i] for i in range(m)] if partitions is None else partitions
    N = model.n_steps
    a_flat = alarm.reshape(-1)
    B = a_flat.size
    iso = np.zeros((B, len(parts)), dtype=bool)
    iso_stat = np.full((B, len(parts)), np.nan)
    onset_hat = np.full(B, -1)
    hit = np.nonzero(a_flat >= 0)[0]
    if hit.size:
        ka = a_flat[hit]
        C = glr.C_hat.reshape(B, N, m, m)[hit, ka]
        d = glr.d_hat.reshape(B, N, m)[hit, ka]
        onset_hat[hit] = glr.onset.reshape(B, N)[hit, ka]
        for j, dec in enumerate(minmax_isolation(C, d, parts, alpha=isolation_alpha)):
            iso[hit, j] = dec.faulty
            iso_stat[hit, j] = dec.statistic
    iso = iso.reshape(*batch, len(parts))
    iso_stat = iso_stat.reshape(*batch, len(parts))
    onset_hat = onset_hat.reshape(batch)
    kal = kalman_gains(model) if kalman is None else kalman
    eps_kal = kalman_filter(model, y, u, gains=kal).innovations  # (46)
    thr_e = energy_threshold(energy_window, model.p, energy_alpha)
    en = energy_statistic(eps_kal, kal.Sigma_chol, energy_window)
    e_alarm = first_alarm(en, thr_e)
    nonpar = np.where((e_alarm >= 0) & ((alarm < 0) | (e_alarm < alarm)), e_alarm, -1)
    return Solution1Result(
        reduced=red,
        glr=glr,
        glr_alarm=alarm,
        onset_hat=onset_hat,
        isolation=iso,
        isolation_stat=iso_stat,
        energy=en,
        energy_alarm=e_alarm,
        nonparametric_alarm=nonpar,
        glr_threshold=float(glr_threshold),
        energy_threshold=thr_e,
    )


@dataclass(frozen=True)
class Solution2Result:
    """Solution 2 (Section 4) on a batch of records.

    Attributes
    ----------
    rls : RLSResult
        Tracking of ``theta_k`` in (47).
    regressor : numpy.ndarray
        ``H_k Gamma_k`` ``(N, p, m)`` with the Kalman gain (Gamma of eq. 9, ``Psi_k`` from ``k = 0``).
    energy : numpy.ndarray
        Windowed energy of the tracking error ``E_k`` (whitened by ``Sigma_k``), ``(*batch, N)``.
    energy_alarm : numpy.ndarray
        First ``k >= start`` above the threshold (``-1``: none).
    energy_threshold : float
    """

    rls: RLSResult
    regressor: np.ndarray
    energy: np.ndarray
    energy_alarm: np.ndarray
    energy_threshold: float


def solution2(
    model: LTVModel,
    y: Any,
    u: Any = None,
    *,
    Psi: Any,
    lam: float,
    energy_window: int,
    energy_alpha: float,
    start: int = 0,
    kalman: KalmanGains | None = None,
    rls: RLSGains | None = None,
) -> Solution2Result:
    """Solution 2: Kalman filter (46), RLS with forgetting factor on (47), energy of ``E_k``.

    Explained in the book: :doc:`/book/bz/parametric-nonparametric`.

    Parameters
    ----------
    model : LTVModel
        Fault-free model; the standard Kalman filter is designed for it.
    y, u : array_like
        Outputs ``(*batch, N, p)`` and inputs ``(N, l)`` (default zeros).
    Psi : array_like
        ``Psi_k`` ``(n, m)`` or ``(N, n, m)``.
    lam : float
        Forgetting factor ``0 < lambda <= 1``.
    energy_window, energy_alpha
        As in :func:`solution1` (threshold ``chi2.ppf(1 - alpha, w p)``; the RLS error is smaller
        than the innovation under no fault, so the level is conservative).
    start : int
        First sample at which an energy alarm may be raised (RLS warm-up).
    kalman : KalmanGains, optional
        Precomputed :func:`fdi_lib.filters.kalman_gains` of ``model`` (shared across calls).
    rls : RLSGains, optional
        Precomputed :func:`fdi_lib.rls.rls_gains` of the regressor ``H_k Gamma_k``, ``Sigma_k``
        and ``lam`` (they do not depend on the record: shared across calls).

    Returns
    -------
    Solution2Result

    Examples
    --------
    A constant ``theta`` tracked by the RLS on 10 realisations:

    >>> import numpy as np
    >>> from fdi_lib.models import fault_profile
    >>> from fdi_lib.simulate import simulate
    >>> from fdi_lib.systems import bz_example as ex
    >>> N = 120
    >>> model = ex.bz_model(N)
    >>> theta = np.broadcast_to([0.06, -0.04], (N, 2))
    >>> fault = fault_profile(model, Psi=ex.state_disturbance(np.zeros((N, 1)), theta))
    >>> s = simulate(model, rng=np.random.default_rng(21), controller=ex.controller(), size=10,
    ...              fault=fault, theta=[1.0])
    >>> res = solution2(model, s.y, s.u, Psi=ex.PSI, lam=0.99, energy_window=20,
    ...                 energy_alpha=1e-4, start=30)
    >>> res.rls.theta_hat[:, -1].mean(axis=0).round(2).tolist()     # the mean of the estimates
    [0.06, -0.04]
    """
    kal = kalman_gains(model) if kalman is None else kalman
    eps = kalman_filter(model, y, u, gains=kal).innovations
    sig = fault_signature(model, kal, fault_profile(model, Psi=Psi))
    return solution2_tracking(
        eps,
        sig.on_innovation,
        kal,
        lam=lam,
        energy_window=energy_window,
        energy_alpha=energy_alpha,
        start=start,
        rls=rls,
    )


def solution2_tracking(
    innovations: np.ndarray,
    regressor: np.ndarray,
    kalman: KalmanGains,
    *,
    lam: float,
    energy_window: int,
    energy_alpha: float,
    start: int = 0,
    rls: RLSGains | None = None,
) -> Solution2Result:
    """What :func:`solution2` does after its Kalman filter: RLS on (47) and the energy of ``E_k``.

    For callers that track the same records with several forgetting factors: the innovation and
    the regressor do not depend on ``lam``, so they are computed once and passed here (the same
    result as :func:`solution2`, bit for bit).

    Explained in the book: :doc:`/book/bz/parametric-nonparametric`.

    Parameters
    ----------
    innovations : numpy.ndarray
        Kalman innovations ``eps_k`` of the records, ``(*batch, N, p)`` (:func:`fdi_lib.filters.kalman_filter`
        with ``kalman``).
    regressor : numpy.ndarray
        ``H_k Gamma_k`` ``(N, p, m)`` with the Kalman gain (:func:`fdi_lib.signatures.fault_signature`).
    kalman : KalmanGains
        The gains of the Kalman filter (``Sigma_k`` whitens the RLS and the energy).
    lam, energy_window, energy_alpha, start, rls
        As in :func:`solution2`.

    Returns
    -------
    Solution2Result

    Examples
    --------
    One filtering for two forgetting factors, each the same as :func:`solution2`:

    >>> import numpy as np
    >>> from fdi_lib.filters import kalman_filter, kalman_gains
    >>> from fdi_lib.models import fault_profile
    >>> from fdi_lib.signatures import fault_signature
    >>> from fdi_lib.simulate import simulate
    >>> from fdi_lib.systems import bz_example as ex
    >>> N = 120
    >>> model = ex.bz_model(N)
    >>> s = simulate(model, rng=np.random.default_rng(21), controller=ex.controller(), size=4)
    >>> kal = kalman_gains(model)
    >>> eps = kalman_filter(model, s.y, s.u, gains=kal).innovations
    >>> X = fault_signature(model, kal, fault_profile(model, Psi=ex.PSI)).on_innovation
    >>> kw = dict(energy_window=20, energy_alpha=1e-4, start=30)
    >>> all(
    ...     np.array_equal(
    ...         solution2_tracking(eps, X, kal, lam=lam, **kw).rls.theta_hat,
    ...         solution2(model, s.y, s.u, Psi=ex.PSI, lam=lam, **kw).rls.theta_hat,
    ...     )
    ...     for lam in (0.95, 0.99)
    ... )
    True
    """
    if rls is not None and rls.lam != lam:
        raise ModelError(f"rls: expected RLS gains for lam = {lam}, got gains for lam = {rls.lam}")
    res = rls_track(innovations, regressor, kalman.Sigma, lam=lam, gains=rls)
    thr = energy_threshold(energy_window, kalman.Sigma.shape[-1], energy_alpha)
    en = energy_statistic(res.errors, kalman.Sigma_chol, energy_window)
    return Solution2Result(
        rls=res,
        regressor=regressor,
        energy=en,
        energy_alarm=first_alarm(en, thr, start),
        energy_threshold=thr,
    )
