"""Kernel-free explorables: frames over a grid of slider values equal the callback's output."""

from __future__ import annotations

import base64
import io
import json
import re

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from PIL import Image  # noqa: E402

from fdi_lib.errors import ModelError, NonFiniteError, ShapeError  # noqa: E402
from fdi_lib.explorables import explorable, figure_data  # noqa: E402
from fdi_lib.plotting import DISPLAY_DPI, FIG_WIDTH_IN, figure  # noqa: E402
from fdi_lib.widgets import bz, rosa2013, zb2014, zb2014_pipeline, zhang2021  # noqa: E402


def _line(a, b, fig=None, offset=0.0):
    fig, ax = figure(fig=fig)
    ax[0, 0].plot([0.0, 1.0, 2.0], [a, b + offset, a * b])
    ax[0, 0].set_title(f"a = {a}, b = {b}")
    return fig


def assert_same_data(got, expected):
    """Element-by-element equality of two figure_data outputs (NaN equal to NaN)."""
    assert len(got) == len(expected)
    for g, e in zip(got, expected):
        if isinstance(e, str):
            assert g == e
        elif isinstance(e, list):
            assert_same_data(g, e)
        else:
            np.testing.assert_allclose(
                np.asarray(g, float), np.asarray(e, float), rtol=0, atol=1e-12, equal_nan=True
            )


def test_frames_follow_the_product_order_and_the_page_indexes_them_the_same_way():
    ex = explorable(
        _line,
        {"a": (1.0, 2.0, 3.0), "b": (10, 20)},
        caption="toy",
        labels={"a": "$a$"},
        default={"a": 2.0, "b": 20},
        offset=0.5,
    )
    assert ex.strides == (2, 1) and len(ex.frames) == 6
    for a in (1.0, 2.0, 3.0):
        for b in (10, 20):
            i = ex.index(a=a, b=b)
            y = ex.data[i][0][5][0][:, 1]  # axes 0, lines, line 0, y column
            np.testing.assert_array_equal(y, [a, b + 0.5, a * b])
    page = ex._repr_html_()
    # the strides and labels the script uses, and one range input per slider starting at the default
    assert json.loads(re.search(r"S = (\[[^\]]*\])", page).group(1)) == [2, 1]
    assert json.loads(re.search(r"L = (\[\[.*?\]\])", page).group(1)) == [
        ["1", "2", "3"],
        ["10", "20"],
    ]
    assert re.findall(r'<input type="range" min="0" max="(\d)" step="1" value="(\d)"', page) == [
        ("2", "1"),
        ("1", "1"),
    ]
    assert f'data-frame="{ex.index(a=2.0, b=20)}"' in page
    assert "<figcaption>toy</figcaption>" in page and "$a$" in page
    assert "http" not in page.replace("data:image/png", "")  # nothing fetched from elsewhere
    assert repr(ex).startswith("<Explorable a (3) x b (2): 6 frames, 0.") and len(repr(ex)) < 80


def test_a_screen_reader_hears_the_values_shown_and_the_alt_text_names_them():
    ex = explorable(
        _line,
        {"a": (1.0, 2.5, 3.0), "b": (10, 20)},
        caption="toy <i>caption</i>",
        alt="A line through three points",
        labels={"a": "slope a"},
        default={"a": 2.5},
    )
    page = ex._repr_html_()
    # each slider announces the value it shows (not its position on the grid: "1")
    assert re.findall(r'value="(\d)" aria-valuetext="([^"]*)"', page) == [("1", "2.5"), ("0", "10")]
    # the alt text describes the figure (not the caption) and names the frame's values
    alt = re.search(r'<img [^>]*alt="([^"]*)"', page).group(1)
    assert alt == "A line through three points. Shown at slope a = 2.5, b = 10."
    assert alt == ex.frame_alt((1, 0)) and "caption" not in alt
    assert ex.frame_alt((2, 1)).endswith("Shown at slope a = 3, b = 20.")
    # a polite live region, empty until a move, and the script's text for both
    assert re.search(r'<p class="fdi-explorable-live" aria-live="polite"[^>]*></p>', page)
    alt_js = json.loads(re.search(r"A = (\"[^\n]*\");", page).group(1))
    assert alt_js == "A line through three points."
    assert json.loads(re.search(r"N = (\[[^\]]*\])", page).group(1)) == ["slope a", "b"]
    # without an alt text, the caption's plain text stands in
    fallback = explorable(_line, {"a": (1.0, 2.0), "b": (10, 20)}, caption="toy <i>x</i>")
    assert fallback.alt == "toy x."
    with pytest.raises(ModelError, match="alt: expected a non-empty string"):
        explorable(_line, {"a": (1.0, 2.0), "b": (10, 20)}, caption="toy", alt="  ")


def test_frames_are_house_style_pngs_with_font_metadata():
    ex = explorable(_line, {"a": (1.0, 2.0), "b": (1, 2)}, caption="toy")
    img = Image.open(io.BytesIO(base64.b64decode(ex.frames[0])))
    assert img.format == "PNG" and img.mode == "P"
    assert img.width == round(FIG_WIDTH_IN * DISPLAY_DPI)
    assert img.text["fdi:dpi"] == f"{DISPLAY_DPI:g}" and float(img.text["fdi:min_font_pt"]) >= 11
    assert len(set(ex.frames)) == 4  # every point draws something different


@pytest.mark.parametrize(
    "grid, default, message",
    [
        ({}, None, "grid: expected at least one name"),
        (
            {"a": (1.0,), "b": (1, 2)},
            None,
            "grid: expected at least one name with two or more values",
        ),
        (
            {"a": (1.0, 2.0), "b": (1, 2)},
            {"c": 1},
            r"default: expected names of the grid \['a', 'b'\], got \['c'\]",
        ),
        (
            {"a": (1.0, 2.0), "b": (1, 2)},
            {"a": 5.0},
            r"default: expected a among the grid values \[1.0, 2.0\], got 5.0",
        ),
    ],
)
def test_bad_grids_are_rejected(grid, default, message):
    with pytest.raises(ModelError, match=message):
        explorable(_line, grid, caption="x", default=default)


def test_index_rejects_values_off_the_grid():
    ex = explorable(_line, {"a": (1.0, 2.0), "b": (1, 2)}, caption="toy")
    with pytest.raises(ModelError, match=r"b: expected one of the grid values \[1, 2\], got 3"):
        ex.index(a=1.0, b=3)


# The chapters' explorables: the corners of each grid (every slider at its first and last value),
# drawn into one reused figure as the build does, against fresh calls of the callback.
CHAPTERS = {
    "signature": (zb2014.explore_signature, zb2014.SIGNATURE_GRID, {}),
    "glr": (zb2014.explore_glr, zb2014.GLR_GRID, {}),
    "pipeline": (zb2014_pipeline.explore_pipeline, zb2014_pipeline.GRID, {}),
    "sparse": (zhang2021.explore_sparse, zhang2021.GRID, {}),
    "bz": (bz.explore_bz, bz.GRID, {}),
    "svo": (rosa2013.explore_svo, rosa2013.GRID, {}),
}


@pytest.mark.parametrize("name", list(CHAPTERS))
def test_chapter_frames_equal_the_callback_at_the_same_slider_values(name):
    callback, grid, fixed = CHAPTERS[name]
    assert all(len(v) >= 4 for v in grid.values())  # the SVO's horizon: 1-4 (N = 5, 6 add nothing)
    corners = {k: (v[0], v[-1]) for k, v in grid.items()}
    ex = explorable(callback, corners, caption=name, **fixed)
    for i, values in enumerate(
        np.array(np.meshgrid(*corners.values(), indexing="ij"), dtype=object)
        .reshape(len(corners), -1)
        .T
    ):
        point = dict(zip(corners, values))
        assert ex.index(**point) == i
        fig = callback(**point, **fixed)
        assert_same_data(ex.data[i], figure_data(fig))
        plt.close(fig)
    assert len(set(ex.frames)) == len(ex.frames)  # each slider changes the picture


# ----------------------------------------------------------------------------- edges (issue 21)
@pytest.mark.parametrize(
    "grid, error, message",
    [
        (
            [("a", (1.0, 2.0))],
            ModelError,
            r"grid: expected a mapping of keyword names to sequences of values, got list",
        ),
        ({"a": 3.0}, ShapeError, r"grid\['a'\]: expected a 1-D sequence of values, got float"),
        ({"a": "abc"}, ShapeError, r"grid\['a'\]: expected a 1-D sequence of values, got str"),
        (
            {"a": np.ones((2, 2))},
            ShapeError,
            r"grid\['a'\]: expected a 1-D sequence of values, got shape \(2, 2\)",
        ),
        (
            {"a": (1.0, np.nan)},
            NonFiniteError,
            r"grid\['a'\]: expected finite values, got nan at index 1",
        ),
        (
            {"a": (1.0, 2.0, 1.0)},
            ModelError,
            r"grid\['a'\]: expected distinct values, got 1.0 at indices 0 and 2",
        ),
        (
            {3: (1.0, 2.0)},
            ModelError,
            r"grid: expected keyword names of the callback \(not 'fig'\), got 3",
        ),
        ({"fig": (1.0, 2.0)}, ModelError, r"got 'fig'"),
        (
            {"offset": (1.0, 2.0), "a": (1.0, 2.0)},
            ModelError,
            r"grid: 'offset' is also given as a fixed keyword",
        ),
    ],
)
def test_bad_grid_values_are_typed_errors_naming_the_entry(grid, error, message):
    with pytest.raises(error, match=message):
        explorable(_line, grid, caption="x", b=1.0, offset=0.0)


def test_a_callback_must_return_a_figure():
    with pytest.raises(
        ModelError,
        match=r"callback: expected a matplotlib Figure from .*\(\{'a': 1.0, "
        r"'b': 1\}\), got NoneType",
    ):
        explorable(lambda a, b, fig=None: None, {"a": (1.0, 2.0), "b": (1, 2)}, caption="x")
    with pytest.raises(ModelError, match=r"callback: expected a function drawing into fig"):
        explorable(None, {"a": (1.0, 2.0)}, caption="x")
    with pytest.raises(ModelError, match=r"caption: expected a string, got int"):
        explorable(_line, {"a": (1.0, 2.0), "b": (1, 2)}, caption=3)
    with pytest.raises(ModelError, match=r"labels: expected a mapping of grid names \['a', 'b'\]"):
        explorable(_line, {"a": (1.0, 2.0), "b": (1, 2)}, caption="x", labels={"c": "C"})


def test_a_failing_callback_says_at_which_point():
    def bad(a, fig=None):
        raise ZeroDivisionError("boom")

    with pytest.raises(ZeroDivisionError) as info:
        explorable(bad, {"a": (1.0, 2.0)}, caption="x")
    assert "explorable: while drawing the frame at {'a': 1.0}" in info.value.__notes__


def test_size_guards_refuse_too_many_frames_before_drawing_and_too_heavy_pages(monkeypatch):
    import fdi_lib.explorables as exp
    from fdi_lib.errors import ResourceError

    calls = []

    def counted(a, b, fig=None):
        calls.append((a, b))
        return _line(a, b, fig=fig)

    with pytest.raises(
        ResourceError,
        match=r"grid: expected at most 100 frames \(MAX_FRAMES\), got "
        r"1000 \(a\) x 1000 \(b\) = 1000000: use fewer values",
    ):
        explorable(counted, {"a": range(1000), "b": range(1000)}, caption="x")
    assert calls == []  # refused before any frame
    monkeypatch.setattr(exp, "MAX_BYTES", 30_000)  # a frame of this toy weighs ~10-20 kB
    with pytest.raises(
        ResourceError,
        match=r"grid: expected at most 0.03 MB of frames \(MAX_BYTES\), got "
        r"0.0\d MB after \d of 9 frames \(about 0.\d MB for all\)",
    ):
        explorable(counted, {"a": (1.0, 2.0, 3.0), "b": (1, 2, 3)}, caption="x")
    assert len(calls) < 9  # stopped as soon as the budget is exceeded
    assert plt.get_fignums() == []  # and the figure closed


def _tall(a, fig=None):
    """Three stacked panels 7 in high, each with a legend (as explore_bz)."""
    fig, axes = figure(3, 1, fig=fig, figsize=(7.5, 7.0))
    for ax in axes[:, 0]:
        ax.plot([0.0, 1.0], [0.0, a], label="a line with a long legend entry")
        ax.legend(loc="upper left")
    return fig


def test_a_deferred_paper_figure_is_drawn_elsewhere_with_the_same_bytes(monkeypatch):
    """With ``$FDI_PAPER_FIGURES`` = ``deferred`` (the book's execution) the display carries, in
    place of the small multiples, a JSON specification from which :func:`paper_figure` draws them
    in another process: the same PNG, byte for byte. Otherwise the display draws them, and so it
    does, deferred or not, for a callback the specification cannot name (one defined in a
    notebook) or a value JSON would not give back as it is (a NumPy scalar)."""
    from fdi_lib import explorables as E

    ex = explorable(_line, {"a": (1.0, 2.0, 3.0)}, caption="toy", default={"a": 2.0}, b=1)
    assert ex.paper_spec() is None  # this module is not the library: not imported by name
    monkeypatch.setattr(E, "PAPER_CALLBACK_PACKAGE", _line.__module__)
    monkeypatch.setenv(E.PAPER_FIGURES_ENV, "deferred")
    bundle = ex._repr_mimebundle_()
    assert set(bundle) == {"text/html", "text/plain", E.PAPER_SPEC_MIME}
    assert bundle["text/html"] == ex._repr_html_()
    spec = json.loads(json.dumps(bundle[E.PAPER_SPEC_MIME]))  # as a notebook keeps it
    assert spec["callback"] == f"{_line.__module__}:_line" and spec["fixed"] == {"b": 1}
    assert E.paper_figure(spec) == ex.small_multiples()
    monkeypatch.setenv(E.PAPER_FIGURES_ENV, "")
    assert ex._repr_mimebundle_()["image/png"] == ex.small_multiples()
    monkeypatch.setenv(E.PAPER_FIGURES_ENV, "deferred")
    local = explorable(lambda a, fig=None: _line(a, 1, fig=fig), {"a": (1.0, 2.0)}, caption="x")
    scalar = explorable(_line, {"a": (1.0, 2.0)}, caption="x", b=np.float64(1.0))
    for drawn in (local, scalar):
        assert drawn.paper_spec() is None
        assert drawn._repr_mimebundle_()["image/png"] == drawn.small_multiples()
    # a specification names a function of the library, and one that is there
    for bad, match in (
        ({**spec, "callback": "os:system"}, "expected 'module:function' of"),
        ({**spec, "callback": f"{_line.__module__}:nope"}, "not found"),
        ({k: v for k, v in spec.items() if k != "grid"}, r"missing \['grid'\]"),
    ):
        with pytest.raises(ModelError, match=match):
            E.paper_figure(bad)


def test_a_panel_of_the_small_multiples_holds_the_pixels_of_its_png():
    """The panels are taken raw from ``savefig`` (no PNG encoded and decoded per panel): the
    same pixels as a PNG of the same figure, its animated artists (which only a save draws) and
    its size at a resolution that is not a whole number of pixels per inch included."""
    from fdi_lib.explorables import _saved_pixels

    def drawn():
        fig, ax = figure(figsize=(5.5, 3.33))
        ax[0, 0].plot([0.0, 1.0], [0.0, 1.0])
        ax[0, 0].plot([0.0, 1.0], [1.0, 0.0], color="red", animated=True)
        return fig

    fig = drawn()
    png = io.BytesIO()
    fig.savefig(png, format="png", dpi=217.3, facecolor="white")
    expected = np.asarray(Image.open(png).convert("RGB"))
    got = _saved_pixels(drawn(), 217.3)
    plt.close("all")
    assert got.size == (expected.shape[1], expected.shape[0])
    np.testing.assert_array_equal(np.asarray(got), expected)
    red = (expected[..., 0] > 200) & (expected[..., 1] < 80)
    assert red.sum() > 100  # the animated line is in both


def test_small_multiples_are_redrawn_for_paper_with_the_default_among_them():
    """The paper form of an explorable: the chosen frames drawn again by the callback, two per
    row, one title each (the slider values), text that prints at PAPER_DRAWN_FONT_PT or more at
    the text width, as many rows as the page holds."""
    from fdi_lib.explorables import (
        PAPER_DRAWN_FONT_PT,
        PAPER_IMAGE_HEIGHT_IN,
        PAPER_TEXT_WIDTH_IN,
        _spread,
        _wrapped,
    )

    assert (
        _spread(10, 2, 4) == [0, 2, 6, 9]
        and _spread(6, 3, 2) == [0, 3]
        and _spread(6, 0, 2) == [0, 5]
    )
    calls = []

    def counted(a, b, fig=None):
        calls.append((a, fig))
        return _line(a, b, fig=fig)

    one = explorable(
        counted,
        {"a": (1.0, 2.0, 3.0, 4.0, 5.0)},
        caption="toy Γ<sub>k</sub>",
        labels={"a": "slope a"},
        default={"a": 2.0},
        b=1,
    )
    calls.clear()
    sheet = Image.open(io.BytesIO(one.small_multiples()))
    # 4 of the 5 values, evenly spread (0, 1.33, 2.67, 4 rounded), the default 2.0 (index 1)
    # among them, each drawn afresh (no figure passed)
    assert calls == [(1.0, None), (2.0, None), (4.0, None), (5.0, None)]
    dpi = float(sheet.text["fdi:dpi"])
    frame = Image.open(io.BytesIO(base64.b64decode(one.frames[0])))
    assert sheet.text["fdi:caption"] == "toy Γ<sub>k</sub>" and dpi == 2 * DISPLAY_DPI
    assert sheet.width == 2 * 2 * frame.width  # two frames a row, at twice their resolution
    width, height = sheet.width / dpi, sheet.height / dpi
    scale = min(PAPER_TEXT_WIDTH_IN / width, PAPER_IMAGE_HEIGHT_IN / height)
    assert float(sheet.text["fdi:min_font_pt"]) * scale == pytest.approx(PAPER_DRAWN_FONT_PT)
    assert height > 2 * frame.height / DISPLAY_DPI  # two rows, taller frames (room on the page)
    # the panels differ (each drawn at its own value)
    pixels = np.asarray(sheet.convert("L"), int)
    half = pixels.shape[1] // 2
    assert not np.array_equal(pixels[:, :half], pixels[:, half:])
    # two sliders: the default and the farthest value of each, 2 x 2
    two = explorable(
        _line, {"a": (1.0, 2.0, 3.0), "b": (10, 20)}, caption="toy", default={"a": 3.0}
    )
    assert Image.open(io.BytesIO(two.small_multiples())).size[0] == sheet.width
    # frames too tall for two rows on a page: one row, at the same printed text size
    tall = explorable(_tall, {"a": (1.0, 2.0, 3.0)}, caption="tall")
    sheet = Image.open(io.BytesIO(tall.small_multiples()))
    width, height = sheet.width / dpi, sheet.height / dpi
    assert height < 7.0 * 1.4 + 1  # one row of 7 in frames (grown by PAPER_GROWTH at most)
    scale = min(PAPER_TEXT_WIDTH_IN / width, PAPER_IMAGE_HEIGHT_IN / height)
    assert float(sheet.text["fdi:min_font_pt"]) * scale == pytest.approx(PAPER_DRAWN_FONT_PT)
    with pytest.raises(ModelError, match="panels: expected an integer of at least 2, got 1"):
        one.small_multiples(panels=1)
    # a title wider than its panel goes on two lines, after a comma (between slider values)
    long = "change of G₀(1) (10⁻⁵) = -10, window w = 160"
    assert _wrapped(long, 17.0, 5.5) == "change of G₀(1) (10⁻⁵) = -10,\nwindow w = 160"
    assert _wrapped("a = 1, b = 2", 17.0, 5.5) == "a = 1, b = 2"
