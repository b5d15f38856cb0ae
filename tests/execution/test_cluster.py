"""Losses with real processes (issue 23): a real ``dask scheduler`` with ``dask worker`` processes that the tests kill.

Every case asserts the exit code, the one line on stderr (no traceback from any process) and that no temporary
``.part`` file is left; a lost cluster is reported within a bounded time, and each wait is bounded.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

import pytest

from helpers.processes import STOP_WITHIN, _env, _recorded, _start, _wait_for

pytestmark = pytest.mark.slow  # real CLI processes, schedulers and workers


# -- a real dask.distributed cluster --------------------------------------------------------------------------
class Cluster:
    """A ``dask scheduler`` and ``dask worker`` processes started and killed by a test."""

    def __init__(self, folder: Path):
        self.folder, self.workers = folder, []
        self.file = folder / "scheduler.json"
        self.scheduler = self._spawn(
            [
                "dask",
                "scheduler",
                "--scheduler-file",
                str(self.file),
                "--port",
                "0",
                "--dashboard-address",
                ":0",
                "--no-show",
            ]
        )
        _wait_for(self.file.exists, 60, "the Dask scheduler")
        self.address = json.loads(self.file.read_text())["address"]

    def _spawn(self, argv) -> subprocess.Popen:
        return subprocess.Popen(
            argv,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            env=_env(),
            cwd=self.folder,
            start_new_session=True,
        )

    def worker(self, nanny: bool) -> subprocess.Popen:
        argv = ["dask", "worker", "--scheduler-file", str(self.file), "--nthreads", "1", "--dashboard-address", ":0"]
        self.workers.append(self._spawn([*argv, "--nanny" if nanny else "--no-nanny"]))
        return self.workers[-1]

    def count(self) -> int:
        from distributed import Client

        with Client(self.address, timeout="10s") as client:
            return len(client.scheduler_info()["workers"])

    def close(self) -> None:
        for proc in [*self.workers, self.scheduler]:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(10)


@pytest.fixture
def cluster(tmp_path):
    if shutil.which("dask") is None:
        pytest.skip("the dask command (dask.distributed) is not installed")
    started = Cluster(tmp_path)
    yield started
    started.close()


def _one_error_line(stderr: str) -> str:
    lines = [line for line in stderr.splitlines() if line and not line.startswith("hht3d: Dask dashboard")]
    assert len(lines) == 1 and lines[0].startswith("hht3d: error: ") and "Traceback" not in stderr, stderr
    return lines[0]


def test_every_worker_lost_is_one_line_naming_the_inputs_not_done(job, cluster):
    workers = [cluster.worker(nanny=False) for _ in range(2)]
    _wait_for(lambda: cluster.count() == 2, 60, "two workers")
    proc = _start(job, "--address", cluster.address, env=_env(DASK_HHT3D__NO_WORKERS_TIMEOUT="3"))
    _wait_for(lambda: len(_recorded(job / "out")) >= 1 or proc.poll() is not None, 90, "a first output")
    for worker in workers:
        os.killpg(worker.pid, signal.SIGKILL)
    killed = time.monotonic()
    _, stderr = proc.communicate(timeout=STOP_WITHIN + 10)
    assert time.monotonic() - killed < STOP_WITHIN
    assert proc.returncode == 1
    line = _one_error_line(stderr)
    assert "has had no workers for 3 s" in line and "inputs not done" in line and "--resume" in line, line


def test_a_killed_worker_under_a_nanny_is_replaced_and_the_run_finishes(job, cluster):
    import psutil

    nanny = cluster.worker(nanny=True)
    _wait_for(lambda: cluster.count() == 1, 60, "a worker")
    proc = _start(job, "--address", cluster.address)
    _wait_for(lambda: len(_recorded(job / "out")) >= 1 or proc.poll() is not None, 90, "a first output")
    children = psutil.Process(nanny.pid).children()
    workers = [child for child in children if "spawn_main" in " ".join(child.cmdline())]  # the nanny's worker
    assert len(workers) == 1, [child.cmdline() for child in children]
    workers[0].kill()
    stdout, stderr = proc.communicate(timeout=180)
    assert proc.returncode == 0, stderr
    assert stdout.count(": ok") == 4, (stdout, stderr)
    assert not list((job / "out").rglob("*.part"))


def test_a_lost_scheduler_is_one_line_within_a_bounded_time(job, cluster):
    cluster.worker(nanny=False)
    _wait_for(lambda: cluster.count() == 1, 60, "a worker")
    proc = _start(job, "--address", cluster.address)
    _wait_for(lambda: len(_recorded(job / "out")) >= 1 or proc.poll() is not None, 90, "a first output")
    os.killpg(cluster.scheduler.pid, signal.SIGKILL)
    killed = time.monotonic()
    _, stderr = proc.communicate(timeout=STOP_WITHIN + 10)
    assert time.monotonic() - killed < STOP_WITHIN
    assert proc.returncode == 1
    line = _one_error_line(stderr)
    assert "lost the connection to the Dask scheduler" in line and "inputs not done" in line, line
