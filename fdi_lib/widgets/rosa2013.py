"""Interactive exploration of the set-valued observer (Rosa & Silvestre 2013 chapter).

:func:`explore_svo` is the pure callback that the book draws once at its default values and
then wires to sliders with :func:`fdi_lib.widgets.interactive_figure`.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from fdi_lib.errors import EmptySetError, ModelError
from fdi_lib.plotting import OURS_COLOR, PAPER_COLOR, figure
from fdi_lib.sets.polytope import plot_polytope, polygon_outline
from fdi_lib.sets.svo import SVORun, run_svo
from fdi_lib.redraw import keep_artists, reusable_artists, set_limits

__all__ = ["explore_svo", "horizon_study", "GRID", "MAX_HORIZON"]

#: Largest horizon the callback accepts.
MAX_HORIZON = 6
#: Slider values of the SVO explorable. With the template rule, N = 5 and 6 give the sets of
#: N = 4 at every bound from 0.4 up on this record (measured): the slider stops at 4.
GRID = {"delta_bound": (0.0, 0.2, 0.4, 0.6, 0.8, 1.0), "horizon": (1, 2, 3, 4)}


@functools.lru_cache(maxsize=len(GRID["delta_bound"]))
def _example(delta_bound: float, noise: float, seed: int, steps: int) -> tuple:
    """What the horizon slider does not change: the model, the record, the hull panel and the
    exact rule's run (kept for as many values as the explorable's grid has uncertainty bounds:
    :func:`horizon_study`, the frames of the explorable and its panels for paper, which run over
    them in turn, compute each once)."""
    from fdi_lib.reproduce.rosa2013 import _fig2_sets, simulate_toy, toy_model, toy_prior

    model = toy_model(delta_bound=delta_bound, noise=noise)
    x, u, y = simulate_toy(model, rng=np.random.default_rng(seed), steps=steps)
    per_vertex, hull, _, _ = _fig2_sets(model, toy_prior(), np.array([0.0]), np.array([0.2]))
    exact = run_svo(model, u, y, toy_prior(), N=1, method="exact")
    for a in (x, u, y, exact.lower, exact.upper):
        a.flags.writeable = False
    return model, x, u, y, per_vertex, hull, hull.volume(), exact


@functools.lru_cache(maxsize=len(GRID["delta_bound"]) * MAX_HORIZON)
def _template_run(delta_bound: float, noise: float, seed: int, steps: int, horizon: int) -> SVORun:
    """The template rule's run (:func:`fdi_lib.sets.svo.run_svo`, sets kept) on the record of
    :func:`_example` with horizon N, its arrays read-only (cached: :func:`horizon_study` and the
    frames of the explorable ask for the same runs)."""
    from fdi_lib.reproduce.rosa2013 import toy_prior

    model, x, u, y, *_ = _example(delta_bound, noise, seed, steps)
    run = run_svo(model, u, y, toy_prior(), N=horizon, method="template", keep_sets=True)
    for a in (run.lower, run.upper, run.n_facets, run.n_vertices, run.step_time):
        a.flags.writeable = False
    return run


def _limits(values: Any) -> tuple[float, float]:
    """The range of ``values`` widened by 5 % on each side (matplotlib's default margin)."""
    lo, hi = float(np.nanmin(values)), float(np.nanmax(values))
    pad = 0.05 * (hi - lo)
    return lo - pad, hi + pad


def _mean_width(run: Any) -> float:
    """Mean width of the bounds on x2 over the record (of a run whose sets never became empty:
    the record is healthy, so an empty set would contradict Proposition 2)."""
    if run.empty_at is not None:
        raise EmptySetError(
            f"SVO: expected a non-empty set at every sample of the healthy record, "
            f"got an empty set at k = {run.empty_at}"
        )
    return float(np.mean(run.upper[:, 1] - run.lower[:, 1]))


def explore_svo(
    delta_bound: float = 0.4,
    horizon: int = 1,
    noise: float = 0.5,
    *,
    seed: int = 0,
    steps: int = 25,
    fig: Any = None,
):
    """Redraw the SVO hull (paper Fig. 2) and the bounds on x2 of the 2-D example for horizon N.

    The bounds of the bottom panel are those of the template rule (:func:`fdi_lib.sets.svo.run_svo`,
    ``method="template"``), for which the horizon matters; the exact rule's bounds (``N = 1``)
    are drawn dashed. The exact rule gains nothing from N on this example: every older level of
    its horizon contains the newest one (:func:`horizon_study` measures it).

    Parameters
    ----------
    delta_bound : float
        Size of the parametric uncertainty (scales :math:`A_1` of :func:`fdi_lib.reproduce.rosa2013.toy_model`).
    horizon : int
        Horizon N of the template SVO (eq. (3)), from 1 to :data:`MAX_HORIZON`.
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
        Left: per-vertex sets and hull for one step; right: bounds on x2(k) (template rule,
        horizon N: band; exact rule: dashed) with the true state.
    """
    if not (0.0 <= delta_bound <= 1.0):
        raise ModelError(f"delta_bound: expected a value in [0, 1], got {delta_bound!r}")
    if not (0.0 < noise <= 2.0):
        raise ModelError(f"noise: expected a value in (0, 2], got {noise!r}")
    if int(horizon) != horizon or not (1 <= horizon <= MAX_HORIZON):
        raise ModelError(f"horizon: expected an integer in 1..{MAX_HORIZON}, got {horizon!r}")
    key = (float(delta_bound), float(noise), int(seed), int(steps))
    _, x, _, _, per_vertex, hull, area, exact = _example(*key)
    res = _template_run(*key, int(horizon))
    k = np.arange(len(x))
    shapes = [polygon_outline(P) for P in (hull, *per_vertex)]
    box = shapes[0]  # the hull contains the per-vertex sets
    shown = np.concatenate([res.lower[:, 1], res.upper[:, 1], x[:, 1]])
    titles = (
        f"hull: area {area:.3f}, union-to-hull gap shown grey",
        f"N = {int(horizon)}: mean width {_mean_width(res):.2f}, exact {_mean_width(exact):.2f}",
    )
    art = reusable_artists(fig, "explore_svo")
    if art is None:  # first call: build the figure; later calls only move its artists
        fig, axes = figure(1, 2, fig=fig, figsize=(8.0, 3.4))
        ax, ax2 = axes[0]
        for a in (ax, ax2):
            # the axis under the data: its ticks and labels, which cost most of a draw, are then
            # static (drawn once) instead of above the moving sets and bands
            a.set_axisbelow(True)
        plot_polytope(hull, ax, color="0.6", alpha=0.25)
        for P, c in zip(per_vertex, (PAPER_COLOR, OURS_COLOR)):
            plot_polytope(P, ax, color=c)
        ax.set_xlabel("$x_1$")
        ax.set_ylabel("$x_2$")
        band = ax2.fill_between(
            k,
            res.lower[:, 1],
            res.upper[:, 1],
            color=OURS_COLOR,
            alpha=0.3,
            label="template SVO, horizon N",
        )
        art = {
            "ax": ax,
            "ax2": ax2,
            "patches": list(ax.patches),
            "edges": list(ax.lines),
            "band": band,
            "exact": ax2.plot(
                k, exact.lower[:, 1], "--", k, exact.upper[:, 1], "--", color=PAPER_COLOR, lw=1.0
            ),
            "true": ax2.plot(k, x[:, 1], "k.-", lw=0.8, label="true $x_2$")[0],
            # dynamic, at a fixed place: a new title is drawn alone, not with its axes
            "titles": [a.set_title(t, y=1.0) for a, t in zip((ax, ax2), titles)],
        }
        art["exact"][0].set_label("exact SVO, N = 1 to 6")
        ax2.set_xlabel("k")
        ax2.set_ylabel("bounds on $x_2$")
        ax2.legend(loc="upper right")
        keep_artists(fig, "explore_svo", art)
    else:
        for patch, edge, V in zip(art["patches"], art["edges"], shapes):
            patch.set_xy(V)
            edge.set_data(np.r_[V[:, 0], V[0, 0]], np.r_[V[:, 1], V[0, 1]])
        art["band"].set_data(k, res.lower[:, 1], res.upper[:, 1])
        for line, bound in zip(art["exact"], (exact.lower, exact.upper)):
            line.set_data(k, bound[:, 1])
        art["true"].set_data(k, x[:, 1])
        for t, text in zip(art["titles"], titles):
            t.set_text(text)
    # set only where they change: an axes whose limits stay is not drawn again
    set_limits(art["ax"], xlim=_limits(box[:, 0]), ylim=_limits(box[:, 1]))
    set_limits(art["ax2"], xlim=_limits(k), ylim=_limits(shown))
    return fig


def horizon_study(
    delta_bounds=GRID["delta_bound"],
    horizons=range(1, MAX_HORIZON + 1),
    *,
    noise: float = 0.5,
    seed: int = 0,
    steps: int = 25,
) -> dict[str, Any]:
    """What the horizon N does to the SVO bounds of the explorable's record, for both rules.

    Returns
    -------
    dict
        ``exact_gap``: largest difference between a bound (either state, any sample) of the
        exact rule with horizon N >= 2 and with N = 1, over ``delta_bounds`` (rounding only: every
        older level of the exact rule's horizon contains the newest one); ``exact_width`` and
        ``template_width``: mean width of the bounds on x2 per delta bound (and per N for the
        template rule); ``template_inside``: whether the true state lies in every template set.
    """
    from fdi_lib.reproduce.rosa2013 import toy_prior

    gap, exact_width, template_width, inside = 0.0, {}, {}, True
    for db in delta_bounds:
        model, x, u, y, *_, exact = _example(float(db), float(noise), int(seed), int(steps))
        exact_width[db] = _mean_width(exact)
        template_width[db] = {}
        for n in horizons:
            if n > 1:
                ex_n = run_svo(model, u, y, toy_prior(), N=int(n), method="exact")
                _mean_width(ex_n)  # never empty
                gap = max(
                    gap,
                    float(
                        np.max(np.abs(np.r_[ex_n.lower - exact.lower, ex_n.upper - exact.upper]))
                    ),
                )
            tmp = _template_run(float(db), float(noise), int(seed), int(steps), int(n))
            template_width[db][n] = _mean_width(tmp)
            inside = inside and all(S.contains(x[i], 1e-7) for i, S in enumerate(tmp.sets))
    return {
        "exact_gap": gap,
        "exact_width": exact_width,
        "template_width": template_width,
        "template_inside": inside,
    }
