"""The house style of fdi_lib.plotting: phone-legible sizes, 2x PNG with its font metadata."""

from __future__ import annotations

import base64
import io
import struct

import matplotlib.pyplot as plt
import pytest

from fdi_lib import plotting
from fdi_lib.plotting import (
    DISPLAY_DPI,
    FIG_WIDTH_IN,
    MIN_FONT_PT,
    PHONE_COLUMN_PX,
    RASTER_SCALE,
    figure,
    png_for_display,
    smallest_font_pt,
)


def _png_chunks(data: bytes) -> dict[bytes, list[bytes]]:
    chunks: dict[bytes, list[bytes]] = {}
    pos = 8
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        chunks.setdefault(data[pos + 4 : pos + 8], []).append(data[pos + 8 : pos + 8 + length])
        pos += 12 + length
    return chunks


def test_smallest_text_is_legible_on_a_phone():
    # text height in CSS px when the figure is shrunk to the phone column
    assert MIN_FONT_PT / 72 * PHONE_COLUMN_PX / FIG_WIDTH_IN >= 9.0
    for key in (
        "font.size",
        "xtick.labelsize",
        "ytick.labelsize",
        "legend.fontsize",
        "axes.labelsize",
        "axes.titlesize",
    ):
        assert plotting.STYLE[key] >= MIN_FONT_PT, key


@pytest.mark.parametrize("figsize", [None, (9.0, 2.5), (4.0, 5.0)])
def test_figure_width_is_the_house_width_and_height_is_kept(figsize):
    fig, axes = figure(2, 2, figsize=figsize)
    width, height = fig.get_size_inches()
    assert width == pytest.approx(FIG_WIDTH_IN)
    assert height == pytest.approx(
        plotting.STYLE["figure.figsize"][1] if figsize is None else figsize[1]
    )
    assert axes.shape == (2, 2)


def test_panels_in_one_row_are_stacked_in_the_requested_shape():
    fig, axes = figure(1, 3, figsize=(9.0, 3.0), sharey=True)
    assert axes.shape == (1, 3)
    assert fig.get_size_inches()[1] == pytest.approx(3 * 3.0 * plotting.STACKED_HEIGHT)
    fig.canvas.draw()
    boxes = [ax.get_position() for ax in axes[0]]
    # one column, top to bottom in the order of axes[0, j]
    assert all(abs(b.x0 - boxes[0].x0) < 1e-9 for b in boxes)
    assert boxes[0].y0 > boxes[1].y0 > boxes[2].y0
    assert axes[0, 2].get_shared_y_axes().joined(axes[0, 0], axes[0, 2])


def test_reused_figure_is_resized_and_cleared():
    fig = plt.figure(figsize=(10.0, 2.0))
    fig.add_subplot().plot([0, 1])
    same, axes = figure(2, 1, fig=fig, figsize=(7.0, 4.0))
    assert same is fig and len(fig.axes) == 2 and axes.shape == (2, 1)
    assert tuple(fig.get_size_inches()) == pytest.approx((FIG_WIDTH_IN, 4.0))


def test_smallest_font_sees_explicit_small_text():
    fig, axes = figure()
    axes[0, 0].plot([0, 1], [0, 1], label="a")
    axes[0, 0].legend()
    assert smallest_font_pt(fig) == pytest.approx(MIN_FONT_PT)
    axes[0, 0].text(0.5, 0.5, "tiny", fontsize=6)
    assert smallest_font_pt(fig) == pytest.approx(6.0)
    axes[0, 0].text(0.5, 0.2, "", fontsize=2)  # empty texts are not drawn: ignored
    assert smallest_font_pt(fig) == pytest.approx(6.0)


def test_png_for_display_is_a_2x_raster_with_font_metadata():
    fig, axes = figure()
    axes[0, 0].plot([0, 1], [1, 0])
    b64, meta = png_for_display(fig)
    data = base64.b64decode(b64)
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    chunks = _png_chunks(data)
    width_px = struct.unpack(">I", chunks[b"IHDR"][0][:4])[0]
    # display width is half the raster, about the figure's width at DISPLAY_DPI (tight bbox)
    assert meta["width"] == round(width_px / RASTER_SCALE)
    assert abs(meta["width"] - FIG_WIDTH_IN * DISPLAY_DPI) < 0.1 * FIG_WIDTH_IN * DISPLAY_DPI
    text = dict(c.split(b"\0", 1) for c in chunks[b"tEXt"])
    assert float(text[b"fdi:min_font_pt"]) == pytest.approx(MIN_FONT_PT)
    assert float(text[b"fdi:dpi"]) == pytest.approx(DISPLAY_DPI * RASTER_SCALE)


def test_png_for_display_of_an_empty_figure_is_none():
    assert png_for_display(plt.figure()) is None


def test_cli_savefig_is_also_2x():
    fig, axes = figure()
    axes[0, 0].plot([0, 1])
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    width_px = struct.unpack(">I", buf.getvalue()[16:20])[0]
    assert width_px == pytest.approx(FIG_WIDTH_IN * DISPLAY_DPI * RASTER_SCALE, rel=0.01)


def test_stacked_panels_keep_the_requested_width_ratios_as_heights():
    fig, axes = figure(1, 2, gridspec_kw={"width_ratios": [2, 1]})
    h = [ax.get_position().height for ax in axes[0]]
    assert axes.shape == (1, 2)
    assert h[0] / h[1] == pytest.approx(2.0, rel=0.05)


def _shown_texts(fig):
    """Every non-empty text a reader sees in ``fig``: titles, axis labels and the tick labels
    inside each axis's view (matplotlib keeps labels of ticks outside it, not drawn)."""
    out = []
    for ax in fig.axes:
        axes = (ax.xaxis, ax.yaxis, ax.zaxis) if ax.name == "3d" else (ax.xaxis, ax.yaxis)
        out += [ax.title] + [a.label for a in axes]
        for axis in axes:
            lo, hi = sorted(axis.get_view_interval())
            out += [
                t.label1
                for t in axis.get_major_ticks()
                if lo - 1e-9 <= t.get_loc() <= hi + 1e-9 and t.label1.get_visible()
            ]
    return [t for t in out if t.get_visible() and t.get_text().strip()]


def test_no_two_texts_of_the_3d_figure_overlap():
    """Fig. 6.1 (the lifted polytope, the book's one 3-D panel): tick labels, axis labels and
    titles are pairwise apart (matplotlib's defaults put them on top of each other)."""
    from itertools import combinations

    from fdi_lib.reproduce import get, reproduce

    fig = get("rosa2013-fig1").plot(reproduce("rosa2013-fig1"))
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in _shown_texts(fig)]
    assert any(name == "3d" for name in (a.name for a in fig.axes))
    overlaps = [(a, b) for (a, ba), (b, bb) in combinations(boxes, 2) if ba.overlaps(bb)]
    plt.close(fig)
    assert overlaps == []


def test_for_paper_enlarges_every_text_drops_axes_titles_and_lifts_legends_off_the_curves():
    """for_paper: every text (tick labels, offsets, labels, legends) font_scale times larger,
    no axes title, each legend above its axes (outside the curves' box), long entries wrapped
    to the axes' width, hidden legend entries left out; a bad scale is refused."""
    import matplotlib.pyplot as plt
    from matplotlib.text import Text

    from fdi_lib.errors import ModelError
    from fdi_lib.plotting import figure, for_paper, smallest_font_pt

    fig, axes = figure(2, 1, figsize=(6.0, 5.0))
    top, bottom = axes[0, 0], axes[1, 0]
    top.plot([0, 1], [0, 1e-6], label="a")
    top.plot([0, 1], [1, 0], label="b")
    top.set(title="the values of the sliders", ylabel="y")
    top.legend(loc="upper left")
    bottom.plot([0, 1], [0, 1], label="a legend entry that is too long for the axes at this size")
    bottom.plot([0, 1], [1, 1], label="hidden", visible=False)
    bottom.legend(loc="upper left").legend_handles[1].set_visible(False)
    bottom.set(title="left", xlabel="k")
    fig.canvas.draw()
    before = smallest_font_pt(fig)
    for_paper(fig, 1.5)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    assert smallest_font_pt(fig) == pytest.approx(1.5 * before)
    assert top.yaxis.get_offset_text().get_fontsize() == pytest.approx(1.5 * before)
    assert all(not t.get_text() for ax in (top, bottom) for t in (ax.title, ax._left_title))
    for ax in (top, bottom):
        legend, box = ax.get_legend().get_window_extent(renderer), ax.get_window_extent(renderer)
        assert legend.y0 >= box.y1 - 1 and legend.width <= box.width  # above, not wider
    texts = [t.get_text() for t in bottom.get_legend().get_texts()]
    assert len(texts) == 1 and "\n" in texts[0]
    assert [t.get_text() for t in top.get_legend().get_texts()] == ["a", "b"]
    assert all(t.get_fontsize() >= 1.5 * before - 1e-9 for t in fig.findobj(Text) if t.get_text())
    with pytest.raises(ModelError, match="font_scale: expected a positive number, got 0"):
        for_paper(fig, 0)
    plt.close(fig)


def test_in_ipython_a_figure_is_drawn_once_for_display():
    """In IPython the book's style shows figures through png_for_display (whose savefig draws
    them) and takes out pyplot's hook that drew every stale figure after a cell before that: a
    draw thrown away (70-200 ms a figure)."""
    from IPython.core.interactiveshell import InteractiveShell
    from matplotlib.figure import Figure

    shell = InteractiveShell.instance()
    plt.install_repl_displayhook()  # as the inline backend's activation does
    hooks = shell.events.callbacks["post_execute"]
    assert any(getattr(f, "__module__", "") == "matplotlib.pyplot" for f in hooks)
    plotting.use_style()
    hooks = shell.events.callbacks["post_execute"]
    assert not any(getattr(f, "__module__", "") == "matplotlib.pyplot" for f in hooks)
    assert shell.display_formatter.formatters["image/png"].lookup_by_type(Figure) is png_for_display
