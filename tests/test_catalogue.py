"""The catalogue of reproductions: its commands recompute what the chapters show, its "shown in"
links point at the figure that draws each reproduction.

The full comparison of every command at the papers' trial counts with the results of a book
build is the post-build check ``tools/check_catalogue.py``; here the commands are parsed and
checked against the book's settings, the CLI is driven through each of them, and one seeded
command is run for real.
"""

from __future__ import annotations

import contextlib
import io
import json
import re
import sys
from pathlib import Path

import pytest

from fdi_lib.reproduce import cli
from fdi_lib.reproduce.book import CHAPTER_SEEDS, book_argv, book_order, book_run, book_settings
from fdi_lib.reproduce.registry import (
    CACHE_ENV,
    Reproduction,
    ReproductionResult,
    get,
    list_reproductions,
)

from source_module import load as _load  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


EXT = _load("fdi_book_ext", ROOT / "_ext" / "fdi_book.py")
sys.path.insert(0, str(ROOT / "tools"))
CHECK = _load("check_catalogue", ROOT / "tools" / "check_catalogue.py")

_COMMAND = re.compile(r"`python -m fdi_lib (reproduce [^`]+)`")


@pytest.fixture(scope="module")
def commands() -> dict[str, list[str]]:
    """The catalogue page's commands (generated as in a build), by id."""
    text, _ = EXT.catalogue_markdown(ROOT)
    argvs = [m.group(1).split() for m in _COMMAND.finditer(text)]
    ids = [a[1] for a in argvs]
    assert len(ids) == len(set(ids)), "one command per reproduction"
    return dict(zip(ids, argvs))


def _chapters() -> dict[str, str]:
    return {
        doc: (ROOT / f"{doc}.md").read_text()
        for doc in EXT._toc_files(ROOT)
        if doc.count("/") >= 2 and (ROOT / f"{doc}.md").is_file()
    }


def test_every_reproduction_has_a_command_with_the_book_settings(commands):
    assert set(commands) == {r.id for r in list_reproductions()}
    for rid, argv in commands.items():
        args = cli._parser().parse_args(argv)
        s, rep = book_settings(rid), get(rid)
        assert args.json and args.id == rid
        assert args.seed == (s.seed if rep.seeded else None), rid
        assert args.trials == s.trials, rid
    # a reproduction registered with chapter_seed=True runs at its chapter's seed, the others at
    # the registry's default
    for r in list_reproductions():
        chapter_seed = CHAPTER_SEEDS[r.chapter] if r.chapter_seed else r.default_seed
        assert book_settings(r.id).seed == chapter_seed
    assert commands["zb2014-fig3"] == ["reproduce", "zb2014-fig3", "--seed", "2015", "--json"]
    assert commands["rosa2013-fig11-rad"][-3:] == ["--trials", "10", "--json"]  # the paper's count


def test_registrations_name_their_chapter_and_valid_book_settings():
    """The chapter and the book's seed travel with each registration: the chapter exists in the
    table of contents and runs the reproduction; the settings pass the argument checks."""
    chapters = _chapters()
    for rep in list_reproductions():
        assert f"book/{rep.chapter}" in chapters, (rep.id, rep.chapter)
        assert re.search(
            rf"""\bbook_run\(\s*["']{re.escape(rep.id)}["']""", chapters[f"book/{rep.chapter}"]
        ), rep.id
        s = book_settings(rep.id)
        rep.check_arguments(seed=s.seed, trials=s.trials)
        if rep.chapter_seed:  # a chapter's seed only for a reproduction that reads its seed
            assert rep.seeded, rep.id
    assert set(CHAPTER_SEEDS) <= {doc.removeprefix("book/") for doc in chapters}


def test_catalogue_lists_each_reproductions_declared_claims():
    """Each entry names the claims its registration declares, with their comparison, or where they
    are listed; the statuses are the ledger's."""
    text, _ = EXT.catalogue_markdown(ROOT)
    assert text.count("**Claims** (declared at its registration") == len(list_reproductions())
    assert "Fig. 8, type II error of fault … (95 % interval)" in text
    assert "SNR of outputs 1 and 2 at r = … (standard error)" in text
    assert "listed under `zhang2021-table1`, `zhang2021-table2`" in text


def test_book_order_follows_the_table_of_contents():
    """Chapters in the order of _toc.yml, then the first book_run of each reproduction in it;
    the catalogue page lists them in the same order."""
    order = book_order()
    assert sorted(order) == sorted(r.id for r in list_reproductions())
    docs = [d for d in EXT._toc_files(ROOT) if d in _chapters()]
    ranks = [docs.index(f"book/{get(rid).chapter}") for rid in order]
    assert ranks == sorted(ranks)
    assert list(EXT.shown_in(ROOT)) == list(order)
    assert order.index("zb2014-fig1") < order.index("zb2014-fig3") < order.index("zhang2021-fig2")


def test_chapters_run_every_reproduction_through_the_book_settings():
    """No chapter calls ``reproduce`` or passes its own seed or trial count to a reproduction
    (``jobs`` and the reproduction's own keyword options are allowed)."""
    called = set()
    for doc, text in _chapters().items():
        for cell in EXT._CELL.finditer(text):
            body = cell.group(1)
            assert not re.search(r"\breproduce\(", body), f"{doc}: call book_run(ID), not reproduce"
            for m in re.finditer(r"\bbook_run\(([^)]*)\)", body):
                args = [a.strip() for a in m.group(1).split(",")]
                assert re.fullmatch(r"""["'][a-z0-9-]+["']""", args[0]), (doc, m.group(0))
                assert not any(re.match(r"(seed|trials)\s*=", a) for a in args[1:]), (
                    doc,
                    m.group(0),
                )
                called.add(args[0].strip("\"'"))
    assert called <= {r.id for r in list_reproductions()}
    assert "zb2014-fig3" in called and "rosa2013-fig11-rad" in called


def test_the_cli_runs_each_command_at_the_settings_of_book_run(commands, monkeypatch):
    """Each printed command passes the CLI's argument checks and calls the reproduction with the
    seed and trial count that the chapters' ``book_run`` passes (calls recorded, not computed)."""
    calls = []

    def record(self, *, seed=None, trials=None, jobs=1, **kwargs):
        calls.append((self.id, seed, trials, kwargs))
        return ReproductionResult(self.id, headline={})

    monkeypatch.setattr(Reproduction, "__call__", record)
    for rid, argv in commands.items():
        with contextlib.redirect_stdout(io.StringIO()):
            assert cli.main(argv) == 0, argv
        book_run(rid)
        cli_call, book_call = calls[-2:]
        rep = get(rid)
        resolved = [
            (i, rep.default_seed if s is None else s, rep.default_trials if t is None else t, k)
            for i, s, t, k in (cli_call, book_call)
        ]
        assert resolved[0] == resolved[1], rid


def test_a_printed_command_recomputes_the_chapter_result(commands, monkeypatch):
    """zb2014-fig3 for real: the command's JSON is the result the chapter shows (206 / 1886), and
    the command without the book's seed would not be (208 / 1729)."""
    monkeypatch.delenv(CACHE_ENV, raising=False)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert cli.main(commands["zb2014-fig3"]) == 0
    got = json.loads(out.getvalue())
    book = json.loads(book_run("zb2014-fig3").to_json())
    assert got == book
    default = get("zb2014-fig3")().headline
    assert (got["headline"]["glr_argmax_time"], round(got["headline"]["glr_max_after_fault"])) == (
        206,
        1886,
    )
    assert (default["glr_argmax_time"], round(default["glr_max_after_fault"])) == (208, 1729)


def test_shown_in_links_the_figure_that_draws_each_reproduction():
    chapters = _chapters()
    where = EXT.shown_in(ROOT)
    figures = {}
    for rid, w in where.items():
        if w["figure"] is None:
            continue
        figures.setdefault(w["figure"], []).append(rid)
        cell = next(
            c.group(1)
            for c in EXT._CELL.finditer(chapters[w["doc"]])
            if re.search(rf"^\s+name:\s*{re.escape(w['figure'])}\s*$", c.group(1), re.M)
        )
        assert re.search(rf"""\bget\(["']{re.escape(rid)}["']\)\.plot\(""", cell), (
            rid,
            w["figure"],
        )
    assert all(len(ids) == 1 for ids in figures.values()), figures  # no figure claimed twice
    # the two links that pointed at the figure of the neighbouring reproduction
    assert where["zb2014-fig6"]["figure"] == "fig-pipeline-fig6"
    assert where["zb2014-fig8"]["figure"] == "fig-pipeline-fig8"
    # every id plotted in a captioned figure is linked to a figure
    for doc, text in chapters.items():
        for cell in EXT._CELL.finditer(text):
            if re.search(r"^\s+name:\s*fig-", cell.group(1), re.M):
                for m in EXT._PLOT.finditer(cell.group(1)):
                    assert where[m.group(1)]["figure"] is not None, m.group(1)


def test_post_build_check_reads_the_commands_of_the_rendered_page():
    # the markup Sphinx writes for an inline literal (one span per word)
    page = (
        "<p>Introduction: <code>python -m fdi_lib reproduce ID --describe</code></p>"
        '<p><strong>Command (the book’s settings):</strong> <code class="docutils literal notranslate"><span class="pre">python</span> '
        '<span class="pre">-m</span> <span class="pre">fdi_lib</span> <span class="pre">reproduce</span> '
        '<span class="pre">zb2014-fig3</span>&#160;<span class="pre">--seed</span> <span class="pre">2015</span> '
        '<span class="pre">--json</span></code> and <code>--plot FILE.png</code></p>'
    )
    assert CHECK.page_commands(page) == [["reproduce", "zb2014-fig3", "--seed", "2015", "--json"]]


def test_post_build_check_compares_the_command_with_the_cached_chapter_result(
    tmp_path, monkeypatch
):
    """A cache holding the chapter's run: the book's command passes, a command at another seed is
    'not run' (the chapters never ran it), and a cached result that the command does not
    recompute 'differs'."""
    monkeypatch.setenv(CACHE_ENV, str(tmp_path))
    book_run("zb2014-fig1")  # deterministic and fast: the chapter's run, cached
    argv = book_argv("zb2014-fig1")
    runs = []
    real_run = CHECK.subprocess.run

    def run_once(*args, **kwargs):  # one real subprocess; the second check reuses its output
        if not runs:
            runs.append(real_run(*args, **kwargs))
        return runs[0]

    monkeypatch.setattr(CHECK.subprocess, "run", run_once)
    assert CHECK.check_command(argv, tmp_path)[1:] == ("ok", "")
    assert (
        CHECK.check_command(["reproduce", "zb2014-fig3", "--seed", "1", "--json"], tmp_path)[1]
        == "not run"
    )
    # tamper with the cached chapter result: the fresh command no longer matches it
    from fdi_lib.reproduce.registry import _cache_entry, _cache_write, cached_run
    import dataclasses

    cached = cached_run("zb2014-fig1")
    key = next(iter(cached.headline))
    tampered = dataclasses.replace(cached, headline={**cached.headline, key: "tampered"})
    _cache_write(*_cache_entry("zb2014-fig1", get("zb2014-fig1").default_seed, None, {}), tampered)
    rid, status, detail = CHECK.check_command(argv, tmp_path)
    assert status == "differs" and key in detail
    # a key the reproduction declares a wall time of this machine is not compared
    monkeypatch.setattr(CHECK, "get", lambda id: dataclasses.replace(get(id), timed_keys=(key,)))
    assert CHECK.check_command(argv, tmp_path)[1:] == ("ok", "")


def test_only_wall_times_are_declared_timed():
    """``timed_keys`` name documented headline keys, and only the timing reproduction has any."""
    import inspect

    timed = {r.id: r.timed_keys for r in list_reproductions() if r.timed_keys}
    assert set(timed) == {"rosa2013-timing"}
    doc = inspect.getdoc(get("rosa2013-timing").func)
    assert all(re.search(rf"^{k}\b.*:", doc, flags=re.M) for k in timed["rosa2013-timing"])


def test_options_reach_the_reproduction_from_book_run_and_the_printed_command(monkeypatch):
    """``book_run(id, **options)`` and ``book_command(id, **options)`` (``--option NAME=VALUE``)
    make the same call; an option the reproduction does not take is a typed error naming it."""
    from fdi_lib.reproduce import cli
    from fdi_lib.reproduce.book import book_argv, book_run
    from fdi_lib.reproduce.registry import Reproduction

    calls = []

    def record(self, *, seed=None, trials=None, jobs=1, **kwargs):
        calls.append((self.id, seed, trials, kwargs))
        return get("zb2014-table1").func(seed=0, trials=None, jobs=1)

    monkeypatch.setattr(Reproduction, "__call__", record)
    book_run("zb2014-fig8", isolation_window="record_end", state2_scale=3.0)
    argv = book_argv("zb2014-fig8", isolation_window="record_end", state2_scale=3.0)
    assert cli.main(argv) == 0
    assert (
        calls[0]
        == calls[1]
        == ("zb2014-fig8", 0, 1000, {"isolation_window": "record_end", "state2_scale": 3.0})
    )
    assert cli.main(["reproduce", "zb2014-fig8", "--option", "window=1", "--json"]) == 2
    assert cli.main(["reproduce", "zb2014-fig8", "--option", "isolation_window", "--json"]) == 2
    assert len(calls) == 2
