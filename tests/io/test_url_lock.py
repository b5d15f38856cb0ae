"""The lock of a URL output folder (hht3d.io.url_lock) against real S3 servers: moto, which honours
``If-None-Match: *``, and s3rver where Node exists, which ignores it (there no lock, and one warning).

Oracles: the exit code and the one line of a run refused, the time it waited, the lock object in the
bucket (its holder, its expiry), and the log records.
"""

from __future__ import annotations

import json
import logging
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from datetime import datetime, timezone

import pytest

pytest.importorskip("s3fs", reason="the object-storage tests need s3fs (pip install -e '.[dev]')")
pytest.importorskip("moto.server", reason="the object-storage tests need moto[server] (pip install -e '.[dev]')")

import fsspec  # noqa: E402

from helpers.models import shipped_model_path  # noqa: E402
from helpers.servers import ROOT, S3_SERVERS, s3_server  # noqa: E402
from hht3d.cli import main  # noqa: E402
from hht3d.dataset import run_dataset  # noqa: E402
from hht3d.errors import OutputError  # noqa: E402
from hht3d.io import url_lock as url_locks  # noqa: E402

BUCKET = "locks"
LOCK = ".hht3d.lock"
PIPELINE = """\
version: 1
storage_options:
  client_kwargs: {{endpoint_url: "{endpoint}"}}
inputs: [{inputs}]
steps:
  - {{op: signal, params: {{kind: mean_curvature}}}}
  - {{op: hht, params: {{max_imfs: {imfs}}}}}
outputs:
  folder: {folder}
  files:
    - {{path: "{{stem}}_hht.npz"}}
"""
UNLOCKED = "the output folder is not locked"


@pytest.fixture(scope="module", params=S3_SERVERS)
def store(request):
    """``(kind, endpoint, storage_options, fs)`` of an S3 server with an empty bucket."""
    with s3_server(request.param) as endpoint:
        options = {"client_kwargs": {"endpoint_url": endpoint}}
        fs = fsspec.filesystem("s3", **options)
        fs.mkdir(BUCKET)
        yield request.param, endpoint, options, fs


def _pipeline(tmp_path, endpoint: str, folder: str, imfs: int = 2, inputs=("spot.ply",)):
    path = tmp_path / "p.yaml"
    names = ", ".join(f'"{shipped_model_path(name)}"' for name in inputs)
    path.write_text(PIPELINE.format(endpoint=endpoint, inputs=names, folder=folder, imfs=imfs))
    return path


def _lock_record(fs, folder: str) -> dict | None:
    fs.invalidate_cache()
    try:
        return json.loads(fs.cat_file(f"{BUCKET}/{folder}/{LOCK}"))
    except FileNotFoundError:
        return None


class _Holder:
    """A run of this process holding a folder's lock in another thread, until :meth:`release`."""

    def __init__(self, url: str, options: dict, run: str):
        self._held, self._release = threading.Event(), threading.Event()
        self._thread = threading.Thread(target=self._hold, args=(url, options, run))
        self._thread.start()
        assert self._held.wait(30)

    def _hold(self, url: str, options: dict, run: str) -> None:
        with url_locks.url_lock(url, options, run):
            self._held.set()
            self._release.wait(60)

    def release(self) -> None:
        self._release.set()
        self._thread.join(30)


def test_a_second_run_into_a_held_folder_waits_then_names_the_holder(store, tmp_path, capsys, monkeypatch):
    kind, endpoint, options, fs = store
    monkeypatch.setenv("HHT3D_LOCK_TIMEOUT", "1")
    pipeline = _pipeline(tmp_path, endpoint, f"s3://{BUCKET}/held")
    holder = _Holder(f"s3://{BUCKET}/held", options, "R-holder")
    try:
        start = time.monotonic()
        code = main(["run", str(pipeline), "--scheduler", "synchronous"])
        waited = time.monotonic() - start
        out, err = capsys.readouterr()
        if kind == "s3rver":  # no lock: the run goes ahead, and says once that the last writer wins
            assert code == 0 and (out + err).count(UNLOCKED) == 1
            return
        who = f"pid {os.getpid()} on {socket.gethostname()} (run R-holder, started "
        assert code == 1 and waited >= 1.0 and "waiting for " + who in out
        assert err.count("\n") == 1 and who in err and "still holds the output folder's lock after 1 s" in err
        assert "HHT3D_LOCK_TIMEOUT" in err
        with pytest.raises(OutputError, match=r"pid \d+ on .* \(run R-holder, started .*\) still holds"):
            run_dataset(
                shipped_model_path("spot.ply"),
                f"s3://{BUCKET}/held",
                storage_options=options,
                scheduler="synchronous",
                progress=False,
                max_imfs=2,
            )
        assert _lock_record(fs, "held")["run"] == "R-holder"
    finally:
        holder.release()
    assert _lock_record(fs, "held") is None


def test_a_released_lock_lets_the_waiting_run_in(store, tmp_path, capsys, monkeypatch):
    kind, endpoint, options, fs = store
    monkeypatch.setenv("HHT3D_LOCK_TIMEOUT", "30")
    holder = _Holder(f"s3://{BUCKET}/released", options, "R-first")
    timer = threading.Timer(1.5, holder.release)
    timer.start()
    start = time.monotonic()
    code = main(["run", str(_pipeline(tmp_path, endpoint, f"s3://{BUCKET}/released")), "--scheduler", "synchronous"])
    waited = time.monotonic() - start
    timer.join()
    out, err = capsys.readouterr()
    assert code == 0, err
    if kind == "moto":
        assert waited >= 1.5 and "(run R-first, started " in out and UNLOCKED not in out + err
    assert _lock_record(fs, "released") is None
    assert fs.exists(f"{BUCKET}/released/spot_hht.npz")


def test_an_expired_lock_is_taken_over_with_a_warning(store, caplog, monkeypatch):
    kind, _, options, fs = store
    monkeypatch.setenv("HHT3D_LOCK_TIMEOUT", "5")  # a run that does not take it over fails in 5 s
    past = datetime.fromtimestamp(time.time() - 5, timezone.utc).isoformat()
    dead = {"host": "gone-host", "pid": 99999, "run": "R-dead", "started": past, "expires": past}
    fs.pipe_file(f"{BUCKET}/expired/{LOCK}", json.dumps(dead).encode())
    with caplog.at_level(logging.INFO, logger="hht3d"):
        rows = run_dataset(
            shipped_model_path("spot.ply"),
            f"s3://{BUCKET}/expired",
            storage_options=options,
            scheduler="synchronous",
            progress=False,
            max_imfs=2,
        )
    assert [r.status for r in rows] == ["ok"]
    messages = [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING]
    if kind == "moto":
        assert [m for m in messages if "took over" in m] == [
            f"s3://{BUCKET}/expired: took over the output folder's lock of pid 99999 on gone-host (run R-dead, "
            f"started {past}), whose last heartbeat is over 120 s old (its run was killed or lost)"
        ]
    else:
        assert sum(UNLOCKED in m for m in messages) == 1
    assert _lock_record(fs, "expired") is None


def test_a_held_lock_is_kept_fresh_by_its_heartbeat(store, monkeypatch):
    kind, _, options, fs = store
    if kind == "s3rver":
        pytest.skip("s3rver ignores If-None-Match: there is no lock to keep fresh")
    monkeypatch.setattr(url_locks, "HEARTBEAT", 0.3)
    holder = _Holder(f"s3://{BUCKET}/beating", options, "R-beat")
    try:
        first = _lock_record(fs, "beating")
        time.sleep(1.5)
        later = _lock_record(fs, "beating")
    finally:
        holder.release()
    assert later["started"] == first["started"] and later["expires"] > first["expires"]


def test_a_stopped_run_releases_its_lock(store, tmp_path):
    """SIGTERM while ``hht3d run`` holds the lock: the stop (os._exit, no ``with`` block ends) removes it."""
    kind, endpoint, _, fs = store
    if kind == "s3rver":
        pytest.skip("s3rver ignores If-None-Match: no lock is held there")
    pipeline = _pipeline(
        tmp_path, endpoint, f"s3://{BUCKET}/stopped", imfs=4, inputs=("spot.ply", "sphere_oct4098.ply")
    )
    proc = subprocess.Popen(
        [sys.executable, "-m", "hht3d", "run", str(pipeline), "--scheduler", "synchronous", "--quiet"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    try:
        deadline = time.monotonic() + 60
        while _lock_record(fs, "stopped") is None and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        assert _lock_record(fs, "stopped")["pid"] == proc.pid
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == 143 and "stopped by SIGTERM" in err, err
    assert _lock_record(fs, "stopped") is None


def test_a_store_without_conditional_writes_warns_once_at_run_start(caplog):
    with caplog.at_level(logging.WARNING, logger="hht3d"):
        rows = run_dataset(
            shipped_model_path("spot.ply"), "memory://unlocked", scheduler="synchronous", progress=False, max_imfs=2
        )
    assert [r.status for r in rows] == ["ok"]
    assert [r.getMessage() for r in caplog.records if UNLOCKED in r.getMessage()] == [
        "memory://unlocked: the output folder is not locked, as this store has no conditional writes here: if two "
        "runs write into it at once, the last writer wins (see Safety in the user guide)"
    ]


def test_a_stop_while_the_lock_is_written_releases_it(store, monkeypatch):
    """A stop that reaches the run after its lock object landed on the store but before the run knew
    it held it (the create request still in flight): the stop's release_all removes the object."""
    from hht3d.stopping import Stopped

    kind, endpoint, options, fs = store
    if kind == "s3rver":
        pytest.skip("s3rver ignores If-None-Match: no lock is held there")
    checked = url_locks._checked

    def stopped_after_writing(*args):
        checked(*args)._stop.set()  # the object is on the store now; no heartbeat
        raise Stopped(signal.SIGTERM)

    monkeypatch.setattr(url_locks, "_checked", stopped_after_writing)
    with pytest.raises(Stopped):
        with url_locks.url_lock(f"s3://{BUCKET}/in-flight", options, "run-in-flight"):
            pass
    assert _lock_record(fs, "in-flight")["run"] == "run-in-flight"
    url_locks.release_all()
    assert _lock_record(fs, "in-flight") is None
