"""Clusters beyond this machine (issue 34.4): the SLURM/PBS recipe (deploy/jobqueue.py,
dask-jobqueue) run end to end against dask-jobqueue's local stand-in (its "batch jobs" are
processes of this machine: no SLURM or PBS queue is available here), the batch scripts a real
queue would get, and the Kubernetes recipe's files (not built here: no container runtime)."""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("dask_jobqueue")

from fdi_lib.reproduce.cli import main  # noqa: E402
from fdi_lib.reproduce.registry import CACHE_ENV  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RECIPE = ROOT / "deploy" / "jobqueue.py"


def _recipe():
    spec = importlib.util.spec_from_file_location("jobqueue_recipe", RECIPE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
def test_the_jobqueue_recipe_gives_the_bytes_of_one_job(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv(CACHE_ENV, raising=False)
    argv = ["zhang2021-table1", "--trials", "8", "--json"]
    assert main(["reproduce", *argv, "--jobs", "1"]) == 0
    ref = capsys.readouterr().out
    env = {k: v for k, v in os.environ.items() if k != CACHE_ENV}
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    proc = subprocess.run(
        [
            sys.executable,
            str(RECIPE),
            "local",
            "--workers",
            "2",
            "--queue-wait",
            "120",
            "--",
            *argv,
        ],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == ref


@pytest.mark.parametrize("kind, directive", [("slurm", "#SBATCH"), ("pbs", "#PBS")])
def test_a_batch_job_starts_one_worker_of_one_thread_with_this_python(kind, directive):
    """The script a real queue would get: its directives, this environment's Python (the workers
    import the same fdi_lib and libraries), one worker process of one thread."""
    with _recipe().make_cluster(kind, memory="2GB", walltime="01:00:00", queue="short") as cluster:
        script = cluster.job_script()
    assert script.count(directive) >= 3 and "01:00:00" in script and "short" in script
    (command,) = [line for line in script.splitlines() if "distributed.cli.dask_worker" in line]
    assert command.startswith(f"{sys.executable} -m distributed.cli.dask_worker tcp://")
    assert re.search(r"--nthreads 1\b", command) and not re.search(r"--nworkers [^1]", command)


def test_the_kubernetes_image_installs_the_library_at_the_locks_versions():
    """The image recipe installs the library with the lock as constraints (the same versions as
    this environment) and starts one-thread workers on the scheduler the manifest names."""
    import yaml

    docker = (ROOT / "deploy" / "kubernetes" / "Dockerfile").read_text()
    assert 'pip install --no-cache-dir --constraint requirements.lock ".[cluster]"' in docker
    assert "COPY requirements.lock" in docker and "COPY fdi_lib ./fdi_lib" in docker
    docs = list(
        yaml.safe_load_all((ROOT / "deploy" / "kubernetes" / "dask-cluster.yaml").read_text())
    )
    service = next(d for d in docs if d["kind"] == "Service")
    workers = next(d for d in docs if d["metadata"]["name"] == "fdi-worker")
    (container,) = workers["spec"]["template"]["spec"]["containers"]
    port = service["spec"]["ports"][0]["port"]
    assert container["command"][:3] == [
        "dask",
        "worker",
        f"tcp://{service['metadata']['name']}:{port}",
    ]
    assert container["command"][3:5] == ["--nthreads", "1"]
    lock = (ROOT / "requirements.lock").read_text()
    for name in ("dask", "distributed", "dask-jobqueue"):
        assert re.search(rf"^{name}==", lock, flags=re.M), name
