"""Figures of the wind-turbine reproductions (the scoreboard, the accommodation).

The computing side, with the registrations, is :mod:`fdi_lib.reproduce.windturbine`; every method
is drawn as its record of :data:`fdi_lib.windturbine.METHODS` says.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fdi_lib import windturbine as W
from fdi_lib.reproduce.registry import ReproductionResult
from fdi_lib.reproduce.windturbine_accommodation import METRICS

__all__ = ["plot_scoreboard", "plot_accommodation"]


def plot_scoreboard(result: ReproductionResult, fig: Any = None):
    """Detection time per fault and method (:data:`fdi_lib.windturbine.METHODS`, each in its
    :class:`~fdi_lib.windturbine.PlotStyle`): mean (marker) and 2.5-97.5 % range (bar), the
    benchmark's requirement (tick); a fault a method never detects has no marker. The methods of
    a fault share its row's height, 0.72 of it at most."""
    from fdi_lib.plotting import figure

    h = result.headline
    fig, axes = figure(1, 1, fig=fig, figsize=(6.4, 4.6))
    ax = axes[0][0]
    ids = list(h["faults"])
    step = min(0.18, 0.72 / len(W.METHODS))
    for j, (m, method) in enumerate(W.METHODS.items()):
        y = np.arange(len(ids)) + (j - (len(W.METHODS) - 1) / 2) * step
        t = []
        color = method.style.color
        for yi, f in zip(y, ids):
            v = h["faults"][f]["methods"][m]
            t.append(np.nan if v["detection_time_mean_s"] is None else v["detection_time_mean_s"])
            if v["detection_time_spread95"] is not None:
                ax.plot(v["detection_time_spread95"], [yi, yi], color=color, lw=1)
        ax.plot(t, y, method.style.marker, color=color, label=method.label, ms=4)
    req = [h["faults"][f]["required_detection_s"] for f in ids]
    ax.plot(
        [np.nan if r is None else r for r in req],
        np.arange(len(ids)),
        "k|",
        ms=14,
        label="required",
    )
    ax.set_xscale("log")
    ax.set_yticks(np.arange(len(ids)), ids)
    ax.invert_yaxis()
    ax.set_xlabel("detection time (s)")
    # below the axes: inside, the legend hid the slow faults' points (F6, F7)
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", ncol=3)
    return fig


def plot_accommodation(result: ReproductionResult, fig: Any = None):
    """RMS effect on power, pitch and generator speed per sensor fault: faulty (left bar) and
    accommodated (right bar), means over the realisations."""
    from fdi_lib.plotting import MIN_FONT_PT, figure

    h = result.headline
    ids = list(h["faults"])
    fig, axes = figure(1, 3, fig=fig, figsize=(7.2, 3.0))
    labels = {
        "power_kw": "power (kW)",
        "pitch_deg": "pitch (deg)",
        "speed_rad_s": "gen. speed (rad/s)",
    }
    x = np.arange(len(ids))
    for ax, m in zip(axes[0], METRICS):
        ax.bar(x - 0.2, [h["faults"][f]["faulty"][m] for f in ids], 0.4, label="faulty", color="C3")
        ax.bar(
            x + 0.2,
            [h["faults"][f]["accommodated"][m] for f in ids],
            0.4,
            label="accommodated",
            color="C0",
        )
        ax.set_xticks(x, ids)
        ax.set_title(f"RMS change, {labels[m]}", fontsize=MIN_FONT_PT)
    fig.legend(*axes[0][0].get_legend_handles_labels(), loc="outside lower center", ncol=2)
    return fig
