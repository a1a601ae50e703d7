"""Fast redraws of the widgets: the pixels equal a full draw, and the fast paths are taken.

:func:`fdi_lib.redraw.render` redraws only what a slider move changed (a saved background, the
dynamic artists over it, the stale axes alone). Every picture it makes is compared, pixel for
pixel, with ``savefig`` of the same figure (a full draw of every artist); the draws themselves
are counted, so that a test fails if a move that changes no limit draws the whole figure.
"""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from PIL import Image  # noqa: E402

import fdi_lib.redraw as fr  # noqa: E402
from fdi_lib.errors import ModelError  # noqa: E402
from fdi_lib.plotting import DISPLAY_DPI, RASTER_SCALE, figure  # noqa: E402
from fdi_lib.reproduce.zb2014 import unstable_run  # noqa: E402
from fdi_lib.reproduce.zb2014_pipeline import single_run  # noqa: E402
from fdi_lib.glr import glr_window  # noqa: E402
from fdi_lib.redraw import (
    keep_artists,
    render,
    reusable_artists,
    stepped_limit,  # noqa: E402
    stepped_range,
)
from fdi_lib.widgets import (
    batched_glr,
    bz,
    rosa2013,
    widget_png,
    zb2014,
    zb2014_pipeline,  # noqa: E402
    zhang2021,
)


@pytest.fixture
def draws(monkeypatch):
    """Counts of full draws and of axes drawn alone by render()."""
    count = {"full": 0, "axes": 0}
    full, alone = FigureCanvasAgg.draw, fr._redraw_axes

    def counted_full(self):
        count["full"] += 1
        full(self)

    def counted_alone(fig, renderer, axes, regions):
        count["axes"] += len(axes)
        return alone(fig, renderer, axes, regions)

    monkeypatch.setattr(FigureCanvasAgg, "draw", counted_full)
    monkeypatch.setattr(fr, "_redraw_axes", counted_alone)
    return count


def full_draw(fig):
    """The figure drawn in full (every artist, animated ones included), as an RGBA array."""
    buf = io.BytesIO()
    fig.savefig(buf, format="rgba", dpi=fig.dpi)
    # savefig marks the figure stale; the widget never saves it: undo that for the next move
    fig.stale = False
    for ax in fig.axes:
        ax.stale = False
    w, h = fig.canvas.get_width_height(physical=True)
    return np.frombuffer(buf.getvalue(), np.uint8).reshape(h, w, 4)


# callback, slider, values visited in order: moves within the same limits, across a step of
# the limits of one panel, and across all of them
MOVES = {
    "signature": (zb2014.explore_signature, "onset", (201, 301, 1, 451)),
    "glr fault size": (zb2014.explore_glr, "fault_size", (1.6, 2.0, 0.0, 3.0)),
    "glr window": (zb2014.explore_glr, "window", (50, 10, 200)),
    "pipeline fault size": (
        zb2014_pipeline.explore_pipeline,
        "fault_size_e5",
        (-2.5, -4.0, 0.0, -10.0),
    ),
    "sparse lambda": (zhang2021.explore_sparse, "lam_scale", (0.3, 0.01, 10.0)),
    "sparse q": (zhang2021.explore_sparse, "q", (6, 1, 25)),
    "bz lambda": (bz.explore_bz, "lam", (0.9, 0.8, 1.0)),
    "bz fault size": (bz.explore_bz, "f_size", (0.0, 0.5)),
    "bz drift speed": (bz.explore_bz, "delta", (1e-3, 3e-4, 0.0, 2e-3)),
    "svo horizon": (rosa2013.explore_svo, "horizon", (2, 4, 1)),
    "svo bound": (rosa2013.explore_svo, "delta_bound", (0.0, 1.0, 0.6)),
}


@pytest.mark.parametrize("name", list(MOVES))
@pytest.mark.parametrize("dpi", [DISPLAY_DPI, DISPLAY_DPI * RASTER_SCALE])
def test_every_redraw_equals_a_full_draw(name, dpi, draws):
    callback, slider, values = MOVES[name]
    fig = callback()
    fig.set_dpi(dpi)
    render(fig)
    assert draws["full"] == 1
    for value in values:
        fig = callback(**{slider: value}, fig=fig)
        render(fig)
        got = np.asarray(fig.canvas.buffer_rgba()).copy()
        np.testing.assert_array_equal(got, full_draw(fig), err_msg=f"{name} = {value}")
    plt.close(fig)


def test_moves_that_keep_the_limits_draw_no_axes(draws):
    fig = zb2014.explore_glr()
    render(fig)
    for window in (50, 150, 100):  # the same limits: only the curves move
        fig = zb2014.explore_glr(window=window, fig=fig)
        render(fig)
    assert draws == {"full": 1, "axes": 0}
    fig = zb2014.explore_glr(fault_size=2.0, fig=fig)  # l_k's limit 300 -> 500: that axes alone
    render(fig)
    assert draws == {"full": 1, "axes": 1}
    # the next move within the limits: nothing is drawn again
    fig = zb2014.explore_glr(fault_size=2.0, threshold=25.0, fig=fig)
    render(fig)
    assert draws == {"full": 1, "axes": 1}
    np.testing.assert_array_equal(np.array(fig.canvas.buffer_rgba()), full_draw(fig))
    plt.close(fig)


def test_new_tick_labels_wider_than_before_are_drawn_with_their_axes_alone(draws):
    # the drift speed 3e-4 -> 1e-3 changes the limits of two panels of three (theta_k 0.1 ->
    # 0.3, l_k 100 -> 1000: wider tick labels): those two are drawn again, inside the regions
    # grown into the blank space around them, and the pixels equal a full draw
    fig = bz.explore_bz()
    render(fig)
    fig = bz.explore_bz(delta=1e-3, fig=fig)
    assert [ax.stale for ax in fig.axes] == [True, False, True]
    render(fig)
    assert draws == {"full": 1, "axes": 2}
    np.testing.assert_array_equal(np.array(fig.canvas.buffer_rgba()), full_draw(fig))
    plt.close(fig)


def test_a_static_line_outside_its_frame_keeps_the_next_region_away(draws):
    # the lower axes draws an unclipped static line up into the gap between the panels: the
    # region of the upper axes, grown towards it, must stop short of it
    def callback(a, fig=None):
        art = reusable_artists(fig, "toy")
        if art is None:
            fig, axes = figure(2, 1, fig=fig, figsize=(6.0, 4.0))
            top, bottom = axes[:, 0]
            bottom.plot([0.5, 0.5], [0.0, 1.3], transform=bottom.transAxes, clip_on=False, lw=3)
            bottom.set_ylim(0, 1)
            art = {"line": top.plot([0, 1], [a, a])[0], "top": top}
            keep_artists(fig, "toy", art)
        art["line"].set_ydata([a, a])
        fr.set_limits(art["top"], ylim=(0.0, fr.stepped_limit(a)))
        return fig

    fig = callback(0.9)
    render(fig)
    fig = callback(2.5, fig=fig)  # new limits of the upper axes: that axes alone
    render(fig)
    assert draws == {"full": 1, "axes": 1}
    np.testing.assert_array_equal(np.array(fig.canvas.buffer_rgba()), full_draw(fig))
    plt.close(fig)


def test_a_changed_static_artist_is_drawn_and_other_figures_are_drawn_in_full(draws):
    fig = zb2014.explore_signature()
    render(fig)
    fig.axes[1].set_ylim(
        0.1, 1e40
    )  # a change that no dynamic artist holds: that axes is drawn again
    render(fig)
    assert draws == {"full": 1, "axes": 1}
    np.testing.assert_array_equal(np.array(fig.canvas.buffer_rgba()), full_draw(fig))  # a copy
    before = dict(draws)  # (savefig draws in full too)
    fig.set_size_inches(5.5, 4.0)  # a new size: everything
    render(fig)
    assert draws == {"full": before["full"] + 1, "axes": 1}
    np.testing.assert_array_equal(np.array(fig.canvas.buffer_rgba()), full_draw(fig))  # a copy
    before = dict(draws)
    plain, ax = figure()
    ax[0, 0].plot([0, 1], [1, 0])
    render(plain)
    render(plain)  # a figure without kept artists: a full draw each time
    assert draws == {"full": before["full"] + 2, "axes": 1}
    plt.close(plain)
    plt.close(fig)  # a closed pyplot figure loses its Agg canvas: render gives it one
    png = widget_png(zb2014.explore_signature(onset=301, fig=fig))
    assert Image.open(io.BytesIO(png)).size == (
        round(5.5 * DISPLAY_DPI * RASTER_SCALE),
        round(4.0 * DISPLAY_DPI * RASTER_SCALE),
    )


def test_keep_artists_animates_the_dynamic_artists_and_what_is_drawn_over_them():
    def callback(a, fig=None):
        art = reusable_artists(fig, "toy")
        if art is None:
            fig, ax = figure(fig=fig)
            ax = ax[0, 0]
            ax.plot([0, 1], [0, 0], zorder=1.8, label="static")
            art = {"line": ax.plot([0, 1], [a, a], label="moves")[0], "axes": ax}
            ax.legend()
            keep_artists(fig, "toy", art)
        art["line"].set_ydata([a, a])
        return fig

    fig = callback(1.0)
    ax = fig.axes[0]
    static, moving = ax.lines
    assert not static.get_animated() and moving.get_animated()
    assert ax.get_legend().get_animated() and all(s.get_animated() for s in ax.spines.values())
    assert not ax.xaxis.get_animated() and not ax.get_animated()
    assert callback(2.0, fig=fig) is fig and moving.get_ydata()[0] == 2.0
    plt.close(fig)


@pytest.mark.parametrize(
    "value, log, expected",
    [
        (1.34, False, 2.0),
        (2.0, False, 2.0),
        (3.01, False, 5.0),
        (5.0, False, 5.0),
        (5.2, False, 10.0),
        (0.031, False, 0.05),
        (216.0, False, 300.0),
        (91.0, True, 100.0),
        (101.0, True, 1000.0),
        (0.3, True, 1.0),
    ],
)
def test_stepped_limit(value, log, expected):
    assert stepped_limit(value, log=log) == pytest.approx(expected, rel=1e-12)


def test_stepped_range_holds_the_data_with_a_margin():
    assert stepped_range([0.0, 1.9]) == (pytest.approx(-0.1), 2.0)
    assert stepped_range([-0.3, 1.34], symmetric=True) == (-2.0, 2.0)
    assert stepped_range([-31922.0, 28432.0]) == (-50000.0, 30000.0)
    assert stepped_range([-4.0, -1.0]) == (-5.0, 0.25)
    assert stepped_range([-0.001, 1.9]) == (pytest.approx(-0.1), 2.0)  # 0 is not on the frame
    lo, hi = stepped_range([0.085, np.nan, 91.4, 0.0], log=True)
    assert lo == pytest.approx(0.01) and hi == pytest.approx(100.0)
    assert stepped_range([np.nan]) == (-0.05, 1.0)
    with pytest.raises(ModelError, match="value: expected a positive finite number, got 0.0"):
        stepped_limit(0.0)


def test_glr_widget_equals_unstable_run():
    # the widget adds the fault's signature to the cached fault-free innovation: the same
    # innovations, statistic and alarm as simulating with the fault
    for fault, onset, window, seed in [(1.5, 201, 100, 0), (3.0, 50, 10, 3), (0.7, 400, 200, 1)]:
        fig = zb2014.explore_glr(fault_size=fault, onset=onset, window=window, seed=seed)
        run = unstable_run(
            theta=(fault, 0.0), onset=onset, window=window, threshold=20.0, seed=seed
        )
        top, bottom = fig.axes
        scale = np.abs(run.innovations).max()
        np.testing.assert_allclose(
            top.lines[0].get_ydata(), run.innovations, rtol=0, atol=1e-12 * scale
        )
        np.testing.assert_allclose(
            bottom.lines[0].get_ydata(), run.glr.statistic, rtol=1e-9, atol=1e-9, equal_nan=True
        )
        expected = "no alarm" if run.alarm < 0 else f"alarm after {run.alarm - onset} samples"
        assert top.get_title().endswith(expected)
        plt.close(fig)


def test_glr_widget_caches_give_the_uncached_computation_exactly():
    # the noise innovation is cached per seed (it does not depend on the onset) and the windowed
    # GLR's noise-independent arrays per window: the same bits as computing them for the move
    from fdi_lib.filters import kalman_filter
    from fdi_lib.models import impulse_family
    from fdi_lib.simulate import simulate
    from fdi_lib.systems import zb2014_unstable as ex

    model, gains = zb2014._unstable_setup()
    fam = impulse_family(model)
    for onset, seed, window in [(10, 0, 100), (201, 1, 25), (490, 0, 200)]:
        sim = simulate(
            model,
            rng=np.random.default_rng(seed),
            controller=ex.controller(),
            fault=fam.profile(onset),
            theta=np.zeros(fam.m),
        )
        eps = kalman_filter(model, sim.y, sim.u, gains=gains).innovations[:, 0]
        _, eps_noise, eps_fault = zb2014._glr_record(onset, seed)
        np.testing.assert_array_equal(eps_noise, eps)
        records = np.stack([eps + eps_fault[:, 0] * size for size in (1.5, 0.0)])[..., None]
        alone = glr_window(records, model, gains, fam, window=window)
        cached = glr_window(
            records,
            model,
            gains,
            zb2014._impulse_family(),
            window=window,
            shared=zb2014._shared_glr(window),
        )
        for f in ("statistic", "onset", "theta_hat", "C_hat", "d_hat"):
            np.testing.assert_array_equal(getattr(cached, f), getattr(alone, f))


def test_pipeline_widget_equals_single_run():
    for size, fault, window, seed, threshold in [
        (-2.0, 1, 160, 0, 50.0),
        (-10.0, 2, 40, 3, 20.0),
        (-1.0, 1, 250, 1, 5.0),
    ]:
        fig = zb2014_pipeline.explore_pipeline(
            fault_size_e5=size, fault=fault, window=window, seed=seed, threshold=threshold
        )
        run = single_run(
            seed=seed, fault=fault, delta=size * 1e-5, threshold=threshold, window=window
        )
        top, bottom = fig.axes
        scale = np.abs(run.innovations).max()
        np.testing.assert_allclose(
            top.lines[0].get_ydata(), run.innovations, rtol=0, atol=1e-12 * scale
        )
        stat = np.where(run.statistic > 0, run.statistic, np.nan)
        np.testing.assert_allclose(bottom.lines[0].get_ydata(), stat, rtol=1e-9, equal_nan=True)
        alarm = bottom.lines[-2]  # the alarm line, hidden when there is none
        assert alarm.get_visible() == (run.alarm >= 0)
        if run.alarm >= 0:
            assert alarm.get_xdata()[0] == run.alarm_time_min
        plt.close(fig)


def test_batched_glr_computes_a_few_grid_values_with_the_asked_one_and_forgets_the_oldest():
    calls = []

    def run(eps):
        calls.append(eps.shape[0])
        return glr_window(eps, model, gains, fam, window=20)

    model, gains = zb2014._unstable_setup()
    fam, eps_noise, eps_fault = zb2014._glr_record(201, 0)

    def innovations(size):
        return (eps_noise + eps_fault[:, 0] * size)[:, None]

    cache = {}
    got = batched_glr(
        cache, ("k",), 0.7, (0.0, 0.7, 1.0, 2.0, 3.0), innovations, run, batch=3, keep=4
    )
    assert calls == [3] and set(cache) == {("k", 0.7), ("k", 0.0), ("k", 1.0)}
    alone = glr_window(innovations(0.7), model, gains, fam, window=20)
    np.testing.assert_allclose(got.statistic, alone.statistic, rtol=1e-9, equal_nan=True)
    np.testing.assert_array_equal(got.onset, alone.onset)
    assert got.theta_hat.shape == alone.theta_hat.shape and got.window == 20
    assert batched_glr(cache, ("k",), 1.0, (), innovations, run) is cache[("k", 1.0)] and calls == [
        3
    ]
    batched_glr(cache, ("k",), 2.0, (0.0, 2.0, 3.0), innovations, run, batch=3, keep=4)
    assert calls == [3, 2] and list(cache) == [("k", 0.0), ("k", 1.0), ("k", 2.0), ("k", 3.0)]


def test_a_plain_draw_of_a_widget_figure_shows_its_moving_artists_too():
    # an interactive backend (or ipympl) calls canvas.draw(), which leaves animated artists
    # out: the draw-event hook of keep_artists adds them, once
    fig = zb2014.explore_glr()
    fig = zb2014.explore_glr(fault_size=2.5, fig=fig)
    fig.canvas.draw()
    np.testing.assert_array_equal(np.array(fig.canvas.buffer_rgba()), full_draw(fig))  # a copy
    render(fig)  # and render's own draws are not drawn over twice
    np.testing.assert_array_equal(np.array(fig.canvas.buffer_rgba()), full_draw(fig))  # a copy
    plt.close(fig)
