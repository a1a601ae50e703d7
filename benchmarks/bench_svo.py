"""Benchmark: set-valued observer of Rosa & Silvestre (2013) on the Eclipse UAV model (n = 4).

Target (issue 5): one SVO update at N = 1 in at most 2 ms, so that the four SVOs of
Architecture I fit in the 10 ms sampling period. Reported, on this machine and its current load:

* wall time per update against the horizon N = 1, 2, 3 (template rule, healthy 10 s run,
  model construction excluded), with the ratio to N = 1 and to the 2 ms target;
* the same for the four SVOs of the Architecture I bank together, against Ts = 10 ms;
* the number of facets and vertices of the sets over the 10 s run (bounded by the template:
  |D| + 2 n_y inequalities), for N = 1;
* the exact rule (paper's construction, vertex images + hulls) on the 2-D example, whose
  facet count is not bounded by construction, for comparison.

Run: .venv/bin/python benchmarks/bench_svo.py
"""

from __future__ import annotations

import time

import numpy as np

from fdi_lib.reproduce.rosa2013 import UAV_X0, simulate_toy, toy_model, toy_prior
from fdi_lib.sets.svo import run_svo, single_threaded_blas
from fdi_lib.systems import eclipse_uav as uav

TARGET_MS = 2.0


@single_threaded_blas
def main() -> None:
    run = uav.simulate("none", "step", rng=np.random.default_rng(0), duration=10.0)
    print(f"UAV healthy run: {len(run.u)} samples (10 s at Ts = 10 ms)")
    models = {kind: [uav.svo_models(run, kind)(k) for k in range(len(run.u))]
              for kind in ("nominal",) + uav.FAULTS}

    print("\n== one SVO (nominal), template rule, time per update")
    base = None
    for N in (1, 2, 3):
        res = run_svo(models["nominal"], run.u, run.y, UAV_X0, N=N)
        st = res.step_time * 1e3
        med = float(np.median(st))
        base = base or med
        print(f"N = {N}: median {med:.3f} ms  p90 {np.percentile(st, 90):.3f} ms  max {st.max():.2f} ms  "
              f"ratio to N=1 {med / base:.2f}  ratio to the {TARGET_MS} ms target {med / TARGET_MS:.2f}  "
              f"alarm: {res.empty_at}")
        if N == 1:
            counts = res

    print("\n== complexity over the 10 s run (N = 1)")
    for name, arr in (("facets", counts.n_facets), ("vertices", counts.n_vertices)):
        q = [int(arr[int(i)]) for i in np.linspace(0, len(arr) - 1, 6)]
        print(f"{name:>8}: min {arr.min()}  max {arr.max()}  at t = 0, 2, 4, 6, 8, 10 s: {q}")

    print("\n== Architecture I bank (4 SVOs) per sample, N = 1")
    total = np.zeros(len(run.u))
    for kind in ("nominal",) + uav.FAULTS:
        res = run_svo(models[kind], run.u, run.y, UAV_X0)
        total += res.step_time
        print(f"{kind:>9}: median {np.median(res.step_time) * 1e3:.3f} ms")
    print(f"     bank: median {np.median(total) * 1e3:.3f} ms per sample, "
          f"{np.mean(total * 1e3 > 10.0) * 100:.1f} % of samples above Ts = 10 ms")

    print("\n== exact rule (vertex images + hulls) on the 2-D example, 25 samples")
    model = toy_model()
    x, u, y = simulate_toy(model, rng=np.random.default_rng(0), steps=25)
    for N in (1, 2, 3):
        t0 = time.perf_counter()
        res = run_svo(model, u, y, toy_prior(), N=N, method="exact")
        el = (time.perf_counter() - t0) / 25 * 1e3
        print(f"N = {N}: {el:.2f} ms per update, facets max {res.n_facets.max()}, vertices max {res.n_vertices.max()}")


if __name__ == "__main__":
    main()
