"""Monte Carlo engine: seed streams, chunking, job-count independence, confidence intervals."""

import functools
import re

import numpy as np
import pytest
from statsmodels.stats.proportion import proportion_confint

from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.models import ltv_model
from fdi_lib.montecarlo import (
    binomial_ci,
    default_chunk_size,
    draw_noise_batch,
    run_monte_carlo,
    run_monte_carlo_many,
    trial_seeds,
)
from fdi_lib.simulate import draw_noise


def _gaussian_chunk(seeds, *, dim):
    """Per-realisation draws (each from its own stream) plus a batch-level reduction."""
    x = np.stack([np.random.default_rng(s).standard_normal(dim) for s in seeds])
    return {"x": x, "norm": np.sqrt(np.sum(x**2, axis=1))}


def _slow_worker_chunk(seeds, *, parent):
    """A chunk whose result carries where it ran; workers (not the calling process) are slow."""
    import os
    import time

    if os.getpid() != parent:
        time.sleep(0.3)
    return {
        "x": np.array([np.random.default_rng(s).standard_normal() for s in seeds]),
        "here": np.full(len(seeds), os.getpid() == parent),
    }


def _bad_chunk(seeds):
    return {"x": np.zeros(len(seeds) + 1)}


def test_trial_seeds_are_reproducible_and_independent():
    a, b = trial_seeds(5, 4), trial_seeds(5, 4)
    draws_a = [np.random.default_rng(s).integers(1 << 62) for s in a]
    draws_b = [np.random.default_rng(s).integers(1 << 62) for s in b]
    assert draws_a == draws_b and len(set(draws_a)) == 4
    with pytest.raises(ModelError, match="n_trials: expected a positive integer"):
        trial_seeds(0, 0)


@pytest.mark.parametrize("chunk_size", [None, 7])
def test_results_do_not_depend_on_jobs_or_chunks(chunk_size):
    fn = functools.partial(_gaussian_chunk, dim=3)
    ref = run_monte_carlo(fn, 23, seed=11, jobs=1, chunk_size=5)
    one = run_monte_carlo(fn, 23, seed=11, jobs=1, chunk_size=chunk_size)
    two = run_monte_carlo(fn, 23, seed=11, jobs=2, chunk_size=chunk_size)
    for key in ref:
        np.testing.assert_array_equal(one[key], ref[key])
        np.testing.assert_array_equal(two[key], ref[key])
    three = run_monte_carlo(fn, 23, seed=11, jobs=3, chunk_size=chunk_size)
    for key in ref:
        np.testing.assert_array_equal(three[key], ref[key])
    # A realisation's draws depend only on (seed, i): the first 10 of 23 are those of 10.
    short = run_monte_carlo(fn, 10, seed=11)
    np.testing.assert_array_equal(short["x"], ref["x"][:10])


@pytest.mark.parametrize("jobs", [1, 2])
def test_many_chunk_functions_in_one_pool_give_each_run(jobs):
    fns = [functools.partial(_gaussian_chunk, dim=d) for d in (2, 3, 1)]
    many = run_monte_carlo_many(fns, 23, seed=4, jobs=jobs, chunk_size=5)
    assert len(many) == 3
    for fn, res in zip(fns, many):
        ref = run_monte_carlo(fn, 23, seed=4, jobs=1, chunk_size=5)
        assert res.keys() == ref.keys()
        for key in ref:
            np.testing.assert_array_equal(res[key], ref[key])
    # common random numbers: the first two components of dim 3 are the draws of dim 2
    np.testing.assert_array_equal(many[1]["x"][:, :2], many[0]["x"])
    with pytest.raises(ModelError, match="chunk_fns: expected at least one chunk function"):
        run_monte_carlo_many([], 4, seed=0)


def test_default_chunk_size_is_job_independent():
    assert default_chunk_size(1000) == 250
    assert default_chunk_size(40) == 10
    assert default_chunk_size(1) == 1


def test_bad_arguments_and_chunk_output():
    fn = functools.partial(_gaussian_chunk, dim=2)
    with pytest.raises(ModelError, match="jobs: expected a non-zero integer"):
        run_monte_carlo(fn, 4, seed=0, jobs=0)
    with pytest.raises(ModelError, match="chunk_size: expected a positive integer"):
        run_monte_carlo(fn, 4, seed=0, chunk_size=0)
    with pytest.raises(ShapeError, match="one row per realisation"):
        run_monte_carlo(_bad_chunk, 4, seed=0)


def test_draw_noise_batch_matches_individual_draws():
    m = ltv_model(
        F=[[0.5, 0.1], [0.0, 0.9]], H=[[1.0, 0.0]], Q=np.diag([1.0, 0.0]), R=2.0, n_steps=12
    )
    seeds = trial_seeds(3, 4)
    batch = draw_noise_batch(m, seeds)
    for i, s in enumerate(seeds):
        one = draw_noise(m, np.random.default_rng(s))
        np.testing.assert_array_equal(batch.w[i], one.w)
        np.testing.assert_array_equal(batch.v[i], one.v)
        np.testing.assert_array_equal(batch.x0[i], one.x0)


@pytest.mark.parametrize("k, n", [(0, 10), (7, 2000), (17, 1000), (1000, 1000), (3, 7)])
def test_binomial_ci_against_statsmodels(k, n):
    lo, hi = binomial_ci(k, n)
    lo2, hi2 = proportion_confint(k, n, alpha=0.05, method="beta")  # Clopper-Pearson
    assert lo == pytest.approx(lo2, abs=1e-9) and hi == pytest.approx(hi2, abs=1e-9)
    with pytest.raises(ModelError, match="successes, trials"):
        binomial_ci(5, 3)


@pytest.mark.parametrize("n, p", [(200, 0.01), (50, 0.3), (30, 0.9)])
def test_binomial_ci_coverage(n, p):
    """Clopper-Pearson is conservative: its exact coverage (summed over the binomial law, no
    sampling) is at least the 95 % it claims."""
    import scipy.stats

    k = np.arange(n + 1)
    covers = np.array([lo <= p <= hi for lo, hi in (binomial_ci(int(j), n) for j in k)])
    assert float(np.sum(scipy.stats.binom.pmf(k, n, p)[covers])) >= 0.95


def test_calling_process_shares_the_work_and_results_keep_their_order():
    """Chunks run in the calling process and in workers, every result lands at its place."""
    import os

    fn = functools.partial(_slow_worker_chunk, parent=os.getpid())
    ref = run_monte_carlo(fn, 40, seed=3, jobs=1, chunk_size=4)
    assert ref["here"].all()
    for _ in range(2):  # cold workers (start-up), then warm ones
        two = run_monte_carlo(fn, 40, seed=3, jobs=2, chunk_size=4)
        np.testing.assert_array_equal(two["x"], ref["x"])
        assert two["here"][:4].all()  # the calling process takes the first chunk itself


def test_single_threaded_blas_limits_every_blas_and_restores_it(monkeypatch):
    from threadpoolctl import threadpool_info, threadpool_limits

    # an environment that does not start the BLAS on one thread (make's does: nothing to limit,
    # tests/test_threads.py)
    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)

    from fdi_lib.threads import blas_single_thread, single_threaded_blas

    def blas_threads():
        return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]

    with threadpool_limits(limits=2, user_api="blas"):  # a known state to restore
        before = blas_threads()
        assert before
        with blas_single_thread():
            assert blas_threads() == [1] * len(before)
        assert blas_threads() == before
        assert single_threaded_blas(blas_threads)() == [1] * len(before)
        assert blas_threads() == before


# ----------------------------------------------------------------------------- edges (issue 21)
def _counting_chunk(seeds, *, calls, width=1):
    calls.append(len(seeds))
    return {"x": np.stack([np.random.default_rng(s).standard_normal(width) for s in seeds])}


def test_chunk_seeds_made_on_demand_are_the_spawned_ones():
    """The engine makes each chunk's seeds when it runs it; they are SeedSequence.spawn's children."""
    from fdi_lib.montecarlo import _spawned

    root = np.random.SeedSequence(7)
    ref = np.random.SeedSequence(7).spawn(12)
    got = _spawned(root, 5, 9)
    assert [s.spawn_key for s in got] == [s.spawn_key for s in ref[5:9]]
    for a, b in zip(got, ref[5:9]):
        np.testing.assert_array_equal(a.generate_state(4), b.generate_state(4))


def test_jobs_are_capped_at_cores_and_chunks_with_a_warning(monkeypatch):
    """jobs=1000 on 8 trials started 65 worker processes: now min(jobs, cores, chunks)."""
    import joblib

    import fdi_lib.montecarlo as mc
    from fdi_lib.errors import JobsCappedWarning

    monkeypatch.setattr(joblib, "cpu_count", lambda *a, **k: 2)
    with pytest.warns(JobsCappedWarning, match=r"jobs: 1000 requested, 2 used \(2 CPU cores\)"):
        assert mc.effective_jobs(1000, 4) == 2
    with pytest.warns(JobsCappedWarning, match=r"jobs: 2 requested, 1 used \(1 chunk of work\)"):
        assert mc.effective_jobs(2, 1) == 1
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert (
            mc.effective_jobs(-1, 8) == 2 and mc.effective_jobs(-1, 1) == 1
        )  # "all cores": no warning
        assert mc.effective_jobs(1, 8) == 1 and mc.effective_jobs(2) == 2
    # the engine starts the capped number of processes, and the results are those of one job
    monkeypatch.setattr(joblib, "cpu_count", lambda *a, **k: 64)
    used = []
    real = mc._run_chunks
    monkeypatch.setattr(
        mc,
        "_run_chunks",
        lambda task, n, first, n_workers, done: (
            used.append(n_workers) or real(task, n, first, 1, done)
        ),
    )
    fn = functools.partial(_gaussian_chunk, dim=2)
    with pytest.warns(JobsCappedWarning, match=r"1000 requested, 4 used \(4 chunks of work\)"):
        out = run_monte_carlo(fn, 8, seed=2, jobs=1000)
    assert used == [4]
    np.testing.assert_array_equal(out["x"], run_monte_carlo(fn, 8, seed=2, jobs=1)["x"])


def test_a_share_of_the_cores_cuts_jobs_silently_and_bad_shares_are_refused(monkeypatch):
    """$FDI_CORES (the share of a chapter executed beside others, tools/execute_book.py) is the
    machine's size for effective_jobs, without a warning; a request above the machine still warns;
    a share that is not a positive integer is a typed error naming the variable."""
    import warnings

    import joblib

    import fdi_lib.montecarlo as mc
    from fdi_lib.errors import JobsCappedWarning

    monkeypatch.setattr(joblib, "cpu_count", lambda *a, **k: 4)
    monkeypatch.setenv(mc.CORES_ENV, "1")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert mc.effective_jobs(2) == 1 and mc.effective_jobs(4, 8) == 1
        assert mc.effective_jobs(-1) == 1
    monkeypatch.setenv(mc.CORES_ENV, "3")
    with pytest.warns(JobsCappedWarning, match=r"jobs: 6 requested, 3 used \(4 CPU cores\)"):
        assert mc.effective_jobs(6) == 3
    with pytest.warns(JobsCappedWarning, match=r"jobs: 3 requested, 2 used \(2 chunks of work\)"):
        assert mc.effective_jobs(3, 2) == 2
    monkeypatch.setenv(mc.CORES_ENV, "")
    assert mc.effective_jobs(-1) == 4  # empty: unset
    for bad in ("0", "-2", "two", "1.5"):
        monkeypatch.setenv(mc.CORES_ENV, bad)
        with pytest.raises(
            ModelError,
            match=rf"\$FDI_CORES: expected a positive integer "
            rf".*got '{re.escape(bad)}'",
        ):
            mc.effective_jobs(2)


def test_a_run_too_large_for_memory_is_refused_after_one_chunk(monkeypatch):
    import fdi_lib.montecarlo as mc
    from fdi_lib.errors import ResourceError

    calls = []
    fn = functools.partial(_counting_chunk, calls=calls, width=50)  # 400 B per realisation
    monkeypatch.setattr(mc, "available_memory", lambda: 1_000_000)
    with pytest.raises(
        ResourceError,
        match=r"n_trials: 2000 realisations x 1 chunk function\(s\) at 400 B "
        r"each \(measured on the first chunk\) would need about 1.6 MB of "
        r"memory; 1 MB is available",
    ):
        run_monte_carlo(fn, 2000, seed=0, chunk_size=100)
    assert calls == [100]  # only the probe chunk ran
    calls.clear()
    assert run_monte_carlo(fn, 1000, seed=0, chunk_size=100)["x"].shape == (
        1000,
        50,
    )  # 800 kB: runs
    assert sum(calls) == 1000


def test_a_trillion_trials_are_refused_at_once():
    """10^12 realisations used to spawn 10^12 seed sequences first (memory growing silently)."""
    from fdi_lib.errors import ResourceError

    calls = []
    with pytest.raises(
        ResourceError,
        match=r"n_trials: 1000000000000 realisations .* would need about "
        r"16 TB of memory",
    ):
        run_monte_carlo(functools.partial(_counting_chunk, calls=calls), 10**12, seed=0)
    assert calls == [250]
    with pytest.raises(
        ResourceError, match=r"n_trials: 1000000000000 seed sequences would need about 470 TB"
    ):
        trial_seeds(0, 10**12)


def test_progress_bar_on_standard_error(capsys):
    """progress=True, or progress_bars() around a run, draws a tqdm bar on standard error once a
    run lasts more than a second; nothing on standard output."""
    import time

    from fdi_lib.montecarlo import progress_bars

    def slow(seeds):
        time.sleep(0.3)
        return {"x": np.zeros(len(seeds))}

    run_monte_carlo(slow, 5, seed=0, chunk_size=1, progress=True, description="toy run")
    out, err = capsys.readouterr()
    assert out == "" and "toy run" in err and "5/5 chunks" in err
    assert re.search(r"\d\d:\d\d elapsed, ETA \d\d:\d\d, ", err), err  # the time left, named
    with progress_bars():
        run_monte_carlo(slow, 5, seed=0, chunk_size=1)
    assert "5/5" in capsys.readouterr().err
    run_monte_carlo(slow, 5, seed=0, chunk_size=1)  # default: no bar
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("id", ["rosa2013-fig11", "rosa2013-fig12"])
def test_the_uav_studies_refuse_a_trillion_trials_at_once(id):
    """The UAV studies spawn their own streams (a batch of runs per job): through trial_seeds, so
    10^12 trials are refused before anything is made (they used to grow memory silently)."""
    from fdi_lib.errors import ResourceError
    from fdi_lib.reproduce import reproduce

    with pytest.raises(ResourceError, match=r"n_trials: 1000000000000 seed sequences"):
        reproduce(id, trials=10**12)


def test_binomial_ci_cached_is_scipy_exact_every_time():
    # binomial_ci computes each (successes, trials, level) once per process: a repeated call gives
    # scipy's exact interval, the same bits, as an immutable tuple
    import scipy.stats

    for k, n, level in [(0, 1000, 0.95), (7, 2000, 0.95), (7, 2000, 0.9), (100, 100, 0.99)]:
        ci = scipy.stats.binomtest(k, n).proportion_ci(confidence_level=level, method="exact")
        for _ in range(2):
            got = binomial_ci(k, n, level)
            assert isinstance(got, tuple) and got == (float(ci.low), float(ci.high))
