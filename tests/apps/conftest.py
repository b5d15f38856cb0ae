"""Fixtures of the filtering tests."""

from __future__ import annotations

import pytest

from helpers.bumps import AMPLITUDE, WAVES
from helpers.meshes import bump_band_sphere
from hht3d import Surface
from hht3d.geometry.signals import mean_curvature
from hht3d.transform import hht


@pytest.fixture(scope="module")
def bumps():
    """(surface, clean unit-sphere vertices, unit bump pattern, HHT of the mean curvature)."""
    v, f, clean, pattern = bump_band_sphere(5, WAVES, AMPLITUDE)
    surface = Surface(v, f, name="bump_band_sphere")
    return surface, clean, pattern, hht(surface, mean_curvature(surface), max_imfs=4)
