"""Every reproduction's ``--json`` is its record (issue 34.3): byte-identical on the machine that
recorded it, and elsewhere the same bytes once each float within the machine's rounding of the
recorded one is written as recorded (:func:`json_identity.differences`).

The record, its trial counts, the tolerances and how to renew it: ``tools/json_identity.py`` (an
``--update`` needs a CHANGELOG line). A refactoring of :mod:`fdi_lib.reproduce` that changes a
byte of a reproduction's JSON beyond rounding fails here, named by identifier and key.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

from fdi_lib.reproduce import list_reproductions

_TOOL = Path(__file__).resolve().parents[1] / "tools" / "json_identity.py"
_spec = importlib.util.spec_from_file_location("json_identity", _TOOL)
json_identity = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(json_identity)

RECORD = json_identity.recorded()
#: Reproductions above about 5 s of CPU at their recorded trials (marked slow).
SLOW = {"windturbine-accommodation", "windturbine-scoreboard", "zhang2021-example2-interventions"}


def test_every_reproduction_is_recorded():
    ids = {r.id for r in list_reproductions()} - set(json_identity.SKIP)
    assert ids == set(RECORD), (sorted(ids - set(RECORD)), sorted(set(RECORD) - ids))


@pytest.mark.parametrize(
    "rid", [pytest.param(r, marks=[pytest.mark.slow] if r in SLOW else []) for r in sorted(RECORD)]
)
def test_json_is_the_record(rid, monkeypatch):
    monkeypatch.delenv("FDI_RESULTS_CACHE", raising=False)  # computed afresh, never read back
    entry = RECORD[rid]
    text = json_identity.json_text(rid, entry["trials"])
    assert json_identity.differences(rid, text, entry["json"]) == []


def test_rounding_is_the_only_allowance():
    """Floats within 1e-8 relative (or 1e-15) of the record and declared counts pass; a float, an
    integer, a string, a key or a layout changed beyond that each fail, named."""
    d = json_identity.differences
    rec = json.dumps(
        {"headline": {"x": 1.0, "n": 3, "s": "a", "z": 1e-17, "vertices_exact": [2021]}}
    )

    def changed(**kw):
        obj = json.loads(rec)
        obj["headline"].update(kw)
        return json.dumps(obj)

    assert d("any", changed(x=1.0 + 3.6e-10, z=8.5e-18), rec) == []
    assert d("rosa2013-timing", changed(vertices_exact=[2018]), rec) == []
    assert d("any", changed(x=1.0 + 1e-6), rec) == [".headline.x: 1.000001 against 1.0"]
    assert d("any", changed(n=4), rec) == [".headline.n: 4 against 3"]
    assert d("any", changed(n=3.0), rec) == [".headline.n: 3.0 against 3"]
    assert d("any", changed(s="b"), rec) == [".headline.s: 'b' against 'a'"]
    assert d("any", changed(vertices_exact=[2018]), rec) == [
        ".headline.vertices_exact[0]: 2018 against 2021"
    ]
    assert d("rosa2013-timing", changed(vertices_exact=[1900]), rec) != []
    assert d("any", rec.replace('"x": 1.0, ', ""), rec)[0].startswith(".headline: keys")
    assert d("any", rec, rec.replace(", ", ",", 1)) == [
        "the text differs beyond its numbers (key order or layout)"
    ]


def test_a_changed_byte_is_caught(monkeypatch, capsys):
    rid = "zb2014-fig1"
    changed = RECORD[rid]["json"].replace(", ", ",", 1)  # one byte fewer, same JSON object
    assert json.loads(changed) == json.loads(RECORD[rid]["json"])
    tampered = {rid: {**RECORD[rid], "json": changed}}
    monkeypatch.setattr(json_identity, "recorded", lambda: tampered)
    assert json_identity.compare([rid]) == 1
    assert f"DIFFERS: {rid}" in capsys.readouterr().out
