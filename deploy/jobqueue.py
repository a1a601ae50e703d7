"""Run a reproduction on a SLURM or PBS cluster: Dask workers as batch jobs (dask-jobqueue).

A recipe, run on the login node of the cluster from the project's folder with ``.venv`` built
(``make venv``; the compute nodes must see this folder, a shared file system, and reach the
login node over TCP)::

    .venv/bin/python deploy/jobqueue.py slurm --workers 16 --memory 4GB --walltime 02:00:00 \\
        --queue NAME --account NAME -- zhang2021-table1 --trials 100000 --json

Each batch job is one Dask worker with one thread (a chunk is vectorised over its realisations and
runs its BLAS on one thread) started by this ``.venv``'s Python: the workers import the same
``fdi_lib`` and the same pinned libraries as the submitting process, which the byte-identical
results need. The scheduler runs in this process, on the login node; once the first worker has
joined (``--queue-wait`` seconds at most), the arguments after ``--`` run as
``fdi-reproduce ... --cluster tcp://SCHEDULER``, and the jobs are cancelled when it ends.
``local`` runs the same recipe with dask-jobqueue's stand-in, whose "jobs" are processes of this
machine: the tests use it (``tests/test_montecarlo_jobqueue.py``), as no SLURM or PBS queue is
available to them; ``--print-job-script`` shows the batch script a real queue would get.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

#: dask-jobqueue's cluster class of each queue ("local": its stand-in, jobs run as local processes).
KINDS = {
    "slurm": "dask_jobqueue.SLURMCluster",
    "pbs": "dask_jobqueue.PBSCluster",
    "local": "dask_jobqueue.local.LocalCluster",
}


def make_cluster(
    kind: str,
    *,
    memory: str,
    walltime: str | None = None,
    queue: str | None = None,
    account: str | None = None,
    python: str = sys.executable,
) -> Any:
    """A dask-jobqueue cluster of one-thread workers started by ``python`` (no job submitted yet:
    ``cluster.scale(n)`` submits them). Options a site needs beyond these (interfaces, modules to
    load, extra directives) go in dask's configuration file ``~/.config/dask/jobqueue.yaml``, which
    dask-jobqueue reads for every value not given here."""
    import importlib

    module, _, name = KINDS[kind].rpartition(".")
    options: dict[str, Any] = dict(
        cores=1, processes=1, memory=memory, python=python, scheduler_options={"dashboard": False}
    )
    if kind != "local":
        options.update(
            {
                k: v
                for k, v in (("walltime", walltime), ("queue", queue), ("account", account))
                if v is not None
            }
        )
    return getattr(importlib.import_module(module), name)(**options)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="deploy/jobqueue.py", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument(
        "kind", choices=sorted(KINDS), help="the batch queue (local: dask-jobqueue's stand-in)"
    )
    parser.add_argument(
        "--workers", type=int, default=2, help="batch jobs, one worker each (default 2)"
    )
    parser.add_argument("--memory", default="2GB", help="memory of a job (default 2GB)")
    parser.add_argument("--walltime", default=None, help="wall time of a job, e.g. 02:00:00")
    parser.add_argument("--queue", default=None, help="queue (SLURM partition) of the jobs")
    parser.add_argument("--account", default=None, help="account charged for the jobs")
    parser.add_argument(
        "--queue-wait",
        type=float,
        default=3600.0,
        help="seconds to wait for the first worker to join (default 3600)",
    )
    parser.add_argument(
        "--print-job-script", action="store_true", help="print a job's batch script and exit"
    )
    parser.epilog = "after --: the arguments of fdi-reproduce (an ID and its options)"
    argv = sys.argv[1:] if argv is None else list(argv)
    cut = argv.index("--") if "--" in argv else len(argv)
    args, rest = parser.parse_args(argv[:cut]), argv[cut + 1 :]
    if not args.print_job_script and not rest:
        parser.error(
            "expected -- and the arguments of fdi-reproduce, e.g. -- zhang2021-table1 --json"
        )
    if args.workers < 1:
        parser.error(f"--workers: expected a positive integer, got {args.workers}")
    import distributed

    from fdi_lib.reproduce.cli import main as reproduce

    with make_cluster(
        args.kind,
        memory=args.memory,
        walltime=args.walltime,
        queue=args.queue,
        account=args.account,
    ) as cluster:
        if args.print_job_script:
            print(cluster.job_script())
            return 0
        cluster.scale(args.workers)
        with distributed.Client(cluster, set_as_default=False) as client:
            try:
                client.wait_for_workers(1, timeout=args.queue_wait)
            except TimeoutError:
                print(
                    f"error: cluster: no batch job of {args.kind} started a worker within "
                    f"{args.queue_wait:g} s",
                    file=sys.stderr,
                )
                return 2
        return reproduce([*rest, "--cluster", cluster.scheduler_address], prog="fdi-reproduce")


if __name__ == "__main__":
    raise SystemExit(main())
