"""Time to grade a class on the whole book (tools/grader.py), two kernels at once on 2 cores.

Target: 30 students in 10 minutes, hangs included. By default (``make benchmarks``, in CI) a
small class is graded: the reference solutions, the untouched starters and a submission that
hangs in glr-2 with a loop that swallows interrupts (killed at the default cell limit), on every
chapter. The time for 30 is extrapolated from it: 30 students as 28 full submissions and 2 hangs,
each costing its measured wall time, on 2 kernels at once (total / 2). With
``FDI_BENCH_GRADE_FULL=1`` the 30 students (28 copies of the reference, 2 hangs) are graded for
real and the measured time is recorded instead.
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO), str(REPO / "tools"), str(REPO / "benchmarks")]

import grader  # noqa: E402
import make_synthetic_class as synth  # noqa: E402
from _record import record  # noqa: E402

JOBS = 2
TARGET_S = 600.0


def main() -> None:
    full = os.environ.get("FDI_BENCH_GRADE_FULL") == "1"
    with tempfile.TemporaryDirectory(prefix="bench-grade-") as tmp:
        out = Path(tmp) / "class"
        synth.write_class(out)
        keep = {"reference", "starter", "hang"}
        for folder in out.iterdir():
            if folder.name not in keep:
                shutil.rmtree(folder)
        if full:
            for i in range(27):
                shutil.copytree(out / "reference", out / f"copy-{i:02d}")
            shutil.copytree(out / "hang", out / "hang-2")
            shutil.rmtree(out / "starter")
        book = Path(tmp) / "class.csv"
        t0 = time.perf_counter()
        grader.grade(out, book, secret="bench", jobs=JOBS)
        wall = time.perf_counter() - t0
        per = {}
        for line in book.with_suffix(".log").read_text().splitlines():
            if line.startswith("== "):
                name, rest = line[3:].split(":", 1)
                per[name] = float(rest.rsplit("(", 1)[1].split(" s)")[0])
    print(
        "seconds per student (wall, 2 kernels at once): "
        + ", ".join(f"{k} {v:.1f}" for k, v in sorted(per.items()))
    )
    if full:
        record(
            "grade 30 students on the whole book (2 cores)",
            wall,
            "s",
            TARGET_S,
            note="measured: 28 full submissions and 2 interrupt-swallowing hangs",
        )
    else:
        estimate = (28 * per["reference"] + 2 * per["hang"]) / JOBS
        record(
            "grade 30 students on the whole book (2 cores, extrapolated)",
            estimate,
            "s",
            TARGET_S,
            note=f"from a class of {len(per)} graded in {wall:.0f} s: (28 x reference "
            f"{per['reference']:.0f} s + 2 x hang {per['hang']:.0f} s) / {JOBS} kernels; "
            "FDI_BENCH_GRADE_FULL=1 measures the 30",
        )


if __name__ == "__main__":
    main()
