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
    import time
    from dask import delayed
    from hht3d.execution import compute

    if __name__ == "__main__":
        compute(*[delayed(time.sleep, pure=False)(120) for _ in range(2)], scheduler="processes", workers=2,
                progress=False)
""")


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's")
def test_pool_workers_end_when_their_parent_is_killed(tmp_path):
    """SIGKILL leaves the parent no chance to stop its workers; the kernel ends them (before, they
    went on computing with parent PID 1)."""
    script = tmp_path / "run.py"
    script.write_text(RUN)
    env = {**os.environ, "PYTHONPATH": str(Path(hht3d.__file__).parents[1])}  # the hht3d under test
    parent = subprocess.Popen([sys.executable, str(script)], env=env)
    try:
        deadline = time.monotonic() + 60
        while len(workers := psutil.Process(parent.pid).children()) < 2 and time.monotonic() < deadline:
            time.sleep(0.2)
        assert len(workers) >= 2
        time.sleep(2)  # the workers' initializer has run
    finally:
        parent.kill()
        parent.wait(10)
    deadline = time.monotonic() + 10
    while (running := [w for w in workers if _running(w)]) and time.monotonic() < deadline:
        time.sleep(0.2)
    for process in running:
        process.kill()
    assert running == []


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
