"""Checks on rendered images."""

from __future__ import annotations

import numpy as np


def assert_red_blue_swapped(image, flipped, changed=None) -> "np.ndarray":
    """Two RGB renderings (0-255) of a field f and of −f with the same symmetric diverging colour
    scale: wherever they differ by more than 60 levels (or on the given mask), red and blue swap
    (the sign of red − blue flips at ≥ 95% of those pixels).  Returns the mask used."""
    if changed is None:
        changed = np.abs(image - flipped).max(axis=2) > 60
    warm = image[..., 0] - image[..., 2]
    cool = flipped[..., 0] - flipped[..., 2]
    assert changed.any()
    assert np.mean(np.sign(warm[changed]) == -np.sign(cool[changed])) > 0.95
    return changed
