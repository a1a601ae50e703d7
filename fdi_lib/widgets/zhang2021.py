"""Interactive exploration of Zhang (2021), Example 1: number of faults, noise and lambda.

:func:`explore_sparse` is a pure callback: one seeded trial of Example 1 with ``q`` faults and
output noise ``R = r I_2``; the Lasso estimate at ``lambda = lam_scale * lambda_rule`` (the
middle of the flat range, log width) is drawn as diamonds, the least-squares re-estimate on
its support as circles and the truth as asterisks, beside the support-size staircase.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from fdi_lib.errors import ModelError
from fdi_lib.montecarlo import trial_rngs, trial_seeds
from fdi_lib.plotting import OURS_COLOR, PAPER_COLOR, figure
from fdi_lib.reproduce.zhang2021 import example1_regression
from fdi_lib.sparse import flat_range, lasso_path, least_squares_on_support
from fdi_lib.systems import zhang2021_example1 as ex
from fdi_lib.redraw import keep_artists, reusable_artists, set_limits, stepped_range

__all__ = ["explore_sparse", "sparse_grid_facts", "GRID"]

#: Slider values of the explorable: the Lasso path and support against lambda for several q.
GRID = {"q": (1, 3, 5, 10, 15, 25), "lam_scale": (0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0)}


@functools.lru_cache(maxsize=8)
def _trial_path(q: int, r: float, seed: int):
    # the trial, its regression and its exact Lasso path do not depend on lambda: a lambda
    # slider only reads the path (cached for the last few (q, r, seed))
    model = ex.example1_model(r=r)
    trials = ex.draw_trials(model, trial_rngs(trial_seeds(seed, 1)), q=q)
    reg, _ = example1_regression(trials, r=r)
    X, y = reg.X[0], reg.y[0]
    path = lasso_path(X, y, n_samples=reg.n_samples)
    return X, y, path, flat_range(path, scale="log"), np.flatnonzero(trials.theta[0])


def explore_sparse(
    q: int = 5, r: float = 0.5, lam_scale: float = 1.0, seed: int = 0, fig: Any = None
):
    """Draw one trial of Example 1 at ``lambda = lam_scale * lambda_rule``; returns the figure.

    Parameters
    ----------
    q : int
        Number of faults (non-zero components of ``theta``, 1 .. 25).
    r : float
        Output-noise factor (``R = r I_2``), > 0.
    lam_scale : float
        Multiplier of the flat-range ``lambda`` (1 = the paper's rule), > 0.
    seed : int
        Trial seed.
    fig : matplotlib.figure.Figure, optional
        Figure to redraw into.
    """
    if not isinstance(q, (int, np.integer)) or not 1 <= q <= 25:
        raise ModelError(f"q: expected an integer in [1, 25], got {q!r}")
    if not np.isfinite(lam_scale) or lam_scale <= 0:
        raise ModelError(f"lam_scale: expected a positive number, got {lam_scale!r}")
    X, y, path, fr, truth = _trial_path(int(q), float(r), int(seed))
    lam = lam_scale * fr.middle
    coef = path.coef(lam)
    support = np.flatnonzero(coef)
    ls = least_squares_on_support(X, y, support)
    ok = np.array_equal(support, truth)

    idx = np.arange(1, X.shape[1] + 1)
    title = f"q = {q}, r = {r:g}: {'isolated' if ok else 'NOT isolated'}"
    lam_b, sizes = path.lambdas, path.support_sizes()
    floor = 1e-4 * lam_b[0]
    edges = np.concatenate([np.clip(lam_b[::-1], floor, None), [3 * lam_b[0]]])
    steps = np.concatenate([sizes[::-1], [0]])
    # round limits (decades of lambda): a move within the same steps redraws only the data
    limits = {
        "left": (stepped_range([floor, 3 * lam_b[0]], log=True), stepped_range(steps)),
        "right": stepped_range([*coef[support], *ls[support], 1.0, 0.0]),
    }
    # the value in the title, in plain text: a mathtext label would be parsed anew at every value
    left_title = f"support size (flat range: {fr.size}), λ = {lam:.3g}"
    art = reusable_artists(fig, "explore_sparse")
    if art is not None:  # the figure of an earlier call: move its artists
        art["steps"].set_data(steps, edges)
        art["flat"].set_x(fr.low)
        art["flat"].set_width(fr.high - fr.low)
        art["lam"].set_xdata([lam, lam])
        art["left_title"].set_text(left_title)
        art["lasso"].set_data(idx[support], coef[support])
        art["ls"].set_data(idx[support], ls[support])
        art["truth"].set_data(idx[truth], np.ones(truth.size))
        art["right_title"].set_text(title)
        set_limits(art["axes"][0], xlim=limits["left"][0], ylim=limits["left"][1])
        set_limits(art["axes"][1], ylim=limits["right"])
        return fig

    fig, axes = figure(1, 2, fig=fig, figsize=(9.0, 3.4))
    ax = axes[0, 0]
    # the staircase and the flat range over the grid (z-order 1.6, not the patches' 1): the
    # moving artists are then all above the axis, which render() keeps as background
    art = {
        "steps": ax.stairs(steps, edges, color=OURS_COLOR, baseline=None, zorder=1.6),
        "flat": ax.axvspan(
            fr.low, fr.high, color=PAPER_COLOR, alpha=0.15, label="flat range", zorder=1.6
        ),
        "lam": ax.axvline(lam, color="k", ls="--", lw=1, label=r"chosen $\lambda$"),
    }
    ax.set(
        xscale="log",
        xlabel=r"$\lambda$",
        ylabel="non-zero components",
        xlim=limits["left"][0],
        ylim=limits["left"][1],
    )
    art["left_title"] = ax.set_title(left_title, y=1.0)  # fixed: no re-placement at each draw
    ax.legend(loc="upper right")
    ax = axes[0, 1]
    art["lasso"] = ax.plot(idx[support], coef[support], "D", color=OURS_COLOR, ms=5, label="Lasso")[
        0
    ]
    art["ls"] = ax.plot(
        idx[support], ls[support], "o", mfc="none", mec="k", ms=10, label="least squares"
    )[0]
    art["truth"] = ax.plot(
        idx[truth], np.ones(truth.size), "*", color=PAPER_COLOR, ms=10, label="true"
    )[0]
    ax.set(
        xlabel=r"component of $\theta$",
        ylabel="value",
        xlim=(0, X.shape[1] + 1),
        ylim=limits["right"],
    )
    art["right_title"] = ax.set_title(title, y=1.0)
    # a fixed place under the markers (z-order 1.9): render() keeps it in its saved background
    # ("best" would move it, so draw it, at every value)
    ax.legend(loc="upper right").set_zorder(1.9)
    art["axes"] = (axes[0, 0], ax)
    keep_artists(fig, "explore_sparse", art)
    return fig


def sparse_grid_facts(grid: dict = GRID, *, r: float = 0.5, seed: int = 0) -> dict[str, Any]:
    """What the sliders of the explorable do, frame by frame (the values :func:`explore_sparse` draws).

    Returns
    -------
    dict
        ``false_alarms``, ``missed``: ``(q, lam_scale)`` -> components wrongly in / wrongly out of
        the Lasso support; ``position``: ``(q, lam_scale)`` -> ``"below"``, ``"in"`` or ``"above"`` the
        flat range; ``flat_ratio``: q -> high / low end of the flat range (its length in decades
        is the log10 of it).
    """
    out: dict[str, Any] = {"false_alarms": {}, "missed": {}, "position": {}, "flat_ratio": {}}
    for q in grid["q"]:
        _, _, path, fr, truth = _trial_path(int(q), float(r), int(seed))
        out["flat_ratio"][q] = float(fr.high / fr.low)
        for scale in grid["lam_scale"]:
            lam = scale * fr.middle
            support = np.flatnonzero(path.coef(lam))
            out["false_alarms"][(q, scale)] = int(np.setdiff1d(support, truth).size)
            out["missed"][(q, scale)] = int(np.setdiff1d(truth, support).size)
            out["position"][(q, scale)] = (
                "below" if lam < fr.low else "above" if lam > fr.high else "in"
            )
    return out
