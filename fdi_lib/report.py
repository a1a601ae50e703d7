"""Numbers and tables for readers: one place for every format the book prints.

The chapters never format numbers themselves: they call these functions, so that a rate, a
count or a time looks the same on every page, and the formats are tested once
(``tests/test_report.py``). Each ``fmt_*`` function returns a string; :func:`table` returns a
:class:`Table`, which Jupyter (and the built book) displays as an HTML table with human row
labels, a units column if given, and notes under it; the PDF edition of the book shows it as a
Markdown table (``_repr_markdown_``), which myst-nb's LaTeX output renders as a real table.

Conventions
-----------
- counts are integers (``fmt_count``);
- rates are percentages with their 95 % interval when one is known (``fmt_rate``);
- times are in ms below one second, in s above (``fmt_time``);
- other numbers get 3 significant digits, a plain decimal form between 1e-3 and 1e5 and a
  ``×10^n`` form outside it; numbers below ``tiny`` in magnitude print as ``< tiny``
  (``fmt_number``);
- a missing value is written ``n/a`` and a note under the table says why (:data:`NA`);
- a number and its unit, and the two bounds of an interval, are joined by a no-break space
  (:data:`NBSP`; shown as a space in the examples below), so a narrow cell wraps only between a
  rate and its interval.

Examples
--------
>>> fmt_rate(0.017, (0.0098, 0.027)).replace(NBSP, " ")
'1.7 % [0.98, 2.7]'
>>> fmt_time(0.00122).replace(NBSP, " ")
'1.22 ms'
>>> fmt_number(5.351584e-235)
'< 10⁻¹⁵'
>>> fmt_count(7.0)
'7'
"""

from __future__ import annotations

import html
import math
import numbers
import re
import unicodedata
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

from .errors import ModelError

__all__ = [
    "NA",
    "NBSP",
    "fmt_count",
    "fmt_rate",
    "fmt_time",
    "fmt_number",
    "fmt_value",
    "Table",
    "table",
    "text_pieces",
    "markdown_text",
    "glue",
]

#: What a table cell shows when a value does not exist; the table's notes say why.
NA = "n/a"

#: No-break space: a number stays with its unit and an interval's bounds stay together, so that a
#: narrow table cell wraps only between a rate and its interval.
#:
#: :meta hide-value:
NBSP = "\u00a0"

_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _finite_number(x: Any, name: str) -> float:
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        raise ModelError(f"{name} must be a real number, got {type(x).__name__} {x!r}")
    x = float(x)
    if not math.isfinite(x):
        raise ModelError(f"{name} must be finite, got {x!r}")
    return x


def _sig(x: float, digits: int) -> str:
    """``x`` with ``digits`` significant digits in plain decimal form, trailing zeros dropped."""
    if x == 0:
        return "0"
    decimals = max(digits - 1 - math.floor(math.log10(abs(x))), 0)
    s = f"{x:.{decimals}f}"
    return s.rstrip("0").rstrip(".") if "." in s else s


def fmt_count(n: Any) -> str:
    """An integer count, with thin-space thousands separators (``12 345``).

    Parameters
    ----------
    n : int or float
        A count; a float must be integral (``7.0`` prints as ``7``).
    """
    x = _finite_number(n, "n")
    if x != round(x):
        raise ModelError(f"n must be an integral count, got {n!r}")
    return f"{int(round(x)):,}".replace(",", "\u202f")


def fmt_number(x: Any, digits: int = 3, tiny: float = 1e-15) -> str:
    """A real number with ``digits`` significant digits, for a reader.

    Parameters
    ----------
    x : float
        The number (NaN and infinities are rejected: a missing value is :data:`NA`).
    digits : int
        Significant digits.
    tiny : float
        Magnitudes below this print as ``< tiny`` (underflow, not information).
    """
    x = _finite_number(x, "x")
    if x == 0:
        return "0"
    if abs(x) < tiny:
        return "< " + fmt_number(tiny, 1, tiny=0.0)
    if 1e-3 <= abs(x) < 1e5:
        return _sig(x, digits)
    exponent = math.floor(math.log10(abs(x)))
    mantissa = x / 10**exponent
    if round(mantissa, digits - 1) in (10.0, -10.0):
        mantissa, exponent = mantissa / 10, exponent + 1
    m = _sig(mantissa, digits)
    power = "10" + str(exponent).translate(_SUPERSCRIPT)
    if m in ("1", "-1"):
        return m[:-1] + power
    return f"{m}×{power}"


def fmt_rate(rate: Any, ci: Sequence[float] | None = None, digits: int = 2) -> str:
    """A rate (a fraction in [0, 1]) as a percentage, with its interval if given.

    Parameters
    ----------
    rate : float or None
        The fraction; ``None`` gives :data:`NA`.
    ci : (float, float), optional
        Its interval (fractions), printed in percent in brackets.
    digits : int
        Significant digits of each percentage (0 and 100 print exactly).
    """
    if rate is None:
        return NA
    r = _finite_number(rate, "rate")
    if not 0.0 <= r <= 1.0:
        raise ModelError(f"rate must be a fraction in [0, 1], got {rate!r}")
    out = f"{_pct(r, digits)}{NBSP}%"
    if ci is not None:
        if len(ci) != 2:
            raise ModelError(f"ci must be a pair (low, high), got {ci!r}")
        lo, hi = (_finite_number(c, "ci") for c in ci)
        if not 0.0 <= lo <= hi <= 1.0:
            raise ModelError(f"ci must satisfy 0 <= low <= high <= 1, got {ci!r}")
        out += f" [{_pct(lo, digits)},{NBSP}{_pct(hi, digits)}]"
    return out


def _pct(r: float, digits: int) -> str:
    p = 100.0 * r
    if p in (0.0, 100.0):
        return f"{p:.0f}"
    return _sig(p, digits)


def fmt_time(seconds: Any, digits: int = 3) -> str:
    """A duration: µs, ms below one second, s up to two minutes, then min.

    Parameters
    ----------
    seconds : float
        Non-negative duration in seconds.
    digits : int
        Significant digits.
    """
    s = _finite_number(seconds, "seconds")
    if s < 0:
        raise ModelError(f"seconds must be non-negative, got {seconds!r}")
    if s == 0:
        return f"0{NBSP}s"
    if s < 1e-3:
        return f"{_sig(s * 1e6, digits)}{NBSP}µs"
    if s < 1.0:
        return f"{_sig(s * 1e3, digits)}{NBSP}ms"
    if s < 120.0:
        return f"{_sig(s, digits)}{NBSP}s"
    return f"{_sig(s / 60.0, digits)}{NBSP}min"


def fmt_value(v: Any, digits: int = 3) -> str:
    """Any cell value: ``None`` → :data:`NA`, bool → yes/no, int → count, float → number,
    sequence → comma-separated values in brackets, string unchanged."""
    if v is None:
        return NA
    if isinstance(v, str):
        return v
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, numbers.Integral):
        return fmt_count(v)
    if isinstance(v, numbers.Real):
        if math.isnan(float(v)):
            raise ModelError(
                "a table cell is NaN: pass None (shown as n/a) and explain it in a note"
            )
        return fmt_number(v, digits)
    if isinstance(v, (list, tuple)) or hasattr(v, "tolist"):
        seq = v.tolist() if hasattr(v, "tolist") else v
        if not isinstance(seq, list):
            return fmt_value(seq, digits)
        return "[" + ", ".join(fmt_value(x, digits) for x in seq) + "]"
    raise ModelError(f"cannot format a table cell of type {type(v).__name__}")


@dataclass(frozen=True)
class Table:
    """A small table for readers: row labels, column headers, formatted cells and notes.

    Displayed as HTML in Jupyter and in the built book (``_repr_html_``), as a Markdown pipe table
    in the PDF edition (``_repr_markdown_``: the LaTeX builder of myst-nb takes ``text/markdown``
    before ``text/plain`` and has no use for HTML); ``str()`` gives a plain-text version;
    :meth:`to_frame` a pandas DataFrame of the formatted cells.
    """

    columns: tuple[str, ...]
    rows: tuple[tuple[str, tuple[str, ...]], ...]
    notes: tuple[str, ...] = field(default=())
    index_header: str = ""

    def _repr_html_(self) -> str:
        esc = _html_text

        def header(text: str, scope: str) -> str:
            # headers carry their scope for screen readers; an empty one (the corner, a row that
            # continues the one above) is a data cell, not a header without a name (axe-core's
            # empty-table-header)
            return f'<th scope="{scope}">{esc(text)}</th>' if text.strip() else "<td></td>"

        head = "".join(header(c, "col") for c in (self.index_header, *self.columns))
        # each cell names its column (data-label): on a phone, a table too wide for the column
        # shows each row as a card, every cell after its column's header (the book's CSS)
        labels = [f' data-label="{html.escape(c, quote=True)}"' for c in self.columns]
        body = "".join(
            "<tr>"
            + header(label, "row")
            + "".join(f"<td{lab}>{esc(c)}</td>" for lab, c in zip(labels, cells))
            + "</tr>"
            for label, cells in self.rows
        )
        notes = "".join(f"<li>{esc(n)}</li>" for n in self.notes)
        foot = f'<ul class="fdi-table-notes">{notes}</ul>' if notes else ""
        return (
            f'<div class="fdi-table-wrap"><table class="fdi-table"><thead><tr>{head}</tr></thead>'
            f"<tbody>{body}</tbody></table>{foot}</div>"
        )

    def _repr_markdown_(self) -> str:
        head = (self.index_header, *self.columns)
        lines = ["| " + " | ".join(_md_cell(c) for c in head) + " |", "|" + "---|" * len(head)]
        lines += [
            "| " + " | ".join(_md_cell(c) for c in (label, *cells)) + " |"
            for label, cells in self.rows
        ]
        if self.notes:
            lines += [""] + [f"- {_md_cell(n)}" for n in self.notes]
        return "\n".join(lines) + "\n"

    def __str__(self) -> str:
        widths = [max(len(self.index_header), *(len(r[0]) for r in self.rows))] + [
            max(len(c), *(len(r[1][j]) for r in self.rows)) for j, c in enumerate(self.columns)
        ]
        line = lambda cells: "  ".join(c.ljust(w) for c, w in zip(cells, widths)).rstrip()  # noqa: E731
        out = [line((self.index_header, *self.columns))]
        out += [line((label, *cells)) for label, cells in self.rows]
        out += [f"note: {n}" for n in self.notes]
        return "\n".join(out)

    def to_frame(self):
        """The formatted cells as a :class:`pandas.DataFrame` (strings), indexed by row label."""
        import pandas as pd

        return pd.DataFrame(
            [list(c) for _, c in self.rows],
            index=[r for r, _ in self.rows],
            columns=list(self.columns),
        )


#: Characters with a meaning in MyST Markdown (emphasis, links, maths, roles, HTML, cell borders),
#: escaped in a table cell; CommonMark removes the backslash before any ASCII punctuation.
_MD_SPECIAL = re.compile(r"([\\`*_{}\[\]<>|$~#&!])")


#: A name from the code in a table's text: an identifier with an underscore between words
#: (``lars_path``, ``explore_glr``) or a Python file (``tools/build_report.py``). A one-character
#: subscript (``x_k``, ``Gamma_k``) is not one: it is maths (:data:`_SYMBOL`).
_CODE_NAME = re.compile(
    r"(?<![\w/.-])((?:[\w-]+/)*(?:(?:[A-Za-z]\w*\.)*[A-Za-z][A-Za-z0-9]*(?:_[A-Za-z0-9]{2,})+"
    r"(?:\.[A-Za-z]\w*)*(?:\.py)?|[\w-]+\.py))(?![\w/])"
)
#: What a table's text marks itself: maths as TeX between dollars (``$C_{m\eta}$``) and code
#: between backticks (a dotted name without an underscore, ``fdi_lib.report``).
_MARKED = re.compile(r"\$([^$\s](?:[^$]*[^$\s])?)\$|`([^`\n]+)`")
_GREEK = (
    "alpha beta gamma delta epsilon zeta eta theta iota kappa lambda mu nu xi pi rho sigma tau "
    "upsilon phi chi psi omega"
).split()
#: Greek letters as TeX macros, by name ("beta", "Gamma") and as Unicode letters ("ζ", "Γ"); the
#: capitals that look like Latin letters (A, B, ...) have no macro and are not listed.
_CAPITALS = "gamma delta theta lambda xi pi sigma upsilon phi psi omega".split()
_GREEK_TEX = {
    **{g: "\\" + g for g in _GREEK},
    **{g.title(): "\\" + g.title() for g in _CAPITALS},
    **{
        unicodedata.lookup(f"greek small letter {g.replace('lambda', 'lamda')}"): "\\" + g
        for g in _GREEK
    },
    **{
        unicodedata.lookup(f"greek capital letter {g.replace('lambda', 'lamda')}"): "\\" + g.title()
        for g in _CAPITALS
    },
}
#: An ASCII symbol with a subscript or a superscript, as a table's text writes it: a letter, a
#: Greek letter (by name or Unicode) or max/min, then ``_k``, ``_{k+1}``, ``_(k-1)`` or
#: ``_1,m1`` (a comma and no space: one subscript, the wind turbine's ``beta_1,m1``), then
#: ``^2``, ``^{-1}``. A name of several letters with a subscript of two (``lars_path``) is code.
_SYMBOL = re.compile(
    r"(?<![\w\\])(?P<base>"
    + "|".join(sorted(_GREEK_TEX, key=len, reverse=True) + ["max", "min"])
    + r"|[A-Za-z])"
    r"(?:_(?P<sub>\{[^{}\n]*\}|\([^()\n]*\)|[A-Za-z0-9]+(?:,[A-Za-z0-9]+)*))?"
    r"(?:\^(?P<sup>\{[^{}\n]*\}|\([^()\n]*\)|[A-Za-z0-9]+))?"
    r"(?![A-Za-z0-9_])"
)
#: A norm written with double bars: ``||r_k||`` or ``||x||_2``.
_NORM = re.compile(r"\|\|([^|\n]+?)\|\|(?:_(\w+))?")


def _tex_group(s: str) -> str:
    """A sub- or superscript as TeX: braces kept, parentheses dropped, longer than one character
    braced."""
    if s.startswith("(") or s.startswith("{"):
        s = s[1:-1]
    return s if len(s) == 1 else "{" + s + "}"


def _symbol_tex(m: re.Match) -> str:
    base = m["base"]
    tex = _GREEK_TEX.get(base, "\\" + base if base in ("max", "min") else base)
    if m["sub"]:
        tex += "_" + _tex_group(m["sub"])
    if m["sup"]:
        tex += "^" + _tex_group(m["sup"])
    return tex


def text_pieces(text: Any) -> list[tuple[str, str]]:
    r"""A table's or a note's text cut into ``(kind, piece)``: ``"text"``, ``"code"`` (a name from
    the code: an identifier with an underscore between words, a dotted name with one, a Python
    file, or what the text writes between backticks) or ``"math"`` (TeX:
    what the text writes between dollars, and the ASCII symbols with a sub- or superscript,
    ``x_k``, ``Gamma_k``, ``beta_1,m1``, ``V^2``, and norms ``||r||``, as maths).

    The renderings of a :class:`Table` (HTML, Markdown) and the claims ledger set the names as
    code and the symbols as maths from these pieces (issue 33: a reader, and a screen reader,
    reads ``explore_glr`` as a name and :math:`M_u` as a symbol, not as ``M`` and ``_u``); the
    plain text (``str``, the JSON) keeps the text as written. Symbols side by side (``H_k ζ_k``)
    make one formula.

    Examples
    --------
    >>> text_pieces("l_k of explore_glr")
    [('math', 'l_k'), ('text', ' of '), ('code', 'explore_glr')]
    >>> text_pieces("max_k |beta_1,m1|, $y_{k+1}$")
    [('math', '\\max_k'), ('text', ' |'), ('math', '\\beta_{1,m1}'), ('text', '|, '), ('math', 'y_{k+1}')]
    """
    out: list[tuple[str, str]] = []

    def add(kind: str, piece: str) -> None:
        if not piece:
            return
        if out and out[-1][0] == kind == "text":
            out[-1] = ("text", out[-1][1] + piece)
        elif kind == "math" and len(out) >= 1 and out[-1][0] == "math":
            out[-1] = ("math", out[-1][1] + " " + piece)
        elif (
            kind == "math"
            and len(out) >= 2
            and out[-1][0] == "text"
            and not out[-1][1].strip()
            and out[-2][0] == "math"
        ):
            out[-2:] = [("math", out[-2][1] + " " + piece)]
        else:
            out.append((kind, piece))

    def symbols(part: str) -> None:
        pos = 0
        for m in re.finditer(f"{_NORM.pattern}|{_SYMBOL.pattern}", part):
            if m.group(0).startswith("||"):
                inner = "".join(piece for _, piece in text_pieces(m.group(1)))
                tex = f"\\Vert {inner}\\Vert" + (f"_{_tex_group(m.group(2))}" if m.group(2) else "")
            elif m["sub"] is None and m["sup"] is None:
                continue
            else:
                tex = _symbol_tex(m)
            add("text", part[pos : m.start()])
            add("math", tex)
            pos = m.end()
        add("text", part[pos:])

    def names(part: str) -> None:
        for j, piece in enumerate(_CODE_NAME.split(part)):
            if j % 2:
                add("code", piece)
            else:
                symbols(piece)

    text, pos = str(text), 0
    for m in _MARKED.finditer(text):
        names(text[pos : m.start()])
        if m[1] is not None:
            add("math", m[1])
        else:
            add("code", m[2])
        pos = m.end()
    names(text[pos:])
    return out


def _html_text(text: str) -> str:
    """A table cell's or note's text as HTML: escaped, the names from the code as code and the
    maths as maths (:func:`text_pieces`), which the page's MathJax typesets."""
    render = {
        "text": html.escape,
        "code": lambda p: f"<code>{html.escape(p)}</code>",
        "math": lambda p: (
            f'<span class="math notranslate nohighlight">\\({html.escape(p)}\\)</span>'
        ),
    }
    return "".join(render[kind](piece) for kind, piece in text_pieces(text))


def markdown_text(text: Any) -> str:
    """Text as MyST Markdown that reads as written: special characters escaped, line breaks as
    spaces (no-break spaces kept), the names from the code as code and the maths as maths
    (:func:`text_pieces`). For a table's cells (the PDF) and for text glued into a page with
    ``{glue:md}`` (an ``IPython.display.Markdown`` of it).

    Examples
    --------
    >>> markdown_text("pitch sensor beta_1,m1 of *explore_glr*")
    'pitch sensor $\\\\beta_{1,m1}$ of \\\\*`explore_glr`\\\\*'
    """
    render = {
        "text": lambda p: _MD_SPECIAL.sub(r"\\\1", p),
        "code": lambda p: f"`{p}`",
        # bars as \vert and \Vert: a bare "|" would end a table's cell inside the maths
        "math": lambda p: "$" + p.replace(r"\|", r"\Vert{}").replace("|", r"\vert{}") + "$",
    }
    flat = re.sub(r"[ \t\r\n]+", " ", str(text)).strip()
    return "".join(render[kind](piece) for kind, piece in text_pieces(flat))


def _md_cell(text: str) -> str:
    """A cell's text as Markdown (:func:`markdown_text`; an empty cell as a space)."""
    return markdown_text(text) or " "


def table(
    rows: Mapping[str, Sequence[Any]],
    columns: Sequence[str],
    *,
    notes: Sequence[str] = (),
    index_header: str = "",
    digits: int = 3,
) -> Table:
    """Build a :class:`Table` from human row labels to cell values.

    Parameters
    ----------
    rows : mapping of str to sequence
        Row label (a human label with its unit, e.g. ``"detection delay (min)"``) to the row's
        cells, one per column. Strings are kept (use the ``fmt_*`` functions for rates and
        times); other values go through :func:`fmt_value`.
    columns : sequence of str
        Column headers (e.g. ``["ours", "paper"]``).
    notes : sequence of str
        Notes printed under the table (say there why a cell is ``n/a``).
    index_header : str
        Header of the label column.
    digits : int
        Significant digits for plain numbers.

    Examples
    --------
    >>> t = table({"false alarms (of 2000 runs)": [0, 7]}, ["ours", "paper"])
    >>> print(t)
                                 ours  paper
    false alarms (of 2000 runs)  0     7
    """
    columns = tuple(str(c) for c in columns)
    if not columns:
        raise ModelError("columns must name at least one column, got none")
    out = []
    for label, cells in rows.items():
        if not isinstance(label, str) or not label:
            raise ModelError(f"row labels must be non-empty strings, got {label!r}")
        cells = list(cells)
        if len(cells) != len(columns):
            raise ModelError(
                f"row {label!r} has {len(cells)} cells, expected {len(columns)} (columns {columns})"
            )
        out.append((label, tuple(fmt_value(c, digits) for c in cells)))
    if any(NA in cells for _, cells in out) and not notes:
        raise ModelError("a cell is n/a: add a note saying why")
    return Table(columns=columns, rows=tuple(out), notes=tuple(notes), index_header=index_header)


#: MIME-type prefix of a glued value that is not displayed (myst-nb's ``GLUE_PREFIX``).
GLUE_PREFIX = "application/papermill.record/"


def glue(name: str, variable: Any, display: bool = True) -> None:
    """Glue a value into the notebook for ``{glue:text}`name``` in the text: ``myst_nb.glue``, same output.

    The same display message as :func:`myst_nb.glue` (myst-nb 1.x: the value's display data,
    prefixed by :data:`GLUE_PREFIX` unless ``display``, with ``scrapbook`` metadata naming it;
    ``tests/test_report.py`` compares the two), without its import: ``myst_nb.glue`` imports
    nbformat, hence jsonschema, whose URI-format checks compile some 40 grammars at import
    (about 1.2 s of CPU in every chapter kernel of the book build).

    Parameters
    ----------
    name : str
        Key used in the text.
    variable : object
        The value; what is stored is its display data (``text/plain`` etc.). A NumPy scalar is
        glued as the Python number it holds: NumPy 2 writes ``np.float64(0.44)`` as its text,
        which ``{glue:text}`` cannot format (the one difference from ``myst_nb.glue``).
    display : bool
        Also show the value in the cell's output.
    """
    import numpy as np
    from IPython.core.formatters import format_display_data
    from IPython.display import display as ipy_display

    if isinstance(variable, np.generic):
        variable = variable.item()
    bundle, metadata = format_display_data(variable)
    prefix = "" if display else GLUE_PREFIX
    metadata["scrapbook"] = dict(name=name, mime_prefix=prefix)
    ipy_display({prefix + k: v for k, v in bundle.items()}, raw=True, metadata=metadata)
