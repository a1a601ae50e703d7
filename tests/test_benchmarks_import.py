"""The benchmarks' scripts (``make benchmarks``, CI) load against the library as it is now: their
module-level code (imports, the private caches they empty, the widgets and workloads they name)
runs here, so a renamed or removed name fails the tests instead of stopping ``make benchmarks``
(a benchmark named ``fdi_lib.widgets.bz._rls_gains`` after it had moved)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
SCRIPTS = sorted(p for p in BENCHMARKS.glob("*.py") if not p.name.startswith("_"))


def _load(path: Path):
    sys.path.insert(0, str(BENCHMARKS))  # their shared helper, benchmarks/_record.py
    try:
        spec = importlib.util.spec_from_file_location(f"_bench_{path.stem}", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)  # the module's code, not its __main__ block
        return module
    finally:
        sys.path.remove(str(BENCHMARKS))


def test_every_benchmark_script_is_found():
    assert {p.name for p in SCRIPTS} >= {"bench_widgets.py", "bench_sparse.py", "bench_svo.py"}


@pytest.mark.parametrize("path", SCRIPTS, ids=lambda p: p.name)
def test_a_benchmark_script_loads(path):
    _load(path)


def test_the_widget_benchmark_empties_caches_that_exist():
    module = _load(BENCHMARKS / "bench_widgets.py")
    assert module.CACHE_CLEARS and all(callable(c) for c in module.CACHE_CLEARS)
    module.reset_caches()
