"""Interactive exploration of the set-valued observer (Rosa & Silvestre 2013 chapter).

:func:`explore_svo` is the pure callback that the book draws once at its default values and
then wires to sliders with :func:`fdi_lib.widgets.interactive_figure`.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from fdi_lib.errors import ModelError
from fdi_lib.plotting import OURS_COLOR, PAPER_COLOR, figure
from fdi_lib.sets.polytope import plot_polytope, polygon_outline
from fdi_lib.sets.svo import run_svo
from fdi_lib.widgets import keep_artists, reusable_artists

__all__ = ["explore_svo", "GRID", "MAX_HORIZON"]

#: Largest horizon the callback accepts. The exact rule costs N one-step hulls per update
#: (:class:`fdi_lib.sets.svo.SetValuedObserver`), not one hull over 2^N parameter sequences.
MAX_HORIZON = 6
#: Slider values of the SVO explorable.
GRID = {"delta_bound": (0.0, 0.2, 0.4, 0.6, 0.8, 1.0), "horizon": (1, 2, 3, 4, 5, 6)}


@functools.lru_cache(maxsize=1)
def _example(delta_bound: float, noise: float, seed: int, steps: int) -> tuple:
    """What the horizon slider does not change: the model, the record and the hull panel (kept
    for the last values only, so that moving any other slider recomputes them)."""
    from fdi_lib.reproduce.rosa2013 import _fig2_sets, simulate_toy, toy_model, toy_prior

    model = toy_model(delta_bound=delta_bound, noise=noise)
    x, u, y = simulate_toy(model, rng=np.random.default_rng(seed), steps=steps)
    per_vertex, hull, _, _ = _fig2_sets(model, toy_prior(), np.array([0.0]), np.array([0.2]))
    for a in (x, u, y):
        a.flags.writeable = False
    return model, x, u, y, per_vertex, hull, hull.volume()


def _limits(lo: float, hi: float) -> tuple[float, float]:
    """``[lo, hi]`` widened by 5 % on each side (matplotlib's default margin)."""
    pad = 0.05 * (hi - lo)
    return lo - pad, hi + pad


def explore_svo(delta_bound: float = 0.4, horizon: int = 1, noise: float = 0.5, *, seed: int = 0,
                steps: int = 25, fig: Any = None):
    """Redraw the SVO hull (paper Fig. 2) and the set sequence of the 2-D example.

    Parameters
    ----------
    delta_bound : float
        Size of the parametric uncertainty (scales A_1 of :func:`fdi_lib.reproduce.rosa2013.toy_model`).
    horizon : int
        Horizon N of the SVO (eq. (3)), from 1 to :data:`MAX_HORIZON`.
    noise : float
        Sensor noise bound nbar.
    seed : int
        Seed of the simulated data (Delta, d, n uniform within the bounds).
    steps : int
        Length of the record.
    fig : matplotlib.figure.Figure, optional
        Figure to redraw into (a figure this callback drew is updated in place: same artists,
        new data).

    Returns
    -------
    matplotlib.figure.Figure
        Left: per-vertex sets and hull for one step; right: bounds on x2(k) with the true state.
    """
    from fdi_lib.reproduce.rosa2013 import toy_prior

    if not (0.0 <= delta_bound <= 1.0):
        raise ModelError(f"delta_bound: expected a value in [0, 1], got {delta_bound!r}")
    if not (0.0 < noise <= 2.0):
        raise ModelError(f"noise: expected a value in (0, 2], got {noise!r}")
    if int(horizon) != horizon or not (1 <= horizon <= MAX_HORIZON):
        raise ModelError(f"horizon: expected an integer in 1..{MAX_HORIZON}, got {horizon!r}")
    model, x, u, y, per_vertex, hull, area = _example(float(delta_bound), float(noise), int(seed), int(steps))
    res = run_svo(model, u, y, toy_prior(), N=int(horizon), method="exact", keep_sets=True)
    k = np.arange(len(x))
    shapes = [polygon_outline(P) for P in (hull, *per_vertex)]
    box = shapes[0]   # the hull contains the per-vertex sets
    inside = all(S.contains(x[i], 1e-7) for i, S in enumerate(res.sets))
    shown = np.concatenate([res.lower[:, 1], res.upper[:, 1], x[:, 1]])
    art = reusable_artists(fig, "explore_svo")
    if art is None:  # first call: build the figure; later calls only move its artists
        fig, axes = figure(1, 2, fig=fig, figsize=(8.0, 3.4))
        ax, ax2 = axes[0]
        plot_polytope(hull, ax, color="0.6", alpha=0.25)
        for P, c in zip(per_vertex, (PAPER_COLOR, OURS_COLOR)):
            plot_polytope(P, ax, color=c)
        ax.set_xlabel("$x_1$")
        ax.set_ylabel("$x_2$")
        band = ax2.fill_between(k, res.lower[:, 1], res.upper[:, 1], color=OURS_COLOR, alpha=0.3,
                                label="SVO bounds on $x_2$")
        art = {"ax": ax, "ax2": ax2, "patches": list(ax.patches), "edges": list(ax.lines), "band": band,
               "true": ax2.plot(k, x[:, 1], "k.-", lw=0.8, label="true $x_2$")[0]}
        ax2.set_xlabel("k")
        ax2.legend(loc="upper right")
        keep_artists(fig, "explore_svo", art)
    else:
        for patch, edge, V in zip(art["patches"], art["edges"], shapes):
            patch.set_xy(V)
            edge.set_data(np.r_[V[:, 0], V[0, 0]], np.r_[V[:, 1], V[0, 1]])
        art["band"].set_data(k, res.lower[:, 1], res.upper[:, 1])
        art["true"].set_data(k, x[:, 1])
    ax, ax2 = art["ax"], art["ax2"]
    ax.set_xlim(*_limits(box[:, 0].min(), box[:, 0].max()))
    ax.set_ylim(*_limits(box[:, 1].min(), box[:, 1].max()))
    ax2.set_xlim(*_limits(0.0, float(k[-1])))
    ax2.set_ylim(*_limits(float(np.nanmin(shown)), float(np.nanmax(shown))))
    ax.set_title(f"hull: area {area:.3f}, union-to-hull gap shown grey")
    ax2.set_title(f"N = {int(horizon)}: true state inside every set: {inside}")
    return fig
