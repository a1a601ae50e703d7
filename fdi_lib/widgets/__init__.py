"""Interactive explorations for the book (ipywidgets).

Each chapter has a module here with a *tested, pure* callback
``explore_*(..., fig=None) -> Figure`` that the notebook wires to sliders via
:func:`interactive_figure`. The callback is what the book also calls once at
the default values to show a static figure, so the HTML is never empty.

Fast redraws (issue 10: a slider move in at most 100 ms of one core). A callback caches per
process what its sliders do not change (models, gains, noise records, signatures, Lasso
paths; :func:`batched_glr` for GLR records), and given the figure it drew before it moves
that figure's artists to round axis limits and draws only what changed, with the redraw
helpers of :mod:`fdi_lib.redraw` (which the reproductions use too).
``benchmarks/bench_widgets.py`` measures every widget.
"""

from __future__ import annotations

import dataclasses
import io
from typing import Any, Callable, Sequence

import numpy as np

from fdi_lib.errors import FDIError
from fdi_lib.redraw import render

__all__ = ["interactive_figure", "widget_png", "batched_glr"]


def batched_glr(
    cache: dict,
    key: tuple,
    size: float,
    grid: Sequence[float],
    innovations: Callable[[float], np.ndarray],
    run: Callable[[np.ndarray], Any],
    *,
    batch: int = 4,
    keep: int = 96,
) -> Any:
    """The windowed GLR (a ``WindowGLRResult``) of the record with fault ``size``.

    The windowed GLR's noise-independent precomputation (signatures, informations, their
    factors) is most of its cost and is shared by the realisations of one
    :func:`fdi_lib.glr.glr_window` call: up to ``batch`` records cost about as much as one. So
    a miss computes, with ``size``, the records of the values of ``grid`` (the explorable's
    fault sizes) not yet in ``cache`` (a dict kept by the caller, ``key`` + ``(size,)`` ->
    result, at most ``keep`` entries): the build's frames and later slider moves to those
    values find them there. The batch's linear algebra may differ from a single record's in the
    last bits (the tests compare with the reproduction at 1e-9).

    Parameters
    ----------
    innovations : callable
        ``size -> eps`` ``(N, p)``, the record's innovations.
    run : callable
        ``eps (B, N, p) -> WindowGLRResult``.
    """
    if key + (size,) not in cache:
        sizes = [size] + [g for g in grid if g != size and key + (g,) not in cache][: batch - 1]
        res = run(np.stack([innovations(g) for g in sizes]))
        for i, g in enumerate(sizes):
            cache[key + (g,)] = dataclasses.replace(
                res,
                **{
                    f: getattr(res, f)[i]
                    for f in ("statistic", "onset", "theta_hat", "C_hat", "d_hat")
                },
            )
        for old in list(cache)[: max(0, len(cache) - keep)]:  # oldest first (insertion order)
            del cache[old]
    return cache[key + (size,)]


def widget_png(fig: Any) -> bytes:
    """``fig`` as the PNG a live widget shows: :func:`fdi_lib.redraw.render` at ``RASTER_SCALE``
    times the display resolution (sharp on high-density screens), encoded by Pillow at a fast
    compression level."""
    from fdi_lib.plotting import DISPLAY_DPI, RASTER_SCALE

    dpi = DISPLAY_DPI * RASTER_SCALE
    if fig.dpi != dpi:
        fig.set_dpi(dpi)
    render(fig)
    return _encode_png(fig)


def _encode_png(fig: Any) -> bytes:
    # the canvas as an RGB PNG; level 1 is several times faster than the default (6) for a
    # file about 25 % larger, which a notebook's kernel sends in well under a millisecond
    from PIL import Image

    canvas = fig.canvas
    img = Image.frombuffer(
        "RGBA", canvas.get_width_height(physical=True), canvas.buffer_rgba(), "raw", "RGBA", 0, 1
    )
    out = io.BytesIO()
    img.convert("RGB").save(out, format="PNG", compress_level=1)
    return out.getvalue()


def interactive_figure(callback: Callable[..., Any], **sliders: Any):
    """Wire ``callback(**values, fig=fig)`` to ipywidgets sliders (``continuous_update=False``).

    Every slider move calls the callback with the figure it drew before and shows
    :func:`widget_png` of it in an image widget (replaced in place: no flicker, no second
    render for a tight bounding box, a fast PNG encoding).

    Parameters
    ----------
    callback : callable
        Pure function drawing into ``fig`` and returning it.
    **sliders : ipywidgets.ValueWidget
        One widget per keyword argument of ``callback``.

    Returns
    -------
    ipywidgets.VBox
        The sliders above the image of the figure (and the message of a bad value, if any).
    """
    import ipywidgets as widgets
    import matplotlib.pyplot as plt

    from fdi_lib.plotting import FIG_WIDTH_IN, DISPLAY_DPI

    for w in sliders.values():
        if hasattr(w, "continuous_update"):
            w.continuous_update = False
    state: dict[str, Any] = {"fig": None}
    image = widgets.Image(
        format="png",
        width=round(FIG_WIDTH_IN * DISPLAY_DPI),
        layout=widgets.Layout(max_width="100%", height="auto"),
    )

    errors = widgets.Output()  # the message of a bad value, below the figure

    def redraw(_change: Any = None) -> None:
        errors.outputs = ()
        try:
            fig = callback(**{k: w.value for k, w in sliders.items()}, fig=state["fig"])
        except FDIError as exc:  # a typed error of a bad value: say why, keep the last figure
            errors.append_stdout(f"{type(exc).__name__}: {exc}\n")
            return
        if fig is not state["fig"]:
            # shown in the image widget only: keep pyplot from showing it again at the end of the
            # cell (a closed figure can still be redrawn by the next callback)
            plt.close(fig)
            state["fig"] = fig
        image.value = widget_png(fig)

    for w in sliders.values():
        w.observe(redraw, names="value")
    redraw()
    return widgets.VBox(
        [
            widgets.HBox(list(sliders.values())[:3]),
            widgets.HBox(list(sliders.values())[3:]),
            image,
            errors,
        ]
    )
