r"""Fault isolation by the minmax (nuisance-rejection) test.

Zhang & Basseville (2014), Section 4.3, eqs. (38)-(43). After an alarm at
:math:`k^*` with estimated onset :math:`\hat r`, the stacked innovations
:math:`Z \sim \mathcal N(M\theta, R)`; with the Fisher information
:math:`\mathbf F = M^\T R^{-1} M` and the normalised residual :math:`\zeta = M^\T R^{-1} Z`
partitioned along :math:`\theta = (\theta_a, \theta_b)`:

.. math::

    \begin{aligned}
    \zeta_a^* &= \zeta_a - \mathbf F_{ab} \mathbf F_{bb}^{-1} \zeta_b, &
    \mathbf F_a^* &= \mathbf F_{aa} - \mathbf F_{ab} \mathbf F_{bb}^{-1} \mathbf F_{ba}, \\
    l_a &= \zeta_a^{*\T} \mathbf F_a^{*-1} \zeta_a^* . && \qquad (41)
    \end{aligned}

Under :math:`\theta_a = 0`, whatever :math:`\theta_b`, :math:`l_a` is chi-square with
:math:`\dim\theta_a` degrees of freedom. Because :math:`R` is block diagonal, :math:`\mathbf F`
and :math:`\zeta` are sums over samples: they are exactly :math:`C_k(\hat r)` and
:math:`d_k(\hat r)` of the GLR test.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import scipy.stats

from fdi_lib.errors import ModelError, PersistentExcitationError, ShapeError
from fdi_lib.filters import KalmanGains
from fdi_lib.validation import (
    array,
    check_skipped,
    covariance,
    integer,
    missing_samples,
    probability,
    real,
)

__all__ = ["information", "minmax_statistic", "MinmaxDecision", "minmax_isolation"]


def information(
    innovations: np.ndarray, signature: np.ndarray, gains: KalmanGains, start: int, stop: int
) -> tuple[np.ndarray, np.ndarray]:
    """Fisher information ``F`` and normalised residual ``zeta`` of eq. (39) over samples ``start .. stop-1``.

    Explained in the book: :doc:`/book/zb2014/glr`.

    Parameters
    ----------
    innovations : array_like
        ``(*batch, N, p)``; a sample with a NaN is missing and skipped (:mod:`fdi_lib.validation`);
        NaN at the samples the gains skip (``gains.missing``).
    signature : array_like
        ``H_k Gamma_k(r_hat) + Phi_k``, shape ``(N, p, m)``.
    gains : KalmanGains
        Provides ``Sigma_k`` (the blocks of ``R`` in (39)).
    start, stop : int
        Sample range (the paper: ``r_hat + 1 .. k*``), ``0 <= start < stop <= N``.

    Returns
    -------
    tuple of numpy.ndarray
        ``F`` ``(m, m)`` (``(*batch, m, m)`` when samples are missing) and ``zeta`` ``(*batch, m)``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model, fault_profile
    >>> from fdi_lib.filters import kalman_gains
    >>> from fdi_lib.signatures import fault_signature
    >>> m = ltv_model(F=[[0.5]], H=[[1.0]], Q=0.01, R=0.01, n_steps=100)
    >>> g = kalman_gains(m)
    >>> Gamma = fault_signature(m, g, fault_profile(m, Phi=[[1.0]])).on_innovation
    >>> F, zeta = information(np.zeros((100, 1)), Gamma, g, start=50, stop=100)
    >>> F.shape, float(zeta[0])                           # no innovation, no evidence
    ((1, 1), 0.0)
    """
    if (
        np.ndim(getattr(gains, "Sigma_chol", None)) != 3
        or np.ndim(getattr(gains, "Sigma", None)) != 3
    ):
        raise ModelError(
            f"gains: expected KalmanGains (Sigma, Sigma_chol of shape (N, p, p)), "
            f"got {type(gains).__name__}"
        )
    eps = array(innovations, "innovations", finite=False)
    S = array(signature, "signature")
    N, p = gains.Sigma.shape[:2]
    if S.ndim != 3 or S.shape[:2] != (N, p) or eps.ndim < 2 or eps.shape[-2:] != (N, p):
        raise ShapeError(
            f"signature/innovations: expected ({N}, {p}, m) and (..., {N}, {p}), "
            f"got {S.shape} and {eps.shape}"
        )
    start = integer(start, "start", low=0, high=N - 1)
    stop = integer(stop, "stop")
    if not start < stop <= N:
        raise ModelError(
            f"stop: expected an integer in (start, N] = ({start}, {N}] (start = {start}, the "
            f"first sample; stop excluded), got {stop}"
        )
    check_skipped(missing_samples(eps, "innovations"), gains, "innovations")
    S, eps = S[start:stop], eps[..., start:stop, :]
    missing = missing_samples(eps, "innovations")
    if (
        missing.any()
    ):  # a missing sample contributes nothing: zero its innovation and signature rows
        eps = np.where(missing[..., None], 0.0, eps)
        S = np.where(missing[..., None, None], 0.0, S)
    L = gains.Sigma_chol[start:stop]
    Sw = np.linalg.solve(L, S)
    ew = np.linalg.solve(L, eps[..., None])[..., 0]
    return np.einsum("...kpi,...kpj->...ij", Sw, Sw), np.einsum("...kpi,...kp->...i", Sw, ew)


def _index(a: Sequence[int], m: int) -> tuple[np.ndarray, np.ndarray]:
    try:
        a = [integer(i, "a") for i in a]
    except TypeError:
        raise ModelError(f"a: expected a sequence of component indices, got {a!r}") from None
    a_idx = np.asarray(sorted(set(a)), dtype=int)
    if a_idx.size == 0 or a_idx.min() < 0 or a_idx.max() >= m or a_idx.size != len(a):
        raise ModelError(f"a: expected distinct component indices in [0, {m}), got {list(a)}")
    b_idx = np.setdiff1d(np.arange(m), a_idx)
    return a_idx, b_idx


def minmax_statistic(F: np.ndarray, zeta: np.ndarray, a: Sequence[int]) -> np.ndarray:
    """Minmax statistic ``l_a`` of eq. (41) for the components ``a`` of ``theta``.

    Explained in the book: :doc:`/book/zb2014/glr`.

    Parameters
    ----------
    F : array_like
        Fisher information ``(..., m, m)``, symmetric positive definite.
    zeta : array_like
        Normalised residual ``(..., m)`` (leading axes broadcast against ``F``).
    a : sequence of int
        Indices of ``theta_a``; the others form the nuisance ``theta_b``.

    Returns
    -------
    numpy.ndarray
        ``l_a``, shape of the broadcast leading axes.

    Examples
    --------
    >>> import numpy as np
    >>> F = np.array([[2.0, 1.0], [1.0, 2.0]]); zeta = np.array([1.0, 1.0])
    >>> float(minmax_statistic(F, zeta, [0]))  # zeta_a* = 1 - 1/2, F_a* = 2 - 1/2
    0.16666666666666666
    """
    F = array(F, "F")
    zeta = array(zeta, "zeta")
    if F.ndim < 2 or F.shape[-1] != F.shape[-2] or zeta.ndim < 1 or zeta.shape[-1] != F.shape[-1]:
        raise ShapeError(
            f"F, zeta: expected (..., m, m) and (..., m), got {F.shape} and {zeta.shape}"
        )
    try:
        np.broadcast_shapes(F.shape[:-2], zeta.shape[:-1])
    except ValueError:
        raise ShapeError(
            f"F, zeta: leading axes {F.shape[:-2]} and {zeta.shape[:-1]} do not broadcast"
        ) from None
    covariance(F.reshape(-1, *F.shape[-2:]), "F", definite=False)  # symmetric PSD (an information)
    a_idx, b_idx = _index(a, F.shape[-1])
    Faa = F[..., a_idx[:, None], a_idx]
    Fab = F[..., a_idx[:, None], b_idx]
    Fbb = F[..., b_idx[:, None], b_idx]
    za, zb = zeta[..., a_idx], zeta[..., b_idx]
    if b_idx.size:
        try:
            # F_ab F_bb^{-1} via a solve with the symmetric F_bb.
            T = np.swapaxes(np.linalg.solve(Fbb, np.swapaxes(Fab, -1, -2)), -1, -2)
        except np.linalg.LinAlgError as exc:
            raise PersistentExcitationError("F: the nuisance block F_bb is singular") from exc
        za = za - np.einsum("...ij,...j->...i", T, zb)
        Faa = Faa - T @ np.swapaxes(Fab, -1, -2)
    try:
        sol = np.linalg.solve(Faa, za[..., None])[..., 0]
    except np.linalg.LinAlgError as exc:
        raise PersistentExcitationError("F: the reduced information F_a* is singular") from exc
    return np.einsum("...i,...i->...", za, sol)


@dataclass(frozen=True)
class MinmaxDecision:
    """One minmax test of a parallel bank (43).

    Attributes
    ----------
    a : tuple of int
        Components tested (``theta_a``).
    statistic : numpy.ndarray
        ``l_a`` (batch shape).
    threshold : float
        ``lambda_a``: the ``1 - alpha`` quantile of chi-square(``dof``) unless given.
    dof : int
        ``dim(theta_a)``.
    faulty : numpy.ndarray
        ``l_a > lambda_a``: the test decides ``theta_a != 0``.
    """

    a: tuple[int, ...]
    statistic: np.ndarray
    threshold: float
    dof: int
    faulty: np.ndarray


def minmax_isolation(
    F: np.ndarray,
    zeta: np.ndarray,
    partitions: Sequence[Sequence[int]],
    *,
    alpha: float = 0.01,
    thresholds: Sequence[float] | None = None,
) -> list[MinmaxDecision]:
    """Bank of parallel minmax tests (43), one per partition ``theta = (theta_a, theta_b)``.

    Explained in the book: :doc:`/book/zb2014/glr`.

    Parameters
    ----------
    F, zeta
        As in :func:`minmax_statistic`.
    partitions : sequence of sequences of int
        The ``a`` index sets, e.g. ``[[0], [1]]`` for one test per component.
    alpha : float
        Nominal type I error of each test; threshold ``chi2.ppf(1 - alpha, dim a)``.
    thresholds : sequence of float, optional
        Explicit thresholds instead (one per partition).

    Examples
    --------
    >>> import numpy as np
    >>> F = np.eye(2) * 100.0; zeta = np.array([50.0, 0.0])   # evidence on theta_1 only
    >>> [bool(d.faulty) for d in minmax_isolation(F, zeta, [[0], [1]], alpha=0.01)]
    [True, False]
    """
    if thresholds is not None and len(thresholds) != len(partitions):
        raise ModelError(f"thresholds: expected {len(partitions)} values, got {len(thresholds)}")
    alpha = probability(alpha, "alpha")
    if thresholds is not None:
        thresholds = [real(t, f"thresholds[{i}]") for i, t in enumerate(thresholds)]
    out = []
    for i, a in enumerate(partitions):
        stat = minmax_statistic(F, zeta, a)
        dof = len(a)
        thr = (
            float(scipy.stats.chi2.ppf(1.0 - alpha, dof))
            if thresholds is None
            else float(thresholds[i])
        )
        out.append(
            MinmaxDecision(
                a=tuple(int(j) for j in a),
                statistic=stat,
                threshold=thr,
                dof=dof,
                faulty=stat > thr,
            )
        )
    return out
