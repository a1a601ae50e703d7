r"""Kalman filter for LTV models, in one-step-predictor and prediction/update forms.

Zhang & Basseville (2014), eqs. (6)-(8), (10):

.. math::

    \begin{aligned}
    \Sigma_k &= H_k P_k H_k^\T + R_k, \\
    K_k &= P_k H_k^\T \Sigma_k^{-1} && \text{(filter gain)}, \\
    \varepsilon_k &= Y_k - J_k U_k - H_k \hat X_k && \text{(innovation)}, \\
    \hat X_{k+1} &= F_k \hat X_k + G_k U_k + F_k K_k \varepsilon_k
        && \text{(predictor, gain } F_k K_k \text{)}, \\
    P_{k+1} &= F_k (I - K_k H_k) P_k F_k^\T + Q_k .
    \end{aligned}

The updated estimate of the prediction/update form (Zhang 2021, eq. (4)) is
:math:`\hat X_{k|k} = \hat X_k + K_k \varepsilon_k`; both are returned.

The gains do not depend on the data: :func:`kalman_gains` computes them once
and :func:`kalman_filter` runs the data recursion, vectorised over any leading
axes of independent realisations (the Monte Carlo engine shares the gains).
Numerics: gains by Cholesky solves (no explicit inverse of :math:`\Sigma_k`), the
covariance update in Joseph form, symmetrised at every step.

Missing samples (NaN outputs, :mod:`fdi_lib.validation`) are part of the gains: at a missing
sample :math:`K_k = 0` and :math:`P_{k|k} = P_k` (the filter predicts without updating, as
``filterpy``'s ``KalmanFilter.update(None)``), so :math:`P_k`, :math:`\Sigma_k`, :math:`A_k = F_k`
and the fault signatures built from the gains are those of the record actually observed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fdi_lib.errors import ModelError, NonFiniteError
from fdi_lib.models import LTVModel, as_record
from fdi_lib.threads import blas_single_thread
from fdi_lib.validation import (
    check_gains,
    check_missing_known,
    cho_solve,
    cholesky,
    common_pattern,
    gains_missing,
    initial_state,
    measurements,
    missing_pattern,
)

__all__ = [
    "KalmanGains",
    "KalmanResult",
    "kalman_gains",
    "kalman_filter",
    "predictor_recursion",
    "as_outputs",
]


@dataclass(frozen=True)
class KalmanGains:
    """Data-independent quantities of the Kalman filter on ``k = 0 .. N-1``.

    Attributes
    ----------
    K : numpy.ndarray
        Filter gains ``K_k = P_k H_k^T Sigma_k^{-1}``, shape ``(N, n, p)``, eq. (7).
    P : numpy.ndarray
        Prediction error covariances ``P_k = Cov(X_k - Xhat_k)``, ``(N+1, n, n)``, eq. (8).
    P_filt : numpy.ndarray
        Updated covariances ``P_{k|k} = (I - K_k H_k) P_k``, ``(N, n, n)``.
    Sigma : numpy.ndarray
        Innovation covariances ``Sigma_k``, ``(N, p, p)``, eq. (8).
    Sigma_chol : numpy.ndarray
        Lower Cholesky factors of ``Sigma_k``, ``(N, p, p)``.
    A : numpy.ndarray
        Closed-loop predictor matrices ``F_k (I - K_k H_k)``, ``(N, n, n)``: the
        dynamics of the prediction error and of the fault signature, eq. (12).
    FK : numpy.ndarray
        Predictor gains ``F_k K_k`` of eq. (6), ``(N, n, p)``.
    missing : numpy.ndarray or None
        Booleans ``(N,)``: the samples the gains skip (``K_k = 0``, ``P_{k|k} = P_k``,
        ``A_k = F_k``); ``None``: a fully observed record.
    """

    K: np.ndarray
    P: np.ndarray
    P_filt: np.ndarray
    Sigma: np.ndarray
    Sigma_chol: np.ndarray
    A: np.ndarray
    FK: np.ndarray
    missing: np.ndarray | None = None

    def whiten(self, residual: np.ndarray) -> np.ndarray:
        """``L_k^{-1} r_k`` with ``Sigma_k = L_k L_k^T``: unit-covariance innovations, ``(..., N, p)``."""
        return np.linalg.solve(self.Sigma_chol, residual[..., None])[..., 0]


def kalman_gains(model: LTVModel, missing: Any = None) -> KalmanGains:
    """Run the Riccati recursion (7)-(8) of the Kalman filter designed for the fault-free model.

    Explained in the book: :doc:`/book/zb2014/signature`.

    Parameters
    ----------
    model : LTVModel
        The fault-free model (1); ``P_0 = model.P0``.
    missing : array_like of bool, optional
        ``(N,)``, ``True`` at the samples that are missing (e.g. ``numpy.isnan(y).any(axis=-1)``):
        there ``K_k = 0`` and ``P_{k|k} = P_k`` (no update); ``Sigma_k`` is still
        ``H_k P_k H_k^T + R_k``, the covariance of the output that was not observed.
        Default: none missing.

    Returns
    -------
    KalmanGains

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> m = ltv_model(F=[[0.9]], H=[[1.0]], Q=1.0, R=1.0, n_steps=200)
    >>> g = kalman_gains(m)
    >>> round(float(g.P[-1, 0, 0]), 4)  # DARE P^2 - 0.81 P - 1 = 0: P = (0.81 + sqrt(0.81**2 + 4)) / 2
    1.4839
    """
    with blas_single_thread():  # small matrices: BLAS threads only add synchronisation
        if not isinstance(model, LTVModel):
            raise ModelError(f"model: expected an LTVModel, got {type(model).__name__}")
        N, n, p = model.n_steps, model.n, model.p
        skip = missing_pattern(missing, N)
        K = np.empty((N, n, p))
        P = np.empty((N + 1, n, n))
        P_filt = np.empty((N, n, n))
        Sigma = np.empty((N, p, p))
        L = np.empty((N, p, p))
        A = np.empty((N, n, n))
        FK = np.empty((N, n, p))
        eye = np.eye(n)
        P[0] = model.P0
        with np.errstate(over="ignore", invalid="ignore"):  # divergence is reported below, by step
            for k in range(N):
                F, H, Pk = model.F[k], model.H[k], P[k]
                S = H @ Pk @ H.T + model.R[k]
                S = 0.5 * (S + S.T)
                c = cholesky(S, step=k, what="the Riccati recursion")[0]
                if skip[k]:  # missing sample: no update
                    Kk, IKH, Pf = np.zeros((n, p)), eye, Pk
                else:
                    Kk = cho_solve(c, H @ Pk).T  # P H^T S^{-1} without forming S^{-1}
                    IKH = eye - Kk @ H
                    Pf = IKH @ Pk @ IKH.T + Kk @ model.R[k] @ Kk.T  # Joseph form: stays PSD
                    Pf = 0.5 * (Pf + Pf.T)
                Pn = F @ Pf @ F.T + model.Q[k]
                K[k], P_filt[k], Sigma[k], A[k], FK[k] = Kk, Pf, S, F @ IKH, F @ Kk
                L[k] = c  # its upper triangle zeroed once, after the recursion
                P[k + 1] = 0.5 * (Pn + Pn.T)
        if not np.all(np.isfinite(P)):
            k = int(np.argwhere(~np.isfinite(P))[0, 0])
            raise NonFiniteError(
                f"model: the Riccati recursion diverged (non-finite P_k at step {k})"
            )
        L = np.tril(L)
        return KalmanGains(
            K=K,
            P=P,
            P_filt=P_filt,
            Sigma=Sigma,
            Sigma_chol=L,
            A=A,
            FK=FK,
            missing=skip if skip.any() else None,
        )


@dataclass(frozen=True)
class KalmanResult:
    """Output of :func:`kalman_filter` (leading batch axes as in the data).

    Attributes
    ----------
    innovations : numpy.ndarray
        ``eps_k``, shape ``(*batch, N, p)``, eq. (10).
    x_pred : numpy.ndarray
        One-step predictions ``Xhat_k = Xhat_{k|k-1}``, shape ``(*batch, N+1, n)``.
    x_filt : numpy.ndarray
        Updated estimates ``Xhat_{k|k}``, shape ``(*batch, N, n)``.
    updated_residuals : numpy.ndarray
        ``Y_k - J_k U_k - H_k Xhat_{k|k}``, shape ``(*batch, N, p)`` (Zhang 2021, eq. (5)).
    gains : KalmanGains
    """

    innovations: np.ndarray
    x_pred: np.ndarray
    x_filt: np.ndarray
    updated_residuals: np.ndarray
    gains: KalmanGains


def as_outputs(model: LTVModel, y: Any, name: str = "y") -> np.ndarray:
    """Validate an output record ``y`` ``(*batch, N, p)`` against ``model`` (see :func:`~fdi_lib.models.as_record`).

    ``name`` is the argument named in errors.

    Explained in the book: :doc:`/book/notation`.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> m = ltv_model(F=np.eye(2), H=np.eye(2), Q=np.eye(2), R=np.eye(2), n_steps=5)
    >>> as_outputs(m, np.zeros((3, 5, 2))).shape          # three realisations
    (3, 5, 2)
    """
    return as_record(y, n_steps=model.n_steps, width=model.p, name=name)


def kalman_filter(
    model: LTVModel, y: Any, u: Any = None, *, gains: KalmanGains | None = None, x0: Any = None
) -> KalmanResult:
    """Run the Kalman one-step predictor (6) on outputs ``y`` and inputs ``u``.

    Explained in the book: :doc:`/book/zb2014/signature`.

    Parameters
    ----------
    model : LTVModel
        The fault-free model the filter is designed for (Remark 1 of the paper).
    y : array_like
        Outputs, shape ``(*batch, N, p)``. A sample with a NaN is missing: the filter predicts
        without updating and its innovation is NaN (:mod:`fdi_lib.validation`). The gains must
        know it (``gains.missing``); all realisations then miss the same samples.
    u : array_like, optional
        Inputs, shape ``(*batch, N, l)`` or ``(N, l)``; default zeros.
    gains : KalmanGains, optional
        Precomputed :func:`kalman_gains` (shared across realisations); default
        ``kalman_gains(model, missing=...)`` for the missing samples of ``y``. The samples they
        mark missing are skipped (NaN innovation) even where ``y`` is finite; a NaN in ``y`` at a
        sample they observe is a :class:`~fdi_lib.errors.NonFiniteError`.
    x0 : array_like, optional
        Initial prediction ``Xhat_0``; default ``model.x0``.

    Returns
    -------
    KalmanResult

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> from fdi_lib.simulate import simulate
    >>> m = ltv_model(F=[[0.9]], H=[[1.0]], Q=0.1, R=0.1, n_steps=2000)
    >>> s = simulate(m, rng=np.random.default_rng(0))
    >>> eps = kalman_filter(m, s.y).innovations       # white, of covariance Sigma_k
    >>> g = kalman_gains(m)
    >>> round(float(np.mean(eps[100:, 0] ** 2 / g.Sigma[100:, 0, 0])), 1)   # normalised: about 1
    1.0
    """
    y_arr, missing = measurements(y, n_steps=model.n_steps, width=model.p, name="y")
    u_arr = as_record(u, n_steps=model.n_steps, width=model.l, name="u")
    if gains is None:
        g = kalman_gains(model, missing=common_pattern(missing, "y") if missing.any() else None)
    else:
        check_gains(model, gains)
        g = gains
    check_missing_known(missing, g, "y")
    eps, xh, xf, upd = predictor_recursion(model, y_arr, u_arr, g.K, gains_missing(g), x0)
    return KalmanResult(innovations=eps, x_pred=xh, x_filt=xf, updated_residuals=upd, gains=g)


def predictor_recursion(
    model: LTVModel, y: np.ndarray, u: np.ndarray, K: np.ndarray, skip: np.ndarray, x0: Any = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The state recursion of the Kalman filter and of the Kitanidis filter (same form, each with
    its own gains ``K``), over checked records.

    ``eps_k = ybar_k - H_k Xhat_k``, ``Xfilt_k = Xhat_k + K_k eps_k``,
    ``Xhat_{k+1} = F_k Xfilt_k + G_k u_k`` with ``ybar_k = y_k - J_k u_k``; at a sample marked in
    ``skip`` (missing) there is no update (``K_k = 0``) and the innovation and updated residual are
    NaN.

    Explained in the book: :doc:`/book/zb2014/signature`.

    Parameters
    ----------
    model : LTVModel
        The system (``F``, ``G``, ``H``, ``J`` per step).
    y : numpy.ndarray
        Checked measurements, ``(*batch, N, p)``.
    u : numpy.ndarray
        Checked inputs, ``(N, l)`` or ``(*batch, N, l)``.
    K : numpy.ndarray
        Gains ``(N, n, p)`` of the filter.
    skip : numpy.ndarray
        Boolean ``(N,)``: the samples the gains treat as missing.
    x0 : array_like, optional
        Initial prediction ``Xhat_0``; default ``model.x0``.

    Returns
    -------
    innovations, x_pred, x_filt, updated_residuals : numpy.ndarray
        ``(*batch, N, p)``, ``(*batch, N + 1, n)``, ``(*batch, N, n)``, ``(*batch, N, p)``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> m = ltv_model(F=[[0.5]], H=[[1.0]], Q=1.0, R=1.0, n_steps=3)
    >>> K = np.zeros((3, 1, 1)); skip = np.zeros(3, dtype=bool)   # no gain: open-loop prediction
    >>> eps, x_pred, x_filt, upd = predictor_recursion(m, np.ones((3, 1)), np.zeros((3, 0)), K, skip,
    ...                                                x0=[4.0])
    >>> x_pred[:, 0].tolist(), eps[:, 0].tolist()
    ([4.0, 2.0, 1.0, 0.5], [-3.0, -1.0, 0.0])
    """
    N, n = model.n_steps, model.n
    batch = y.shape[:-2]
    any_skip = bool(skip.any())
    # Sample-major work arrays (step k: the contiguous block [k]), written in place by each step's
    # products and sums (the same operations as on the records' layout: the same bits).
    xh = np.empty((N + 1, *batch, n))
    xh[0] = initial_state(model, x0)
    eps = np.empty((N, *batch, y.shape[-1]))
    xf = np.empty((N, *batch, n))
    # Known input contributions, computed for all k at once.
    Gu = np.broadcast_to(np.einsum("kij,...kj->...ki", model.G, u), (*batch, N, n))
    ybar = y - np.einsum("kij,...kj->...ki", model.J, u)
    yk, Guk = np.moveaxis(ybar, -2, 0), np.moveaxis(Gu, -2, 0)
    HT, KT, FT = (np.swapaxes(a, 1, 2) for a in (model.H, K, model.F))
    for k in range(N):
        if any_skip and skip[k]:  # a missing sample: NaN innovation, no update (K_k = 0)
            eps[k] = np.nan
            xf[k] = xh[k]
        else:
            e = np.matmul(xh[k], HT[k], out=eps[k])
            np.subtract(yk[k], e, out=e)
            np.add(xh[k], np.matmul(e, KT[k], out=xf[k]), out=xf[k])
        np.add(np.matmul(xf[k], FT[k], out=xh[k + 1]), Guk[k], out=xh[k + 1])
    eps, xh, xf = (np.ascontiguousarray(np.moveaxis(a, 0, -2)) for a in (eps, xh, xf))
    upd = ybar - np.einsum("kij,...kj->...ki", model.H, xf)
    if any_skip:
        upd = np.where(skip[:, None], np.nan, upd)
    return eps, xh, xf, upd
