"""Record, or compare with the record, the ``--json`` of every reproduction (issue 34.3).

The record (``tests/data/json_identity.json``, and ``json_identity_windturbine.json`` for the
wind-turbine identifiers, which their chapter changes on purpose) holds for each identifier the
trial count it ran at and the exact text that ``python -m fdi_lib reproduce ID --json`` prints at
the default seed (:meth:`~fdi_lib.reproduce.registry.ReproductionResult.to_json`), with the
headline keys that measure wall time (``timed_keys``) set to ``null``. A refactoring must leave
every text byte-identical: ``tests/test_json_identity.py`` recomputes them.

Byte-identical on the machine that recorded; elsewhere, up to its rounding (:func:`differences`).
The last bits of a float can depend on the processor (the same code and seeds; OpenBLAS and numpy
pick their kernels by the processor's instruction sets, a likely cause we have not isolated):
recomputed on an AVX2 AMD EPYC, the recorded floats moved by at most 3.6e-10 relative, and a
handful of values that are zero up to rounding by about 1e-18.
So a recomputed text is the record when it is the same text once each float within :data:`REL_TOL`
(or :data:`ABS_TOL`) of the recorded one is written as recorded, and every other byte (keys, their
order, strings, integers, booleans, the layout) is the same. Integers that count what rounding
decides are declared in :data:`ROUNDING_DEPENDENT` with why.

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
import math
import sys
from pathlib import Path

DATA = Path(__file__).resolve().parents[1] / "tests" / "data"
#: Identifiers whose prefix is here are recorded apart (their owners change them on purpose).
SEPARATE = {"windturbine": DATA / "json_identity_windturbine.json"}
MAIN = DATA / "json_identity.json"
#: Trials of a Monte Carlo reproduction in the record (``min_trials`` when that is higher).
TRIALS = 2
#: Relative and absolute tolerances of a float against its record (see the module docstring).
REL_TOL = 1e-8
ABS_TOL = 1e-15
#: Integers decided by rounding: identifier -> headline key -> (relative tolerance, why).
ROUNDING_DEPENDENT: dict[str, dict[str, tuple[float, str]]] = {
    "rosa2013-timing": {
        "vertices_exact": (
            0.01,
            "vertices of the exact set, about 2,000 after two updates, a count the last bits of "
            "its floating-point enumeration decide (2,018 on an AVX2 machine against the "
            "recorded 2,021; the same seeds)",
        )
    }
}
#: Reproductions too slow to recompute in the test suite even at :data:`TRIALS`, with why.
SKIP: dict[str, str] = {
    "windturbine-false-alarms": "one stream is the benchmark's whole 4400 s scenario, about 22 s of "
    "a core; its counts are tested on short streams (tests/reproduce/test_windturbine_scoreboard.py) "
    "and its command against the book's result by tools/check_catalogue.py",
}


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


def differences(rid: str, text: str, record: str) -> list[str]:
    """What tells the recomputed ``text`` of ``rid`` from its ``record`` beyond the machine's
    rounding (empty: the same; see the module docstring), one line per difference."""
    if text == record:
        return []
    out: list[str] = []
    merged = _merge(json.loads(text), json.loads(record), "", ROUNDING_DEPENDENT.get(rid, {}), out)
    if not out and json.dumps(merged) != record:
        out.append("the text differs beyond its numbers (key order or layout)")
    return out


def _merge(new, old, path: str, rounding: dict, out: list[str]):
    """``new`` with each number within its tolerance of ``old`` replaced by ``old``; what is not
    goes to ``out``."""
    if isinstance(new, dict) and isinstance(old, dict):
        if list(new) != list(old):
            out.append(f"{path or '/'}: keys {list(new)} against {list(old)}")
            return new
        return {k: _merge(new[k], old[k], f"{path}.{k}", rounding, out) for k in new}
    if isinstance(new, list) and isinstance(old, list):
        if len(new) != len(old):
            out.append(f"{path}: {len(new)} items against {len(old)}")
            return new
        return [
            _merge(a, b, f"{path}[{i}]", rounding, out) for i, (a, b) in enumerate(zip(new, old))
        ]
    if type(new) is float and type(old) is float:
        both_nan = math.isnan(new) and math.isnan(old)
        if both_nan or math.isclose(new, old, rel_tol=REL_TOL, abs_tol=ABS_TOL):
            return old
    elif type(new) is int and type(old) is int:
        key = next((k for k in rounding if path.startswith(f".headline.{k}")), None)
        if new == old or (key and abs(new - old) <= rounding[key][0] * abs(old)):
            return old
    elif type(new) is type(old) and new == old:
        return old
    out.append(f"{path}: {new!r} against {old!r}")
    return new


def compare(ids: list[str]) -> int:
    table = recorded()
    bad = 0
    for rid in ids or sorted(table):
        entry = table[rid]
        text = json_text(rid, entry["trials"])
        diff = differences(rid, text, entry["json"])
        if diff:
            print(f"DIFFERS: {rid}: " + "; ".join(diff[:5]), flush=True)
            bad += 1
        elif text != entry["json"]:
            print(f"same up to rounding: {rid}", flush=True)
    print(f"{len(ids or table) - bad} the same, {bad} different")
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
