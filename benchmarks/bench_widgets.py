"""Benchmark: redraw time of every live widget of the book against the 100 ms target (issue 10).

A slider move in a live notebook calls the widget's callback with the figure it drew before
(``fdi_lib.widgets.interactive_figure``); what the slider does not change (models, gains,
signatures, noise records, Lasso paths) is cached by the callbacks. Reported per widget, after
a first call at the defaults (caches warm), median and best of ``REPEATS`` moves of one slider:

* ``compute + draw``: the callback (computation and artists) plus an Agg render of the figure,
  the issue's definition of a redraw (one core, default settings);
* ``+ PNG``: the same plus encoding the PNG that the inline backend sends to the notebook;
* ``CPU``: the process CPU time of compute + draw, which is what one free core would take (the
  wall time on a shared, loaded machine is several times larger); the verdict uses it.

Run: OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_widgets.py
The machine's load changes the figures; the report prints the load average beside them.
"""

from __future__ import annotations

import io
import os
import statistics
import time

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

from fdi_lib.widgets import bz, rosa2013, zb2014, zb2014_pipeline, zhang2021  # noqa: E402

TARGET_MS = 100.0
REPEATS = 5

# widget: (callback, the slider moved, two values it alternates between)
WIDGETS = {
    "explore_signature (onset)": (zb2014.explore_signature, "onset", (101, 201)),
    "explore_glr (fault size)": (zb2014.explore_glr, "fault_size", (1.5, 2.0)),
    "explore_glr (window)": (zb2014.explore_glr, "window", (100, 50)),
    "explore_pipeline (fault size)": (zb2014_pipeline.explore_pipeline, "fault_size_e5", (-2.0, -4.0)),
    "explore_sparse (lambda)": (zhang2021.explore_sparse, "lam_scale", (1.0, 0.3)),
    "explore_sparse (q)": (zhang2021.explore_sparse, "q", (5, 6)),
    "explore_bz (lambda)": (bz.explore_bz, "lam", (0.95, 0.9)),
    "explore_svo (bound)": (rosa2013.explore_svo, "delta_bound", (0.4, 0.3)),
}


def main() -> None:
    print(f"load average {os.getloadavg()[0]:.1f}; target {TARGET_MS:g} ms per redraw")
    print(f"{'widget':34s} {'compute+draw (wall)':>20s} {'best':>8s} {'+ PNG':>8s} {'CPU':>8s}  verdict")
    for name, (callback, slider, values) in WIDGETS.items():
        fig = callback()
        fig.canvas.draw()
        draw, png, cpu = [], [], []
        for i in range(REPEATS):
            t0, c0 = time.perf_counter(), time.process_time()
            fig = callback(**{slider: values[(i + 1) % 2]}, fig=fig)
            fig.canvas.draw()
            t1 = time.perf_counter()
            cpu.append(1e3 * (time.process_time() - c0))
            fig.savefig(io.BytesIO(), format="png")
            draw.append(1e3 * (t1 - t0))
            png.append(1e3 * (time.perf_counter() - t0))
        plt.close(fig)
        med, c = statistics.median(draw), statistics.median(cpu)
        verdict = "ok" if c <= TARGET_MS else f"{c / TARGET_MS:.1f}x over"
        print(f"{name:34s} {med:17.0f} ms {min(draw):5.0f} ms {statistics.median(png):5.0f} ms "
              f"{c:5.0f} ms  {verdict}")


if __name__ == "__main__":
    main()
