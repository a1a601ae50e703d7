"""Registry of paper reproductions: one function per figure or table.

A reproduction is a function ``func(*, seed, trials, jobs) -> ReproductionResult``
registered with :func:`register`. Its identifier (``zb2014-fig3``), the keys of
its ``headline`` dictionary and their meaning (documented in the function's
docstring) are a public contract used by the book, the tests and the CLI
``python -m fdi_lib reproduce ID --json``: keep them stable.

Results cache
-------------
If the environment variable ``FDI_RESULTS_CACHE`` names a directory, every call of a
registered reproduction first looks there for a result computed with the same
``(id, seed, trials, keyword arguments)`` by the same code (a hash of every source file of
:mod:`fdi_lib`, :func:`code_version`) in the same environment (Python version, machine type and
the versions of the numerical libraries), and stores what it computes. ``jobs`` and the executor
are not part of the key: results are identical for any number of jobs and on any cluster. A
keyword argument is described exactly, type included (arrays by a hash of their bytes); a run
with an argument that cannot be (an arbitrary object) is not cached. ``make book`` sets the
variable so that a result computed by a chapter is reused by the claims ledger
(:mod:`fdi_lib.reproduce.ledger`) instead of being computed twice. Without the variable
nothing is read or written.

The cache serves only what was asked: each entry stores its full key beside the result, and an
entry whose key is not the request's (a file copied or renamed) is a miss. So is anything at an
entry's path that cannot be read as an entry (damaged bytes, a folder, another format), and a
cache that cannot be written (the variable names a file) is skipped, each with a
:class:`~fdi_lib.errors.CacheWarning`: the result is computed as without a cache. Writers (threads
or processes) each write a temporary file of their own and rename it into place, so a reader
never sees half an entry. Entries are pickles: the cache directory is as trusted as the code.
"""

from __future__ import annotations

import hashlib
import dis
import functools
import json
import os
import pickle
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from fdi_lib.errors import CacheWarning, ModelError, UnknownReproductionError
from fdi_lib.validation import seed as check_seed

__all__ = [
    "DeferredPlot",
    "Reproduction",
    "ReproductionResult",
    "register",
    "get",
    "list_reproductions",
    "reproduce",
    "code_version",
    "cache_dir",
    "cached_run",
    "cached_results",
    "CACHE_ENV",
]

#: Environment variable naming the results cache directory (see the module docstring).
CACHE_ENV = "FDI_RESULTS_CACHE"


@dataclass(frozen=True)
class ReproductionResult:
    """What a reproduction returns.

    Attributes
    ----------
    id : str
        The reproduction identifier, e.g. ``"zb2014-fig3"``.
    headline : dict
        JSON-serialisable headline numbers (the ``--json`` output); keys documented
        in the reproduction function's docstring.
    paper : dict
        The values the paper states for (some of) the same keys, for side-by-side display.
    settings : dict
        Everything needed to re-run: seed, number of trials, model settings.
    data : dict
        Arrays used to draw the figure (not part of the JSON contract).
    """

    id: str
    headline: dict[str, Any]
    paper: dict[str, Any] = field(default_factory=dict)
    settings: dict[str, Any] = field(default_factory=dict)
    data: dict[str, Any] = field(default_factory=dict, repr=False)

    def to_json_dict(self) -> dict[str, Any]:
        """The JSON object printed by the CLI: ``id``, ``headline``, ``paper``, ``settings``."""
        return _jsonable(
            {
                "id": self.id,
                "headline": self.headline,
                "paper": self.paper,
                "settings": self.settings,
            }
        )

    def to_json(self, **kwargs: Any) -> str:
        return json.dumps(self.to_json_dict(), **kwargs)


@dataclass(frozen=True)
class Reproduction:
    """A registered reproduction (see :func:`register`)."""

    id: str
    paper: str
    title: str
    func: Callable[..., ReproductionResult]
    plot: Callable[..., Any] | None
    default_trials: int | None
    default_seed: int
    min_trials: int = 2
    #: Headline keys that measure this machine's wall time (they change from run to run and are
    #: never compared between runs, e.g. by the catalogue's post-build check).
    timed_keys: tuple[str, ...] = ()
    #: The chapter that shows it (``"zb2014/glr"`` for ``book/zb2014/glr.md``).
    chapter: str = ""
    #: Whether the book runs it at its chapter's seed (:data:`fdi_lib.reproduce.book.CHAPTER_SEEDS`)
    #: rather than at ``default_seed``.
    chapter_seed: bool = False
    #: Whether it runs on a surrogate or reconstructed model (the paper's model is not public).
    surrogate: bool = False
    #: Its paper claims: ``(pattern, Claim)`` pairs, the pattern an ``fnmatch`` pattern of a path
    #: of its ``paper`` dictionary (``"success_rate/*"``); see :mod:`fdi_lib.reproduce.ledger`.
    claims: tuple[tuple[str, Any], ...] = ()
    #: The book's trial count where it differs from ``default_trials`` (``None``: the default), for
    #: a study whose default costs more than a chapter can spend; the catalogue's command carries
    #: it (:func:`fdi_lib.reproduce.book.book_argv`), and the chapter says what the default gives.
    book_trials: int | None = None

    @property
    def monte_carlo(self) -> bool:
        """Whether the reproduction uses ``trials`` (a paper count, or a function that reads it)."""
        return self.default_trials is not None or self._reads("trials")

    @property
    def seeded(self) -> bool:
        """Whether the reproduction reads its ``seed`` (a deterministic one ignores it)."""
        return self._reads("seed")

    def _reads(self, name: str) -> bool:
        return any(
            ins.opname.startswith("LOAD") and ins.argval == name
            for ins in dis.get_instructions(self.func)
        )

    def check_arguments(
        self, *, seed: int | None = None, trials: int | None = None, jobs: int = 1
    ) -> None:
        """Validate ``seed`` (integer >= 0), ``trials`` (positive integer, only for a Monte Carlo
        reproduction) and ``jobs`` (non-zero integer) before anything is computed."""
        if seed is not None:
            check_seed(seed)
        if trials is not None:
            if (
                isinstance(trials, (bool, np.bool_))
                or not isinstance(trials, (int, np.integer))
                or trials < 1
            ):
                raise ModelError(f"trials: expected a positive integer, got {trials!r}")
            if not self.monte_carlo:
                raise ModelError(
                    f"trials: {self.id} is one deterministic or seeded run; expected no "
                    f"trial count, got {trials!r}"
                )
        if (
            isinstance(jobs, (bool, np.bool_))
            or not isinstance(jobs, (int, np.integer))
            or jobs == 0
        ):
            raise ModelError(f"jobs: expected a non-zero integer (-1 = all cores), got {jobs!r}")

    def __call__(
        self, *, seed: int | None = None, trials: int | None = None, jobs: int = 1, **kwargs: Any
    ) -> ReproductionResult:
        self.check_arguments(seed=seed, trials=trials, jobs=jobs)
        seed = self.default_seed if seed is None else seed
        trials = self.default_trials if trials is None else trials
        trials = None if trials is None else int(trials)
        entry = _cache_entry(self.id, int(seed), trials, kwargs)
        cached = None if entry is None else _cache_read(*entry)
        if cached is not None:
            return cached
        result = self.func(seed=int(seed), trials=trials, jobs=int(jobs), **kwargs)
        if not isinstance(result, ReproductionResult) or result.id != self.id:
            raise TypeError(
                f"reproduction {self.id!r} returned {type(result).__name__} "
                f"with id {getattr(result, 'id', None)!r}"
            )
        if entry is not None:
            _cache_write(*entry, result)
        return result


_CODE_VERSION: str | None = None


def code_version() -> str:
    """SHA-256 of the source of every module of :mod:`fdi_lib` (part of the cache key)."""
    global _CODE_VERSION
    if _CODE_VERSION is None:
        root = Path(__file__).resolve().parents[1]
        h = hashlib.sha256()
        for f in sorted(root.rglob("*.py")):
            h.update(str(f.relative_to(root)).encode())
            h.update(f.read_bytes())
        _CODE_VERSION = h.hexdigest()
    return _CODE_VERSION


def cache_dir() -> Path | None:
    """The results cache directory (``$FDI_RESULTS_CACHE``), or ``None`` when caching is off."""
    value = os.environ.get(CACHE_ENV, "").strip()
    return Path(value) if value else None


#: Distributions whose version changes a result (the numbers of a run depend on their code); with
#: the Python version and the machine type, part of every cache key.
_RESULT_LIBRARIES = (
    "numpy",
    "scipy",
    "scikit-learn",
    "cvxpy",
    "control",
    "statsmodels",
    "highspy",
    "numba",
    "pycddlib-standalone",
    "clarabel",
    "osqp",
    "scs",
)


@functools.lru_cache(maxsize=1)
def _environment() -> dict[str, Any]:
    """What besides the settings and :func:`code_version` changes a result: the Python version,
    the machine type and the versions of :data:`_RESULT_LIBRARIES` (``None`` when absent). Read
    once per process (about 50 ms: a scan of the installed distributions); treat as read-only."""
    import importlib.metadata
    import platform

    def version(name: str) -> str | None:
        try:
            return importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            return None

    return {
        "python": platform.python_version(),
        "machine": platform.machine(),
        "libraries": {name: version(name) for name in _RESULT_LIBRARIES},
    }


class _Uncacheable(Exception):
    """A keyword argument whose value has no exact, stable description (not cached)."""


def _canonical(value: Any) -> Any:
    """``value`` as JSON that tells apart every two values a reproduction could tell apart: the
    type is kept (``1``, ``1.0``, ``True`` and ``"1"`` differ), floats exactly (``float.hex``),
    arrays by dtype, shape and a hash of their bytes (``repr`` elides the middle of a large one).
    Anything else raises :class:`_Uncacheable`."""
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (int, np.integer)) and not isinstance(value, np.bool_):
        return {"int": str(int(value))}
    if isinstance(value, (float, np.floating)):
        return {"float": float(value).hex(), "type": type(value).__name__}
    if isinstance(value, np.bool_):
        return {"bool_": bool(value)}
    if isinstance(value, (list, tuple)):
        return {type(value).__name__: [_canonical(v) for v in value]}
    if isinstance(value, dict):
        if not all(isinstance(k, str) for k in value):
            raise _Uncacheable
        return {"dict": [[k, _canonical(value[k])] for k in sorted(value)]}
    if isinstance(value, np.ndarray) and value.dtype.kind in "biufc":
        data = np.ascontiguousarray(value)
        digest = hashlib.sha256(data.tobytes()).hexdigest()
        return {"array": [data.dtype.str, list(data.shape), digest]}
    raise _Uncacheable


def _cache_entry(
    id: str, seed: int, trials: int | None, kwargs: dict[str, Any]
) -> tuple[Path, dict[str, Any]] | None:
    """Where the result of these settings is cached, and its full key (stored with the result and
    compared on reading), or ``None`` when caching is off or a keyword argument cannot be
    described exactly (then the run is not cached)."""
    root = cache_dir()
    if root is None:
        return None
    try:
        options = {k: _canonical(v) for k, v in kwargs.items()}
    except _Uncacheable:
        return None
    key = {
        "id": id,
        "seed": int(seed),
        "trials": trials,
        "options": options,
        "code": code_version(),
        "environment": _environment(),
    }
    digest = hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:24]
    return root / id / f"{code_version()[:16]}-{digest}.pkl", key


def cached_run(
    id: str, *, seed: int | None = None, trials: int | None = None, **kwargs: Any
) -> ReproductionResult | None:
    """The cached result of ``reproduce(id, seed=seed, trials=trials, **kwargs)`` for the current
    code, or ``None`` if no run with exactly these settings was cached (or caching is off).

    Defaults resolve as in :meth:`Reproduction.__call__`: in a book build, this says whether a
    chapter ran ``id`` at these settings, and what it got.
    """
    rep = get(id)
    seed = rep.default_seed if seed is None else seed
    trials = rep.default_trials if trials is None else trials
    entry = _cache_entry(id, int(seed), None if trials is None else int(trials), kwargs)
    return None if entry is None else _cache_read(*entry)


def _cache_read(path: Path, key: dict[str, Any]) -> ReproductionResult | None:
    """The result cached at ``path`` for exactly ``key``, or ``None`` (a miss): see :func:`_load`;
    an entry stored for other settings (a file copied or renamed under another key) is a miss
    with a :class:`~fdi_lib.errors.CacheWarning`."""
    loaded = _load(path, key["id"])
    if loaded is None:
        return None
    stored, result = loaded
    if stored != key:
        differ = sorted(k for k in key if stored.get(k) != key[k])
        warnings.warn(
            CacheWarning(
                f"{CACHE_ENV}: the entry {path} was stored for other settings "
                f"({', '.join(differ)} differ); computing it again"
            ),
            stacklevel=3,
        )
        return None
    return result


def _load(path: Path, id: str) -> tuple[dict[str, Any], ReproductionResult] | None:
    """The key and the result of ``id`` stored at ``path``, or ``None`` (a miss). Nothing at
    ``path`` is a silent miss; anything else that is not an entry of ``id`` is a miss with a
    :class:`~fdi_lib.errors.CacheWarning` (and is replaced by the result computed instead), never
    a traceback: another kind of file (a folder), damaged bytes, another id's entry, an entry of
    the former format (a result without its key)."""
    try:
        if not path.exists() and not path.is_symlink():
            return None
        if not path.is_file():
            raise IsADirectoryError(f"expected a regular file, got a {_kind(path)}")
        path.touch()  # the newest entry of an id is the one last used (see cached_results)
        with path.open("rb") as fh:
            entry = pickle.load(fh)
    except Exception as exc:  # unpickling damaged bytes can raise almost any type (EOFError,
        # UnpicklingError, ValueError, KeyError, a stale class's AttributeError, ...): all are a miss
        warnings.warn(
            CacheWarning(
                f"{CACHE_ENV}: cannot read the cached result {path} "
                f"({type(exc).__name__}: {exc}); computing it again"
            ),
            stacklevel=4,
        )
        return None
    stored = entry.get("key") if isinstance(entry, dict) else None
    result = entry.get("result") if isinstance(entry, dict) else entry
    whole = isinstance(stored, dict) and isinstance(result, ReproductionResult)
    if not whole or result.id != id:
        got = f"{type(result).__name__} {getattr(result, 'id', '')!r}" + (
            "" if isinstance(stored, dict) else " without its key"
        )
        warnings.warn(
            CacheWarning(
                f"{CACHE_ENV}: expected a result of {id!r} in {path}, got {got}; computing it again"
            ),
            stacklevel=4,
        )
        return None
    return stored, result


def _kind(path: Path) -> str:
    if path.is_dir():
        return "folder"
    return "broken link" if path.is_symlink() and not path.exists() else "special file"


def _cache_write(path: Path, key: dict[str, Any], result: ReproductionResult) -> None:
    """Store ``result`` with its ``key`` at ``path`` atomically, through a temporary file of a name
    of its own (threads and processes writing the same entry never share one; the last rename
    wins, and each renames a complete file). A cache that cannot be written (``$FDI_RESULTS_CACHE``
    a file, no permission, disk full, a folder at ``path``) is skipped with a
    :class:`~fdi_lib.errors.CacheWarning`."""
    import tempfile

    tmp: Path | None = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
        tmp = Path(name)
        with os.fdopen(fd, "wb") as fh:
            pickle.dump({"key": key, "result": result}, fh)
        if path.is_dir() and not path.is_symlink():
            raise IsADirectoryError(21, "a folder is at the entry's path", str(path))
        tmp.replace(path)  # atomic: a concurrent reader never sees half a file
    except (pickle.PicklingError, TypeError, AttributeError):
        _unlink_quietly(tmp)  # not picklable: this result is simply not cached
    except OSError as exc:
        _unlink_quietly(tmp)
        warnings.warn(
            CacheWarning(
                f"{CACHE_ENV}: cannot store the result in {path} "
                f"({exc.strerror or exc}); not cached"
            ),
            stacklevel=3,
        )


def _unlink_quietly(path: Path | None) -> None:
    try:
        if path is not None:
            path.unlink(missing_ok=True)
    except OSError:  # its folder is not a folder: there is nothing to remove
        pass


def cached_results() -> dict[str, ReproductionResult]:
    """For each id, the cached result of the current code that was used last, if any.

    Reads ``$FDI_RESULTS_CACHE`` (empty dictionary when caching is off): in a book build,
    these are the results the chapters computed (entries of another environment, see
    :func:`_environment`, are skipped).
    """
    root = cache_dir()
    out: dict[str, ReproductionResult] = {}
    if root is not None and root.exists() and not root.is_dir():
        warnings.warn(
            CacheWarning(
                f"{CACHE_ENV}: expected a directory, got the file {root}; no cached result is read"
            ),
            stacklevel=2,
        )
    if root is None or not root.is_dir():
        return out
    prefix = code_version()[:16]
    environment = _environment()
    for sub in sorted(p for p in root.iterdir() if p.is_dir()):
        entries = sorted(sub.glob(f"{prefix}-*.pkl"), key=lambda p: p.stat().st_mtime)
        for entry in reversed(entries):  # the newest readable one (a damaged one is warned about)
            loaded = _load(entry, sub.name)
            if (
                loaded is not None
                and loaded[0].get("code") == code_version()
                and loaded[0].get("environment") == environment
            ):
                out[sub.name] = loaded[1]
                break
    return out


_REGISTRY: dict[str, Reproduction] = {}


@dataclass(frozen=True)
class DeferredPlot:
    """A figure function named by its dotted path, imported at its first call.

    The paper modules of :mod:`fdi_lib.reproduce` compute; their figures live in
    :mod:`fdi_lib.reproduce.views`, which imports them (never the reverse). A registration names
    its figure with this (``register(..., plot="fdi_lib.reproduce.views.zb2014.plot_fig1")``):
    ``rep.plot(result, fig=None)`` draws as before, and ``--json`` runs import no view.
    """

    path: str

    def resolve(self) -> Callable[..., Any]:
        """The function ``path`` names (an ``ImportError`` or ``AttributeError`` if none)."""
        import importlib

        module, _, name = self.path.rpartition(".")
        return getattr(importlib.import_module(module), name)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self.resolve()(*args, **kwargs)


def register(
    id: str,
    *,
    paper: str,
    title: str,
    chapter: str,
    default_trials: int | None = None,
    default_seed: int = 0,
    plot: str | Callable[..., Any] | None = None,
    min_trials: int = 2,
    timed_keys: tuple[str, ...] = (),
    chapter_seed: bool = False,
    surrogate: bool = False,
    claims: Mapping[str, Any] | None = None,
    book_trials: int | None = None,
) -> Callable[[Callable[..., ReproductionResult]], Callable[..., ReproductionResult]]:
    """Decorator registering a reproduction function under ``id``.

    ``default_trials`` is the paper's own number of Monte Carlo trials (``None``
    for deterministic or single-run figures); ``plot(result, fig=None)`` draws it. A paper's
    module gives ``plot`` as the dotted name of a function of its presentation module
    (``"fdi_lib.reproduce.views.zb2014.plot_fig1"``), imported when a figure is drawn: computing
    never imports presentation (:class:`DeferredPlot`).
    ``min_trials`` is the fewest trials the command line accepts: 2 where the JSON has 95 %
    intervals (they need two trials), 1 for a reproduction whose JSON has none.
    ``timed_keys`` are the headline keys that measure wall time on this machine (not
    reproducible from run to run).

    Everything the book and the claims ledger need travels with the registration: ``chapter``
    (``"zb2014/glr"``: the book document ``book/zb2014/glr.md`` that runs and shows it; the
    book's order of reproductions is that of ``_toc.yml``), ``chapter_seed`` (the book runs it at
    its chapter's seed), ``surrogate`` (it runs on a surrogate model) and ``claims``: for each
    path pattern of its ``paper`` dictionary, the :class:`~fdi_lib.reproduce.ledger_claims.Claim`
    that says where in the paper the value is, its units and how it is compared (see
    :mod:`fdi_lib.reproduce.ledger`; a paper value without a declaration fails the tests).
    ``book_trials`` is the book's trial count where a chapter cannot spend the default's time
    (``None``: the book runs ``default_trials``); it must be smaller than ``default_trials``.
    """
    if book_trials is not None and (
        isinstance(book_trials, bool)
        or not isinstance(book_trials, int)
        or default_trials is None
        or not min_trials <= book_trials < default_trials
    ):
        raise ModelError(
            f"book_trials: expected an integer in [min_trials={min_trials}, default_trials="
            f"{default_trials}), got {book_trials!r}"
        )

    def decorator(func: Callable[..., ReproductionResult]) -> Callable[..., ReproductionResult]:
        if id in _REGISTRY:
            raise ModelError(f"reproduction id {id!r} registered twice")
        _REGISTRY[id] = Reproduction(
            id=id,
            paper=paper,
            title=title,
            func=func,
            plot=DeferredPlot(plot) if isinstance(plot, str) else plot,
            default_trials=default_trials,
            default_seed=default_seed,
            min_trials=min_trials,
            timed_keys=tuple(timed_keys),
            chapter=chapter,
            chapter_seed=chapter_seed,
            surrogate=surrogate,
            claims=tuple((claims or {}).items()),
            book_trials=book_trials,
        )
        return func

    return decorator


def _load_all() -> None:
    """Import every module of :mod:`fdi_lib.reproduce` so that they register."""
    import importlib
    import pkgutil

    import fdi_lib.reproduce as pkg

    for info in pkgutil.iter_modules(pkg.__path__):
        if not info.ispkg and info.name not in {"registry", "cli"}:  # views/ registers nothing
            importlib.import_module(f"{pkg.__name__}.{info.name}")


def list_reproductions() -> list[Reproduction]:
    """All registered reproductions, sorted by identifier."""
    _load_all()
    return [_REGISTRY[k] for k in sorted(_REGISTRY)]


def get(id: str) -> Reproduction:
    """The reproduction registered under ``id`` (``UnknownReproductionError`` otherwise); the
    modules of :mod:`fdi_lib.reproduce` are imported unless ``id``'s has been already (a
    chapter's own reproductions do not import the others', e.g. numba's for the polytopes)."""
    if id not in _REGISTRY:
        _load_all()
    try:
        return _REGISTRY[id]
    except KeyError:
        known = ", ".join(sorted(_REGISTRY)) or "none"
        raise UnknownReproductionError(f"id: no reproduction {id!r}; known ids: {known}") from None


def reproduce(
    id: str, *, seed: int | None = None, trials: int | None = None, jobs: int = 1, **kwargs: Any
) -> ReproductionResult:
    """Run the reproduction ``id`` (same call as ``python -m fdi_lib reproduce ID``)."""
    return get(id)(seed=seed, trials=trials, jobs=jobs, **kwargs)


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (np.floating, float)):
        f = float(obj)
        return f if np.isfinite(f) else None
    return obj
