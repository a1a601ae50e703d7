"""Redraw helpers for figures that a slider moves: one home below the reproductions and the widgets.

A plotting function given the figure it drew before moves that figure's artists
(:func:`reusable_artists`, :func:`keep_artists`) to round axis limits (:func:`stepped_range`,
:func:`set_limits`) instead of rebuilding and laying out a new figure; :func:`render` then draws
only what changed: the static rest of the picture (axes, grid, ticks and their text, which cost
most of a draw) is saved once and restored, and the axes whose limits changed are drawn again
alone. The reproductions (``fdi_lib.reproduce``) and the widgets (``fdi_lib.widgets``) both use
them; matplotlib is imported only where a function needs it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fdi_lib.errors import ModelError

__all__ = [
    "keep_artists",
    "render",
    "reusable_artists",
    "set_limits",
    "stepped_limit",
    "stepped_range",
]

_ARTISTS = "_fdi_widget_artists"
_BACKGROUND = "_fdi_widget_background"
_DRAW_HOOK = "_fdi_widget_draw_hook"
_RENDERING = "_fdi_widget_rendering"


def keep_artists(fig: Any, key: str, artists: dict[str, Any]) -> None:
    """Remember on ``fig`` the artists a callback ``key`` drew, for :func:`reusable_artists`.

    Every artist among the values of ``artists`` (a value may also be a list or tuple of
    artists), other than an ``Axes``, is *dynamic*: the callback changes it at the next slider
    move. It is animated, and so is everything its axes draws after it (higher z-order): a full
    draw leaves them out and :func:`render` draws them over the saved rest of the picture, in
    the same order as a full draw. Saving the figure (``savefig``, the book's PNGs) draws
    everything as usual, and so does any other draw of the figure (``canvas.draw()``, an
    interactive backend): a draw-event hook adds the animated artists.
    """
    setattr(fig, _ARTISTS, (key, artists))
    setattr(fig, _BACKGROUND, None)
    if not getattr(fig, _DRAW_HOOK, False):
        # a plain draw (an interactive backend, ipympl, canvas.draw()) still shows everything
        fig.canvas.mpl_connect("draw_event", _draw_dynamic)
        setattr(fig, _DRAW_HOOK, True)
    fig.set_layout_engine("constrained")  # a new figure is laid out at its next draw
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes

    dynamic = set()
    for value in artists.values():
        for a in value if isinstance(value, (list, tuple)) else (value,):
            if isinstance(a, Artist) and not isinstance(a, Axes):
                dynamic.add(id(a))
    for ax in fig.axes:
        above = False
        for a in _draw_order(ax):
            above = above or id(a) in dynamic
            # with its parts (a legend's texts): a change of a part of an animated artist must
            # not mark the axes stale either
            for part in a.findobj():
                part.set_animated(above)


def _draw_dynamic(event: Any) -> None:
    # after a plain draw of a figure that keep_artists set up (not render's own, not savefig's,
    # which both draw the animated artists themselves): draw them over it
    fig = event.canvas.figure
    if getattr(fig, _RENDERING, False) or event.canvas.is_saving():
        return
    _draw_animated(fig, event.renderer)


def _draw_animated(fig: Any, renderer: Any) -> None:
    for ax in fig.axes:
        for a in _draw_order(ax):
            if a.get_animated() and a.get_visible():
                a.draw(renderer)
    # (the parts of an animated artist are animated too: drawing them marks nothing stale)


def _draw_order(ax: Any) -> list[Any]:
    # the order in which Axes.draw draws its children: patch first, then by z-order (stable)
    children = [a for a in ax.get_children() if a is not ax.patch]
    return [ax.patch, *sorted(children, key=lambda a: a.get_zorder())]


def reusable_artists(fig: Any, key: str) -> dict[str, Any] | None:
    """The artists that callback ``key`` kept on ``fig`` (``None``: draw the figure anew).

    A callback that finds its own artists on the figure it is given updates their data instead
    of clearing and rebuilding the figure: a slider move then costs the computation and one
    :func:`render` without a new layout (issue 10, redraw <= 100 ms). Any other figure (or
    ``None``) is rebuilt and laid out anew by :func:`keep_artists`.
    """
    kept = getattr(fig, _ARTISTS, None) if fig is not None else None
    if kept is None or kept[0] != key or not kept[1]:
        return None
    # Moving artists keeps the layout the figure was last drawn with: the constrained layout,
    # half of a render, is not redone (the panels also stay put between slider values).
    fig.set_layout_engine("none")
    return kept[1]


def render(fig: Any) -> None:
    """Draw ``fig`` on its Agg canvas (``fig.canvas.buffer_rgba()``), as a full draw would.

    For a figure whose callback kept its artists (:func:`keep_artists`), the first call draws
    everything but the dynamic artists and saves that picture (axes, grid, ticks, labels:
    most of the cost of a draw is their text); later calls restore it and draw only the
    dynamic artists. A change of a static artist or of the limits marks its axes stale: unless
    every axes is stale, only the stale axes are then drawn again, over their own region of the
    saved picture (regions that do not overlap, each grown into the blank space around its axes
    for new tick labels; otherwise, or after a change of size or resolution, everything is
    drawn again). Any other figure is drawn in full. The tests compare the pixels with a full
    draw.
    """
    canvas = fig.canvas
    if not hasattr(canvas, "copy_from_bbox"):  # e.g. a figure closed by pyplot has no Agg canvas
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        canvas = FigureCanvasAgg(fig)
    if getattr(fig, _ARTISTS, None) is None:
        canvas.draw()
        return
    saved = getattr(fig, _BACKGROUND, None)
    state = (canvas.get_width_height(physical=True), fig.dpi)
    renderer = canvas.get_renderer()
    stale = [ax for ax in fig.axes if ax.stale]
    full = (
        saved is None
        or saved[0] != state
        or (fig.stale and not stale)
        or (stale and saved[2] is None)
        or len(stale) == len(fig.axes)
    )  # every axes changed: drawing all is cheaper (2 of 3 alone: 108-122 ms against 133-145
    # for explore_bz's drift speed, the regions grown by _static_regions)
    if not full:
        canvas.restore_region(saved[1])
        if stale:  # draw the stale axes again over their part of the picture, save the result
            full = not _redraw_axes(fig, renderer, stale, saved[2])
            if not full:
                setattr(fig, _BACKGROUND, (state, canvas.copy_from_bbox(fig.bbox), saved[2]))
                # the stale axes marked the figure stale: it is now drawn (otherwise the next
                # render would draw it in full, see `fig.stale and not stale`)
                fig.stale = False
    if full:
        setattr(fig, _RENDERING, True)
        try:
            canvas.draw()  # everything static (animated artists are left out)
        finally:
            setattr(fig, _RENDERING, False)
        renderer = canvas.get_renderer()
        background = canvas.copy_from_bbox(fig.bbox)
        setattr(fig, _BACKGROUND, (state, background, _static_regions(fig, renderer)))
    _draw_animated(fig, renderer)


def _static_regions(fig: Any, renderer: Any) -> dict[Any, tuple[int, int, int, int]] | None:
    """Pixel box ``(x0, y0, x1, y1)`` (rows from the top) of what each axes draws, or ``None`` if
    an axes may not be redrawn alone: boxes that overlap, or figure-level artists."""
    if (
        fig.texts
        or fig.legends
        or fig.patches
        or fig.lines
        or fig.images
        or fig.artists
        or fig.patch.get_facecolor()[3] != 1.0
    ):
        return None
    width, height = fig.canvas.get_width_height(physical=True)
    regions = {}
    for ax in fig.axes:
        x0, y0, x1, y1 = _static_box(ax, renderer)
        regions[ax] = (x0 - 1, height - y1 - 1, x1 + 1, height - y0 + 1)  # rows from the top
    if _overlap(list(regions.values())):
        return None
    # Each region then grows into the blank space around it (the figure's background, up to
    # halfway to the next axes): new tick labels, wider or taller after a change of the limits,
    # are then still drawn inside it, and the axes is redrawn alone instead of the figure.
    wide = {ax: _grown(r, regions.values(), width, height) for ax, r in regions.items()}
    return regions if _overlap(list(wide.values())) else wide


def _overlap(boxes: list[tuple[int, int, int, int]]) -> bool:
    """Whether two of the boxes ``(x0, y0, x1, y1)`` overlap."""
    for i, a in enumerate(boxes):
        for b in boxes[i + 1 :]:
            if a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]:
                return True
    return False


def _grown(box: tuple[int, int, int, int], boxes: Any, width: int, height: int) -> tuple[int, ...]:
    """``box`` grown left and right, then up and down, to halfway to the nearest of the other
    ``boxes`` (which ``box`` does not overlap) that it would meet, or to the figure's edge."""
    x0, y0, x1, y1 = box
    others = [b for b in boxes if b != box]
    rows = [b for b in others if b[1] < y1 and y0 < b[3]]  # beside it
    left = max([b[2] for b in rows if b[2] <= x0], default=None)
    right = min([b[0] for b in rows if b[0] >= x1], default=None)
    x0 = 0 if left is None else (left + x0) // 2
    x1 = width if right is None else (right + x1) // 2
    cols = [b for b in others if b[0] < x1 and x0 < b[2]]  # above or below it, as grown
    above = max([b[3] for b in cols if b[3] <= y0], default=None)
    below = min([b[1] for b in cols if b[1] >= y1], default=None)
    y0 = 0 if above is None else (above + y0) // 2
    y1 = height if below is None else (below + y1) // 2
    return x0, y0, x1, y1


def _static_box(ax: Any, renderer: Any) -> tuple[int, int, int, int]:
    """Pixel box ``(x0, y0, x1, y1)`` (display coordinates) of what ``ax`` draws statically: its
    frame with the tick marks outside it, the tick labels in view, the axis labels and offsets,
    its texts (titles included) and legends that are not animated, and its static lines and
    patches that are not clipped to the frame (cheaper than ``get_tightbbox``, which also lays
    out every minor tick). Its other artists are clipped to the frame."""
    from matplotlib.legend import Legend
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    from matplotlib.text import Text
    from matplotlib.transforms import Bbox

    frame = ax.bbox
    x0, y0, x1, y1 = frame.x0, frame.y0, frame.x1, frame.y1
    boxes = []
    for axis, (low, high) in ((ax.xaxis, ("y0", "y1")), (ax.yaxis, ("x0", "x1"))):
        lo, hi = sorted(axis.get_view_interval())
        span = 1e-9 * max(abs(lo), abs(hi), 1.0)
        for ticks in (axis.majorTicks, axis.minorTicks):
            if not ticks:
                continue
            first = ticks[0]
            # tick marks point outwards by their size (points), on the sides where they are drawn
            tick = first.tick1line
            out = (tick.get_markersize() + tick.get_markeredgewidth()) * renderer.dpi / 72
            if first.tick1line.get_visible():
                x0, y0 = (x0, y0 - out) if low == "y0" else (x0 - out, y0)
            if first.tick2line.get_visible():
                x1, y1 = (x1, y1 + out) if high == "y1" else (x1 + out, y1)
            for tick in ticks:
                if lo - span <= tick.get_loc() <= hi + span:
                    boxes += [
                        t.get_window_extent(renderer)
                        for t in (tick.label1, tick.label2)
                        if t.get_visible() and t.get_text()
                    ]
        boxes += [
            t.get_window_extent(renderer)
            for t in (axis.label, axis.offsetText)
            if t.get_visible() and t.get_text()
        ]
    boxes += [
        a.get_window_extent(renderer)
        for a in ax.get_children()
        if isinstance(a, (Text, Legend))
        and a.get_visible()
        and not a.get_animated()
        and (isinstance(a, Legend) or a.get_text())
    ]
    boxes += [
        a.get_window_extent(renderer)
        for a in ax.get_children()
        if isinstance(a, (Line2D, Patch))
        and a is not ax.patch
        and not a.get_clip_on()
        and a.get_visible()
        and not a.get_animated()
    ]
    box = Bbox.union([Bbox([[x0, y0], [x1, y1]]), *boxes])
    return int(np.floor(box.x0)), int(np.floor(box.y0)), int(np.ceil(box.x1)), int(np.ceil(box.y1))


def _redraw_axes(
    fig: Any, renderer: Any, axes: list[Any], regions: dict[Any, tuple[int, int, int, int]]
) -> bool:
    """Blank the region of each of ``axes`` and draw its static artists again; ``False`` if an
    axes now draws outside its region (then the whole figure must be drawn)."""
    buf = np.asarray(renderer.buffer_rgba())
    colour = np.round(np.asarray(fig.patch.get_facecolor()) * 255).astype(np.uint8)
    for ax in axes:
        x0, y0, x1, y1 = regions[ax]
        buf[max(y0, 0) : max(y1, 0), max(x0, 0) : max(x1, 0)] = colour
        ax.draw(renderer)
        bx0, by0, bx1, by1 = _static_box(ax, renderer)
        height = buf.shape[0]
        if bx0 < x0 or bx1 > x1 or height - by1 < y0 or height - by0 > y1:
            return False
    return True


def stepped_limit(value: float, *, log: bool = False) -> float:
    """The smallest "round" number ``>= value`` (``value > 0``): 1, 2, 3 or 5 times a power of ten
    (``log``: a power of ten).

    Widgets set their axis limits to such steps instead of autoscaling to the data: a slider
    move that keeps the data within the same steps keeps the ticks, so :func:`render` redraws
    only the data, and the reader compares frames on the same axes.
    """
    value = float(value)
    if not np.isfinite(value) or value <= 0:
        raise ModelError(f"value: expected a positive finite number, got {value!r}")
    decade = 10.0 ** np.floor(np.log10(value))
    if log:
        return float(decade if decade >= value else 10.0 * decade)
    for m in (1.0, 2.0, 3.0, 5.0, 10.0):
        if m * decade >= value * (1 - 1e-12):
            return float(m * decade)
    raise AssertionError("unreachable")  # pragma: no cover


def stepped_range(
    values: Any, *, log: bool = False, symmetric: bool = False
) -> tuple[float, float]:
    """Axis limits in :func:`stepped_limit` steps that hold the finite ``values`` with a 5 % margin.

    Linear: each side at a round number (``symmetric``: ``-a, a``), and at least 5 % of the
    other side away from 0, as matplotlib's margin would. ``log``: whole decades around the
    positive values.
    """
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if log:
        v = v[v > 0]
        if not v.size:
            return 0.1, 10.0
        return (
            1.0 / stepped_limit(1.05 / v.min(), log=True),
            stepped_limit(1.05 * v.max(), log=True),
        )
    lo, hi = (float(v.min()), float(v.max())) if v.size else (0.0, 0.0)
    if symmetric:
        a = stepped_limit(1.05 * max(-lo, hi)) if max(-lo, hi) > 0 else 1.0
        return -a, a
    top = stepped_limit(1.05 * hi) if hi > 0 else 0.0
    bottom = -stepped_limit(-1.05 * lo) if lo < 0 else 0.0
    if top == bottom == 0.0:
        return -0.05, 1.0
    # each side at least 5 % of the other (a value at 0 is not drawn on the frame)
    return min(bottom, -0.05 * top), max(top, -0.05 * bottom)


def set_limits(
    ax: Any, *, xlim: tuple[float, float] | None = None, ylim: tuple[float, float] | None = None
) -> None:
    """Set the limits of ``ax`` only where they change (setting equal limits still marks the
    axes stale, which would make :func:`render` draw everything again)."""
    if xlim is not None and tuple(ax.get_xlim()) != tuple(map(float, xlim)):
        ax.set_xlim(xlim)
    if ylim is not None and tuple(ax.get_ylim()) != tuple(map(float, ylim)):
        ax.set_ylim(ylim)
