"""Generalized likelihood ratio (GLR) tests on the Kalman innovation.

Zhang & Basseville (2014), Section 4:

* known fault profile, eqs. (24)-(30): recursive information ``C_k`` and score ``d_k``,
  ``l_k = d_k^T C_k^{-1} d_k``, ``theta_hat_k = C_k^{-1} d_k``;
* jump with unknown onset in a moving window, eqs. (31)-(37):
  ``l_k = max_{k-w+1 <= r <= k-s} d_k(r)^T C_k(r)^{-1} d_k(r)``, ``r_hat_k = argmax``.

The windowed test keeps, for every candidate onset of the window, the signature
``Gamma_k(r)`` and the sums ``C_k(r)``, ``d_k(r)`` as stacked arrays updated with
one vectorised step per sample (no loop over ``r``), either online
(:class:`WindowedGLR`, sample by sample) or over a record (:func:`glr_window`).
Everything noise-independent (``Gamma_k(r)``, ``C_k(r)`` and its spectral
factorisation) is computed once per sample and shared by all realisations of a
batch of innovations ``(*batch, N, p)``.

Quadratic forms use the Moore-Penrose pseudo-inverse of ``C`` (via ``eigh``):
``d^T C^+ d`` is the exact GLR statistic even when ``C`` is singular
(non-identifiable directions of ``theta`` carry no likelihood), and equals
``d^T C^{-1} d`` when persistent excitation (22) holds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdi_lib.errors import ModelError, NonFiniteError, ShapeError
from fdi_lib.filters import KalmanGains
from fdi_lib.models import FaultFamily, LTVModel
from fdi_lib.validation import array, check_gains, integer, missing_samples, real

__all__ = ["GLRResult", "glr_known_profile", "WindowGLRResult", "WindowedGLR", "glr_window",
           "quadratic_form", "first_alarm"]

#: Relative eigenvalue cut-off of the pseudo-inverse of information matrices.
RANK_RTOL = 1e-10


def _pinv_factors(C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(V, inv)`` with ``C^+ = V diag(inv) V^T`` for symmetric PSD ``C`` ``(..., m, m)``."""
    lam, V = np.linalg.eigh(C)
    cutoff = RANK_RTOL * np.maximum(lam[..., -1:], np.finfo(float).tiny)
    inv = np.where(lam > cutoff, 1.0 / np.where(lam > cutoff, lam, 1.0), 0.0)
    return V, inv


def quadratic_form(C: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(d^T C^+ d, C^+ d)`` for symmetric PSD ``C`` ``(..., m, m)`` and ``d`` ``(..., m)``.

    ``C`` may have fewer leading axes than ``d`` (it is shared across the extra
    leading axes of ``d``, e.g. Monte Carlo realisations).
    """
    V, inv = _pinv_factors(C)
    q = np.sum(V * d[..., :, None], axis=-2)          # V^T d
    return np.sum(q * q * inv, axis=-1), np.sum(V * (q * inv)[..., None, :], axis=-1)


def _check_innovations(eps: np.ndarray, N: int, p: int) -> tuple[np.ndarray, np.ndarray]:
    """Innovations ``(..., N, p)`` and their missing samples ``(..., N)`` (NaN rows, :mod:`fdi_lib.validation`)."""
    eps = array(eps, "innovations", finite=False)
    if eps.ndim < 2 or eps.shape[-2:] != (N, p):
        raise ShapeError(f"innovations: expected shape (..., {N}, {p}), got {eps.shape}")
    return eps, missing_samples(eps, "innovations")


@dataclass(frozen=True)
class GLRResult:
    """Known-profile GLR (24)-(30): statistic ``(*batch, N)``, ``theta_hat`` ``(*batch, N, m)``,
    information ``C`` ``(N, m, m)`` and score ``d`` ``(*batch, N, m)`` after each sample."""

    statistic: np.ndarray
    theta_hat: np.ndarray
    C: np.ndarray
    d: np.ndarray


def glr_known_profile(innovations: np.ndarray, gains: KalmanGains, signature: np.ndarray) -> GLRResult:
    """GLR test with a fully known fault profile, eqs. (24)-(30).

    Parameters
    ----------
    innovations : array_like
        ``eps_k``, shape ``(*batch, N, p)``; a sample with a NaN is missing and skipped
        (:mod:`fdi_lib.validation`).
    gains : KalmanGains
        Provides ``Sigma_k``.
    signature : array_like
        ``H_k Gamma_k + Phi_k``, shape ``(N, p, m)`` (:attr:`Signature.on_innovation`).

    Returns
    -------
    GLRResult
        ``statistic[..., k] = l_k`` uses ``eps_0 .. eps_k``; under no fault and persistent
        excitation it is chi-square with ``m`` degrees of freedom. With missing samples,
        ``C`` has the batch axes of the innovations, ``(*batch, N, m, m)``.
    """
    if np.ndim(getattr(gains, "Sigma_chol", None)) != 3 or np.ndim(getattr(gains, "Sigma", None)) != 3:
        raise ModelError(f"gains: expected KalmanGains (Sigma, Sigma_chol of shape (N, p, p)), "
                         f"got {type(gains).__name__}")
    S = array(signature, "signature")
    N, p = gains.Sigma.shape[:2]
    if S.ndim != 3 or S.shape[:2] != (N, p):
        raise ShapeError(f"signature: expected shape ({N}, {p}, m), got {S.shape}")
    eps, missing = _check_innovations(innovations, N, p)
    if missing.any():  # a missing sample contributes nothing: zero its innovation and signature rows
        eps = np.where(missing[..., None], 0.0, eps)
        S = np.where(missing[..., None, None], 0.0, S)
    # Whitened regressors and innovations: Sigma^{-1/2} S and Sigma^{-1/2} eps (Cholesky solves).
    Sw = np.linalg.solve(gains.Sigma_chol, S)
    ew = gains.whiten(eps)
    C = np.cumsum(np.einsum("...kpi,...kpj->...kij", Sw, Sw), axis=-3)   # (27)
    d = np.cumsum(np.einsum("...kpi,...kp->...ki", Sw, ew), axis=-2)     # (28)
    stat, theta = quadratic_form(C, d)                                # (30), (24)
    return GLRResult(statistic=stat, theta_hat=theta, C=C, d=d)


@dataclass(frozen=True)
class WindowGLRResult:
    """Windowed GLR with unknown onset, eqs. (35)-(37).

    Attributes
    ----------
    statistic : numpy.ndarray
        ``l_k``, shape ``(*batch, N)``; ``nan`` where no onset is admissible yet.
    onset : numpy.ndarray
        ``r_hat_k``, shape ``(*batch, N)``, integer, ``-1`` where undefined (eq. (36)).
    theta_hat : numpy.ndarray
        ``theta_hat_k(r_hat_k)``, shape ``(*batch, N, m)`` (eq. (34)).
    C_hat, d_hat : numpy.ndarray
        ``C_k(r_hat_k)`` ``(*batch, N, m, m)`` and ``d_k(r_hat_k)`` ``(*batch, N, m)``: the
        Fisher information and normalised residual of the minmax isolation test (41)
        run from the estimated onset.
    window, min_samples : int
        ``w`` and ``s`` of eq. (37).
    """

    statistic: np.ndarray
    onset: np.ndarray
    theta_hat: np.ndarray
    C_hat: np.ndarray
    d_hat: np.ndarray
    window: int
    min_samples: int


class WindowedGLR:
    """Online windowed GLR test (35)-(37), one :meth:`update` per sample.

    Parameters
    ----------
    model : LTVModel
    gains : KalmanGains
    family : FaultFamily
        Jump profiles ``Psi_k(r)``, ``Phi_k(r)`` (:func:`fdi_lib.models.step_family`
        or :func:`~fdi_lib.models.impulse_family`).
    window : int
        ``w``: onsets ``r`` in ``{k-w+1, ..., k-s}`` are candidates at time ``k``.
    min_samples : int, optional
        ``s >= 0`` of eqs. (35)-(37); default ``ceil(m / p)``, the fewest samples that can
        make ``C_k(r)`` invertible.
    batch_shape : tuple of int
        Leading shape of the innovations passed to :meth:`update` (realisations).

    Notes
    -----
    Time indices are ``k = 0 .. N-1``. Cost per sample: ``O(w (n^2 m + p m^2))`` for
    the shared quantities plus ``O(batch w p m)`` for the scores.
    """

    def __init__(self, model: LTVModel, gains: KalmanGains, family: FaultFamily, window: int,
                 min_samples: int | None = None, batch_shape: tuple[int, ...] = ()) -> None:
        if not isinstance(model, LTVModel) or not isinstance(family, FaultFamily):
            raise ModelError(f"model, family: expected an LTVModel and a FaultFamily, got "
                             f"{type(model).__name__} and {type(family).__name__}")
        check_gains(model, gains)
        N, n, p, m = model.n_steps, model.n, model.p, family.m
        if family.Psi_tilde.shape[:2] != (N, n) or family.Phi_tilde.shape[:2] != (N, p):
            raise ShapeError(f"family: expected Psi~ ({N}, {n}, m) and Phi~ ({N}, {p}, m), "
                             f"got {family.Psi_tilde.shape} and {family.Phi_tilde.shape}")
        window = integer(window, "window", low=1, high=N)
        s = -(-m // p) if min_samples is None else min_samples
        s = integer(s, "min_samples", low=0, high=window - 1)
        if family.kind == "impulse" and np.any(family.Phi_tilde):
            raise ModelError("family: impulsive profiles act on the state only (Phi~ must be zero)")
        self.model, self.gains, self.family = model, gains, family
        self.window, self.min_samples = int(window), int(s)
        self.batch_shape = tuple(batch_shape)
        w = self.window
        # Stacks indexed by slot = r mod w, for the onsets r in {k-w+1, ..., k}.
        self._Gamma = np.zeros((w, n, m))
        self._C = np.zeros((w, m, m))
        # Scores d_k(r) stored as (w, m, B), realisations last: every per-onset product below is
        # then a BLAS matrix product with B columns, and reductions run over contiguous rows.
        self._B = int(np.prod(self.batch_shape, dtype=int))
        self._d = np.zeros((w, m, self._B))
        self._onset = np.full(w, -1)
        self._drive = family.Psi_tilde - gains.FK @ family.Phi_tilde   # Psi~_k - F_k K_k Phi~_k
        self.k = 0

    def update(self, eps_k: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Process innovation ``eps_k`` ``(*batch, p)``.

        A NaN ``eps_k`` (missing sample) must be missing in every realisation of the batch; the
        sample is then skipped (it adds nothing to ``C_k(r)`` and ``d_k(r)``).

        Returns ``(l_k, r_hat_k, theta_hat_k, C_k(r_hat), d_k(r_hat))`` (``nan``/``-1`` when
        no onset is admissible yet).
        """
        model, g, fam, k, w = self.model, self.gains, self.family, self.k, self.window
        if k >= model.n_steps:
            raise ModelError(f"update: the model horizon N={model.n_steps} is exhausted")
        eps_k = array(eps_k, "eps_k", finite=False)
        if eps_k.shape != (*self.batch_shape, model.p):
            raise ShapeError(f"eps_k: expected shape {(*self.batch_shape, model.p)}, got {eps_k.shape}")
        missing = missing_samples(eps_k, "eps_k")
        skip = bool(np.all(missing))
        if np.any(missing) and not skip:
            i = tuple(int(j) for j in np.argwhere(missing)[0])
            raise NonFiniteError(f"eps_k: expected a sample missing (NaN) in all realisations or in none, "
                                 f"got NaN at batch index {i} only (step {k})")
        if skip:
            eps_k = np.zeros_like(eps_k)
        if k > 0:
            # Gamma_k(r) = A_{k-1} Gamma_{k-1}(r) + drive_{k-1}(r), for all onsets at once (eq. (31)).
            r = self._onset
            if fam.kind == "step":
                active = (r >= 0) & (k - 1 >= r)
            else:  # impulse: Psi_{k-1}(r) != 0 only for r = k
                active = np.zeros(w, dtype=bool)
            self._Gamma = g.A[k - 1] @ self._Gamma + active[:, None, None] * self._drive[k - 1]
        # New onset r = k enters the window (replacing r = k - w).
        slot = k % w
        self._onset[slot] = k
        self._C[slot] = 0.0
        self._d[slot] = 0.0
        self._Gamma[slot] = self._drive[k - 1] if (fam.kind == "impulse" and k > 0) else 0.0
        # Signature on the innovation for every onset: H_k Gamma_k(r) + Phi~_k 1{k >= r}.
        sig = model.H[k] @ self._Gamma
        if fam.kind == "step":
            sig = sig + fam.Phi_tilde[k]
        sig_w = np.linalg.solve(g.Sigma_chol[k], sig)                 # Sigma^{-1/2} S, (w, p, m)
        if skip:  # a missing sample contributes nothing to the sums
            sig_w = np.zeros_like(sig_w)
        e_w = np.linalg.solve(g.Sigma_chol[k], eps_k.reshape(self._B, model.p).T)   # (p, B)
        sig_wT = np.swapaxes(sig_w, -1, -2)                           # (w, m, p)
        self._C += sig_wT @ sig_w                                     # (32), recursively (27)
        self._d += sig_wT @ e_w                                       # (33), recursively (28)
        self.k = k + 1
        admissible = (self._onset >= 0) & (self._onset <= k - self.min_samples) & (self._onset > k - w)
        nan = np.full(self.batch_shape, np.nan)
        if not admissible.any():
            m = fam.m
            return (nan, np.full(self.batch_shape, -1), np.full((*self.batch_shape, m), np.nan),
                    np.full((*self.batch_shape, m, m), np.nan), np.full((*self.batch_shape, m), np.nan))
        slots = np.nonzero(admissible)[0]
        V, inv = _pinv_factors(self._C[slots])       # shared by all realisations
        root = V * np.sqrt(inv)[:, None, :]          # C^+ = root root^T
        d = self._d[slots]                           # (S, m, B)
        q = np.swapaxes(root, -1, -2) @ d            # (S, m, B)
        stat = np.sum(q * q, axis=1)                 # (35) for every admissible onset, (S, B)
        best = np.argmax(stat, axis=0)               # (36), (B,)
        cols = np.arange(self._B)
        l_k = stat[best, cols]
        th = (root[best] @ q[best, :, cols][..., None])[..., 0]             # (34): C^+ d
        d_hat = d[best, :, cols]
        shape = self.batch_shape
        m = fam.m
        l_k, th, d_hat = l_k.reshape(shape), th.reshape(*shape, m), d_hat.reshape(*shape, m)
        best_onset = self._onset[slots][best].reshape(shape)
        C_hat = self._C[slots][best].reshape(*shape, m, m)
        return l_k, best_onset, th, C_hat, d_hat



def glr_window(innovations: np.ndarray, model: LTVModel, gains: KalmanGains, family: FaultFamily,
               window: int, min_samples: int | None = None) -> WindowGLRResult:
    """Windowed GLR with unknown onset (35)-(37) over a whole record.

    Parameters
    ----------
    innovations : array_like
        ``eps_k``, shape ``(*batch, N, p)``; several realisations share the
        noise-independent computations. A sample with a NaN is missing and skipped
        (realisations with different missing samples are run as separate groups).
    model, gains, family, window, min_samples
        As in :class:`WindowedGLR`.

    Returns
    -------
    WindowGLRResult
    """
    if not isinstance(model, LTVModel):
        raise ModelError(f"model: expected an LTVModel, got {type(model).__name__}")
    eps, missing = _check_innovations(innovations, model.n_steps, model.p)
    batch = eps.shape[:-2]
    if missing.any() and batch:
        flat_missing = missing.reshape(-1, model.n_steps)
        patterns, group = np.unique(flat_missing, axis=0, return_inverse=True)
        if len(patterns) > 1:
            return _grouped_glr_window(eps, group.reshape(-1), model, gains, family, window, min_samples)
    det = WindowedGLR(model, gains, family, window, min_samples, batch_shape=batch)
    N, m = model.n_steps, family.m
    stat = np.empty((*batch, N))
    onset = np.empty((*batch, N), dtype=int)
    theta = np.empty((*batch, N, m))
    C_hat = np.empty((*batch, N, m, m))
    d_hat = np.empty((*batch, N, m))
    for k in range(N):
        (stat[..., k], onset[..., k], theta[..., k, :], C_hat[..., k, :, :],
         d_hat[..., k, :]) = det.update(eps[..., k, :])
    return WindowGLRResult(statistic=stat, onset=onset, theta_hat=theta, C_hat=C_hat, d_hat=d_hat,
                           window=det.window, min_samples=det.min_samples)


def _grouped_glr_window(eps: np.ndarray, group: np.ndarray, model: LTVModel, gains: KalmanGains,
                        family: FaultFamily, window: int, min_samples: int | None) -> WindowGLRResult:
    """:func:`glr_window` run once per group of realisations sharing the same missing samples."""
    batch, N, m = eps.shape[:-2], model.n_steps, family.m
    flat = eps.reshape(-1, N, model.p)
    B = flat.shape[0]
    out = {"statistic": np.empty((B, N)), "onset": np.empty((B, N), dtype=int),
           "theta_hat": np.empty((B, N, m)), "C_hat": np.empty((B, N, m, m)), "d_hat": np.empty((B, N, m))}
    res = None
    for i in np.unique(group):
        rows = np.nonzero(group == i)[0]
        res = glr_window(flat[rows], model, gains, family, window, min_samples)
        for key, arr in out.items():
            arr[rows] = getattr(res, key)
    return WindowGLRResult(**{key: arr.reshape(*batch, *arr.shape[1:]) for key, arr in out.items()},
                           window=res.window, min_samples=res.min_samples)


def first_alarm(statistic: np.ndarray, threshold: float, start: int = 0) -> np.ndarray:
    """Index of the first ``k >= start`` with ``statistic[..., k] > threshold`` (``-1`` if none).

    Parameters
    ----------
    statistic : array_like
        ``(..., N)``. NaN is allowed only as a leading warm-up (a windowed statistic not yet
        defined); a NaN after a finite value, or an infinite value, raises
        :class:`~fdi_lib.errors.NonFiniteError` with its index: NaN is never read as "no alarm".
    threshold : float
        Finite alarm threshold.
    start : int
        First admissible index, ``0 <= start <= N``.

    Examples
    --------
    >>> import numpy as np
    >>> first_alarm(np.array([[0.5, 7.0, 9.0], [0.1, 0.2, 0.3]]), 6.63)
    array([ 1, -1])
    >>> first_alarm(np.array([np.nan, 7.0, 9.0]), 6.63, start=2)   # a leading warm-up NaN is fine
    array(2)
    """
    stat = array(statistic, "statistic", finite=False)
    if stat.ndim < 1:
        raise ShapeError(f"statistic: expected an array (..., N), got a scalar")
    threshold = real(threshold, "threshold")
    start = integer(start, "start", low=0, high=stat.shape[-1])
    nan = np.isnan(stat)
    bad = np.isinf(stat) | (nan & np.logical_or.accumulate(~nan, axis=-1))
    if bad.any():
        i = tuple(int(j) for j in np.argwhere(bad)[0])
        raise NonFiniteError(f"statistic: expected finite values after the warm-up, got {stat[i]} "
                             f"at index {i}")
    over = np.nan_to_num(stat, nan=-np.inf) > threshold
    over[..., :start] = False
    hit = over.any(axis=-1)
    return np.where(hit, np.argmax(over, axis=-1), -1)
