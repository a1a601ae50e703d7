"""Figures and reader helpers of the gas-pipeline reproductions (Zhang & Basseville 2014, Figs 5-9).

The computing side, with the registrations, is :mod:`fdi_lib.reproduce.zb2014_pipeline` (the
set-up, single runs, Figs 5, 6, 9 and Table 1) and :mod:`fdi_lib.reproduce.zb2014_pipeline_mc`
(the Monte Carlo of Figs 7-8 and the sensitivity studies).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.stats

from fdi_lib.plotting import figure, OURS_COLOR, PAPER_COLOR, THRESHOLD_COLOR
from fdi_lib.report import fmt_rate
from fdi_lib.reproduce.registry import ReproductionResult
from fdi_lib.reproduce.zb2014_pipeline import MINMAX_THRESHOLD, SingleRun
from fdi_lib.systems import gas_pipeline as gp

__all__ = [
    "plot_single_run",
    "plot_signals",
    "plot_onset_profile",
    "format_rate",
    "plot_fig7",
    "plot_fig8",
]


def _draw_single_run(
    fig: Any,
    run: SingleRun,
    stat: np.ndarray,
    title: str,
    labels: tuple[str, ...],
    widget: bool,
    alarm_x: list[float],
    onset_x: list[float],
) -> tuple[Any, dict[str, Any]]:
    """The first drawing of :func:`plot_single_run`: the figure and its artists by name (what
    a later draw of a run of the same length moves)."""
    alarm = run.alarm >= 0
    fig, axes = figure(2, 1, fig=fig, sharex=True, figsize=(7.0, 5.0))
    ax0, ax1 = axes[:, 0]
    art = {
        "eps": ax0.plot(run.t_min, run.innovations, color=OURS_COLOR, lw=0.8)[0],
        "onsets": [
            ax0.axvline(run.true_onset * gp.TS_MIN, color="k", ls=":", lw=1, label="true onset")
        ],
    }
    ax0.set(ylabel=r"$\varepsilon_k$ (Nm$^3$/h)")
    art["title"] = ax0.set_title(title, y=1.0)  # fixed: no re-placement at each draw
    legends = [ax0.legend(loc="lower left")]
    art["stat"] = ax1.semilogy(run.t_min, stat, color=OURS_COLOR, label=r"$l_k$ (35)")[0]
    art["threshold"] = ax1.axhline(run.threshold, color=THRESHOLD_COLOR, ls="--", label=labels[0])
    ax1.axvspan(0, gp.DISABLED_MIN, color="0.9", label="GLR disabled")
    art["onsets"].append(ax1.axvline(run.true_onset * gp.TS_MIN, color="k", ls=":", lw=1))
    art["alarm"] = [
        ax1.axvline(alarm_x[0], color=PAPER_COLOR, lw=1, label=labels[1], visible=alarm),
        ax1.axvline(onset_x[0], color="tab:green", lw=1, label=labels[2], visible=alarm),
    ]
    ax1.set(xlabel=r"$t = k T_s$ (min)", ylabel=r"$l_k$")
    legends.append(ax1.legend(loc="lower right", ncols=2))
    if widget:
        for legend in legends:
            legend.set_zorder(1.9)
    else:  # its texts change with the run
        art["legend"] = legends[1]
    art["axes"] = (ax0, ax1)
    return fig, art


def plot_single_run(result: ReproductionResult, fig: Any = None, *, widget: bool = False):
    """Paper Figs 5, 6, 9: innovation (top) and GLR statistic ``l_k`` (bottom, log scale).

    The legend gives the threshold, the alarm time and the onset estimate ("no alarm" when
    there is none). Given the figure it drew before for a run of the same length, it moves its
    artists to the new run (a widget's slider move, :func:`fdi_lib.redraw.reusable_artists`).
    ``widget``: round y limits (:func:`fdi_lib.redraw.stepped_range`) instead of the data's,
    which stay put while the slider moves within a step, and fixed legends (the values are in
    the slider and the title) drawn under the curves, which :func:`fdi_lib.redraw.render`
    keeps in its saved background.
    """
    from fdi_lib.redraw import keep_artists, reusable_artists, set_limits, stepped_range

    run: SingleRun = result.data["run"]
    stat = np.where(run.statistic > 0, run.statistic, np.nan)
    title = result.settings.get("title", "")
    alarm = run.alarm >= 0
    alarm_x = [run.alarm_time_min if alarm else 0.0] * 2
    onset_x = [run.onset_estimate_min if alarm else 0.0] * 2
    if widget:
        labels = ("threshold", "alarm", "onset estimate")
    else:
        labels = (f"threshold {run.threshold:g}",) + (
            (f"alarm {run.alarm_time_min:g} min", f"onset estimate {run.onset_estimate_min:g} min")
            if alarm
            else ("no alarm", "no onset estimate")
        )
    limits = {}
    if widget:
        # innovation symmetric about 0; l_k from four decades below the threshold's (room for
        # the legend under the curve; the warm-up's smaller values do not matter to the test)
        # to at least a decade above the threshold (the innovation's from
        # ``settings["innovation_bound"]`` if given: a bound that does not depend on the noise)
        low = 10.0 ** (np.floor(np.log10(run.threshold)) - 4)
        bound = result.settings.get("innovation_bound")
        limits = {
            0: stepped_range(run.innovations if bound is None else [bound], symmetric=True),
            1: (low, stepped_range([*stat, 10 * run.threshold], log=True)[1]),
        }
    key = f"plot_single_run {run.t_min.size} {widget}"
    art = reusable_artists(fig, key)
    if art is None:
        fig, art = _draw_single_run(fig, run, stat, title, labels, widget, alarm_x, onset_x)
        for i, ylim in limits.items():
            art["axes"][i].set_ylim(ylim)
        keep_artists(fig, key, art)
    else:
        art["eps"].set_ydata(run.innovations)
        art["stat"].set_ydata(stat)
        for line in art["onsets"]:
            line.set_xdata([run.true_onset * gp.TS_MIN] * 2)
        art["title"].set_text(title)
        art["threshold"].set_ydata([run.threshold] * 2)
        for line, x in zip(art["alarm"], (alarm_x, onset_x)):
            line.set_xdata(x)
            line.set_visible(alarm)
        for i, ax in enumerate(art["axes"]):
            if limits:
                set_limits(ax, ylim=limits[i])
            else:
                ax.relim()
                ax.autoscale_view()
    if not widget:
        texts = art["legend"].get_texts()
        for i, text in zip((1, 3, 4), labels):
            texts[i].set_text(text)
        for i in (3, 4):
            art["legend"].legend_handles[i].set_visible(alarm)
    return fig


def plot_signals(variant: str = "physical", fig: Any = None):
    """Inlet flow ``U_k``, noise-free outlet flow and schedule ``p_k`` of a surrogate (not in the paper)."""
    u, p = gp.pipeline_input(variant=variant), gp.pipeline_schedule(variant=variant)
    t = np.arange(gp.N_STEPS) * gp.TS_MIN
    fig, axes = figure(1, 2, fig=fig, figsize=(7.5, 3.0))
    axes[0, 0].plot(t, u / 1e3, color=OURS_COLOR, label=r"$U_k$")
    axes[0, 0].plot(
        t,
        gp.noise_free_output(u, p, variant=variant) / 1e3,
        color=PAPER_COLOR,
        ls="--",
        label=r"$Y_k$ without noise",
    )
    axes[0, 0].set(xlabel=r"$t$ (min from 06:00)", ylabel=r"flow ($10^3$ Nm$^3$/h)")
    axes[0, 0].legend()
    axes[0, 1].plot(t, p, color="tab:green")
    axes[0, 1].set(xlabel=r"$t$ (min from 06:00)", ylabel=r"$p_k$")
    return fig


def plot_onset_profile(result: ReproductionResult, fig: Any = None):
    """GLR statistic of every candidate onset at the alarm of Fig 5 (not in the paper)."""
    both, alone = result.data["profile"], result.data["profile_u_only"]
    fig, ax = figure(fig=fig, figsize=(7.0, 3.5))
    ax = ax[0, 0]
    ax.plot(
        both["onsets"] * gp.TS_MIN,
        both["statistic"],
        color=OURS_COLOR,
        label=r"both columns of $\Psi_k$ ($m = 2$)",
    )
    ax.plot(
        alone["onsets"] * gp.TS_MIN,
        alone["statistic"],
        color=PAPER_COLOR,
        ls="--",
        label=r"$U_k$ column alone ($m = 1$)",
    )
    ax.axvline(gp.FAULT_ONSET_MIN, color="k", ls=":", lw=1, label="true onset")
    ax.set(xlabel=r"candidate onset $r T_s$ (min)", ylabel=r"$l_{k^*}(r)$")
    ax.legend()
    return fig


def _grid_bins(x: np.ndarray, max_bins: int = 40) -> np.ndarray | int:
    """Histogram edges on the sampling grid (multiples of ``Ts``), at most ``max_bins`` bins."""
    if x.size == 0:
        return 1
    lo, hi = float(np.min(x)), float(np.max(x))
    width = gp.TS_MIN * max(1, int(np.ceil((hi - lo + gp.TS_MIN) / (gp.TS_MIN * max_bins))))
    return np.arange(lo - width / 2, hi + width, width)


def plot_fig7(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 7: histograms of detection delays (top) and onset errors (bottom), fault 1 left, 2 right."""
    fig, axes = figure(2, 2, fig=fig, figsize=(7.5, 5.0))
    for j, fault in enumerate((1, 2)):
        delay = result.data["delay_min"][fault]
        err = result.data["onset_error_min"][fault]
        axes[0, j].hist(delay, bins=_grid_bins(delay), color=OURS_COLOR)
        axes[0, j].set(title=f"fault {fault}: detection delay", xlabel=r"$k^* T_s - 600$ (min)")
        axes[1, j].hist(err, bins=_grid_bins(err), color=OURS_COLOR)
        axes[1, j].set(
            title=f"fault {fault}: onset estimation error", xlabel=r"$\hat r T_s - 600$ (min)"
        )
    return fig


def plot_fig8(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 8: histograms of the two minmax statistics per fault, chi-square(1) and (2) densities."""
    fig, axes = figure(2, 2, fig=fig, figsize=(7.5, 5.0))
    x = np.linspace(0.05, 25, 300)
    for j, fault in enumerate((1, 2)):
        for i, test in enumerate((1, 2)):
            ax = axes[i, j]
            stat = result.data["minmax"][fault][test]
            absent = test != fault
            hi = 25 if absent else max(25, float(np.percentile(stat, 99)))
            ax.hist(
                np.clip(stat, 0, hi),
                bins=50,
                range=(0, hi),
                density=True,
                color=OURS_COLOR,
                alpha=0.8,
            )
            if absent:
                ax.plot(
                    x, scipy.stats.chi2.pdf(x, 1), color=PAPER_COLOR, ls="--", label=r"$\chi^2(1)$"
                )
                ax.plot(x, scipy.stats.chi2.pdf(x, 2), color="k", ls=":", label=r"$\chi^2(2)$")
                ax.set_ylim(0, 0.6)
                ax.legend()
            ax.axvline(MINMAX_THRESHOLD, color=THRESHOLD_COLOR, lw=1)
            ax.set(title=f"fault {fault}, test on fault {test}", xlabel=rf"$l_{{{test}}}$ (41)")
    return fig


def format_rate(rate: dict[str, Any]) -> str:
    """A rate dict of these reproductions (``rate``, ``ci95``) as :func:`fdi_lib.report.fmt_rate` text.

    Parameters
    ----------
    rate : dict
        ``{"rate": float or None, "ci95": [low, high], ...}`` (as returned in the headlines).

    Returns
    -------
    str
        e.g. ``"5.8 % [4.4, 7.4]"``; ``"n/a"`` when no run qualified.
    """
    ci = rate.get("ci95")
    ok = rate.get("rate") is not None and ci is not None and None not in ci
    return fmt_rate(rate.get("rate"), ci if ok else None)
