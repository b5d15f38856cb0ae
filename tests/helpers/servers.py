"""Real servers for the object-storage tests and benchmark: an S3 server and a Dask cluster.

* :func:`s3_server`: moto's ``ThreadedMotoServer`` (an S3-compatible HTTP
  server, the way s3fs's own tests run) on 127.0.0.1 at a free port; or,
  with ``kind="s3rver"``, the independent Node.js server s3rver (npm), where
  Node and npm exist (:data:`S3_SERVERS` lists the kinds this machine has).
* :func:`dask_cluster`: ``dask scheduler`` and two ``dask worker`` processes,
  each started in its own empty temporary folder (its cwd, ``TMPDIR`` and
  ``HOME``), so that the workers cannot see the client's files.

Both are torn down on exit, and every wait is bounded.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: Fake credentials: moto accepts any, s3rver its own default account.
FAKE_CREDENTIALS = {"AWS_ACCESS_KEY_ID": "S3RVER", "AWS_SECRET_ACCESS_KEY": "S3RVER", "AWS_DEFAULT_REGION": "us-east-1"}
START_TIMEOUT = 60.0


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


#: s3rver's version, installed once per machine into :data:`S3RVER_HOME` when Node and npm exist.
S3RVER = "s3rver@3.7.1"
S3RVER_HOME = Path.home() / ".cache" / "hht3d-tests" / S3RVER.replace("@", "-")
#: The S3 servers the object-storage tests run against here: moto always, s3rver where Node is.
S3_SERVERS = ("moto", "s3rver") if shutil.which("node") and shutil.which("npm") else ("moto",)


@contextlib.contextmanager
def s3_server(kind: str = "moto"):
    """Yield the endpoint URL of a running S3 server (with fake credentials in the environment)."""
    saved = {k: os.environ.get(k) for k in FAKE_CREDENTIALS}
    os.environ.update(FAKE_CREDENTIALS)
    try:
        with _moto() if kind == "moto" else _s3rver() as endpoint:
            yield endpoint
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


@contextlib.contextmanager
def _moto():
    import logging

    from moto.server import ThreadedMotoServer

    logging.getLogger("werkzeug").setLevel(logging.ERROR)  # no line per request
    port = free_port()
    server = ThreadedMotoServer(ip_address="127.0.0.1", port=port, verbose=False)
    server.start()
    try:
        yield f"http://127.0.0.1:{port}"
    finally:
        server.stop()


@contextlib.contextmanager
def _s3rver():
    """s3rver on 127.0.0.1, accepting any well-formed signature (the fake credentials)."""
    script = S3RVER_HOME / "node_modules" / "s3rver" / "bin" / "s3rver.js"
    if not script.is_file():
        S3RVER_HOME.mkdir(parents=True, exist_ok=True)
        subprocess.run(
            ["npm", "install", "--no-audit", "--no-fund", "--silent", "--prefix", str(S3RVER_HOME), S3RVER],
            check=True,
            timeout=300,
            capture_output=True,
        )
    port = free_port()
    with tempfile.TemporaryDirectory(prefix="hht3d-s3rver-") as data:
        server = subprocess.Popen(
            [
                "node",
                str(script),
                "--directory",
                data,
                "--address",
                "127.0.0.1",
                "--port",
                str(port),
                "--silent",
                "--allow-mismatched-signatures",
                "--no-vhost-buckets",
            ],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            _wait_for(lambda: _listening(port), [server])
            yield f"http://127.0.0.1:{port}"
        finally:
            server.terminate()
            server.wait(10)


def _listening(port: int) -> bool:
    with socket.socket() as sock:
        return sock.connect_ex(("127.0.0.1", port)) == 0


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


def worker_leftovers(folders) -> list[Path]:
    """Mesh and result files left in the workers' folders (their temporary copies must be removed)."""
    suffixes = {".ply", ".npz", ".obj", ".off", ".stl", ".html", ".json", ".csv"}
    return [p for folder in folders[:-1] for p in folder.rglob("*") if p.suffix.lower() in suffixes]
