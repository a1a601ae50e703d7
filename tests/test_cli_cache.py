"""The results cache serves only what was asked (issue 36.5): a key that covers every setting, a
stored key compared on reading, a wrong kind of file at an entry's path, concurrent writers."""

from __future__ import annotations

import multiprocessing
import shutil
import threading
import warnings

import numpy as np
import pytest

import fdi_lib.reproduce.registry as registry
from fdi_lib.errors import CacheWarning
from fdi_lib.reproduce import reproduce
from fdi_lib.reproduce.registry import CACHE_ENV, Reproduction, ReproductionResult, cached_results

FAKE = "test-cache-probe"


@pytest.fixture
def calls(monkeypatch, tmp_path):
    """A registered Monte Carlo reproduction that records its calls and returns its settings (no
    computation), with the cache in ``tmp_path / "cache"``."""
    made = []

    def func(*, seed, trials, jobs, x=None):
        made.append((seed, trials, x))
        return ReproductionResult(
            FAKE, {"trials": trials, "x": repr(x)}, settings={"trials": trials}
        )

    rep = Reproduction(
        FAKE,
        paper="none",
        title="cache probe",
        func=func,
        plot=None,
        default_trials=10,
        default_seed=0,
    )
    monkeypatch.setitem(registry._REGISTRY, FAKE, rep)
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "cache"))
    return made


def _entries(tmp_path):
    return sorted((tmp_path / "cache" / FAKE).glob("*.pkl"))


def test_an_entry_under_another_key_is_a_miss_with_a_warning(calls, tmp_path):
    """An entry of 10 trials found under the key of 20 trials was returned as the 20-trial
    result."""
    reproduce(FAKE, trials=10)
    (ten,) = _entries(tmp_path)
    reproduce(FAKE, trials=20)
    (twenty,) = set(_entries(tmp_path)) - {ten}
    shutil.copyfile(ten, twenty)  # a copied or renamed file
    with pytest.warns(
        CacheWarning, match=r"stored for other settings \(trials differ\); computing"
    ):
        got = reproduce(FAKE, trials=20)
    assert got.headline["trials"] == 20 and calls[-1] == (0, 20, None)
    assert len(calls) == 3
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert reproduce(FAKE, trials=20).headline["trials"] == 20  # rewritten: a clean hit
    assert len(calls) == 3


def test_the_key_tells_apart_values_that_repr_confuses(calls):
    """``repr`` elides the middle of a large array: two runs with different arrays shared an
    entry. Types are kept apart (1, 1.0, True, "1"); equal values still hit."""
    a = np.arange(5000.0)
    b = a.copy()
    b[2500] = -1.0  # differs only where repr prints "..."
    assert repr(a) == repr(b)
    for x in (a, b, 1, 1.0, True, "1", [1], (1,), {"k": 1}, {"k": 1.0}):
        reproduce(FAKE, x=x)
    assert len(calls) == 10
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for x in (a.copy(), b.copy(), 1, 1.0, True, "1", [1], (1,), {"k": 1}, {"k": 1.0}):
            reproduce(FAKE, x=x)
    assert len(calls) == 10
    reproduce(FAKE, x=a.astype(np.float32))  # same values, another dtype: another result
    reproduce(FAKE, x=a.reshape(50, 100))  # another shape
    assert len(calls) == 12


def test_an_argument_without_an_exact_description_is_not_cached(calls, tmp_path):
    reproduce(FAKE, x=object())
    reproduce(FAKE, x=object())
    assert len(calls) == 2 and _entries(tmp_path) == []


def test_another_environment_is_a_miss(calls, monkeypatch):
    """The key covers the numerical libraries' versions: a result of another numpy is not served."""
    reproduce(FAKE)
    env = registry._environment()
    other = {**env, "libraries": {**env["libraries"], "numpy": "0.0.1"}}
    monkeypatch.setattr(registry, "_environment", lambda: other)
    assert cached_results() == {}
    reproduce(FAKE)
    assert len(calls) == 2
    assert FAKE in cached_results()


def test_a_folder_at_an_entrys_path_is_a_miss_with_a_warning(calls, tmp_path):
    """A folder where an entry belongs made reproduce() raise IsADirectoryError."""
    reproduce(FAKE)
    (entry,) = _entries(tmp_path)
    entry.unlink()
    entry.mkdir()
    with pytest.warns(CacheWarning) as record:
        got = reproduce(FAKE)
    messages = [str(w.message) for w in record]
    assert any("cannot read the cached result" in m and "got a folder" in m for m in messages), (
        messages
    )
    assert any("cannot store the result in" in m for m in messages), messages
    assert got.headline["trials"] == 10 and len(calls) == 2 and entry.is_dir()
    with pytest.warns(CacheWarning, match="got a folder"):
        assert FAKE not in cached_results()


def _write_many(entry, key, result, n):
    for _ in range(n):
        registry._cache_write(entry, key, result)


def _entry_and_result():
    entry, key = registry._cache_entry(FAKE, 0, 10, {})
    return entry, key, ReproductionResult(FAKE, {"trials": 10}, settings={"trials": 10})


def test_threads_writing_one_entry_never_collide(calls, tmp_path):
    """Threads of one process shared a temporary file name: 132 FileNotFoundErrors in 800 writes."""
    entry, key, result = _entry_and_result()
    errors = []

    def writer():
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                _write_many(entry, key, result, 50)
        except BaseException as exc:  # noqa: BLE001 (collected and asserted below)
            errors.append(exc)

    threads = [threading.Thread(target=writer) for _ in range(16)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    assert list(entry.parent.iterdir()) == [entry], "a temporary file was left behind"
    assert registry._cache_read(entry, key).headline == {"trials": 10}


@pytest.mark.skipif("fork" not in multiprocessing.get_all_start_methods(), reason="forks writers")
def test_processes_writing_one_entry_never_collide_and_readers_see_whole_entries(calls, tmp_path):
    entry, key, result = _entry_and_result()
    registry._cache_write(entry, key, result)
    ctx = multiprocessing.get_context("fork")
    procs = [ctx.Process(target=_write_many, args=(entry, key, result, 100)) for _ in range(4)]
    for p in procs:
        p.start()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a half-written entry would be a CacheWarning
        reads = 0
        while any(p.is_alive() for p in procs) or reads < 50:
            assert registry._cache_read(entry, key).headline == {"trials": 10}
            reads += 1
    for p in procs:
        p.join()
    assert [p.exitcode for p in procs] == [0] * 4
    assert list(entry.parent.iterdir()) == [entry], "a temporary file was left behind"
