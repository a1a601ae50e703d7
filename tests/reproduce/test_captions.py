"""Figure captions say "reproduces" only when the claims ledger says so.

The rule (:func:`fdi_lib.reproduce.views.ledger.figure_claim`) is tested on hand-made results; the
chapters are checked to take every caption verb about a paper figure from the ledger (a glued
value, never typed). ``tests/browser/check_captions.py`` checks the built book: each glued verb
against the ledger of the build's cached results, and the rendered captions.
"""

import dataclasses
import html
import re
from pathlib import Path

import jupytext
import pytest

from fdi_lib.reproduce import ledger_claims as C
from fdi_lib.reproduce.views import ledger as V
from fdi_lib.reproduce import list_reproductions
from fdi_lib.reproduce.registry import ReproductionResult

ROOT = Path(__file__).resolve().parents[2]

# ----------------------------------------------------------------------------- the verb rule
RATES = ReproductionResult(
    id="zhang2021-table1",
    headline={
        "success_rate": {"5": 0.998, "15": 0.31},
        "ci95": {"5": [0.99, 1.0], "15": [0.28, 0.34]},
    },
    paper={"success_rate": {"5": 0.995, "15": 0.295}},
    settings={"trials": 1000},
)


def test_verb_reproduces_only_when_every_compared_claim_agrees():
    claim = V.figure_claim(RATES)  # within interval, twice
    assert (claim.verb, claim.differs) == (V.REPRODUCES, "")
    off = dataclasses.replace(
        RATES,
        headline={
            "success_rate": {"5": 0.998, "15": 0.465},
            "ci95": {"5": [0.99, 1.0], "15": [0.43, 0.50]},
        },
    )
    claim = V.figure_claim(off)
    assert claim.verb == V.COMPARE
    assert claim.differs.replace("\u00a0", " ") == (
        "; differs: success rate at q = 15: paper 29.5 %, ours 46.5 %"
    )  # both in %


def test_verb_ignores_inputs_and_calibration_targets():
    """Values the book sets count neither way: only inputs gives "redraws", inputs and our
    estimates of them do not spoil agreement."""
    paper = {"onset_estimate": 201, "glr_argmax_time": "within the window after 201"}
    res = ReproductionResult(
        id="zb2014-fig3",
        paper=paper,
        settings={},
        headline={"onset_estimate": 201, "glr_argmax_time": 208},
    )
    statuses = {r.path[0]: r.status for r in V.figure_claim(res).rows}
    assert statuses == {"onset_estimate": C.INPUT_RECOVERED, "glr_argmax_time": C.REPRODUCED}
    assert V.figure_claim(res).verb == V.REPRODUCES
    missed = dataclasses.replace(res, headline={"onset_estimate": 201, "glr_argmax_time": 400})
    claim = V.figure_claim(missed)
    assert claim.verb == V.COMPARE and "bottom panel: l_k is largest" in claim.differs
    # Rosa & Silvestre Figs 8-10: the fault the book sets, and the §6.4 detection time, which is
    # Fig. 11's claim (listed there once): the figure redraws
    alpha = ReproductionResult(
        id="rosa2013-fig8",
        settings={},
        headline={"onset_s": 0.5, "detection_time_ms": 10.0},
        paper={"onset_s": 0.5, "detection_time_ms": 10},
    )
    assert [r.path for r in V.figure_claim(alpha).rows] == [("onset_s",)]
    assert V.figure_claim(alpha).verb == V.REDRAWS
    calibrated = ReproductionResult(
        id="zb2014-fig9",
        headline={"glr_level_over_threshold": 50.6},
        paper={
            "glr_level_over_threshold": 50.0,
            "calibrated_to": ["glr_level_over_threshold"],
            "predictions": [],
        },
        settings={},
    )
    assert V.figure_claim(calibrated).verb == V.REDRAWS


def test_verb_with_too_few_trials_and_many_differences():
    few = dataclasses.replace(RATES, settings={"trials": 2})
    claim = V.figure_claim(few)
    assert claim.verb == V.COMPARE and "not computed at paper scale" in claim.differs
    assert "differs" not in claim.differs  # too few trials is no difference
    many = dataclasses.replace(
        RATES,
        paper={"success_rate": {str(q): 0.9 for q in range(5, 9)}},
        headline={
            "success_rate": {str(q): 0.1 for q in range(5, 9)},
            "ci95": {str(q): [0.05, 0.15] for q in range(5, 9)},
        },
    )
    claim = V.figure_claim(many)
    assert claim.differs.replace("\u00a0", " ").count("paper 90 %") == V.CAPTION_ITEMS
    assert "2 more in the claims ledger" in claim.differs


# ----------------------------------------------------------------------------- the chapters
CHAPTERS = sorted(
    p for p in (ROOT / "book").rglob("*.md") if p.read_text().startswith("---\njupytext")
)
_GLUED = re.compile(r"\{glue:text\}`caption-(?P<id>[\w-]+)-verb` paper (Fig|Table)")
_TYPED = re.compile(r"\b([Rr]eproduces|[Cc]ompare with|[Rr]edraws)\b")


def _figure_cells():
    for md in CHAPTERS:
        for cell in jupytext.read(md).cells:
            caption = cell.metadata.get("mystnb", {}).get("figure", {}).get("caption")
            if cell.cell_type == "code" and caption:
                yield md.relative_to(ROOT), " ".join(str(caption).split()), cell.source


def test_chapters_have_figures():
    assert len(list(_figure_cells())) >= 24


@pytest.mark.parametrize(
    "doc, caption, source",
    list(_figure_cells()),
    ids=lambda v: str(v)[:40] if isinstance(v, Path) else "",
)
def test_caption_verbs_come_from_the_ledger(doc, caption, source):
    """A caption naming a paper figure or table takes its verb and "what differs" from
    ``glue_caption`` of the result it plots; no verb about a paper figure is typed."""
    ids = {r.id for r in list_reproductions()}
    glued = _GLUED.search(caption)
    without_glue = re.sub(r"\{glue:text\}`[^`]*`", "", caption)
    assert not _TYPED.search(without_glue), (doc, caption)
    if not glued:
        assert not re.search(r"paper (Fig|Table)\.? ?[IVX\d]", caption), (doc, caption)
        return
    id = glued.group("id")
    assert id in ids, (doc, id)
    assert f"{{glue:text}}`caption-{id}-differs`" in caption, (doc, caption)
    var = re.search(r"^glue_caption\((\w+)\)$", source, flags=re.M)
    assert var, (doc, "the figure cell must call glue_caption(result)")
    assert re.search(rf'get\("{id}"\)\.plot\({var.group(1)}\b', source), (doc, id, source)


# ----------------------------------------------------------------------------- the post-build check
def _load_check():
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "check_captions", ROOT / "tests" / "browser" / "check_captions.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_post_build_check_fails_on_a_caption_that_disagrees(tmp_path, monkeypatch):
    """``tests/browser/check_captions.py`` on a hand-made built page and results cache."""
    from fdi_lib.reproduce import reproduce
    from fdi_lib.reproduce.book import book_run

    check = _load_check()
    monkeypatch.setenv("FDI_RESULTS_CACHE", str(tmp_path / "cache"))
    f1, f3 = book_run("zb2014-fig1"), book_run("zb2014-fig3")  # cached, as in a build
    reproduce("zb2014-fig3", seed=1)  # another run, used last: not the book's, not read
    c1, c3 = V.figure_claim(f1), V.figure_claim(f3)
    assert (c1.verb, c3.verb) == (V.COMPARE, V.REPRODUCES)  # Γ_k over 1; Fig. 3 agrees

    def page(*caps, attrs=""):
        (tmp_path / "html").mkdir(exist_ok=True)
        body = "".join(
            f"<figure{attrs}><figcaption><p><span>{c}</span></p></figcaption></figure>"
            for c in caps
        )
        (tmp_path / "html" / "page.html").write_text(f"<html><body>{body}</body></html>")
        return check.check(tmp_path / "html")

    good1 = (
        f"Norms; <span class='pasted-text'>{c1.verb}</span> paper Fig. 1 of Z "
        f"(zb2014-fig1{html.escape(c1.differs)})."
    )
    good3 = f"GLR; {c3.verb} paper Fig. 3 of Z (zb2014-fig3)."
    assert page(good1, good3, "Not in the paper.") == []
    kinds = [f[1] for f in page(good1.replace(c1.verb, "reproduces"), good3)]
    assert kinds == ["verb"]
    assert [f[1] for f in page(good1.replace(html.escape(c1.differs), ""))] == ["differs"]
    assert [f[1] for f in page("Paper Fig. 11 under the other reading (rosa2013-fig11-rad).")] == [
        "caption"
    ]
    assert [f[1] for f in page("GLR; reproduces paper Fig. 4 of Z (zb2014-fig4).")] == ["result"]
    # an explorable redraws a paper figure's setting and claims nothing: not checked
    sliders = "SVO hull against the bound (as paper Fig. 2)."
    assert [f[1] for f in page(sliders)] == ["caption"]
    assert page(sliders, attrs=' class="fdi-explorable" id="x"') == []
    assert (
        page(sliders, attrs=' class="align-default fdi-explorable-figure" id="fig-svo-explore"')
        == []
    )


def test_a_caption_imports_no_other_reproduction_module():
    """A chapter's caption (its figure's own ledger) reads its reproduction's registration alone:
    the other papers' modules (numba's polytopes of Rosa 2013 among them) are not imported, in a
    fresh process as a chapter's kernel; the book's order of all of them is still that of
    :func:`~fdi_lib.reproduce.book.book_key`."""
    import subprocess
    import sys

    code = (
        "import sys\n"
        "from fdi_lib.reproduce import zb2014_pipeline_single\n"
        "from fdi_lib.reproduce.book import book_order, book_key, book_run\n"
        "from fdi_lib.reproduce.views.ledger import glue_caption\n"
        "glue_caption(book_run('zb2014-table1'))\n"
        "print(sorted(m for m in sys.modules if m.startswith('fdi_lib.reproduce.')\n"
        "             and m.split('.')[2].startswith(('rosa', 'bz', 'wind', 'zhang'))))\n"
        "print(list(book_order()) == sorted(book_order(), key=book_key))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT
    ).stdout.split("\n")
    assert out[:2] == ["[]", "True"]
