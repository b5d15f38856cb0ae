"""Workers of a local process pool (hht3d.execution.workers): they end with their parent."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import psutil
import pytest

import hht3d

RUN = textwrap.dedent("""
    import sys
    import time
    from dask import delayed
    from hht3d.execution import compute, schedulers

    if __name__ == "__main__":
        if sys.argv[1] == "watch":
            from helpers.processes import pool_initializer_without_prctl

            schedulers.limit_blas_threads = pool_initializer_without_prctl
        compute(*[delayed(time.sleep, pure=False)(120) for _ in range(2)], scheduler="processes", workers=2,
                progress=False)
""")


@pytest.mark.slow
@pytest.mark.parametrize(
    "how",
    [
        pytest.param(
            "kernel",
            marks=pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's"),
        ),
        "watch",
    ],
)
def test_pool_workers_end_when_their_parent_is_killed(tmp_path, how):
    """SIGKILL leaves the parent no chance to stop its workers (before, they went on computing with
    parent PID 1 inside a 120 s task).  ``kernel``: Linux's PR_SET_PDEATHSIG ends them; ``watch``:
    prctl unused, as on macOS and Windows, so the workers' own check of their parent must end them,
    within a task, in about PARENT_CHECK (measured 0.51-0.53 s; the kernel: 0.02 s)."""
    script = tmp_path / "run.py"
    script.write_text(RUN)
    root = Path(hht3d.__file__).parents[1]  # the hht3d under test, and the tests' helpers
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(root), str(root / "tests")])}
    parent = subprocess.Popen([sys.executable, str(script), how], env=env)
    try:
        deadline = time.monotonic() + 60
        while len(workers := psutil.Process(parent.pid).children()) < 2 and time.monotonic() < deadline:
            time.sleep(0.2)
        assert len(workers) >= 2
        time.sleep(2)  # the workers' initializer has run
    finally:
        parent.kill()
        parent.wait(10)
    killed = time.monotonic()
    deadline = killed + 10
    while (running := [w for w in workers if _running(w)]) and time.monotonic() < deadline:
        time.sleep(0.1)
    for process in running:
        process.kill()
    assert running == [], f"workers still running {time.monotonic() - killed:.1f} s after their parent's SIGKILL"


def _running(process: psutil.Process) -> bool:
    try:
        return process.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


UNGUARDED = textwrap.dedent("""
    from hht3d import data_path
    from hht3d.dataset import run_dataset

    run_dataset([data_path("spot.ply")], "out", scheduler="{scheduler}", workers=2, max_imfs=1)
""")


@pytest.mark.parametrize("scheduler", ["distributed", "processes"])
def test_a_run_at_a_scripts_top_level_fails_naming_the_fix(scheduler, tmp_path):
    """Each spawned worker imports the script again: outside `if __name__ == "__main__":` the run
    hung for 17 minutes without a word (Dask's own bootstrap error hidden); now one line at once."""
    script = tmp_path / "run.py"
    script.write_text(UNGUARDED.format(scheduler=scheduler))
    env = {**os.environ, "PYTHONPATH": str(Path(hht3d.__file__).parents[1])}
    done = subprocess.run(
        [sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=60, env=env
    )
    assert done.returncode == 1
    assert f"run.py:5: the {scheduler} scheduler starts worker processes" in done.stderr
    assert 'put the call under `if __name__ == "__main__":`' in done.stderr
    assert not (tmp_path / "out").exists()


def test_a_worker_whose_parent_ended_writes_and_records_nothing(tmp_path, monkeypatch):
    """A worker finishing a write just after its run's process ended (before the kernel or its check
    ends it) renames nothing and records nothing in the manifest; while the parent runs, it writes."""
    from hht3d.errors import OutputError
    from hht3d.io import atomic
    from hht3d.io.manifest import entries, recording

    def write(name: str) -> None:
        with recording(tmp_path, "run-1"), atomic.atomic_path(tmp_path / name) as tmp:
            tmp.write_bytes(b"result")

    monkeypatch.setattr(atomic, "_PARENT", os.getppid())
    write("early.npz")
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    monkeypatch.setattr(atomic, "_PARENT", gone.pid)  # not this process's parent: it ended
    with pytest.raises(OutputError, match=f"the run's process {gone.pid} has ended"):
        write("late.npz")
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith(".hht3d")) == ["early.npz"]
    assert set(entries(tmp_path)) == {"early.npz"}
