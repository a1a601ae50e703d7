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

from typing import Any, Callable, Sequence

import numpy as np
import scipy.stats

from fdi_lib.errors import ModelError, ShapeError
from fdi_lib.models import LTVModel
from fdi_lib.simulate import Noise, draw_noise, noise_roots
from fdi_lib.validation import integer, probability, seed as check_seed

__all__ = ["trial_seeds", "trial_rngs", "run_monte_carlo", "run_monte_carlo_many", "draw_noise_batch", "binomial_ci",
           "default_chunk_size"]

ChunkFn = Callable[[Sequence[np.random.SeedSequence]], dict[str, np.ndarray]]


def trial_seeds(seed: int, n_trials: int) -> list[np.random.SeedSequence]:
    """One independent :class:`~numpy.random.SeedSequence` per realisation.

    ``seed`` is an integer >= 0, ``n_trials`` the number of realisations (>= 1).
    """
    seed = check_seed(seed)
    n_trials = integer(n_trials, "n_trials", low=1)
    return np.random.SeedSequence(seed).spawn(n_trials)


def trial_rngs(seeds: Sequence[np.random.SeedSequence]) -> list[np.random.Generator]:
    """A :class:`~numpy.random.Generator` per seed sequence of ``seeds``."""
    return [np.random.default_rng(s) for s in seeds]


def draw_noise_batch(model: LTVModel, seeds: Sequence[np.random.SeedSequence]) -> Noise:
    """Noise of ``model`` for a chunk of realisations, one per entry of ``seeds`` (each its own
    stream), stacked on axis 0."""
    roots = noise_roots(model)  # covariance roots shared by all the draws
    draws = [draw_noise(model, rng, roots=roots) for rng in trial_rngs(seeds)]
    return Noise(x0=np.stack([d.x0 for d in draws]), w=np.stack([d.w for d in draws]),
                 v=np.stack([d.v for d in draws]))


def default_chunk_size(n_trials: int) -> int:
    """Default realisations per chunk for ``n_trials``: ``min(250, ceil(n_trials / 4))``, independent of the job count.

    Four chunks or more keep two workers busy; about 250 realisations per chunk
    amortise the noise-independent work of a chunk (e.g. the windowed GLR's
    ``Gamma_k(r)``, ``C_k(r)``) while keeping its arrays small (a few MiB).
    """
    return max(1, min(250, -(-int(n_trials) // 4)))


def _chunks(n: int, size: int) -> list[slice]:
    return [slice(i, min(i + size, n)) for i in range(0, n, size)]


def run_monte_carlo(chunk_fn: ChunkFn, n_trials: int, *, seed: int, jobs: int = 1,
                    chunk_size: int | None = None, progress: bool = False,
                    description: str = "Monte Carlo") -> dict[str, np.ndarray]:
    """Run ``n_trials`` realisations of ``chunk_fn`` and concatenate the results.

    Parameters
    ----------
    chunk_fn : callable
        ``chunk_fn(seeds) -> dict`` of arrays whose leading axis has ``len(seeds)``
        entries, one per realisation (must be a picklable module-level function or
        :func:`functools.partial` for ``jobs != 1``).
    n_trials : int
        Number of realisations.
    seed : int
        Root seed; realisation ``i`` uses ``SeedSequence(seed).spawn(n_trials)[i]``.
    jobs : int
        Parallel workers (joblib, processes); ``-1`` for all cores.
    chunk_size : int, optional
        Realisations per call of ``chunk_fn``; default :func:`default_chunk_size`, which
        does not depend on ``jobs`` (same chunks, hence bit-identical results, for any
        number of workers). Changes only memory and speed when ``chunk_fn`` is exactly
        batch-invariant; give it explicitly to reproduce a run bit for bit.
    progress : bool
        Show a tqdm progress bar over chunks.
    description : str
        Label of the progress bar.

    Returns
    -------
    dict of numpy.ndarray
        Each entry concatenated over realisations (leading axis ``n_trials``).
    """
    return run_monte_carlo_many([chunk_fn], n_trials, seed=seed, jobs=jobs, chunk_size=chunk_size,
                                progress=progress, description=description)[0]


def run_monte_carlo_many(chunk_fns: Sequence[ChunkFn], n_trials: int, *, seed: int, jobs: int = 1,
                         chunk_size: int | None = None, progress: bool = False,
                         description: str = "Monte Carlo") -> list[dict[str, np.ndarray]]:
    """:func:`run_monte_carlo` of several chunk functions on the same realisations, in one pool.

    E.g. the columns of a table (common random numbers: realisation ``i`` of every column uses
    the same seed). Result ``c`` is exactly ``run_monte_carlo(chunk_fns[c], n_trials, ...)``
    with the same arguments; but the chunks of all the columns are handed out together, so
    that no process waits at the end of a column for the others to finish theirs.

    Parameters
    ----------
    chunk_fns : sequence of callable
        Chunk functions, as ``chunk_fn`` of :func:`run_monte_carlo`.
    n_trials, seed, jobs, chunk_size, progress, description
        As in :func:`run_monte_carlo` (the progress bar counts the chunks of all the functions).

    Returns
    -------
    list of dict of numpy.ndarray
        One per chunk function, as :func:`run_monte_carlo` returns.
    """
    seeds = trial_seeds(seed, n_trials)
    if isinstance(jobs, (bool, np.bool_)) or not isinstance(jobs, (int, np.integer)) or jobs == 0:
        raise ModelError(f"jobs: expected a non-zero integer (-1 = all cores), got {jobs!r}")
    chunk_fns = list(chunk_fns)
    if not chunk_fns:
        raise ModelError("chunk_fns: expected at least one chunk function, got none")
    import joblib

    n_workers = joblib.cpu_count() if jobs < 0 else int(jobs)
    if chunk_size is None:
        chunk_size = default_chunk_size(n_trials)
    chunk_size = integer(chunk_size, "chunk_size", low=1)
    parts = _chunks(len(seeds), int(chunk_size))
    tasks = [(fn, seeds[sl]) for fn in chunk_fns for sl in parts]
    if progress:
        from tqdm.auto import tqdm

        bar: Any = tqdm(total=len(tasks), desc=description, unit="chunk")
    else:
        bar = None
    results = _run_chunks(tasks, n_workers, None if bar is None else bar.update)
    if bar is not None:
        bar.close()
    outs = []
    for c in range(len(chunk_fns)):
        col = results[c * len(parts): (c + 1) * len(parts)]
        out = {}
        for key in col[0].keys():
            arrays = [np.asarray(r[key]) for r in col]
            for sl, arr in zip(parts, arrays):
                if arr.shape[:1] != (sl.stop - sl.start,):
                    raise ShapeError(f"chunk_fn: entry {key!r} must have one row per realisation "
                                     f"({sl.stop - sl.start}), got shape {arr.shape}")
            out[key] = np.concatenate(arrays, axis=0)
        outs.append(out)
    return outs


def _call(chunk_fn: ChunkFn, seeds: Sequence[np.random.SeedSequence]) -> dict[str, np.ndarray]:
    """One chunk, with the BLAS on one thread (the same floating-point operations in every process)."""
    from fdi_lib.threads import blas_single_thread

    with blas_single_thread():
        return chunk_fn(seeds)


def _run_chunks(tasks: list[tuple[ChunkFn, Sequence[np.random.SeedSequence]]], n_workers: int,
                done: Callable[[], Any] | None) -> list[dict[str, np.ndarray]]:
    """Results of every task ``(chunk_fn, seeds)`` (a chunk), in order, on this process and
    ``n_workers - 1`` others.

    The calling process computes chunks too: it is warm (modules imported, per-process caches of
    a chunk function's set-up filled), while a worker process pays its start-up (about a second
    of imports) and its caches once. Chunks are handed out one at a time: this process takes them
    from the front, each worker (driven by a thread of this process) the next one from the back as
    soon as it is free. When no new chunk is left and no worker has delivered yet (still
    starting), this process recomputes a pending chunk rather than wait for it (the result is the
    same): more jobs are never much slower than one. Workers are a reusable loky pool, kept
    between calls: the start-up is paid once per session.
    """
    if n_workers == 1 or len(tasks) == 1:
        out = []
        for task in tasks:
            out.append(_call(*task))
            if done is not None:
                done()
        return out
    import threading
    import warnings

    from joblib.externals.loky import get_reusable_executor

    with warnings.catch_warnings():  # a new size waits for chunks left running by a takeover
        warnings.filterwarnings("ignore", "Trying to resize an executor", UserWarning)
        executor = get_reusable_executor(max_workers=n_workers - 1, timeout=600)
    lock = threading.Lock()
    delivered = threading.Event()  # a worker has delivered a chunk (set) or failed
    todo = list(range(len(tasks)))
    pending: set[int] = set()
    results: dict[int, dict[str, np.ndarray]] = {}
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
                if not todo or errors:
                    return
                i = todo.pop()
                pending.add(i)
            try:
                res = executor.submit(_call, *tasks[i]).result()
            except BaseException as exc:  # re-raised by the calling thread
                with lock:
                    errors.append(exc)
                delivered.set()
                return
            store(i, res)
            delivered.set()

    threads = [threading.Thread(target=drive_worker, daemon=True) for _ in range(n_workers - 1)]
    for t in threads:
        t.start()
    while True:
        with lock:
            if errors:
                raise errors[0]
            if todo:
                i: int | None = todo.pop(0)
            elif pending and not delivered.is_set():
                i = max(pending)  # workers still starting: take over the chunk given out last
            else:
                i = None
        if i is None:
            break
        if i not in results:
            store(i, _call(*tasks[i]))
    for t in threads:  # wait for the chunks still running in workers (not for taken-over ones)
        while t.is_alive() and len(results) < len(tasks) and not errors:
            t.join(0.01)
    if len(results) < len(tasks):
        raise errors[0]
    return [results[i] for i in range(len(tasks))]

def binomial_ci(successes: int, trials: int, level: float = 0.95) -> tuple[float, float]:
    """Exact (Clopper-Pearson) confidence interval of a binomial proportion (scipy's ``binomtest``).

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
        raise ModelError(f"successes, trials: expected 0 <= successes <= trials, trials >= 1, "
                         f"got {successes}, {trials}")
    ci = scipy.stats.binomtest(int(successes), int(trials)).proportion_ci(confidence_level=level,
                                                                        method="exact")
    return float(ci.low), float(ci.high)

