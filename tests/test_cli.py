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


def documented_keys(rep) -> set[str]:
    """Keys of the "Headline keys" section of ``rep``'s docstring, following "keys as X" references."""
    import inspect

    doc = inspect.getdoc(rep.func) or ""
    if not re.search(r"Headline keys[^\n]*\n-+\n", doc):
        ref = re.search(r"[Kk]eys:? as (?::func:`(\w+)`|``([\w-]+)``)", doc)
        assert ref, f"{rep.id}: no 'Headline keys' section and no 'keys as ...' reference"
        if ref.group(1):
            module = __import__(rep.func.__module__, fromlist=["_"])
            target = next(
                r for r in list_reproductions() if r.func is getattr(module, ref.group(1))
            )
        else:
            target = get(ref.group(2))
        return documented_keys(target)
    section = re.split(r"Headline keys[^\n]*\n-+\n", doc, maxsplit=1)[1]
    section = re.split(r"\n\S[^\n]*\n-+\n", section, maxsplit=1)[0]  # up to the next section
    names = re.findall(r"^(\w+(?:, \w+)*) :", section, flags=re.M)
    return {key for entry in names for key in entry.split(", ")}


def test_every_registered_reproduction_documents_its_headline_keys():
    for rep in list_reproductions():
        assert len(documented_keys(rep)) >= 1, rep.id
        assert rep.plot is None or callable(rep.plot)


@pytest.mark.parametrize("rid", ["zb2014-fig1", "zb2014-fig2", "zb2014-fig4", "rosa2013-fig9"])
def test_headline_keys_are_exactly_the_documented_ones(rid):
    result = reproduce(rid)
    assert set(result.headline) == documented_keys(get(rid))


def test_json_is_one_object_with_the_contract_keys():
    proc = subprocess.run(
        [sys.executable, "-m", "fdi_lib", "reproduce", "zb2014-fig3", "--json"],
        capture_output=True,
        text=True,
        check=True,
    )
    obj = json.loads(proc.stdout)
    assert set(obj) == {"id", "headline", "paper", "settings"}
    for key in ("glr_max_before_fault", "glr_max_after_fault", "glr_argmax_time", "onset_estimate"):
        assert key in obj["headline"]


def test_unknown_id_and_bad_arguments(capsys):
    with pytest.raises(
        UnknownReproductionError, match="no reproduction 'zb2014-fig99'; known ids: .*zb2014-fig1"
    ):
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


@pytest.mark.parametrize(
    "kw",
    [
        {"default_trials": 9, "book_trials": 9},  # not smaller than the default
        {"default_trials": 9, "book_trials": 0, "min_trials": 1},  # below the fewest accepted
        {"default_trials": 9, "book_trials": 1},  # min_trials defaults to 2
        {"default_trials": 9, "book_trials": 1.5, "min_trials": 1},  # not an integer
        {"default_trials": 9, "book_trials": True, "min_trials": 1},
        {"book_trials": 1, "min_trials": 1},  # deterministic: no trials to reduce
    ],
)
def test_a_book_trial_count_outside_min_to_default_is_refused_at_registration(kw):
    """``register(book_trials=...)``: the book's count must lie in ``[min_trials,
    default_trials)``; anything else is refused when the module registers, and nothing is
    registered under the id."""
    from fdi_lib.reproduce.registry import _REGISTRY, register

    with pytest.raises(ModelError, match=r"book_trials: expected an integer in \[min_trials="):
        register("book-trials-probe", paper="none", title="t", chapter="none", **kw)
    assert "book-trials-probe" not in _REGISTRY


def test_unknown_keyword_is_rejected_by_name():
    with pytest.raises(TypeError, match="unexpected keyword argument 'sed'"):
        reproduce("zb2014-fig1", sed=3)


@pytest.mark.parametrize(
    "argv, pattern",
    [
        (["zb2014-fig1", "--seed", "-1"], r"seed: expected a non-negative integer, got -1"),
        (["zb2014-fig1", "--seed", "abc"], r"argument --seed: invalid int value: 'abc'"),
        (["zb2014-fig1", "--seed", "1.5"], r"argument --seed: invalid int value: '1.5'"),
        (
            ["zb2014-fig1", "--plot", "/no/such/folder/fig.png"],
            r"--plot: expected a file in an existing folder",
        ),
        (["zb2014-fig1", "--plot", "fig.docx"], r"--plot: expected an image file"),
        (["zb2014-table1", "--plot", "fig.png"], r"--plot: zb2014-table1 has no figure"),
        (
            ["zb2014-fig1", "--trials", "5"],
            r"trials: zb2014-fig1 is one deterministic or seeded run",
        ),
        (["zhang2021-table1", "--trials", "1"], r"--trials: expected at least 2"),
        (["zhang2021-table1", "--jobs", "0"], r"jobs: expected a non-zero integer"),
    ],
)
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


@pytest.mark.parametrize(
    "argv, pattern",
    [
        (["--ledger", "zb2014-fig1"], r"an ID and --ledger do not go together"),
        (["zb2014-fig1", "--ledger"], r"an ID and --ledger do not go together"),
        (["--ledger", "--plot", "fig.png"], r"--plot does not apply to --ledger"),
        (["--ledger", "--seed", "3"], r"--seed does not apply to --ledger"),
        (["--ledger", "--option", "a=1"], r"--option does not apply to --ledger"),
        (
            ["--ledger", "--jobs", "0"],
            r"argument --jobs: expected a non-zero integer \(-1 = all cores\), got 0",
        ),
        (["--ledger", "--seed", "-1"], r"argument --seed: expected a non-negative integer, got -1"),
        (["--ledger", "--trials", "0"], r"argument --trials: expected a positive integer, got 0"),
        (["--ledger", "--jobs", "two"], r"argument --jobs: invalid int value: 'two'"),
        (["--list", "zb2014-fig1"], r"an ID and --list do not go together"),
        (["--list", "--json"], r"--json does not apply to --list"),
        (["--describe"], r"--describe needs a reproduction ID"),
        (["zb2014-fig1", "--describe", "--seed", "2"], r"--seed does not apply to --describe"),
        ([], r"give a reproduction ID, --list or --ledger"),
    ],
)
def test_options_that_do_not_apply_are_a_usage_error_at_once(argv, pattern, capsys, monkeypatch):
    """``--ledger`` with an ID, --plot, a bad --jobs or --seed ran on for minutes: now argparse's
    usage error (one line, exit 2) before anything is computed."""
    import fdi_lib.reproduce.ledger as ledger_module
    from fdi_lib.reproduce.registry import Reproduction

    def no_compute(*args, **kwargs):
        raise AssertionError("something ran before the usage error")

    monkeypatch.setattr(Reproduction, "__call__", no_compute)
    monkeypatch.setattr(ledger_module, "ledger", no_compute)
    with pytest.raises(SystemExit) as exc:
        main(["reproduce", *argv])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and err.startswith("error: "), err
    assert re.search(pattern, err), err
    assert err.rstrip().endswith("(see python -m fdi_lib reproduce --help)")


def test_the_console_script_is_the_reproduce_command_under_its_own_name(capsys, monkeypatch):
    """``fdi-reproduce --list`` failed ("the following arguments are required: command") and its
    usage named python -m fdi_lib. The entry point is the one pyproject.toml declares."""
    import importlib
    import tomllib
    from pathlib import Path

    scripts = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text())
    module, _, name = scripts["project"]["scripts"]["fdi-reproduce"].partition(":")
    entry = getattr(importlib.import_module(module), name)
    monkeypatch.setattr(sys, "argv", ["fdi-reproduce", "--list"])
    assert entry() == 0
    listed = capsys.readouterr().out
    assert listed == _run_main(capsys, ["reproduce", "--list"])
    monkeypatch.setattr(sys, "argv", ["fdi-reproduce", "zb2014-fig1", "--json"])
    assert entry() == 0
    assert json.loads(capsys.readouterr().out)["id"] == "zb2014-fig1"
    monkeypatch.setattr(sys, "argv", ["fdi-reproduce", "--help"])
    with pytest.raises(SystemExit, match="0"):
        entry()
    text = capsys.readouterr().out
    assert text.startswith("usage: fdi-reproduce [-h]") and "python -m fdi_lib" not in text
    monkeypatch.setattr(sys, "argv", ["fdi-reproduce", "--list", "zb2014-fig1"])
    with pytest.raises(SystemExit, match="2"):
        entry()
    assert capsys.readouterr().err.rstrip().endswith("(see fdi-reproduce --help)")


def _run_main(capsys, argv):
    assert main(argv) == 0
    return capsys.readouterr().out


def test_psutil_is_declared():
    """psutil was imported (montecarlo.available_memory) but not declared in pyproject.toml."""
    import tomllib
    from pathlib import Path

    meta = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text())
    declared = {re.split(r"[<>=!~ \[]", d)[0].lower() for d in meta["project"]["dependencies"]}
    assert "psutil" in declared
