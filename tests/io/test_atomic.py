"""Atomic writes (hht3d.io.atomic): nothing left by a failed write, output paths probed without a trace, stale
temporaries of a killed run removed at the start of the next."""

import os
import subprocess
import sys

import numpy as np
import pytest

from helpers.processes import PIPELINE, _env
from hht3d.errors import OutputError
from hht3d.io import atomic_path, check_output_paths, write_npz


def _current_umask() -> int:
    import os

    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_atomic_write_leaves_nothing_on_failure(tmp_path):
    target = tmp_path / "x.npz"
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_bytes(b"partial")
            raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []
    write_npz(target, {"a": np.arange(3)})
    assert np.load(target)["a"].tolist() == [0, 1, 2]
    assert target.stat().st_mode & 0o777 == 0o666 & ~_current_umask()  # like an ordinary write


def test_output_paths_are_probed_without_leaving_anything(tmp_path):
    (tmp_path / "file").write_text("x")
    (tmp_path / "dir.npz").mkdir()
    check_output_paths([tmp_path / "new" / "deeper" / "a.npz", tmp_path / "b.npz"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dir.npz", "file"]
    for path, message in [
        (tmp_path / "file" / "a.npz", "file is not a folder"),
        (tmp_path / "dir.npz", "a folder of that name is in the way"),
        (tmp_path / ("x" * 300) / "a.npz", "File name too long"),
    ]:
        with pytest.raises(OutputError, match=message):
            check_output_paths([path])


@pytest.mark.slow  # a real CLI process
def test_stale_temporaries_of_a_killed_run_are_removed_at_start(job):
    """A ``.NAME.PID-XXXXXXXX.part`` of a process that has ended is removed; one of a live process is not."""
    out = job / "out"
    out.mkdir()
    ended = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    stale = out / f".s0_hht.npz.{int(ended.stdout)}-abcdefgh.part"
    live = out / f".s0_hht.npz.{os.getpid()}-abcdefgh.part"
    stale.write_bytes(b"half")
    live.write_bytes(b"being written")
    (job / "p.yaml").write_text(
        PIPELINE.format(inputs=job / "scans" / "s0.ply", out=out).replace("max_imfs: 2", "max_imfs: 1")
    )
    done = subprocess.run(
        [sys.executable, "-m", "hht3d", "run", str(job / "p.yaml"), "--quiet", "--scheduler", "synchronous"],
        capture_output=True,
        text=True,
        cwd=job,
        env=_env(),
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert not stale.exists() and live.read_bytes() == b"being written"


def _swap_for_link(folder, target) -> None:
    folder.rmdir()
    folder.symlink_to(target)


def test_a_folder_swapped_for_a_link_before_the_write_is_refused_at_the_rename(tmp_path):
    """The checks passed on a real ``out/sub``; the writer then finds it swapped for a link to a folder
    holding the user's file of the output's name: refused at the rename, the user's file kept."""
    from hht3d.io.manifest import Recorded, entries

    (tmp_path / "out" / "sub").mkdir(parents=True)
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "elsewhere" / "a.npz").write_bytes(b"mine")

    def write(path):
        _swap_for_link(tmp_path / "out" / "sub", tmp_path / "elsewhere")
        write_npz(path, {"x": np.arange(3.0)})

    with pytest.raises(
        OutputError,
        match=r"a.npz: not written: its folder now resolves to .*elsewhere, outside the "
        r"output folder .*out \(swapped for a link after the check\?\)",
    ):
        Recorded(write, tmp_path / "out", "R")(tmp_path / "out" / "sub" / "a.npz")
    assert sorted(os.listdir(tmp_path / "elsewhere")) == ["a.npz"]
    assert (tmp_path / "elsewhere" / "a.npz").read_bytes() == b"mine" and entries(tmp_path / "out") == {}


def test_a_folder_swapped_while_the_file_is_written_is_not_renamed_into(tmp_path):
    """The temporary file is made in the real folder; the folder is swapped for a link before the writer
    writes it: nothing is renamed, the user's file kept, and neither temporary file stays."""
    (tmp_path / "out").mkdir()
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "elsewhere" / "a.bin").write_bytes(b"mine")
    with pytest.raises(
        OutputError,
        match=r"a.bin: not written: its folder .*out was replaced while the file was "
        "written",
    ):
        with atomic_path(tmp_path / "out" / "a.bin") as tmp:
            os.rename(tmp_path / "out", tmp_path / "moved")
            (tmp_path / "out").symlink_to(tmp_path / "elsewhere")
            tmp.write_bytes(b"output")
    assert sorted(os.listdir(tmp_path / "elsewhere")) == ["a.bin"] and os.listdir(tmp_path / "moved") == []
    assert (tmp_path / "elsewhere" / "a.bin").read_bytes() == b"mine"


def test_the_temporary_file_is_new_and_not_a_link(tmp_path, monkeypatch):
    """A link planted under the temporary name is not followed: another name is taken."""
    import uuid

    names = iter(["0" * 32, "1" * 32])
    monkeypatch.setattr(uuid, "uuid4", lambda: type("U", (), {"hex": next(names)})())
    planted = tmp_path / f".a.bin.{os.getpid()}-00000000.part"
    planted.symlink_to(tmp_path / "victim")
    with atomic_path(tmp_path / "a.bin") as tmp:
        assert tmp.name.endswith("-11111111.part")
        tmp.write_bytes(b"output")
    assert (tmp_path / "a.bin").read_bytes() == b"output" and not (tmp_path / "victim").exists()
