"""Figures of the Rosa & Silvestre (2013) reproductions (Figs 1-2, 8-12, the timing of Remark 4).

The computing side, with the registrations, is :mod:`fdi_lib.reproduce.rosa2013` and
:mod:`fdi_lib.reproduce.rosa2013_uav`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fdi_lib.plotting import axes3d, figure, OURS_COLOR, PAPER_COLOR
from fdi_lib.reproduce.registry import ReproductionResult
from fdi_lib.sets.polytope import plot_polytope
from fdi_lib.systems import eclipse_uav as uav


__all__ = [
    "plot_fig1",
    "plot_fig2",
    "plot_alpha",
    "plot_fig11",
    "plot_fig12",
    "plot_timing",
]


def plot_fig1(result: ReproductionResult, fig: Any = None):
    """3-D lifted polytope (vertices and edges of its hull) and its shadow on the x1-x2 plane."""
    from scipy.spatial import ConvexHull

    # the book's style: two panels stacked on a phone, the 3-D one taller (room for its labels)
    fig, axes = figure(1, 2, fig=fig, width_ratios=[1.4, 1])
    spec = axes[0, 0].get_subplotspec()
    axes[0, 0].remove()
    ax = axes3d(fig, spec)
    V = result.data["lifted_vertices"]
    hull = ConvexHull(V)
    for s in hull.simplices:
        tri = V[np.r_[s, s[0]]]
        ax.plot(tri[:, 0], tri[:, 1], tri[:, 2], color=OURS_COLOR, lw=0.5)
    P = result.data["projection"]
    W = P.vertices()
    c = W.mean(axis=0)
    W = W[np.argsort(np.arctan2(W[:, 1] - c[1], W[:, 0] - c[0]))]
    zmin = V[:, 2].min() - 0.3
    ax.plot(np.r_[W[:, 0], W[0, 0]], np.r_[W[:, 1], W[0, 1]], zmin, color=PAPER_COLOR)
    # short labels: the panel is small; the title says which time each coordinate is at
    ax.set_xlabel("$x_1$")
    ax.set_ylabel("$x_2$")
    ax.set_zlabel("$d$")
    ax.set_title("Set(P, p) in $(x(k+1), d(k))$ and its shadow")
    ax2 = axes[0, 1]
    plot_polytope(P, ax2, color=PAPER_COLOR)
    ax2.set_xlabel("$x_1(k+1)$")
    ax2.set_ylabel("$x_2(k+1)$")
    ax2.set_title("projection onto $\\mathbb{R}^n$")
    return fig


def plot_fig2(result: ReproductionResult, fig: Any = None):
    """The two per-vertex sets, their hull (paper Fig. 2) and our sound set."""
    fig, axes = figure(1, 1, fig=fig, figsize=(7.0, 3.6))
    ax = axes[0, 0]
    d = result.data
    plot_polytope(d["hull"], ax, color="0.6", alpha=0.25, label="hull (paper)")
    plot_polytope(d["per_vertex"][1], ax, color=OURS_COLOR, label="$\\Delta=+1$")
    plot_polytope(d["per_vertex"][0], ax, color=PAPER_COLOR, label="$\\Delta=-1$")
    V = d["ours"].vertices()
    c = V.mean(axis=0)
    V = V[np.argsort(np.arctan2(V[:, 1] - c[1], V[:, 0] - c[0]))]
    ax.plot(
        np.r_[V[:, 0], V[0, 0]],
        np.r_[V[:, 1], V[0, 1]],
        "k--",
        lw=1.0,
        label="ours (hull, then strip)",
    )
    ax.set_xlabel("$x_1(k+1)$")
    ax.set_ylabel("$x_2(k+1)$")
    ax.legend(loc="center left", bbox_to_anchor=(1.02, 0.5))
    ax.set_title("paper Fig. 2: SVO hull, $n_A = 1$, $N = 1$")
    return fig


def plot_alpha(result: ReproductionResult, fig: Any = None):
    """Measured and true angle of attack with the fault (paper Figs 8-10)."""
    fig, axes = figure(1, 1, fig=fig)
    ax = axes[0, 0]
    d = result.data
    ax.plot(
        d["t"],
        d["alpha_meas_deg"],
        color=OURS_COLOR,
        lw=0.8,
        label="measured $\\alpha$ (faulty sensor)",
    )
    ax.plot(d["t"], d["alpha_true_deg"], color="k", lw=0.8, label="true $\\alpha$")
    ax.axvline(uav.ONSET, color="0.5", ls=":", label="fault onset")
    if d["detect_t"] is not None:
        ax.axvline(d["detect_t"], color=PAPER_COLOR, ls="--", label="detected (nominal SVO empty)")
    ax.set_xlabel(r"$t$ (s)")
    ax.set_ylabel(r"$\alpha$ (°)")
    ax.set_title(rf"$\alpha$-sensor fault, {d['scenario']} scenario")
    ax.legend(loc="best")
    return fig


def _bar_plot(result: ReproductionResult, key: str, title: str, fig: Any = None):
    fig, axes = figure(1, 1, fig=fig)
    ax = axes[0, 0]
    vals = result.headline[key]
    width = 0.25
    x = np.arange(len(uav.FAULTS))
    for i, s in enumerate(uav.SCENARIOS):
        h = [vals[f][s] if vals[f][s] is not None else 0.0 for f in uav.FAULTS]
        bars = ax.bar(x + (i - 1) * width, h, width, label=s)
        for b, f in zip(bars, uav.FAULTS):
            if vals[f][s] is None:
                ax.text(
                    b.get_x() + b.get_width() / 2,
                    1.0,
                    "n.d.",
                    ha="center",
                    va="bottom",
                    rotation=90,
                )
    ax.set_xticks(x, [r"$\alpha$ sensor", r"elevator $\eta$", r"$M_u$ (dynamics)"])
    ax.set_yscale("symlog", linthresh=10)
    ax.set_ylabel(r"mean time $\bar t$ (ms)")
    ax.set_title(title)
    ax.legend(title="scenario")
    return fig


def plot_fig11(result: ReproductionResult, fig: Any = None):
    """Bar chart of mean detection times (n.d. = not detected), paper Fig. 11."""
    return _bar_plot(result, "detection_time_ms", "paper Fig. 11: mean detection time", fig)


def plot_fig12(result: ReproductionResult, fig: Any = None):
    """Bar chart of mean isolation times (n.d. = not isolated), paper Fig. 12."""
    return _bar_plot(result, "isolation_time_ms", "paper Fig. 12: mean isolation time", fig)


def plot_timing(result: ReproductionResult, fig: Any = None):
    """Median step time against N, with the paper's range and the 10 ms sampling period."""
    fig, axes = figure(1, 1, fig=fig, figsize=(5.0, 3.2))
    ax = axes[0, 0]
    Ns = sorted(result.headline["step_ms"])
    ax.plot(
        Ns,
        [result.headline["step_ms"][n] for n in Ns],
        "o-",
        color=OURS_COLOR,
        label="ours, template rule (median)",
    )
    if "step_ms_exact" in result.headline:
        ax.plot(
            Ns,
            [result.headline["step_ms_exact"][n] for n in Ns],
            "s--",
            color=OURS_COLOR,
            label=f"ours, exact rule (median of the first {result.headline['exact_steps']} steps)",
        )
    ax.axhspan(5, 200, color=PAPER_COLOR, alpha=0.15, label="paper: 5-200 ms")
    ax.axhline(10, color="k", ls=":", label="$T_s$ = 10 ms")
    ax.set_yscale("log")
    ax.set_xticks(Ns)
    ax.set_xlabel(r"horizon $N$")
    ax.set_ylabel(r"time per SVO step $t_{\rm step}$ (ms)")
    ax.legend()
    return fig
