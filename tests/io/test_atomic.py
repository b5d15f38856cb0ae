"""Atomic writes (hht3d.io.atomic): nothing left by a failed write, output paths probed without a trace, stale
temporaries of a killed run removed at the start of the next."""
import os
import subprocess
import sys

import numpy as np
import pytest

from hht3d.errors import OutputError
from hht3d.io import atomic_path, check_output_paths, write_npz
from helpers.processes import PIPELINE, _env


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
    for path, message in [(tmp_path / "file" / "a.npz", "file is not a folder"),
                          (tmp_path / "dir.npz", "a folder of that name is in the way"),
                          (tmp_path / ("x" * 300) / "a.npz", "File name too long")]:
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
    (job / "p.yaml").write_text(PIPELINE.format(inputs=job / "scans" / "s0.ply", out=out)
                                .replace("max_imfs: 2", "max_imfs: 1"))
    done = subprocess.run([sys.executable, "-m", "hht3d", "run", str(job / "p.yaml"), "--quiet",
                           "--scheduler", "synchronous"], capture_output=True, text=True, cwd=job, env=_env(),
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert not stale.exists() and live.read_bytes() == b"being written"
