"""Fixtures of the spectral tests: the shipped model spot, a point cloud, a jittered grid, a cylinder's waves."""

from __future__ import annotations

import numpy as np
import pytest

import hht3d
from helpers.meshes import fibonacci_sphere, grid, open_cylinder
from helpers.models import shipped_model_path
from helpers.spectral import LENGTH, RADIUS, WAVENUMBERS
from hht3d.geometry.surface import Surface

SPOT = shipped_model_path("spot.ply")


@pytest.fixture(scope="module")
def spot():
    return hht3d.load(SPOT)


@pytest.fixture(scope="module")
def cloud():
    return Surface(fibonacci_sphere(2000), None)


@pytest.fixture(scope="module")
def jittered_grid():
    return Surface(*grid(30, 20, 1.5, 1.0, jitter=0.3))


@pytest.fixture(scope="module")
def cylinder():
    # 128 vertices around: 16 per period at k = 8; 60 rings over length 6.
    return Surface(*open_cylinder(60, 128, length=LENGTH, radius=RADIUS))


@pytest.fixture(scope="module")
def cylinder_waves(cylinder):
    theta = np.arctan2(cylinder.vertices[:, 1], cylinder.vertices[:, 0])
    return np.stack([np.cos(k * theta) for k in WAVENUMBERS])
