"""Execute the book's chapters side by side on the machine's cores, into the jupyter-cache that
``make book`` then builds from (issue 35).

    python tools/execute_book.py --cache _build/.jupyter_cache-book \
                                 --config-out _build/_config_book.yml [--jobs N] [--reuse CACHE]

Why this mechanism. Jupyter Book 1.x executes the notebooks one after another while Sphinx reads
them. Two ways to run them concurrently exist in its stack, and neither fits:

- Sphinx's parallel read (``sphinx-build -j``; ``jupyter-book build`` has no such option) forks
  processes over chunks of documents in alphabetical order (15 documents on 2 cores: two chunks
  of 7, their execution times 32 s and 72 s), cannot order the claims ledger after the chapters
  whose results it reads, and needs every extension of the book to declare itself parallel-safe;
- jupyter-cache's ``local-parallel`` executor starts one process per notebook on every core, in
  no order, with one environment for all, and records a failing notebook instead of stopping.

So this script does the scheduling and leaves the rest to myst-nb's own execution mode ``cache``:

1. every document of ``_toc.yml`` that is a notebook is read as myst-nb reads it
   (``myst_nb.core.read``) and executed as myst-nb executes it (``jupyter_cache``'s
   ``single_nb_execution``, in the chapter's folder, the ``execute:`` settings of ``_config.yml``),
   on ``--jobs`` worker processes (default: the cores; each runs one chapter at a time, whose
   kernel inherits the worker's environment), the longest first (the times of the last build's
   report, ``_build/build-report.json``, else :data:`LONGEST` then the size of the code), the
   claims ledger (:data:`AFTER_ALL`) after every other chapter, as in a serial build (it reads
   the results the chapters cached, ``$FDI_RESULTS_CACHE``);
2. each chapter's Monte Carlo shares the cores without oversubscription: its kernel gets
   ``FDI_CORES`` = the cores divided among the chapters not yet finished (at least one), which
   :func:`fdi_lib.montecarlo.effective_jobs` reads as the machine's size; results do not depend
   on the number of processes, so the outputs are those of a serial build (tested:
   ``tests/test_execute_book.py`` compares the glued values);
   each kernel also leaves the explorables' small multiples for paper out of their outputs
   (``$FDI_PAPER_FIGURES`` = ``deferred``, :data:`fdi_lib.explorables.PAPER_FIGURES_ENV`): the
   HTML pages never show them, and the PDF edition draws them from the specification that takes
   their place (``tools/pdf_edition.py``), 1.5-2.7 s of each explorable's cell fewer here;
3. each executed notebook goes into the jupyter-cache ``--cache`` with its run time; a cell error
   stops the script (exit status 1, the traceback printed) before the book is built, as
   ``execute.allow_errors: false`` does in a serial build;
4. ``--config-out`` gets the book's ``_config.yml`` in execution mode ``cache`` on that cache:
   Jupyter Book then takes every chapter's outputs from it (a chapter whose code cells differ
   would be executed by the build itself, strictly, as before) and ``_ext/fdi_book.py`` writes
   the executed notebooks to ``jupyter_execute`` as a serial build does.

One line per chapter, ``<path>: Executed notebook in N seconds`` (myst-nb's own wording, which
``tools/build_report.py`` reads from the build log), and the wall time of the whole execution.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import threading
import time
from pathlib import Path
from typing import Any, NamedTuple

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO), str(REPO / "tools")]

from fdi_lib.explorables import PAPER_FIGURES_ENV  # noqa: E402
from fdi_lib.montecarlo import CORES_ENV  # noqa: E402

#: Without the times of a last build (a fresh clone), the chapters known to be the longest (issue
#: 35's measurements: 24 s, 24 s and 21 s of the book's 104 s) start first, then the others by the
#: size of their code; started last, one of them would run alone on its share at the end.
LONGEST = ("book/windturbine/benchmark", "book/zhang2021/sparse", "book/rosa2013/svo")

#: Documents that read what the others computed (the claims ledger reads the results cache that
#: the chapters fill): executed once every other document is done.
AFTER_ALL = ("book/zz-ledger",)


class Chapter(NamedTuple):
    doc: str  # document name, as in _toc.yml ("book/zb2014/glr")
    path: Path  # its source file
    notebook: Any  # as myst-nb reads it (nbformat.NotebookNode)
    weight: float  # expected run time (any unit): the longest are started first


def toc_documents(toc: Path) -> list[str]:
    """Every document of ``_toc.yml``, in book order."""
    import yaml

    out: list[str] = []

    def walk(node) -> None:
        if isinstance(node, dict):
            for key in ("root", "file"):
                if isinstance(node.get(key), str):
                    out.append(node[key].removesuffix(".md").removesuffix(".ipynb"))
            for value in node.values():
                if isinstance(value, (list, dict)):
                    walk(value)
        elif isinstance(node, list):
            for item in node:
                walk(item)

    walk(yaml.safe_load(toc.read_text()))
    return list(dict.fromkeys(out))


def read_notebook(path: Path):
    """The notebook of ``path`` as myst-nb reads it, or ``None`` for a page that is not one."""
    from myst_nb.core.config import NbParserConfig
    from myst_nb.core.read import create_nb_reader
    from myst_parser.config.main import MdParserConfig

    text = path.read_text()
    reader = create_nb_reader(str(path), MdParserConfig(), NbParserConfig(), text)
    return None if reader is None else reader.read(text)


def chapters(root: Path, toc: Path, times: dict[str, float]) -> list[Chapter]:
    """The notebooks of the book with at least one code cell, each weighted by its last run
    time (``times``, keyed by source path) or else by :data:`LONGEST` and the characters of its
    code cells."""
    out = []
    for doc in toc_documents(toc):
        path = next((p for p in (root / f"{doc}.md", root / f"{doc}.ipynb") if p.is_file()), None)
        nb = None if path is None else read_notebook(path)
        code = [c.source for c in nb.cells if c.cell_type == "code"] if nb is not None else []
        if code:
            rel = path.relative_to(root).as_posix()
            size = sum(map(len, code)) / 1e6  # below the hint's 1, 2, 3 for any chapter
            weight = times.get(rel, len(LONGEST) - LONGEST.index(doc) if doc in LONGEST else size)
            out.append(Chapter(doc, path, nb, weight))
    return out


def execution_settings(config: Path) -> dict:
    """``timeout`` and ``allow_errors`` of the ``execute:`` section of ``_config.yml``."""
    import yaml

    execute = yaml.safe_load(config.read_text()).get("execute", {})
    if execute.get("run_in_temp"):
        raise SystemExit(f"{config}: execute.run_in_temp is not supported by {Path(__file__).name}")
    return {
        "timeout": execute.get("timeout", 30),
        "allow_errors": bool(execute.get("allow_errors", False)),
    }


def execute(
    path: str, notebook: str, cores: int, timeout: int, allow_errors: bool
) -> tuple[float | None, str]:
    """In a worker process: execute ``notebook`` (JSON, as read from the chapter ``path``) in the
    chapter's folder as myst-nb does, its kernel on ``cores`` cores (``$FDI_CORES``, which the
    kernel inherits: a worker runs one chapter at a time; the explorables' paper figures
    deferred, ``$FDI_PAPER_FIGURES``); returns the run time and the executed
    notebook, or ``None`` and the traceback."""
    import nbformat
    from jupyter_cache.executors.utils import single_nb_execution

    os.environ[CORES_ENV] = str(cores)
    os.environ[PAPER_FIGURES_ENV] = "deferred"
    nb = nbformat.reads(notebook, as_version=4)
    result = single_nb_execution(
        nb,
        cwd=str(Path(path).parent),
        timeout=timeout,
        allow_errors=allow_errors,
        meta_override=True,
    )
    if result.err is not None:
        return None, f"{type(result.err).__name__}\n{result.exc_string}"
    return result.time, nbformat.writes(result.nb)


class Scheduler:
    """Runs the chapters, ``jobs`` at a time, and caches each executed notebook."""

    def __init__(
        self,
        chapters: list[Chapter],
        cache_dir: Path,
        jobs: int,
        cores: int,
        settings: dict,
        root: Path,
    ) -> None:
        from jupyter_cache import get_cache

        from pdf_edition import library_hash

        self.cache = get_cache(str(cache_dir))
        self.library = library_hash()
        self.root, self.jobs, self.cores, self.settings = root, jobs, cores, settings
        self.lock = threading.Lock()
        self.unfinished = len(chapters)
        self.failed: list[str] = []
        self.times: dict[str, float] = {}

    def share(self) -> int:
        """The cores of one more chapter: all of them divided among the chapters not finished."""
        with self.lock:
            return max(1, self.cores // max(1, min(self.jobs, self.unfinished)))

    def reuse(self, chapters: list[Chapter], other: Path) -> list[Chapter]:
        """Copy from the jupyter-cache ``other`` every chapter whose code cells it holds executed
        (jupyter-cache's hash of the code and the kernel) with the library of now (the hash of
        ``fdi_lib``'s sources recorded with it), with its run time there; the chapters left to
        execute."""
        from jupyter_cache import get_cache
        from jupyter_cache.base import CacheBundleIn

        if not other.is_dir():
            return chapters
        source, left = get_cache(str(other)), []
        for chapter in chapters:
            try:
                record = source.match_cache_notebook(chapter.notebook)
            except KeyError:
                record = None
            if record is None or record.data.get("library") != self.library:
                left.append(chapter)
                continue
            nb = source.get_cache_bundle(record.pk).nb
            bundle = CacheBundleIn(nb, str(chapter.path), data=dict(record.data))
            self.cache.cache_notebook_bundle(bundle, check_validity=False, overwrite=True)
            self.unfinished -= 1
            print(
                f"{chapter.path.relative_to(self.root).as_posix()}: the same code cells as in "
                f"{other}: its outputs reused",
                flush=True,
            )
        return left

    def run(self, chapter: Chapter, workers) -> None:
        import nbformat
        from jupyter_cache.base import CacheBundleIn

        if self.failed:
            return  # a chapter failed: start no other one
        cores = self.share()
        try:
            seconds, out = workers.submit(
                execute,
                str(chapter.path),
                nbformat.writes(chapter.notebook),
                cores,
                self.settings["timeout"],
                self.settings["allow_errors"],
            ).result()
        except Exception as exc:  # the worker process died (killed, out of memory)
            seconds, out = None, f"{type(exc).__name__}: {exc}"
        rel = chapter.path.relative_to(self.root).as_posix()
        with self.lock:
            self.unfinished -= 1
            if seconds is None:
                print(f"{rel}: executing the notebook failed: {out}", file=sys.stderr, flush=True)
                self.failed.append(rel)
                return
            nb = nbformat.reads(out, as_version=4)
            self.cache.cache_notebook_bundle(
                CacheBundleIn(
                    nb,
                    str(chapter.path),
                    data={"execution_seconds": seconds, "library": self.library},
                ),
                check_validity=False,
                overwrite=True,
            )
            self.times[rel] = seconds
            print(
                f"{rel}: Executed notebook in {seconds:.2f} seconds (on {cores} "
                f"core{'s' * (cores > 1)})",
                flush=True,
            )

    def run_all(self, batches: list[list[Chapter]]) -> None:
        """Each batch after the previous one, its chapters on ``jobs`` worker processes (started
        once: the imports of nbclient and nbformat, seconds of CPU, are paid per worker, not per
        chapter), driven by as many threads of this process."""
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

        context = multiprocessing.get_context("spawn")  # this process has threads: no fork
        with ProcessPoolExecutor(max_workers=self.jobs, mp_context=context) as workers:
            for batch in batches:
                with ThreadPoolExecutor(max_workers=self.jobs) as pool:
                    list(pool.map(lambda c: self.run(c, workers), batch))


def write_config(config: Path, cache_dir: Path, target: Path) -> None:
    """The book's ``_config.yml`` in execution mode ``cache`` on ``cache_dir`` (the PDF edition's
    :func:`pdf_edition.pdf_config`: local extensions made absolute) at ``target``."""
    from pdf_edition import pdf_config

    pdf_config(config.parent, cache_dir.resolve(), target)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--root", type=Path, default=REPO, help="the book's folder (_config.yml, _toc.yml)"
    )
    parser.add_argument(
        "--cache", type=Path, required=True, help="the jupyter-cache to fill (emptied first)"
    )
    parser.add_argument(
        "--config-out", type=Path, help="write the build's _config.yml (mode cache) here"
    )
    parser.add_argument(
        "--jobs", type=int, default=0, help="chapters at a time (default: the cores)"
    )
    parser.add_argument("--only", nargs="*", help="only these documents (e.g. book/zb2014/glr)")
    parser.add_argument(
        "--reuse",
        type=Path,
        help="a jupyter-cache of the same library (make book's): a chapter whose "
        "code cells it holds executed is taken from it, not executed",
    )
    parser.add_argument(
        "--report",
        type=Path,
        default=REPO / "_build" / "build-report.json",
        help="the last build's report, whose run times order the chapters",
    )
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    import shutil

    import joblib

    root = args.root.resolve()
    cores = max(1, int(joblib.cpu_count()))  # loky's count, as fdi_lib.montecarlo uses
    jobs = cores if args.jobs <= 0 else args.jobs
    times = {}
    if args.report.is_file():
        try:
            times = json.loads(args.report.read_text()).get("execution_s") or {}
            times = {str(k): float(v) for k, v in times.items()}
        except (ValueError, TypeError, AttributeError):
            times = {}  # an unreadable report orders as a fresh clone does
    todo = chapters(root, root / "_toc.yml", times)
    if args.only is not None:
        todo = [c for c in todo if c.doc in args.only]
    last = [c for c in todo if c.doc in AFTER_ALL]
    first = sorted((c for c in todo if c.doc not in AFTER_ALL), key=lambda c: -c.weight)
    if args.cache.exists():
        shutil.rmtree(args.cache)
    settings = execution_settings(root / "_config.yml")
    print(f"Executing {len(todo)} notebooks, {jobs} at a time on {cores} cores", flush=True)
    start = time.perf_counter()
    scheduler = Scheduler(todo, args.cache, jobs, cores, settings, root)
    if args.reuse is not None:
        reuse = args.reuse.resolve()
        first, last = scheduler.reuse(first, reuse), scheduler.reuse(last, reuse)
    scheduler.run_all([b for b in (first, last) if b])
    wall = time.perf_counter() - start
    if scheduler.failed:
        print(
            f"Execution failed: {', '.join(scheduler.failed)} (traceback above); the book is "
            "not built",
            file=sys.stderr,
        )
        return 1
    print(
        f"Executed {len(todo)} notebooks in {wall:.1f} s of wall time "
        f"({sum(scheduler.times.values()):.1f} s summed over the chapters)",
        flush=True,
    )
    if args.config_out is not None:
        write_config(root / "_config.yml", args.cache, args.config_out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
