"""Figures of the Zhang & Basseville (2014) reproductions on the unstable example (Figs 1-4).

The computing side, with the registrations, is :mod:`fdi_lib.reproduce.zb2014`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fdi_lib.plotting import figure, OURS_COLOR, THRESHOLD_COLOR
from fdi_lib.reproduce.registry import ReproductionResult
from fdi_lib.reproduce.zb2014 import UnstableRun

__all__ = [
    "plot_detection",
    "plot_fig1",
    "plot_fig2",
    "plot_persistent_excitation",
    "plot_null_histograms",
]


def plot_fig1(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 1: ``||Gamma_k||_2`` against ``k`` (left); zoom on ``r = 101`` with ``||Gamma_k e_1||_2``.

    The right panel also draws the floor ``||F e_2||`` (:func:`~fdi_lib.reproduce.zb2014.gamma_lower_bound`).
    """
    fig, axes = figure(1, 2, fig=fig, gridspec_kw={"width_ratios": [2, 1]})
    left, right = axes[0]
    for r, norms in result.data["gamma_norm"].items():
        left.plot(np.arange(norms.size), norms, label=f"$r = {r}$")
    left.axhline(1.0, color="k", lw=0.8, ls="--", label="paper's bound 1")
    left.set(xlabel="$k$", ylabel=r"$\|\Gamma_k\|_2$")
    left.legend(ncols=3, loc="upper right")
    r = "101" if "101" in result.data["gamma_norm"] else next(iter(result.data["gamma_norm"]))
    k = np.arange(int(r) - 2, int(r) + 15)
    right.plot(k, result.data["gamma_norm"][r][k], label=r"$\|\Gamma_k\|_2$")
    right.plot(k, result.data["gamma_e1_norm"][r][k], ls=":", label=r"$\|\Gamma_k e_1\|_2$")
    right.axhline(1.0, color="k", lw=0.8, ls="--")
    right.axhline(
        result.headline["gamma_lower_bound"], color="0.4", lw=0.8, ls="-.", label=r"$\|F e_2\|_2$"
    )
    right.set(xlabel="$k$", title=f"zoom on $r = {r}$")
    right.legend(loc="center right")
    return fig


def plot_persistent_excitation(
    curves: dict[str, np.ndarray], s: int, floor: float = 1e-16, fig: Any = None
):
    """Smallest eigenvalue of the windowed information against ``k``, log scale.

    Parameters
    ----------
    curves : dict
        Legend label to :func:`~fdi_lib.reproduce.zb2014.window_min_eigenvalue` output (values for ``k = s-1, ...``).
    s : int
        The window length.
    floor : float
        Values below it (rounding level: singular windows) are drawn at it.
    fig : matplotlib.figure.Figure, optional
        Figure to draw into.
    """
    fig, ax = figure(fig=fig)
    ax = ax[0, 0]
    for label, values in curves.items():
        k = np.arange(s - 1, s - 1 + values.size)
        ax.semilogy(k, np.maximum(values, floor), label=label)
    ax.set(xlabel="$k$", ylabel=rf"$\lambda_{{\min}}$ of the information, $s = {s}$")
    ax.legend()
    return fig


def plot_null_histograms(panels: dict[str, Any], xlabel: str, fig: Any = None):
    """Histograms of statistics simulated under no fault, with their chi-square density.

    Parameters
    ----------
    panels : dict
        Panel title (may be empty) to a :class:`fdi_lib.calibration.Calibration`; one panel each,
        side by side, the density of ``chi2(calibration.dof)`` drawn on each.
    xlabel : str
        Label of the statistic (mathtext).
    fig : matplotlib.figure.Figure, optional
        Figure to draw into.
    """
    import scipy.stats

    fig, axes = figure(1, len(panels), fig=fig)
    for ax, (title, cal) in zip(axes[0], panels.items()):
        ax.hist(
            cal.statistics,
            bins=50,
            density=True,
            alpha=0.6,
            color=OURS_COLOR,
            label=f"{cal.statistics.size} runs",
        )
        x = np.linspace(0.02, max(8.0, float(np.quantile(cal.statistics, 0.999))), 300)
        ax.plot(
            x,
            scipy.stats.chi2(cal.dof).pdf(x),
            "--",
            color=THRESHOLD_COLOR,
            label=rf"$\chi^2({cal.dof})$",
        )
        ax.set(title=title, xlabel=xlabel, ylim=(0, 1.2 if cal.dof == 1 else None))
    axes[0, 0].set_ylabel("density")
    axes[0, 0].legend()
    return fig


# ----------------------------------------------------------------------------- Figure 2
def plot_fig2(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 2: ``||alpha_k(r)||_2`` on a log scale."""
    fig, ax = figure(fig=fig)
    ax = ax[0, 0]
    for r, norms in result.data["alpha_norm"].items():
        k = np.arange(norms.size)
        mask = norms > 0
        ax.semilogy(k[mask], norms[mask], label=f"$r = {r}$")
    ax.set(xlabel="$k$", ylabel=r"$\|\alpha_k(r)\|_2$", title="Willsky-Jones recursion (A.6)")
    ax.legend(ncols=2, loc="upper left")  # 2 x 2: four in a row ran past the axes
    return fig


def _draw_detection(
    fig: Any,
    run: UnstableRun,
    k: np.ndarray,
    stat: np.ndarray,
    title: str,
    labels: tuple[str, ...],
    alarm_xy: tuple[list, list],
    widget: bool,
    limits: dict[str, tuple[float, float]],
) -> tuple[Any, dict[str, Any]]:
    """The first drawing of :func:`plot_detection`: the figure and its artists by name (what a
    later draw of a run of the same length moves)."""
    fig, axes = figure(2, 1, fig=fig, sharex=True, figsize=(7.0, 4.6))
    top, bottom = axes[0, 0], axes[1, 0]
    art = {
        "eps": top.plot(k, run.innovations, color=OURS_COLOR, lw=0.8)[0],
        "top": top,
        "bottom": bottom,
    }
    art["onsets"] = [top.axvline(run.onset, color="k", ls=":", lw=0.8)]
    top.set(ylabel=r"$\varepsilon_k$")
    art["title"] = top.set_title(title, y=1.0)  # fixed: no re-placement at each draw
    art["stat"] = bottom.plot(k, stat, color=OURS_COLOR)[0]
    if run.threshold is not None:
        art["threshold"] = bottom.axhline(
            run.threshold, color=THRESHOLD_COLOR, ls="--", lw=0.8, label=labels[0]
        )
    art["onsets"].append(bottom.axvline(run.onset, color="k", ls=":", lw=0.8, label=labels[1]))
    if run.threshold is not None:
        art["alarm"] = bottom.plot(*alarm_xy, "o", color=THRESHOLD_COLOR, label=labels[2])[0]
    bottom.set(xlabel="$k$", ylabel=r"$l_k$")
    legend = bottom.legend(loc="upper left")
    if widget:
        legend.set_zorder(1.9)
    else:  # its texts change with the run
        art["legend"] = legend
    if limits:
        top.set_ylim(limits["top"])
        bottom.set_ylim(limits["bottom"])
    return fig, art


def plot_detection(
    run: UnstableRun, fig: Any = None, title: str | None = None, *, widget: bool = False
):
    """Innovation (top) and GLR statistic ``l_k`` (bottom), as in paper Figs. 3-4.

    With a threshold, the legend has an alarm entry ("no alarm" when there is none). Given
    the figure it drew before for a run of the same length, it moves its artists to ``run``
    (a widget's slider move, :func:`fdi_lib.redraw.reusable_artists`). ``widget``: round y
    limits (:func:`fdi_lib.redraw.stepped_range`) instead of the data's, which stay put while
    the slider moves within a step, and a fixed legend (the values are in the sliders and the
    title) drawn under the curves, which :func:`fdi_lib.redraw.render` keeps in its saved
    background.
    """
    from fdi_lib.redraw import keep_artists, reusable_artists, set_limits, stepped_range

    k = np.arange(run.innovations.size)
    stat = run.glr.statistic
    title = title or (
        rf"$\theta = [{run.theta[0]:g}, {run.theta[1]:g}]$, "
        rf"onset $r = {run.onset}$, $w = {run.window}$"
    )
    has_alarm = run.threshold is not None and run.alarm >= 0
    alarm_xy = ([run.alarm], [stat[run.alarm]]) if has_alarm else ([], [])
    # legend entries: [threshold, onset, alarm] with a threshold, [onset] without
    if widget:
        labels = ("threshold", "onset $r$", "alarm")
    else:
        labels = (
            f"threshold {run.threshold:g}" if run.threshold is not None else "",
            f"onset $r = {run.onset}$",
            f"alarm at $k = {run.alarm}$" if has_alarm else "no alarm",
        )
    limits = {}
    if widget:
        limits = {
            "top": stepped_range(run.innovations, symmetric=True),
            "bottom": stepped_range([*stat, run.threshold or 0.0]),
        }
    key = f"plot_detection {k.size} {run.threshold is None} {widget}"
    art = reusable_artists(fig, key)
    if art is not None:
        art["eps"].set_ydata(run.innovations)
        art["stat"].set_ydata(stat)
        for line in art["onsets"]:
            line.set_xdata([run.onset, run.onset])
        art["title"].set_text(title)
        if run.threshold is not None:
            art["threshold"].set_ydata([run.threshold, run.threshold])
            art["alarm"].set_data(*alarm_xy)
        for ax in ("top", "bottom"):
            if limits:
                set_limits(art[ax], ylim=limits[ax])
            else:
                art[ax].relim()
                art[ax].autoscale_view()
    else:
        fig, art = _draw_detection(fig, run, k, stat, title, labels, alarm_xy, widget, limits)
        keep_artists(fig, key, art)
    if not widget:
        texts = art["legend"].get_texts()
        if run.threshold is None:
            texts[0].set_text(labels[1])
        else:
            for text, label in zip(texts, labels):
                text.set_text(label)
            art["legend"].legend_handles[2].set_visible(has_alarm)
    return fig


def plot_fig3(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 3."""
    return plot_detection(result.data["run"], fig=fig)


def plot_fig4(result: ReproductionResult, fig: Any = None):
    """Paper Fig. 4."""
    return plot_detection(result.data["run"], fig=fig)
