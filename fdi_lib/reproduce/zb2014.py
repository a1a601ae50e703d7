"""Zhang & Basseville (2014), Section 6.1: Figures 1-4 on the unstable example.

* ``zb2014-fig1``: spectral norm of ``Gamma_k`` (eq. (12)) for impulses at r = 1, 101, 201, 301;
* ``zb2014-fig2``: spectral norm of the Willsky-Jones ``alpha_k(r)`` (eq. (A.6)), log scale;
* ``zb2014-fig3``, ``zb2014-fig4``: innovation and windowed GLR ``l_k`` (eq. (35)),
  ``theta = [4, 0]`` and ``[1.5, 0]``, onset 201, window ``w = 100``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fdi_lib.filters import KalmanGains, kalman_filter, kalman_gains
from fdi_lib.glr import WindowGLRResult, first_alarm, glr_window
from fdi_lib.models import LTVModel, impulse_family
from fdi_lib.plotting import OURS_COLOR, THRESHOLD_COLOR, figure
from fdi_lib.reproduce.registry import ReproductionResult, register
from fdi_lib.signatures import fault_signature, willsky_jones
from fdi_lib.simulate import simulate
from fdi_lib.systems import zb2014_unstable as ex

__all__ = ["ONSETS", "UnstableRun", "unstable_run", "plot_detection", "plot_fig1", "plot_fig2"]

PAPER = "Zhang & Basseville 2014"
#: Impulse onsets of Figures 1 and 2.
ONSETS = (1, 101, 201, 301)


def _spectral_norms(mats: np.ndarray) -> np.ndarray:
    return np.linalg.norm(mats, ord=2, axis=(-2, -1))


def _setup(n_steps: int = ex.N_STEPS) -> tuple[LTVModel, KalmanGains]:
    model = ex.unstable_model(n_steps)
    return model, kalman_gains(model)


# ----------------------------------------------------------------------------- Figure 1
def plot_fig1(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 1: ``||Gamma_k||_2`` against ``k`` for each onset."""
    fig, ax = figure(fig=fig)
    ax = ax[0, 0]
    for r, norms in result.data["gamma_norm"].items():
        ax.plot(np.arange(norms.size), norms, label=f"r = {r}")
    ax.axhline(1.0, color="k", lw=0.8, ls=":", label="paper's bound 1")
    ax.set(xlabel="k", ylabel=r"$\|\Gamma_k\|_2$", title="Fault-signature filter (12), impulsive fault")
    ax.legend(ncols=5, loc="upper right")
    return fig


@register("zb2014-fig1", paper=PAPER, title="Spectral norm of Gamma_k, impulses at r = 1, 101, 201, 301",
          plot=plot_fig1)
def fig1(*, seed: int, trials: int | None, jobs: int) -> ReproductionResult:
    """Paper Fig. 1: boundedness of the fault-signature filter (12) on the unstable example.

    ``Psi_k = delta_{r,k+1} I`` for ``r`` in (1, 101, 201, 301); deterministic (no seed used).

    Headline keys
    -------------
    gamma_norm_max : dict
        Per onset ``r`` (string key), ``max_k ||Gamma_k||_2``. The paper states the norm
        "remains under 1".
    gamma_norm_final : dict
        Per onset, ``||Gamma_N||_2`` at the end of the record (decay to zero).
    signature_norm_max : dict
        Per onset, ``max_k ||H_k Gamma_k||_2``: the signature actually seen on the innovation.
    """
    model, gains = _setup()
    fam = impulse_family(model)
    norms, sig_norms = {}, {}
    for r in ONSETS:
        sig = fault_signature(model, gains, fam.profile(r))
        norms[str(r)] = _spectral_norms(sig.Gamma)
        sig_norms[str(r)] = _spectral_norms(sig.on_innovation)
    headline = {
        "gamma_norm_max": {r: float(v.max()) for r, v in norms.items()},
        "gamma_norm_final": {r: float(v[-1]) for r, v in norms.items()},
        "signature_norm_max": {r: float(v.max()) for r, v in sig_norms.items()},
    }
    paper = {"gamma_norm_max": {str(r): "< 1" for r in ONSETS}}
    return ReproductionResult(id="zb2014-fig1", headline=headline, paper=paper,
                              settings={"onsets": list(ONSETS), "n_steps": model.n_steps},
                              data={"gamma_norm": norms, "signature_norm": sig_norms})


# ----------------------------------------------------------------------------- Figure 2
def plot_fig2(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 2: ``||alpha_k(r)||_2`` on a log scale."""
    fig, ax = figure(fig=fig)
    ax = ax[0, 0]
    for r, norms in result.data["alpha_norm"].items():
        k = np.arange(norms.size)
        mask = norms > 0
        ax.semilogy(k[mask], norms[mask], label=f"r = {r}")
    ax.set(xlabel="k", ylabel=r"$\|\alpha_k(r)\|_2$", title="Willsky-Jones recursion (A.6)")
    ax.legend(ncols=4, loc="upper left")
    return fig


@register("zb2014-fig2", paper=PAPER, title="Spectral norm of Willsky-Jones alpha_k(r) (log scale)",
          plot=plot_fig2)
def fig2(*, seed: int, trials: int | None, jobs: int) -> ReproductionResult:
    """Paper Fig. 2: the Willsky-Jones ``alpha_k(r)`` of eq. (A.6) diverges on the unstable example.

    Deterministic (no seed used).

    Headline keys
    -------------
    alpha_log10_norm_final : dict
        Per onset ``r`` (string key), ``log10 ||alpha_N(r)||_2`` at the end of the record.
    alpha_log10_slope : dict
        Per onset, least-squares slope of ``log10 ||alpha_k(r)||_2`` against ``k`` over the
        last 100 samples; ``log10(1.2) = 0.0792`` is the growth rate of the unstable mode.
    rho_minus_HGamma_max : dict
        Per onset, ``max_k |rho_k(r) - H_k Gamma_k(r)|``: the Willsky-Jones innovation signature
        (A.8) equals ours in exact arithmetic; in floating point it is computed as a difference
        of two diverging terms.
    """
    model, gains = _setup()
    fam = impulse_family(model)
    alpha_norm, log_final, slope, rho_err = {}, {}, {}, {}
    for r in ONSETS:
        wj = willsky_jones(model, gains, r)
        norms = _spectral_norms(wj.alpha)
        alpha_norm[str(r)] = norms
        log_final[str(r)] = float(np.log10(norms[-1]))
        k = np.arange(norms.size - 100, norms.size)
        slope[str(r)] = float(np.polyfit(k, np.log10(norms[k]), 1)[0])
        sig = fault_signature(model, gains, fam.profile(r))
        rho_err[str(r)] = float(np.abs(wj.rho - sig.on_innovation).max())
    headline = {"alpha_log10_norm_final": log_final, "alpha_log10_slope": slope,
                "rho_minus_HGamma_max": rho_err}
    paper = {"alpha_log10_norm_final": {str(r): "grows linearly in k (exponential divergence)"
                                        for r in ONSETS}}
    return ReproductionResult(id="zb2014-fig2", headline=headline, paper=paper,
                              settings={"onsets": list(ONSETS), "n_steps": model.n_steps},
                              data={"alpha_norm": alpha_norm})


# ----------------------------------------------------------------------------- Figures 3-4
@dataclass(frozen=True)
class UnstableRun:
    """One closed-loop run of the unstable example with an impulsive fault and the windowed GLR.

    Attributes
    ----------
    innovations : numpy.ndarray
        ``eps_k``, shape ``(N,)``.
    glr : WindowGLRResult
        The windowed GLR (35)-(37) with the impulsive family.
    theta, onset, window, threshold, seed
        The settings.
    alarm : int
        First ``k`` with ``l_k > threshold`` (``-1`` if none).
    """

    innovations: np.ndarray
    glr: WindowGLRResult
    theta: tuple[float, float]
    onset: int
    window: int
    threshold: float | None
    seed: int
    alarm: int


def unstable_run(theta: tuple[float, float] = (4.0, 0.0), onset: int = 201, window: int = 100,
                 threshold: float | None = None, seed: int = 0, n_steps: int = ex.N_STEPS) -> UnstableRun:
    """Simulate Section 6.1 with ``delta_{r,k+1} theta``, run the Kalman filter and the windowed GLR.

    Parameters
    ----------
    theta : pair of float
        Fault vector (jump of the state at time ``onset``).
    onset : int
        ``r``; the state jumps at ``X_r``.
    window : int
        GLR search window ``w`` (eq. (37)); ``s = 2`` samples are needed for ``C_k(r)`` to be
        invertible with one sensor and ``m = 2``.
    threshold : float, optional
        Alarm threshold on ``l_k``; the paper states none for this example, so the
        reproductions use none (``alarm = -1``).
    seed : int
        Seed of the noise (``numpy.random.default_rng(seed)``).
    """
    model, gains = _setup(n_steps)
    fam = impulse_family(model)
    sim = simulate(model, rng=np.random.default_rng(seed), controller=ex.controller(),
                   fault=fam.profile(onset), theta=np.asarray(theta, dtype=float))
    eps = kalman_filter(model, sim.y, sim.u, gains=gains).innovations[:, 0]
    res = glr_window(eps[:, None], model, gains, fam, window=window)
    alarm = -1 if threshold is None else int(first_alarm(res.statistic, threshold))
    return UnstableRun(innovations=eps, glr=res, theta=(float(theta[0]), float(theta[1])), onset=onset,
                       window=window, threshold=threshold, seed=seed, alarm=alarm)


def plot_detection(run: UnstableRun, fig: Any = None, title: str | None = None):
    """Innovation (top) and GLR statistic ``l_k`` (bottom), as in paper Figs. 3-4."""
    fig, axes = figure(2, 1, fig=fig, sharex=True, figsize=(7.0, 4.6))
    k = np.arange(run.innovations.size)
    top, bottom = axes[0, 0], axes[1, 0]
    top.plot(k, run.innovations, color=OURS_COLOR, lw=0.8)
    top.axvline(run.onset, color="k", ls=":", lw=0.8)
    top.set(ylabel=r"$\varepsilon_k$",
            title=title or f"theta = {list(run.theta)}, onset {run.onset}, w = {run.window}")
    bottom.plot(k, run.glr.statistic, color=OURS_COLOR)
    if run.threshold is not None:
        bottom.axhline(run.threshold, color=THRESHOLD_COLOR, ls="--", lw=0.8,
                       label=f"threshold {run.threshold:g}")
    bottom.axvline(run.onset, color="k", ls=":", lw=0.8, label=f"onset {run.onset}")
    if run.alarm >= 0:
        bottom.plot([run.alarm], [run.glr.statistic[run.alarm]], "o", color=THRESHOLD_COLOR,
                    label=f"alarm at k = {run.alarm}")
    bottom.set(xlabel="k", ylabel=r"$l_k$")
    bottom.legend(loc="upper left")
    return fig


def _detection_result(rid: str, theta: tuple[float, float], seed: int) -> ReproductionResult:
    run = unstable_run(theta=theta, seed=seed)
    stat = run.glr.statistic
    before = np.nanmax(stat[: run.onset])
    after = np.nanmax(stat[run.onset:])
    k_max = int(np.nanargmax(stat))
    headline = {
        "glr_max_before_fault": float(before),
        "glr_max_after_fault": float(after),
        "glr_argmax_time": k_max,
        "onset_estimate": int(run.glr.onset[k_max]),
        "theta_estimate": run.glr.theta_hat[k_max].tolist(),
        "innovation_max_abs_before_fault": float(np.abs(run.innovations[: run.onset]).max()),
        "innovation_max_abs_after_fault": float(np.abs(run.innovations[run.onset:]).max()),
    }
    paper = {"onset_estimate": run.onset, "glr_argmax_time": "within the window after 201",
             "theta_estimate": list(theta)}
    return ReproductionResult(id=rid, headline=headline, paper=paper,
                              settings={"theta": list(theta), "onset": run.onset, "window": run.window,
                                        "seed": seed},
                              data={"run": run})


def plot_fig3(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 3."""
    return plot_detection(result.data["run"], fig=fig)


@register("zb2014-fig3", paper=PAPER, title="Innovation and GLR l_k, theta = [4, 0], onset 201, w = 100",
          plot=plot_fig3)
def fig3(*, seed: int, trials: int | None, jobs: int) -> ReproductionResult:
    """Paper Fig. 3: impulsive fault ``theta = [4, 0]`` at ``k = 201``, windowed GLR with ``w = 100``.

    One closed-loop run (seeded). Headline keys
    -------------------------------------------
    glr_max_before_fault : float
        ``max l_k`` for ``k < 201`` (no fault yet).
    glr_max_after_fault : float
        ``max l_k`` for ``k >= 201``.
    glr_argmax_time : int
        ``k`` of the largest ``l_k``.
    onset_estimate : int
        ``r_hat_k`` (eq. (36)) at that ``k``.
    theta_estimate : list of float
        ``theta_hat_k(r_hat_k)`` (eq. (34)) at that ``k``.
    innovation_max_abs_before_fault, innovation_max_abs_after_fault : float
        ``max |eps_k|`` before and after the fault: how visible the fault is on the raw innovation.
    """
    return _detection_result("zb2014-fig3", (4.0, 0.0), seed)


def plot_fig4(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 4."""
    return plot_detection(result.data["run"], fig=fig)


@register("zb2014-fig4", paper=PAPER, title="Innovation and GLR l_k, theta = [1.5, 0], onset 201, w = 100",
          plot=plot_fig4)
def fig4(*, seed: int, trials: int | None, jobs: int) -> ReproductionResult:
    """Paper Fig. 4: the smaller impulsive fault ``theta = [1.5, 0]``; same keys as ``zb2014-fig3``."""
    return _detection_result("zb2014-fig4", (1.5, 0.0), seed)
