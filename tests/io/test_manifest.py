"""The output folder's lock and manifest as untrusted, shared things: who holds the lock, how long a run waits
for it, and a lock file that is not hht3d's (the CLI's cases are rows of tests/cli/test_bad_outputs.py)."""

from __future__ import annotations

import json
import os
import re
import socket
import subprocess
import sys

import pytest

from helpers.bad_inputs import PIPELINE, ROOT, _substitute
from hht3d.cli import main
from hht3d.errors import OutputError
from hht3d.io.lock import LOCK, folder_lock, lock_timeout
from hht3d.io.manifest import entries, valid_entries

HOLD = (
    "import sys, time\nfrom hht3d.io.lock import folder_lock\n"
    "with folder_lock(sys.argv[1], 'R-holder'):\n    print('held', flush=True)\n    time.sleep(120)\n"
)


@pytest.fixture
def held(tmp_path):
    """``(folder, pid)``: ``<tmp>/out`` locked by another live process (ended afterwards)."""
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(tmp_path / "out")],
        stdout=subprocess.PIPE,
        text=True,
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    try:
        assert holder.stdout.readline().strip() == "held"
        yield tmp_path / "out", holder.pid
    finally:
        holder.kill()
        holder.wait(timeout=20)


def test_a_held_lock_names_its_holder_and_times_out(held, monkeypatch, caplog):
    folder, pid = held
    assert json.loads((folder / LOCK).read_text()) == {"pid": pid, "host": socket.gethostname(), "run": "R-holder"}
    monkeypatch.setenv("HHT3D_LOCK_TIMEOUT", "0.5")
    holder = f"pid {pid} on {socket.gethostname()} (run R-holder)"
    with caplog.at_level("INFO", logger="hht3d.io"):
        with pytest.raises(OutputError, match=re.escape(f"{holder} still holds the output folder's lock after 0.5 s")):
            with folder_lock(folder):
                pass
    assert [r.getMessage() for r in caplog.records] == [
        f"{folder}: waiting for {holder}, which holds the output folder's lock (at most 0.5 s)"
    ]


def test_a_run_into_a_locked_folder_says_who_holds_it_and_stops(held, inputs, tmp_path, capfd, monkeypatch):
    folder, pid = held
    (tmp_path / "p.yaml").write_text(_substitute(PIPELINE, {"in": inputs, "out": folder}))
    monkeypatch.setenv("HHT3D_LOCK_TIMEOUT", "1")
    assert main(["run", str(tmp_path / "p.yaml")]) == 1
    out, err = capfd.readouterr()
    assert f"waiting for pid {pid} on {socket.gethostname()} (run R-holder)" in out
    assert err.count("\n") == 1 and f"pid {pid} on" in err and "still holds the output folder's lock after 1 s" in err
    assert sorted(p.name for p in folder.iterdir()) == [LOCK]


def test_the_lock_is_free_again_once_its_holder_is_killed(held):
    folder, pid = held
    os.kill(pid, 9)
    os.waitpid(pid, 0)
    with folder_lock(folder, "R-next"):
        assert json.loads((folder / LOCK).read_text())["run"] == "R-next"


@pytest.mark.parametrize("value", ["soon", "-1", "nan"])
def test_a_bad_lock_timeout_is_one_line(value, monkeypatch):
    monkeypatch.setenv("HHT3D_LOCK_TIMEOUT", value)
    with pytest.raises(OutputError, match="HHT3D_LOCK_TIMEOUT=.*not a number of seconds"):
        lock_timeout()


def test_a_lock_file_linking_outside_is_neither_created_nor_locked(tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / LOCK).symlink_to(tmp_path / "victim")
    with pytest.raises(OutputError, match="lock file is a link or not a regular file"):
        with folder_lock(tmp_path / "out"):
            pass
    assert not (tmp_path / "victim").exists()


def test_only_well_formed_entries_inside_the_folder_count(tmp_path):
    good = {"size": 3, "sha256": "a" * 64}
    data = {
        "files": {
            "a.npz": good,
            "sub/../b.npz": good,
            "../c.npz": good,
            "/d.npz": good,
            "e.npz": {**good, "size": True},
            "f.npz": {**good, "sha256": "x"},
            "g.npz": [good],
            7: good,
        }
    }
    assert sorted(valid_entries(data)) == ["a.npz", "b.npz"]
    (tmp_path / "out").mkdir()
    (tmp_path / "outside").mkdir()
    (tmp_path / "out" / "link").symlink_to(tmp_path / "outside")
    (tmp_path / "out" / ".hht3d-manifest.json").write_text(json.dumps({"files": {"a.npz": good, "link/x.npz": good}}))
    assert sorted(entries(tmp_path / "out")) == ["a.npz"]
