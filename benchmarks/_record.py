"""Shared reporting of the benchmarks: one line per target, and a JSON record for the status page.

Each target prints its measured figure, the target and the ratio measured / target; a speed-up
against a baseline timed in the same run is printed with it. When the environment variable
``FDI_BENCH_JSON`` names a file (``make benchmarks`` sets ``_build/benchmarks.json``), the record
is appended to it; the book's status page (book/status.md) shows that file when present.
"""

from __future__ import annotations

import datetime
import json
import os
import platform


def record(
    target: str,
    measured: float,
    unit: str,
    goal: float,
    *,
    higher_is_better: bool = False,
    baseline: str = "",
    speedup: float | None = None,
    note: str = "",
) -> None:
    """Print one target line and append it to ``$FDI_BENCH_JSON`` if set.

    ``speedup`` is baseline time / our time (or our throughput / the baseline's), both measured in
    this run; ``baseline`` says what the baseline is.
    """
    met = measured >= goal if higher_is_better else measured <= goal
    sign = ">=" if higher_is_better else "<="
    line = (
        f"TARGET {target}: {measured:,.4g} {unit} (target {sign} {goal:,.4g} {unit}: "
        f"{'met' if met else 'NOT met'}; measured / target = {measured / goal:.2f})"
    )
    if speedup is not None:
        line += f"; {speedup:,.1f}x against {baseline}"
    if note:
        line += f" [{note}]"
    print(line, flush=True)
    path = os.environ.get("FDI_BENCH_JSON")
    if not path:
        return
    entries = []
    if os.path.exists(path):
        with open(path) as f:
            entries = json.load(f)
    entries.append(
        {
            "target": target,
            "measured": measured,
            "unit": unit,
            "goal": goal,
            "higher_is_better": higher_is_better,
            "met": bool(met),
            "baseline": baseline,
            "speedup": speedup,
            "note": note,
            "when": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "load_average": os.getloadavg()[0],
            "cores": os.cpu_count(),
            "machine": platform.machine(),
        }
    )
    with open(path, "w") as f:
        json.dump(entries, f, indent=1)
