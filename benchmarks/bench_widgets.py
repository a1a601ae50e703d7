"""Benchmark: redraw time of every live widget and frame time of every explorable (issue 10).

Live widgets. A slider move in a live notebook calls the widget's callback with the figure it
drew before and shows :func:`fdi_lib.widgets.widget_png` of it (``interactive_figure``); what
the slider does not change (models, gains, signatures, noise records, Lasso paths) is cached by
the callbacks. Reported per widget, after a first call at the defaults (caches warm), as the
median process CPU time (what one free core takes; the wall time on a shared, loaded machine is
larger) of ``REPEATS`` moves of one slider between two values:

* ``move``: callback + :func:`fdi_lib.redraw.render` at the widget's resolution (2x), the
  issue's definition of a redraw (compute and Agg draw, one core, default settings); the
  verdict uses it (target 100 ms, aim 60 ms);
* ``all axes``: the same move with every axes drawn again (what a move costs when it changes
  the limits of every panel; :func:`render` then redraws the whole figure);
* ``+ PNG``: encoding the PNG that the image widget shows.

The two values of each slider cross a step of the round axis limits where they do (then the
axes whose limits change are drawn again: the ``move`` column includes that). Before every timed
move the widgets' caches of per-value results hold only what the start value left there (GLR
and noise records, Lasso paths, RLS gains): the move computes what a move to a value not seen
before computes.

Explorables. For each chapter's explorable (:func:`fdi_lib.explorables.explorable` over the
chapter's grid, as its cell runs it, per-process caches of the widgets cold) the CPU time of all
its frames (target 2.5 s per cell) and its page weight (target 3 MB).

Run: OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_widgets.py [--no-explorables]
The machine's load changes the figures; the report prints the load average beside them.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
from _record import record  # noqa: E402

from fdi_lib.explorables import explorable  # noqa: E402
from fdi_lib.plotting import DISPLAY_DPI, RASTER_SCALE  # noqa: E402
from fdi_lib.redraw import render  # noqa: E402
from fdi_lib.reproduce import bz_setup  # noqa: E402
from fdi_lib.widgets import (
    _encode_png,
    bz,
    rosa2013,
    zb2014,
    zb2014_pipeline,  # noqa: E402
    zhang2021,
)
from fdi_lib.widgets.explorables import EXPLORABLES  # noqa: E402

TARGET_MS = 100.0
AIM_MS = 60.0
FRAMES_TARGET_S = 2.5
PAGE_TARGET_MB = 3.0
REPEATS = 5
#: The widgets' caches of results per slider value (what does not depend on a slider stays)
CACHE_CLEARS = (
    zb2014._GLR_CACHE.clear,
    zb2014._glr_record.cache_clear,
    zb2014._noise_innovations.cache_clear,
    zb2014._shared_glr.cache_clear,
    zb2014_pipeline._GLR_CACHE.clear,
    zb2014_pipeline._noise_innovations.cache_clear,
    zhang2021._trial_path.cache_clear,
    bz._record.cache_clear,
    bz_setup.regressor_rls_gains.cache_clear,  # the RLS gains per lambda (shared with the chapter)
    rosa2013._example.cache_clear,  # per uncertainty bound
    rosa2013._template_run.cache_clear,  # per uncertainty bound and horizon
)

# widget: (callback, the slider moved, two values it alternates between; the second value of a
# fault size is not on the explorable's grid, whose GLR records batched_glr computes together)
WIDGETS = {
    "explore_signature (onset)": (zb2014.explore_signature, "onset", (101, 201)),
    "explore_glr (fault size)": (zb2014.explore_glr, "fault_size", (1.5, 2.5)),
    "explore_glr (window)": (zb2014.explore_glr, "window", (100, 50)),
    "explore_pipeline (fault size)": (
        zb2014_pipeline.explore_pipeline,
        "fault_size_e5",
        (-2.0, -3.0),
    ),
    "explore_pipeline (window)": (zb2014_pipeline.explore_pipeline, "window", (160, 80)),
    "explore_sparse (lambda)": (zhang2021.explore_sparse, "lam_scale", (1.0, 0.3)),
    "explore_sparse (q)": (zhang2021.explore_sparse, "q", (5, 6)),
    "explore_bz (lambda)": (bz.explore_bz, "lam", (0.95, 0.9)),
    "explore_bz (fault size)": (bz.explore_bz, "f_size", (0.2, 0.3)),
    "explore_glr (onset)": (zb2014.explore_glr, "onset", (201, 150)),
    "explore_glr (threshold)": (zb2014.explore_glr, "threshold", (20.0, 40.0)),
    "explore_pipeline (seed)": (zb2014_pipeline.explore_pipeline, "seed", (0, 1)),
    "explore_pipeline (threshold)": (zb2014_pipeline.explore_pipeline, "threshold", (50.0, 60.0)),
    "explore_sparse (r)": (zhang2021.explore_sparse, "r", (0.5, 1.0)),
    "explore_sparse (seed)": (zhang2021.explore_sparse, "seed", (0, 1)),
    "explore_bz (drift speed)": (bz.explore_bz, "delta", (3e-4, 1e-3)),
    "explore_svo (bound)": (rosa2013.explore_svo, "delta_bound", (0.4, 0.3)),
    "explore_svo (horizon)": (rosa2013.explore_svo, "horizon", (1, 2)),
}


def _cpu_ms(f) -> float:
    c0 = time.process_time()
    f()
    return 1e3 * (time.process_time() - c0)


def reset_caches() -> None:
    """Empty the widgets' caches of per-slider-value results."""
    for clear in CACHE_CLEARS:
        clear()


def bench_widget(name: str) -> None:
    callback, slider, values = WIDGETS[name]
    fig = callback(**{slider: values[0]})
    fig.set_dpi(DISPLAY_DPI * RASTER_SCALE)  # the live widget's resolution
    render(fig)
    moves, full, png = [], [], []

    def at(value):
        # untimed: the figure and the caches as a reader who has only been at `value` leaves them
        nonlocal fig
        reset_caches()
        fig = callback(**{slider: value}, fig=fig)
        render(fig)

    for _ in range(REPEATS):
        at(values[0])

        def move():
            nonlocal fig
            fig = callback(**{slider: values[1]}, fig=fig)
            render(fig)

        moves.append(_cpu_ms(move))
        png.append(_cpu_ms(lambda: _encode_png(fig)))  # what widget_png adds to the render
        at(values[1])

        def move_all():
            nonlocal fig
            fig = callback(**{slider: values[0]}, fig=fig)
            for ax in fig.axes:
                ax.stale = True
            render(fig)

        full.append(_cpu_ms(move_all))
    plt.close(fig)
    med = statistics.median(moves)
    verdict = "ok" if med <= AIM_MS else "ok (over the 60 ms aim)" if med <= TARGET_MS else "over"
    print(
        f"{name:32s} {med:6.0f} ms {statistics.median(full):9.0f} ms {statistics.median(png):7.0f} ms  {verdict}"
    )
    record(
        f"live widget redraw, {name} (CPU, move)",
        med,
        "ms",
        TARGET_MS,
        note=f"all axes redrawn {statistics.median(full):.0f} ms; PNG {statistics.median(png):.0f} ms",
    )


def bench_explorable(name: str) -> None:
    callback, grid = EXPLORABLES[name]
    t0 = time.process_time()
    ex = explorable(callback, grid, caption=name)
    cpu = time.process_time() - t0
    n = len(ex.frames)
    print(
        f"{name:28s} {n:4d} frames {cpu:6.2f} s ({1e3 * cpu / n:4.0f} ms/frame) page {ex.nbytes / 1e6:5.2f} MB"
    )
    record(f"explorable {name}, {n} frames (CPU)", cpu, "s", FRAMES_TARGET_S)
    record(f"explorable {name}, page weight", ex.nbytes / 1e6, "MB", PAGE_TARGET_MB)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--no-explorables", action="store_true", help="live widgets only")
    args = parser.parse_args()
    if not args.no_explorables:
        # first, with the widgets' per-process caches cold, as in a chapter
        print(
            f"load average {os.getloadavg()[0]:.1f}; explorables: target {FRAMES_TARGET_S:g} s "
            f"of CPU per cell, {PAGE_TARGET_MB:g} MB per page"
        )
        for name in EXPLORABLES:
            bench_explorable(name)
    print(
        f"load average {os.getloadavg()[0]:.1f}; live widgets: target {TARGET_MS:g} ms (aim {AIM_MS:g} ms) "
        f"of CPU per redraw, median of {REPEATS} moves"
    )
    print(f"{'widget':32s} {'move':>9s} {'all axes':>12s} {'+ PNG':>10s}  verdict")
    for name in WIDGETS:
        bench_widget(name)


if __name__ == "__main__":
    main()
