"""The claims ledger: every paper value appears, every status is computed from the numbers."""

import dataclasses
import json
import re
from pathlib import Path

import pytest

from fdi_lib.reproduce import list_reproductions, reproduce
from fdi_lib.reproduce import ledger as L
from fdi_lib.reproduce.book import book_settings
from fdi_lib.reproduce.registry import ReproductionResult, cached_results

ROOT = Path(__file__).resolve().parents[2]
# Cheap reproductions (no Monte Carlo) covering numbers, lists, booleans, inequalities, checks.
CHEAP = ["zb2014-fig1", "zb2014-fig2", "zb2014-fig3", "zb2014-fig4", "zb2014-table1",
         "zhang2021-fig2", "zhang2021-fig3", "rosa2013-fig8", "rosa2013-fig10", "rosa2013-timing"]


@pytest.fixture(scope="module")
def cheap_results():
    return {id: reproduce(id) for id in CHEAP}


# ----------------------------------------------------------------------------- statuses
def test_status_of_numbers_lists_and_intervals():
    assert L.claim_status(786.0, 786.0)[0] == L.REPRODUCED
    assert L.claim_status(786.0, 786.5)[0] == L.REPRODUCED          # within 1e-3 relative
    assert L.claim_status(786.0, 790.0)[0] == L.DIFFERS
    assert L.claim_status(0.295, 0.465, (0.43, 0.50))[0] == L.DIFFERS
    assert L.claim_status(0.295, 0.31, (0.28, 0.34))[0] == L.WITHIN
    assert L.claim_status([4.0, 0.0], [4.0, 0.0])[0] == L.REPRODUCED
    assert L.claim_status([4.0, 0.0], [4.0, 0.1])[0] == L.DIFFERS
    assert L.claim_status([4.0, 0.0], [4.0])[0] == L.DIFFERS
    assert L.claim_status(20, None)[0] == L.NOT_COMPUTED             # we have no value
    never = L.ClaimSpec(missing="not detected")                      # None is a result
    assert L.claim_status(20, None, spec=never) == (L.DIFFERS, "ours: not detected")
    # a single run: inside the 95 % range of our runs, or not
    assert L.claim_status(786.0, 778.0, spread=(700.0, 800.0))[0] == L.WITHIN_SPREAD
    assert L.claim_status(88.0, 36.0, spread=(20.0, 60.0))[0] == L.DIFFERS
    assert L.claim_status(786.0, 786.0, spread=(700.0, 800.0))[0] == L.REPRODUCED
    assert L.claim_status(True, True)[0] == L.REPRODUCED
    assert L.claim_status(True, False)[0] == L.DIFFERS


def test_status_of_text_claims():
    assert L.claim_status("< 1", 0.99)[0] == L.REPRODUCED
    assert L.claim_status("< 1", 1.81)[0] == L.DIFFERS
    assert L.claim_status("< 500", [100.0, 499.0])[0] == L.REPRODUCED
    assert L.claim_status("about 3500", 3500.0)[0] == L.REPRODUCED
    assert L.claim_status("about 3500", 280.0)[0] == L.DIFFERS
    assert L.claim_status("grows", 1.0)[0] == L.NOT_REPRODUCIBLE    # no check: flagged
    spec = L.ClaimSpec(check=lambda p, o, h: o > 2, criterion="o > 2")
    assert L.claim_status("grows", 3.0, spec=spec) == (L.REPRODUCED, "o > 2")
    assert L.claim_status("grows", 1.0, spec=spec)[0] == L.DIFFERS
    assert L.claim_status("0 (Prop. 2)", -0.08, (-0.09, -0.07),
                          L.ClaimSpec(value=lambda p: 0.0))[0] == L.DIFFERS
    assert L.claim_status("0 (Prop. 2)", -0.01, (-0.03, 0.01),
                          L.ClaimSpec(value=lambda p: 0.0))[0] == L.WITHIN
    why = "timing on another machine"
    assert L.claim_status(5.0, 5.0, spec=L.ClaimSpec(reason=why)) == (L.NOT_REPRODUCIBLE, why)


def test_claim_paths_skip_values_that_state_nothing():
    paper = {"a": 1, "b": {"x": "< 1", "y": None}, "c": "not stated", "d": [1, 2],
             "e": "illustration, no numbers"}
    assert L.claim_paths(paper) == [("a",), ("b", "x"), ("d",)]
    declared = {"a": 1, "calibrated_to": ["a"], "predictions": [], "b": {"predictions": 2}}
    assert L.claim_paths(declared) == [("a",), ("b", "predictions")]   # role lists: top level only


def test_surrogate_role_is_the_reproductions_declaration():
    paper = {"x": 1, "y": 2, "z": 3, "calibrated_to": ["x"], "predictions": ["y"]}
    typed = L.ClaimSpec(role=L.CALIBRATION)
    assert [L.surrogate_role("zb2014-fig9", paper, (k,), typed) for k in "xyz"] == [
        L.CALIBRATION, L.PREDICTION, L.INPUT]                 # the typed role is ignored
    assert L.surrogate_role("rosa2013-fig8", {"x": 1}, ("x",), typed) == L.CALIBRATION
    assert L.surrogate_role("rosa2013-fig8", {"x": 1}, ("x",)) == L.PREDICTION
    assert L.surrogate_role("zb2014-fig1", {"x": 1}, ("x",), typed) is None
    # moving a key between the lists moves its row
    res = ReproductionResult(id="zb2014-fig9", headline={"x": 1.0, "y": 2.0},
                             paper={"x": 1.0, "y": 2.0, "calibrated_to": ["x"], "predictions": ["y"]},
                             settings={})
    roles = {r.path: r.role for r in L.build_ledger({"zb2014-fig9": res}).rows}
    assert roles == {("x",): L.CALIBRATION, ("y",): L.PREDICTION}
    swapped = dataclasses.replace(res, paper={**res.paper, "calibrated_to": ["y"], "predictions": ["x"]})
    roles = {r.path: r.role for r in L.build_ledger({"zb2014-fig9": swapped}).rows}
    assert roles == {("x",): L.PREDICTION, ("y",): L.CALIBRATION}


# ----------------------------------------------------------------------------- the ledger
def _listed(ledger):
    return {(r.id, r.path) for r in ledger.rows}


def test_every_paper_value_appears(cheap_results):
    led = L.build_ledger(cheap_results, strict=True)
    listed = _listed(led)
    for id, res in cheap_results.items():
        for path in L.claim_paths(res.paper):
            owner = L._owner(id, path, L.spec_for(id, path) or L.ClaimSpec())
            assert owner in listed or owner[0] not in cheap_results, (id, path)
    assert sum(led.counts().values()) == len(led.rows)
    # rows in book order
    order = [L.BOOK_ORDER.index(r.id) for r in led.rows]
    assert order == sorted(order)


def test_statuses_are_computed_not_typed(cheap_results):
    """Perturb a paper value: the status follows the numbers."""
    base = {(r.id, r.path): r.status for r in L.build_ledger(cheap_results).rows}
    assert base[("zb2014-table1", ("G0_1_nominal",))] == L.INPUT_VALUE      # set by the book
    assert base[("zb2014-fig1", ("gamma_norm_max", "101"))] == L.DIFFERS_MEASURED
    t1 = cheap_results["zb2014-table1"]
    moved = dataclasses.replace(t1, paper={**t1.paper, "G0_1_nominal": t1.paper["G0_1_nominal"] * 1.01})
    f1 = cheap_results["zb2014-fig1"]
    relaxed = dataclasses.replace(f1, paper={**f1.paper, "gamma_norm_max": {"101": "< 2"}})
    rows = {(r.id, r.path): r.status
            for r in L.build_ledger({**cheap_results, "zb2014-table1": moved,
                                     "zb2014-fig1": relaxed}).rows}
    assert rows[("zb2014-table1", ("G0_1_nominal",))] == L.DIFFERS_UNKNOWN  # an input we miss
    assert rows[("zb2014-fig1", ("gamma_norm_max", "101"))] == L.REPRODUCED
    # the status column (the first) of the rendered table is the computed one
    text = L.build_ledger(cheap_results).to_myst()
    for status in L.STATUSES:
        assert text.count(f"* - {status}\n") == sum(s == status for s in base.values()), status


def test_within_interval_from_a_stochastic_result():
    res = ReproductionResult(id="zhang2021-table1", headline={
        "success_rate": {"15": 0.31, "16": 0.46}, "ci95": {"15": [0.28, 0.34], "16": [0.43, 0.49]}},
        paper={"success_rate": {"15": 0.295, "16": 0.251}}, settings={"trials": 1000})
    rows = L.build_ledger({"zhang2021-table1": res}, strict=True).rows
    assert [r.status for r in rows] == [L.WITHIN, L.DIFFERS_UNKNOWN]
    assert rows[0].ci == (0.28, 0.34) and rows[1].explain and rows[0].trials == 1000
    assert rows[1].cause is None and rows[0].paper_trials == 1000
    # the paper's rate between our two readings of the rule, measured on the same trials
    between = dataclasses.replace(res, headline={**res.headline,
                                                 "success_rate_linear": {"15": 0.30, "16": 0.20}})
    rows = L.build_ledger({"zhang2021-table1": between}, strict=True).rows
    assert [r.status for r in rows] == [L.WITHIN, L.DIFFERS_MEASURED]
    assert rows[1].cause == "sec-zhang2021-oracles" and rows[1].status_detail
    # both cells of a rate in %: no paper fraction beside a percentage of ours
    text = L.build_ledger({"zhang2021-table1": res}).to_myst().replace("\u00a0", " ")
    assert "25.1 %" in text and "46 %" in text and "0.251" not in text


def test_statuses_need_the_papers_trial_count():
    """A Monte Carlo result with fewer trials than the paper's gives no comparison status."""
    res = ReproductionResult(id="zhang2021-table1", headline={
        "success_rate": {"15": 0.31, "16": 0.46}, "ci95": {"15": [0.0, 0.9], "16": [0.0, 0.9]}},
        paper={"success_rate": {"15": 0.295, "16": 0.251}}, settings={"trials": L.FALLBACK_TRIALS})
    rows = L.build_ledger({"zhang2021-table1": res}, strict=True).rows
    assert {r.status for r in rows} == {L.NOT_COMPUTED}       # not "within interval" (huge CI)
    assert all(r.status_detail.startswith("not computed at paper scale") for r in rows)
    assert L.get("zhang2021-table1").default_trials == rows[0].paper_trials == 1000
    # an input stays an input at any trial count
    f8 = ReproductionResult(id="zb2014-fig8", headline={"threshold_dof": 1},
                            paper={"threshold_dof": "1 (caption) / 2 (text)", "calibrated_to": [],
                                   "predictions": []}, settings={"trials": 2})
    assert [r.status for r in L.build_ledger({"zb2014-fig8": f8}).rows] == [L.INPUT_VALUE]


def test_within_spread_of_a_single_run():
    """Figs. 5-6 of the pipeline: one run of the paper against our run-to-run distribution."""
    paper = {"alarm_time_min": 786.0, "detection_delay_min": 186.0,
             "calibrated_to": [], "predictions": ["alarm_time_min", "detection_delay_min"]}
    head = {"alarm_time_min": 778.0, "detection_delay_min": 178.0}
    plain = ReproductionResult(id="zb2014-fig5", headline=head, paper=paper, settings={})
    assert {r.status for r in L.build_ledger({"zb2014-fig5": plain}).rows} == {L.DIFFERS_UNKNOWN}
    spread = dataclasses.replace(plain, headline={
        **head, "alarm_time_min_spread95": [700.0, 800.0], "alarm_time_min_paper_percentile": 71.0,
        "detection_delay_min_spread95": [100.0, 180.0], "spread_runs": 1000})
    rows = {r.path[0]: r for r in L.build_ledger({"zb2014-fig5": spread}).rows}
    assert rows["alarm_time_min"].status == L.WITHIN_SPREAD
    assert "71" in rows["alarm_time_min"].status_detail and "1 000" in rows[
        "alarm_time_min"].status_detail.replace("\u202f", " ")
    assert rows["detection_delay_min"].status in L.DIFFERING      # 186 outside [100, 180]


def test_one_row_per_claim():
    """The Table I/II values the λ-rule study checks again are listed once, under the table."""
    t1 = ReproductionResult(id="zhang2021-table1", headline={
        "success_rate": {"15": 0.465}, "ci95": {"15": [0.43, 0.50]}},
        paper={"success_rate": {"15": 0.295}}, settings={"trials": 1000})
    lr = ReproductionResult(id="zhang2021-lambda-rule", headline={
        "success_rate": {"log": {"q15": 0.455}}, "ci95": {"log": {"q15": [0.38, 0.53]}}},
        paper={"success_rate": {"q15": 0.295}}, settings={"trials": 200})
    rows = L.build_ledger({"zhang2021-table1": t1, "zhang2021-lambda-rule": lr}, strict=True).rows
    assert [(r.id, r.path) for r in rows] == [("zhang2021-table1", ("success_rate", "15"))]
    assert "zhang2021-lambda-rule on 200 trials: 45.5" in rows[0].note


def test_the_other_reading_of_a_figure_is_a_note_and_its_caption_has_its_own_statuses():
    """The per-radian UAV figures check the paper's Figs 11-12 again: one row per claim (the
    per-degree reading's), the other reading in its note; its own figure's caption judges it."""
    deg = ReproductionResult(id="rosa2013-fig11", headline={
        "detection_time_ms": {"alpha": {"step": 10.0}}}, paper={
        "detection_time_ms": {"alpha": {"step": 10}}}, settings={"trials": 10})
    rad = dataclasses.replace(deg, id="rosa2013-fig11-rad", headline={
        "detection_time_ms": {"alpha": {"step": None}}})
    rows = L.build_ledger({"rosa2013-fig11": deg, "rosa2013-fig11-rad": rad}, strict=True).rows
    assert [(r.id, r.status) for r in rows] == [("rosa2013-fig11", L.REPRODUCED)]
    assert "rosa2013-fig11-rad on 10 trials: not detected in any run" in rows[0].note
    claim = L.figure_claim(rad)
    assert claim.verb == L.COMPARE and "not detected" in claim.differs
    assert L.figure_claim(deg).verb == L.REPRODUCES


def test_every_difference_links_to_where_it_is_shown(cheap_results):
    for _, doc in L.CHAPTERS:
        assert (ROOT / f"{doc}.md").exists(), doc
    for s in L.SPECS.values():
        if s.explain and "/" in s.explain:
            assert (ROOT / f"{s.explain}.md").exists(), s.explain
    for r in L.build_ledger(cheap_results).rows:
        if r.status in (*L.DIFFERING, L.NOT_REPRODUCIBLE, L.NOT_COMPUTED):
            assert r.explain, (r.id, r.path)
        assert (r.cause is not None) == (r.status == L.DIFFERS_MEASURED), (r.id, r.path)


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
    targets = {t for s in L.SPECS.values() for t in (s.cause, s.explain) if t and "/" not in t}
    missing = sorted(targets - _book_labels())
    assert not missing, missing


def test_every_rule_names_a_registered_reproduction():
    ids = [r.id for r in list_reproductions()]
    for pattern in L.SPECS:
        id_pattern = pattern.split(":", 1)[0]
        assert any(L.fnmatch.fnmatchcase(i, id_pattern) for i in ids), pattern
    assert set(L.BOOK_ORDER) == set(ids)


def test_json_and_summary(cheap_results):
    led = L.build_ledger(cheap_results, sources={id: "computed" for id in cheap_results})
    d = json.loads(json.dumps(led.to_json_dict()))
    assert set(d["counts"]) == set(L.STATUSES)
    assert set(d["counts_by_paper"]) == set(L.PAPERS)
    assert sum(sum(c.values()) for c in d["counts_by_paper"].values()) == len(d["rows"])
    assert len(d["rows"]) == len(led.rows)
    old_keys = {"id", "key", "claim", "paper", "ours", "ci95", "status", "where", "explanation",
                "note", "surrogate", "trials", "source"}                # backward compatible
    assert old_keys | {"paper_id", "status_detail", "cause", "paper_trials"} == set(d["rows"][0])
    for row in d["rows"]:
        assert row["status"] in L.STATUSES
        assert row["claim"].startswith(L.PAPERS[row["paper_id"]] + ", ")
        assert row["id"].startswith(row["paper_id"] + "-")
        if row["surrogate"] == L.INPUT:                 # never counted as reproduced
            assert row["status"] != L.REPRODUCED, row
    html = led.summary()._repr_html_()
    assert all(s in html for s in L.STATUSES)
    assert "<thead><tr><th>status</th>" in html                         # status first
    inputs = [r for r in led.rows if r.id == "zb2014-table1"]      # declared: neither list
    assert inputs and all(r.role == L.INPUT for r in inputs)
    assert {r.role for r in led.rows if r.id == "rosa2013-fig8"} == {L.INPUT, L.PREDICTION}
    assert all(r.role is None for r in led.rows if r.id.startswith("zb2014-fig1"))


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
    reproduce("zb2014-fig3", seed=book_seed)          # the chapter's run
    reproduce("zb2014-fig3", seed=2)                  # used last, with other settings
    got = cached_results()
    assert set(got) == {"zb2014-table1", "zb2014-fig3"}
    assert got["zb2014-fig3"].settings["seed"] == 2
    # the ledger reads the run at the book's settings, not the one used last
    results, sources = L.collect_results(ids=["zb2014-fig3"])
    assert results["zb2014-fig3"].settings["seed"] == book_seed != 2
    assert sources["zb2014-fig3"].startswith("cached")
    monkeypatch.delenv("FDI_RESULTS_CACHE")
    assert cached_results() == {}


def test_cli_ledger_json(monkeypatch, capsys, cheap_results):
    from fdi_lib.reproduce import cli

    monkeypatch.setattr(L, "collect_results",
                        lambda **kw: (cheap_results, {id: "computed" for id in cheap_results}))
    assert cli.main(["reproduce", "--ledger", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert sum(d["counts"].values()) == len(d["rows"]) > 20
    assert cli.main(["reproduce", "--ledger"]) == 0
    assert "differs, measured cause" in capsys.readouterr().out


@pytest.mark.slow
def test_every_registered_paper_value_appears_in_the_ledger():
    """All reproductions (Monte Carlo ones with 2 trials): strict build, nothing left out."""
    results = {r.id: r(trials=None if r.default_trials is None else 2)
               for r in list_reproductions()}
    led = L.build_ledger(results, strict=True)      # raises on a claim without a rule
    listed = _listed(led)
    n_claims = 0
    for id, res in results.items():
        for path in L.claim_paths(res.paper):
            n_claims += 1
            assert L._owner(id, path, L.spec_for(id, path) or L.ClaimSpec()) in listed, (id, path)
    shown_twice = sum(1 for id, res in results.items() for p in L.claim_paths(res.paper)
                      if (s := L.spec_for(id, p)) and s.shown_under)
    assert len(led.rows) == n_claims - shown_twice
    assert all(r.status in L.STATUSES for r in led.rows)
    # 2 trials: no Monte Carlo claim gets a comparison status
    for r in led.rows:
        if r.paper_trials is not None and r.status not in (L.INPUT_VALUE, L.NOT_REPRODUCIBLE):
            assert r.status == L.NOT_COMPUTED, (r.id, r.path, r.status)
    for r in led.rows:
        if r.id in L.SURROGATE_IDS:
            assert r.role in (L.CALIBRATION, L.PREDICTION, L.INPUT)
        else:
            assert r.role is None
    # declarations: every declared key is compared (a paper value or a headline key), and the
    # ledger's roles follow them (fig 7: "missed" calibrated, fig 9: the level calibrated)
    for id, res in results.items():
        if any(k in res.paper for k in L.ROLE_KEYS):
            assert id in L.SURROGATE_IDS, id
            for k in res.paper.get("calibrated_to", []) + res.paper.get("predictions", []):
                assert k in res.paper or k in res.headline, (id, k)
    roles = {(r.id, r.path): r.role for r in led.rows}
    assert roles[("zb2014-fig7", ("missed", "2"))] == L.CALIBRATION
    assert roles[("zb2014-fig9", ("glr_level_over_threshold",))] == L.CALIBRATION
    assert roles[("zb2014-fig5", ("alarm_time_min",))] == L.PREDICTION
    # every rule is used by some claim (no dead rule)
    keys = [f"{id}:{'/'.join(p)}" for id, res in results.items() for p in L.claim_paths(res.paper)]
    for pattern in L.SPECS:
        assert any(L.fnmatch.fnmatchcase(k, pattern) for k in keys), pattern
