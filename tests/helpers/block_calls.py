"""Module-level functions for the tests of :mod:`hht3d.geometry.block_processes`: a child process
imports them by name, so they cannot live in a test module."""

from __future__ import annotations

import os

import numpy as np


def doubled(values: np.ndarray) -> np.ndarray:
    """Twice ``values``, after writing to descriptor 1 as native code would."""
    os.write(1, b"native output on stdout\n")
    return 2 * values


def refused(values: np.ndarray) -> np.ndarray:
    raise ValueError(f"block of {len(values)} refused")


def ended(values: np.ndarray) -> np.ndarray:
    os._exit(3)


def process_id(_: int) -> int:
    return os.getpid()
