"""Interactive exploration of the set-valued observer (Rosa & Silvestre 2013 chapter).

:func:`explore_svo` is the pure callback that the book draws once at its default values and
then wires to sliders with :func:`fdi_lib.widgets.interactive_figure`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fdi_lib.errors import ModelError
from fdi_lib.plotting import OURS_COLOR, PAPER_COLOR, figure
from fdi_lib.sets.polytope import plot_polytope
from fdi_lib.sets.svo import run_svo

__all__ = ["explore_svo", "GRID"]

#: Slider values of the SVO explorable. The horizon stops at 4: the SVO cost grows as
#: ``2^(N n_A)`` parameter sequences (one frame at N = 6 took 36 s on the loaded build machine).
GRID = {"delta_bound": (0.0, 0.2, 0.4, 0.6, 0.8, 1.0), "horizon": (1, 2, 3, 4)}


def explore_svo(delta_bound: float = 0.4, horizon: int = 1, noise: float = 0.5, *, seed: int = 0,
                steps: int = 25, fig: Any = None):
    """Redraw the SVO hull (paper Fig. 2) and the set sequence of the 2-D example.

    Parameters
    ----------
    delta_bound : float
        Size of the parametric uncertainty (scales A_1 of :func:`fdi_lib.reproduce.rosa2013.toy_model`).
    horizon : int
        Horizon N of the SVO (eq. (3)).
    noise : float
        Sensor noise bound nbar.
    seed : int
        Seed of the simulated data (Delta, d, n uniform within the bounds).
    steps : int
        Length of the record.
    fig : matplotlib.figure.Figure, optional
        Figure to redraw into.

    Returns
    -------
    matplotlib.figure.Figure
        Left: per-vertex sets and hull for one step; right: bounds on x2(k) with the true state.
    """
    from fdi_lib.reproduce.rosa2013 import _fig2_sets, simulate_toy, toy_model, toy_prior

    if not (0.0 <= delta_bound <= 1.0):
        raise ModelError(f"delta_bound: expected a value in [0, 1], got {delta_bound!r}")
    if not (0.0 < noise <= 2.0):
        raise ModelError(f"noise: expected a value in (0, 2], got {noise!r}")
    if int(horizon) != horizon or not (1 <= horizon <= 4):
        raise ModelError(f"horizon: expected an integer in 1..4, got {horizon!r}")
    model = toy_model(delta_bound=delta_bound, noise=noise)
    x, u, y = simulate_toy(model, rng=np.random.default_rng(seed), steps=steps)
    res = run_svo(model, u, y, toy_prior(), N=int(horizon), method="exact", keep_sets=True)
    fig, axes = figure(1, 2, fig=fig, figsize=(8.0, 3.4))
    ax, ax2 = axes[0]
    per_vertex, hull, ours, _ = _fig2_sets(model, toy_prior(), np.array([0.0]), np.array([0.2]))
    plot_polytope(hull, ax, color="0.6", alpha=0.25)
    for P, c in zip(per_vertex, (PAPER_COLOR, OURS_COLOR)):
        plot_polytope(P, ax, color=c)
    ax.set_title(f"hull: area {hull.volume():.3f}, union-to-hull gap shown grey")
    ax.set_xlabel("$x_1$")
    ax.set_ylabel("$x_2$")
    k = np.arange(len(x))
    ax2.fill_between(k, res.lower[:, 1], res.upper[:, 1], color=OURS_COLOR, alpha=0.3, label="SVO bounds on $x_2$")
    ax2.plot(k, x[:, 1], "k.-", lw=0.8, label="true $x_2$")
    inside = all(S.contains(x[i], 1e-7) for i, S in enumerate(res.sets))
    ax2.set_title(f"N = {int(horizon)}: true state inside every set: {inside}")
    ax2.set_xlabel("k")
    ax2.legend(loc="upper right")
    return fig
