"""Benchmark: the four wind-turbine methods on a long fault-free stream (issue 32, point 3).

For each method alone (:func:`fdi_lib.windturbine.stream_counts`, windows of the false-alarm study,
:func:`fdi_lib.reproduce.windturbine_streams.stream_design`), on one continuous fault-free stream of the
benchmark's scenario:

* samples per second (one core's process time, on the ``SHORT_S`` stream without the memory
  tracer, which slows every allocation), against the sensors' 100 samples per second (real time:
  ratio >= 1);
* peak memory (tracemalloc: what the detector allocates, the stream's input excluded) on a stream
  ``LONG_S`` long and on one ``SHORT_S`` long, both longer than one batch of windows (the memory
  unit, ``stream_counts``'s ``batch``): the ratio long / short must stay near 1 (constant memory),
  where a detector that held the whole record would grow with the length (ratio
  ``LONG_S / SHORT_S``).

Run: .venv/bin/python benchmarks/bench_windturbine_stream.py
"""

from __future__ import annotations

import time
import tracemalloc

import numpy as np

from _record import record
from fdi_lib import windturbine as W
from fdi_lib.reproduce.windturbine_streams import stream_design
from fdi_lib.systems import wind_turbine as wt
from fdi_lib.threads import blas_single_thread

SHORT_S = 200.0
LONG_S = 800.0
#: Memory may grow by this factor from the short stream to the long one (4x longer).
MEMORY_RATIO_GOAL = 1.2


def _rate(d: W.Design, start: int, rec: W.Records, n: int, method: str) -> float:
    y, u = rec.y[0, :n].copy(), rec.u[0, :n].copy()
    t0 = time.process_time()
    out = W.stream_counts(d, y, u, start, methods=(method,))
    return out["samples"] / (time.process_time() - t0)


def _peak(d: W.Design, start: int, rec: W.Records, n: int, method: str) -> float:
    y, u = rec.y[0, :n].copy(), rec.u[0, :n].copy()
    tracemalloc.start()
    W.stream_counts(d, y, u, start, methods=(method,))
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak


def main() -> None:
    d, start = stream_design(2009)
    seeds = np.random.SeedSequence(2009).spawn(1)
    rec = W.records(wt.simulate(seed=seeds, faults=(), duration_s=LONG_S))
    n_short, n_long = (int(round(s / d.constants.Ts)) for s in (SHORT_S, LONG_S))
    with blas_single_thread():
        for method in W.METHODS:
            # warm the caches
            W.stream_counts(d, rec.y[0, : d.N], rec.u[0, : d.N], start, methods=(method,))
            rate = _rate(d, start, rec, n_short, method)
            short = _peak(d, start, rec, n_short, method)
            long_ = _peak(d, start, rec, n_long, method)
            record(
                f"wind-turbine stream {method}: samples per second (one core)",
                rate,
                "samples/s",
                100.0,
                higher_is_better=True,
                note=f"{SHORT_S:g} s stream, without the memory tracer",
            )
            record(
                f"wind-turbine stream {method}: peak memory {LONG_S:g} s / {SHORT_S:g} s",
                long_ / short,
                "ratio",
                MEMORY_RATIO_GOAL,
                note=f"{long_ / 1e6:.1f} MB and {short / 1e6:.1f} MB; a whole-record detector: "
                f"{LONG_S / SHORT_S:g}",
            )


if __name__ == "__main__":
    main()
