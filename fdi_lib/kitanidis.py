r"""Kitanidis unbiased minimum-variance filter for LTV models with an unknown input.

Model (Zhang 2021, eq. (1)/(23), in the book's notation :math:`A \to F`, :math:`B \to G`,
:math:`C \to H`, :math:`D \to J`, state fault profile :math:`\Phi \to \Psi`):

.. math::

    \begin{aligned}
    X_{k+1} &= F_k X_k + G_k U_k + E_k d_k + W_k \; (+ \Psi_k \theta), \\
    Y_k &= H_k X_k + J_k U_k + V_k \; (+ \Phi_k \theta),
    \end{aligned}

with :math:`d_k` an arbitrary unknown input (no statistics, no model). The filter of
Kitanidis (1987), as written in Zhang (2021), eq. (24), designed for :math:`\theta = 0`,
with :math:`\hat X_k` the prediction, :math:`\hat X_{k|k}` the estimate, :math:`P_k` the prior
covariance, :math:`K^{\mathrm c}_k` the Kalman part of the gain and :math:`K_k` the Kitanidis
gain (:math:`\bar K_k` in the book):

.. math::

    \begin{aligned}
    P_k &= F_{k-1} P_{k-1|k-1} F_{k-1}^\T + Q_{k-1} && \text{(24a)}, \\
    \Sigma_k &= H_k P_k H_k^\T + R_k && \text{(24b)}, \\
    K^{\mathrm c}_k &= P_k H_k^\T \Sigma_k^{-1}, \\
    \Gamma^{\mathrm K}_k &= (I - K^{\mathrm c}_k H_k) E_{k-1} && \text{(24c)}, \\
    \Xi_k &= E_{k-1}^\T H_k^\T \Sigma_k^{-1} H_k E_{k-1} && \text{(24d)}, \\
    K_k &= K^{\mathrm c}_k + \Gamma^{\mathrm K}_k \Xi_k^{-1} E_{k-1}^\T H_k^\T \Sigma_k^{-1}
        && \text{(24g)}, \\
    P_{k|k} &= P_k - K^{\mathrm c}_k H_k P_k
        + \Gamma^{\mathrm K}_k \Xi_k^{-1} \Gamma^{\mathrm K\T}_k && \text{(24f)}, \\
    \hat X_{k|k} &= \hat X_k + K_k \varepsilon_k, \quad
        \varepsilon_k = Y_k - J_k U_k - H_k \hat X_k, \\
    \hat X_{k+1} &= F_k \hat X_{k|k} + G_k U_k && \text{(24h)}.
    \end{aligned}

The gain satisfies the key identity (30), :math:`(I - K_k H_k) E_{k-1} = 0`, so the
unknown input vanishes from the estimation error; it needs assumption (iv):
:math:`H_k E_{k-1}` of full column rank (else :class:`~fdi_lib.errors.RankConditionError`).

Time convention (the same as :mod:`fdi_lib.filters`): ``k = 0 .. N-1``; :math:`P_0` =
``model.P0`` is the covariance of :math:`X_0` *before* :math:`Y_0`; since :math:`X_0` carries no
unknown input, the update at :math:`k = 0` is the ordinary Kalman update
(:math:`K_0 = K^{\mathrm c}_0`, i.e. :math:`E_{-1} = 0`). With no unknown input at all
(:math:`s = 0`) the filter *is* the Kalman filter of :func:`fdi_lib.filters.kalman_filter`.

One-step-predictor form (Basseville & Zhang, eqs. (27)-(28), whose OCR is garbled):

.. math::

    \begin{aligned}
    \hat X_{k+1} &= F_k \hat X_k + G_k U_k + F_k L_k (Y_k - J_k U_k - H_k \hat X_k),
        \qquad L_k = K_k, \\
    P_{k+1} &= F_k \big[(I - L_k H_k) P_k (I - L_k H_k)^\T + L_k R_k L_k^\T\big] F_k^\T + Q_k,
    \end{aligned}

which is the same recursion (:math:`\hat X_{k+1} = F_k \hat X_{k|k} + G_k U_k`); the Joseph
form there equals (24f) (a short algebra shown in the book chapter ``zhang2021``).
Its "innovation" :math:`\varepsilon_k` is returned as :attr:`KitanidisResult.innovations` with
``gains.Sigma`` = :math:`H_k P_k H_k^\T + R_k`; note that :math:`\varepsilon_k` contains the term
:math:`H_k E_{k-1} d_{k-1}` (the prediction cannot know :math:`d_{k-1}`), whereas the
updated residual :math:`Y_k - J_k U_k - H_k \hat X_{k|k}` (25) does not depend on :math:`d` at all.

The gains do not depend on the data: :func:`kitanidis_gains` computes them once
and :func:`kitanidis_filter` runs the data recursion, vectorised over any leading
axes of independent realisations.

Missing samples (NaN outputs, :mod:`fdi_lib.validation`) are part of the gains: at a missing
sample :math:`K_k = 0` and :math:`P_{k|k} = P_k` (no update). The unknown input :math:`d_{k-1}`
that the update at :math:`k` would have rejected then stays in the estimation error: the next
observed sample :math:`j` rejects all the pending directions
:math:`[F_{j-1} \cdots F_k E_{k-1}, \dots, E_{j-1}]` (the gain (24g) with an orthonormal basis
of their span in place of :math:`E_{j-1}`, whose image under :math:`H_j` must have full column
rank).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fdi_lib.errors import NonFiniteError, RankConditionError, ShapeError
from fdi_lib.filters import predictor_recursion
from fdi_lib.models import FaultProfile, LTVModel, as_record, as_sequence
from fdi_lib.threads import blas_single_thread
from fdi_lib.validation import (
    array,
    check_finite,
    check_missing_known,
    cho_solve,
    cholesky,
    common_pattern,
    gains_missing,
    measurements,
    missing_pattern,
    solve_triangular,
)

__all__ = [
    "KitanidisGains",
    "KitanidisResult",
    "ResidualSignature",
    "as_unknown_input_matrix",
    "kitanidis_gains",
    "kitanidis_filter",
    "residual_signature",
]

#: Relative tolerance of the full-column-rank test of ``H_{k+1} E_k`` (assumption (iv)).
RANK_RTOL = 1e-10


def as_unknown_input_matrix(model: LTVModel, E: Any) -> np.ndarray:
    """Validate ``E`` = ``E_k`` against ``model`` (constant ``(n, s)``, per step ``(N, n, s)`` or callable of ``k``).

    Returns a read-only array of shape ``(N, n, s)``; ``E_k`` multiplies ``d_k`` in the
    equation of ``X_{k+1}``.

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> m = ltv_model(F=np.eye(2), H=np.eye(2), Q=np.eye(2), R=np.eye(2), n_steps=4)
    >>> as_unknown_input_matrix(m, [[1.0], [0.0]]).shape   # E_k on every step
    (4, 2, 1)
    """
    first = array(E(0) if callable(E) else E, "E", finite=False)
    if first.ndim == 1 and first.shape[0] == model.n:
        first = first[:, None]
        if not callable(E):
            E = first
    if first.ndim not in (2, 3) or first.shape[-2] != model.n:
        raise ShapeError(
            f"E: expected shape ({model.n}, s) or ({model.n_steps}, {model.n}, s), "
            f"got {first.shape}"
        )
    s = first.shape[-1]
    return as_sequence(E, n_steps=model.n_steps, shape=(model.n, s), name="E")


def _span(M: np.ndarray) -> np.ndarray:
    """Orthonormal basis ``(n, r)`` of the column space of ``M`` (rank by :data:`RANK_RTOL`, an SVD)."""
    U, sv, _ = np.linalg.svd(M, full_matrices=False)
    return U[:, : int(np.count_nonzero(sv > RANK_RTOL * max(1.0, sv[0] if sv.size else 0.0)))]


@dataclass(frozen=True)
class KitanidisGains:
    """Data-independent quantities of the Kitanidis filter on ``k = 0 .. N-1``.

    Attributes
    ----------
    K : numpy.ndarray
        Kitanidis gains ``K-bar_k`` of eq. (24g), ``(N, n, p)``; ``Xhat_k = Xpred_k + K_k eps_k``.
        Also the gain ``L_k`` of the one-step-predictor form (predictor gain ``F_k L_k``).
    K_kalman : numpy.ndarray
        Kalman part ``P_k H_k^T Sigma_k^{-1}``, ``(N, n, p)``.
    P : numpy.ndarray
        Prior covariances ``P-bar_{k|k-1}`` (24a), ``(N+1, n, n)`` (``P[0] = model.P0``).
    P_filt : numpy.ndarray
        Updated covariances ``P-bar_{k|k}`` (24f), ``(N, n, n)``.
    Sigma : numpy.ndarray
        ``H_k P_k H_k^T + R_k`` (24b), ``(N, p, p)``.
    Sigma_chol : numpy.ndarray
        Lower Cholesky factors of ``Sigma_k``.
    Xi : numpy.ndarray
        ``E_{k-1}^T H_k^T Sigma_k^{-1} H_k E_{k-1}`` (24d), ``(N, s, s)``; ``Xi[0] = 0`` (no unknown input
        acts on ``X_0``); also 0 at a missing sample and at the first observed sample after one
        (which rejects the inputs pending since the gap, not ``d_{k-1}`` alone).
    residual_cov : numpy.ndarray
        Covariance of the fault-free residual (25), ``H P_{k|k} H^T + R - H K R - R K^T H^T``, ``(N, p, p)``.
    E : numpy.ndarray
        The unknown-input matrices used, ``(N, n, s)``.
    missing : numpy.ndarray or None
        Booleans ``(N,)``: the samples the gains skip (``K_k = 0``, ``P_{k|k} = P_k``); ``None``:
        a fully observed record.
    """

    K: np.ndarray
    K_kalman: np.ndarray
    P: np.ndarray
    P_filt: np.ndarray
    Sigma: np.ndarray
    Sigma_chol: np.ndarray
    Xi: np.ndarray
    residual_cov: np.ndarray
    E: np.ndarray
    missing: np.ndarray | None = None


def kitanidis_gains(model: LTVModel, E: Any, missing: Any = None) -> KitanidisGains:
    """Run the covariance recursion (24a)-(24g) of the Kitanidis filter.

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Parameters
    ----------
    model : LTVModel
        Fault-free model; ``P_0 = model.P0``.
    E : array_like or callable
        Unknown-input matrices ``E_k``, ``(n, s)`` constant, ``(N, n, s)`` per step or ``k -> (n, s)``.
    missing : array_like of bool, optional
        ``(N,)``, ``True`` at the missing samples: no update there (see the module docstring).

    Returns
    -------
    KitanidisGains

    Raises
    ------
    RankConditionError
        If some ``H_{k+1} E_k`` (``k = 0 .. N-2``) does not have full column rank ``s`` (assumption (iv));
        after missing samples, ``H_j`` times all the pending unknown-input directions.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> m = ltv_model(F=0.5 * np.eye(2), H=np.eye(2), Q=np.eye(2), R=np.eye(2), n_steps=5)
    >>> g = kitanidis_gains(m, E=[[1.0], [0.0]])
    >>> E = np.array([[1.0], [0.0]])
    >>> float(np.abs((np.eye(2) - g.K[3] @ m.H[3]) @ E).max()) < 1e-14   # identity (30)
    True
    """
    with blas_single_thread():  # small matrices: BLAS threads only add synchronisation
        Es = as_unknown_input_matrix(model, E)
        N, n, p = model.n_steps, model.n, model.p
        s = Es.shape[2]
        skip = missing_pattern(missing, N)
        pending = np.zeros((n, 0))  # unknown-input directions not yet rejected by an update
        K = np.empty((N, n, p))
        Kc = np.empty((N, n, p))
        P = np.empty((N + 1, n, n))
        P_filt = np.empty((N, n, n))
        Sigma = np.empty((N, p, p))
        L = np.empty((N, p, p))
        Xi = np.zeros((N, s, s))
        Rcov = np.empty((N, p, p))
        P[0] = model.P0
        with np.errstate(over="ignore", invalid="ignore"):  # divergence is reported below, by step
            for k in range(N):
                H, Pk, Rk = model.H[k], P[k], model.R[k]
                S = H @ Pk @ H.T + Rk
                S = 0.5 * (S + S.T)
                c = cholesky(S, step=k, what="the Kitanidis covariance recursion")[0]
                if (
                    k > 0
                ):  # d_{k-1} joins the directions still to reject (after a gap, propagated ones too)
                    pending = (
                        _span(np.hstack([model.F[k - 1] @ pending, Es[k - 1]]))
                        if skip[k - 1]
                        else Es[k - 1]
                    )
                q = pending.shape[1]
                if skip[
                    k
                ]:  # missing sample: no update, the pending inputs wait for the next sample
                    Kk = Kbar = np.zeros((n, p))
                    Pf = Pk
                else:
                    Kk = cho_solve(c, H @ Pk).T  # P H^T S^{-1} by Cholesky solves (S, H P finite)
                    Pf = Pk - Kk @ H @ Pk
                    Kbar = Kk
                if q > 0 and not skip[k]:
                    HE = H @ pending
                    sv = np.linalg.svd(HE, compute_uv=False)
                    if sv.size < q or sv[-1] <= RANK_RTOL * max(1.0, sv[0]):
                        smin = float(sv[-1]) if sv.size == q else 0.0
                        gap = (
                            " (with the unknown inputs pending since the missing samples)"
                            if skip[k - 1]
                            else ""
                        )
                        raise RankConditionError(
                            f"E: assumption (iv) needs H_{{k+1}} E_k of full column rank {q}{gap}; at k = {k - 1}, "
                            f"H_{k} E_{k - 1} has shape {HE.shape} and smallest singular value {smin:.3g}"
                        )
                    # Square-root form: with Sigma = L L^T and L^{-1} H E = Qw Rw (thin QR), Xi = Rw^T Rw and
                    # Xi^{-1} E^T H^T Sigma^{-1} = Rw^{-1} Qw^T L^{-1}, a left inverse of H E accurate to
                    # cond(Rw) = sqrt(cond(Xi)) rather than cond(Xi): identity (30) then holds to that precision.
                    Lk = np.tril(c)
                    W = solve_triangular(Lk, HE, lower=True)
                    Qw, Rw = np.linalg.qr(W)
                    Linv = solve_triangular(Lk, np.eye(p), lower=True)
                    M = solve_triangular(Rw, Qw.T @ Linv)  # M H E = I
                    Gam = pending - Kk @ HE  # (24c)
                    Kbar = Kk + Gam @ M  # (24g)
                    GR = solve_triangular(Rw, Gam.T, trans=True).T  # Gamma Rw^{-1}
                    Pf = Pf + GR @ GR.T  # (24f): + Gamma Xi^{-1} Gamma^T
                    if not skip[k - 1]:
                        Xi[k] = W.T @ W  # (24d)
                Pf = 0.5 * (Pf + Pf.T)
                HK = H @ Kbar
                Rc = H @ Pf @ H.T + Rk - HK @ Rk - Rk @ HK.T
                Rcov[k] = 0.5 * (Rc + Rc.T)
                K[k], Kc[k], P_filt[k], Sigma[k], L[k] = Kbar, Kk, Pf, S, c  # tril: below
                Pn = model.F[k] @ Pf @ model.F[k].T + model.Q[k]
                P[k + 1] = 0.5 * (Pn + Pn.T)
        if not np.all(np.isfinite(P)):
            k = int(np.argwhere(~np.isfinite(P))[0, 0])
            raise NonFiniteError(
                f"model: the Kitanidis covariance recursion diverged (non-finite P at step {k})"
            )
        L = np.tril(L)
        return KitanidisGains(
            K=K,
            K_kalman=Kc,
            P=P,
            P_filt=P_filt,
            Sigma=Sigma,
            Sigma_chol=L,
            Xi=Xi,
            residual_cov=Rcov,
            E=Es,
            missing=skip if skip.any() else None,
        )


@dataclass(frozen=True)
class KitanidisResult:
    """Output of :func:`kitanidis_filter` (leading batch axes as in the data).

    Attributes
    ----------
    residuals : numpy.ndarray
        ``Y_k - J_k U_k - H_k Xhat_k``, eq. (25), ``(*batch, N, p)``: independent of ``d``.
    x_filt : numpy.ndarray
        ``Xhat_k`` of (24h), ``(*batch, N, n)``.
    x_pred : numpy.ndarray
        ``Xpred_k = F_{k-1} Xhat_{k-1} + G_{k-1} U_{k-1}`` (``Xpred_0 = x0``), ``(*batch, N+1, n)``.
    innovations : numpy.ndarray
        ``eps_k = Y_k - J_k U_k - H_k Xpred_k`` (predictor form), ``(*batch, N, p)``.
    gains : KitanidisGains
    """

    residuals: np.ndarray
    x_filt: np.ndarray
    x_pred: np.ndarray
    innovations: np.ndarray
    gains: KitanidisGains


def _check_gains(model: LTVModel, gains: Any, name: str = "gains") -> None:
    if not hasattr(gains, "K") or np.shape(gains.K) != (model.n_steps, model.n, model.p):
        raise ShapeError(
            f"{name}: expected gains with K of shape {(model.n_steps, model.n, model.p)} "
            f"for this model, got {np.shape(getattr(gains, 'K', None))}"
        )


def kitanidis_filter(
    model: LTVModel,
    y: Any,
    u: Any = None,
    E: Any = None,
    *,
    gains: KitanidisGains | None = None,
    x0: Any = None,
) -> KitanidisResult:
    """Run the Kitanidis filter (24h) and return its residuals (25).

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Parameters
    ----------
    model : LTVModel
        Fault-free model (without the unknown input term).
    y : array_like
        Outputs ``(*batch, N, p)``. A sample with a NaN is missing: the filter predicts without
        updating and its innovation and residual are NaN (:mod:`fdi_lib.validation`). The gains
        must know it (``gains.missing``), as in :func:`fdi_lib.filters.kalman_filter`.
    u : array_like, optional
        Known inputs ``(*batch, N, l)`` or ``(N, l)``; default zeros.
    E : array_like or callable, optional
        Unknown-input matrices (required unless ``gains`` is given).
    gains : KitanidisGains, optional
        Precomputed :func:`kitanidis_gains` (shared across realisations); default
        ``kitanidis_gains(model, E, missing=...)`` for the missing samples of ``y``.
    x0 : array_like, optional
        ``Xpred_0``; default ``model.x0``.

    Returns
    -------
    KitanidisResult

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> from fdi_lib.simulate import simulate
    >>> m = ltv_model(F=0.5 * np.eye(2), G=[[1.0], [0.0]], H=np.eye(2), Q=0.01 * np.eye(2),
    ...               R=0.01 * np.eye(2), n_steps=400)
    >>> u = np.where(np.arange(400) >= 200, 5.0, 0.0)[:, None]   # an unknown input from k = 200
    >>> s = simulate(m, rng=np.random.default_rng(3), u=u)
    >>> r = kitanidis_filter(m, s.y, E=[[1.0], [0.0]])   # the filter is not told u
    >>> before, after = np.abs(r.residuals[:200, 1]).mean(), np.abs(r.residuals[250:, 1]).mean()
    >>> round(float(before), 2), round(float(after), 2)     # the residual ignores the jump of u
    (0.05, 0.06)
    """
    y_arr, missing = measurements(y, n_steps=model.n_steps, width=model.p, name="y")
    if gains is None:
        if E is None:
            raise ShapeError(
                "E: expected the unknown-input matrices (or precomputed gains=), got None"
            )
        gains = kitanidis_gains(
            model, E, missing=common_pattern(missing, "y") if missing.any() else None
        )
    else:
        _check_gains(model, gains)
    check_missing_known(missing, gains, "y")
    u_arr = as_record(u, n_steps=model.n_steps, width=model.l, name="u")
    eps, xp, xf, res = predictor_recursion(model, y_arr, u_arr, gains.K, gains_missing(gains), x0)
    return KitanidisResult(residuals=res, x_filt=xf, x_pred=xp, innovations=eps, gains=gains)


@dataclass(frozen=True)
class ResidualSignature:
    """Fault signature on an updated residual (Zhang 2021, Props 1 and 2).

    Attributes
    ----------
    Upsilon : numpy.ndarray or None
        ``Upsilon_k`` (7) with a Kalman gain, or ``Upsilon-tilde_k`` (27) with a Kitanidis gain,
        ``(*batch, N, n, m)``; None when not asked for (``residual_signature(upsilon=False)``).
    on_residual : numpy.ndarray
        ``H_k Upsilon_k + Phi_k``, ``(*batch, N, p, m)``: the regressor of ``theta`` in (6)/(26).
    """

    Upsilon: np.ndarray | None
    on_residual: np.ndarray


def residual_signature(
    model: LTVModel,
    gains: Any,
    fault: FaultProfile | None = None,
    *,
    Psi: Any = None,
    Phi: Any = None,
    upsilon: bool = True,
) -> ResidualSignature:
    r"""Signature of :math:`\theta` on the updated residual, Zhang (2021) eqs. (7) and (27).

    Generalised to an output profile :math:`\Phi_k`, for the updated residual
    :math:`\tilde Y_k = Y_k - J_k U_k - H_k \hat X_{k|k}`:

    .. math::

        \begin{aligned}
        \Upsilon_0 &= -K_0 \Phi_0, \\
        \Upsilon_{k+1} &= (I - K_{k+1} H_{k+1}) (F_k \Upsilon_k + \Psi_k) - K_{k+1} \Phi_{k+1}, \\
        \tilde Y_k &= (H_k \Upsilon_k + \Phi_k) \theta + \tilde Y^0_k
        \end{aligned}

    (for :math:`\Phi = 0` this is exactly (7b)/(27b) with :math:`\Upsilon_0 = 0`).

    Explained in the book: :doc:`/book/zhang2021/sparse`.

    Parameters
    ----------
    model : LTVModel
    gains : KalmanGains or KitanidisGains
        Any object with filter gains ``K`` of shape ``(N, n, p)`` such that
        :math:`\hat X_{k|k} = \hat X_k + K_k \varepsilon_k`: :func:`fdi_lib.filters.kalman_gains` (Prop. 1)
        or :func:`kitanidis_gains` (Prop. 2).
    fault : FaultProfile, optional
        ``Psi_k`` (``(N, n, m)``) and ``Phi_k`` (``(N, p, m)``), shared by all realisations.
    Psi, Phi : array_like, optional
        Instead of ``fault``: per-realisation profiles ``(*batch, N, n, m)`` / ``(*batch, N, p, m)``
        (e.g. a random ``Psi_k`` drawn in each Monte Carlo trial).
    upsilon : bool
        Return ``Upsilon`` too (default). ``False``: only ``on_residual`` (the same values), the
        recursion kept in one sample's memory instead of ``N`` (for a regression alone: the
        ``Upsilon`` of a Monte Carlo chunk's trials are tens of MB).

    Returns
    -------
    ResidualSignature

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> m = ltv_model(F=0.5 * np.eye(2), H=np.eye(2), Q=np.eye(2), R=np.eye(2), n_steps=20)
    >>> g = kitanidis_gains(m, [[1.0], [0.0]])
    >>> from fdi_lib.models import fault_profile
    >>> sig = residual_signature(m, g, fault_profile(m, Phi=np.eye(2)))   # both sensors
    >>> sig.Upsilon.shape, sig.on_residual.shape
    ((20, 2, 2), (20, 2, 2))
    """
    _check_gains(model, gains)
    N, n, p = model.n_steps, model.n, model.p
    if fault is not None:
        if Psi is not None or Phi is not None:
            raise ShapeError("fault: give either fault or Psi/Phi arrays, not both")
        Psi_a, Phi_a = np.asarray(fault.Psi), np.asarray(fault.Phi)
    else:
        if Psi is None and Phi is None:
            raise ShapeError("Psi, Phi: expected at least one fault profile, got None")
        Psi_a = None if Psi is None else array(Psi, "Psi", finite=False)
        Phi_a = None if Phi is None else array(Phi, "Phi", finite=False)
        m = (Psi_a if Psi_a is not None else Phi_a).shape[-1]
        if Psi_a is None:  # one zero profile, broadcast over the realisations below
            Psi_a = np.zeros((N, n, m))
        if Phi_a is None:
            Phi_a = np.zeros((N, p, m))
    if Psi_a.ndim < 3 or Psi_a.shape[-3:-1] != (N, n):
        raise ShapeError(f"Psi: expected shape (..., {N}, {n}, m), got {Psi_a.shape}")
    if Phi_a.ndim < 3 or Phi_a.shape[-3:-1] != (N, p) or Phi_a.shape[-1] != Psi_a.shape[-1]:
        raise ShapeError(
            f"Phi: expected shape (..., {N}, {p}, {Psi_a.shape[-1]}), got {Phi_a.shape}"
        )
    for arr, name in ((Psi_a, "Psi"), (Phi_a, "Phi")):
        check_finite(arr, name)
    batch = np.broadcast_shapes(Psi_a.shape[:-3], Phi_a.shape[:-3])
    m = Psi_a.shape[-1]
    # An all-zero Phi (the usual state-fault case) is skipped rather than multiplied (tested before
    # the broadcast: a shared profile is not read once per realisation).
    has_phi = bool(np.any(Phi_a))
    Psi_a = np.broadcast_to(Psi_a, (*batch, N, n, m))
    Phi_a = np.broadcast_to(Phi_a, (*batch, N, p, m))
    nb = int(np.prod(batch, dtype=int))
    # The recursion acts column by column: the columns of all realisations side by side, (N, rows,
    # batch * m), so that each step is one plain matrix product (one BLAS call). The profiles are
    # read in place at each step, seen in that layout ((rows, batch, m) views, not copied).
    Psi_c = np.moveaxis(Psi_a.reshape(nb, N, n, m), 0, 2)
    Phi_c = np.moveaxis(Phi_a.reshape(nb, N, p, m), 0, 2) if has_phi else None
    K = gains.K
    IKH = np.eye(n) - K @ model.H  # (N, n, n)
    # Upsilon_k in U[k % kept]: every sample, or (upsilon=False) the last one (each step reads
    # Upsilon_{k-1} into V, a buffer kept across the steps, before it writes Upsilon_k)
    kept = N if upsilon else 1
    U = np.empty((kept, n, nb * m))
    V = np.empty((n, nb * m))
    # H_k Upsilon_k, one product per sample while Upsilon_k is in cache, written in place in the
    # stacked layout; the regression (36)-(38) built from it is a view too (k and the output merge
    # into its rows), which fdi_lib.sparse.lasso_path_batch gathers a few realisations at a time
    HU = np.empty((N, p, nb * m))
    U[0] = -K[0] @ Phi_c[0].reshape(p, nb * m) if has_phi else 0.0
    for k in range(N):
        Uk = U[k % kept]
        if k > 0:
            np.matmul(model.F[k - 1], U[(k - 1) % kept], out=V)
            np.add(V.reshape(n, nb, m), Psi_c[k - 1], out=V.reshape(n, nb, m))
            np.matmul(IKH[k], V, out=Uk)
            if has_phi:
                Uk -= K[k] @ Phi_c[k].reshape(p, nb * m)
        np.matmul(model.H[k], Uk, out=HU[k])
    # back to (*batch, N, rows, m) as views of the stacked arrays (no copy, realisations not
    # contiguous)
    Ups = np.moveaxis(U.reshape(N, n, nb, m), 2, 0).reshape(*batch, N, n, m) if upsilon else None
    on_res = np.moveaxis(HU.reshape(N, p, nb, m), 2, 0).reshape(*batch, N, p, m)
    if has_phi:
        on_res = on_res + Phi_a
    return ResidualSignature(Upsilon=Ups, on_residual=on_res)
