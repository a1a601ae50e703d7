"""Command line: ``python -m fdi_lib reproduce [--list | ID [--seed S] [--trials N] [--jobs J] [--json]]``.

``--json`` prints exactly one JSON object ``{"id", "headline", "paper", "settings"}``
on standard output; the ``headline`` keys of each identifier are documented in
the docstring of its reproduction function (``--describe ID`` prints it).
"""

from __future__ import annotations

import argparse
import inspect
import sys

from fdi_lib.errors import FDIError
from fdi_lib.reproduce.registry import get, list_reproductions


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m fdi_lib", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    rep = sub.add_parser("reproduce", help="reproduce a figure or table of the papers")
    rep.add_argument("id", nargs="?", help="reproduction identifier, e.g. zb2014-fig3")
    rep.add_argument("--list", action="store_true", help="list the identifiers and exit")
    rep.add_argument("--describe", action="store_true", help="print the documentation of ID and exit")
    rep.add_argument("--seed", type=int, default=None, help="random seed (default: the reproduction's)")
    rep.add_argument("--trials", type=int, default=None,
                     help="Monte Carlo trials (default: the paper's own count)")
    rep.add_argument("--jobs", type=int, default=1, help="parallel jobs, -1 for all cores (default 1)")
    rep.add_argument("--json", action="store_true", help="print one JSON object of headline numbers")
    rep.add_argument("--plot", metavar="FILE", default=None, help="also save the figure to FILE")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    if args.list:
        for r in list_reproductions():
            trials = "" if r.default_trials is None else f"  [{r.default_trials} trials]"
            print(f"{r.id:<22} {r.paper:<28} {r.title}{trials}")
        return 0
    if not args.id:
        print("error: give a reproduction ID or --list", file=sys.stderr)
        return 2
    try:
        rep = get(args.id)
        if args.describe:
            print(inspect.getdoc(rep.func))
            return 0
        result = rep(seed=args.seed, trials=args.trials, jobs=args.jobs)
    except FDIError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        if rep.plot is None:
            print(f"error: {args.id} has no figure", file=sys.stderr)
            return 2
        rep.plot(result).savefig(args.plot, dpi=120, bbox_inches="tight")
    if args.json:
        print(result.to_json())
    else:
        print(f"{rep.id}: {rep.title} ({rep.paper})")
        for key, value in result.headline.items():
            paper = result.paper.get(key, "")
            print(f"  {key:<28} ours: {value!s:<40} paper: {paper}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
