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
realisations is then evaluated by blocks of samples. A family whose profiles differ per
realisation (e.g. made of each realisation's own input: :func:`fdi_lib.models.step_family` with
a leading batch axis) keeps these arrays per realisation, still built for all of them at once.

Missing samples: the gains know them (:func:`fdi_lib.filters.kalman_gains` with ``missing=``),
hence so do ``Sigma_k`` and the signatures; the innovations are NaN there and the sample adds
nothing to ``C`` and ``d`` (folded into the precomputed ``C_k(r)`` of the windowed test, so
that its block evaluation stays available).

Quadratic forms use the Moore-Penrose pseudo-inverse of ``C`` (via its eigen-decomposition:
one Jacobi rotation per 2 x 2 matrix, applied to all matrices at once, LAPACK's ``eigh`` beyond
4 x 4):
``d^T C^+ d`` is the exact GLR statistic even when ``C`` is singular
(non-identifiable directions of ``theta`` carry no likelihood), and equals
``d^T C^{-1} d`` when persistent excitation (22) holds.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fdi_lib.errors import CovarianceError, ModelError, NonFiniteError, ShapeError
from fdi_lib.filters import KalmanGains
from fdi_lib.models import FaultFamily, LTVModel
from fdi_lib.validation import (
    COV_RTOL,
    array,
    check_gains,
    check_skipped,
    gains_missing,
    integer,
    missing_samples,
    real,
)

__all__ = [
    "GLRResult",
    "glr_known_profile",
    "WindowGLRResult",
    "WindowedGLR",
    "glr_window",
    "quadratic_form",
    "first_alarm",
]

#: Relative eigenvalue cut-off of the pseudo-inverse of information matrices.
RANK_RTOL = 1e-10


def _pinv_factors(C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(V, inv)`` with ``C^+ = V diag(inv) V^T`` for symmetric PSD ``C`` ``(..., m, m)``."""
    lam, V = _eigh(C)
    return V, _pinv_diagonal(lam)


def _eigh(C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(lam, V)`` of symmetric ``C`` ``(..., m, m)``: :func:`_small_eigh` up to 4 x 4, LAPACK beyond."""
    return _small_eigh(C) if C.shape[-1] <= _JACOBI_MAX_M else np.linalg.eigh(C)


def _pinv_diagonal(lam: np.ndarray) -> np.ndarray:
    """``1 / lam`` above the cut-off ``RANK_RTOL * max(lam)``, 0 below: the pseudo-inverse's
    eigenvalues. An eigenvalue below the smallest normal number is below the cut-off too (its
    inverse would overflow to infinity): an information that small is none."""
    tiny = np.finfo(float).tiny  # (a top below it leaves every eigenvalue below it too)
    if lam.shape[-1] == 1:  # its own top: lam > RANK_RTOL lam holds for every lam >= tiny, and
        # fails for +inf, whose inverse is the 0 left where nothing is kept: the same values
        keep = lam >= tiny
    else:
        keep = (lam > RANK_RTOL * lam.max(axis=-1, keepdims=True)) & (lam >= tiny)
    return np.divide(1.0, lam, out=np.zeros(lam.shape), where=keep)


def _pinv_root(C: np.ndarray) -> np.ndarray:
    """``R`` with ``C^+ = R R^T`` for symmetric PSD ``C`` ``(..., m, m)``: ``V diag(inv)^(1/2)`` of
    :func:`_pinv_factors`. For ``m = 1`` (``V = 1``) the square root of ``inv`` itself, the same
    bits without the eigenvector stack and its product."""
    if C.shape[-1] == 1:
        inv = _pinv_diagonal(C[..., 0])
        return np.sqrt(inv, out=inv)[..., None, :]
    V, inv = _pinv_factors(C)
    return V * np.sqrt(inv)[..., None, :]


#: Largest size decomposed by :func:`_small_eigh` (cyclic Jacobi); larger ones go to LAPACK.
_JACOBI_MAX_M = 4


def _small_eigh(C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigen-decomposition ``C = V diag(lam) V^T`` of a stack of small symmetric matrices.

    Cyclic Jacobi rotations, each applied to the whole stack at once (a few array operations
    instead of one LAPACK call per matrix, which dominates for thousands of 2 x 2 matrices).
    ``m = 1`` is diagonal already; for ``m = 2`` one rotation is exact; larger ``m`` sweep until
    the off-diagonal part is below rounding (quadratic convergence: a handful of sweeps).
    Eigenvalues are not sorted.
    """
    m = C.shape[-1]
    if m == 1:  # already diagonal
        return C[..., 0].copy(), np.ones_like(C)
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
        off = np.sum(A * A, axis=(-2, -1)) - np.sum(
            np.diagonal(A, axis1=-2, axis2=-1) ** 2, axis=-1
        )
        if m == 2 or np.all(off <= (1e-32 * scale * scale)):
            break
    return np.diagonal(A, axis1=-2, axis2=-1).copy(), V


def quadratic_form(C: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(d^T C^+ d, C^+ d)`` for symmetric PSD ``C`` ``(..., m, m)`` and ``d`` ``(..., m)``.

    ``C`` may have fewer leading axes than ``d`` (it is shared across the extra
    leading axes of ``d``, e.g. Monte Carlo realisations).

    Explained in the book: :doc:`/book/zb2014/glr`.

    Raises
    ------
    NonFiniteError
        A NaN or infinite value in ``C`` or ``d`` (named, with its index).
    CovarianceError
        ``C`` not symmetric, or not positive semi-definite (an eigenvalue below
        ``-COV_RTOL`` times the largest magnitude), with the index of the matrix.

    Examples
    --------
    >>> import numpy as np
    >>> C = np.array([[[2.0, 0.0], [0.0, 0.0]]])          # singular: theta_2 not identifiable
    >>> d = np.array([[4.0, 0.0]])
    >>> stat, theta = quadratic_form(C, d)
    >>> float(stat[0]), theta[0].tolist()                 # d^T C^+ d = 16 / 2
    (8.0, [2.0, 0.0])
    """
    C = array(C, "C")
    d = array(d, "d")
    if (
        C.ndim < 2
        or C.shape[-1] != C.shape[-2]
        or d.ndim < 1
        or d.shape[-1] != C.shape[-1]
        or C.shape[-1] < 1
    ):
        raise ShapeError(
            f"C, d: expected shapes (..., m, m) and (..., m) with m >= 1, got {C.shape} and "
            f"{d.shape}"
        )
    scale = np.abs(C).max(axis=(-2, -1))
    asym = np.abs(C - np.swapaxes(C, -1, -2)).max(axis=(-2, -1))
    bad = asym > COV_RTOL * scale
    if bad.any():
        i = tuple(int(j) for j in np.argwhere(bad)[0])
        raise CovarianceError(
            f"C: expected symmetric matrices, got asymmetry {asym[i]:.3g} "
            f"(largest entry {scale[i]:.3g}) at index {i}"
        )
    lam, V = _eigh(C)
    bad = lam.min(axis=-1) < -COV_RTOL * np.abs(lam).max(axis=-1)
    if bad.any():
        i = tuple(int(j) for j in np.argwhere(bad)[0])
        raise CovarianceError(
            f"C: expected positive semi-definite matrices, got smallest eigenvalue "
            f"{lam[i].min():.6g} (largest magnitude {np.abs(lam[i]).max():.3g}) at index {i}"
        )
    inv = _pinv_diagonal(lam)
    q = np.sum(V * d[..., :, None], axis=-2)  # V^T d
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


def glr_known_profile(
    innovations: np.ndarray, gains: KalmanGains, signature: np.ndarray
) -> GLRResult:
    """GLR test with a fully known fault profile, eqs. (24)-(30).

    Explained in the book: :doc:`/book/zb2014/glr`.

    Parameters
    ----------
    innovations : array_like
        ``eps_k``, shape ``(*batch, N, p)``; a sample with a NaN is missing and skipped
        (:mod:`fdi_lib.validation`). It must be NaN at the samples the gains skip
        (``gains.missing``).
    gains : KalmanGains
        Provides ``Sigma_k``; those of the filter that produced the innovations, which knew its
        missing samples (:func:`fdi_lib.filters.kalman_gains` with ``missing=``).
    signature : array_like
        ``H_k Gamma_k + Phi_k``, shape ``(N, p, m)`` (:attr:`Signature.on_innovation`), from
        :func:`fdi_lib.signatures.fault_signature` with the same gains.

    Returns
    -------
    GLRResult
        ``statistic[..., k] = l_k`` uses ``eps_0 .. eps_k``; under no fault and persistent
        excitation it is chi-square with ``m`` degrees of freedom. With missing samples,
        ``C`` has the batch axes of the innovations, ``(*batch, N, m, m)``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model, fault_profile
    >>> from fdi_lib.filters import kalman_gains, kalman_filter
    >>> from fdi_lib.signatures import fault_signature
    >>> from fdi_lib.simulate import simulate
    >>> m = ltv_model(F=[[0.5]], H=[[1.0]], Q=0.01, R=0.01, n_steps=400)
    >>> f = fault_profile(m, Phi=[[1.0]])                       # a sensor bias theta
    >>> s = simulate(m, rng=np.random.default_rng(1), fault=f, theta=[0.3])
    >>> g = kalman_gains(m)
    >>> r = glr_known_profile(kalman_filter(m, s.y).innovations, g, fault_signature(m, g, f).on_innovation)
    >>> theta, se = float(r.theta_hat[-1, 0]), float(r.C[-1, 0, 0]) ** -0.5   # C: Fisher information
    >>> bool(abs(theta - 0.3) < 3 * se), bool(r.statistic[-1] > 100.0)        # estimate; detected
    (True, True)
    """
    if (
        np.ndim(getattr(gains, "Sigma_chol", None)) != 3
        or np.ndim(getattr(gains, "Sigma", None)) != 3
    ):
        raise ModelError(
            f"gains: expected KalmanGains (Sigma, Sigma_chol of shape (N, p, p)), "
            f"got {type(gains).__name__}"
        )
    S = array(signature, "signature")
    N, p = gains.Sigma.shape[:2]
    if S.ndim != 3 or S.shape[:2] != (N, p) or S.shape[2] < 1:
        raise ShapeError(f"signature: expected shape ({N}, {p}, m) with m >= 1, got {S.shape}")
    eps, missing = _check_innovations(innovations, N, p)
    check_skipped(missing, gains, "innovations")
    if (
        missing.any()
    ):  # a missing sample contributes nothing: zero its innovation and signature rows
        eps = np.where(missing[..., None], 0.0, eps)
        S = np.where(missing[..., None, None], 0.0, S)
    # Whitened regressors and innovations: Sigma^{-1/2} S and Sigma^{-1/2} eps (Cholesky solves).
    Sw = np.linalg.solve(gains.Sigma_chol, S)
    ew = gains.whiten(eps)
    C = np.cumsum(np.einsum("...kpi,...kpj->...kij", Sw, Sw), axis=-3)  # (27)
    d = np.cumsum(np.einsum("...kpi,...kp->...ki", Sw, ew), axis=-2)  # (28)
    stat, theta = quadratic_form(C, d)  # (30), (24)
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
        run from the estimated onset. ``theta_hat``, ``C_hat`` and ``d_hat`` are ``None`` when
        :func:`glr_window` was asked for the statistics alone (``estimates=False``);
        ``theta_hat`` and ``C_hat`` are ``None`` with ``estimates="scores"``.
    window, min_samples : int
        ``w`` and ``s`` of eq. (37).
    """

    statistic: np.ndarray
    onset: np.ndarray
    theta_hat: np.ndarray | None
    C_hat: np.ndarray | None
    d_hat: np.ndarray | None
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
        or :func:`~fdi_lib.models.impulse_family`), shared by all realisations, or one per
        realisation (``family.batch_shape == batch_shape``, :func:`~fdi_lib.models.step_family`
        with a leading batch axis): then ``Gamma_k(r)``, ``C_k(r)`` and the factors of its
        pseudo-inverse are per realisation, still computed for all realisations at once (one
        matrix product per sample in the recursion (31)).
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
    memory; both times the number of realisations for per-realisation profiles) plus
    ``O(batch w p m)`` for the scores.

    Raises
    ------
    ShapeError
        Profiles not ``(N, n, m)``/``(N, p, m)`` (after the family's batch axes), or
        per-realisation profiles whose batch shape is not ``batch_shape``.
    """

    def __init__(
        self,
        model: LTVModel,
        gains: KalmanGains,
        family: FaultFamily,
        window: int,
        min_samples: int | None = None,
        batch_shape: tuple[int, ...] = (),
    ) -> None:
        self._setup(model, gains, family, window, min_samples, batch_shape)
        self._shared()
        self._reset()

    @classmethod
    def _unkept(
        cls,
        model: LTVModel,
        gains: KalmanGains,
        family: FaultFamily,
        window: int,
        min_samples: int | None,
        batch_shape: tuple[int, ...],
    ) -> "WindowedGLR":
        """A detector without its noise-independent arrays, for :meth:`_record` with the blocks of
        :meth:`_shared_blocks` (a record of many realisations with their own profiles)."""
        det = object.__new__(cls)
        det._setup(model, gains, family, window, min_samples, batch_shape)
        det._reset()
        return det

    def _setup(
        self,
        model: LTVModel,
        gains: KalmanGains,
        family: FaultFamily,
        window: int,
        min_samples: int | None,
        batch_shape: tuple[int, ...],
    ) -> None:
        """Check the arguments of :class:`WindowedGLR`; set them, the onsets held by the slots,
        the admissible ones and ``Sigma_k^{-1/2}``."""
        if not isinstance(model, LTVModel) or not isinstance(family, FaultFamily):
            raise ModelError(
                f"model, family: expected an LTVModel and a FaultFamily, got "
                f"{type(model).__name__} and {type(family).__name__}"
            )
        check_gains(model, gains)
        N, n, p, m = model.n_steps, model.n, model.p, family.m
        Psi, Phi = family.Psi_tilde, family.Phi_tilde
        if (
            Psi.ndim < 3
            or Psi.shape[-3:-1] != (N, n)
            or Phi.shape[-3:-1] != (N, p)
            or Phi.shape[:-3] != Psi.shape[:-3]
            or Phi.shape[-1] != m
        ):
            raise ShapeError(
                f"family: expected Psi~ (*batch, {N}, {n}, m) and Phi~ (*batch, {N}, {p}, m), "
                f"got {Psi.shape} and {Phi.shape}"
            )
        _check_family_batch(family, tuple(batch_shape))
        window = integer(window, "window", low=1, high=N)
        s = -(-m // p) if min_samples is None else min_samples
        s = integer(s, "min_samples", low=0, high=window - 1)
        if family.kind == "impulse" and np.any(family.Phi_tilde):
            raise ModelError("family: impulsive profiles act on the state only (Phi~ must be zero)")
        self.model, self.gains, self.family = model, gains, family
        self._skipped = gains_missing(gains)  # samples the filter skipped: no information, no score
        self.window, self.min_samples = int(window), int(s)
        self.batch_shape = tuple(batch_shape)
        self._B = int(np.prod(self.batch_shape, dtype=int))
        # Per-realisation profiles: the arrays of _shared carry a realisation axis after the slot,
        # (N, w, B, ...) instead of (N, w, ...); _project and _pick hide the difference.
        self._per_realisation = bool(family.batch_shape)
        self._admissible: list[np.ndarray] | None = None  # per sample, the admissible slots
        k_all = np.arange(N)
        # onset held by slot j at time k: the r = j mod w in (k - w, k] (-1 before the record)
        onset = k_all[:, None] - (k_all[:, None] - np.arange(window)[None, :]) % window  # (N, w)
        onset[onset < 0] = -1
        self._onsets = onset
        self._allowed = (onset >= 0) & (onset <= k_all[:, None] - self.min_samples)  # (N, w)
        self._Linv = np.linalg.inv(gains.Sigma_chol)  # Sigma_k^{-1/2}, (N, p, p)

    def _reset(self) -> None:
        """Start at ``k = 0``: zero scores and missing-sample information."""
        w, m = self.window, self.family.m
        # Scores d_k(r) stored as (w, m, B), slot = r mod w, realisations last: every per-onset
        # product below is then a BLAS matrix product with B columns.
        self._d = np.zeros((w, m, self._B))
        # Information of the missing samples still in the window, per slot (subtracted from C_k(r)).
        self._C_missing = np.zeros((w, self._B, m, m) if self._per_realisation else (w, m, m))
        self._dropped = -w  # the last dropped sample (none: C_missing is zero while k - w < it)
        self._cols = np.arange(self._B)
        self.k = 0

    def _shared(self) -> None:
        """Everything noise-independent, for all ``k`` at once (stacks indexed by slot ``r mod w``):
        :meth:`_shared_blocks` as one block of all the samples, kept."""
        for _, self._sig_wT, self._Cs, self._root in self._shared_blocks(self.model.n_steps):
            pass

    def _shared_blocks(self, size: int, first: int = 0):
        """The noise-independent arrays by blocks of ``size`` samples from sample ``first`` on:
        yields ``(ks, sig_wT, C, root)``, ``ks`` the block's slice of samples (the first block's
        arrays before the second is computed: the memory of one block, whatever ``N``). The
        entries of the onsets ``r >= first`` are those of ``first = 0``, bit for bit (each onset's
        recursions start from zero at ``r``); the onsets before ``first`` hold partial sums, which
        :meth:`_record` never reads when ``first <= start - w + 1`` (their slots are reset first).

        ``Gamma_k(r)`` by the recursion (31) (one vectorised step per sample over the window's
        onsets), then in single array operations over the block's ``(k, r)``: the whitened
        signatures ``Sigma_k^{-1/2} (H_k Gamma_k(r) + Phi~_k)`` (``sig_wT``: ``(K, w, m, p)``, or
        ``(K, p, w, B, m)`` for per-realisation profiles, as computed), the informations
        ``C_k(r)`` (sums (32), recursively (27)), and the factors of their pseudo-inverses
        ``C^+ = R R^T`` (``root``). Every entry is the same operation whatever the blocks
        (products per sample, elementwise operations, one decomposition per matrix), except the
        Jacobi sweeps of ``3 <= m <= 4``, whose number the whole stack sets (:func:`_small_eigh`).
        """
        model, g, fam, w = self.model, self.gains, self.family, self.window
        N, n, p, m = model.n_steps, model.n, model.p, fam.m
        F = self._B if self._per_realisation else 1  # profiles: one per realisation, or shared
        Psi = fam.Psi_tilde.reshape(F, N, n, m)
        Phi = fam.Phi_tilde.reshape(F, N, p, m)
        has_phi = _has_output_faults(fam)
        drive = Psi - g.FK @ Phi if has_phi else Psi  # Psi~_k - F_k K_k Phi~_k, (F, N, n, m)
        drive_c = np.ascontiguousarray(np.transpose(drive, (2, 1, 0, 3)))  # (n, N, F, m)
        started = self._onsets >= 0
        full = started.all(axis=1)  # every slot holds an onset: no mask needed
        Phi_k = np.moveaxis(Phi, 0, 2)[:, :, None, :, :]  # (N, p, 1, F, m)
        head = min(N, w - 1)  # before, some slots hold no onset yet; after, all do
        last = np.zeros((n, w * F * m))  # Gamma_{k0 - 1} of the block starting at k0
        acc = np.zeros((w, F, m, m))  # C_{k0 - 1}(r)
        for k0 in range(first, N, size):
            K = min(size, N - k0)
            # Gamma_k(r) as (n, w F m): slots (and realisations) side by side, so that (31) is one
            # matrix product per sample
            Gamma = np.zeros((K, n, w, F, m))
            flat = Gamma.reshape(K, n, w * F * m)
            for k in range(max(k0, 1), k0 + K):  # Gamma_0 = 0
                i = k - k0
                # Gamma_k(r) = A_{k-1} Gamma_{k-1}(r) + drive_{k-1}(r), eq. (31)
                np.matmul(g.A[k - 1], flat[i - 1] if i else last, out=flat[i])
                if fam.kind == "step":
                    if full[k - 1]:
                        Gamma[i] += drive_c[:, k - 1, None, :, :]
                    else:
                        Gamma[i] += started[k - 1][None, :, None, None] * drive_c[:, k - 1, None]
                # impulse: Psi_{k-1}(r) != 0 only for r = k
                Gamma[i][:, k % w] = drive_c[:, k - 1] if fam.kind == "impulse" else 0.0  # r = k
            last = flat[-1].copy()
            sig = (model.H[k0 : k0 + K] @ flat).reshape(K, p, w, F, m)
            del Gamma, flat
            if fam.kind == "step" and has_phi:  # + Phi~_k for the started onsets (in place)
                h = min(K, max(0, head - k0))
                ph = Phi_k[k0 : k0 + K]
                sig[:h] = sig[:h] + started[k0 : k0 + h, None, :, None, None] * ph[:h]
                sig[h:] += ph[h:]  # times True is the same bits
            sig_w = (self._Linv[k0 : k0 + K] @ sig.reshape(K, p, w * F * m)).reshape(sig.shape)
            del sig
            if self._skipped[k0 : k0 + K].any():  # a skipped sample adds nothing to C_k(r), d_k(r)
                sig_w[self._skipped[k0 : k0 + K]] = 0.0
            inc = np.einsum("kpwfi,kpwfj->kwfij", sig_w, sig_w)  # (K, w, F, m, m)
            if self._per_realisation:  # as computed, (K, p, w, B, m): _score_terms reads slabs
                sig_wT = sig_w
            else:  # (K, w, m, p): one (w m, p) matrix per sample
                sig_wT = np.ascontiguousarray(np.transpose(sig_w[:, :, :, 0], (0, 2, 3, 1)))
            del sig_w
            C = np.empty_like(inc)
            for k in range(k0, k0 + K):
                acc[k % w] = 0.0
                acc += inc[k - k0]
                C[k - k0] = acc
            del inc
            root = _pinv_root(C)  # C^+ = root root^T
            if not self._per_realisation:  # drop the realisation axis of a shared family
                C, root = C[:, :, 0], root[:, :, 0]
            yield slice(k0, k0 + K), sig_wT, C, root
            del sig_wT, C, root  # the next block's arrays in the memory of these

    def _project(self, root: np.ndarray, d: np.ndarray) -> np.ndarray:
        """``R^T d`` per onset (and realisation): ``root`` ``(..., m, m)`` (or ``(..., B, m, m)`` for
        per-realisation profiles), scores ``d`` ``(..., m, B)``; returns ``(..., m, B)``."""
        if self._per_realisation:
            if root.shape[-1] == 1:  # one product per entry, + 0.0: the bits of the einsum
                q = root[..., 0, 0][..., None, :] * d  # (which sums from 0.0)
                q += 0.0
                return q
            return np.einsum("...bji,...jb->...ib", root, d)
        return np.swapaxes(root, -1, -2) @ d

    @staticmethod
    def _quadratic(q: np.ndarray) -> np.ndarray:
        """``q^T q`` over the parameter axis (-2) of projections ``q`` ``(..., m, B)``: ``(..., B)``
        (for ``m = 1`` the square, the bits of the sum of one square)."""
        if q.shape[-2] == 1:
            return np.square(q[..., 0, :])
        return np.einsum("...mb,...mb->...b", q, q)

    def _pick(self, arr: np.ndarray, index: tuple, cols: np.ndarray) -> np.ndarray:
        """``arr[index]`` of a shared array, ``arr[index + (cols,)]`` of a per-realisation one
        (its realisation axis after the slot): the chosen onset's entry for every realisation."""
        return arr[(*index, cols)] if self._per_realisation else arr[index]

    def _score_terms(self, S: np.ndarray, e_w: np.ndarray) -> np.ndarray:
        """Terms of ``K`` samples in every ``d_k(r)``, ``(K, w, m, B)``, from their whitened
        signatures ``S`` (``sig_wT`` of :meth:`_shared_blocks`: ``(K, w, m, p)``, or
        ``(K, p, w, B, m)`` for per-realisation profiles) and innovations ``e_w`` ``(K, p, B)``
        (eq. (28))."""
        if self._per_realisation:  # the sum over p in order, then + 0.0: the bits of an einsum
            t = S[:, 0] * e_w[:, 0, None, :, None]  # (K, w, B, m)
            for i in range(1, S.shape[1]):
                t += S[:, i] * e_w[:, i, None, :, None]
            t += 0.0  # a sum of -0.0 terms is +0.0, as einsum's (which starts from 0.0)
            return np.swapaxes(t, -1, -2)
        K, w, m, p = S.shape
        if p == 1:  # one product per entry, as the matrix products below compute it (up to the
            # sign of a zero product, which the scores, sums from +0.0, do not keep), at a
            # fraction of their cost: numpy's matrix product of an inner size 1 is slow
            return S * e_w[:, None]
        if m == 1:  # (1, p) @ (p, B) per onset: numpy's gemv, whose bits a gemm does not keep
            return S @ e_w[:, None]
        # one matrix product (w m, p) @ (p, B) per sample, not w: the same gemm per entry
        return (S.reshape(K, w * m, p) @ e_w).reshape(K, w, m, -1)

    def information(self, k: Any, onset: Any) -> np.ndarray:
        """``C_k(r)``, eq. (32), of the onsets ``onset`` at the samples ``k`` (integer arrays of one
        shape; returns that shape plus ``(m, m)``), for a family shared by the realisations.

        It is the ``C_hat`` of :func:`glr_window` (this detector's or a :meth:`fresh` one's) where
        ``r_hat_k = onset`` and no innovation in the window is missing (a missing one's information
        is taken off there): with ``estimates="scores"``, the minmax isolation reads it at the few
        samples it needs instead of every sample's.

        Raises
        ------
        ModelError
            Per-realisation profiles, or an onset not admissible at its sample
            (``k - w < r <= k - s``).
        """
        if self._per_realisation or not hasattr(self, "_Cs"):
            raise ModelError(
                "information: expected a detector of a shared family that keeps its arrays, got "
                + ("per-realisation profiles" if self._per_realisation else "one without them")
            )
        k, onset = np.broadcast_arrays(np.asarray(k), np.asarray(onset))
        if k.dtype.kind not in "iu" or onset.dtype.kind not in "iu":
            raise ModelError(f"k, onset: expected integers, got {k.dtype} and {onset.dtype}")
        w, s, N = self.window, self.min_samples, self.model.n_steps
        bad = (k < 0) | (k >= N) | (onset <= k - w) | (onset > k - s)
        if bad.any():
            i = tuple(int(j) for j in np.argwhere(bad)[0])
            raise ModelError(
                f"onset: expected an onset r with k - {w} < r <= k - {s} (window w = {w}, "
                f"min_samples s = {s}) at a sample 0 <= k < {N}, got r = {onset[i]} at k = {k[i]} "
                f"(index {i})"
            )
        return self._Cs[k, onset % w]

    def fresh(self, batch_shape: tuple[int, ...] = ()) -> "WindowedGLR":
        """A new detector at ``k = 0`` for innovations of leading shape ``batch_shape``.

        It shares this detector's noise-independent arrays (signatures, informations and the
        factors of their pseudo-inverses, which :meth:`update` only reads), so that many batches
        of realisations (Monte Carlo chunks) pay their construction once.
        """
        _check_family_batch(self.family, tuple(batch_shape))
        new = object.__new__(WindowedGLR)
        new.__dict__.update(self.__dict__)
        new.batch_shape = tuple(batch_shape)
        new._B = int(np.prod(new.batch_shape, dtype=int))
        new._reset()
        return new

    def update(
        self, eps_k: np.ndarray, *, statistics: bool = True
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Process innovation ``eps_k`` ``(*batch, p)``.

        A NaN ``eps_k`` (missing sample) must be missing in every realisation of the batch; the
        sample is then skipped (it adds nothing to ``C_k(r)`` and ``d_k(r)``). At a sample the
        gains skip (``gains.missing``) ``eps_k`` must be NaN.

        Returns ``(l_k, r_hat_k, theta_hat_k, C_k(r_hat), d_k(r_hat))`` (``nan``/``-1`` when
        no onset is admissible yet). With ``statistics=False`` only the scores are updated and
        the ``nan``/``-1`` values are returned (a sample at which the test is not run, e.g. while
        it is disabled: the statistics of later samples are unchanged).
        """
        model, k, m = self.model, self.k, self.family.m
        if k >= model.n_steps:
            raise ModelError(f"update: the model horizon N={model.n_steps} is exhausted")
        eps_k = array(eps_k, "eps_k", finite=False)
        if eps_k.shape != (*self.batch_shape, model.p):
            raise ShapeError(
                f"eps_k: expected shape {(*self.batch_shape, model.p)}, got {eps_k.shape}"
            )
        missing = missing_samples(eps_k, "eps_k")
        skip = bool(np.all(missing))
        if np.any(missing) and not skip:
            i = tuple(int(j) for j in np.argwhere(missing)[0])
            raise NonFiniteError(
                f"eps_k: expected a sample missing (NaN) in all realisations or in none, "
                f"got NaN at batch index {i} only (step {k})"
            )
        known = bool(
            self._skipped[k]
        )  # skipped by the filter: nothing in C_k(r), d_k(r) (see _shared)
        if known and not skip:
            raise ModelError(
                f"eps_k: expected NaN at step {k}, a sample the gains skip (missing), got a "
                f"finite value: innovations and gains of different filters"
            )
        out = self._advance(eps_k.reshape(self._B, model.p), skip, statistics)
        shape = self.batch_shape
        if out is None:
            return (
                np.full(shape, np.nan),
                np.full(shape, -1),
                np.full((*shape, m), np.nan),
                np.full((*shape, m, m), np.nan),
                np.full((*shape, m), np.nan),
            )
        l_k, best_onset, th, C_hat, d_hat = out
        return (
            l_k.reshape(shape),
            best_onset.reshape(shape),
            th.reshape(*shape, m),
            C_hat.reshape(*shape, m, m),
            d_hat.reshape(*shape, m),
        )

    def _advance(
        self, eps_k: np.ndarray, skip: bool, statistics: bool, estimates: bool | str = True
    ) -> tuple[np.ndarray, ...] | None:
        """:meth:`update` of checked innovations ``eps_k`` ``(B, p)`` (``skip``: the sample is
        missing in every realisation): the outputs flat over the realisations, ``(B, ...)``, or
        ``None`` when no onset is admissible yet or ``statistics`` is false; those of
        :func:`_outputs` ``(estimates)``, in its order."""
        k, w = self.k, self.window
        # New onset r = k enters the window (replacing r = k - w); scores (33), recursively (28).
        slot = k % w
        self._d[slot] = 0.0
        if self._dropped >= 0:  # zero until a sample is dropped
            self._C_missing[slot] = 0.0
        if skip and not self._skipped[k]:  # a dropped innovation contributes nothing: its score
            # term is zero, its information term (precomputed in C_k(r)) is subtracted for every
            # onset it belongs to
            S = self._sig_wT[k]  # (w, m, p), or (p, w, B, m): as (w, B, m, p), contiguous
            S = np.ascontiguousarray(np.moveaxis(S, 0, -1)) if self._per_realisation else S
            self._C_missing += S @ np.swapaxes(S, -1, -2)
            self._dropped = k
        elif not skip:
            e_w = self._Linv[k] @ eps_k.T  # (p, B)
            self._d += self._score_terms(self._sig_wT[k : k + 1], e_w[None])[0]
        self.k = k + 1
        if self._admissible is None:  # built by the first update (a whole record never needs it)
            self._admissible = [np.nonzero(a)[0] for a in self._allowed]
        slots = self._admissible[k]
        if not slots.size or not statistics:
            return None
        if self._dropped > k - w and np.any(self._C_missing[slots]):  # missing samples in the
            # window: the admissible onsets' informations less theirs, and new factors
            C = self._Cs[k, slots] - self._C_missing[slots]  # (S, m, m), or (S, B, m, m)
            root = _pinv_root(C)
            d, onsets, allowed = self._d[slots], self._onsets[k, slots], None
        else:  # every slot (views, no copies), the inadmissible ones out of the maximisation
            C, root, d = self._Cs[k], self._root[k], self._d  # (w, m, m) or (w, B, m, m); (w, m, B)
            onsets, allowed = self._onsets[k], self._allowed[k]
        q = self._project(root, d)  # (S, m, B)
        stat = self._quadratic(q)  # (35) for every onset, (S, B)
        if allowed is not None:  # (in place: stat is a new array)
            stat[~allowed] = -np.inf
        best = np.argmax(
            stat, axis=0
        )  # (36), (B,): the first of equal ones, as among the admissible
        cols = self._cols
        l_k = stat[best, cols]
        if not estimates:
            return l_k, onsets[best]
        if estimates == "scores":
            return l_k, onsets[best], d[best, :, cols]
        th = (self._pick(root, (best,), cols) @ q[best, :, cols][..., None])[..., 0]  # (34): C^+ d
        return l_k, onsets[best], th, self._pick(C, (best,), cols), d[best, :, cols]

    def _record(
        self, eps: np.ndarray, start: int = 0, blocks=None, estimates: bool | str = True
    ) -> WindowGLRResult:
        """:func:`glr_window`: all the samples of a fresh detector, statistics evaluated by blocks.

        The scores ``d_k(r)`` are accumulated sample by sample as in :meth:`update` (same sums
        in the same order) and kept for a block of samples; the quadratic forms (35), the
        maximisation (36) and the estimates (34) then run on the whole block at once. The
        statistics are wanted from ``start`` on: the samples before ``start - w + 1`` are not read
        (they only enter the scores of onsets never admissible from ``start`` on, whose slots are
        reset before), and the outputs there stay ``nan``/``-1``. ``blocks``: the noise-independent
        arrays by blocks of samples (:meth:`_shared_blocks`, of a detector that does not keep them);
        default the kept ones, in blocks of about 2e6 floats of scores. ``estimates`` as in
        :func:`glr_window`.
        """
        model, w, m, B = self.model, self.window, self.family.m, self._B
        N, p = model.n_steps, model.p
        if self.k != 0:
            raise ModelError("_record: expected a fresh detector")
        if self._skipped.any():  # NaN there; their signature rows are zero (_shared)
            eps = np.where(self._skipped[:, None], 0.0, eps)
        e_w = self._Linv @ np.moveaxis(eps.reshape(B, N, p), 0, 2)  # (N, p, B)
        stat = np.full((N, B), np.nan)
        onset = np.full((N, B), -1)
        keys = _outputs(estimates)
        theta, C_hat, d_hat = (
            np.full((N, B, *shape), np.nan) if key in keys else None
            for key, shape in (("theta_hat", (m,)), ("C_hat", (m, m)), ("d_hat", (m,)))
        )
        first = max(0, start - w + 1)
        if blocks is None:
            size = max(1, min(N, 2_000_000 // (w * m * B * (m if self._per_realisation else 1))))
            blocks = (
                (
                    slice(k0, k0 + size),
                    self._sig_wT[k0 : k0 + size],
                    self._Cs[k0 : k0 + size],
                    self._root[k0 : k0 + size],
                )
                for k0 in range(first, N, size)
            )
        cols = np.arange(B)
        for now, sig_wT, Cs, root in blocks:
            skip = max(0, first - now.start)  # samples of the block before the first one read
            if skip >= sig_wT.shape[0]:
                continue
            k0 = now.start + skip
            sig_wT, Cs, root = sig_wT[skip:], Cs[skip:], root[skip:]
            ks = np.arange(k0, k0 + sig_wT.shape[0])
            now = slice(k0, k0 + ks.size)  # ks as a slice: views, not copies
            D = np.empty((ks.size, w, m, B))
            terms = self._score_terms(sig_wT, e_w[now])
            for i, k in enumerate(ks):
                self._d[k % w] = 0.0
                self._d += terms[i]
                D[i] = self._d
            q = self._project(root, D)  # (K, w, m, B)
            st = self._quadratic(q)  # (35), (K, w, B)
            np.copyto(st, -np.inf, where=~self._allowed[now][:, :, None])
            best = np.argmax(st, axis=1)  # (36), (K, B)
            ok = self._allowed[now].any(axis=1)  # some onset admissible
            kk = np.arange(ks.size)[:, None]
            stat[ks[ok]] = np.take_along_axis(st, best[:, None, :], axis=1)[:, 0][ok]
            onset[ks[ok]] = self._onsets[ks[:, None], best][ok]
            if not estimates:
                del sig_wT, Cs, root, D, terms, q, st  # before the next block is computed
                continue
            at = best[:, None, None, :]
            if theta is not None:
                qb = np.take_along_axis(q, at, axis=1)[:, 0]  # (K, m, B)
                th = np.einsum("kbij,kjb->kbi", self._pick(root, (kk, best), cols), qb)  # (34)
                theta[ks[ok]] = th[ok]
                C_hat[ks[ok]] = self._pick(Cs, (kk, best), cols)[ok]
            d_hat[ks[ok]] = np.swapaxes(np.take_along_axis(D, at, axis=1)[:, 0], 1, 2)[ok]
            del sig_wT, Cs, root, D, terms, q, st  # before the next block is computed
        self.k = N
        shape = self.batch_shape
        return WindowGLRResult(
            statistic=np.moveaxis(stat, 0, -1).reshape(*shape, N),
            onset=np.moveaxis(onset, 0, -1).reshape(*shape, N),
            **{
                key: None
                if arr is None
                else np.moveaxis(arr, 0, 1).reshape(*shape, N, *arr.shape[2:])
                for key, arr in (("theta_hat", theta), ("C_hat", C_hat), ("d_hat", d_hat))
            },
            window=w,
            min_samples=self.min_samples,
        )


def glr_window(
    innovations: np.ndarray,
    model: LTVModel,
    gains: KalmanGains,
    family: FaultFamily,
    window: int,
    min_samples: int | None = None,
    *,
    shared: WindowedGLR | None = None,
    start: int = 0,
    estimates: bool | str = True,
) -> WindowGLRResult:
    """Windowed GLR with unknown onset (35)-(37) over a whole record.

    Explained in the book: :doc:`/book/zb2014/glr`.

    Parameters
    ----------
    innovations : array_like
        ``eps_k``, shape ``(*batch, N, p)``; several realisations share the
        noise-independent computations. A sample with a NaN is missing and skipped
        (realisations with different missing samples are run as separate groups). It must be
        NaN at the samples the gains skip (``gains.missing``): the samples the filter did not
        update at, which the signatures ``Gamma_k(r)`` computed from the gains know.
    model, gains, family, window, min_samples
        As in :class:`WindowedGLR`. A ``family`` of per-realisation profiles
        (``family.batch_shape == batch``, :func:`fdi_lib.models.step_family` with a leading batch
        axis) gives each realisation the test of its own profile, the same as one call per
        realisation with its own family, in one pass over the samples; when the realisations'
        arrays exceed ``_PER_REALISATION_BYTES``, they are computed and read by blocks of samples
        of ``_SAMPLE_BLOCK_BYTES`` (at most the budget; all realisations at once), or, for ``3 <= m <= 4`` (whose Jacobi sweeps the stack
        of matrices sets), with dropped samples or a ``shared`` detector, the realisations are
        taken by blocks within it.
    shared : WindowedGLR, optional
        A detector built with these same ``model``, ``gains`` and ``family`` objects, ``window``
        and ``min_samples``, whose noise-independent quantities are reused
        (:meth:`WindowedGLR.fresh`) instead of computed again: for many batches of the same
        setting, e.g. Monte Carlo chunks. The results are the same.
    start : int
        First sample whose statistics are wanted (``0 <= start <= N``): before it the outputs are
        ``nan``/``-1`` and only the scores are accumulated, which saves the statistics of a
        period where the test is disabled; the outputs from ``start`` on are unchanged.
    estimates : bool or "scores"
        With ``False``, the statistics and onsets alone (``theta_hat``, ``C_hat``, ``d_hat`` of the
        result are ``None``): a detector that only compares ``l_k`` with a threshold skips the
        estimates (34) and the picks of ``C_k(r_hat)``, ``d_k(r_hat)``; the statistics and onsets
        are the same. With ``"scores"``, also ``d_hat`` (``theta_hat`` and ``C_hat`` are
        ``None``): a caller that reads the estimates at a few samples takes the information there
        from :meth:`WindowedGLR.information` instead of a ``(*batch, N, m, m)`` array.

    Returns
    -------
    WindowGLRResult

    Raises
    ------
    ShapeError
        Innovations not ``(*batch, N, p)``, or per-realisation profiles whose batch shape is not
        ``batch``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model, fault_profile, step_family
    >>> from fdi_lib.filters import kalman_gains, kalman_filter
    >>> from fdi_lib.simulate import simulate
    >>> m = ltv_model(F=[[0.5]], H=[[1.0]], Q=0.01, R=0.01, n_steps=300)
    >>> fam = step_family(m, Phi=[[1.0]])
    >>> s = simulate(m, rng=np.random.default_rng(2), fault=fam.profile(200), theta=[1.0])
    >>> r = glr_window(kalman_filter(m, s.y).innovations, m, kalman_gains(m), fam, window=50)
    >>> k = int(first_alarm(r.statistic, 20.0))
    >>> k, int(r.onset[k])                     # first affected innovation eps_{r+1}; onset r = 200
    (201, 200)
    """
    if not isinstance(model, LTVModel):
        raise ModelError(f"model: expected an LTVModel, got {type(model).__name__}")
    eps, missing = _check_innovations(innovations, model.n_steps, model.p)
    nan_rows = missing
    start = integer(start, "start", low=0, high=model.n_steps)
    _outputs(estimates)  # checked before any work
    batch = eps.shape[:-2]
    check_gains(model, gains)
    check_skipped(missing, gains, "innovations")
    if not isinstance(family, FaultFamily):
        raise ModelError(f"family: expected a FaultFamily, got {type(family).__name__}")
    _check_family_batch(family, batch)
    blocks = None  # the detector's arrays by blocks of samples, not kept (many own profiles)
    missing = missing & ~gains_missing(gains)  # dropped innovations the gains do not know
    if missing.any() and batch:
        flat_missing = missing.reshape(-1, model.n_steps)
        patterns, group = np.unique(flat_missing, axis=0, return_inverse=True)
        if len(patterns) > 1:
            return _grouped_glr_window(
                eps,
                group.reshape(-1),
                model,
                gains,
                family,
                window,
                min_samples,
                shared,
                start,
                estimates,
            )
    if (
        family.batch_shape
    ):  # per-realisation arrays: blocks of realisations within the memory budget
        B = int(np.prod(batch, dtype=int))
        window = integer(window, "window", low=1, high=model.n_steps)
        per = 8 * model.n_steps * window * family.m * (model.n + 3 * model.p + 4 * family.m)
        size = max(1, _PER_REALISATION_BYTES // per)
        if B > size and (shared is not None or missing.any() or family.m in (3, 4)):
            return _grouped_glr_window(
                eps,
                np.arange(B) // size,
                model,
                gains,
                family,
                window,
                min_samples,
                shared,
                start,
                estimates,
            )
        if B > size:  # all realisations at once, the arrays by blocks of samples in the budget
            det = WindowedGLR._unkept(model, gains, family, window, min_samples, batch)
            block = min(_PER_REALISATION_BYTES, _SAMPLE_BLOCK_BYTES)
            blocks = det._shared_blocks(
                max(1, block * model.n_steps // (B * per)),
                max(0, start - det.window + 1),  # the first sample _record reads
            )
    if blocks is None and shared is None:
        det = WindowedGLR(model, gains, family, window, min_samples, batch_shape=batch)
    elif blocks is None:
        s = -(-family.m // model.p) if min_samples is None else min_samples
        if (
            not isinstance(shared, WindowedGLR)
            or shared.model is not model
            or shared.gains is not gains
            or shared.family is not family
            or (shared.window, shared.min_samples) != (window, s)
        ):
            raise ModelError(
                "shared: expected a WindowedGLR built with the same model, gains and family "
                f"objects, window {window} and min_samples {s}, got "
                f"{type(shared).__name__} with window {getattr(shared, 'window', None)} "
                f"and min_samples {getattr(shared, 'min_samples', None)}"
            )
        det = shared.fresh(batch)
    if (det._B <= _RECORD_MAX_BATCH or det._per_realisation) and not missing.any():
        res = det._record(eps, start, blocks, estimates)
        if start:  # the same outputs as sample by sample: none before start
            for arr, undefined in (
                (res.statistic, np.nan),
                (res.onset, -1),
                (res.theta_hat, np.nan),
                (res.C_hat, np.nan),
                (res.d_hat, np.nan),
            ):
                if arr is not None:
                    arr[(slice(None),) * len(batch) + (slice(0, start),)] = undefined
        return res
    # many realisations: one update per sample already works on wide arrays (the innovations
    # checked above: the samples missing in one realisation are missing in all)
    N, m, B = model.n_steps, family.m, det._B
    keys = _outputs(estimates)
    out = tuple(_empty_outputs(keys, B, N, m).values())
    undefined = tuple(  # the outputs of a sample without statistics
        np.full((B, *a.shape[2:]), -1 if key == "onset" else np.nan, dtype=a.dtype)
        for key, a in zip(keys, out)
    )
    flat = eps.reshape(B, N, model.p)
    skip = nan_rows.reshape(-1, N).all(axis=0)
    for k0 in range(0, N, _OUTPUT_BLOCK):  # the outputs written by blocks of samples
        ks = range(k0, min(N, k0 + _OUTPUT_BLOCK))
        rows = [
            det._advance(flat[:, k], bool(skip[k]), k >= start, estimates) or undefined for k in ks
        ]
        for i, arr in enumerate(out):
            arr[:, ks.start : ks.stop] = np.stack([r[i] for r in rows], axis=1)
    fields = dict.fromkeys(_outputs(True))  # None: not asked for
    fields.update({key: a.reshape(*batch, *a.shape[1:]) for key, a in zip(keys, out)})
    return WindowGLRResult(**fields, window=det.window, min_samples=det.min_samples)


def _outputs(estimates: bool | str) -> tuple[str, ...]:
    """The fields of :class:`WindowGLRResult` that :func:`glr_window` computes for ``estimates``
    (checked: ``True``, ``False`` or ``"scores"``), in the order :meth:`WindowedGLR._advance`
    returns them."""
    if isinstance(estimates, (bool, np.bool_)):
        return ("statistic", "onset", "theta_hat", "C_hat", "d_hat")[: 5 if estimates else 2]
    if isinstance(estimates, str) and estimates == "scores":
        return ("statistic", "onset", "d_hat")
    raise ModelError(f"estimates: expected True, False or 'scores', got {estimates!r}")


def _empty_outputs(keys: tuple[str, ...], B: int, N: int, m: int) -> dict[str, np.ndarray]:
    """Uninitialised arrays ``(B, N, ...)`` of the fields ``keys`` of :class:`WindowGLRResult`."""
    shapes = {"statistic": (), "onset": (), "theta_hat": (m,), "C_hat": (m, m), "d_hat": (m,)}
    return {k: np.empty((B, N, *shapes[k]), dtype=int if k == "onset" else float) for k in keys}


#: Up to this many realisations, :func:`glr_window` evaluates the statistics by blocks of
#: samples (:meth:`WindowedGLR._record`: few, wide array operations); beyond, sample by sample.
#: Per-realisation profiles always take the blocks (their projections are not shared products).
_RECORD_MAX_BATCH = 4

#: Samples whose outputs :func:`glr_window` stacks and writes at once when it steps sample by sample.
_OUTPUT_BLOCK = 64

#: Budget (bytes) of the arrays :func:`glr_window` holds for realisations with their own profiles
#: (signatures, informations, pseudo-inverse factors: ``N w m (n + 3 p + 4 m)`` floats per
#: realisation): by blocks of samples, or of realisations, within it.
_PER_REALISATION_BYTES = 64 * 2**20

#: Bytes of one block of samples of those arrays when they are taken by blocks of samples: a size
#: that stays in a core's cache for the block's memory-bound operations (a whole budget per block
#: ran them 1.6 times slower: the wind-turbine blades' test, 225 realisations, 3 samples a block
#: against 52). The bits do not depend on it (:meth:`WindowedGLR._shared_blocks`).
_SAMPLE_BLOCK_BYTES = 4 * 2**20


def _has_output_faults(family: FaultFamily) -> bool:
    """Whether ``family`` has a non-zero ``Phi~`` (faults on the outputs). Without,
    :meth:`WindowedGLR._shared_blocks` skips the terms that add zeros to the drive ``Psi~ - F K Phi~``
    and to the signatures: they change no value but the sign of a zero, which is squared or added
    to +0.0 before any output (the same bits; about 9 % of the time of the wind-turbine blades'
    per-realisation arrays, whose profiles act on the states only)."""
    return bool(np.any(family.Phi_tilde))


def _check_family_batch(family: FaultFamily, batch: tuple[int, ...]) -> None:
    """Raise :class:`ShapeError` if ``family`` has per-realisation profiles not of batch shape ``batch``."""
    if family.batch_shape and family.batch_shape != tuple(batch):
        raise ShapeError(
            f"family: expected per-realisation profiles of batch shape {tuple(batch)} (that of "
            f"the innovations) or a shared family, got batch shape {family.batch_shape}"
        )


def _grouped_glr_window(
    eps: np.ndarray,
    group: np.ndarray,
    model: LTVModel,
    gains: KalmanGains,
    family: FaultFamily,
    window: int,
    min_samples: int | None,
    shared: WindowedGLR | None,
    start: int,
    estimates: bool | str,
) -> WindowGLRResult:
    """:func:`glr_window` run once per group of realisations (those sharing the same missing samples,
    or a block of realisations with their own profiles, which take their rows of the family)."""
    batch, N, m = eps.shape[:-2], model.n_steps, family.m
    flat = eps.reshape(-1, N, model.p)
    B = flat.shape[0]
    out = _empty_outputs(_outputs(estimates), B, N, m)
    res = None
    for i in np.unique(group):
        rows = np.nonzero(group == i)[0]
        fam, sh = family, shared
        if (
            family.batch_shape
        ):  # this group's profiles: a new family (a detector's arrays do not fit it)
            Psi, Phi = (
                P.reshape(B, *P.shape[-3:])[rows] for P in (family.Psi_tilde, family.Phi_tilde)
            )
            fam = FaultFamily(kind=family.kind, Psi_tilde=Psi, Phi_tilde=Phi)
            sh = None
        res = glr_window(
            flat[rows],
            model,
            gains,
            fam,
            window,
            min_samples,
            shared=sh,
            start=start,
            estimates=estimates,
        )
        for key, arr in out.items():
            arr[rows] = getattr(res, key)
    fields = dict.fromkeys(("theta_hat", "C_hat", "d_hat"))  # None: not asked for
    fields.update({key: arr.reshape(*batch, *arr.shape[1:]) for key, arr in out.items()})
    return WindowGLRResult(
        **fields,
        window=res.window,
        min_samples=res.min_samples,
    )


def first_alarm(statistic: np.ndarray, threshold: float, start: int = 0) -> np.ndarray:
    """Index of the first ``k >= start`` with ``statistic[..., k] > threshold`` (``-1`` if none).

    Explained in the book: :doc:`/book/zb2014/glr`.

    Parameters
    ----------
    statistic : array_like
        ``(..., N)``. NaN is allowed only as a leading warm-up (a windowed statistic not yet
        defined); a NaN after a finite value, a record that is NaN throughout, or an infinite
        value raises :class:`~fdi_lib.errors.NonFiniteError` with its index: NaN is never read
        as "no alarm".
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
        raise ShapeError("statistic: expected an array (..., N), got a scalar")
    threshold = real(threshold, "threshold")
    start = integer(start, "start", low=0, high=stat.shape[-1])
    nan = np.isnan(stat)
    bad = np.isinf(stat) | (nan & np.logical_or.accumulate(~nan, axis=-1))
    if bad.any():
        i = tuple(int(j) for j in np.argwhere(bad)[0])
        raise NonFiniteError(
            f"statistic: expected finite values after the warm-up, got {stat[i]} at index {i}"
        )
    if stat.shape[-1] and nan[..., -1].any():  # NaN to the end: no value at all, never "no alarm"
        i = tuple(int(j) for j in np.argwhere(nan[..., -1])[0])
        raise NonFiniteError(
            f"statistic: expected finite values after the warm-up, got only NaN in record {i}"
        )
    over = np.nan_to_num(stat, nan=-np.inf) > threshold
    over[..., :start] = False
    hit = over.any(axis=-1)
    return np.where(hit, np.argmax(over, axis=-1), -1)
