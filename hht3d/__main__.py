"""``python -m hht3d`` and the ``hht3d`` command: the stop handlers first, then the command line.

Loading the command line takes about half a second (numpy, scipy, Open3D, Dask).  The SIGTERM
and SIGINT handlers of :mod:`hht3d.stopping` are installed before it, here, so a signal at any
moment after the interpreter starts ends the command with one line, ``hht3d: stopped by
SIGTERM``, and exit 143 (130 for SIGINT), never a silent -15.  (``import hht3d`` itself is light:
its exports load on first use.)
"""

from __future__ import annotations

import sys

from .stopping import Stopped, stop_on_signals


def main() -> int:
    """Run the ``hht3d`` command (:func:`hht3d.cli.main`) with its stop handlers installed first."""
    try:
        with stop_on_signals():
            from .cli import main as run_command

            return run_command()
    except Stopped as stop:  # before the command line loaded: nothing started, nothing to clean
        print(f"hht3d: stopped by {stop}", file=sys.stderr)
        return stop.exit_code


if __name__ == "__main__":
    sys.exit(main())
