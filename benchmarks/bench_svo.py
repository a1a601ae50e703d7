"""Benchmark: set-valued observers of Rosa & Silvestre (2013) on the Eclipse UAV model (n = 4).

Targets (issue 14): one update at N = 1, the construction of the step's model included, in at
most 0.5 ms for the template rule and 5 ms for the paper's exact rule (vertex images and hulls).
Reported, on this machine and its current load:

* template rule: wall time per update against the horizon N = 1, 2, 3 (healthy 10 s run), model
  construction included (the batched ZOH of :func:`eclipse_uav.svo_models`, shared per step,
  plus the step's ``SVOModel``), with the ratio to the target;
* the same N = 1 run with the vertex enumeration of the previous implementation (qhull after a
  Chebyshev-centre LP: the basis route switched off), for the speed-up ratio;
* the joint horizon form (``joint=True``) at N = 2 on the first second, for comparison;
* the four SVOs of the Architecture I bank together, against Ts = 10 ms;
* the number of facets and vertices of the template sets over the 10 s run;
* many records at once (:func:`fdi_lib.sets.svo.run_svo_many`, as the Figs 11-12 study runs
  them): CPU time per observer and sample against one observer at a time;
* the exact rule on the book's 2-D example for N = 1..6: one one-step hull per horizon level, so
  the time grows about linearly with N, not with the 2^N vertex sequences;
* the exact rule (scaled coordinates) at N = 1, 2, 3 on the first ``EXACT_STEPS`` samples: its
  sets grow at every step, so the time per step grows too;
* sets that are boxes (every state measured, as in the wind turbine's banks; ``BOX_N`` states,
  ``BATCH`` records stepped together): CPU per observer and sample of the interval route
  (``fdi_lib.sets.svo._box_route``) against the vertex route on the same records, the same sets
  (target: at least ``BOX_TARGET`` times faster).

Compare with Remark 4 (5-200 ms per step, MATLAB, Xeon 2.6 GHz, exact rule) like for like: the
exact rule's figures, not the template's.

Run: .venv/bin/python benchmarks/bench_svo.py
"""

from __future__ import annotations

import time

import numpy as np

from _record import record

from fdi_lib.reproduce.rosa2013 import UAV_X0, simulate_toy, toy_model, toy_prior
from fdi_lib.sets import Polytope, polytope, svo
from fdi_lib.sets.svo import ModelSequence, run_svo, run_svo_many
from fdi_lib.systems import eclipse_uav as uav
from fdi_lib.threads import single_threaded_blas

TEMPLATE_TARGET_MS = 0.5
EXACT_TARGET_MS = 5.0
EXACT_STEPS = 2
BATCH = 100  # records stepped together (the Figs 11-12 study has 100 per reading)
ONE_BY_ONE = 10  # of which run one at a time for the ratio
BOX_N = 5  # states of the box benchmark (the wind turbine's drive train)
BOX_STEPS = 400
BOX_TARGET = 2.0


def _models(run, kind):
    """The per-step models and the per-step share of their batched construction (s)."""
    t0 = time.perf_counter()
    models = uav.svo_models(run, kind)
    return models, (time.perf_counter() - t0) / len(run.u)


@single_threaded_blas
def main() -> None:
    max_bases = polytope._MAX_BASES
    run = uav.simulate("none", "step", rng=np.random.default_rng(0), duration=10.0)
    print(f"UAV healthy run: {len(run.u)} samples (10 s at Ts = 10 ms), eta per {run.eta_unit}")

    print("\n== one SVO (nominal), template rule, time per update incl. model construction")
    counts = None
    for N in (1, 2, 3):
        models, build = _models(run, "nominal")
        res = run_svo(models, run.u, run.y, UAV_X0, N=N)
        st = (res.step_time + build) * 1e3
        med = float(np.median(st))
        print(
            f"N = {N}: median {med:.3f} ms  p90 {np.percentile(st, 90):.3f} ms  max {st.max():.2f} ms  "
            f"(model share {build * 1e3:.3f} ms)  ratio to the {TEMPLATE_TARGET_MS} ms target "
            f"{med / TEMPLATE_TARGET_MS:.2f}  alarm: {res.empty_at}"
        )
        counts = counts or res

    print(
        "\n== reference: the same N = 1 run with vertices by qhull (basis route off, as before issue 14's"
        " speed-up)"
    )
    models, build = _models(run, "nominal")
    fast = run_svo(models, run.u, run.y, UAV_X0)
    polytope._MAX_BASES = 0
    polytope._bases.cache_clear()
    try:
        ref = run_svo(models, run.u, run.y, UAV_X0)
    finally:
        polytope._MAX_BASES = max_bases
        polytope._bases.cache_clear()
    med_fast, med_ref = (float(np.median(r.step_time + build)) * 1e3 for r in (fast, ref))
    print(
        f"qhull route: median {med_ref:.3f} ms, bases: {med_fast:.3f} ms per update "
        f"(speed-up x{med_ref / med_fast:.1f}); same alarm: {fast.empty_at == ref.empty_at}"
    )

    print("\n== joint horizon form (eq. 3, shared disturbances), N = 2, first 1 s")
    models, build = _models(run, "nominal")
    res = run_svo(models, run.u[:100], run.y[:101], UAV_X0, N=2, joint=True)
    print(f"N = 2 joint: median {np.median(res.step_time + build) * 1e3:.2f} ms per update")

    print("\n== complexity over the 10 s run (template, N = 1)")
    for name, arr in (("facets", counts.n_facets), ("vertices", counts.n_vertices)):
        q = [int(arr[int(i)]) for i in np.linspace(0, len(arr) - 1, 6)]
        print(f"{name:>8}: min {arr.min()}  max {arr.max()}  at t = 0, 2, 4, 6, 8, 10 s: {q}")

    print("\n== Architecture I bank (4 SVOs) per sample, template, N = 1")
    total = np.zeros(len(run.u))
    for kind in ("nominal",) + uav.FAULTS:
        models, build = _models(run, kind)
        res = run_svo(models, run.u, run.y, UAV_X0)
        total += res.step_time + build
        print(f"{kind:>9}: median {np.median(res.step_time + build) * 1e3:.3f} ms")
    print(
        f"     bank: median {np.median(total) * 1e3:.3f} ms per sample, "
        f"{np.mean(total * 1e3 > 10.0) * 100:.1f} % of samples above Ts = 10 ms"
    )

    print(f"\n== many records at once (TemplateBatch), nominal SVOs of {BATCH} healthy 6 s records")
    runs = uav.simulate_many(
        [("none", "step")] * BATCH,
        [np.random.default_rng(s) for s in np.random.SeedSequence(1).spawn(BATCH)],
    )
    seqs = [uav.svo_models(r, "nominal") for r in runs]
    u, y = np.stack([r.u for r in runs]), np.stack([r.y for r in runs])
    c0 = time.process_time()
    many = run_svo_many(seqs, u, y, UAV_X0)
    c_many = (time.process_time() - c0) / (BATCH * len(runs[0].u))
    c0 = time.process_time()
    one = [run_svo(m, r.u, r.y, UAV_X0) for m, r in zip(seqs[:ONE_BY_ONE], runs[:ONE_BY_ONE])]
    c_one = (time.process_time() - c0) / (ONE_BY_ONE * len(runs[0].u))
    same = [o.empty_at for o in one] == list(many.empty_at[:ONE_BY_ONE])
    print(
        f"CPU per observer and sample: batch {c_many * 1e6:.1f} us, one at a time {c_one * 1e6:.1f} us "
        f"(first {ONE_BY_ONE} records; x{c_one / c_many:.1f}); same alarms: {same}"
    )

    print(
        "\n== exact rule, 2-D example of the book, horizon N: one-step hulls per level (recursion)"
    )
    toy = toy_model()
    x, u1, y1 = simulate_toy(toy, rng=np.random.default_rng(0), steps=25)
    for N in range(1, 7):
        c0 = time.process_time()
        res = run_svo(toy, u1, y1, toy_prior(), N=N, method="exact")
        ms = (time.process_time() - c0) * 1e3 / len(u1)
        print(
            f"N = {N}: {ms:.2f} ms CPU per update ({2**N} vertex sequences for the oldest set), "
            f"max facets {res.n_facets.max()}, alarm: {res.empty_at}"
        )

    print(f"\n== exact rule (vertex images + hulls, scaled), first {EXACT_STEPS} updates")
    short = slice(0, EXACT_STEPS)
    for N in (1, 2, 3):
        models, build = _models(run, "nominal")
        res = run_svo(
            models,
            run.u[short],
            run.y[: EXACT_STEPS + 1],
            UAV_X0,
            N=N,
            method="exact",
            scale=uav.svo_scale(),
        )
        st = (res.step_time + build) * 1e3
        print(
            f"N = {N}: per update {', '.join(f'{v:.1f}' for v in st)} ms "
            f"(target {EXACT_TARGET_MS} ms), vertices {res.n_vertices.tolist()}"
        )

    boxes()


def _box_records(rng: np.random.Generator) -> tuple[list[ModelSequence], np.ndarray, np.ndarray]:
    """``BATCH`` random stable ``BOX_N``-state systems, every state measured (the template's sets are
    boxes), one uncertain direction of ``A``, and a fault-free record of each."""
    n, T = BOX_N, BOX_STEPS
    seqs, us, ys = [], [], []
    for _ in range(BATCH):
        A = rng.standard_normal((n, n))
        A *= 0.9 / max(abs(np.linalg.eigvals(A)))
        A1, B, L = 0.02 * rng.standard_normal((n, n)), rng.standard_normal((n, 1)), 0.05 * np.eye(n)
        x, u = np.zeros(n), rng.uniform(-1, 1, (T, 1))
        y = np.empty((T + 1, n))
        for k in range(T + 1):
            y[k] = x + 0.1 * rng.uniform(-1, 1, n)
            if k < T:
                x = (A + rng.uniform(-1, 1) * A1) @ x + B @ u[k] + L @ rng.uniform(-1, 1, n)
        rep = lambda a: np.repeat(a[None], T, axis=0)  # noqa: E731
        seqs.append(
            ModelSequence(
                A=rep(A), B=rep(B), C=np.eye(n), L=L, noise=np.full(n, 0.1), A_unc=rep(A1[None])
            )
        )
        us.append(u)
        ys.append(y)
    return seqs, np.stack(us), np.stack(ys)


@single_threaded_blas
def boxes() -> None:
    print(f"\n== sets that are boxes: {BATCH} records of {BOX_N} measured states, interval route")
    seqs, u, y = _box_records(np.random.default_rng(3))
    X0 = Polytope.box(-np.ones(BOX_N), np.ones(BOX_N))
    run_svo_many(seqs[:2], u[:2, :5], y[:2, :6], X0)  # compiled code loaded
    route = svo._box_route
    cpu, runs = {}, {}
    for name, table in (("vertices", lambda b: svo._NO_BOX), ("interval", route)):
        svo._box_route = table
        try:
            c0 = time.process_time()
            runs[name] = run_svo_many(seqs, u, y, X0, bounds=False)
            cpu[name] = (time.process_time() - c0) / (BATCH * BOX_STEPS)
        finally:
            svo._box_route = route
    same = runs["vertices"].empty_at == runs["interval"].empty_at
    record(
        f"template SVOs on boxes ({BOX_N} states), interval route against every vertex",
        cpu["vertices"] / cpu["interval"],
        "x",
        BOX_TARGET,
        higher_is_better=True,
        baseline="the vertex route on the same records",
        speedup=cpu["vertices"] / cpu["interval"],
        note=f"CPU per observer and sample {cpu['interval'] * 1e6:.2f} us against "
        f"{cpu['vertices'] * 1e6:.2f} us; same sets emptied: {same}",
    )


if __name__ == "__main__":
    main()
