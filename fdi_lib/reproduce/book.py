"""The settings at which the book runs each reproduction: one source for the chapters and the catalogue.

The chapters call :func:`book_run` (never :func:`~fdi_lib.reproduce.registry.reproduce` with
their own seed), the catalogue of reproductions prints :func:`book_command`, and a test runs
every printed command against the result the chapter computed. So the command a reader copies
from the catalogue gives the numbers the book shows.

The registry's default seeds (those of ``python -m fdi_lib reproduce ID`` without ``--seed``)
are not changed by this module: a chapter that runs a reproduction at another seed says so
here, and the catalogue's command carries that seed.

:data:`CHAPTER_SEEDS` is the one seed of each chapter (its other seeded computations use it
too); :data:`BOOK_RUNS` lists the reproductions the book runs at settings other than the
registry's defaults. :func:`book_settings` resolves both against the registry.
"""

from __future__ import annotations

import json
import shlex
from dataclasses import dataclass
from typing import Any

from fdi_lib.errors import ModelError
from fdi_lib.reproduce.registry import ReproductionResult, get

__all__ = ["CHAPTER_SEEDS", "BOOK_RUNS", "BookRun", "book_settings", "book_run", "book_argv",
           "book_command"]

#: The one seed of each chapter (``book/<paper>/<chapter>.md``), for its reproductions and for
#: its own seeded computations.
CHAPTER_SEEDS: dict[str, int] = {
    "zb2014/signature": 2014,
    "zb2014/glr": 2015,
    "zb2014/pipeline": 0,
    "bz/parametric-nonparametric": 2015,
    "rosa2013/svo": 2013,
    "windturbine/benchmark": 2009,
}


@dataclass(frozen=True)
class BookRun:
    """Settings of one reproduction in the book.

    Attributes
    ----------
    seed : int or None
        Seed passed to the reproduction (``None``: the registry's default seed).
    trials : int or None
        Monte Carlo trials (``None``: the registry's default, the paper's count when it has one).
    """

    seed: int | None = None
    trials: int | None = None


_GLR, _BZ, _SVO = (CHAPTER_SEEDS[c] for c in ("zb2014/glr", "bz/parametric-nonparametric", "rosa2013/svo"))

#: Reproductions that the book runs at other settings than the registry's defaults.
BOOK_RUNS: dict[str, BookRun] = {
    "zb2014-fig3": BookRun(seed=_GLR),
    "zb2014-fig4": BookRun(seed=_GLR),
    "bz-whiteness": BookRun(seed=_BZ),
    "bz-solution1": BookRun(seed=_BZ),
    "bz-solution2": BookRun(seed=_BZ),
    "rosa2013-fig8": BookRun(seed=_SVO),
    "rosa2013-fig9": BookRun(seed=_SVO),
    "rosa2013-fig10": BookRun(seed=_SVO),
    "rosa2013-fig11": BookRun(seed=_SVO),   # the paper's 10 runs per case (the default)
    "rosa2013-fig12": BookRun(seed=_SVO),
    "rosa2013-fig11-rad": BookRun(seed=_SVO),   # the paper's 10 too (2 s at 2 jobs)
    "rosa2013-fig12-rad": BookRun(seed=_SVO),
    "rosa2013-timing": BookRun(seed=_SVO),
    "windturbine-scoreboard": BookRun(seed=CHAPTER_SEEDS["windturbine/benchmark"]),   # 10 realisations (the default)
    # 5 realisations of each sensor fault (about 2 s of CPU each with the four methods)
    "windturbine-accommodation": BookRun(seed=CHAPTER_SEEDS["windturbine/benchmark"], trials=5),
}


def book_settings(id: str) -> BookRun:
    """The seed and trial count at which the book runs ``id``, resolved against the registry.

    Returns
    -------
    BookRun
        ``seed`` always an integer (the registry's default when the book sets none); ``trials``
        the book's count, else the registry's default (``None`` for a reproduction without a
        trial count of its own).
    """
    rep = get(id)
    run = BOOK_RUNS.get(id, BookRun())
    return BookRun(seed=rep.default_seed if run.seed is None else run.seed,
                   trials=rep.default_trials if run.trials is None else run.trials)


def book_run(id: str, *, jobs: int = 1, **options: Any) -> ReproductionResult:
    """Run ``id`` at the book's settings (:func:`book_settings`); ``jobs`` changes no result.

    ``options`` are the reproduction's own keyword options (e.g. ``isolation_window`` of
    ``zb2014-fig8``), as ``--option NAME=VALUE`` on the command line (:func:`book_argv`). The
    claims ledger reads the run without options (:func:`fdi_lib.reproduce.ledger.collect_results`).
    """
    s = book_settings(id)
    return get(id)(seed=s.seed, trials=s.trials, jobs=jobs, **options)


def book_argv(id: str, **options: Any) -> list[str]:
    """Arguments of ``python -m fdi_lib`` that recompute ``id`` as the book does, with ``--json``
    (``options`` as ``--option NAME=VALUE``, values in JSON).

    ``--seed`` appears for every reproduction that reads its seed, ``--trials`` for every one
    with a trial count, so the command does not depend on the registry's defaults.
    """
    rep = get(id)
    s = book_settings(id)
    argv = ["reproduce", id]
    if rep.seeded:
        argv += ["--seed", str(s.seed)]
    elif s.seed != rep.default_seed:
        raise ModelError(f"BOOK_RUNS[{id!r}].seed: {id} reads no seed; expected none, got {s.seed!r}")
    if s.trials is not None:
        argv += ["--trials", str(s.trials)]
    for name, value in options.items():
        argv += ["--option", f"{name}={json.dumps(value)}"]
    return argv + ["--json"]


def book_command(id: str, **options: Any) -> str:
    """The shell command that recomputes ``id`` as the book does (:func:`book_argv`)."""
    return shlex.join(["python", "-m", "fdi_lib", *book_argv(id, **options)])

