"""Calibration of the GLR and minmax statistics under no fault (shown, not assumed).

* Known-profile GLR (Zhang & Basseville 2014, eq. (30)): under ``theta = 0``, ``l_k`` is
  chi-square with ``m = dim(theta)`` degrees of freedom (when ``C_k`` is invertible).
* Minmax test (41): under ``theta_a = 0``, whatever the nuisance ``theta_b``, ``l_a`` is
  chi-square with ``dim(theta_a)`` degrees of freedom.

Both are checked by Monte Carlo with :func:`fdi_lib.montecarlo.run_monte_carlo`: many seeded
runs, a Kolmogorov-Smirnov test against the chi-square law, and the empirical rejection rate
at level ``alpha`` with its exact binomial confidence interval.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Sequence

import numpy as np
import scipy.stats

from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.filters import KalmanGains, kalman_filter, kalman_gains
from fdi_lib.glr import glr_known_profile
from fdi_lib.isolation import minmax_statistic
from fdi_lib.models import FaultProfile, LTVModel
from fdi_lib.montecarlo import binomial_ci, draw_noise_batch, run_monte_carlo
from fdi_lib.signatures import fault_signature
from fdi_lib.simulate import simulate

__all__ = ["Calibration", "glr_null_calibration", "minmax_null_calibration"]


@dataclass(frozen=True)
class Calibration:
    """Empirical law of a test statistic against its nominal chi-square law.

    Attributes
    ----------
    statistics : numpy.ndarray
        One value per run, shape ``(n_runs,)``.
    dof : int
        Degrees of freedom of the nominal chi-square law.
    ks_pvalue : float
        Kolmogorov-Smirnov p-value of ``statistics`` against chi-square(``dof``).
    alpha : float
        Nominal level; threshold ``chi2.ppf(1 - alpha, dof)``.
    rejection_rate : float
        Fraction of runs above the threshold (the empirical type I error).
    rejection_ci : tuple of float
        Exact 95 % binomial interval of ``rejection_rate``.
    """

    statistics: np.ndarray
    dof: int
    ks_pvalue: float
    alpha: float
    rejection_rate: float
    rejection_ci: tuple[float, float]


def _summarise(stat: np.ndarray, dof: int, alpha: float) -> Calibration:
    threshold = scipy.stats.chi2.ppf(1.0 - alpha, dof)
    rejections = int(np.sum(stat > threshold))
    return Calibration(
        statistics=stat,
        dof=dof,
        ks_pvalue=float(scipy.stats.kstest(stat, scipy.stats.chi2(dof).cdf).pvalue),
        alpha=alpha,
        rejection_rate=rejections / stat.size,
        rejection_ci=binomial_ci(rejections, stat.size),
    )


def _information_chunk(
    seeds,
    model: LTVModel,
    fault: FaultProfile,
    theta: np.ndarray,
    u: np.ndarray,
    gains: KalmanGains,
    signature: np.ndarray,
):
    """Simulate a chunk, filter it, return the final information ``C_N`` and scores ``d_N``."""
    sim = simulate(model, noise=draw_noise_batch(model, seeds), u=u, fault=fault, theta=theta)
    eps = kalman_filter(model, sim.y, u, gains=gains).innovations
    res = glr_known_profile(eps, gains, signature)
    return {
        "statistic": res.statistic[:, -1],
        "d": res.d[:, -1],
        "C": np.broadcast_to(res.C[-1], (len(seeds), *res.C[-1].shape)),
    }


def _run(
    model: LTVModel,
    fault: FaultProfile,
    theta: np.ndarray,
    u: np.ndarray | None,
    n_runs: int,
    seed: int,
    jobs: int,
) -> dict[str, np.ndarray]:
    # Noise-independent parts computed once and shared by every chunk.
    gains = kalman_gains(model)
    sig = fault_signature(model, gains, fault).on_innovation
    u_arr = np.zeros((model.n_steps, model.l)) if u is None else np.asarray(u, dtype=float)
    fn = functools.partial(
        _information_chunk,
        model=model,
        fault=fault,
        theta=theta,
        u=u_arr,
        gains=gains,
        signature=sig,
    )
    return run_monte_carlo(fn, n_runs, seed=seed, jobs=jobs)


def _check(model: LTVModel, fault: FaultProfile, n_runs: int, alpha: float) -> None:
    if fault.Psi.shape[:2] != (model.n_steps, model.n):
        raise ShapeError(
            f"fault: expected Psi of shape ({model.n_steps}, {model.n}, m), got {fault.Psi.shape}"
        )
    if not isinstance(n_runs, (int, np.integer)) or n_runs < 2:
        raise ModelError(f"n_runs: expected an integer >= 2, got {n_runs!r}")
    if not 0.0 < alpha < 1.0:
        raise ModelError(f"alpha: expected a probability in (0, 1), got {alpha!r}")


def glr_null_calibration(
    model: LTVModel,
    fault: FaultProfile,
    *,
    n_runs: int,
    seed: int,
    alpha: float = 0.05,
    jobs: int = 1,
    u: np.ndarray | None = None,
) -> Calibration:
    """Law of the known-profile GLR ``l_N`` (eq. (30), last sample) over ``n_runs`` fault-free runs.

    Explained in the book: :doc:`/book/zb2014/glr`.

    Parameters
    ----------
    model : LTVModel
    fault : FaultProfile
        The (known) profile the test looks for; the data are simulated with ``theta = 0``.
    n_runs : int
        Number of Monte Carlo runs.
    seed : int
        Root seed (per-run streams, identical for any ``jobs``).
    alpha : float
        Nominal level of the reported rejection rate.
    jobs : int
        Parallel workers of :func:`fdi_lib.montecarlo.run_monte_carlo` (same results for any value).
    u : array_like, optional
        Known input ``(N, l)``; default zeros.

    Examples
    --------
    >>> from fdi_lib.models import fault_profile, ltv_model
    >>> m = ltv_model(F=[[0.9]], H=[[1.0]], Q=0.01, R=0.01, n_steps=50)
    >>> c = glr_null_calibration(m, fault_profile(m, Psi=[[1.0]]), n_runs=200, seed=1)
    >>> c.dof, c.rejection_rate, bool(c.ks_pvalue > 0.01)
    (1, 0.04, True)
    """
    _check(model, fault, n_runs, alpha)
    out = _run(model, fault, np.zeros(fault.m), u, n_runs, seed, jobs)
    return _summarise(out["statistic"], fault.m, alpha)


def minmax_null_calibration(
    model: LTVModel,
    fault: FaultProfile,
    a: Sequence[int],
    theta: Sequence[float],
    *,
    n_runs: int,
    seed: int,
    alpha: float = 0.05,
    jobs: int = 1,
    u: np.ndarray | None = None,
) -> Calibration:
    """Law of the minmax statistic ``l_a`` (41) when ``theta_a = 0`` and the nuisance ``theta_b`` is not.

    The Fisher information and normalised residual are accumulated over the whole record
    (known profile): they are ``C_N`` and ``d_N`` of the GLR recursion (27)-(28).

    Explained in the book: :doc:`/book/zb2014/glr`.

    Parameters
    ----------
    model, fault, n_runs, seed, alpha, jobs, u
        As in :func:`glr_null_calibration` (the data are simulated with ``theta``).
    a : sequence of int
        Indices of ``theta_a``; ``theta[a]`` must be zero.
    theta : sequence of float
        The true fault vector (non-zero nuisance components allowed).

    Examples
    --------
    >>> from fdi_lib.models import fault_profile, ltv_model
    >>> import numpy as np
    >>> m = ltv_model(F=np.diag([0.9, 0.5]), H=np.eye(2), Q=0.01 * np.eye(2), R=0.01 * np.eye(2),
    ...               n_steps=50)
    >>> c = minmax_null_calibration(m, fault_profile(m, Psi=np.eye(2)), [0], [0.0, 0.5],
    ...                             n_runs=200, seed=1)
    >>> c.dof, bool(c.ks_pvalue > 0.01)                   # chi-square with 1 degree of freedom
    (1, True)
    """
    _check(model, fault, n_runs, alpha)
    th = np.asarray(theta, dtype=float)
    if th.shape != (fault.m,):
        raise ShapeError(f"theta: expected shape ({fault.m},), got {th.shape}")
    if np.any(th[list(a)] != 0):
        raise ModelError(
            f"theta: the tested components a={list(a)} must be zero under the null, got {th[list(a)]}"
        )
    out = _run(model, fault, th, u, n_runs, seed, jobs)
    stat = minmax_statistic(out["C"], out["d"], a)
    return _summarise(stat, len(a), alpha)
