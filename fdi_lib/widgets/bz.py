"""Interactive exploration of the chapter on parametric and non-parametric faults.

:func:`explore_bz` runs both solutions on one seeded record of the designed example
(:mod:`fdi_lib.systems.bz_example`) in which ``theta_k`` drifts from k = 50 with speed
``delta`` and a non-parametric fault of amplitude ``f_size`` starts at k = 200, and draws

1. the RLS estimate ``theta_hat_k`` (forgetting factor ``lam``) against the true ``theta_k``;
2. the energy of the RLS tracking error ``E_k`` (solution 2) and of the Kalman innovation
   (solution 1's non-parametric detector) against their chi-square thresholds;
3. the windowed GLR on the projected Kitanidis residual (solution 1), which ignores ``f``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.stats

from fdi_lib.errors import ModelError
from fdi_lib.filters import kalman_filter
from fdi_lib.nonparametric import (
    Solution1Result,
    Solution2Result,
    solution1,
    solution2_tracking,
)
from fdi_lib.plotting import OURS_COLOR, THRESHOLD_COLOR, figure
from fdi_lib.reproduce.bz import SOL1, SOL2, _simulate
from fdi_lib.reproduce.bz_setup import (
    kalman_regressor,
    kitanidis_detector,
    regressor_rls_gains,
    setup,
)
from fdi_lib.simulate import draw_noise
from fdi_lib.systems import bz_example as ex
from fdi_lib.redraw import keep_artists, reusable_artists, set_limits, stepped_range

__all__ = ["BZRun", "bz_run", "explore_bz", "GRID"]

#: Slider values of the explorable (drift speed at its default 3e-4); lambda moves fastest,
#: so that the build recomputes only solution 2 between neighbouring frames.
GRID = {"f_size": (0.0, 0.1, 0.2, 0.3, 0.4, 0.5), "lam": (0.8, 0.85, 0.9, 0.95, 0.98, 1.0)}


@dataclass(frozen=True)
class BZRun:
    """One record and both solutions (see :func:`bz_run`)."""

    theta_path: np.ndarray
    f: np.ndarray
    sol1: Solution1Result
    sol2: Solution2Result


def bz_run(lam: float = 0.95, delta: float = 3e-4, f_size: float = 0.2, *, seed: int = 0) -> BZRun:
    """Simulate the drift + non-parametric fault scenario and run solutions 1 and 2.

    Parameters
    ----------
    lam : float
        RLS forgetting factor in (0, 1].
    delta : float
        Drift speed ``||e_k||_inf`` (eq. 21), ``>= 0``.
    f_size : float
        Amplitude of the non-parametric fault (sinusoid of period 25 from k = 200), ``>= 0``.
    seed : int
        Seed of the noise (the same record for every slider value).
    """
    if not 0.0 < lam <= 1.0:
        raise ModelError(f"lam: expected a forgetting factor in (0, 1], got {lam!r}")
    if delta < 0 or f_size < 0:
        raise ModelError(f"delta, f_size: expected non-negative values, got {delta!r}, {f_size!r}")
    th, f, sim, s1, eps = _record(float(delta), float(f_size), int(seed))
    n = SOL2["n_steps"]
    # solution2 (fdi_lib.nonparametric) without what lambda does not change: the record's Kalman
    # innovation (cached with the record), the regressor and the RLS gains of each lambda (cached
    # in fdi_lib.reproduce.bz_setup, shared with bz-solution2; tests: the same result as solution2)
    s2 = solution2_tracking(
        eps,
        kalman_regressor(n),
        setup(n)[1],
        lam=lam,
        energy_window=SOL2["energy_window"],
        energy_alpha=SOL2["energy_alpha"],
        start=SOL2["warmup"],
        rls=regressor_rls_gains(n, float(lam)),
    )
    return BZRun(theta_path=th, f=f, sol1=s1, sol2=s2)


@functools.lru_cache(maxsize=8)
def _record(delta: float, f_size: float, seed: int):
    # the record, solution 1 and the Kalman innovation do not depend on the forgetting factor: a
    # lambda slider reruns only the RLS of solution 2 (cached for the last few (delta, f_size,
    # seed))
    n = SOL2["n_steps"]
    model, kal, kg, _, T = setup(n)
    noise = draw_noise(model, np.random.default_rng(seed))
    th = ex.drift_path(n, delta=delta, onset=SOL2["drift_onset"])
    f = ex.nonparametric_profile(n, size=f_size, onset=SOL2["f_onset"])
    sim = _simulate(model, noise, f, th)
    thr = float(scipy.stats.chi2.ppf(1.0 - SOL1["glr_level"], 2))
    s1 = solution1(
        model,
        sim.y,
        sim.u,
        E=ex.E,
        Psi=ex.PSI,
        window=SOL1["window"],
        glr_threshold=thr,
        energy_window=SOL1["energy_window"],
        energy_alpha=SOL1["energy_alpha"],
        kgains=kg,
        kalman=kal,
        T=T,
        # solution 1's windowed GLR arrays (signatures, informations, their pseudo-inverses)
        # depend on the setting, not on the record: a move of the drift or of the fault reuses
        # them (a new record measured 17.6 ms of CPU with them recomputed, 13.0 ms without; the
        # rest of such a redraw, about 90 ms, is matplotlib's)
        glr=kitanidis_detector(n, SOL1["window"]),
    )
    eps = kalman_filter(model, sim.y, sim.u, gains=kal).innovations  # solution 2's innovation
    return th, f, sim, s1, eps


def explore_bz(
    lam: float = 0.95, delta: float = 3e-4, f_size: float = 0.2, fig: Any = None, *, seed: int = 0
):
    """Tracking and detection plots for the given forgetting factor, drift speed and fault size.

    Returns
    -------
    matplotlib.figure.Figure
    """
    run = bz_run(lam, delta, f_size, seed=seed)
    # plain text (Unicode symbols): a title in mathtext would be parsed anew at every slider value
    title = f"RLS tracking, λ = {lam:g}, δ = {delta:.1e}, f amplitude {f_size:g}"
    alarm2, alarm1 = int(run.sol2.energy_alarm), int(run.sol1.nonparametric_alarm)
    # round limits: a move that keeps the curves within the same steps redraws only the data
    limits = (
        stepped_range([*run.theta_path.ravel(), *run.sol2.rls.theta_hat.ravel()], symmetric=True),
        stepped_range([*run.sol2.energy, *run.sol1.energy, run.sol2.energy_threshold], log=True),
        stepped_range([*run.sol1.glr.statistic, run.sol1.glr_threshold]),
    )
    art = reusable_artists(fig, "explore_bz")
    if art is None:  # first call: build the figure; later calls move its artists
        fig, axes = figure(3, 1, fig=fig, sharex=True, figsize=(7.5, 7.0))
        k = np.arange(run.theta_path.shape[0])
        ax = axes[0, 0]
        art = {"theta": [], "theta_hat": []}
        for i, c in enumerate((OURS_COLOR, "#ff7f0e")):
            art["theta"] += ax.plot(k, run.theta_path[:, i], color=c, ls="--", lw=1.0)
            art["theta_hat"] += ax.plot(
                k,
                run.sol2.rls.theta_hat[:, i],
                color=c,
                label=rf"$\hat\theta^{{({i + 1})}}_k$ (dashed: true)",
            )
        ax.axvline(SOL2["f_onset"], color="0.5", lw=0.8, ls=":")
        ax.set(ylabel=r"$\theta_k$")
        art["title"] = ax.set_title(title, y=1.0)  # fixed: no re-placement at each draw
        # fixed legends under the curves: render() keeps them in its saved background
        ax.legend(loc="upper left", ncols=2).set_zorder(1.9)
        ax = axes[1, 0]
        art["energy"] = ax.semilogy(
            k, run.sol2.energy, color=OURS_COLOR, label="RLS error energy (solution 2)"
        )[0]
        art["energy1"] = ax.semilogy(
            k, run.sol1.energy, color="0.5", lw=0.9, label="Kalman innovation energy (solution 1)"
        )[0]
        art["threshold"] = ax.axhline(
            run.sol2.energy_threshold, color=THRESHOLD_COLOR, ls="--", lw=0.9, label="threshold"
        )
        # alarms of solution 2 and of solution 1's energy test (hidden, at 0, when there is none)
        art["alarms"] = [
            ax.axvline(max(a, 0), color=c, ls=":", lw=1.0, visible=a >= 0)
            for a, c in ((alarm2, OURS_COLOR), (alarm1, "0.5"))
        ]
        ax.axvline(SOL2["f_onset"], color="0.5", lw=0.8, ls=":")
        ax.set(ylabel="energy (w = 20)")
        ax.legend(loc="upper left").set_zorder(1.9)
        ax = axes[2, 0]
        art["glr"] = ax.plot(
            k, run.sol1.glr.statistic, color=OURS_COLOR, label="GLR on projected Kitanidis residual"
        )[0]
        art["glr_threshold"] = ax.axhline(
            run.sol1.glr_threshold, color=THRESHOLD_COLOR, ls="--", lw=0.9, label="threshold"
        )
        ax.axvline(SOL2["f_onset"], color="0.5", lw=0.8, ls=":")
        ax.set(xlabel="k", ylabel=r"$l_k$")
        ax.legend(loc="upper left").set_zorder(1.9)
        art["axes"] = tuple(axes[:, 0])
        for ax, ylim in zip(art["axes"], limits):
            ax.set_ylim(ylim)
        keep_artists(fig, "explore_bz", art)
        return fig
    for i, line in enumerate(art["theta"]):
        line.set_ydata(run.theta_path[:, i])
    for i, line in enumerate(art["theta_hat"]):
        line.set_ydata(run.sol2.rls.theta_hat[:, i])
    art["title"].set_text(title)
    art["energy"].set_ydata(run.sol2.energy)
    art["energy1"].set_ydata(run.sol1.energy)
    art["threshold"].set_ydata([run.sol2.energy_threshold] * 2)
    for line, a in zip(art["alarms"], (alarm2, alarm1)):
        line.set_xdata([max(a, 0)] * 2)
        line.set_visible(a >= 0)
    art["glr"].set_ydata(run.sol1.glr.statistic)
    art["glr_threshold"].set_ydata([run.sol1.glr_threshold] * 2)
    for ax, ylim in zip(art["axes"], limits):
        set_limits(ax, ylim=ylim)
    return fig
