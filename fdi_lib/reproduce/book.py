"""The settings at which the book runs each reproduction: one source for the chapters and the catalogue.

The chapters call :func:`book_run` (never :func:`~fdi_lib.reproduce.registry.reproduce` with
their own seed), the catalogue of reproductions prints :func:`book_command`, and a test runs
every printed command against the result the chapter computed. So the command a reader copies
from the catalogue gives the numbers the book shows.

The registry's default seeds (those of ``python -m fdi_lib reproduce ID`` without ``--seed``)
are not changed by this module: a chapter that runs a reproduction at another seed says so
here, and the catalogue's command carries that seed.

:data:`CHAPTER_SEEDS` is the one seed of each chapter (its other seeded computations use it
too); a reproduction registered with ``chapter_seed=True`` runs in the book at its chapter's seed
(:func:`fdi_lib.reproduce.registry.register`: the book's settings travel with the registration).
:func:`book_settings` resolves them against the registry. :func:`book_order` is the book's order of
the reproductions (the chapters of ``_toc.yml``, then the first ``book_run`` of each in its
chapter; :func:`book_key` the place of one).
"""

from __future__ import annotations

import json
import re
import shlex
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

from fdi_lib.errors import ModelError
from fdi_lib.reproduce.registry import ReproductionResult, get, list_reproductions

__all__ = [
    "CHAPTER_SEEDS",
    "BookRun",
    "book_settings",
    "book_run",
    "book_argv",
    "book_command",
    "toc_documents",
    "book_order",
    "book_key",
    "BOOK_ROOT",
]

#: The repository holding ``_toc.yml`` and ``book/`` (absent from an installed package).
BOOK_ROOT = Path(__file__).resolve().parents[2]

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


def book_settings(id: str) -> BookRun:
    """The seed and trial count at which the book runs ``id``, resolved against the registry.

    Returns
    -------
    BookRun
        ``seed`` always an integer (the registry's default when the book sets none); ``trials``
        the registration's ``book_trials`` (a study too long for a chapter at its default), else
        the registry's default (``None`` for a reproduction without a trial count of its own).
    """
    rep = get(id)
    if rep.chapter_seed and rep.chapter not in CHAPTER_SEEDS:
        raise ModelError(
            f"chapter_seed: {id} runs at its chapter's seed; expected its chapter in "
            f"CHAPTER_SEEDS ({sorted(CHAPTER_SEEDS)}), got {rep.chapter!r}"
        )
    return BookRun(
        seed=CHAPTER_SEEDS[rep.chapter] if rep.chapter_seed else rep.default_seed,
        trials=rep.default_trials if rep.book_trials is None else rep.book_trials,
    )


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
        raise ModelError(
            f"chapter_seed: {id} reads no seed; expected chapter_seed=False, got the "
            f"chapter's seed {s.seed!r}"
        )
    if s.trials is not None:
        argv += ["--trials", str(s.trials)]
    for name, value in options.items():
        argv += ["--option", f"{name}={json.dumps(value)}"]
    return argv + ["--json"]


def book_command(id: str, **options: Any) -> str:
    """The shell command that recomputes ``id`` as the book does (:func:`book_argv`)."""
    return shlex.join(["python", "-m", "fdi_lib", *book_argv(id, **options)])


def toc_documents(root: Path | None = None) -> list[str]:
    """The documents of the book's ``_toc.yml`` under ``root`` (default :data:`BOOK_ROOT`), in
    order (``"book/zb2014/glr"``); empty when there is no ``_toc.yml`` (an installed package)."""
    import yaml

    toc_file = (BOOK_ROOT if root is None else Path(root)) / "_toc.yml"
    if not toc_file.is_file():
        return []
    files: list[str] = []

    def walk(items: Any) -> None:
        for item in items or []:
            if "file" in item:
                files.append(item["file"])
            walk(item.get("chapters")), walk(item.get("sections"))

    toc = yaml.safe_load(toc_file.read_text())
    walk(toc.get("parts")), walk(toc.get("chapters"))
    return files


@lru_cache(maxsize=None)
def _book_sources() -> tuple[list[str], dict[str, str]]:
    """The documents of ``_toc.yml`` (:func:`toc_documents`) and the text of each, read once."""
    docs = toc_documents()
    texts = {
        doc: (BOOK_ROOT / f"{doc}.md").read_text()
        for doc in docs
        if (BOOK_ROOT / f"{doc}.md").is_file()
    }
    return docs, texts


def book_key(id: str) -> tuple[int, int, str]:
    """Where the reproduction ``id`` comes in :func:`book_order`, its sort key there, from its own
    registration (no other reproduction's module imported): its chapter's place in ``_toc.yml``
    (the registration's ``chapter``), then the place of its first ``book_run("ID"`` in that
    chapter, then the identifier (without the book's sources: the identifier alone counts)."""
    docs, texts = _book_sources()
    doc = f"book/{get(id).chapter}"
    text = texts.get(doc, "")
    m = re.search(rf"""\bbook_run\(\s*["']{re.escape(id)}["']""", text)
    return docs.index(doc) if doc in docs else len(docs), m.start() if m else len(text), id


@lru_cache(maxsize=None)
def book_order() -> tuple[str, ...]:
    """Every registered reproduction in book order (sorted by :func:`book_key`; without the
    book's sources, by identifier)."""
    return tuple(sorted((r.id for r in list_reproductions()), key=book_key))
