"""Generalized likelihood ratio (GLR) tests on the Kalman innovation.

Zhang & Basseville (2014), Section 4:

* known fault profile, eqs. (24)-(30): recursive information ``C_k`` and score ``d_k``,
  ``l_k = d_k^T C_k^{-1} d_k``, ``theta_hat_k = C_k^{-1} d_k``;
* jump with unknown onset in a moving window, eqs. (31)-(37):
  ``l_k = max_{k-w+1 <= r <= k-s} d_k(r)^T C_k(r)^{-1} d_k(r)``, ``r_hat_k = argmax``.

The windowed test keeps, for every candidate onset of the window, the signature
``Gamma_k(r)`` and the sums ``C_k(r)``, ``d_k(r)`` as stacked arrays (no loop over ``r``),
either online (:class:`WindowedGLR`, sample by sample) or over a record (:func:`glr_window`).
Everything noise-independent (``Gamma_k(r)``, ``C_k(r)`` and the factors of its
pseudo-inverse) is computed once, for all samples at once, when the detector is built, and
shared by all realisations of a batch of innovations ``(*batch, N, p)``; a record of few
realisations is then evaluated by blocks of samples.

Quadratic forms use the Moore-Penrose pseudo-inverse of ``C`` (via its eigen-decomposition:
one Jacobi rotation per 2 x 2 matrix, applied to all matrices at once, LAPACK's ``eigh`` beyond
4 x 4):
``d^T C^+ d`` is the exact GLR statistic even when ``C`` is singular
(non-identifiable directions of ``theta`` carry no likelihood), and equals
``d^T C^{-1} d`` when persistent excitation (22) holds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.filters import KalmanGains
from fdi_lib.models import FaultFamily, LTVModel

__all__ = ["GLRResult", "glr_known_profile", "WindowGLRResult", "WindowedGLR", "glr_window",
           "quadratic_form", "first_alarm"]

#: Relative eigenvalue cut-off of the pseudo-inverse of information matrices.
RANK_RTOL = 1e-10


def _pinv_factors(C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(V, inv)`` with ``C^+ = V diag(inv) V^T`` for symmetric PSD ``C`` ``(..., m, m)``."""
    lam, V = _small_eigh(C) if C.shape[-1] <= _JACOBI_MAX_M else np.linalg.eigh(C)
    cutoff = RANK_RTOL * np.maximum(lam.max(axis=-1, keepdims=True), np.finfo(float).tiny)
    inv = np.where(lam > cutoff, 1.0 / np.where(lam > cutoff, lam, 1.0), 0.0)
    return V, inv


#: Largest size decomposed by :func:`_small_eigh` (cyclic Jacobi); larger ones go to LAPACK.
_JACOBI_MAX_M = 4


def _small_eigh(C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigen-decomposition ``C = V diag(lam) V^T`` of a stack of small symmetric matrices.

    Cyclic Jacobi rotations, each applied to the whole stack at once (a few array operations
    instead of one LAPACK call per matrix, which dominates for thousands of 2 x 2 matrices).
    For ``m = 2`` one rotation is exact; larger ``m`` sweep until the off-diagonal part is
    below rounding (quadratic convergence: a handful of sweeps). Eigenvalues are not sorted.
    """
    m = C.shape[-1]
    if m == 2:  # one rotation, on contiguous component arrays
        a, b, c = C[..., 0, 0], C[..., 0, 1], C[..., 1, 1]
        nz = b != 0
        with np.errstate(over="ignore"):  # b ~ 0: theta = inf, t = 0
            theta = (c - a) / (2.0 * np.where(nz, b, 1.0))
            t = np.where(nz, np.sign(theta) / (np.abs(theta) + np.hypot(theta, 1.0)), 0.0)
        t = np.where(nz & (theta == 0), 1.0, t)
        cs = 1.0 / np.sqrt(t * t + 1.0)
        sn = t * cs
        V = np.stack([np.stack([cs, sn], axis=-1), np.stack([-sn, cs], axis=-1)], axis=-2)
        return np.stack([a - t * b, c + t * b], axis=-1), V
    A = np.array(C, dtype=float)
    V = np.broadcast_to(np.eye(m), A.shape).copy()
    scale = np.sqrt(np.sum(A * A, axis=(-2, -1)))
    for _ in range(1 if m == 2 else 12):
        for p in range(m - 1):
            for q in range(p + 1, m):
                apq = A[..., p, q]
                nz = apq != 0
                with np.errstate(over="ignore"):  # apq ~ 0: theta = inf, t = 0
                    theta = (A[..., q, q] - A[..., p, p]) / (2.0 * np.where(nz, apq, 1.0))
                    t = np.where(nz, np.sign(theta) / (np.abs(theta) + np.hypot(theta, 1.0)), 0.0)
                t = np.where(nz & (theta == 0), 1.0, t)
                c = 1.0 / np.sqrt(t * t + 1.0)
                s = (t * c)[..., None]
                c = c[..., None]
                for M in (A, V):  # columns p, q of A J and of V J
                    mp, mq = M[..., :, p].copy(), M[..., :, q].copy()
                    M[..., :, p] = c * mp - s * mq
                    M[..., :, q] = s * mp + c * mq
                mp, mq = A[..., p, :].copy(), A[..., q, :].copy()  # rows p, q of J^T (A J)
                A[..., p, :] = c * mp - s * mq
                A[..., q, :] = s * mp + c * mq
                A[..., p, q] = A[..., q, p] = 0.0
        off = np.sum(A * A, axis=(-2, -1)) - np.sum(np.diagonal(A, axis1=-2, axis2=-1) ** 2, axis=-1)
        if m == 2 or np.all(off <= (1e-32 * scale * scale)):
            break
    return np.diagonal(A, axis1=-2, axis2=-1).copy(), V


def quadratic_form(C: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(d^T C^+ d, C^+ d)`` for symmetric PSD ``C`` ``(..., m, m)`` and ``d`` ``(..., m)``.

    ``C`` may have fewer leading axes than ``d`` (it is shared across the extra
    leading axes of ``d``, e.g. Monte Carlo realisations).
    """
    V, inv = _pinv_factors(C)
    q = np.sum(V * d[..., :, None], axis=-2)          # V^T d
    return np.sum(q * q * inv, axis=-1), np.sum(V * (q * inv)[..., None, :], axis=-1)


def _check_innovations(eps: np.ndarray, N: int, p: int) -> np.ndarray:
    eps = np.asarray(eps, dtype=float)
    if eps.ndim < 2 or eps.shape[-2:] != (N, p):
        raise ShapeError(f"innovations: expected shape (..., {N}, {p}), got {eps.shape}")
    return eps


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
        ``eps_k``, shape ``(*batch, N, p)``.
    gains : KalmanGains
        Provides ``Sigma_k``.
    signature : array_like
        ``H_k Gamma_k + Phi_k``, shape ``(N, p, m)`` (:attr:`Signature.on_innovation`).

    Returns
    -------
    GLRResult
        ``statistic[..., k] = l_k`` uses ``eps_0 .. eps_k``; under no fault and persistent
        excitation it is chi-square with ``m`` degrees of freedom.
    """
    S = np.asarray(signature, dtype=float)
    N, p = gains.Sigma.shape[:2]
    if S.ndim != 3 or S.shape[:2] != (N, p):
        raise ShapeError(f"signature: expected shape ({N}, {p}, m), got {S.shape}")
    eps = _check_innovations(innovations, N, p)
    # Whitened regressors and innovations: Sigma^{-1/2} S and Sigma^{-1/2} eps (Cholesky solves).
    Sw = np.linalg.solve(gains.Sigma_chol, S)
    ew = gains.whiten(eps)
    C = np.cumsum(np.einsum("kpi,kpj->kij", Sw, Sw), axis=0)          # (27)
    d = np.cumsum(np.einsum("kpi,...kp->...ki", Sw, ew), axis=-2)     # (28)
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
    the shared quantities (all computed at construction, kept in ``O(N w m (m + p))``
    memory) plus ``O(batch w p m)`` for the scores.
    """

    def __init__(self, model: LTVModel, gains: KalmanGains, family: FaultFamily, window: int,
                 min_samples: int | None = None, batch_shape: tuple[int, ...] = ()) -> None:
        N, n, p, m = model.n_steps, model.n, model.p, family.m
        if family.Psi_tilde.shape[:2] != (N, n) or family.Phi_tilde.shape[:2] != (N, p):
            raise ShapeError(f"family: expected Psi~ ({N}, {n}, m) and Phi~ ({N}, {p}, m), "
                             f"got {family.Psi_tilde.shape} and {family.Phi_tilde.shape}")
        if not isinstance(window, (int, np.integer)) or window < 1:
            raise ModelError(f"window: expected a positive integer, got {window!r}")
        s = -(-m // p) if min_samples is None else min_samples
        if not isinstance(s, (int, np.integer)) or not 0 <= s < window:
            raise ModelError(f"min_samples: expected an integer in [0, window={window}), got {s!r}")
        if family.kind == "impulse" and np.any(family.Phi_tilde):
            raise ModelError("family: impulsive profiles act on the state only (Phi~ must be zero)")
        self.model, self.gains, self.family = model, gains, family
        self.window, self.min_samples = int(window), int(s)
        self.batch_shape = tuple(batch_shape)
        self._B = int(np.prod(self.batch_shape, dtype=int))
        self._shared()
        # Scores d_k(r) stored as (w, m, B), slot = r mod w, realisations last: every per-onset
        # product below is then a BLAS matrix product with B columns.
        self._d = np.zeros((self.window, m, self._B))
        self.k = 0

    def _shared(self) -> None:
        """Everything noise-independent, for all ``k`` at once (stacks indexed by slot ``r mod w``).

        ``Gamma_k(r)`` by the recursion (31) (one vectorised step per sample over the window's
        onsets), then in single array operations over all ``(k, r)``: the whitened signatures
        ``Sigma_k^{-1/2} (H_k Gamma_k(r) + Phi~_k)``, the informations ``C_k(r)`` (sums (32),
        recursively (27)), and the factors of their pseudo-inverses ``C^+ = R R^T``.
        """
        model, g, fam, w = self.model, self.gains, self.family, self.window
        N, n, m = model.n_steps, model.n, fam.m
        drive = fam.Psi_tilde - g.FK @ fam.Phi_tilde   # Psi~_k - F_k K_k Phi~_k
        k_all = np.arange(N)
        # onset held by slot j at time k: the r = j mod w in (k - w, k] (-1 before the record)
        onset = k_all[:, None] - (k_all[:, None] - np.arange(w)[None, :]) % w      # (N, w)
        onset[onset < 0] = -1
        # Gamma_k(r) as (n, w m): slots side by side, so that (31) is one matrix product per sample
        Gamma = np.zeros((N, n, w, m))
        G = np.zeros((n, w, m))
        drive_c = np.ascontiguousarray(np.swapaxes(drive, 0, 1))  # (n, N, m)
        for k in range(N):
            if k > 0:  # Gamma_k(r) = A_{k-1} Gamma_{k-1}(r) + drive_{k-1}(r), eq. (31)
                G = (g.A[k - 1] @ G.reshape(n, w * m)).reshape(n, w, m)
                if fam.kind == "step":
                    G += (onset[k - 1] >= 0)[None, :, None] * drive_c[:, k - 1, None, :]
                # impulse: Psi_{k-1}(r) != 0 only for r = k
            G[:, k % w] = drive_c[:, k - 1] if (fam.kind == "impulse" and k > 0) else 0.0   # r = k enters
            Gamma[k] = G
        sig = (model.H @ Gamma.reshape(N, n, w * m)).reshape(N, -1, w, m)      # (N, p, w, m)
        if fam.kind == "step":
            sig = sig + (onset >= 0)[:, None, :, None] * fam.Phi_tilde[:, :, None, :]
        self._Linv = np.linalg.inv(g.Sigma_chol)                         # Sigma_k^{-1/2}, (N, p, p)
        sig_w = (self._Linv @ sig.reshape(N, -1, w * m)).reshape(sig.shape)
        self._sig_wT = np.ascontiguousarray(np.transpose(sig_w, (0, 2, 3, 1)))  # (N, w, m, p)
        inc = np.einsum("kpwi,kpwj->kwij", sig_w, sig_w)                 # (N, w, m, m)
        C = np.empty_like(inc)
        acc = np.zeros((w, m, m))
        for k in range(N):
            acc[k % w] = 0.0
            acc += inc[k]
            C[k] = acc
        self._Cs = C
        self._onsets = onset
        self._allowed = (onset >= 0) & (onset <= k_all[:, None] - self.min_samples)   # (N, w)
        self._admissible = [np.nonzero(a)[0] for a in self._allowed]
        V, inv = _pinv_factors(C)
        self._root = V * np.sqrt(inv)[..., None, :]                      # C^+ = root root^T

    def update(self, eps_k: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Process innovation ``eps_k`` ``(*batch, p)``.

        Returns ``(l_k, r_hat_k, theta_hat_k, C_k(r_hat), d_k(r_hat))`` (``nan``/``-1`` when
        no onset is admissible yet).
        """
        model, k, w, m = self.model, self.k, self.window, self.family.m
        if k >= model.n_steps:
            raise ModelError(f"update: the model horizon N={model.n_steps} is exhausted")
        eps_k = np.asarray(eps_k, dtype=float)
        if eps_k.shape != (*self.batch_shape, model.p):
            raise ShapeError(f"eps_k: expected shape {(*self.batch_shape, model.p)}, got {eps_k.shape}")
        # New onset r = k enters the window (replacing r = k - w); scores (33), recursively (28).
        self._d[k % w] = 0.0
        e_w = self._Linv[k] @ eps_k.reshape(self._B, model.p).T         # (p, B)
        self._d += self._sig_wT[k] @ e_w
        self.k = k + 1
        shape = self.batch_shape
        slots = self._admissible[k]
        if not slots.size:
            return (np.full(shape, np.nan), np.full(shape, -1), np.full((*shape, m), np.nan),
                    np.full((*shape, m, m), np.nan), np.full((*shape, m), np.nan))
        root = self._root[k, slots]                  # shared by all realisations
        d = self._d[slots]                           # (S, m, B)
        q = np.swapaxes(root, -1, -2) @ d            # (S, m, B)
        stat = np.einsum("smb,smb->sb", q, q)        # (35) for every admissible onset, (S, B)
        best = np.argmax(stat, axis=0)               # (36), (B,)
        cols = np.arange(self._B)
        l_k = stat[best, cols]
        th = (root[best] @ q[best, :, cols][..., None])[..., 0]             # (34): C^+ d
        d_hat = d[best, :, cols]
        l_k, th, d_hat = l_k.reshape(shape), th.reshape(*shape, m), d_hat.reshape(*shape, m)
        best_onset = self._onsets[k, slots][best].reshape(shape)
        C_hat = self._Cs[k, slots][best].reshape(*shape, m, m)
        return l_k, best_onset, th, C_hat, d_hat


    def _record(self, eps: np.ndarray) -> WindowGLRResult:
        """:func:`glr_window`: all the samples of a fresh detector, statistics evaluated by blocks.

        The scores ``d_k(r)`` are accumulated sample by sample as in :meth:`update` (same sums
        in the same order) and kept for a block of samples; the quadratic forms (35), the
        maximisation (36) and the estimates (34) then run on the whole block at once.
        """
        model, w, m, B = self.model, self.window, self.family.m, self._B
        N, p = model.n_steps, model.p
        if self.k != 0:
            raise ModelError("_record: expected a fresh detector")
        e_w = self._Linv @ np.moveaxis(eps.reshape(B, N, p), 0, 2)        # (N, p, B)
        stat = np.full((N, B), np.nan)
        onset = np.full((N, B), -1)
        theta = np.full((N, B, m), np.nan)
        C_hat = np.full((N, B, m, m), np.nan)
        d_hat = np.full((N, B, m), np.nan)
        block = max(1, min(N, 2_000_000 // (w * m * B)))
        for k0 in range(0, N, block):
            ks = np.arange(k0, min(N, k0 + block))
            D = np.empty((ks.size, w, m, B))
            for i, k in enumerate(ks):
                self._d[k % w] = 0.0
                self._d += self._sig_wT[k] @ e_w[k]
                D[i] = self._d
            root = self._root[ks]                                        # (K, w, m, m)
            q = np.swapaxes(root, -1, -2) @ D                            # (K, w, m, B)
            st = np.einsum("kwmb,kwmb->kwb", q, q)                       # (35)
            st = np.where(self._allowed[ks][:, :, None], st, -np.inf)
            best = np.argmax(st, axis=1)                                 # (36), (K, B)
            ok = self._allowed[ks].any(axis=1)                           # some onset admissible
            kk = np.arange(ks.size)[:, None]
            stat[ks[ok]] = np.take_along_axis(st, best[:, None, :], axis=1)[:, 0][ok]
            onset[ks[ok]] = self._onsets[ks[:, None], best][ok]
            at = best[:, None, None, :]
            qb = np.take_along_axis(q, at, axis=1)[:, 0]                 # (K, m, B)
            th = np.einsum("kbij,kjb->kbi", root[kk, best], qb)          # (34): C^+ d
            theta[ks[ok]] = th[ok]
            C_hat[ks[ok]] = self._Cs[ks[:, None], best][ok]
            d_hat[ks[ok]] = np.swapaxes(np.take_along_axis(D, at, axis=1)[:, 0], 1, 2)[ok]
        self.k = N
        shape = self.batch_shape
        return WindowGLRResult(statistic=np.moveaxis(stat, 0, -1).reshape(*shape, N),
                               onset=np.moveaxis(onset, 0, -1).reshape(*shape, N),
                               theta_hat=np.moveaxis(theta, 0, 1).reshape(*shape, N, m),
                               C_hat=np.moveaxis(C_hat, 0, 1).reshape(*shape, N, m, m),
                               d_hat=np.moveaxis(d_hat, 0, 1).reshape(*shape, N, m),
                               window=w, min_samples=self.min_samples)


def glr_window(innovations: np.ndarray, model: LTVModel, gains: KalmanGains, family: FaultFamily,
               window: int, min_samples: int | None = None) -> WindowGLRResult:
    """Windowed GLR with unknown onset (35)-(37) over a whole record.

    Parameters
    ----------
    innovations : array_like
        ``eps_k``, shape ``(*batch, N, p)``; several realisations share the
        noise-independent computations.
    model, gains, family, window, min_samples
        As in :class:`WindowedGLR`.

    Returns
    -------
    WindowGLRResult
    """
    eps = _check_innovations(innovations, model.n_steps, model.p)
    batch = eps.shape[:-2]
    det = WindowedGLR(model, gains, family, window, min_samples, batch_shape=batch)
    if det._B <= _RECORD_MAX_BATCH:
        return det._record(eps)
    # many realisations: one update per sample already works on wide arrays
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


#: Up to this many realisations, :func:`glr_window` evaluates the statistics by blocks of
#: samples (:meth:`WindowedGLR._record`: few, wide array operations); beyond, sample by sample.
_RECORD_MAX_BATCH = 4


def first_alarm(statistic: np.ndarray, threshold: float, start: int = 0) -> np.ndarray:
    """Index of the first ``k >= start`` with ``statistic[..., k] > threshold`` (``-1`` if none)."""
    stat = np.asarray(statistic, dtype=float)
    over = np.nan_to_num(stat, nan=-np.inf) > threshold
    over[..., :start] = False
    hit = over.any(axis=-1)
    return np.where(hit, np.argmax(over, axis=-1), -1)
