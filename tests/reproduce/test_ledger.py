"""The claims ledger: every paper value appears, every status is computed from the numbers."""

import dataclasses
import fnmatch
import json
import re
from pathlib import Path

import pytest

from fdi_lib.reproduce import list_reproductions, reproduce
from fdi_lib.reproduce import ledger as L
from fdi_lib.reproduce import ledger_claims as C
from fdi_lib.reproduce import ledger_status as S
from fdi_lib.reproduce.views import ledger as V
from fdi_lib.reproduce.book import book_order, book_settings
from fdi_lib.reproduce.registry import ReproductionResult, cached_results

ROOT = Path(__file__).resolve().parents[2]
# Cheap reproductions (no Monte Carlo) covering numbers, lists, booleans, inequalities, checks.
CHEAP = [
    "zb2014-fig1",
    "zb2014-fig2",
    "zb2014-fig3",
    "zb2014-fig4",
    "zb2014-table1",
    "zhang2021-fig2",
    "zhang2021-fig3",
    "rosa2013-fig8",
    "rosa2013-fig10",
    "rosa2013-timing",
]


@pytest.fixture(scope="module")
def cheap_results():
    return {id: reproduce(id) for id in CHEAP}


# ----------------------------------------------------------------------------- statuses
def _claim(test=C.BY_TOLERANCE, **kw):
    return C.Claim(location="Fig. 0", units="", test=test, **kw)


def test_status_of_numbers_lists_and_intervals():
    assert S.claim_status(786.0, 786.0)[0] == C.REPRODUCED
    assert S.claim_status(786.0, 786.5)[0] == C.REPRODUCED  # within 1e-3 relative
    assert S.claim_status(786.0, 790.0)[0] == C.DIFFERS
    interval = _claim(C.BY_INTERVAL)
    assert S.claim_status(0.295, 0.465, (0.43, 0.50), interval)[0] == C.DIFFERS
    assert S.claim_status(0.295, 0.31, (0.28, 0.34), interval)[0] == C.WITHIN
    # only the declared test agrees: inside the interval is no agreement by tolerance, and an
    # equal value without an interval is not computed by the interval test
    assert S.claim_status(0.295, 0.31, (0.28, 0.34))[0] == C.DIFFERS
    assert S.claim_status(0.295, 0.295, None, interval)[0] == C.NOT_COMPUTED
    # by standard error: within z = 1.96 standard errors of ours, per component
    se = _claim(C.BY_STANDARD_ERROR)
    assert S.claim_status([10.0, 9.0], [10.1, 9.1], se=[0.1, 0.1], spec=se)[0] == C.WITHIN
    assert S.claim_status([10.78, 9.0], [10.1, 9.1], se=[0.1, 0.1], spec=se)[0] == C.DIFFERS
    assert S.claim_status([10.0, 9.0], [10.0, 9.0], spec=se)[0] == C.NOT_COMPUTED  # no se
    assert S.claim_status([4.0, 0.0], [4.0, 0.0])[0] == C.REPRODUCED
    assert S.claim_status([4.0, 0.0], [4.0, 0.1])[0] == C.DIFFERS
    assert S.claim_status([4.0, 0.0], [4.0])[0] == C.DIFFERS
    assert S.claim_status(20, None)[0] == C.NOT_COMPUTED  # we have no value
    never = _claim(missing="not detected")  # None is a result
    assert S.claim_status(20, None, spec=never) == (C.DIFFERS, "ours: not detected")
    # a single run: inside the 95 % range of our runs, or not
    spread = _claim(C.BY_SPREAD)
    assert S.claim_status(786.0, 778.0, spread=(700.0, 800.0), spec=spread)[0] == C.WITHIN_SPREAD
    assert S.claim_status(88.0, 36.0, spread=(20.0, 60.0), spec=spread)[0] == C.DIFFERS
    assert S.claim_status(786.0, 786.0, spread=(700.0, 800.0), spec=spread)[0] == C.WITHIN_SPREAD
    assert S.claim_status(True, True)[0] == C.REPRODUCED
    assert S.claim_status(True, False)[0] == C.DIFFERS


def test_status_of_text_claims():
    assert S.claim_status("< 1", 0.99)[0] == C.REPRODUCED
    assert S.claim_status("< 1", 1.81)[0] == C.DIFFERS
    assert S.claim_status("< 500", [100.0, 499.0])[0] == C.REPRODUCED
    assert S.claim_status("about 3500", 3500.0)[0] == C.REPRODUCED
    assert S.claim_status("about 3500", 280.0)[0] == C.DIFFERS
    assert S.claim_status("grows", 1.0)[0] == C.NOT_REPRODUCIBLE  # no check: flagged
    spec = _claim(C.BY_CHECK, check=lambda p, o, h: o > 2, criterion="o > 2")
    assert S.claim_status("grows", 3.0, spec=spec) == (C.REPRODUCED, "o > 2")
    assert S.claim_status("grows", 1.0, spec=spec)[0] == C.DIFFERS
    zero = _claim(C.BY_INTERVAL, value=lambda p: 0.0)
    assert S.claim_status("0 (Prop. 2)", -0.08, (-0.09, -0.07), zero)[0] == C.DIFFERS
    assert S.claim_status("0 (Prop. 2)", -0.01, (-0.03, 0.01), zero)[0] == C.WITHIN
    why = "timing on another machine"
    assert S.claim_status(5.0, 5.0, spec=_claim(C.NOT_CHECKABLE, reason=why)) == (
        C.NOT_REPRODUCIBLE,
        why,
    )


def test_a_declaration_states_its_location_and_a_known_test():
    with pytest.raises(L.ModelError, match="Claim.test"):
        C.Claim(location="Fig. 1", units="", test="close enough")
    with pytest.raises(L.ModelError, match="Claim.location"):
        C.Claim(location=" ", units="", test=C.BY_TOLERANCE)
    with pytest.raises(L.ModelError, match="Claim.reason"):
        C.Claim(location="Fig. 1", units="", test=C.NOT_CHECKABLE)
    with pytest.raises(L.ModelError, match="Claim.check"):
        C.Claim(location="Fig. 1", units="", test=C.BY_CHECK)
    with pytest.raises(TypeError):
        C.Claim(location="Fig. 1", test=C.BY_TOLERANCE)  # units must be stated


def test_claim_paths_skip_values_that_state_nothing():
    paper = {
        "a": 1,
        "b": {"x": "< 1", "y": None},
        "c": "not stated",
        "d": [1, 2],
        "e": "illustration, no numbers",
    }
    assert S.claim_paths(paper) == [("a",), ("b", "x"), ("d",)]
    declared = {"a": 1, "calibrated_to": ["a"], "predictions": [], "b": {"predictions": 2}}
    assert S.claim_paths(declared) == [("a",), ("b", "predictions")]  # role lists: top level only


def test_surrogate_role_is_the_reproductions_declaration():
    paper = {"x": 1, "y": 2, "z": 3, "calibrated_to": ["x"], "predictions": ["y"]}
    typed = _claim(role=C.CALIBRATION)
    assert [S.surrogate_role("zb2014-fig9", paper, (k,), typed) for k in "xyz"] == [
        C.CALIBRATION,
        C.PREDICTION,
        C.INPUT,
    ]  # the typed role is ignored
    assert S.surrogate_role("rosa2013-fig8", {"x": 1}, ("x",), typed) == C.CALIBRATION
    assert S.surrogate_role("rosa2013-fig8", {"x": 1}, ("x",)) == C.PREDICTION
    assert S.surrogate_role("zb2014-fig1", {"x": 1}, ("x",), typed) is None
    # moving a key between the lists moves its row
    res = ReproductionResult(
        id="zb2014-fig9",
        headline={"x": 1.0, "y": 2.0},
        paper={"x": 1.0, "y": 2.0, "calibrated_to": ["x"], "predictions": ["y"]},
        settings={},
    )
    roles = {r.path: r.role for r in L.build_ledger({"zb2014-fig9": res}).rows}
    assert roles == {("x",): C.CALIBRATION, ("y",): C.PREDICTION}
    swapped = dataclasses.replace(
        res, paper={**res.paper, "calibrated_to": ["y"], "predictions": ["x"]}
    )
    roles = {r.path: r.role for r in L.build_ledger({"zb2014-fig9": swapped}).rows}
    assert roles == {("x",): C.PREDICTION, ("y",): C.CALIBRATION}


# ----------------------------------------------------------------------------- the ledger
def _listed(ledger):
    return {(r.id, r.path) for r in ledger.rows}


def test_every_paper_value_appears(cheap_results):
    led = L.build_ledger(cheap_results, strict=True)
    listed = _listed(led)
    for id, res in cheap_results.items():
        for path in S.claim_paths(res.paper):
            owner = L._owner(id, path, S.claim_for(id, path))
            assert owner in listed or owner[0] not in cheap_results, (id, path)
    assert sum(led.counts().values()) == len(led.rows)
    # rows in book order (the table of contents)
    order = [book_order().index(r.id) for r in led.rows]
    assert order == sorted(order)


def test_statuses_are_computed_not_typed(cheap_results):
    """Perturb a paper value: the status follows the numbers."""
    base = {(r.id, r.path): r.status for r in L.build_ledger(cheap_results).rows}
    assert base[("zb2014-table1", ("G0_1_nominal",))] == C.INPUT_VALUE  # set by the book
    assert base[("zb2014-fig1", ("gamma_norm_max", "101"))] == C.DIFFERS_MEASURED
    t1 = cheap_results["zb2014-table1"]
    moved = dataclasses.replace(
        t1, paper={**t1.paper, "G0_1_nominal": t1.paper["G0_1_nominal"] * 1.01}
    )
    f1 = cheap_results["zb2014-fig1"]
    relaxed = dataclasses.replace(f1, paper={**f1.paper, "gamma_norm_max": {"101": "< 2"}})
    rows = {
        (r.id, r.path): r.status
        for r in L.build_ledger(
            {**cheap_results, "zb2014-table1": moved, "zb2014-fig1": relaxed}
        ).rows
    }
    assert rows[("zb2014-table1", ("G0_1_nominal",))] == C.DIFFERS_UNKNOWN  # an input we miss
    assert rows[("zb2014-fig1", ("gamma_norm_max", "101"))] == C.REPRODUCED
    # the status column (the first) of the rendered table is the computed one
    text = L.build_ledger(cheap_results).to_myst()
    for status in C.STATUSES:
        assert text.count(f"* - {status}\n") == sum(s == status for s in base.values()), status


def test_within_interval_from_a_stochastic_result():
    res = ReproductionResult(
        id="zhang2021-table1",
        headline={
            "success_rate": {"15": 0.31, "16": 0.46},
            "ci95": {"15": [0.28, 0.34], "16": [0.43, 0.49]},
        },
        paper={"success_rate": {"15": 0.295, "16": 0.251}},
        settings={"trials": 1000},
    )
    rows = L.build_ledger({"zhang2021-table1": res}, strict=True).rows
    assert [r.status for r in rows] == [C.WITHIN, C.DIFFERS_UNKNOWN]
    assert rows[0].ci == (0.28, 0.34) and rows[1].explain and rows[0].trials == 1000
    assert rows[1].cause is None and rows[0].paper_trials == 1000
    # the paper's rate between our two readings of the rule, on the same trials: a bracket, not
    # a cause (neither reading's interval holds it)
    between = dataclasses.replace(
        res, headline={**res.headline, "success_rate_linear": {"15": 0.30, "16": 0.20}}
    )
    rows = L.build_ledger({"zhang2021-table1": between}, strict=True).rows
    assert [r.status for r in rows] == [C.WITHIN, C.DIFFERS_BRACKETED]
    assert rows[1].cause is None and "between" in rows[1].status_detail
    # both cells of a rate in %: no paper fraction beside a percentage of ours
    text = L.build_ledger({"zhang2021-table1": res}).to_myst().replace("\u00a0", " ")
    assert "25.1 %" in text and "46 %" in text and "0.251" not in text


def test_statuses_need_the_papers_trial_count():
    """A Monte Carlo result with fewer trials than the paper's gives no comparison status."""
    res = ReproductionResult(
        id="zhang2021-table1",
        headline={
            "success_rate": {"15": 0.31, "16": 0.46},
            "ci95": {"15": [0.0, 0.9], "16": [0.0, 0.9]},
        },
        paper={"success_rate": {"15": 0.295, "16": 0.251}},
        settings={"trials": C.FALLBACK_TRIALS},
    )
    rows = L.build_ledger({"zhang2021-table1": res}, strict=True).rows
    assert {r.status for r in rows} == {C.NOT_COMPUTED}  # not "within interval" (huge CI)
    assert all(r.status_detail.startswith("not computed at paper scale") for r in rows)
    assert L.get("zhang2021-table1").default_trials == rows[0].paper_trials == 1000
    # an input stays an input at any trial count
    f8 = ReproductionResult(
        id="zb2014-fig8",
        headline={"threshold_dof": 1},
        paper={"threshold_dof": "1 (caption) / 2 (text)", "calibrated_to": [], "predictions": []},
        settings={"trials": 2},
    )
    assert [r.status for r in L.build_ledger({"zb2014-fig8": f8}).rows] == [C.INPUT_VALUE]


def test_within_spread_of_a_single_run():
    """Figs. 5-6 of the pipeline: one run of the paper against our run-to-run distribution."""
    paper = {
        "alarm_time_min": 786.0,
        "detection_delay_min": 186.0,
        "calibrated_to": [],
        "predictions": ["alarm_time_min", "detection_delay_min"],
    }
    head = {"alarm_time_min": 778.0, "detection_delay_min": 178.0}
    plain = ReproductionResult(id="zb2014-fig5", headline=head, paper=paper, settings={})
    # declared by the spread of single runs: without our spread there is nothing to compare
    assert {r.status for r in L.build_ledger({"zb2014-fig5": plain}).rows} == {C.NOT_COMPUTED}
    spread = dataclasses.replace(
        plain,
        headline={
            **head,
            "alarm_time_min_spread95": [700.0, 800.0],
            "alarm_time_min_paper_percentile": 71.0,
            "detection_delay_min_spread95": [100.0, 180.0],
            "spread_runs": 1000,
        },
    )
    rows = {r.path[0]: r for r in L.build_ledger({"zb2014-fig5": spread}).rows}
    assert rows["alarm_time_min"].status == C.WITHIN_SPREAD
    assert "71" in rows["alarm_time_min"].status_detail and "1 000" in rows[
        "alarm_time_min"
    ].status_detail.replace("\u202f", " ")
    assert rows["detection_delay_min"].status in C.DIFFERING  # 186 outside [100, 180]


def test_one_row_per_claim():
    """The Table I/II values the λ-rule study checks again are listed once, under the table."""
    t1 = ReproductionResult(
        id="zhang2021-table1",
        headline={"success_rate": {"15": 0.465}, "ci95": {"15": [0.43, 0.50]}},
        paper={"success_rate": {"15": 0.295}},
        settings={"trials": 1000},
    )
    lr = ReproductionResult(
        id="zhang2021-lambda-rule",
        headline={"success_rate": {"log": {"q15": 0.455}}, "ci95": {"log": {"q15": [0.38, 0.53]}}},
        paper={"success_rate": {"q15": 0.295}},
        settings={"trials": 200},
    )
    rows = L.build_ledger({"zhang2021-table1": t1, "zhang2021-lambda-rule": lr}, strict=True).rows
    assert [(r.id, r.path) for r in rows] == [("zhang2021-table1", ("success_rate", "15"))]
    assert "zhang2021-lambda-rule on 200 trials: 45.5" in rows[0].note


def test_the_other_reading_of_a_figure_is_a_note_and_its_caption_has_its_own_statuses():
    """The per-radian UAV figures check the paper's Figs 11-12 again: one row per claim (the
    per-degree reading's), the other reading in its note; its own figure's caption judges it."""
    deg = ReproductionResult(
        id="rosa2013-fig11",
        headline={"detection_time_ms": {"alpha": {"step": 10.0}}},
        paper={"detection_time_ms": {"alpha": {"step": 10}}},
        settings={"trials": 10},
    )
    rad = dataclasses.replace(
        deg, id="rosa2013-fig11-rad", headline={"detection_time_ms": {"alpha": {"step": None}}}
    )
    rows = L.build_ledger({"rosa2013-fig11": deg, "rosa2013-fig11-rad": rad}, strict=True).rows
    assert [(r.id, r.status) for r in rows] == [("rosa2013-fig11", C.REPRODUCED)]
    assert "rosa2013-fig11-rad on 10 trials: not detected in any run" in rows[0].note
    claim = V.figure_claim(rad)
    assert claim.verb == V.COMPARE and "not detected" in claim.differs
    assert V.figure_claim(deg).verb == V.REPRODUCES
    # the caption names the claim as the per-degree row does, not by its JSON path
    assert (
        claim.rows[0].label
        == rows[0].label
        == ("Fig. 11 (§6.4 text), alpha fault, step scenario: mean detection time")
    )
    assert claim.differs.startswith("; differs: alpha fault, step scenario: mean detection time:")
    assert "detection_time_ms" not in claim.differs


def test_a_figure_lists_a_claim_it_repeats_under_itself_once():
    """Fig. 7's false-alarm rate is its count again (declared ``figure_reading=False``): the
    caption names the count alone."""
    fig7 = ReproductionResult(
        id="zb2014-fig7",
        headline={"false_alarms": 0, "false_alarm_rate": {"rate": 0.0}},
        paper={"false_alarms": 7, "false_alarm_rate": {"rate": 0.0035}},
        settings={"trials": 2000},
    )
    rows = V.figure_claim(fig7).rows
    assert [r.path for r in rows] == [("false_alarms",)]


def _declarations():
    """``(id, pattern, Claim)`` of every registration."""
    return [
        (rep.id, pattern, claim) for rep in list_reproductions() for pattern, claim in rep.claims
    ]


def test_every_difference_links_to_where_it_is_shown(cheap_results):
    for rep in list_reproductions():
        assert (ROOT / f"{S.chapter_of(rep.id)}.md").exists(), rep.id
    for _, _, c in _declarations():
        if c.explain and "/" in c.explain:
            assert (ROOT / f"{c.explain}.md").exists(), c.explain
    for r in L.build_ledger(cheap_results).rows:
        if r.status in (*C.DIFFERING, C.NOT_REPRODUCIBLE, C.NOT_COMPUTED):
            assert r.explain, (r.id, r.path)
        assert (r.cause is not None) == (r.status in (C.DIFFERS_MEASURED, C.DIFFERS_HYPOTHESIS)), (
            r.id,
            r.path,
        )


_FENCE = re.compile(r"^(`{3,}|:{3,})")
_HEADING = re.compile(r"^(#{1,6}) ")


def _sections():
    """label -> the text of the section it names (a ``(label)=`` before a heading, or the section
    holding a figure ``name:``), from its heading to the next heading of the same or a higher
    level, code cells included (glue calls) but their ``#`` comments not read as headings."""
    out = {}
    for md in (ROOT / "book").rglob("*.md"):
        lines = md.read_text().splitlines()
        heads, fenced = [], False  # (line, level) of each heading outside code
        for i, line in enumerate(lines):
            if line.startswith("```"):
                fenced = not fenced
            elif not fenced and (m := _HEADING.match(line)):
                heads.append((i, len(m.group(1))))

        def section(start):
            level = next((lv for i, lv in heads if i == start), 7)
            end = next((i for i, lv in heads if i > start and lv <= level), len(lines))
            return "\n".join(lines[start:end])

        for i, line in enumerate(lines):
            if (m := re.match(r"^\(([\w-]+)\)=\s*$", line)) and any(h == i + 1 for h, _ in heads):
                out[m.group(1)] = section(i + 1)
            elif m := re.match(r"^ +name: (fig-[\w-]+)\s*$", line):
                start = max((h for h, _ in heads if h < i), default=0)
                out[m.group(1)] = section(start)
    return out


def _glued(text):
    """Glue keys shown in ``text`` (``{glue}`key```, ``{glue:text}`key:.2f```...), lower case."""
    return {k.lower() for k in re.findall(r"\{glue(?::\w+)?\}`([^`:]+)", text)}


def _missing_glue(results=None):
    """``(id, pattern, label, key)`` of every declared measurement that its section does not glue.

    Each key is formatted with the path parts of each claim the declaration matches whose row
    links the section (in the ledger of ``results``), or with ``*`` for every part (any glue key of
    that form) without results."""
    sections = _sections()
    linked = set()
    if results:
        linked = {
            (r.id, r.path)
            for r in L.build_ledger(results).rows
            if r.status in (C.DIFFERS_MEASURED, C.DIFFERS_HYPOTHESIS)
        }
    missing = []
    for id, pattern, c in _declarations():
        for label, keys in ((c.cause, c.cause_glue), (c.hypothesis, c.hypothesis_glue)):
            if not label:
                continue
            if not keys or label not in sections:
                missing.append((id, pattern, label, "no glued measurement declared or no section"))
                continue
            shown = _glued(sections[label])
            leaves = S.claim_paths(results[id].paper) if results and id in results else []
            paths = [
                p for p in leaves if fnmatch.fnmatchcase("/".join(p), pattern) and (id, p) in linked
            ]
            for parts in [p[1:] for p in paths] if results else [("*",) * 5]:
                for key in keys:
                    want = key.format(*parts).lower()
                    if not any(fnmatch.fnmatchcase(k, want) for k in shown):
                        missing.append((id, pattern, label, want))
    return missing


def test_every_measured_cause_links_a_section_that_glues_its_measurement():
    """A "differs, measured cause" or "hypothesis tested" declaration names a section of the book
    that shows (glues) the declared numbers of that claim."""
    assert not _missing_glue()
    assert sum(bool(c.cause or c.hypothesis) for _, _, c in _declarations()) >= 10


def test_the_glue_check_fails_on_a_section_without_the_measurement():
    sections = _sections()
    assert "pl_union" in _glued(sections["sec-pipeline-fig7"])
    assert "pl_union" not in _glued(sections["sec-pipeline-isolation-window"])
    assert "sig-quoted" in _glued(sections["sec-zb-fig1-bound"])


def _book_labels():
    labels = set()
    for md in (ROOT / "book").rglob("*.md"):
        text = md.read_text()
        labels |= set(re.findall(r"^\(([\w-]+)\)=", text, flags=re.M))
        labels |= set(re.findall(r"^:label: ([\w-]+)", text, flags=re.M))
        labels |= set(re.findall(r"^ +name: (fig-[\w-]+)", text, flags=re.M))
    return labels


def test_every_cause_and_explanation_names_an_existing_book_label():
    """A "differs, measured cause" row links a section of the book that exists (read from the
    book's sources: ``(label)=``, ``:label:``, figure ``name:``)."""
    targets = {
        t
        for _, _, c in _declarations()
        for t in (c.cause, c.hypothesis, c.explain)
        if t and "/" not in t
    }
    missing = sorted(targets - _book_labels())
    assert not missing, missing


def test_claims_are_declared_at_registration_and_the_central_lists_are_gone():
    for name in ("SPECS", "BOOK_ORDER", "SURROGATE_IDS", "CHAPTERS", "ClaimSpec"):
        assert not hasattr(L, name), name
    from fdi_lib.reproduce import book

    assert not hasattr(book, "BOOK_RUNS")
    for id, pattern, c in _declarations():
        assert isinstance(c, C.Claim), (id, pattern)
        if c.shown_under:
            L.get(c.shown_under)  # names a registered reproduction


def test_a_claim_without_a_declaration_fails():
    res = ReproductionResult(
        id="zb2014-fig1",
        headline={"unstable_eigenvalue": 1.2, "new": 1.0},
        paper={"unstable_eigenvalue": 1.2808, "new_claim": 3.0},
        settings={},
    )
    with pytest.raises(L.ModelError, match="no claim declared"):
        L.build_ledger({"zb2014-fig1": res}, strict=True)


def test_json_and_summary(cheap_results):
    led = L.build_ledger(cheap_results, sources={id: "computed" for id in cheap_results})
    d = json.loads(json.dumps(led.to_json_dict()))
    assert set(d["counts"]) == set(C.STATUSES)
    assert set(d["counts_by_paper"]) == set(C.PAPERS)
    assert sum(sum(c.values()) for c in d["counts_by_paper"].values()) == len(d["rows"])
    assert len(d["rows"]) == len(led.rows)
    old_keys = {
        "id",
        "key",
        "claim",
        "paper",
        "ours",
        "ci95",
        "status",
        "where",
        "explanation",
        "note",
        "surrogate",
        "trials",
        "source",
    }  # backward compatible
    assert old_keys | {
        "paper_id",
        "status_detail",
        "cause",
        "paper_trials",
        "location",
        "units",
        "test",
    } == set(d["rows"][0])
    for row in d["rows"]:
        assert row["status"] in C.STATUSES
        assert row["claim"].startswith(C.PAPERS[row["paper_id"]] + ", ")
        assert row["id"].startswith(row["paper_id"] + "-")
        if row["surrogate"] == C.INPUT:  # never counted as reproduced
            assert row["status"] != C.REPRODUCED, row
    html = led.summary()._repr_html_()
    assert all(s in html for s in C.STATUSES)
    assert '<thead><tr><th scope="col">status</th>' in html  # status first
    inputs = [r for r in led.rows if r.id == "zb2014-table1"]  # declared: neither list
    assert inputs and all(r.role == C.INPUT for r in inputs)
    # its detection time is the §6.4 sentence, listed under Fig. 11
    assert {r.role for r in led.rows if r.id == "rosa2013-fig8"} == {C.INPUT}
    assert all(r.role is None for r in led.rows if r.id.startswith("zb2014-fig1"))


def _row(status, location="Fig. 1, x", paper_id="zb2014"):
    return C.LedgerRow(
        id=f"{paper_id}-fig1",
        path=("x",),
        label=location,
        paper=1,
        ours=1,
        ci=None,
        status=status,
        where="book/x",
        explain=None,
        note="",
        role=None,
        trials=None,
        source="",
        location=location,
    )


def test_mission_items_take_their_state_from_their_rows(cheap_results):
    assert len(S.MISSION) == 40
    assert len({(p, item) for p, item, _ in S.MISSION}) == 40
    assert S.item_state([]) == "no row"
    assert S.item_state([_row(C.REPRODUCED), _row(C.INPUT_RECOVERED)]) == "reproduced"
    assert S.item_state([_row(C.INPUT_VALUE)]) == "values the book sets"
    assert S.item_state([_row(C.REPRODUCED), _row(C.DIFFERS_MEASURED)]) == "differs, measured cause"
    # the least explained difference decides
    assert S.item_state([_row(C.DIFFERS_MEASURED), _row(C.DIFFERS_BRACKETED)]) == "bracketed"
    assert S.item_state([_row(C.DIFFERS_HYPOTHESIS), _row(C.DIFFERS_UNKNOWN)]) == "unknown"
    assert S.item_state([_row(C.NOT_REPRODUCIBLE)]) == "not reproducible"
    led = L.build_ledger(cheap_results)
    items = {(i["paper_id"], i["item"]): i for i in led.mission()}
    assert items[("zb2014", "Fig. 1")]["state"] == "differs, measured cause"
    assert items[("zb2014", "Fig. 2")]["state"] == "reproduced"
    assert items[("zb2014", "Table 1")]["state"] == "values the book sets"
    assert items[("zb2014", "Fig. 9")]["state"] == "no row"  # not among the cheap results
    # "Fig. 1" is not "Fig. 10"
    assert not any("fig10" in r for r in items[("rosa2013", "Fig. 1")]["rows"])
    assert items[("rosa2013", "Fig. 10")]["rows"]
    counts = led.mission_counts()
    assert sum(sum(c.values()) for c in counts.values()) == 40
    assert "40" in led.mission_summary()._repr_html_()


def test_ledger_json_is_the_same_bytes_on_every_run_and_any_jobs(monkeypatch):
    """The wall times of the runs are kept apart: two runs, and a run on two cores, print the
    same JSON."""
    monkeypatch.delenv("FDI_RESULTS_CACHE", raising=False)
    ids = ["zb2014-fig1", "zb2014-table1", "zhang2021-table1"]
    texts = []
    for jobs in (1, 1, 2):
        results, sources, timings = L.collect_results(
            ids=ids, max_trials=4, use_cache=False, jobs=jobs
        )
        assert set(timings) == set(ids) and all(t >= 0 for t in timings.values())
        texts.append(json.dumps(L.build_ledger(results, sources=sources).to_json_dict()))
    assert texts[0] == texts[1] == texts[2]
    assert "4 trials" in texts[0] and " s)" not in texts[0]


# ----------------------------------------------------------------------------- cache and CLI
def test_results_cache_round_trip(tmp_path, monkeypatch):
    monkeypatch.setenv("FDI_RESULTS_CACHE", str(tmp_path))
    a = reproduce("zb2014-table1")
    files = list((tmp_path / "zb2014-table1").glob("*.pkl"))
    assert len(files) == 1
    b = reproduce("zb2014-table1")
    assert b.headline == a.headline and len(list(tmp_path.rglob("*.pkl"))) == 1
    reproduce("zb2014-fig3", seed=1)
    book_seed = book_settings("zb2014-fig3").seed
    reproduce("zb2014-fig3", seed=book_seed)  # the chapter's run
    reproduce("zb2014-fig3", seed=2)  # used last, with other settings
    got = cached_results()
    assert set(got) == {"zb2014-table1", "zb2014-fig3"}
    assert got["zb2014-fig3"].settings["seed"] == 2
    # the ledger reads the run at the book's settings, not the one used last
    results, sources, timings = L.collect_results(ids=["zb2014-fig3"])
    assert timings == {}  # read, not computed
    assert results["zb2014-fig3"].settings["seed"] == book_seed != 2
    assert sources["zb2014-fig3"].startswith("cached")
    monkeypatch.delenv("FDI_RESULTS_CACHE")
    assert cached_results() == {}


def test_cli_ledger_json(monkeypatch, capsys, cheap_results):
    from fdi_lib.reproduce import cli

    monkeypatch.setattr(
        L,
        "collect_results",
        lambda **kw: (
            cheap_results,
            {id: "computed" for id in cheap_results},
            {id: 1.0 for id in cheap_results},
        ),
    )
    assert cli.main(["reproduce", "--ledger", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert sum(d["counts"].values()) == len(d["rows"]) > 20
    assert set(d) == {"counts", "counts_by_paper", "mission", "rows", "sources"}  # no timings
    assert len(d["mission"]["items"]) == 40
    assert cli.main(["reproduce", "--ledger"]) == 0
    text = capsys.readouterr().out
    assert "differs, measured cause" in text and "zb2014-fig1 in 1.0 s" in text


@pytest.mark.slow
def test_every_registered_paper_value_appears_in_the_ledger(monkeypatch):
    """All reproductions (Monte Carlo ones with 2 trials; the wind turbine's false-alarm streams cut
    to 60 s, from 4400): strict build, nothing left out, one row per paper location, every
    declaration used."""
    from fdi_lib.systems import wind_turbine as wt

    monkeypatch.setattr(wt, "SCENARIO_S", 60.0)  # read by the false-alarm study alone
    results = {
        r.id: r(trials=None if r.default_trials is None else 2) for r in list_reproductions()
    }
    led = L.build_ledger(results, strict=True)  # raises on a claim without a declaration
    listed = _listed(led)
    n_claims = 0
    for id, res in results.items():
        for path in S.claim_paths(res.paper):
            n_claims += 1
            assert L._owner(id, path, S.claim_for(id, path)) in listed, (id, path)
    shown_twice = sum(
        1
        for id, res in results.items()
        for p in S.claim_paths(res.paper)
        if S.claim_for(id, p).shown_under
    )
    assert len(led.rows) == n_claims - shown_twice
    assert all(r.status in C.STATUSES for r in led.rows)
    # one claim, one row: no two rows share a paper location
    where = [(r.paper_id, r.location) for r in led.rows]
    assert len(where) == len(set(where)), sorted(w for w in where if where.count(w) > 1)
    assert all(r.location and r.test in C.TESTS for r in led.rows)
    # 2 trials: no Monte Carlo claim gets a comparison status
    for r in led.rows:
        if r.paper_trials is not None and r.status not in (C.INPUT_VALUE, C.NOT_REPRODUCIBLE):
            assert r.status == C.NOT_COMPUTED, (r.id, r.path, r.status)
    # no estimate of a value the book sets counts as a reproduction
    for r in led.rows:
        if r.test in (C.IS_INPUT, C.ESTIMATES_INPUT, C.IS_CALIBRATION) or r.role == C.INPUT:
            assert r.status not in C.AGREES, (r.id, r.path, r.status)
    for r in led.rows:
        if L.get(r.id).surrogate:
            assert r.role in (C.CALIBRATION, C.PREDICTION, C.INPUT)
        else:
            assert r.role is None
    # declarations: every declared key is compared (a paper value or a headline key), and the
    # ledger's roles follow them (fig 7: "missed" calibrated, fig 9: the level calibrated)
    for id, res in results.items():
        if any(k in res.paper for k in C.ROLE_KEYS):
            assert L.get(id).surrogate, id
            for k in res.paper.get("calibrated_to", []) + res.paper.get("predictions", []):
                assert k in res.paper or k in res.headline, (id, k)
    roles = {(r.id, r.path): r.role for r in led.rows}
    assert roles[("zb2014-fig7", ("missed", "2"))] == C.CALIBRATION
    assert roles[("zb2014-fig9", ("glr_level_over_threshold",))] == C.CALIBRATION
    assert roles[("zb2014-fig5", ("alarm_time_min",))] == C.PREDICTION
    # every declaration is used by some claim (no dead declaration)
    keys = {id: ["/".join(p) for p in S.claim_paths(res.paper)] for id, res in results.items()}
    for id, pattern, _ in _declarations():
        assert any(fnmatch.fnmatchcase(k, pattern) for k in keys[id]), (id, pattern)
    # each measured cause's section glues the measurement of each of its claims
    assert not _missing_glue(results)
    # the rows the issue named exist
    for id, key in (
        ("zb2014-fig9", "innovation_recovery"),
        ("bz-whiteness", "h_zeta_max"),
        ("zhang2021-table2", "snr_db/150"),
    ):
        assert (id, tuple(key.split("/"))) in listed, (id, key)
