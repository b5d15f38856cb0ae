"""Real servers on this machine for ``bench_storage``: an S3 server and a Dask cluster.

* :func:`s3_server`: moto's ``ThreadedMotoServer`` (an S3-compatible HTTP
  server, the way s3fs's own tests run) on 127.0.0.1 at a free port.
* :func:`dask_cluster`: ``dask scheduler`` and ``dask worker`` processes,
  each started in its own empty temporary folder (its cwd, ``TMPDIR`` and
  ``HOME``), so that the workers cannot see the client's files.

Both are torn down on exit, and every wait is bounded.  The same as ``tests/helpers/servers.py``
(the tests keep their own copy; benchmarks import nothing from tests/).
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks.common import ROOT

#: Fake credentials: moto accepts any.
FAKE_CREDENTIALS = {
    "AWS_ACCESS_KEY_ID": "testing-key-id",
    "AWS_SECRET_ACCESS_KEY": "testing-secret-value",
    "AWS_DEFAULT_REGION": "us-east-1",
}
START_TIMEOUT = 60.0


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@contextlib.contextmanager
def s3_server():
    """Yield the endpoint URL of a running moto S3 server (with fake credentials in the environment)."""
    import logging

    from moto.server import ThreadedMotoServer

    logging.getLogger("werkzeug").setLevel(logging.ERROR)  # no line per request
    port = free_port()
    server = ThreadedMotoServer(ip_address="127.0.0.1", port=port, verbose=False)
    saved = {k: os.environ.get(k) for k in FAKE_CREDENTIALS}
    os.environ.update(FAKE_CREDENTIALS)
    server.start()
    try:
        yield f"http://127.0.0.1:{port}"
    finally:
        server.stop()
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


def _start(args, folder: Path, env: dict, log: str) -> subprocess.Popen:
    with open(folder / log, "wb") as out:
        return subprocess.Popen(args, cwd=folder, env=env, stdout=out, stderr=subprocess.STDOUT)


@contextlib.contextmanager
def dask_cluster(workers: int = 2, *, env: dict | None = None, memory_limit: str = "0"):
    """Yield ``(address, folders)``: a scheduler and ``workers`` single-threaded workers, each a separate
    process in its own empty temporary folder (``folders[i]``; the scheduler's is ``folders[-1]``).

    The workers import hht3d from this checkout (``PYTHONPATH``) and have the
    client's environment (the same BLAS settings, so the same rounding) with
    the fake S3 credentials, one BLAS thread, and ``HOME``/``TMPDIR`` in their folder.
    """
    base = Path(tempfile.mkdtemp(prefix="hht3d-cluster-"))
    folders = [base / f"worker{i}" for i in range(workers)] + [base / "scheduler"]
    for folder in folders:
        folder.mkdir()
    scheduler_file = folders[-1] / "scheduler.json"
    common = {
        **os.environ,
        **FAKE_CREDENTIALS,
        "PYTHONPATH": str(ROOT),
        "OMP_NUM_THREADS": "1",
        "MKL_NUM_THREADS": "1",
        "OPENBLAS_NUM_THREADS": "1",
        **(env or {}),
    }
    processes = []
    try:
        processes.append(
            _start(
                [
                    sys.executable,
                    "-m",
                    "distributed.cli.dask_scheduler",
                    "--host",
                    "127.0.0.1",
                    "--port",
                    "0",
                    "--no-dashboard",
                    "--scheduler-file",
                    str(scheduler_file),
                ],
                folders[-1],
                {**common, "HOME": str(folders[-1]), "TMPDIR": str(folders[-1])},
                "scheduler.log",
            )
        )
        address = _wait_for(lambda: json.loads(scheduler_file.read_text())["address"], processes)
        for folder in folders[:-1]:
            processes.append(
                _start(
                    [
                        sys.executable,
                        "-m",
                        "distributed.cli.dask_worker",
                        address,
                        "--nthreads",
                        "1",
                        "--nworkers",
                        "1",
                        "--no-nanny",
                        "--memory-limit",
                        memory_limit,
                        "--local-directory",
                        str(folder / "dask"),
                        "--death-timeout",
                        "60",
                    ],
                    folder,
                    {**common, "HOME": str(folder), "TMPDIR": str(folder)},
                    "worker.log",
                )
            )
        _wait_for(lambda: _workers_connected(address, workers), processes)
        yield address, folders
    finally:
        for process in processes:
            process.terminate()
        for process in processes:
            try:
                process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(timeout=20)


def _workers_connected(address: str, count: int) -> bool:
    from distributed import Client

    with Client(address, timeout="10s") as client:
        client.wait_for_workers(count, timeout=START_TIMEOUT)
    return True


def _wait_for(probe, processes, timeout: float = START_TIMEOUT):
    """The first truthy value of ``probe()`` within ``timeout`` seconds; fail if a process exits."""
    deadline = time.monotonic() + timeout
    while True:
        dead = [p for p in processes if p.poll() is not None]
        if dead:
            raise RuntimeError(f"a cluster process exited with {dead[0].returncode}: {dead[0].args}")
        with contextlib.suppress(Exception):
            value = probe()
            if value:
                return value
        if time.monotonic() > deadline:
            raise TimeoutError(f"the Dask cluster did not start within {timeout} s")
        time.sleep(0.2)
