"""Kernel-free explorable figures for the static book: sliders over precomputed frames.

At build time :func:`explorable` evaluates a tested widget callback (``fdi_lib.widgets.*``) over
a grid of slider values, redrawing one figure, and keeps every frame as a PNG of the book's
house style. The page shows one ``<input type="range">`` per parameter and swaps the image on
every move: no kernel, no network, no file under ``_static``; the script is inlined in the
cell's HTML output (myst-nb keeps raw ``text/html`` outputs, scripts included).

Why frames and not a plotting library. Bokeh (inline resources) or Plotly (bundled
plotly.js) would put 1-4 MB of JavaScript on every page that has an explorable, before any
data, and would redraw the figures in a second style (fonts, mathtext, legends, log axes,
polytope patches) that we would have to keep in step with :mod:`fdi_lib.plotting`. A frame
here is the very figure the callback draws, in the one house style; at one CSS pixel per
figure pixel (``DISPLAY_DPI``, 605 px wide) and a 64-colour palette a frame weighs
20-70 kB, so 36 frames stay far under the 3 MB budget of an explorable, and moving a slider
is an image swap on already decoded images (a few ms in Chromium, far under 50 ms).
The frames keep the ``fdi:min_font_pt``/``fdi:dpi`` PNG metadata that the browser test reads.

On paper (the PDF edition of the book) an explorable is a small-multiples figure: a few of the
same figures, two side by side, each titled with its slider values (:meth:`Explorable.small_multiples`,
the ``image/png`` output that myst-nb's LaTeX builder prefers to HTML), drawn again by the callback
for paper (:func:`fdi_lib.plotting.for_paper`: larger text, so that it prints at
:data:`PAPER_MIN_FONT_PT` or more at the width of the text, legends above the axes, no axes
title); the PNG carries the caption (``fdi:caption``) for the book's extension to typeset under it.
The HTML book never shows it, and drawing it took 1.5-2.7 s of each explorable's cell (13.6 s
over the book's seven): where ``$FDI_PAPER_FIGURES`` is ``deferred`` (the book's execution,
``tools/execute_book.py``) the display leaves it out and carries instead what
:func:`paper_figure` needs to draw it in another process (:meth:`Explorable.paper_spec`, a small
JSON output of type :data:`PAPER_SPEC_MIME`), which the PDF edition does before its LaTeX build
(``tools/pdf_edition.py``): the same bytes (tested).

:func:`figure_data` reduces a figure to its data arrays and texts; the tests compare the frames
of the grid with the callback's output at the same slider values through it.
"""

from __future__ import annotations

import base64
import html
import html.parser
import io
import itertools
import importlib
import json
import os
import uuid
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

from fdi_lib.errors import ModelError, NonFiniteError, ResourceError, ShapeError
from fdi_lib.plotting import DISPLAY_DPI, RASTER_SCALE, for_paper, smallest_font_pt
from fdi_lib.redraw import render

__all__ = [
    "Explorable",
    "explorable",
    "PANELS",
    "PAPER_MIN_FONT_PT",
    "PAPER_TEXT_WIDTH_IN",
    "PAPER_IMAGE_HEIGHT_IN",
    "figure_data",
    "caption_text",
    "script_text",
    "PALETTE_COLOURS",
    "MAX_FRAMES",
    "MAX_BYTES",
    "PAPER_SPEC_MIME",
    "PAPER_FIGURES_ENV",
    "paper_figure",
]

#: Colours of the palette PNG of a frame (the house style uses a handful; 64 keeps antialiasing).
PALETTE_COLOURS = 64

#: Most frames of one explorable: each is a callback call and a PNG encoding at build time and
#: 20-70 kB of page (the chapters' grids have 10 to 42 points).
MAX_FRAMES = 100

#: Frames of the small-multiples figure of an explorable on paper (:meth:`Explorable.small_multiples`).
PANELS = 4

#: Smallest text of the small multiples printed, in points (issue 33; ``tools/check_pdf.py``
#: measures it in the PDF). They are drawn for :data:`PAPER_DRAWN_FONT_PT`, above it, because
#: the PDF's image resolution that the check reads is rounded to a whole pixel per inch.
PAPER_MIN_FONT_PT = 8.0
PAPER_DRAWN_FONT_PT = 8.5
#: The page that the small multiples are drawn for, in inches: the narrower text of the two
#: editions of the PDF (A4, 210 mm wide less Sphinx's two 1 in margins) and the tallest image of
#: a figure there (Sphinx's LaTeX, as the book sets it: 0.8 of the shorter text height, US
#: letter's 11 in less two 1 in margins; ``LATEX_LAYOUT`` of ``_ext/fdi_book.py``).
PAPER_TEXT_WIDTH_IN = 210 / 25.4 - 2
PAPER_IMAGE_HEIGHT_IN = 0.8 * (11 - 2)
#: Most a frame of the small multiples grows in height on paper, where the page has room.
PAPER_GROWTH = 1.4

#: Most bytes of one explorable's HTML, its page weight (the chapters' measure 0.15 to 1.6 MB).
MAX_BYTES = 3_000_000

#: MIME type of an explorable's paper-figure specification in a notebook's output
#: (:meth:`Explorable.paper_spec`, read by :func:`paper_figure`).
PAPER_SPEC_MIME = "application/vnd.fdi.explorable-paper+json"
#: Environment variable: ``deferred`` leaves the small multiples out of an explorable's display
#: (where the specification can draw them elsewhere); anything else, or unset, draws them.
PAPER_FIGURES_ENV = "FDI_PAPER_FIGURES"
#: Modules whose callbacks :func:`paper_figure` imports by name (the book's widgets): a notebook's
#: output names a function to call, and nothing outside the library is imported for it.
PAPER_CALLBACK_PACKAGE = "fdi_lib."


def figure_data(fig: Figure) -> list[Any]:
    """The data a figure shows, axis by axis: line and patch coordinates, collections, texts.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A drawn figure.

    Returns
    -------
    list
        For each axes: ``[title, xlabel, ylabel, x limits, y limits, lines, collections,
        patches]`` with float arrays (NaN kept) for the data; comparable with
        :func:`numpy.testing.assert_allclose` element by element.
    """
    out: list[Any] = []
    for ax in fig.axes:
        lines = [np.asarray(ln.get_xydata(), dtype=float) for ln in ax.lines]
        colls = []
        for c in ax.collections:
            paths = [p.vertices for p in c.get_paths()]
            colls.append(
                np.concatenate(paths) if paths else np.asarray(c.get_offsets(), dtype=float)
            )
        # in the patch's own coordinates (a Rectangle's path is the unit square; its position and
        # size are in its patch transform)
        patches = [
            np.asarray(p.get_patch_transform().transform(p.get_path().vertices), dtype=float)
            for p in ax.patches
        ]
        out.append(
            [
                ax.get_title(),
                ax.get_xlabel(),
                ax.get_ylabel(),
                np.asarray(ax.get_xlim()),
                np.asarray(ax.get_ylim()),
                lines,
                colls,
                patches,
            ]
        )
    return out


def _png_frame(fig: Figure) -> str:
    """``fig`` as a base64 palette PNG at one pixel per CSS pixel, with the house-style metadata.

    One Agg render at the display resolution (``DISPLAY_DPI``) by :func:`fdi_lib.redraw.render`
    (the callbacks move their artists between grid points: only what changed is drawn again),
    its pixels quantised to :data:`PALETTE_COLOURS` colours (fast octree) and written by Pillow
    at its default compression. Measured on the chapters' grids (issue 10): the encoding takes
    about 7 ms a frame (quantisation 3 ms, compression 2.5 ms); compression level 1 would save
    1.5 ms for 25 % more bytes, and frames at twice the resolution (sharper on high-density
    screens) would weigh 2-3 times more (the parametric/non-parametric page: 3.8 MB with 64
    colours, 3.2 MB with 32, 2.6 MB with 16) and take 20-30 ms more a frame.
    """
    from PIL import Image
    from PIL.PngImagePlugin import PngInfo

    if fig.dpi != DISPLAY_DPI:
        fig.set_dpi(DISPLAY_DPI)
    render(fig)
    img = Image.frombuffer(
        "RGBA", fig.canvas.get_width_height(), fig.canvas.buffer_rgba(), "raw", "RGBA", 0, 1
    )
    img = img.convert("RGB").quantize(colors=PALETTE_COLOURS, method=Image.Quantize.FASTOCTREE)
    info = PngInfo()
    info.add_text("fdi:min_font_pt", f"{smallest_font_pt(fig):g}")
    info.add_text("fdi:dpi", f"{DISPLAY_DPI:g}")
    out = io.BytesIO()
    img.save(out, format="PNG", pnginfo=info)
    return base64.b64encode(out.getvalue()).decode("ascii")


# The whole client side: one image, one range input per parameter, frames decoded up front. A
# slider announces the value it shows (aria-valuetext, not its position on the grid), the image's
# alt text names the values it is drawn at, and a polite live region says which frame is shown.
_SCRIPT = """(function () {
  const root = document.getElementById(%(id)s), F = %(frames)s, L = %(labels)s, S = %(strides)s;
  const N = %(names)s, A = %(alt)s;
  const img = root.querySelector("img"), ins = root.querySelectorAll("input[type=range]");
  const live = root.querySelector(".fdi-explorable-live");
  const pics = F.map(function (b) {
    const p = new Image(); p.src = "data:image/png;base64," + b; p.decode().catch(function () {}); return p;
  });
  function show() {
    let i = 0;
    const said = [];
    ins.forEach(function (e, j) {
      const v = L[j][e.value];
      i += S[j] * Number(e.value); e.nextElementSibling.textContent = v;
      e.setAttribute("aria-valuetext", v); said.push(N[j] + " = " + v);
    });
    img.src = pics[i].src; root.dataset.frame = i;
    img.alt = A + " Shown at " + said.join(", ") + ".";
    live.textContent = "Figure redrawn at " + said.join(", ") + ".";
  }
  ins.forEach(function (e) { e.addEventListener("input", show); });
})();"""


@dataclass(frozen=True, repr=False)
class Explorable:
    """Frames of a callback over a grid of slider values, displayed as HTML with sliders.

    Attributes
    ----------
    names : tuple of str
        Keyword arguments of the callback that the sliders move.
    labels : tuple of str
        What each slider is called on the page.
    grid : tuple of tuple
        The slider values, one tuple per name.
    frames : tuple of str
        Base64 PNG per grid point, in :func:`itertools.product` order (last name fastest).
    data : tuple
        :func:`figure_data` of each frame.
    default : tuple of int
        Index of the shown value of each slider.
    caption : str
        Caption of the figure (HTML allowed).
    alt : str
        What the figure shows, in one or two sentences of plain text (the image's alt text,
        followed by the slider values of the frame shown: :meth:`frame_alt`).
    callback : callable
        The callback that drew the frames (called again by :meth:`small_multiples`).
    fixed : mapping
        The keyword arguments passed unchanged to every call of ``callback``.
    """

    names: tuple[str, ...]
    labels: tuple[str, ...]
    grid: tuple[tuple[Any, ...], ...]
    frames: tuple[str, ...]
    data: tuple[Any, ...]
    default: tuple[int, ...]
    caption: str
    alt: str
    callback: Callable[..., Figure] = field(compare=False)
    fixed: Mapping[str, Any] = field(compare=False)

    @property
    def strides(self) -> tuple[int, ...]:
        """Frame-index step of each slider (product order, last name fastest)."""
        sizes = [len(g) for g in self.grid]
        return tuple(int(np.prod(sizes[i + 1 :], dtype=int)) for i in range(len(sizes)))

    def index(self, **values: Any) -> int:
        """Index of the frame drawn at the given slider values (each must be a grid value)."""
        i = 0
        for name, g, s in zip(self.names, self.grid, self.strides):
            if values[name] not in g:
                raise ModelError(
                    f"{name}: expected one of the grid values {list(g)}, got {values[name]!r}"
                )
            i += s * g.index(values[name])
        return i

    def frame_alt(self, point: Sequence[int]) -> str:
        """Alt text of the frame at grid indices ``point``: :attr:`alt` and the values shown."""
        said = ", ".join(
            f"{label} = {_fmt(g[i])}" for label, g, i in zip(self.labels, self.grid, point)
        )
        return f"{self.alt} Shown at {said}."

    def __repr__(self) -> str:
        # the notebook's text/plain beside the HTML: a summary, not megabytes of frames
        sizes = " x ".join(f"{n} ({len(g)})" for n, g in zip(self.names, self.grid))
        return f"<Explorable {sizes}: {len(self.frames)} frames, {self.nbytes / 1e6:.2f} MB>"

    @property
    def nbytes(self) -> int:
        """Size of the HTML of this explorable, in bytes (its page weight)."""
        return len(self._repr_html_().encode("utf-8"))

    def _repr_html_(self) -> str:
        uid = "fdi-explorable-" + uuid.uuid5(uuid.NAMESPACE_OID, "".join(self.frames[:2])).hex[:12]
        start = sum(s * d for s, d in zip(self.strides, self.default))
        shown = [[_fmt(v) for v in g] for g in self.grid]
        sliders = "".join(
            # wraps on a phone: label, slider and value each on their own line if need be; the
            # value is read out by the slider itself (aria-valuetext), not again by its <output>
            f'<label style="display:flex;flex-wrap:wrap;align-items:center;gap:0.2em 0.6em;margin:0.2em 0">'
            f'<span>{html.escape(label)}</span><input type="range" min="0" max="{len(g) - 1}" '
            f'step="1" value="{d}" aria-valuetext="{html.escape(s[d], quote=True)}" '
            f'style="width:12em;max-width:100%">'
            f'<output aria-hidden="true">{html.escape(s[d])}</output></label>'
            for label, g, d, s in zip(self.labels, self.grid, self.default, shown)
        )
        script = _SCRIPT % {
            "id": json.dumps(uid),
            "frames": json.dumps(list(self.frames)),
            "labels": json.dumps(shown),
            "strides": json.dumps(list(self.strides)),
            "names": json.dumps(list(self.labels)),
            "alt": json.dumps(self.alt),
        }
        hidden = "position:absolute;width:1px;height:1px;overflow:hidden;clip-path:inset(50%)"
        return (
            f'<figure class="fdi-explorable" id="{uid}" data-frame="{start}">'
            f'<div class="fdi-explorable-sliders">{sliders}</div>'
            f'<img src="data:image/png;base64,{self.frames[start]}" '
            f'alt="{html.escape(self.frame_alt(self.default), quote=True)}" '
            f'style="max-width:100%;height:auto">'
            f'<p class="fdi-explorable-live" aria-live="polite" style="{hidden}"></p>'
            f"<figcaption>{self.caption}</figcaption></figure><script>{script}</script>"
        )

    def small_multiples(self, panels: int = PANELS) -> bytes:
        """A few frames as one PNG, for paper: two per row, each titled with its slider values,
        drawn again by the callback for paper.

        The frames are spread evenly over each slider's values and always include the shown
        (default) value: ``panels`` values of a single slider, two values (the default and the
        value farthest from it) of each of the first two sliders otherwise, the other sliders at
        their defaults; only as many rows as fit the tallest image of a page
        (:data:`PAPER_IMAGE_HEIGHT_IN`) at the width of the text (:data:`PAPER_TEXT_WIDTH_IN`).
        Each is drawn by the callback and :func:`fdi_lib.plotting.for_paper`, its text (and the
        titles') enlarged to print at :data:`PAPER_DRAWN_FONT_PT` or more at that width, up to
        :data:`PAPER_GROWTH` times taller where the page has room. The PNG
        carries the caption (``fdi:caption``, HTML) and the house-style metadata (smallest font,
        resolution); its palette has 256 colours.

        Parameters
        ----------
        panels : int
            Frames to show when there is a single slider (at least 2).
        """
        return self._small_multiples(panels, self._frame_info())

    def _frame_info(self) -> dict[str, float]:
        """The shown frame's size in pixels, resolution and smallest text (its PNG metadata)."""
        from PIL import Image

        first = Image.open(
            io.BytesIO(
                base64.b64decode(
                    self.frames[sum(s * d for s, d in zip(self.strides, self.default))]
                )
            )
        )
        return {
            "width": first.width,
            "height": first.height,
            "dpi": float(first.info.get("fdi:dpi", DISPLAY_DPI)),
            "min_font_pt": float(first.info["fdi:min_font_pt"]),
        }

    def _small_multiples(self, panels: int, frame: Mapping[str, float]) -> bytes:
        """:meth:`small_multiples` with the shown frame's :meth:`_frame_info` given."""
        import matplotlib.pyplot as plt
        from PIL import Image
        from PIL.PngImagePlugin import PngInfo

        from fdi_lib.plotting import STYLE

        if isinstance(panels, bool) or not isinstance(panels, int) or panels < 2:
            raise ModelError(f"panels: expected an integer of at least 2, got {panels!r}")
        columns = 2
        dpi = float(frame["dpi"])
        width, height = frame["width"] / dpi, frame["height"] / dpi  # inches
        scale = min(1.0, PAPER_TEXT_WIDTH_IN / (columns * width))  # printed / drawn
        font_scale = PAPER_DRAWN_FONT_PT / (float(frame["min_font_pt"]) * scale)
        title_pt = STYLE["axes.titlesize"] * font_scale
        shown = [[_fmt(v) for v in g] for g in self.grid]
        # the longest title the panels can have (the first two sliders' widest values), on as
        # many lines as it needs at the frame's width: every row of titles gets those lines
        longest = ", ".join(
            f"{label} = {max(values, key=len)}" for label, values in zip(self.labels, shown[:2])
        )
        lines = _wrapped(longest, title_pt, width).count("\n") + 1
        title_h = (1.0 + 1.2 * lines) * title_pt / 72  # inches, as _tiled draws them
        rows = max(1, min(2, int(PAPER_IMAGE_HEIGHT_IN / (scale * (height + title_h)))))
        # taller frames where the page has room: the legends above the axes take some of it
        grow = max(
            1.0, min(PAPER_GROWTH, (PAPER_IMAGE_HEIGHT_IN / (scale * rows) - title_h) / height)
        )
        per = (
            [min(panels, len(self.grid[0]), columns * rows)]
            if len(self.grid) == 1
            else [2, 2 if rows > 1 else 1] + [1] * (len(self.grid) - 2)
        )
        picks = [_spread(len(g), d, m) for g, d, m in zip(self.grid, self.default, per)]
        tiles = []
        for point in itertools.product(*picks):
            values = {n: g[i] for n, g, i in zip(self.names, self.grid, point)}
            fig = self.callback(**values, **self.fixed, fig=None)
            try:
                fig.set_size_inches(width, height * grow)
                for_paper(fig, font_scale)
                image = _saved_pixels(fig, dpi * RASTER_SCALE)
                smallest = smallest_font_pt(fig)
            finally:
                plt.close(fig)
            title = ", ".join(
                f"{label} = {shown[j][i]}"
                for j, (label, i) in enumerate(zip(self.labels, point))
                if len(picks[j]) > 1
            )
            tiles.append((image, _wrapped(title, title_pt, width), smallest))
        sheet, title_pt = _tiled(tiles, columns, dpi * RASTER_SCALE, title_pt, lines)
        fonts = [t[2] for t in tiles] + ([title_pt] if title_pt else [])
        info = PngInfo()
        info.add_text("fdi:caption", self.caption)
        info.add_text("fdi:min_font_pt", f"{min(fonts):g}")
        info.add_text("fdi:dpi", f"{dpi * RASTER_SCALE:g}")
        out = io.BytesIO()
        sheet.quantize(colors=256, method=Image.Quantize.FASTOCTREE).save(
            out, format="PNG", pnginfo=info, dpi=(dpi * RASTER_SCALE,) * 2
        )
        return out.getvalue()

    def paper_spec(self) -> dict[str, Any] | None:
        """What :func:`paper_figure` needs to draw :meth:`small_multiples` in another process, as
        JSON values: the callback's name (a function of :data:`PAPER_CALLBACK_PACKAGE`), the
        sliders, the fixed arguments, the caption and the shown frame's :meth:`_frame_info`.
        ``None`` when they cannot say it exactly: a callback defined elsewhere (in a notebook), or
        a value that is not an ``int``, ``float``, ``bool`` or ``str`` (a NumPy scalar, a tuple),
        which JSON would not give back as it is."""
        module = getattr(self.callback, "__module__", None) or ""
        qualname = getattr(self.callback, "__qualname__", "")
        if not module.startswith(PAPER_CALLBACK_PACKAGE) or "<" in qualname:
            return None
        values = [v for g in self.grid for v in g] + list(self.fixed.values())
        if not all(type(v) in (int, float, bool, str) for v in values):
            return None
        return {
            "callback": f"{module}:{qualname}",
            "names": list(self.names),
            "labels": list(self.labels),
            "grid": [list(g) for g in self.grid],
            "default": list(self.default),
            "fixed": dict(self.fixed),
            "caption": self.caption,
            "frame": self._frame_info(),
            "panels": PANELS,
        }

    def _repr_mimebundle_(self, include: Any = None, exclude: Any = None) -> dict[str, Any]:
        """HTML (sliders and frames), a text summary, and for paper the small multiples
        (``image/png``) or, where ``$FDI_PAPER_FIGURES`` is ``deferred`` and the explorable can
        say how to draw them, their :meth:`paper_spec` (:data:`PAPER_SPEC_MIME`)."""
        bundle: dict[str, Any] = {"text/html": self._repr_html_(), "text/plain": repr(self)}
        spec = self.paper_spec()
        if spec is not None:
            bundle[PAPER_SPEC_MIME] = spec
        if spec is None or os.environ.get(PAPER_FIGURES_ENV) != "deferred":
            bundle["image/png"] = self.small_multiples(PANELS)
        return bundle


def paper_figure(spec: Mapping[str, Any]) -> bytes:
    """The small multiples (:meth:`Explorable.small_multiples`) of the explorable that
    :meth:`Explorable.paper_spec` describes, drawn in this process: the same PNG, byte for byte,
    as the explorable's own (its callback imported by name and called at the same values, in the
    book's style).

    Raises
    ------
    ModelError
        ``spec`` is not such a specification (a missing key, or a callback outside
        :data:`PAPER_CALLBACK_PACKAGE` or not found there).
    """
    import matplotlib as mpl

    from fdi_lib.plotting import use_style

    keys = ("callback", "names", "labels", "grid", "default", "fixed", "caption", "frame", "panels")
    if not isinstance(spec, Mapping) or set(keys) - set(spec):
        missing = sorted(set(keys) - set(spec)) if isinstance(spec, Mapping) else keys
        raise ModelError(f"spec: expected an explorable's paper_spec, missing {list(missing)}")
    module, _, qualname = str(spec["callback"]).partition(":")
    if not module.startswith(PAPER_CALLBACK_PACKAGE) or not qualname:
        raise ModelError(
            f"spec['callback']: expected 'module:function' of {PAPER_CALLBACK_PACKAGE}*, got "
            f"{spec['callback']!r}"
        )
    try:
        callback: Any = importlib.import_module(module)
        for part in qualname.split("."):
            callback = getattr(callback, part)
    except (ImportError, AttributeError) as exc:
        raise ModelError(f"spec['callback']: {spec['callback']!r} not found ({exc})") from None
    ex = Explorable(
        names=tuple(spec["names"]),
        labels=tuple(spec["labels"]),
        grid=tuple(tuple(g) for g in spec["grid"]),
        frames=(),
        data=(),
        default=tuple(spec["default"]),
        caption=spec["caption"],
        alt="",
        callback=callback,
        fixed=dict(spec["fixed"]),
    )
    with mpl.rc_context():
        use_style()
        return ex._small_multiples(spec["panels"], spec["frame"])


def _saved_pixels(fig: Figure, dpi: float) -> Any:
    """The RGB image of ``fig`` that ``savefig`` at ``dpi`` on white writes (animated artists
    included): its raw pixels, the very pixels of its PNG without encoding and decoding one (a
    PNG per panel of the small multiples took a fifth of their time). ``fig`` is left at ``dpi``,
    whose canvas gives the size of the pixels."""
    from PIL import Image

    fig.set_dpi(dpi)
    out = io.BytesIO()
    fig.savefig(out, format="rgba", dpi=dpi, facecolor="white")
    return Image.frombuffer(
        "RGBA", fig.canvas.get_width_height(), out.getvalue(), "raw", "RGBA", 0, 1
    ).convert("RGB")


def _spread(n: int, default: int, m: int) -> list[int]:
    """``m`` indices of ``range(n)`` spread evenly, ``default`` among them (replacing the
    nearest): ``_spread(10, 2, 4) == [0, 2, 6, 9]``; with ``m == 2``, the default and the end
    farthest from it."""
    if m == 1:
        return [default]
    picks = sorted({int(round(x)) for x in np.linspace(0, n - 1, m)})
    nearest = min(picks, key=lambda i: (abs(i - default), i))
    return sorted({default, *(i for i in picks if i != nearest)})


def _wrapped(title: str, size: float, width: float) -> str:
    """``title`` on as many lines as it needs to fit ``width`` inches at ``size`` points (with
    a margin), broken after its commas (between slider values)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = Figure(dpi=72)
    renderer = FigureCanvasAgg(fig).get_renderer()

    def fits(text: str) -> bool:
        return (
            fig.text(0, 0, text, fontsize=size).get_window_extent(renderer).width
            < 0.95 * width * 72
        )

    parts = title.split(", ")
    lines = parts[:1]
    for part in parts[1:]:
        if fits(f"{lines[-1]}, {part}"):
            lines[-1] = f"{lines[-1]}, {part}"
        else:
            lines[-1] += ","
            lines.append(part)
    return "\n".join(lines)


def _tiled(
    tiles: Sequence[tuple[Any, str, Any]],
    columns: int,
    dpi: float,
    title_pt: float,
    title_lines: int,
) -> tuple[Any, float | None]:
    """One RGB image of the ``(image, title, _)`` tiles, ``columns`` per row, each image pasted
    unscaled (no resampling) under its title (room for ``title_lines`` lines), and the size of
    the titles (``title_pt`` points at ``dpi``; ``None`` without titles). The titles alone are drawn by
    matplotlib, on a white sheet; Pillow pastes the images (an Agg ``figimage`` of the frames
    took ten times longer)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    w = max(t[0].width for t in tiles)
    h = max(t[0].height for t in tiles)
    size = title_pt if any(t[1] for t in tiles) else None
    title_h = int((1.0 + 1.2 * title_lines) * size / 72 * dpi) if size else 0
    rows, cols = -(-len(tiles) // columns), min(columns, len(tiles))
    width, height = cols * w, rows * (h + title_h)
    fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi, facecolor="white")
    canvas = FigureCanvasAgg(fig)
    for k, (_, title, _) in enumerate(tiles):
        r, c = divmod(k, columns)
        if title:
            fig.text(
                (c * w + w / 2) / width,
                1 - (r * (h + title_h) + title_h / 2) / height,
                title,
                ha="center",
                va="center",
                fontsize=size,
            )
    canvas.draw()
    sheet = Image.frombuffer(
        "RGBA", canvas.get_width_height(), canvas.buffer_rgba(), "raw", "RGBA", 0, 1
    )
    sheet = sheet.convert("RGB")
    for k, (image, _, _) in enumerate(tiles):
        r, c = divmod(k, columns)
        sheet.paste(image, (c * w, r * (h + title_h) + title_h))
    return sheet, size


#: Characters with a Unicode subscript ("_") or superscript ("^") form, and those forms.
_SCRIPTS = {
    "_": ("0123456789+-=()aehijklmnoprstuvx", "₀₁₂₃₄₅₆₇₈₉₊₋₌₍₎ₐₑₕᵢⱼₖₗₘₙₒₚᵣₛₜᵤᵥₓ"),
    "^": ("0123456789+-=()niT", "⁰¹²³⁴⁵⁶⁷⁸⁹⁺⁻⁼⁽⁾ⁿⁱᵀ"),
}


def script_text(text: str, mark: str) -> str:
    """``text`` as a subscript (``mark`` "_") or superscript ("^") in plain text: in Unicode
    scripts where every character has one ("k" → "ₖ"), else after the mark ("_N", "_(k|k-1)").
    Used for alt texts, here and by the book's extension (``_ext/fdi_book.py``)."""
    plain, scripted = _SCRIPTS[mark]
    text = text.replace("\u2212", "-")
    if text and all(c in plain for c in text):
        return text.translate(str.maketrans(plain, scripted))
    return f"{mark}{text}" if len(text) == 1 else f"{mark}({text})"


class _CaptionText(html.parser.HTMLParser):
    """Collects the text of an HTML caption, ``<sub>``/``<sup>`` text by :func:`script_text`."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.parts: list[str] = []
        self.open: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.open.append(tag)

    def handle_endtag(self, tag):
        if tag in self.open:
            del self.open[len(self.open) - 1 - self.open[::-1].index(tag)]

    def handle_data(self, data):
        kind = next((t for t in reversed(self.open) if t in ("sub", "sup")), None)
        self.parts.append(
            data if kind is None else script_text(data, "_" if kind == "sub" else "^")
        )


def caption_text(caption: str) -> str:
    """The plain text of an HTML caption, for the image's alt text.

    >>> caption_text("GLR l<sub>k</sub> &amp; <i>w</i> = 100")
    'GLR lₖ & w = 100'
    """
    parser = _CaptionText()
    parser.feed(caption)
    parser.close()
    return " ".join("".join(parser.parts).split())


def _sentence(text: str) -> str:
    """``text`` on one line, ending with a full stop (an alt text that values follow)."""
    text = " ".join(text.split())
    return text if text.endswith((".", "!", "?")) else text + "."


def _fmt(v: Any) -> str:
    return f"{v:g}" if isinstance(v, (float, np.floating)) else str(v)


def _name(callback: Any) -> str:
    return getattr(callback, "__qualname__", None) or type(callback).__name__


def _check_grid(
    grid: Any, fixed: Mapping[str, Any]
) -> tuple[tuple[str, ...], tuple[tuple[Any, ...], ...]]:
    """The names and values of a grid, each value list checked: a 1-D sequence of at least two
    distinct values, finite where they are numbers (a NaN would match no slider position)."""
    if not isinstance(grid, Mapping):
        raise ModelError(
            f"grid: expected a mapping of keyword names to sequences of values, got "
            f"{type(grid).__name__}"
        )
    if not grid or any(
        not isinstance(v, (str, bytes)) and np.ndim(v) >= 1 and len(v) < 2 for v in grid.values()
    ):
        raise ModelError(
            f"grid: expected at least one name with two or more values each, got {dict(grid)!r}"
        )
    names, values = [], []
    for name, vals in grid.items():
        if not isinstance(name, str) or not name.isidentifier() or name == "fig":
            raise ModelError(
                f"grid: expected keyword names of the callback (not 'fig'), got {name!r}"
            )
        if name in fixed:
            raise ModelError(
                f"grid: {name!r} is also given as a fixed keyword argument; expected one or the other"
            )
        if isinstance(vals, (str, bytes, Mapping)) or np.ndim(vals) != 1:
            what = f"shape {np.shape(vals)}" if np.ndim(vals) > 1 else type(vals).__name__
            raise ShapeError(f"grid[{name!r}]: expected a 1-D sequence of values, got {what}")
        vals = tuple(vals)
        for i, v in enumerate(vals):
            if isinstance(v, (float, np.floating)) and not np.isfinite(v):
                raise NonFiniteError(
                    f"grid[{name!r}]: expected finite values, got {v} at index {i}"
                )
            j = vals.index(v)
            if j != i:
                raise ModelError(
                    f"grid[{name!r}]: expected distinct values, got {v!r} at indices {j} and {i}"
                )
        names.append(name)
        values.append(vals)
    return tuple(names), tuple(values)


def explorable(
    callback: Callable[..., Figure],
    grid: Mapping[str, Sequence[Any]],
    *,
    caption: str,
    alt: str | None = None,
    labels: Mapping[str, str] | None = None,
    default: Mapping[str, Any] | None = None,
    **fixed: Any,
) -> Explorable:
    """Evaluate ``callback(**values, **fixed, fig=fig)`` over the grid; one frame per point.

    Parameters
    ----------
    callback : callable
        Widget callback drawing into ``fig`` and returning it (``fdi_lib.widgets.*``).
    grid : mapping of str to sequence
        Slider values per keyword argument (at least one name, each with at least two values).
    caption : str
        Caption shown under the figure.
    alt : str, optional
        What the figure shows, in one or two sentences of plain text, for a reader who cannot
        see it (the image's alt text, followed by the slider values of the frame shown); by
        default the caption's text.
    labels : mapping of str to str, optional
        Slider labels on the page (default: the names).
    default : mapping of str to value, optional
        Values shown first (grid values; default: the first of each).
    **fixed
        Keyword arguments passed unchanged to every call.

    Returns
    -------
    Explorable
        Displays as HTML (``_repr_html_``) in a notebook.

    Raises
    ------
    ModelError, ShapeError, NonFiniteError
        A grid that is not a mapping of keyword names to 1-D sequences of at least two distinct
        (finite) values, a name also given in ``fixed``, bad ``labels``/``default``/``caption``,
        or a callback that does not return a matplotlib Figure (the message names the point).
    ResourceError
        More than :data:`MAX_FRAMES` grid points (before anything is drawn), or frames heavier
        than :data:`MAX_BYTES` in all (as soon as they are).
    """
    import matplotlib.pyplot as plt

    names, values = _check_grid(grid, fixed)
    if not callable(callback):
        raise ModelError(
            f"callback: expected a function drawing into fig and returning it, got "
            f"{type(callback).__name__}"
        )
    if not isinstance(caption, str):
        raise ModelError(f"caption: expected a string, got {type(caption).__name__}")
    if alt is not None and (not isinstance(alt, str) or not alt.strip()):
        raise ModelError(f"alt: expected a non-empty string of plain text, got {alt!r}")
    if labels is not None and (not isinstance(labels, Mapping) or set(labels) - set(names)):
        raise ModelError(
            f"labels: expected a mapping of grid names {list(names)} to labels, got {labels!r}"
        )
    if default is not None and not isinstance(default, Mapping):
        raise ModelError(
            f"default: expected a mapping of grid names to values, got {type(default).__name__}"
        )
    default = dict(default or {})
    unknown = set(default) - set(names)
    if unknown:
        raise ModelError(
            f"default: expected names of the grid {list(names)}, got {sorted(unknown)}"
        )
    start = []
    for n, g in zip(names, values):
        if n in default and default[n] not in g:
            raise ModelError(
                f"default: expected {n} among the grid values {list(g)}, got {default[n]!r}"
            )
        start.append(g.index(default[n]) if n in default else 0)
    n_frames = int(np.prod([len(g) for g in values]))
    if n_frames > MAX_FRAMES:
        sizes = " x ".join(f"{len(g)} ({n})" for n, g in zip(names, values))
        raise ResourceError(
            f"grid: expected at most {MAX_FRAMES} frames (MAX_FRAMES), got {sizes} = "
            f"{n_frames}: use fewer values"
        )
    fig = None
    frames: list[str] = []
    data = []
    weight = 0
    try:
        for point in itertools.product(*values):
            kwargs = dict(zip(names, point))
            try:
                out = callback(**kwargs, **fixed, fig=fig)
            except Exception as exc:
                exc.add_note(f"explorable: while drawing the frame at {kwargs}")
                raise
            if not isinstance(out, Figure):
                raise ModelError(
                    f"callback: expected a matplotlib Figure from {_name(callback)}({kwargs}), "
                    f"got {type(out).__name__}"
                )
            if fig is not None and out is not fig:
                plt.close(fig)  # the callback drew a new figure instead of reusing this one
            fig = out
            frames.append(_png_frame(fig))
            data.append(figure_data(fig))
            weight += len(frames[-1])
            if weight > MAX_BYTES:
                raise ResourceError(
                    f"grid: expected at most {MAX_BYTES / 1e6:g} MB of frames (MAX_BYTES), got "
                    f"{weight / 1e6:.2f} MB after {len(frames)} of {n_frames} frames (about "
                    f"{weight / len(frames) * n_frames / 1e6:.1f} MB for all): use fewer "
                    f"values or a simpler figure"
                )
    finally:
        if fig is not None:
            plt.close(fig)
    labels = dict(labels or {})
    return Explorable(
        names=names,
        labels=tuple(labels.get(n, n) for n in names),
        grid=values,
        frames=tuple(frames),
        data=tuple(data),
        default=tuple(start),
        caption=caption,
        alt=_sentence(alt or caption_text(caption)),
        callback=callback,
        fixed=dict(fixed),
    )
