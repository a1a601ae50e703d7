"""Monte Carlo beyond this machine's pool (issue 25): any concurrent.futures executor, a Dask cluster
(``--cluster``), the same bytes as ``--jobs 1``, a killed worker, no process left behind."""

from __future__ import annotations

import concurrent.futures
import functools
import multiprocessing
import multiprocessing.resource_tracker
import os
import signal
import socket
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

pytest.importorskip("distributed")

import fdi_lib.montecarlo as mc  # noqa: E402
from fdi_lib.errors import ClusterError, ModelError  # noqa: E402
from fdi_lib.reproduce.cli import main  # noqa: E402
from fdi_lib.reproduce.registry import CACHE_ENV  # noqa: E402
from fdi_lib.reproduce.zhang2021 import example1_chunk  # noqa: E402


def _draws_chunk(seeds, *, dim):
    """Per-realisation draws, a batch reduction, and the process that ran the chunk."""
    x = np.stack([np.random.default_rng(s).standard_normal(dim) for s in seeds])
    return {"x": x, "norm": np.sqrt(np.sum(x**2, axis=1)), "pid": np.full(len(seeds), os.getpid())}


def _kill_once_chunk(seeds, *, parent, marker):
    """The first chunk run outside ``parent`` kills its own worker process (SIGKILL, no clean-up), once."""
    if os.getpid() != parent:
        try:
            fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            pass
        else:
            os.write(fd, str(os.getpid()).encode())
            os.close(fd)
            os.kill(os.getpid(), signal.SIGKILL)
    return _draws_chunk(seeds, dim=2)


def _assert_same(got, ref, skip=("pid",)):
    assert len(got) == len(ref)
    for g, r in zip(got, ref):
        assert g.keys() == r.keys()
        for key in r:
            if key not in skip:
                np.testing.assert_array_equal(g[key], r[key], err_msg=key)


def _children() -> set[int]:
    import psutil

    return {
        p.pid
        for p in psutil.Process().children(recursive=True)
        if p.status() != psutil.STATUS_ZOMBIE
    }


@pytest.fixture(scope="module")
def scheduler():
    """The address of an existing Dask cluster (2 local workers, as ``dask scheduler`` and ``dask
    worker`` would make), for ``--cluster tcp://...``; closed after the module's tests."""
    import logging

    import distributed

    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        host="127.0.0.1",
        dashboard_address=None,
        scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
        silence_logs=logging.CRITICAL,
    ) as cluster:
        yield cluster.scheduler_address


@pytest.fixture
def no_cache(monkeypatch):
    monkeypatch.delenv(CACHE_ENV, raising=False)


@pytest.fixture
def executor_runs(monkeypatch):
    """Count the runs that went through an executor (so a silent fallback to this process fails)."""
    calls = []
    real = mc._run_on_executor

    def spy(executor, task, n_tasks, first, done, **kwargs):
        calls.append(n_tasks)
        return real(executor, task, n_tasks, first, done, **kwargs)

    monkeypatch.setattr(mc, "_run_on_executor", spy)
    return calls


def test_a_process_pool_gives_the_runs_of_one_job(executor_runs):
    """A standard ProcessPoolExecutor: same arrays as jobs=1, chunks run in its workers."""
    fns = [functools.partial(_draws_chunk, dim=3), functools.partial(example1_chunk, q=5, r=0.5)]
    ref = mc.run_monte_carlo_many(fns, 13, seed=21, chunk_size=3)
    with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as ex:
        got = mc.run_monte_carlo_many(fns, 13, seed=21, chunk_size=3, executor=ex)
        with mc.use_executor(ex):  # the context's executor, as --cluster sets it
            ctx = mc.run_monte_carlo(fns[0], 13, seed=21, chunk_size=3)
    _assert_same(got, ref)
    _assert_same([ctx], ref[:1])
    assert executor_runs == [10, 5]
    assert set(got[0]["pid"][3:]) - {os.getpid()}, "no chunk ran in the pool's workers"
    assert (got[0]["pid"][:3] == os.getpid()).all()  # the first chunk (memory probe) runs here


class _CountingPool(concurrent.futures.ThreadPoolExecutor):
    """A thread pool that tells its number of workers (as a Dask cluster's executor does) and
    counts the tasks submitted to it."""

    def __init__(self, workers):
        super().__init__(workers)
        self.n, self.submitted = workers, []

    def workers(self):
        return self.n

    def submit(self, fn, /, *args):
        self.submitted.append(fn.__name__)
        return super().submit(fn, *args)


@pytest.mark.parametrize(
    "task_seconds, tasks", [(1e-12, ["_call"] * 19), (1e9, ["_call_many"] * 6 + ["_call"] * 7)]
)
def test_short_chunks_go_to_workers_several_to_a_task_with_the_same_results(
    task_seconds, tasks, monkeypatch
):
    """Chunks shorter than TASK_SECONDS (timed on the first) are batched, at least four tasks a
    worker: 20 chunks on 2 workers, the 19 after the first as 19 tasks, or as tasks of 2 while
    more than 4 per worker are left (6 tasks, 12 chunks), then the last 7 alone (the tasks shrink
    towards the end); the arrays are those of jobs=1."""
    monkeypatch.setattr(mc, "TASK_SECONDS", task_seconds)
    fn = functools.partial(_draws_chunk, dim=3)
    ref = mc.run_monte_carlo(fn, 40, seed=4, chunk_size=2)
    with _CountingPool(2) as pool:
        got = mc.run_monte_carlo(fn, 40, seed=4, chunk_size=2, executor=pool)
    _assert_same([got], [ref])
    assert pool.submitted == tasks


def test_a_task_lasts_task_seconds_and_every_worker_gets_four(monkeypatch):
    monkeypatch.setattr(mc, "TASK_SECONDS", 0.5)
    assert mc._batch_size(0.1, 1000, None) == 1  # workers unknown: one chunk a task
    assert mc._batch_size(0.1, 1000, 2) == 5  # 0.5 s / 0.1 s
    assert mc._batch_size(0.01, 80, 2) == 10  # 50 by time, 10 for four tasks a worker
    assert mc._batch_size(2.0, 1000, 16) == 1  # long chunks: one a task


def test_tasks_shrink_towards_the_end_of_the_run():
    """Guided self-scheduling: at most the batch, at most n_left / (2 workers), at least 1."""
    sizes, left = [], 41
    while left:
        sizes.append(mc._task_chunks(5, left, 2))
        left -= sizes[-1]
    assert sizes == [5, 5, 5, 5, 5, 4, 3, 2, 1, 1, 1, 1, 1, 1, 1]
    assert mc._task_chunks(5, 3, None) == 3  # workers unknown: the batch, within what is left


@pytest.mark.slow
@pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="kills a worker with SIGKILL")
def test_a_dask_cluster_gives_the_runs_of_one_job_even_when_a_worker_is_killed(
    tmp_path, scheduler, executor_runs
):
    """An existing Dask cluster (tcp://): bit-identical arrays to jobs=1; a worker killed in the
    middle of a chunk (SIGKILL) is replaced and its chunk run again by Dask, with the same result;
    the scheduler is left running."""
    fns = [functools.partial(_draws_chunk, dim=2), functools.partial(example1_chunk, q=9, r=0.5)]
    ref = mc.run_monte_carlo_many(fns, 16, seed=5, chunk_size=2)
    marker = tmp_path / "killed"
    kill = functools.partial(_kill_once_chunk, parent=os.getpid(), marker=str(marker))
    with mc.dask_executor(scheduler) as ex:
        got = mc.run_monte_carlo_many(fns, 16, seed=5, chunk_size=2, executor=ex)
        survived = mc.run_monte_carlo(kill, 16, seed=5, chunk_size=2, executor=ex)
    _assert_same(got, ref)
    assert set(got[0]["pid"][2:]) - {os.getpid()}, "no chunk ran in the cluster's workers"
    assert marker.exists() and int(marker.read_text()) != os.getpid(), "no worker was killed"
    _assert_same([survived], ref[:1])
    assert executor_runs == [16, 8]
    import distributed

    with distributed.Client(
        scheduler, set_as_default=False
    ) as client:  # still there, its worker replaced
        client.wait_for_workers(2, timeout=60)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_an_unreachable_scheduler_is_one_error_line(capsys, monkeypatch):
    monkeypatch.setattr(mc, "CONNECT_TIMEOUT", 0.5)
    address = f"tcp://127.0.0.1:{_free_port()}"  # nothing listens there
    t0 = time.monotonic()
    assert (
        main(["reproduce", "zhang2021-table1", "--trials", "4", "--cluster", address, "--json"])
        == 2
    )
    assert time.monotonic() - t0 < 30
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith(
        f"error: cluster: cannot reach the Dask scheduler at {address} within 0.5 s ("
    )
    assert err.count("\n") == 1 and "Traceback" not in err
    with pytest.raises(ClusterError, match="cannot reach the Dask scheduler"):
        with mc.dask_executor(address, timeout=0.5):
            pass


@pytest.mark.parametrize("spec", ["local", "local:0", "local:two", "127.0.0.1:8786", "tcp://"])
def test_a_malformed_cluster_is_refused_before_anything_starts(spec, capsys):
    with pytest.raises(ModelError, match=r"cluster: expected local:N"):
        with mc.dask_executor(spec):
            pass
    assert main(["reproduce", "zhang2021-table1", "--cluster", spec]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: cluster: expected local:N") and err.count("\n") == 1


def test_jobs_and_cluster_are_exclusive(capsys):
    with pytest.raises(SystemExit, match="2"):
        main(["reproduce", "zhang2021-table1", "--jobs", "2", "--cluster", "local:2"])
    err = capsys.readouterr().err
    assert (
        err.startswith("error: argument --cluster: not allowed with argument --jobs")
        and err.count("\n") == 1
    )


@pytest.mark.slow
@pytest.mark.parametrize(
    "argv, cluster",
    [
        (["zhang2021-table1", "--trials", "8"], "local:2"),
        (["bz-solution1", "--trials", "40"], "tcp"),
    ],
    ids=["zhang2021-table1-local", "bz-solution1-tcp"],
)
def test_json_is_the_same_bytes_for_jobs_and_a_cluster(
    argv, cluster, request, capsys, no_cache, executor_runs
):
    """--jobs 1, --jobs 2 and --cluster (a local cluster started for the run, or an existing
    scheduler) print the same JSON; a local cluster's workers are gone when the command returns."""
    if cluster == "tcp":
        cluster = request.getfixturevalue("scheduler")
    outs = {}
    for where in (["--jobs", "1"], ["--jobs", "2"]):
        assert main(["reproduce", *argv, *where, "--json"]) == 0
        outs[where[-1]] = capsys.readouterr().out
    multiprocessing.resource_tracker.ensure_running()
    before = _children()  # loky's reusable workers of --jobs 2 stay for the next run, by design
    assert main(["reproduce", *argv, "--cluster", cluster, "--json"]) == 0
    outs["cluster"] = capsys.readouterr().out
    assert _children() - before == set(), "a worker process outlived the cluster run"
    assert executor_runs, "the cluster run did not go through the executor"
    assert outs["1"].startswith('{"id": "') and outs["1"].endswith("}\n")
    assert outs["2"] == outs["1"]
    assert outs["cluster"] == outs["1"]


def _descendants(pid: int) -> set[int]:
    import psutil

    try:
        return {p.pid for p in psutil.Process(pid).children(recursive=True)}
    except psutil.NoSuchProcess:
        return set()


@pytest.mark.slow
def test_ctrl_c_stops_a_local_cluster_run_with_no_process_left(no_cache):
    """Ctrl-C during a --cluster local:2 run (SIGINT to the terminal's process group: the command
    and its workers, as they start): exit 130, ``interrupted`` as the only line on standard error
    (no worker's traceback), nothing on standard output, and every worker process gone."""
    import psutil

    env = {k: v for k, v in os.environ.items() if k != CACHE_ENV}
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "fdi_lib",
            "reproduce",
            "zhang2021-table1",
            "--trials",
            "400",
            "--cluster",
            "local:2",
            "--json",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,
    )
    try:
        deadline = time.monotonic() + 120
        seen: set[int] = set()
        while time.monotonic() < deadline and proc.poll() is None:  # until both workers run
            seen |= _descendants(proc.pid)
            workers = [
                p for p in seen if psutil.pid_exists(p) and "spawn_main" in " ".join(_cmdline(p))
            ]
            if len(workers) >= 2:
                break
            time.sleep(0.2)
        assert proc.poll() is None and len(workers) >= 2, "the run ended before its workers started"
        time.sleep(0.5)
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert proc.returncode == 130, err
    assert out == "" and err == "interrupted\n"
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and any(_running(p) for p in seen):
        time.sleep(0.1)
    assert not any(_running(p) for p in seen), "a process outlived the interrupted run"


def _cmdline(pid: int) -> list[str]:
    import psutil

    try:
        return psutil.Process(pid).cmdline()
    except psutil.Error:
        return []


def _running(pid: int) -> bool:
    import psutil

    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False
