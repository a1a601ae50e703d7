"""Command line: ``python -m fdi_lib reproduce [--list | --ledger | ID [--seed S] [--trials N]
[--jobs J | --cluster local:N | --cluster tcp://HOST:PORT] [--option NAME=VALUE ...] [--json]]``.

``--option NAME=VALUE`` passes a keyword option of the reproduction (listed by ``--describe``),
e.g. ``zb2014-fig8 --option isolation_window=record_end``.

``--cluster`` runs the Monte Carlo chunks on a Dask cluster (:func:`fdi_lib.montecarlo.dask_executor`):
``local:N`` starts ``N`` worker processes on this machine for the run and stops them at its end,
``tcp://HOST:PORT`` uses the scheduler at that address. The chunks and their seeds are those of
``--jobs 1``, so the ``--json`` output is the same bytes. The UAV studies of Rosa 2013, which keep
their own pool, then run in this process. A scheduler that cannot be reached is one ``error:`` line.

``--ledger`` prints the claims ledger (:mod:`fdi_lib.reproduce.ledger`): every value the
papers state, ours, and the computed status; with ``--json``, one object
``{"counts", "counts_by_paper", "mission", "rows", "sources"}``, the same bytes on every run, at any
``--jobs`` and with ``--cluster`` (the wall times of the runs it makes are printed only without
``--json``); ``--trials N`` caps the Monte Carlo trials of the runs it makes (results cached by a
book build, ``$FDI_RESULTS_CACHE``, are read instead); ``--jobs``/``--cluster`` run them in parallel
or on a cluster.

``--json`` prints exactly one JSON object ``{"id", "headline", "paper", "settings"}``
on standard output; the ``headline`` keys of each identifier are documented in
the docstring of its reproduction function (``--describe ID`` prints it).

Standard error carries everything else, one line each: ``error: ...`` (exit code 2),
``warning: ...`` (e.g. ``--jobs`` above the number of CPU cores, which is then used instead:
results do not depend on it), a progress bar over the chunks of Monte Carlo runs longer than a
second when standard error is a terminal (``--progress`` / ``--no-progress`` to choose), and
``interrupted`` on Ctrl-C (SIGINT; exit code 130, the worker processes stopped, a local cluster
shut down).
"""

from __future__ import annotations

import argparse
import contextlib
import inspect
import sys
import warnings
from pathlib import Path
from typing import Any, Callable

from fdi_lib.errors import FDIError, ModelError
from fdi_lib.montecarlo import dask_executor, effective_jobs, progress_bars, use_executor
from fdi_lib.reproduce.registry import get, list_reproductions
from fdi_lib.validation import integer, seed as check_seed


class _Parser(argparse.ArgumentParser):
    """Argument errors as one line on standard error and exit code 2 (no usage block)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        print(f"error: {message} (see {self.prog} --help)", file=sys.stderr)
        raise SystemExit(2)


def _check_plot(path: str) -> None:
    """``--plot FILE``: an existing folder and an image format matplotlib writes."""
    folder = Path(path).expanduser().resolve().parent
    if not folder.is_dir():
        raise ModelError(
            f"--plot: expected a file in an existing folder, got {path!r} ({folder} does not exist)"
        )
    suffix = Path(path).suffix.lstrip(".").lower()
    if suffix:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        formats = FigureCanvasAgg(Figure()).get_supported_filetypes()
        if suffix not in formats:
            raise ModelError(
                f"--plot: expected an image file ({', '.join(sorted(formats))}), got {path!r}"
            )


def _integer_type(check: Callable[[int], Any]) -> Callable[[str], int]:
    """An argparse ``type``: the text as an integer that passes ``check`` (a validation function
    raising an :class:`~fdi_lib.errors.FDIError`), else argparse's usage error, at once."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"invalid int value: {text!r}") from None
        try:
            check(value)
        except FDIError as exc:  # its message names the argument: argparse names the option
            raise argparse.ArgumentTypeError(str(exc).partition(": ")[2]) from None
        return value

    return parse


def _jobs(value: int) -> None:
    if value == 0:
        raise ModelError(f"jobs: expected a non-zero integer (-1 = all cores), got {value}")


#: The options each use of the command reads; any other one given is a usage error, rather than
#: an option silently ignored while a long run goes on.
_READS = {
    "--list": (),
    "--describe": (),
    "--ledger": ("--json", "--trials", "--jobs", "--cluster", "--progress"),
    "ID": (
        "--json",
        "--seed",
        "--trials",
        "--jobs",
        "--cluster",
        "--progress",
        "--option",
        "--plot",
    ),
}


def _given(args: argparse.Namespace) -> list[str]:
    """The options of ``args`` given on the command line (each default is ``None``, ``False`` or
    empty)."""
    names = ("json", "seed", "trials", "jobs", "cluster", "progress", "option", "plot")
    return [f"--{n}" for n in names if getattr(args, n) not in (None, False, [])]


def _check_applies(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """A usage error (exit 2) for a combination whose options would not all be read."""
    modes = [
        m
        for m, on in (
            ("--list", args.list),
            ("--ledger", args.ledger),
            ("--describe", args.describe),
        )
        if on
    ]
    if args.id and args.describe:
        modes = ["--describe"] + [m for m in modes if m != "--describe"]
    elif args.id:
        modes.insert(0, "ID")
    if not modes:
        parser.error("give a reproduction ID, --list or --ledger")
    if len(modes) > 1:
        parser.error(f"{modes[0]} and {modes[1]} do not go together".replace("ID and", "an ID and"))
    if modes == ["--describe"] and not args.id:
        parser.error("--describe needs a reproduction ID")
    extra = [o for o in _given(args) if o not in _READS[modes[0]]]
    if extra:
        what = {"ID": "a reproduction"}.get(modes[0], modes[0])
        parser.error(
            f"{extra[0]} does not apply to {what} (it reads "
            f"{', '.join(_READS[modes[0]]) or 'no other option'})"
        )


def _parser(prog: str = "python -m fdi_lib") -> argparse.ArgumentParser:
    """The command line's parser: ``python -m fdi_lib reproduce ...`` (default), or the
    ``reproduce`` command alone under the name ``prog`` (``fdi-reproduce``, the console script)."""
    return _parsers(prog)[0]


def _parsers(prog: str) -> tuple[argparse.ArgumentParser, argparse.ArgumentParser]:
    """:func:`_parser` and the parser of its ``reproduce`` command (the same one for a console
    script), whose usage errors name the command."""
    console = prog != "python -m fdi_lib"
    name = prog if console else f"{prog} reproduce"
    description = __doc__.replace("python -m fdi_lib reproduce", name)
    raw = argparse.RawDescriptionHelpFormatter
    parser = _Parser(prog=prog, description=description, formatter_class=raw)
    if console:
        rep = parser
    else:
        sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
        rep = sub.add_parser(
            "reproduce",
            help="reproduce a figure or table of the papers",
            description=description,
            formatter_class=raw,
        )
    rep.add_argument("id", nargs="?", help="reproduction identifier, e.g. zb2014-fig3")
    rep.add_argument("--list", action="store_true", help="list the identifiers and exit")
    rep.add_argument(
        "--ledger",
        action="store_true",
        help="print the claims ledger of the four papers (with --json: one object)",
    )
    rep.add_argument(
        "--describe", action="store_true", help="print the documentation of ID and exit"
    )
    rep.add_argument(
        "--seed",
        type=_integer_type(check_seed),
        default=None,
        help="random seed, an integer >= 0 (default: the reproduction's)",
    )
    rep.add_argument(
        "--trials",
        type=_integer_type(lambda n: integer(n, "trials", low=1)),
        default=None,
        help="Monte Carlo trials (default: the paper's own count)",
    )
    where = rep.add_mutually_exclusive_group()
    where.add_argument(
        "--jobs",
        type=_integer_type(_jobs),
        default=None,
        help="parallel jobs, -1 for all cores (default 1)",
    )
    where.add_argument(
        "--cluster",
        metavar="local:N|tcp://HOST:PORT",
        default=None,
        help="run the Monte Carlo chunks on a Dask cluster: N local worker "
        "processes started for the run, or an existing scheduler (same "
        "results as --jobs 1)",
    )
    rep.add_argument(
        "--progress",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="progress bar over the Monte Carlo chunks on standard error (default: when "
        "standard error is a terminal)",
    )
    rep.add_argument(
        "--option",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="a keyword option of the reproduction (its --describe lists them), VALUE "
        "in JSON or a plain string, e.g. isolation_window=record_end; repeatable",
    )
    rep.add_argument(
        "--json", action="store_true", help="print one JSON object of headline numbers"
    )
    rep.add_argument("--plot", metavar="FILE", default=None, help="also save the figure to FILE")
    return parser, rep


#: Exit code of an interrupted run (SIGINT): 128 + 2, as a shell reports it.
EXIT_INTERRUPTED = 130


def _warning_line(message: Any, category: type[Warning], *args: Any, **kwargs: Any) -> None:
    """A warning as one line on standard error (no file, line and source text)."""
    print(f"warning: {message}", file=sys.stderr)


def main(argv: list[str] | None = None, *, prog: str = "python -m fdi_lib") -> int:
    """Run the command line; returns the exit code (0, 2 on an error, 130 when interrupted).

    A usage error (an option that is malformed or does not apply) exits at once with code 2
    (``SystemExit``), before anything is imported or computed."""
    with warnings.catch_warnings():  # restores the warning display on return
        warnings.showwarning = _warning_line
        try:
            return _main(argv, prog)
        except KeyboardInterrupt:
            # the Monte Carlo engine has stopped its workers before the interruption reached here
            print("interrupted", file=sys.stderr)
            return EXIT_INTERRUPTED


def console_main() -> int:
    """The console script ``fdi-reproduce [ID | --list | --ledger] ...``: the ``reproduce``
    command of ``python -m fdi_lib``, under its own name."""
    return main(sys.argv[1:], prog="fdi-reproduce")


def _main(argv: list[str] | None, prog: str) -> int:
    parser, rep_parser = _parsers(prog)
    args = parser.parse_args(argv)
    _check_applies(rep_parser, args)
    if args.jobs is None:
        args.jobs = 1
    if args.list:
        for r in list_reproductions():
            trials = "" if r.default_trials is None else f"  [{r.default_trials} trials]"
            print(f"{r.id:<22} {r.paper:<28} {r.title}{trials}")
        return 0
    if args.ledger:
        return _print_ledger(args)
    try:
        rep = get(args.id)
        if args.describe:
            print(inspect.getdoc(rep.func))
            return 0
        # Every argument is checked before anything is computed.
        rep.check_arguments(seed=args.seed, trials=args.trials, jobs=args.jobs)
        options = _options(rep, args.option)
        if args.trials is not None and args.trials < rep.min_trials:
            raise ModelError(
                f"--trials: expected at least {rep.min_trials} (the JSON's 95 % intervals need "
                f"two trials), got {args.trials}"
            )
        if args.plot:
            if rep.plot is None:
                raise ModelError(f"--plot: {args.id} has no figure")
            _check_plot(args.plot)
        # --jobs above the CPU cores (or -1) becomes the core count here, so that every reproduction,
        # including those with their own pool, starts no more processes than can run
        jobs = effective_jobs(args.jobs)
        with _where(args):
            result = rep(seed=args.seed, trials=args.trials, jobs=jobs, **options)
    except FDIError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        try:
            rep.plot(result).savefig(args.plot, dpi=120, bbox_inches="tight")
        except OSError as exc:
            print(
                f"error: --plot: could not write {args.plot!r}: {exc.strerror or exc}",
                file=sys.stderr,
            )
            return 2
    if args.json:
        print(result.to_json())
    else:
        print(f"{rep.id}: {rep.title} ({rep.paper})")
        for key, value in result.headline.items():
            paper = result.paper.get(key, "")
            print(f"  {key:<28} ours: {value!s:<40} paper: {paper}")
    return 0


@contextlib.contextmanager
def _where(args: argparse.Namespace) -> Any:
    """Context of a run: the progress bars (``--progress``, default: standard error is a terminal)
    and, with ``--cluster``, the Dask cluster's executor for every Monte Carlo run inside (a local
    cluster is stopped on leaving, also on an error or Ctrl-C)."""
    show = (
        args.progress
        if args.progress is not None
        else bool(getattr(sys.stderr, "isatty", lambda: False)())
    )
    with contextlib.ExitStack() as stack:
        if args.cluster is not None:
            stack.enter_context(use_executor(stack.enter_context(dask_executor(args.cluster))))
        stack.enter_context(progress_bars(show))
        yield


def _options(rep: Any, items: list[str]) -> dict[str, Any]:
    """``--option NAME=VALUE`` items as keyword arguments of ``rep``: VALUE parsed as JSON, else
    kept as a string; a name the reproduction does not take is an error naming it."""
    import json

    known = [
        n
        for n, p in inspect.signature(rep.func).parameters.items()
        if p.kind is p.KEYWORD_ONLY and n not in ("seed", "trials", "jobs")
    ]
    out: dict[str, Any] = {}
    for item in items:
        name, sep, text = item.partition("=")
        if not sep or not name:
            raise ModelError(f"--option: expected NAME=VALUE, got {item!r}")
        if name not in known:
            raise ModelError(
                f"--option: {rep.id} has no option {name!r}; expected one of "
                f"{', '.join(known) or 'none'}"
            )
        try:
            out[name] = json.loads(text)
        except ValueError:
            out[name] = text
    return out


def _print_ledger(args: argparse.Namespace) -> int:
    import json

    from fdi_lib.reproduce.ledger import ledger

    try:
        with _where(args):
            led = ledger(max_trials=args.trials, jobs=effective_jobs(args.jobs))
    except FDIError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(led.to_json_dict()))
        return 0
    print("  ".join(f"{status}: {n}" for status, n in led.counts().items()))
    for id, seconds in led.timings.items():
        print(f"{'computed':<24} {id} in {seconds:.1f} s")
    for r in led.rows:
        print(
            f"{r.status:<24} {r.claim}\n{'':<24} paper: {r.paper}  ours: {r.ours}"
            + (f"  95 % interval: [{r.ci[0]:.4g}, {r.ci[1]:.4g}]" if r.ci else "")
            + (f"  ({r.role})" if r.role else "")
            + (f"  see {r.cause or r.explain}" if r.cause or r.explain else "")
            + (f"\n{'':<24} {r.status_detail}" if r.status_detail else "")
        )
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
