"""Figures of the wind-turbine reproductions (the scoreboard).

The computing side, with the registrations, is :mod:`fdi_lib.reproduce.windturbine`; every method
is drawn as its record of :data:`fdi_lib.windturbine.METHODS` says.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fdi_lib import windturbine as W
from fdi_lib.reproduce.registry import ReproductionResult

__all__ = ["plot_scoreboard"]


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
