"""The command line at its edges (issue 21): --jobs above the cores, progress, SIGINT, a damaged
results cache."""

from __future__ import annotations

import os
import pickle
import signal
import subprocess
import sys
import time
import warnings

import pytest

from fdi_lib.errors import CacheWarning
from fdi_lib.reproduce import get, reproduce
from fdi_lib.reproduce.cli import main
from fdi_lib.reproduce.registry import CACHE_ENV, Reproduction, cached_results


@pytest.fixture
def spy(monkeypatch):
    """Record the jobs and the progress setting a reproduction is called with (nothing computed)."""
    import fdi_lib.montecarlo as mc

    calls = []

    def fake(self, *, seed=None, trials=None, jobs=1, **kwargs):
        calls.append({"jobs": jobs, "progress": mc._PROGRESS.get()})
        return get("zb2014-table1").func(seed=0, trials=None, jobs=1)

    monkeypatch.setattr(Reproduction, "__call__", fake)
    return calls


def test_jobs_above_the_cores_are_capped_with_a_one_line_warning(spy, capsys, monkeypatch):
    """--jobs 1000000 reached 1.6 GB (a thread and a process slot per job): now the core count."""
    import joblib

    monkeypatch.setattr(joblib, "cpu_count", lambda *a, **k: 2)
    assert main(["reproduce", "zb2014-table1", "--jobs", "1000000", "--json"]) == 0
    out, err = capsys.readouterr()
    assert spy[-1]["jobs"] == 2
    assert (
        err
        == "warning: jobs: 1000000 requested, 2 used (2 CPU cores); the results do not depend on it\n"
    )
    assert out.startswith('{"id": "zb2014-table1"')
    assert main(["reproduce", "zb2014-table1", "--jobs", "-1", "--json"]) == 0
    assert spy[-1]["jobs"] == 2 and capsys.readouterr().err == ""  # every core, no warning


def test_progress_bars_follow_a_terminal_on_standard_error(spy, monkeypatch):
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    assert main(["reproduce", "zb2014-table1"]) == 0
    monkeypatch.setattr(sys.stderr, "isatty", lambda: False, raising=False)
    assert main(["reproduce", "zb2014-table1"]) == 0
    assert [c["progress"] for c in spy] == [True, False]


def _descendants(pid: int) -> set[int]:
    """Process ids below ``pid`` (Linux /proc: every thread's children)."""
    out, todo = set(), [pid]
    while todo:
        p = todo.pop()
        for task in os.listdir(f"/proc/{p}/task") if os.path.isdir(f"/proc/{p}/task") else []:
            try:
                with open(f"/proc/{p}/task/{task}/children") as fh:
                    kids = {int(k) for k in fh.read().split()}
            except OSError:
                continue
            todo.extend(kids - out)
            out |= kids
    return out


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"  # a zombie has exited
    except OSError:
        return False


@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="reads Linux /proc")
def test_sigint_exits_130_with_one_line_and_no_worker_left():
    """Ctrl-C used to print a 40-line traceback; now 'interrupted', exit 130, workers stopped."""
    env = {k: v for k, v in os.environ.items() if k != CACHE_ENV}
    proc = subprocess.Popen(
        [sys.executable, "-m", "fdi_lib", "reproduce", "zhang2021-table1", "--jobs", "2", "--json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        deadline = time.monotonic() + 120
        workers: set[int] = set()
        while time.monotonic() < deadline and proc.poll() is None:  # until the worker pool runs
            workers = _descendants(proc.pid)
            if len(workers) >= 2:  # loky's resource tracker and a worker
                break
            time.sleep(0.1)
        assert workers and proc.poll() is None, "the run ended before its workers started"
        time.sleep(0.5)
        os.kill(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 130
    assert err == "interrupted\n" and out == ""
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and any(_alive(w) for w in workers):
        time.sleep(0.1)
    assert not any(_alive(w) for w in workers), "a worker process outlived the interrupted run"


def test_a_damaged_cache_entry_is_a_miss_with_a_warning(tmp_path, monkeypatch):
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "cache"))
    first = reproduce("zb2014-table1")
    (entry,) = (tmp_path / "cache" / "zb2014-table1").glob("*.pkl")
    for damage in (b"garbage", entry.read_bytes()[:40], pickle.dumps({"not": "a result"})):
        entry.write_bytes(damage)
        with pytest.warns(
            CacheWarning,
            match=r"FDI_RESULTS_CACHE: (cannot read|expected a result of "
            r"'zb2014-table1')",
        ):
            again = reproduce("zb2014-table1")
        assert again.headline == first.headline
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            assert reproduce("zb2014-table1").headline == first.headline  # rewritten: a clean hit
            assert cached_results()["zb2014-table1"].headline == first.headline
        entry.write_bytes(damage)
        with pytest.warns(CacheWarning, match="cannot read|expected a result"):
            assert "zb2014-table1" not in cached_results()


def test_a_cache_variable_naming_a_file_is_skipped_with_a_warning(tmp_path, monkeypatch, capsys):
    target = tmp_path / "a-file"
    target.write_text("not a folder")
    monkeypatch.setenv(CACHE_ENV, str(target))
    with pytest.warns(
        CacheWarning, match=r"FDI_RESULTS_CACHE: cannot store the result in .*a-file"
    ):
        result = reproduce("zb2014-table1")
    assert result.id == "zb2014-table1" and target.read_text() == "not a folder"
    with pytest.warns(CacheWarning, match=r"expected a directory, got the file .*a-file"):
        assert cached_results() == {}
    assert (
        main(["reproduce", "zb2014-table1", "--json"]) == 0
    )  # the CLI: one warning line, no traceback
    err = capsys.readouterr().err
    assert err.startswith("warning: FDI_RESULTS_CACHE: cannot store") and len(err.splitlines()) == 1
