"""One central matplotlib style for the book and the CLI, and small shared helpers.

Plot functions of the reproductions live next to them (``plot_<figure>(result, fig=None)``)
and use :func:`figure` so that every figure of the book looks the same.

The style is sized for a phone: every figure is :data:`FIG_WIDTH_IN` inches wide and its
smallest text is :data:`MIN_FONT_PT` points, so that when a figure is shrunk to the
``PHONE_COLUMN_PX`` CSS pixels of a 390 px wide phone screen its text is still at least
``MIN_FONT_PT / 72 * PHONE_COLUMN_PX / FIG_WIDTH_IN`` (about 9.9) CSS pixels high. In a notebook
(the book), figures are PNG rasters at twice their display resolution (sharp on high-density
screens) that carry their smallest font size and resolution as PNG text metadata
(``fdi:min_font_pt``, ``fdi:dpi``); the book's browser test reads them.
"""

from __future__ import annotations

import base64
import importlib
import io
import struct
from textwrap import fill
from typing import Any

import matplotlib as mpl
import matplotlib.pyplot as plt
from matplotlib.figure import Figure
from matplotlib.text import Text

from fdi_lib.errors import ModelError

__all__ = [
    "STYLE",
    "use_style",
    "figure",
    "PAPER_COLOR",
    "OURS_COLOR",
    "THRESHOLD_COLOR",
    "FIG_WIDTH_IN",
    "STACKED_HEIGHT",
    "MIN_FONT_PT",
    "DISPLAY_DPI",
    "RASTER_SCALE",
    "PHONE_COLUMN_PX",
    "smallest_font_pt",
    "png_for_display",
    "for_paper",
    "axes3d",
]

OURS_COLOR = "#1f77b4"
PAPER_COLOR = "#d62728"
THRESHOLD_COLOR = "#d62728"

#: Width of every figure of the book (inches); ``figure(figsize=...)`` only chooses the height.
FIG_WIDTH_IN = 5.5
#: Smallest font of the house style (tick labels, legends), in points.
MIN_FONT_PT = 11.0
#: CSS pixels per inch at which a figure is displayed at its natural size (5.5 in -> 605 px).
DISPLAY_DPI = 110
#: The PNG holds ``RASTER_SCALE`` device pixels per CSS pixel (sharp on high-density screens).
RASTER_SCALE = 2
#: Height of each stacked panel, as a fraction of the height asked for one row (see figure).
STACKED_HEIGHT = 0.8
#: Width of the text column of the book on a 390 px wide phone, in CSS pixels (measured in
#: Chromium: 358; the browser test checks every figure against its rendered width).
PHONE_COLUMN_PX = 358

STYLE: dict[str, Any] = {
    "figure.figsize": (FIG_WIDTH_IN, 3.4),
    "figure.dpi": DISPLAY_DPI,
    "savefig.dpi": DISPLAY_DPI * RASTER_SCALE,
    "font.size": MIN_FONT_PT,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.titlesize": MIN_FONT_PT + 1.5,
    "axes.labelsize": MIN_FONT_PT + 1.0,
    "xtick.labelsize": MIN_FONT_PT,
    "ytick.labelsize": MIN_FONT_PT,
    "legend.fontsize": MIN_FONT_PT,
    "legend.title_fontsize": MIN_FONT_PT,
    "figure.titlesize": MIN_FONT_PT + 1.5,
    "legend.frameon": False,
    "lines.linewidth": 1.4,
}


def smallest_font_pt(fig: Figure) -> float:
    """The smallest font size (points) of the visible, non-empty texts of ``fig``."""
    sizes = [
        t.get_fontsize() for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip()
    ]
    return float(min(sizes)) if sizes else float(MIN_FONT_PT)


def _png_width(data: bytes) -> int:
    # IHDR is the first chunk: 8-byte signature, 4-byte length, "IHDR", then width (big-endian)
    return struct.unpack(">I", data[16:20])[0]


def png_for_display(fig: Figure) -> tuple[str, dict[str, Any]] | None:
    """``fig`` as a base64 PNG at ``RASTER_SCALE`` x its display resolution, with the display
    width as output metadata (IPython ``image/png`` formatter; ``None`` for an empty figure)."""
    if not fig.axes and not fig.lines and not fig.texts:
        return None
    dpi = fig.dpi * RASTER_SCALE
    buf = io.BytesIO()
    fig.savefig(
        buf,
        format="png",
        dpi=dpi,
        bbox_inches="tight",
        facecolor="white",
        metadata={"fdi:min_font_pt": f"{smallest_font_pt(fig):g}", "fdi:dpi": f"{dpi:g}"},
    )
    data = buf.getvalue()
    width = round(_png_width(data) / RASTER_SCALE)
    return base64.b64encode(data).decode("ascii"), {"width": width}


def _register_display_formatter() -> None:
    """In IPython (the book's notebooks), display figures with :func:`png_for_display`."""
    try:
        from IPython import get_ipython
    except ImportError:  # pragma: no cover - IPython is a dependency of the book only
        return
    shell = get_ipython()
    if shell is None:
        return
    # The inline backend configures IPython's figure formatters when it is first imported (at
    # the first figure): import it now, so that it does not replace this formatter later.
    try:
        backend = mpl.get_backend(auto_select=False)
    except TypeError:  # matplotlib < 3.10
        backend = mpl.rcParams._get("backend")
    if backend in ("inline", "module://matplotlib_inline.backend_inline"):
        importlib.import_module("matplotlib_inline.backend_inline")
    formatters = shell.display_formatter.formatters
    formatters["image/png"].for_type(Figure, png_for_display)
    for mime in ("image/svg+xml", "image/jpeg", "application/pdf"):
        formatters[mime].pop(Figure, None)
    # pyplot's hook draws every stale figure after a cell, before the inline backend shows it
    # through png_for_display, whose savefig draws it again at its own resolution: the first
    # draw is thrown away (70-200 ms a figure, about 70 figures in the book). The figures are
    # still shown after each cell (the inline backend's flush_figures), drawn once.
    import matplotlib.pyplot as plt

    plt.uninstall_repl_displayhook()


def use_style() -> None:
    """Apply the book's matplotlib style (idempotent); in IPython, also its figure display."""
    mpl.rcParams.update(STYLE)
    _register_display_formatter()


def figure(
    nrows: int = 1,
    ncols: int = 1,
    *,
    fig: Any = None,
    sharex: bool = False,
    figsize: tuple[float, float] | None = None,
    **kwargs: Any,
):
    """A figure with the book's style: ``(fig, axes)``; ``fig`` reuses an existing figure (widgets).

    Every figure is ``FIG_WIDTH_IN`` wide (legible on a phone); ``figsize`` sets the height of
    one row of panels (its width is ignored). Panels asked for side by side in one row
    (``nrows == 1``, ``ncols > 1``) are stacked in one column, each ``STACKED_HEIGHT`` of that
    height, because a phone column has no room for them; ``axes`` keeps the requested shape
    ``(nrows, ncols)``, so ``axes[0, j]`` is still the j-th panel.
    """
    use_style()
    height = STYLE["figure.figsize"][1] if figsize is None else figsize[1]
    stack = nrows == 1 and ncols > 1
    if stack:
        height = height * STACKED_HEIGHT * ncols
    if fig is None:
        fig = plt.figure(figsize=(FIG_WIDTH_IN, height), layout="constrained")
    else:
        fig.clear()
        fig.set_size_inches(FIG_WIDTH_IN, height)
    if stack:
        # the requested widths of side-by-side panels become the heights of the stacked ones
        grid = dict(kwargs.pop("gridspec_kw", None) or {})
        ratios = kwargs.pop("width_ratios", None) or grid.pop("width_ratios", None)
        if ratios is not None:
            grid["height_ratios"] = ratios
        axes = fig.subplots(
            ncols, 1, sharex=sharex, squeeze=False, gridspec_kw=grid or None, **kwargs
        ).reshape(1, ncols)
    else:
        axes = fig.subplots(nrows, ncols, sharex=sharex, squeeze=False, **kwargs)
    return fig, axes


def for_paper(fig: Figure, font_scale: float) -> Figure:
    """``fig`` redrawn for paper, where it prints smaller than on screen: every text
    ``font_scale`` times larger, no axes title (the panel's title says what it shows) and each
    axes' legend above its axes instead of over the curves (as many columns as fit the axes'
    width). Returns ``fig``, changed in place; a layout engine (:func:`figure`'s) makes room.

    Used for the small multiples of an explorable in the PDF edition
    (:meth:`fdi_lib.explorables.Explorable.small_multiples`).
    """
    if isinstance(font_scale, bool) or not isinstance(font_scale, (int, float)) or font_scale <= 0:
        raise ModelError(f"font_scale: expected a positive number, got {font_scale!r}")
    axes = [
        (ax, [getattr(ax, f"{n}axis") for n in "xyz" if hasattr(ax, f"{n}axis")]) for ax in fig.axes
    ]
    for ax, _ in axes:
        for loc in ("center", "left", "right"):
            ax.set_title("", loc=loc)
    # tick labels are made anew at each draw, at their axis' tick label size: set that instead
    tick_size = {
        id(axis): axis.get_major_ticks()[0].label1.get_fontsize() for _, axs in axes for axis in axs
    }
    ticks = {
        id(text)
        for _, axs in axes
        for axis in axs
        for tick in axis.get_major_ticks() + axis.get_minor_ticks()
        for text in (tick.label1, tick.label2)
    } | {id(axis.offsetText) for _, axs in axes for axis in axs}
    for text in fig.findobj(Text):
        if id(text) not in ticks:
            text.set_fontsize(text.get_fontsize() * font_scale)
    for _, axs in axes:
        for axis in axs:
            axis.set_tick_params(which="both", labelsize=tick_size[id(axis)] * font_scale)
            axis.offsetText.set_fontsize(tick_size[id(axis)] * font_scale)
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        legend = ax.get_legend()
        if legend is None:
            continue
        handles = list(legend.legend_handles)
        labels = [t.get_text() for t in legend.get_texts()]
        size = legend.get_texts()[0].get_fontsize() if labels else None
        shown = [(h, lab) for h, lab in zip(handles, labels) if h is not None and h.get_visible()]
        handles, labels = [h for h, _ in shown], [lab for _, lab in shown]
        legend.remove()
        if not handles:
            continue
        # as many columns as fit the axes (narrower once the layout makes room for the text)
        limit = 0.9 * ax.get_window_extent(renderer).width
        for ncols in range(len(handles), 0, -1):
            legend = _legend_above(ax, handles, labels, ncols, size)
            width = legend.get_window_extent(renderer).width
            if width <= limit:
                break
            legend.remove()
        else:  # one column is still too wide: its long labels on more lines (not maths)
            chars = [max(12, int(len(lab) * limit / width)) for lab in labels]
            labels = [lab if "$" in lab else fill(lab, n) for lab, n in zip(labels, chars)]
            _legend_above(ax, handles, labels, 1, size)
    return fig


def _legend_above(ax: Any, handles: list, labels: list[str], ncols: int, size: Any) -> Any:
    """A legend of ``ax`` just above it, left-aligned with it (:func:`for_paper`)."""
    return ax.legend(
        handles,
        labels,
        loc="lower left",
        bbox_to_anchor=(0.0, 1.0),
        borderaxespad=0.2,
        ncols=ncols,
        fontsize=size,
    )


def axes3d(fig: Figure, spec: Any, *, nbins: int = 3, labelpad: float = 10, zoom: float = 0.8):
    """A 3-D axes of the book's style in the subplot ``spec`` of ``fig`` (``mpl_toolkits.mplot3d``).

    At the book's figure width a 3-D axes is a few centimetres wide, and matplotlib's defaults
    (as many ticks as a 2-D axis, labels parallel to the axes, close to the tick labels) put tick
    labels on top of each other and of the axis labels, and the labels outside the axes' box,
    where the layout engine does not see them (over the next panel's title: Fig. 6.1 did). Here each axis has at most ``nbins + 1`` ticks, its
    label sits ``labelpad`` points away from the tick labels, and the box is drawn at ``zoom``
    of the axes so that the labels stay inside it (``tests/test_plotting.py`` checks that no
    two texts of a figure with a 3-D panel overlap).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (from :func:`figure`).
    spec : matplotlib.gridspec.SubplotSpec
        Where the 3-D axes goes (the subplot spec of a panel of :func:`figure`).
    nbins : int
        Most intervals between ticks on each axis.
    labelpad : float
        Distance of each axis label from its tick labels, in points.
    zoom : float
        Size of the drawn box relative to the axes (below 1 leaves room for the labels).
    """
    from matplotlib.ticker import MaxNLocator

    ax = fig.add_subplot(spec, projection="3d")
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(MaxNLocator(nbins))
        axis.labelpad = labelpad
        axis.set_rotate_label(False)  # horizontal: a rotated label's box overlaps its neighbours
    ax.set_box_aspect(None, zoom=zoom)
    return ax
