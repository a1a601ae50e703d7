"""Benchmark: windowed GLR with a fault profile per realisation, one pass against one call per realisation.

The Basseville-Zhang test of a pitch actuator's stiffness in the wind-turbine chapter
(:func:`fdi_lib.windturbine.run_bz`) has a data-dependent profile ``Psi~_k = g (beta_r,k - ybar_k)``:
each realisation its own. Before, it built one :func:`~fdi_lib.models.step_family` and ran one
:func:`~fdi_lib.glr.glr_window` per realisation (the baseline, timed in this run); now one family with
a leading batch axis and one call for the whole chunk. Same sizes as the chapter's blade subsystem:
a 2-state actuator at ``Ts = 0.01`` s, 2 outputs, ``m = 1``, ``N = 1700``, ``w = 50``, 27
realisations (a chunk of the scoreboard: 3 seeds times 9 faults). Target: at least 1.5x less CPU
(the wind-turbine chapter's execution budget, issue 24). The two agree to 1e-10 (asserted).

Run: .venv/bin/python benchmarks/bench_glr_batched.py
"""

from __future__ import annotations

import os
import time

import numpy as np
from _record import record

from fdi_lib.filters import kalman_filter, kalman_gains
from fdi_lib.glr import glr_window
from fdi_lib.models import ltv_model, step_family
from fdi_lib.simulate import simulate

N, W, B, TS, WN, ZETA = 1700, 50, 27, 0.01, 11.11, 0.6


def cpu(fn, repeat=3):
    """Best CPU seconds of this process over ``repeat`` runs of ``fn`` (the machine is shared)."""
    times = []
    for _ in range(repeat):
        c0 = time.process_time()
        fn()
        times.append(time.process_time() - c0)
    return min(times)


def main() -> None:
    F = np.array([[1.0, TS], [-(WN**2) * TS, 1.0 - 2 * ZETA * WN * TS]])
    model = ltv_model(F=F, H=np.eye(2), Q=1e-6 * np.eye(2), R=np.diag([0.2, 0.2]) ** 2, n_steps=N)
    gains = kalman_gains(model)
    rng = np.random.default_rng(0)
    eps = kalman_filter(model, simulate(model, rng=rng, size=B).y, gains=gains).innovations
    drive = np.cumsum(rng.standard_normal((B, N)), axis=1) * 0.01  # a reference per realisation
    col = np.array([0.0, WN**2 * TS])
    Psi = col[None, None, :, None] * drive[:, :, None, None]  # (B, N, n, m)

    def loop():
        return np.stack(
            [
                glr_window(eps[b], model, gains, step_family(model, Psi=Psi[b]), W).statistic
                for b in range(B)
            ]
        )

    def batched():
        return glr_window(eps, model, gains, step_family(model, Psi=Psi), W).statistic

    ref, new = loop(), batched()
    assert np.allclose(new, ref, rtol=1e-10, atol=0, equal_nan=True), (
        "batched and per-realisation disagree"
    )
    c_loop, c_batch = cpu(loop), cpu(batched)
    print(
        f"windowed GLR with per-realisation profiles, N = {N}, w = {W}, {B} realisations; "
        f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} (CPU times are the figures)"
    )
    print(f"  one glr_window per realisation : {c_loop:6.2f} s CPU")
    print(f"  one batched glr_window         : {c_batch:6.2f} s CPU")
    record(
        "windowed GLR, per-realisation profiles in one pass (27 realisations, N = 1700, w = 50)",
        c_loop / c_batch,
        "x",
        1.5,
        higher_is_better=True,
        baseline="one glr_window per realisation (CPU time)",
        speedup=c_loop / c_batch,
        note="CPU time; issue 24, the wind-turbine chapter's budget",
    )


if __name__ == "__main__":
    main()
