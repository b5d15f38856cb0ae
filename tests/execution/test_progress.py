"""Progress of a computation (hht3d.execution): into a log, a few plain lines."""

from __future__ import annotations

import re
import time

from dask import delayed

from hht3d.execution import compute


def test_progress_into_a_log_is_a_few_plain_lines(monkeypatch, capfd):
    """A long run into a log (stderr not a terminal): a line per interval, not a bar redrawn 10 times a second."""
    monkeypatch.setattr("hht3d.execution.progress.PROGRESS_INTERVAL", 0.1)
    tasks = [delayed(time.sleep, pure=False)(0.02) for _ in range(40)]
    compute(*tasks, scheduler="synchronous", progress=True)
    lines = capfd.readouterr().err.splitlines()
    assert 3 <= len(lines) <= 12, lines
    assert all(re.fullmatch(r"hht3d: \d+% of 40 tasks done, \d+ s", line) for line in lines), lines
    assert lines[-1].startswith("hht3d: 100% of 40 tasks done")
