"""The library installs and runs on its own (``make install-check``; issue 34).

    python tools/check_install.py [--out _build/install-check]

Builds the wheel of ``fdi_lib`` from a copy of the repository's package files (``pip wheel
--no-deps`` builds in the source tree: a copy leaves ``build/`` and ``fdi_lib.egg-info`` out of
the repository, where CI's test suite runs at the same time), installs it into a
new virtual environment that shares nothing with the book's (no system site-packages, no
repository on its path: every command runs from the environment's own folder), with its
dependencies resolved by pip from the wheel's metadata and held to the tested versions by
``requirements.lock`` as constraints, then runs the console script as a user would:
``fdi-reproduce --list`` and one reproduction with ``--json``. Fails (exit status 1, one line
naming the step) if any step fails or the reproduction's JSON lacks its public keys.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
#: What the wheel is built from (pyproject.toml's readme, the licence file setuptools adds, the
#: package), copied to ``OUT/src``.
PACKAGE_FILES = ("pyproject.toml", "README.md", "LICENSE", "fdi_lib")
#: A reproduction that runs in a second: the console script's JSON contract is what is checked.
REPRODUCTION = "zb2014-table1"
PUBLIC_KEYS = {"id", "headline", "paper", "settings"}


def _run(step: str, cmd: list[str], cwd: Path) -> str:
    start = time.perf_counter()
    done = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    if done.returncode != 0:
        tail = (done.stderr or done.stdout).strip().splitlines()[-5:]
        raise SystemExit(
            f"install-check: {step} failed (exit {done.returncode}): " + " | ".join(tail)
        )
    print(f"install-check: {step}: ok ({time.perf_counter() - start:.0f} s)", flush=True)
    return done.stdout


def check(out: Path) -> None:
    if out.exists():
        shutil.rmtree(out)
    src, dist, env = out / "src", out / "dist", out / "venv"
    dist.mkdir(parents=True)
    src.mkdir()
    for name in PACKAGE_FILES:
        if (REPO / name).is_dir():
            shutil.copytree(
                REPO / name, src / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc")
            )
        else:
            shutil.copy2(REPO / name, src / name)
    _run(
        "wheel",
        [sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "-w", str(dist), str(src)],
        cwd=out,
    )
    wheels = sorted(dist.glob("fdi_lib-*.whl"))
    if len(wheels) != 1:
        raise SystemExit(
            f"install-check: expected one fdi_lib wheel in {dist}, found {len(wheels)}"
        )
    _run("venv", [sys.executable, "-m", "venv", str(env)], cwd=out)
    python, script = env / "bin" / "python", env / "bin" / "fdi-reproduce"
    _run(
        "install",
        [
            str(python),
            "-m",
            "pip",
            "install",
            "--quiet",
            "-c",
            str(REPO / "requirements.lock"),
            str(wheels[0]),
        ],
        cwd=out,
    )
    where = _run(
        "import", [str(python), "-c", "import fdi_lib; print(fdi_lib.__file__)"], cwd=env
    ).strip()
    if not where.startswith(str(env)):
        raise SystemExit(
            f"install-check: fdi_lib imported from {where}, not from the new environment"
        )
    listing = _run("fdi-reproduce --list", [str(script), "--list"], cwd=env)
    if REPRODUCTION not in listing:
        raise SystemExit(f"install-check: {REPRODUCTION} missing from fdi-reproduce --list")
    result = json.loads(
        _run(f"fdi-reproduce {REPRODUCTION} --json", [str(script), REPRODUCTION, "--json"], cwd=env)
    )
    missing = PUBLIC_KEYS - set(result)
    if missing or result["id"] != REPRODUCTION:
        raise SystemExit(
            f"install-check: the JSON of {REPRODUCTION} lacks {sorted(missing)} or names "
            f"{result.get('id')!r}"
        )
    print(f"install-check: {wheels[0].name} installs and runs in a clean environment")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO / "_build" / "install-check")
    check(parser.parse_args(argv).out.resolve())
    return 0


if __name__ == "__main__":
    sys.exit(main())
