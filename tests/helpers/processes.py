"""Real ``hht3d run`` processes for the tests of stops and losses (issue 23): the pipeline they run, their
environment (this checkout on ``PYTHONPATH``), what they recorded, bounded waits."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from hht3d.io.manifest import MANIFEST

ROOT = Path(__file__).resolve().parents[2]
#: Seconds the CLI is given to stop after a signal, and a lost cluster to be reported.
STOP_WITHIN = 20
PIPELINE = """\
version: 1
inputs: {inputs}
steps:
  - {{op: signal, params: {{kind: mean_curvature}}}}
  - {{op: hht, params: {{max_imfs: 2}}}}
outputs:
  folder: {out}
  files:
    - {{path: "{{stem}}_hht.npz"}}
    - {{path: "{{stem}}_hht.png"}}
"""


def _env(**extra) -> dict:
    return {**os.environ, "PYTHONPATH": str(ROOT), **extra}


def _start(job: Path, *args: str, env=None) -> subprocess.Popen:
    """``hht3d run`` in its own session (so that a signal to its group is what a terminal's Ctrl-C does)."""
    return subprocess.Popen(
        [sys.executable, "-m", "hht3d", "run", str(job / "p.yaml"), "--quiet", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=job,
        env=env or _env(),
        start_new_session=True,
    )


def _recorded(out: Path) -> dict:
    try:
        return json.loads((out / MANIFEST).read_text())["files"]
    except (OSError, ValueError, KeyError):
        return {}


def _wait_for(condition, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            pytest.fail(f"timed out after {timeout} s waiting for {what}")
        time.sleep(0.1)


def pool_initializer_without_prctl(parent: int, storage_options: dict | None = None) -> None:
    """The process pool's initializer as on a platform without ``PR_SET_PDEATHSIG`` (macOS, Windows):
    the worker must end through its own check of the parent (importable by spawned workers)."""
    from hht3d.execution import workers

    workers._kernel_ends_worker = lambda: False
    workers.limit_blas_threads(parent, storage_options)
