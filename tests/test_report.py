"""Formats of fdi_lib.report: each case is the string a reader must see."""

import numpy as np
import pytest

from fdi_lib.errors import ModelError
from fdi_lib.report import (
    NA,
    NBSP,
    Table,
    fmt_count,
    fmt_number,
    fmt_rate,
    fmt_time,
    fmt_value,
    table,
)


@pytest.mark.parametrize(
    "x, expected",
    [
        (7.0, "7"),
        (0, "0"),
        (12345, "12\u202f345"),
        (np.int64(2000), "2\u202f000"),
    ],
)
def test_fmt_count(x, expected):
    assert fmt_count(x) == expected


@pytest.mark.parametrize("bad", [7.5, float("nan"), "7", True])
def test_fmt_count_rejects(bad):
    with pytest.raises(ModelError, match="n must be"):
        fmt_count(bad)


@pytest.mark.parametrize(
    "x, expected",
    [
        (5.351584e-235, "< 10⁻¹⁵"),
        (0.0, "0"),
        (1.2808, "1.28"),
        (-0.333333, "-0.333"),
        (43980.0, "43980"),
        (1.5e7, "1.5×10⁷"),
        (2.5e-5, "2.5×10⁻⁵"),
        (-4e-5, "-4×10⁻⁵"),
        (9.9999e5, "10⁶"),
        (1e-3, "0.001"),
        (100.0, "100"),
    ],
)
def test_fmt_number(x, expected):
    assert fmt_number(x) == expected


@pytest.mark.parametrize(
    "rate, ci, expected",
    [
        (0.017, None, "1.7 %"),
        (0.0, None, "0 %"),
        (1.0, None, "100 %"),
        (0.017, (0.0098, 0.027), "1.7 % [0.98, 2.7]"),
        (0.901, (0.88, 0.92), "90 % [88, 92]"),
        (None, None, NA),
    ],
)
def test_fmt_rate(rate, ci, expected):
    out = fmt_rate(rate, ci)
    assert out.replace(NBSP, " ") == expected
    # the only breakable space separates the rate from its interval
    assert out.count(" ") == (ci is not None)


@pytest.mark.parametrize(
    "rate, ci, match",
    [
        (1.5, None, "fraction in"),
        (0.5, (0.6, 0.4), "low <= high"),
        (0.5, (0.1,), "pair"),
        (float("nan"), None, "finite"),
    ],
)
def test_fmt_rate_rejects(rate, ci, match):
    with pytest.raises(ModelError, match=match):
        fmt_rate(rate, ci)


@pytest.mark.parametrize(
    "s, expected",
    [
        (0.00122, "1.22 ms"),
        (2.5e-5, "25 µs"),
        (89.4, "89.4 s"),
        (211.0, "3.52 min"),
        (0, "0 s"),
    ],
)
def test_fmt_time(s, expected):
    assert fmt_time(s) == expected.replace(" ", NBSP)


def test_fmt_value_dispatch():
    assert fmt_value(None) == NA
    assert fmt_value(True) == "yes"
    assert fmt_value([1, 2.5]) == "[1, 2.5]"
    assert fmt_value(np.array([600, 786])) == "[600, 786]"
    with pytest.raises(ModelError, match="NaN"):
        fmt_value(float("nan"))


def test_table_html_and_text():
    t = table(
        {"false alarms (of 2000 runs)": [0, 7], "type I error": [fmt_rate(0.01), None]},
        ["ours", "paper"],
        notes=["the paper gives no type I error for this case"],
    )
    html = t._repr_html_().replace(NBSP, " ")
    assert html.count("<tr>") == 3 and "fdi-table" in html and "n/a" in html
    assert "the paper gives no type I error" in html
    assert t.to_frame().loc["type I error", "paper"] == NA
    # headers name their scope; an empty corner is no header (axe-core: empty-table-header)
    assert '<thead><tr><td></td><th scope="col">ours</th><th scope="col">paper</th>' in html
    assert '<tr><th scope="row">type I error</th>' in html
    named = Table(("ours", ""), (("a", ("1", "x")), (" ", ("2", "y"))), index_header="case")
    html = named._repr_html_()
    assert '<thead><tr><th scope="col">case</th><th scope="col">ours</th><td></td></tr>' in html
    assert '<tr><td></td><td data-label="ours">2</td>' in html  # a row continuing the one above
    assert str(t).splitlines()[1].split() == ["false", "alarms", "(of", "2000", "runs)", "0", "7"]


def test_table_cells_name_their_column():
    """On a phone a wide table becomes one card per row: every body cell carries its column's
    header (escaped) as data-label, in the order of the columns."""
    import re

    t = table({"delay": [1, 2, 3]}, ["ours", 'paper "A" & B', "q < 5"])
    assert re.findall(r'<td data-label="([^"]*)">', t._repr_html_()) == [
        "ours",
        "paper &quot;A&quot; &amp; B",
        "q &lt; 5",
    ]


def test_table_sets_names_from_the_code_as_code_and_symbols_as_maths():
    """An identifier with an underscore between words, or a Python file, reads as code in the HTML
    (not as maths with a subscript); a symbol with a one-character subscript, a Greek letter's name
    with one and TeX between dollars are maths for the page's MathJax (issue 33); the text around
    is escaped, and the plain text keeps what was written."""
    t = table(
        {"redraw, explore_glr (onset)": ["x_k < 1 & Gamma_k"], "$C_{m\\eta}$ (per rad)": ["1"]},
        ["ours"],
        notes=["timed by tools/build_report.py against lars_path; beta_1,m1 and ||r_k||_2"],
    )
    html = t._repr_html_()
    math = '<span class="math notranslate nohighlight">\\({}\\)</span>'.format
    assert '<th scope="row">redraw, <code>explore_glr</code> (onset)</th>' in html
    assert f">{math('x_k')} &lt; 1 &amp; {math(chr(92) + 'Gamma_k')}</td>" in html
    assert f'<th scope="row">{math("C_{m" + chr(92) + "eta}")} (per rad)</th>' in html
    assert (
        "<li>timed by <code>tools/build_report.py</code> against <code>lars_path</code>; "
        f"{math(chr(92) + 'beta_{1,m1}')} and {math(chr(92) + 'Vert r_k' + chr(92) + 'Vert_2')}</li>"
        in html
    )
    assert "explore_glr" in str(t) and "x_k < 1" in str(t) and "<code>" not in str(t)


def test_table_markdown_sets_code_as_code_and_maths_as_maths():
    """The PDF's form of a table: the names from the code are code spans, the symbols and the TeX
    between dollars are the maths of MyST's parser (its dollarmath plugin)."""
    from markdown_it import MarkdownIt
    from mdit_py_plugins.dollarmath import dollarmath_plugin

    t = table({"M_u, $C_{m\\eta}$ of explore_glr": ["beta_1,m1 | 2"]}, ["ours"])
    md = MarkdownIt("commonmark").enable("table").use(dollarmath_plugin)
    tokens = md.parse(t._repr_markdown_())
    assert sum(tok.type in ("th_open", "td_open") for tok in tokens) == 4
    pieces = [(c.type, c.content) for tok in tokens if tok.type == "inline" for c in tok.children]
    assert ("math_inline", "M_u") in pieces and ("math_inline", "C_{m\\eta}") in pieces
    assert ("code_inline", "explore_glr") in pieces
    assert ("math_inline", "\\beta_{1,m1}") in pieces and ("text", " | 2") in pieces


def test_table_markdown_keeps_bars_in_maths_inside_their_cell():
    """A bar in the maths (an absolute value, a norm) would end the table's cell, leaving raw TeX
    in the PDF (C_{m\\alpha} on the SVO chapter's page): written as \\vert and \\Vert."""
    from markdown_it import MarkdownIt
    from mdit_py_plugins.dollarmath import dollarmath_plugin

    t = table({r"$C_{m\eta} / |C_{m\alpha}|$ (%), $\|r\|_2$": [1.0]}, ["ours"])
    md = MarkdownIt("commonmark").enable("table").use(dollarmath_plugin)
    tokens = md.parse(t._repr_markdown_())
    assert sum(tok.type in ("th_open", "td_open") for tok in tokens) == 4
    pieces = [(c.type, c.content) for tok in tokens if tok.type == "inline" for c in tok.children]
    assert ("math_inline", r"C_{m\eta} / \vert{}C_{m\alpha}\vert{}") in pieces
    assert ("math_inline", r"\Vert{}r\Vert{}_2") in pieces


def test_table_rejects():
    with pytest.raises(ModelError, match="expected 2"):
        table({"a": [1]}, ["ours", "paper"])
    with pytest.raises(ModelError, match="add a note"):
        table({"a": [1, None]}, ["ours", "paper"])
    with pytest.raises(ModelError, match="row labels"):
        table({"": [1]}, ["ours"])


@pytest.mark.parametrize(
    "value, display", [(1.2345, False), (7, True), ("text", False), (np.float64(-2.5e-5), False)]
)
def test_glue_same_message_as_myst_nb(value, display):
    """fdi_lib.report.glue sends the display message of myst_nb.glue (data and metadata); a NumPy
    scalar as the Python number it holds (NumPy 2's repr "np.float64(...)" cannot be formatted)."""
    from IPython.core.interactiveshell import InteractiveShell
    from IPython.utils.capture import capture_output
    from myst_nb import glue as myst_glue

    from fdi_lib.report import glue

    InteractiveShell.instance()
    with capture_output() as ours:
        glue("key", value, display=display)
    with capture_output() as theirs:
        myst_glue("key", value.item() if isinstance(value, np.generic) else value, display=display)
    assert len(ours.outputs) == len(theirs.outputs) == 1
    assert "np." not in str(ours.outputs[0].data)
    assert ours.outputs[0].data == theirs.outputs[0].data
    assert ours.outputs[0].metadata == theirs.outputs[0].metadata
    assert ours.outputs[0].metadata["scrapbook"]["name"] == "key"
    assert (
        any(k.startswith("application/papermill.record/") for k in ours.outputs[0].data) != display
    )


def test_table_markdown_is_a_pipe_table_with_the_same_cells_literally():
    """The PDF's form of a table: a Markdown table whose cells, read back by a Markdown parser
    (markdown-it, the parser of MyST), are the table's cells, special characters included."""
    from markdown_it import MarkdownIt

    t = table(
        {
            "false alarms *of* [2000] runs": [0, fmt_rate(0.017, (0.0098, 0.027))],
            "type I error | #1 !x": [None, "a~b <c> {d}"],
        },
        ["ours", "paper"],
        notes=["no *type I* _error_"],
        index_header="",
    )
    tokens = MarkdownIt("commonmark").enable("table").parse(t._repr_markdown_())
    assert sum(tok.type in ("th_open", "td_open") for tok in tokens) == 9
    texts = ["".join(c.content for c in tok.children) for tok in tokens if tok.type == "inline"]
    # the text the parser reads is the cell's, with no emphasis, code, link or HTML made of it
    assert texts == [
        "",
        "ours",
        "paper",
        "false alarms *of* [2000] runs",
        "0",
        fmt_rate(0.017, (0.0098, 0.027)),
        "type I error | #1 !x",
        "n/a",
        "a~b <c> {d}",
        "no *type I* _error_",
    ]
    assert not [
        tok
        for tok in tokens
        if tok.type == "inline"
        for c in tok.children
        if c.type not in ("text", "softbreak")
    ]
