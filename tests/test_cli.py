"""The reproduction CLI and registry: a public contract (ids, JSON keys, errors)."""

import json
import re
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


@pytest.mark.parametrize("argv, pattern", [
    (["zb2014-fig1", "--seed", "-1"], r"seed: expected a non-negative integer, got -1"),
    (["zb2014-fig1", "--seed", "abc"], r"argument --seed: invalid int value: 'abc'"),
    (["zb2014-fig1", "--seed", "1.5"], r"argument --seed: invalid int value: '1.5'"),
    (["zb2014-fig1", "--plot", "/no/such/folder/fig.png"], r"--plot: expected a file in an existing folder"),
    (["zb2014-fig1", "--plot", "fig.docx"], r"--plot: expected an image file"),
    (["zb2014-table1", "--plot", "fig.png"], r"--plot: zb2014-table1 has no figure"),
    (["zb2014-fig1", "--trials", "5"], r"trials: zb2014-fig1 is one deterministic or seeded run"),
    (["zhang2021-table1", "--trials", "1"], r"trials: expected at least 2"),
    (["zhang2021-table1", "--jobs", "0"], r"jobs: expected a non-zero integer"),
])
def test_cli_checks_arguments_before_computing(argv, pattern, capsys, monkeypatch):
    """A one-line error and exit code 2, before anything is computed (no traceback)."""
    from fdi_lib.reproduce.registry import Reproduction

    def no_compute(self, **kwargs):
        raise AssertionError("the reproduction ran before its arguments were checked")

    monkeypatch.setattr(Reproduction, "__call__", no_compute)
    try:
        code = main(["reproduce", *argv])
    except SystemExit as exc:  # argparse's own checks (invalid int)
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    assert err.startswith("error: ")
    assert re.search(pattern, err), err


def test_monte_carlo_flag_follows_the_use_of_trials():
    assert get("zb2014-fig7").monte_carlo and get("bz-whiteness").monte_carlo
    assert not get("zb2014-fig3").monte_carlo and not get("rosa2013-fig8").monte_carlo
