"""The claims ledger: every paper value appears, every status is computed from the numbers."""

import dataclasses
import json
import re
from pathlib import Path

import pytest

from fdi_lib.reproduce import list_reproductions, reproduce
from fdi_lib.reproduce import ledger as L
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
    assert L.claim_status(20, None)[0] == L.DIFFERS                  # we have no value
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
            spec = L.spec_for(id, path)
            owner = spec.shown_under if spec and spec.shown_under else id
            assert (owner, path) in listed or owner not in cheap_results, (id, path)
    assert sum(led.counts().values()) == len(led.rows)
    # rows in book order
    order = [L.BOOK_ORDER.index(r.id) for r in led.rows]
    assert order == sorted(order)


def test_statuses_are_computed_not_typed(cheap_results):
    """Perturb a paper value: the status follows the numbers."""
    base = {(r.id, r.path): r.status for r in L.build_ledger(cheap_results).rows}
    assert base[("zb2014-table1", ("G0_1_nominal",))] == L.REPRODUCED
    assert base[("zb2014-fig1", ("gamma_norm_max", "101"))] == L.DIFFERS
    t1 = cheap_results["zb2014-table1"]
    moved = dataclasses.replace(t1, paper={**t1.paper, "G0_1_nominal": t1.paper["G0_1_nominal"] * 1.01})
    f1 = cheap_results["zb2014-fig1"]
    relaxed = dataclasses.replace(f1, paper={**f1.paper, "gamma_norm_max": {"101": "< 2"}})
    rows = {(r.id, r.path): r.status
            for r in L.build_ledger({**cheap_results, "zb2014-table1": moved,
                                     "zb2014-fig1": relaxed}).rows}
    assert rows[("zb2014-table1", ("G0_1_nominal",))] == L.DIFFERS
    assert rows[("zb2014-fig1", ("gamma_norm_max", "101"))] == L.REPRODUCED
    # the status column of the rendered table is the computed one
    text = L.build_ledger(cheap_results).to_myst()
    assert text.count("  - differs") == sum(s == L.DIFFERS for s in base.values())


def test_within_interval_from_a_stochastic_result():
    res = ReproductionResult(id="zhang2021-table1", headline={
        "success_rate": {"15": 0.31, "16": 0.46}, "ci95": {"15": [0.28, 0.34], "16": [0.43, 0.49]}},
        paper={"success_rate": {"15": 0.295, "16": 0.251}}, settings={"trials": 1000})
    rows = L.build_ledger({"zhang2021-table1": res}, strict=True).rows
    assert [r.status for r in rows] == [L.WITHIN, L.DIFFERS]
    assert rows[0].ci == (0.28, 0.34) and rows[1].explain and rows[0].trials == 1000


def test_every_difference_links_to_an_existing_target(cheap_results):
    labels, figures = set(), set()
    for md in (ROOT / "book").rglob("*.md"):
        text = md.read_text()
        labels |= set(re.findall(r"^\(([\w-]+)\)=", text, flags=re.M))
        labels |= set(re.findall(r"^:label: ([\w-]+)", text, flags=re.M))
        figures |= set(re.findall(r"^ +name: (fig-[\w-]+)", text, flags=re.M))
    targets = {s.explain for s in L.SPECS.values() if s.explain}
    targets |= {doc for _, doc in L.CHAPTERS}
    for t in targets:
        if "/" in t:
            assert (ROOT / f"{t}.md").exists(), t
        elif t.startswith("fig-"):
            assert t in figures, t
        else:
            assert t in labels, t
    for r in L.build_ledger(cheap_results).rows:
        if r.status in (L.DIFFERS, L.NOT_REPRODUCIBLE):
            assert r.explain, (r.id, r.path)


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
    assert len(d["rows"]) == len(led.rows)
    assert {"paper", "ours", "ci95", "status", "explanation", "surrogate"} <= set(d["rows"][0])
    html = led.summary()._repr_html_()
    assert all(s in html for s in L.STATUSES)
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
    reproduce("zb2014-fig3", seed=2)                  # the last one used is the ledger's
    got = cached_results()
    assert set(got) == {"zb2014-table1", "zb2014-fig3"}
    assert got["zb2014-fig3"].settings["seed"] == 2
    results, sources = L.collect_results(ids=["zb2014-fig3"])
    assert results["zb2014-fig3"].settings["seed"] == 2 and sources["zb2014-fig3"].startswith("cached")
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
    assert "differs" in capsys.readouterr().out


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
            spec = L.spec_for(id, path)
            owner = spec.shown_under if spec and spec.shown_under else id
            assert (owner, path) in listed, (id, path)
    shown_twice = sum(1 for id, res in results.items() for p in L.claim_paths(res.paper)
                      if (s := L.spec_for(id, p)) and s.shown_under)
    assert len(led.rows) == n_claims - shown_twice
    assert all(r.status in L.STATUSES for r in led.rows)
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
