"""The reproduction CLI and registry: a public contract (ids, JSON keys, errors)."""

import json
import subprocess
import sys

import pytest

from fdi_lib.errors import ModelError, UnknownReproductionError
from fdi_lib.reproduce import get, list_reproductions, reproduce
from fdi_lib.reproduce.cli import main


def test_list_contains_the_foundation_ids(capsys):
    assert main(["reproduce", "--list"]) == 0
    out = capsys.readouterr().out
    for rid in ("zb2014-fig1", "zb2014-fig2", "zb2014-fig3", "zb2014-fig4"):
        assert rid in out


def test_every_registered_reproduction_is_documented():
    for rep in list_reproductions():
        doc = rep.func.__doc__ or ""
        assert len(doc) > 40, f"{rep.id} has no docstring documenting its headline keys"
        assert rep.plot is None or callable(rep.plot)


def test_json_is_one_object_with_the_contract_keys():
    proc = subprocess.run([sys.executable, "-m", "fdi_lib", "reproduce", "zb2014-fig3", "--json"],
                          capture_output=True, text=True, check=True)
    obj = json.loads(proc.stdout)
    assert set(obj) == {"id", "headline", "paper", "settings"}
    for key in ("glr_max_before_fault", "glr_max_after_fault", "glr_argmax_time", "onset_estimate"):
        assert key in obj["headline"]


def test_unknown_id_and_bad_arguments(capsys):
    with pytest.raises(UnknownReproductionError, match="no reproduction 'zb2014-fig99'; known ids: .*zb2014-fig1"):
        get("zb2014-fig99")
    assert main(["reproduce", "zb2014-fig99"]) == 2
    assert "no reproduction" in capsys.readouterr().err
    with pytest.raises(ModelError, match=r"trials: expected a positive integer, got 0"):
        reproduce("zb2014-fig1", trials=0)
    with pytest.raises(ModelError, match=r"jobs: expected a non-zero integer"):
        reproduce("zb2014-fig1", jobs=0)


def test_describe_prints_the_docstring(capsys):
    assert main(["reproduce", "zb2014-fig1", "--describe"]) == 0
    assert "gamma_norm_max" in capsys.readouterr().out


def test_unknown_keyword_is_rejected_by_name():
    with pytest.raises(TypeError, match="unexpected keyword argument 'sed'"):
        reproduce("zb2014-fig1", sed=3)
