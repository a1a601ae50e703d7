"""Record, or compare with the record, the ``--json`` of every reproduction (issue 34.3).

The record (``tests/data/json_identity.json``, and ``json_identity_windturbine.json`` for the
wind-turbine identifiers, which their chapter changes on purpose) holds for each identifier the
trial count it ran at and the exact text that ``python -m fdi_lib reproduce ID --json`` prints at
the default seed (:meth:`~fdi_lib.reproduce.registry.ReproductionResult.to_json`), with the
headline keys that measure wall time (``timed_keys``) set to ``null``. A refactoring must leave
every text byte-identical: ``tests/test_json_identity.py`` recomputes them.

Trial counts: a deterministic or single-run reproduction runs as the CLI runs it; a Monte Carlo
one at :data:`TRIALS` (its own ``min_trials`` when higher), so that the whole check stays near a
minute of CPU; the code paths are those of the paper's counts, the numbers are not.

Usage::

    python tools/json_identity.py              # compare; exit 1 and name every difference
    python tools/json_identity.py --update     # record anew (say why in CHANGELOG.md)
    python tools/json_identity.py --update windturbine-scoreboard   # only these identifiers

An ``--update`` changes the public contract's numbers: it needs a CHANGELOG line saying which
identifiers changed and why.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

DATA = Path(__file__).resolve().parents[1] / "tests" / "data"
#: Identifiers whose prefix is here are recorded apart (their owners change them on purpose).
SEPARATE = {"windturbine": DATA / "json_identity_windturbine.json"}
MAIN = DATA / "json_identity.json"
#: Trials of a Monte Carlo reproduction in the record (``min_trials`` when that is higher).
TRIALS = 2
#: Reproductions too slow to recompute in the test suite even at :data:`TRIALS`, with why.
SKIP: dict[str, str] = {}


def record_path(rid: str) -> Path:
    """The record file that holds ``rid``."""
    return next((p for prefix, p in SEPARATE.items() if rid.startswith(prefix)), MAIN)


def trials_for(rep) -> int | None:
    """The trial count ``rep`` is recorded at (``None``: it takes none)."""
    return max(TRIALS, rep.min_trials) if rep.monte_carlo else None


def json_text(rid: str, trials: int | None) -> str:
    """What ``reproduce RID --json [--trials N]`` prints, wall-time keys set to ``null``."""
    from fdi_lib.reproduce import get

    rep = get(rid)
    result = rep(trials=trials, jobs=1)
    obj = json.loads(result.to_json())
    for key in rep.timed_keys:
        if key in obj["headline"]:
            obj["headline"][key] = None
    return json.dumps(obj)


def load(path: Path) -> dict[str, dict]:
    return json.loads(path.read_text(encoding="utf-8")) if path.exists() else {}


def recorded() -> dict[str, dict]:
    """Every recorded identifier -> ``{"trials": ..., "json": ...}``."""
    out = load(MAIN)
    for path in SEPARATE.values():
        out.update(load(path))
    return out


def update(ids: list[str]) -> None:
    from fdi_lib.reproduce import list_reproductions

    reps = {r.id: r for r in list_reproductions() if r.id not in SKIP}
    for rid in ids or sorted(reps):
        path = record_path(rid)
        table = load(path)
        trials = trials_for(reps[rid])
        table[rid] = {"trials": trials, "json": json_text(rid, trials)}
        path.write_text(json.dumps(dict(sorted(table.items())), indent=1) + "\n", encoding="utf-8")
        print(f"recorded {rid} ({trials} trials) in {path.name}", flush=True)


def compare(ids: list[str]) -> int:
    table = recorded()
    bad = 0
    for rid in ids or sorted(table):
        entry = table[rid]
        if json_text(rid, entry["trials"]) != entry["json"]:
            print(f"DIFFERS: {rid}", flush=True)
            bad += 1
    print(f"{len(ids or table) - bad} identical, {bad} different")
    return 1 if bad else 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("ids", nargs="*", help="identifiers (default: all)")
    parser.add_argument("--update", action="store_true", help="record anew")
    args = parser.parse_args(argv)
    if args.update:
        update(args.ids)
        return 0
    return compare(args.ids)


if __name__ == "__main__":
    sys.exit(main())
