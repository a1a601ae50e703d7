"""Every reproduction's ``--json`` is byte-identical to its record (issue 34.3).

The record, its trial counts and how to renew it: ``tools/json_identity.py`` (an ``--update``
needs a CHANGELOG line). A refactoring of :mod:`fdi_lib.reproduce` that changes a single byte of
a reproduction's JSON fails here, named by identifier.
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
def test_json_is_byte_identical_to_the_record(rid, monkeypatch):
    monkeypatch.delenv("FDI_RESULTS_CACHE", raising=False)  # computed afresh, never read back
    entry = RECORD[rid]
    assert json_identity.json_text(rid, entry["trials"]) == entry["json"]


def test_a_changed_byte_is_caught(monkeypatch, capsys):
    rid = "zb2014-fig1"
    changed = RECORD[rid]["json"].replace(", ", ",", 1)  # one byte fewer, same JSON object
    assert json.loads(changed) == json.loads(RECORD[rid]["json"])
    tampered = {rid: {**RECORD[rid], "json": changed}}
    monkeypatch.setattr(json_identity, "recorded", lambda: tampered)
    assert json_identity.compare([rid]) == 1
    assert f"DIFFERS: {rid}" in capsys.readouterr().out
