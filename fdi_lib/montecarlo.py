"""Monte Carlo engine: seeded, chunked, vectorised, parallel, and independent of the job count.

Every realisation ``i`` gets its own random stream, spawned from one seed with
:class:`numpy.random.SeedSequence` (``SeedSequence(seed).spawn(n_trials)[i]``).
Realisations are processed in chunks by a user function that is vectorised over
the chunk (noise-independent quantities such as Kalman gains, signatures and
information matrices are computed once and shared), and chunks are spread over
CPU cores: the calling process computes chunks itself, ``jobs - 1`` worker processes (a
reusable loky pool, joblib's) take the others, each chunk with a single-threaded BLAS.
Since a realisation's random numbers depend only on
``(seed, i)``, results are bit-identical whatever ``jobs`` (the default chunk
size does not depend on ``jobs``, so the chunks, and hence the floating-point
operations, are the same for any number of workers).

Beyond one machine, the chunks go to any :class:`concurrent.futures.Executor` instead
(``executor=``, or :func:`use_executor` around a whole computation): a Dask cluster
(:func:`dask_executor`, the command line's ``--cluster``), a process pool, an adapter of Ray's
futures. Each chunk is the same call on the same realisations, so the results are bit-identical
to ``jobs=1`` for any executor and number of workers (on workers with the same CPU type and
library versions: the BLAS picks its kernels by CPU).

What is shared and what runs per realisation
--------------------------------------------
A chunk function computes once what does not depend on the noise (Kalman gains
and ``Sigma_k``, the signatures ``Gamma_k(r)`` and informations ``C_k(r)`` of the
windowed GLR, which :func:`fdi_lib.glr.glr_window` shares across a leading axis
of realisations) and runs the noise-dependent parts (simulation, Kalman
innovations, scores ``d_k(r)``, minmax statistics) vectorised over the chunk.
Draws are the only per-realisation loop (:func:`draw_noise_batch`), because each
realisation owns its random stream.

Closed loops (a controller in :func:`fdi_lib.simulate.simulate`) make the input
depend on the noise: the simulation and the Kalman filter are still vectorised
over the chunk (the controller acts element-wise), and the detector only needs
the innovations, so its shared quantities are unchanged; nothing runs per realisation.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import contextvars
import functools
import math
import os
import sys
import time
import warnings
from typing import Any, Callable, Iterator, Sequence

import numpy as np

from fdi_lib.errors import ClusterError, JobsCappedWarning, ModelError, ResourceError, ShapeError
from fdi_lib.models import LTVModel
from fdi_lib.simulate import Noise, draw_noise, noise_roots
from fdi_lib.validation import integer, probability, seed as check_seed

__all__ = [
    "trial_seeds",
    "trial_rngs",
    "run_monte_carlo",
    "run_monte_carlo_many",
    "draw_noise_batch",
    "binomial_ci",
    "default_chunk_size",
    "effective_jobs",
    "progress_bars",
    "use_executor",
    "dask_executor",
    "available_memory",
    "check_memory",
]

ChunkFn = Callable[[Sequence[np.random.SeedSequence]], dict[str, np.ndarray]]
#: ``task(i) -> (chunk_fn, root, start, stop)``: chunk ``i`` of a run, as :func:`_call` takes it.
Task = Callable[[int], tuple[ChunkFn, np.random.SeedSequence, int, int]]

#: Bytes held by one spawned SeedSequence (470 measured with tracemalloc over 10^4 of them, numpy 2).
_SEED_BYTES = 470


def trial_seeds(seed: int, n_trials: int) -> list[np.random.SeedSequence]:
    """One independent :class:`~numpy.random.SeedSequence` per realisation.

    ``seed`` is an integer >= 0, ``n_trials`` the number of realisations (>= 1). A list that
    would not fit in memory (about 0.5 kB a realisation) is refused with a
    :class:`~fdi_lib.errors.ResourceError` before anything is made; :func:`run_monte_carlo`
    makes each chunk's seeds when it runs the chunk instead.

    Explained in the book: :doc:`/book/running`.

    Examples
    --------
    >>> seeds = trial_seeds(7, 3)
    >>> len(seeds), seeds[2].spawn_key             # realisation i is child i of the root seed
    (3, (2,))
    """
    seed = check_seed(seed)
    n_trials = integer(n_trials, "n_trials", low=1)
    check_memory(_SEED_BYTES * n_trials, "n_trials", f"{n_trials} seed sequences")
    return np.random.SeedSequence(seed).spawn(n_trials)


def trial_rngs(seeds: Sequence[np.random.SeedSequence]) -> list[np.random.Generator]:
    """A :class:`~numpy.random.Generator` per seed sequence of ``seeds``.

    Explained in the book: :doc:`/book/running`.

    Examples
    --------
    >>> a = trial_rngs(trial_seeds(7, 2))[1].standard_normal()
    >>> b = trial_rngs(trial_seeds(7, 50))[1].standard_normal()
    >>> bool(a == b)                      # realisation 1's stream does not depend on the count
    True
    """
    return [np.random.default_rng(s) for s in seeds]


def draw_noise_batch(model: LTVModel, seeds: Sequence[np.random.SeedSequence]) -> Noise:
    """Noise of ``model`` for a chunk of realisations, one per entry of ``seeds`` (each its own
    stream), stacked on axis 0.

    Explained in the book: :doc:`/book/running`.

    Examples
    --------
    >>> import numpy as np
    >>> from fdi_lib.models import ltv_model
    >>> m = ltv_model(F=0.5 * np.eye(2), H=np.eye(2), Q=np.eye(2), R=np.eye(2), n_steps=30)
    >>> noise = draw_noise_batch(m, trial_seeds(0, 4))
    >>> noise.x0.shape, noise.w.shape, noise.v.shape      # (realisations, [steps,] size)
    ((4, 2), (4, 30, 2), (4, 30, 2))
    """
    roots = noise_roots(model)  # covariance roots shared by all the draws
    draws = [draw_noise(model, rng, roots=roots) for rng in trial_rngs(seeds)]
    return Noise(
        x0=np.stack([d.x0 for d in draws]),
        w=np.stack([d.w for d in draws]),
        v=np.stack([d.v for d in draws]),
    )


def default_chunk_size(n_trials: int) -> int:
    """Default realisations per chunk for ``n_trials``: ``min(250, ceil(n_trials / 4))``, independent of the job count.

    Four chunks or more keep two workers busy; about 250 realisations per chunk
    amortise the noise-independent work of a chunk (e.g. the windowed GLR's
    ``Gamma_k(r)``, ``C_k(r)``) while keeping its arrays small (a few MiB).

    Explained in the book: :doc:`/book/running`.

    Examples
    --------
    >>> default_chunk_size(10), default_chunk_size(1000), default_chunk_size(100_000)
    (3, 250, 250)
    """
    return max(1, min(250, -(-int(n_trials) // 4)))


def run_monte_carlo(
    chunk_fn: ChunkFn,
    n_trials: int,
    *,
    seed: int,
    jobs: int = 1,
    chunk_size: int | None = None,
    progress: bool | None = None,
    description: str = "Monte Carlo",
    executor: concurrent.futures.Executor | None = None,
) -> dict[str, np.ndarray]:
    """Run ``n_trials`` realisations of ``chunk_fn`` and concatenate the results.

    Explained in the book: :doc:`/book/running`.

    Parameters
    ----------
    chunk_fn : callable
        ``chunk_fn(seeds) -> dict`` of arrays whose leading axis has ``len(seeds)``
        entries, one per realisation (must be a picklable module-level function or
        :func:`functools.partial` for ``jobs != 1`` or an executor).
    n_trials : int
        Number of realisations.
    seed : int
        Root seed; realisation ``i`` uses ``SeedSequence(seed).spawn(n_trials)[i]``.
    jobs : int
        Parallel workers (joblib, processes); ``-1`` for all cores. Capped at the number of
        cores and of chunks (:func:`effective_jobs`, a warning when a positive request is cut).
    chunk_size : int, optional
        Realisations per call of ``chunk_fn``; default :func:`default_chunk_size`, which
        does not depend on ``jobs`` (same chunks, hence bit-identical results, for any
        number of workers). Changes only memory and speed when ``chunk_fn`` is exactly
        batch-invariant; give it explicitly to reproduce a run bit for bit.
    progress : bool, optional
        Show a tqdm progress bar over chunks on standard error (once the run has lasted a
        second), with the time elapsed and the time left (``ETA``); ``None`` (default): as set by
        :func:`progress_bars` (off unless the command line turned it on).
    description : str
        Label of the progress bar.
    executor : concurrent.futures.Executor, optional
        Where the chunks run instead of this machine's processes (``jobs`` is then not used): any
        executor, e.g. a Dask cluster's (:func:`dask_executor`, ``Client.get_executor()``), a
        :class:`~concurrent.futures.ProcessPoolExecutor`. The first chunk runs here (the
        memory probe), the others are handed to ``executor`` (at most :data:`IN_FLIGHT` at a
        time); the chunks and their seeds are those of ``jobs=1``, so are the results. Default:
        the executor set by :func:`use_executor`, if any.

    Returns
    -------
    dict of numpy.ndarray
        Each entry concatenated over realisations (leading axis ``n_trials``).

    Raises
    ------
    ResourceError
        The results would not fit in the available memory: the first chunk's size per
        realisation times ``n_trials``, checked before any other chunk runs.

    Examples
    --------
    A chunk function draws each realisation from its own seed; the chunks and the number of
    processes do not change the results:

    >>> import numpy as np
    >>> def chunk(seeds):
    ...     return {"x": np.array([np.random.default_rng(s).standard_normal() for s in seeds])}
    >>> a = run_monte_carlo(chunk, 10, seed=1)
    >>> b = run_monte_carlo(chunk, 10, seed=1, chunk_size=3)
    >>> a["x"].shape, bool(np.array_equal(a["x"], b["x"]))
    ((10,), True)
    """
    return run_monte_carlo_many(
        [chunk_fn],
        n_trials,
        seed=seed,
        jobs=jobs,
        chunk_size=chunk_size,
        progress=progress,
        description=description,
        executor=executor,
    )[0]


def run_monte_carlo_many(
    chunk_fns: Sequence[ChunkFn],
    n_trials: int,
    *,
    seed: int,
    jobs: int = 1,
    chunk_size: int | None = None,
    progress: bool | None = None,
    description: str = "Monte Carlo",
    executor: concurrent.futures.Executor | None = None,
) -> list[dict[str, np.ndarray]]:
    """:func:`run_monte_carlo` of several chunk functions on the same realisations, in one pool.

    E.g. the columns of a table (common random numbers: realisation ``i`` of every column uses
    the same seed). Result ``c`` is exactly ``run_monte_carlo(chunk_fns[c], n_trials, ...)``
    with the same arguments; but the chunks of all the columns are handed out together, so
    that no process waits at the end of a column for the others to finish theirs.

    Explained in the book: :doc:`/book/running`.

    Parameters
    ----------
    chunk_fns : sequence of callable
        Chunk functions, as ``chunk_fn`` of :func:`run_monte_carlo`.
    n_trials, seed, jobs, chunk_size, progress, description, executor
        As in :func:`run_monte_carlo` (the progress bar counts the chunks of all the functions).

    Returns
    -------
    list of dict of numpy.ndarray
        One per chunk function, as :func:`run_monte_carlo` returns.

    Raises
    ------
    ResourceError
        The results of ``n_trials`` realisations would not fit in the available memory (estimated
        from the first chunk, before any other is run).

    Examples
    --------
    >>> import numpy as np
    >>> def chunk(seeds):
    ...     return {"x": np.array([np.random.default_rng(s).standard_normal() for s in seeds])}
    >>> def square(seeds):
    ...     return {"x2": chunk(seeds)["x"] ** 2}
    >>> first, second = run_monte_carlo_many([chunk, square], 10, seed=1)
    >>> bool(np.array_equal(first["x"] ** 2, second["x2"]))    # the same realisations
    True
    """
    seed = check_seed(seed)
    n_trials = integer(n_trials, "n_trials", low=1)
    chunk_fns = list(chunk_fns)
    if not chunk_fns:
        raise ModelError("chunk_fns: expected at least one chunk function, got none")
    if chunk_size is None:
        chunk_size = default_chunk_size(n_trials)
    chunk_size = integer(chunk_size, "chunk_size", low=1)
    root = np.random.SeedSequence(seed)
    n_parts = -(-n_trials // chunk_size)
    n_tasks = len(chunk_fns) * n_parts
    if executor is None:
        executor = _EXECUTOR.get()
    n_workers = effective_jobs(jobs, n_tasks) if executor is None else 1

    def part(j: int) -> slice:
        return slice(j * chunk_size, min((j + 1) * chunk_size, n_trials))

    def task(i: int) -> tuple[ChunkFn, np.random.SeedSequence, int, int]:
        # task i: chunk i % n_parts of function i // n_parts (its seeds are made where it runs)
        c, j = divmod(i, n_parts)
        sl = part(j)
        return chunk_fns[c], root, sl.start, sl.stop

    bar: Any = None
    if progress if progress is not None else _PROGRESS.get():
        from tqdm.auto import tqdm

        # on standard error, and only once a run has lasted a second (no flicker on short ones); the
        # time left is named (tqdm's own "elapsed<remaining" is easily misread)
        bar = tqdm(
            total=n_tasks,
            desc=description,
            unit="chunk",
            file=sys.stderr,
            delay=1.0,
            bar_format="{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} chunks "
            "[{elapsed} elapsed, ETA {remaining}, {rate_fmt}]",
        )
    try:
        started = time.thread_time()  # CPU time: what a chunk costs a core, whatever the load
        first = _call(*task(0))  # the calling process's first chunk, also the memory probe
        first_seconds = time.thread_time() - started
        _check_memory(first, part(0), n_trials, len(chunk_fns))
        if bar is not None:
            bar.update()
        done = None if bar is None else bar.update
        if executor is None:
            results = _run_chunks(task, n_tasks, first, n_workers, done)
        else:
            results = _run_on_executor(
                executor, task, n_tasks, first, done, first_seconds=first_seconds
            )
    finally:
        if bar is not None:
            bar.close()
    outs = []
    for c in range(len(chunk_fns)):
        col = results[c * n_parts : (c + 1) * n_parts]
        out = {}
        for key in col[0].keys():
            arrays = [np.asarray(r[key]) for r in col]
            for j, arr in enumerate(arrays):
                sl = part(j)
                if arr.shape[:1] != (sl.stop - sl.start,):
                    raise ShapeError(
                        f"chunk_fn: entry {key!r} must have one row per realisation "
                        f"({sl.stop - sl.start}), got shape {arr.shape}"
                    )
            out[key] = np.concatenate(arrays, axis=0)
        outs.append(out)
    return outs


#: Whether :func:`run_monte_carlo` shows a progress bar when its ``progress`` is ``None`` (see
#: :func:`progress_bars`; the command line turns it on for an interactive terminal).
_PROGRESS: contextvars.ContextVar[bool] = contextvars.ContextVar("fdi_lib_progress", default=False)


@contextlib.contextmanager
def progress_bars(enabled: bool = True) -> Iterator[None]:
    """Context manager: Monte Carlo runs inside show a progress bar on standard error if ``enabled``
    (hide it otherwise), unless their ``progress`` argument says otherwise.

    Explained in the book: :doc:`/book/running`.

    Examples
    --------
    >>> import numpy as np
    >>> def chunk(seeds):
    ...     return {"k": np.arange(len(seeds))}
    >>> with progress_bars(False):           # no bar, whatever the command line said
    ...     out = run_monte_carlo(chunk, 8, seed=0)
    >>> out["k"].shape
    (8,)
    """
    token = _PROGRESS.set(bool(enabled))
    try:
        yield
    finally:
        _PROGRESS.reset(token)


#: The executor that :func:`run_monte_carlo` uses when its ``executor`` is ``None`` (see :func:`use_executor`).
_EXECUTOR: contextvars.ContextVar[concurrent.futures.Executor | None] = contextvars.ContextVar(
    "fdi_lib_executor", default=None
)


@contextlib.contextmanager
def use_executor(executor: concurrent.futures.Executor | None) -> Iterator[None]:
    """Context manager: Monte Carlo runs inside hand their chunks to ``executor`` (``None``: this
    machine's processes, as ``jobs`` says), unless their ``executor`` argument names another.

    So a whole reproduction, or the claims ledger, runs on a cluster without passing the executor
    down every call (as the command line's ``--cluster`` does). The setting is this thread's.

    Explained in the book: :doc:`/book/running`.

    Examples
    --------
    >>> import numpy as np
    >>> from concurrent.futures import ThreadPoolExecutor
    >>> def chunk(seeds):
    ...     return {"x": np.array([np.random.default_rng(s).random() for s in seeds])}
    >>> with ThreadPoolExecutor(2) as pool, use_executor(pool):
    ...     a = run_monte_carlo(chunk, 12, seed=3)
    >>> bool(np.array_equal(a["x"], run_monte_carlo(chunk, 12, seed=3)["x"]))
    True
    """
    token = _EXECUTOR.set(executor)
    try:
        yield
    finally:
        _EXECUTOR.reset(token)


#: Seconds to wait for a Dask scheduler (``dask_executor("tcp://...")``) before giving up.
CONNECT_TIMEOUT = 5.0
#: Seconds a run on a Dask cluster may go on with no worker before it fails (:func:`dask_executor`).
WORKER_TIMEOUT = 60.0
#: Seconds between two looks at a cluster's health while a run waits for its chunks.
WATCH_INTERVAL = 0.5


@contextlib.contextmanager
def dask_executor(
    cluster: str, *, timeout: float | None = None, worker_timeout: float | None = None
) -> Iterator[concurrent.futures.Executor]:
    """Context manager: the :class:`concurrent.futures.Executor` of a Dask cluster, closed on exit.

    Explained in the book: :doc:`/book/running`.

    Parameters
    ----------
    cluster : str
        ``"local:N"``: a cluster of ``N`` worker processes on this machine, one thread each, started
        for the block and stopped at its end (also on an error or Ctrl-C), listening on
        ``127.0.0.1`` only, without dashboard. ``"tcp://HOST:PORT"`` (or another Dask protocol):
        an existing scheduler (``dask scheduler``, with workers started by ``dask worker``; they
        need this version of :mod:`fdi_lib` importable); it is left running.
        ``local:N`` above the CPU cores starts as many workers as cores, with the
        :class:`~fdi_lib.errors.JobsCappedWarning` of ``jobs`` (the results do not depend on it).
    timeout : float, optional
        Seconds to wait for the scheduler; default :data:`CONNECT_TIMEOUT`.
    worker_timeout : float, optional
        Seconds a run may go on without any worker on the cluster (all lost, none joined) before it
        fails; default :data:`WORKER_TIMEOUT`. The run's chunks are then cancelled.

    Raises
    ------
    ModelError
        ``cluster`` is not of either form, or ``dask.distributed`` is not installed (the ``cluster``
        extra of the package).
    ClusterError
        One line naming the address: the scheduler cannot be reached (connection refused, no
        answer within ``timeout``), the address is not a Dask scheduler's, the scheduler has no
        worker within ``timeout``, or the local cluster cannot start. During a run (raised by
        :func:`run_monte_carlo`): no worker for ``worker_timeout`` seconds, or the scheduler lost.

    Examples
    --------
    ``with dask_executor("local:2") as ex, use_executor(ex): ...`` runs the block's Monte Carlo
    on two local workers (the chapter's recipes); a malformed cluster is refused before anything
    starts:

    >>> with dask_executor("local:0"):
    ...     pass
    Traceback (most recent call last):
    ...
    fdi_lib.errors.ModelError: cluster: expected local:N with N a positive integer, got 'local:0'
    """
    kind, sep, rest = str(cluster).partition(":")
    n_workers = 0  # of a local cluster; 0 for a scheduler's address
    if kind == "local":
        with contextlib.suppress(ValueError):
            n_workers = int(rest)
        if n_workers < 1:
            raise ModelError(
                f"cluster: expected local:N with N a positive integer, got {cluster!r}"
            )
        n_workers = effective_jobs(n_workers, name="cluster: workers of local:N:")
    elif not (sep and rest.startswith("//") and len(rest) > 2):
        raise ModelError(
            f"cluster: expected local:N or a scheduler address such as tcp://HOST:PORT, "
            f"got {cluster!r}"
        )
    try:
        import distributed
    except ImportError:
        raise ModelError(
            "cluster: needs dask.distributed; expected it installed (pip install "
            "'fdi_lib[cluster]'), got none"
        ) from None

    timeout = CONNECT_TIMEOUT if timeout is None else float(timeout)
    worker_timeout = WORKER_TIMEOUT if worker_timeout is None else float(worker_timeout)
    stack = contextlib.ExitStack()
    stack.enter_context(_dask_logs_quiet())
    try:
        # Ctrl-C is held while the cluster starts and while it stops: Dask cannot stop a cluster
        # interrupted half-way through its start (its exit handler then fails on the workers still
        # starting), nor finish a stop interrupted by a second Ctrl-C
        with _sigint_held():
            client = _start_dask(stack, distributed, cluster, n_workers, timeout)
        yield _WatchedExecutor(client, cluster, worker_timeout)
    finally:
        with _sigint_held():
            stack.close()


@contextlib.contextmanager
def _dask_logs_quiet() -> Iterator[None]:
    """Context manager: Dask's loggers (``distributed.*``) print nothing below CRITICAL inside. A
    cluster's faults reach the caller as one :class:`~fdi_lib.errors.ClusterError` line; Dask's
    own log lines on standard error (a lost scheduler's "Failed to reconnect ...") would come
    before it, and a chunk's error reaches the caller as its exception anyway."""
    import logging

    known = logging.root.manager.loggerDict
    names = ["distributed"] + [n for n in known if n.startswith("distributed.")]
    loggers = [logging.getLogger(n) for n in names]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for lg, level in zip(loggers, levels):
            lg.setLevel(level)


def _start_dask(
    stack: contextlib.ExitStack, distributed: Any, cluster: str, n_workers: int, timeout: float
) -> Any:
    """The client of :func:`dask_executor` (``n_workers > 0``: a local cluster of that many
    workers), with a worker, entered in ``stack`` with its cluster."""
    import logging

    address: Any = cluster
    if n_workers:
        import dask

        try:
            # processes (one BLAS thread each: Dask's nanny sets OMP/OPENBLAS/MKL_NUM_THREADS=1),
            # on the loopback interface only, no dashboard (the scheduler's small HTTP server,
            # health and metrics, on a free loopback port); no log on standard error (a chunk's error
            # reaches the caller as an exception). Two of Dask's defaults cost a chunk CPU time
            # (the nannies pass this configuration to their workers): glibc's malloc trim threshold
            # set to 64 kiB in the workers' environment (MALLOC_TRIM_THRESHOLD_, to return freed
            # memory to the system at once) made a chunk of Table I of Zhang 2021 (100
            # realisations) take 0.074 s of CPU in a worker against 0.057 s in this process: its
            # many temporary arrays of a few MiB were given back and faulted in again at each
            # operation; without it, 0.057 s in both. And the workers' statistical profiler (a
            # thread sampling the running task's stack every 10 ms for the dashboard, which is
            # off): 0.025 s of CPU per second per idle worker against 0.015 s without.
            environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {}))
            environ.pop("MALLOC_TRIM_THRESHOLD_", None)
            with dask.config.set(
                {
                    "distributed.worker.profile.enabled": False,
                    "distributed.nanny.pre-spawn-environ": environ,
                }
            ):
                address = stack.enter_context(
                    distributed.LocalCluster(
                        n_workers=n_workers,
                        threads_per_worker=1,
                        processes=True,
                        host="127.0.0.1",
                        dashboard_address=None,
                        scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                        silence_logs=logging.CRITICAL,
                    )
                )
        except (OSError, RuntimeError) as exc:  # RuntimeError: "Nanny failed to start"
            raise ClusterError(
                f"cluster: cannot start a local cluster of {n_workers} workers ({_one_line(exc)})"
            ) from None
    try:
        if not n_workers:  # an address: Dask's handshake first, on a connection of its own
            _handshake(address, timeout)
        client = stack.enter_context(
            distributed.Client(address, timeout=timeout, set_as_default=False)
        )
    except OSError as exc:  # including TimeoutError: "Timed out trying to connect to ... after 5 s"
        raise ClusterError(
            f"cluster: cannot reach the Dask scheduler at {cluster} within {timeout:g} s "
            f"({_one_line(exc)})"
        ) from None
    except Exception as exc:  # a server of another protocol: its bytes read as a Dask frame
        # (a length of 3 EiB: MemoryError, ValueError, a msgpack error, ...)
        raise ClusterError(
            f"cluster: {cluster} is not a Dask scheduler (its answer is not Dask's "
            f"protocol: {_one_line(exc)[:200]})"
        ) from None
    try:  # a scheduler without workers would leave the run waiting for ever
        client.wait_for_workers(1, timeout=timeout)
    except OSError:  # TimeoutError
        raise ClusterError(
            f"cluster: the Dask scheduler at {cluster} has no worker (none joined within "
            f"{timeout:g} s)"
        ) from None
    return client


def _handshake(address: str, timeout: float) -> None:
    """Open a Dask connection to ``address`` (with Dask's configured TLS, if any) and close it: an
    :class:`OSError` if nothing answers, another exception if the answer is not Dask's.

    Done before the :class:`distributed.Client` is made: a client whose construction fails on a
    server of another protocol is left half made, and at the interpreter's exit it waits 10 s and
    prints a traceback ("Exception ignored in Client.__del__"). This connection has an event loop
    of its own, in a thread of its own (a notebook's thread already runs one)."""
    import asyncio

    from distributed.comm import connect
    from distributed.security import Security

    async def probe() -> None:
        comm = await connect(address, timeout=timeout, **Security().get_connection_args("client"))
        await comm.close()

    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        pool.submit(asyncio.run, probe()).result()


class _WatchedExecutor(concurrent.futures.Executor):
    """The executor of a Dask client (random task keys, ``pure=False``: no hashing of the
    arguments, every chunk a new task), with :meth:`check`, the health of the cluster, which
    :func:`_run_on_executor` calls while it waits for chunks."""

    def __init__(self, client: Any, address: str, worker_timeout: float) -> None:
        import time

        self._client = client
        self._executor = client.get_executor(pure=False)
        self._address = address
        self._worker_timeout = worker_timeout
        self._clock = time.monotonic
        self._workerless_since: float | None = None

    def submit(
        self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any
    ) -> concurrent.futures.Future:
        return self._executor.submit(fn, *args, **kwargs)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        self._executor.shutdown(wait=wait)

    def workers(self) -> int:
        """The number of workers of the cluster now."""
        return int(self._client.scheduler_info(n_workers=0).get("n_workers", 0))

    def check(self, failure: BaseException | None = None) -> None:
        """Raise a one-line :class:`~fdi_lib.errors.ClusterError` if the scheduler is lost, or has
        had no worker for the watchdog's time; ``failure`` (a chunk's exception) is the cluster's
        when it is a cancellation or a lost connection, not the chunk's own error."""
        status = self._client.status
        if status not in ("running", "newly-created"):
            raise ClusterError(
                f"cluster: lost the Dask scheduler at {self._address} during the "
                f"run (its client is {status})"
            ) from None
        if failure is not None and _is_lost_connection(failure):
            raise ClusterError(
                f"cluster: lost the Dask scheduler at {self._address} during the "
                f"run ({_one_line(failure)[:200]})"
            ) from None
        workers = self.workers()
        now = self._clock()
        if workers:
            self._workerless_since = None
        elif self._workerless_since is None:
            self._workerless_since = now
        elif now - self._workerless_since >= self._worker_timeout:
            raise ClusterError(
                f"cluster: the Dask scheduler at {self._address} has had no worker "
                f"for {self._worker_timeout:g} s; the run is cancelled"
            )


def _is_lost_connection(exc: BaseException) -> bool:
    """Whether a chunk's exception says that its cluster went away (its future cancelled, the
    connection to the scheduler closed) rather than that the chunk failed."""
    import asyncio

    return isinstance(exc, (concurrent.futures.CancelledError, asyncio.CancelledError)) or type(
        exc
    ).__name__ in ("CommClosedError", "FutureCancelledError")


@contextlib.contextmanager
def _sigint_held() -> Iterator[None]:
    """Context manager: a Ctrl-C (SIGINT) inside is held, and raised as ``KeyboardInterrupt`` on
    leaving. SIGINT is blocked (POSIX, main thread), so the processes and threads started inside
    keep it blocked: the workers of a local cluster are stopped by their nanny, not by the
    terminal's Ctrl-C in the middle of their start-up."""
    import signal
    import threading

    if (
        not hasattr(signal, "pthread_sigmask")
        or threading.current_thread() is not threading.main_thread()
    ):
        yield
        return
    from multiprocessing import resource_tracker

    resource_tracker.ensure_running()  # its start unblocks SIGINT: started first, it stays blocked below
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)  # a held SIGINT is delivered here


def _one_line(exc: BaseException) -> str:
    """``exc`` as one line: its type and its message with the line breaks removed."""
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}"


#: At most this many tasks (of one chunk or more) are handed to an executor at a time
#: (:func:`run_monte_carlo`'s ``executor``): enough to keep a cluster of hundreds of workers busy,
#: few enough that a run of millions of chunks does not hold millions of pending tasks.
IN_FLIGHT = 1024


#: A task handed to a cluster lasts about this long at least: chunks that take less (the CPU
#: time of the first chunk, which the calling process runs) go to a worker together, as one task,
#: since each task costs the scheduler milliseconds (``benchmarks/bench_cluster.py`` measures it).
TASK_SECONDS = 0.5


def _batch_size(first_seconds: float | None, n_left: int, workers: int | None) -> int:
    """Chunks per task on an executor of ``workers`` workers (``None``: unknown, one chunk per
    task), for ``n_left`` chunks of about ``first_seconds`` each: enough to last
    :data:`TASK_SECONDS`, few enough that every worker gets at least four tasks (no worker idles
    long at the end of the run)."""
    if not workers or not first_seconds or first_seconds <= 0:
        return 1
    return max(1, min(math.ceil(TASK_SECONDS / first_seconds), n_left // (4 * workers)))


def _task_chunks(batch: int, n_left: int, workers: int | None) -> int:
    """Chunks in the next task handed out, ``n_left`` chunks not handed out yet: ``batch`` (from
    :func:`_batch_size`), but no more than ``n_left / (2 workers)``, so that the tasks shrink
    towards the end of the run (guided self-scheduling, Polychronopoulos and Kuck 1987): the
    cluster takes tasks in the order given, the last ones are single chunks, and the workers
    finish within about a chunk of each other instead of a whole task."""
    if not workers:
        return min(batch, n_left)
    return max(1, min(batch, n_left // (2 * workers)))


def _call_many(
    calls: Sequence[tuple[ChunkFn, np.random.SeedSequence, int, int]],
) -> list[dict[str, np.ndarray]]:
    """:func:`_call` of each chunk of ``calls`` in turn (one task of several chunks)."""
    return [_call(*c) for c in calls]


def _run_on_executor(
    executor: concurrent.futures.Executor,
    task: Task,
    n_tasks: int,
    first: dict[str, np.ndarray],
    done: Callable[[], Any] | None,
    *,
    first_seconds: float | None = None,
) -> list[dict[str, np.ndarray]]:
    """Results of every task ``_call(*task(i))`` (a chunk), in order, ``first`` (task 0) computed
    already (in ``first_seconds`` of CPU time): the others submitted to ``executor``, at most
    :data:`IN_FLIGHT` at a time, collected as they finish. On an executor that tells its number of workers (a
    ``workers()`` method, :func:`dask_executor`'s) chunks shorter than :data:`TASK_SECONDS` go
    several to a task (:func:`_batch_size`); each chunk is the same call either way, so are the
    results. On an error (a chunk's, re-raised here) or an interruption, the chunks not yet
    finished are cancelled (Dask stops them; a process pool, those not started) before it
    propagates. A worker lost mid-chunk is the executor's to handle (Dask reruns its chunks
    elsewhere); an executor with a ``check`` method (:func:`dask_executor`'s) is watched every
    :data:`WATCH_INTERVAL` seconds while no chunk finishes, and asked whether a chunk's exception
    is the cluster's (a lost scheduler): it raises a :class:`~fdi_lib.errors.ClusterError` then.
    """
    results: dict[int, dict[str, np.ndarray]] = {0: first}
    pending: dict[concurrent.futures.Future, range] = {}
    given = 1  # tasks handed out: range(1, given)
    check = getattr(executor, "check", None)  # a cluster's watchdog (see dask_executor)
    workers = getattr(executor, "workers", None)
    n_workers = workers() if workers is not None else None
    batch = _batch_size(first_seconds, n_tasks - 1, n_workers)
    try:
        while given < n_tasks or pending:
            while given < n_tasks and len(pending) < IN_FLIGHT:
                chunks = range(given, given + _task_chunks(batch, n_tasks - given, n_workers))
                calls = [task(i) for i in chunks]
                future = (
                    executor.submit(_call, *calls[0])
                    if len(calls) == 1
                    else executor.submit(_call_many, calls)
                )
                pending[future] = chunks
                given = chunks.stop
            finished, _ = concurrent.futures.wait(
                pending,
                timeout=None if check is None else WATCH_INTERVAL,
                return_when=concurrent.futures.FIRST_COMPLETED,
            )
            if not finished and check is not None:
                check()
            for future in finished:
                try:
                    out = future.result()
                except Exception as exc:
                    if check is not None:
                        check(exc)  # the cluster's failure (one line) rather than the chunk's
                    raise
                chunks = pending.pop(future)
                for i, res in zip(chunks, [out] if len(chunks) == 1 else out):
                    results[i] = res
                    if done is not None:
                        done()
    except BaseException:
        for future in pending:
            with contextlib.suppress(Exception):  # a lost scheduler cannot cancel: none runs
                future.cancel()
        raise
    return [results[i] for i in range(n_tasks)]


def _spawned(root: np.random.SeedSequence, start: int, stop: int) -> list[np.random.SeedSequence]:
    """``root.spawn(n)[start:stop]`` of a fresh ``root``, for any ``n >= stop``.

    Built as numpy's ``SeedSequence.spawn`` builds its children (same entropy and pool size,
    spawn key extended by the child's index), but only for the chunk at hand: spawning all
    ``n_trials`` children up front would hold one object per realisation (about 0.5 kB each)
    before anything runs. ``tests/test_montecarlo.py`` checks the identity with ``spawn``.
    """
    return [
        np.random.SeedSequence(
            root.entropy, spawn_key=(*root.spawn_key, i), pool_size=root.pool_size
        )
        for i in range(start, stop)
    ]


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation without swapping (psutil's ``available``),
    or ``None`` when it cannot be read (no psutil: then nothing is refused).

    Explained in the book: :doc:`/book/running`.

    Examples
    --------
    >>> available_memory() > 0
    True
    """
    try:
        import psutil
    except ImportError:  # pragma: no cover (psutil is present wherever Jupyter is)
        return None
    return int(psutil.virtual_memory().available)


def check_memory(needed: float, name: str, what: str) -> None:
    """Raise :class:`~fdi_lib.errors.ResourceError` naming ``name`` when ``needed`` bytes exceed
    :func:`available_memory`; ``what`` says what would need them.

    Explained in the book: :doc:`/book/running`.

    Examples
    --------
    >>> check_memory(1e3, "n_trials", "1 realisation")         # fits: nothing happens
    >>> check_memory(1e30, "n_trials", "1e26 trials")    # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fdi_lib.errors.ResourceError: n_trials: 1e26 trials would need about 1e+15 PB of memory; ...
    """
    available = available_memory()
    if available is not None and needed > available:
        raise ResourceError(
            f"{name}: {what} would need about {_bytes_text(needed)} of memory; "
            f"{_bytes_text(available)} is available: use fewer"
        )


def _bytes_text(n: float) -> str:
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if abs(n) < 1000 or unit == "PB":
            return f"{n:.3g} {unit}"
        n /= 1000
    raise AssertionError  # unreachable


def _check_memory(first: dict[str, np.ndarray], sl: slice, n_trials: int, n_fns: int) -> None:
    """Refuse a run whose results would not fit in memory, from the size of its first chunk.

    The run keeps every chunk's arrays and then their concatenation (twice the results), for each
    chunk function; the first function's size per realisation stands for all of them.
    """
    per_trial = sum(np.asarray(v).nbytes for v in first.values()) / (sl.stop - sl.start)
    needed = 2.0 * per_trial * n_trials * n_fns
    check_memory(
        needed,
        "n_trials",
        f"{n_trials} realisations x {n_fns} chunk function(s) at "
        f"{_bytes_text(per_trial)} each (measured on the first chunk)",
    )


#: Environment variable: the number of cores this process may use when it shares the machine with
#: others (set by ``tools/execute_book.py`` for each chapter's kernel, the chapters being executed
#: side by side). :func:`effective_jobs` reads it as the machine's size, without a warning: the
#: cut is the build's choice, and results do not depend on the number of processes.
CORES_ENV = "FDI_CORES"


def _cores_share(cores: int) -> int:
    """``$FDI_CORES``, or ``cores`` when it is unset or empty; any other value than a positive
    integer is a :class:`~fdi_lib.errors.ModelError` naming the variable."""
    value = os.environ.get(CORES_ENV, "").strip()
    if not value:
        return cores
    if not value.isdigit() or int(value) < 1:
        raise ModelError(
            f"${CORES_ENV}: expected a positive integer (the cores this process may "
            f"use), got {value!r}"
        )
    return int(value)


def effective_jobs(jobs: int, n_tasks: int | None = None, *, name: str = "jobs:") -> int:
    """The number of processes that ``jobs`` asks for and that can run: ``min(jobs, cores, n_tasks)``.

    ``jobs = -1`` (any negative value) means every core; ``n_tasks`` (optional) is the number of
    chunks of work. A positive request above that issues a :class:`~fdi_lib.errors.JobsCappedWarning`
    (results do not depend on the number of processes, only the time does), its message starting
    with ``name``. When ``$FDI_CORES`` (:data:`CORES_ENV`) is set, at most that many processes are
    used, without a warning.

    Explained in the book: :doc:`/book/running`.

    Examples
    --------
    >>> import warnings
    >>> effective_jobs(1), effective_jobs(-1, n_tasks=1)    # one process; all cores but one task
    (1, 1)
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     used = effective_jobs(10**6)
    >>> used < 10**6, caught[0].category.__name__
    (True, 'JobsCappedWarning')
    """
    if isinstance(jobs, (bool, np.bool_)) or not isinstance(jobs, (int, np.integer)) or jobs == 0:
        raise ModelError(f"jobs: expected a non-zero integer (-1 = all cores), got {jobs!r}")
    import joblib

    cores = max(1, int(joblib.cpu_count()))  # loky's count: CPU affinity and cgroup quotas included
    unshared = cores if n_tasks is None else min(cores, max(1, int(n_tasks)))
    limit = min(unshared, _cores_share(cores))
    used = limit if jobs < 0 else min(int(jobs), limit)
    if jobs > unshared:  # cut by the machine or the work; a cut to the share ($FDI_CORES) is silent
        why = f"{cores} CPU core{'s' * (cores > 1)}"
        if n_tasks is not None and n_tasks < cores:
            why = f"{n_tasks} chunk{'s' * (n_tasks > 1)} of work"
        warnings.warn(
            JobsCappedWarning(
                f"{name} {jobs} requested, {used} used ({why}); the results do not depend on it"
            ),
            stacklevel=3,
        )
    return used


def _call(
    chunk_fn: ChunkFn, root: np.random.SeedSequence, start: int, stop: int
) -> dict[str, np.ndarray]:
    """Realisations ``start:stop`` of ``root``'s streams by ``chunk_fn`` (their seeds made here, in
    the process that runs them), with the BLAS on one thread (the same floating-point operations
    in every process)."""
    from fdi_lib.threads import blas_single_thread

    seeds = _spawned(root, start, stop)
    with blas_single_thread():
        return chunk_fn(seeds)


def _run_chunks(
    task: Task,
    n_tasks: int,
    first: dict[str, np.ndarray],
    n_workers: int,
    done: Callable[[], Any] | None,
) -> list[dict[str, np.ndarray]]:
    """Results of every task ``_call(*task(i))`` (a chunk), in order, on this process
    and ``n_workers - 1`` others; ``first`` is the result of task 0, already computed here.

    The calling process computes chunks too: it is warm (modules imported, per-process caches of
    a chunk function's set-up filled), while a worker process pays its start-up (about a second
    of imports) and its caches once. Chunks are handed out one at a time: this process takes them
    from the front, each worker (driven by a thread of this process) the next one from the back as
    soon as it is free. When no new chunk is left and no worker has delivered yet (still
    starting), this process recomputes a pending chunk rather than wait for it (the result is the
    same): more jobs are never much slower than one. Workers are a reusable loky pool, kept
    between calls: the start-up is paid once per session. An interruption (``KeyboardInterrupt``)
    kills the workers before it propagates: no process is left computing.

    This scheduler drives the pool through the standard executor interface (``submit``,
    ``result``), but is not replaced by :func:`_run_on_executor` over the same pool: there the
    calling process only waits, and the columns of Table I of Zhang 2021 (5 x 160 trials, chunks
    of 40, 2 cores) took 1.2 to 1.8 times as long as here, warm or cold (issue 25).
    """
    if n_workers == 1 or n_tasks == 1:
        out = [first]
        for i in range(1, n_tasks):
            out.append(_call(*task(i)))
            if done is not None:
                done()
        return out
    import threading

    from joblib.externals.loky import get_reusable_executor

    with warnings.catch_warnings():  # a new size waits for chunks left running by a takeover
        warnings.filterwarnings("ignore", "Trying to resize an executor", UserWarning)
        executor = get_reusable_executor(max_workers=n_workers - 1, timeout=600)
    lock = threading.Lock()
    delivered = threading.Event()  # a worker has delivered a chunk (set) or failed
    todo = [1, n_tasks]  # the chunks not handed out yet: range(todo[0], todo[1])
    pending: set[int] = set()
    results: dict[int, dict[str, np.ndarray]] = {0: first}
    errors: list[BaseException] = []

    def store(i: int, res: dict[str, np.ndarray]) -> None:
        with lock:
            pending.discard(i)
            if i not in results:
                results[i] = res
                if done is not None:
                    done()

    def drive_worker() -> None:
        while True:
            with lock:
                if todo[0] >= todo[1] or errors:
                    return
                todo[1] -= 1
                i = todo[1]
                pending.add(i)
            try:
                res = executor.submit(_call, *task(i)).result()
            except BaseException as exc:  # re-raised by the calling thread
                with lock:
                    errors.append(exc)
                delivered.set()
                return
            store(i, res)
            delivered.set()

    threads = [threading.Thread(target=drive_worker, daemon=True) for _ in range(n_workers - 1)]
    try:
        for t in threads:
            t.start()
        while True:
            with lock:
                if errors:
                    raise errors[0]
                if todo[0] < todo[1]:
                    i: int | None = todo[0]
                    todo[0] += 1
                elif pending and not delivered.is_set():
                    i = max(pending)  # workers still starting: take over the chunk given out last
                else:
                    i = None
            if i is None:
                break
            if i not in results:
                store(i, _call(*task(i)))
        for t in threads:  # wait for the chunks still running in workers (not for taken-over ones)
            while t.is_alive() and len(results) < n_tasks and not errors:
                t.join(0.01)
    except KeyboardInterrupt:
        with lock:
            todo[0] = todo[1]  # nothing more is handed out
        executor.shutdown(wait=False, kill_workers=True)
        raise
    if len(results) < n_tasks:
        raise errors[0]
    return [results[i] for i in range(n_tasks)]


def binomial_ci(successes: int, trials: int, level: float = 0.95) -> tuple[float, float]:
    """Exact (Clopper-Pearson) confidence interval of a binomial proportion (scipy's ``binomtest``).

    Explained in the book: :doc:`/book/zb2014/glr`.

    Parameters
    ----------
    successes : int
        Number of successes, ``0 <= successes <= trials``.
    trials : int
        Number of trials, ``>= 1``.
    level : float
        Confidence level in ``(0, 1)``.

    Examples
    --------
    >>> [round(v, 4) for v in binomial_ci(3, 100)]
    [0.0062, 0.0852]
    """
    successes = integer(successes, "successes", low=0)
    trials = integer(trials, "trials", low=1)
    level = probability(level, "level")
    if not 0 <= successes <= trials or trials < 1:
        raise ModelError(
            f"successes, trials: expected 0 <= successes <= trials, trials >= 1, "
            f"got {successes}, {trials}"
        )
    return _exact_ci(int(successes), int(trials), float(level))


@functools.lru_cache(maxsize=1024)
def _exact_ci(successes: int, trials: int, level: float) -> tuple[float, float]:
    # scipy's root finding costs about 2 ms a call, and the reproductions ask for the same
    # counts many times (e.g. 0 or all of n runs): each is computed once per process. Imported
    # here: scipy.stats takes a third of a second to import, which a worker process running
    # chunks would pay at its start for nothing
    import scipy.stats

    ci = scipy.stats.binomtest(successes, trials).proportion_ci(
        confidence_level=level, method="exact"
    )
    return float(ci.low), float(ci.high)
