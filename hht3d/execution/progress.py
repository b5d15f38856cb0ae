"""Progress of a local scheduler: a redrawn bar on a terminal or in a notebook, rate-limited plain lines otherwise.

The plain lines are records of the ``hht3d.progress`` logger (:mod:`hht3d.logs`):
:func:`hht3d.execution.compute` shows them on stderr unless the application has
configured logging.
"""

from __future__ import annotations

import importlib.util
import sys
import time
from typing import Any

from dask.callbacks import Callback

from ..logs import PROGRESS, get_logger

__all__ = ["PROGRESS_INTERVAL", "ProgressLines", "local_progress", "is_terminal", "in_notebook"]

#: Seconds between progress lines when stderr is not a terminal.
PROGRESS_INTERVAL = 10.0
_LOG = get_logger(PROGRESS)


def is_terminal(stream: Any) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):  # no isatty, or closed
        return False


def in_notebook() -> bool:
    """True inside a Jupyter kernel that can show widgets (IPython's kernel shell, ipywidgets installed).

    IPython is never imported here: outside a notebook it is not loaded, or loaded without a kernel.
    """
    ipython = sys.modules.get("IPython")
    shell = None if ipython is None else ipython.get_ipython()
    return getattr(shell, "kernel", None) is not None and importlib.util.find_spec("ipywidgets") is not None


def local_progress() -> Any:
    """A redrawn bar on a terminal or in a notebook (whose output redraws a ``\\r`` line); rate-limited
    plain lines otherwise."""
    if is_terminal(sys.stderr) or in_notebook():
        from dask.diagnostics import ProgressBar

        return ProgressBar(minimum=1.0, out=sys.stderr)
    return ProgressLines()


class ProgressLines(Callback):
    """Progress of a local scheduler as plain log lines, ``hht3d: 40% of 125 tasks done, 12 s``.

    At most one line per ``interval`` seconds (default
    :data:`PROGRESS_INTERVAL`), and a last one when the run took longer than
    that: a log of a long run gets a few lines, not a redrawn bar's thousands
    of updates.
    """

    def __init__(self, interval: float | None = None):
        super().__init__()
        self.interval = PROGRESS_INTERVAL if interval is None else interval
        self.start = self.last = time.monotonic()

    def _start_state(self, dsk: Any, state: Any) -> None:
        self.start = self.last = time.monotonic()

    def _posttask(self, key: Any, result: Any, dsk: Any, state: Any, worker_id: Any) -> None:
        now = time.monotonic()
        if now - self.last >= self.interval:
            self.last = now
            self._line(state, now)

    def _finish(self, dsk: Any, state: Any, errored: bool) -> None:
        now = time.monotonic()
        if now - self.start >= self.interval and not errored:
            self._line(state, now)

    def _line(self, state: dict, now: float) -> None:
        done = len(state["finished"])
        total = done + sum(len(state[k]) for k in ("ready", "waiting", "running"))
        _LOG.info("%d%% of %d tasks done, %.0f s", 100 * done // max(total, 1), total, now - self.start)
