"""Fixtures of the pipeline tests: a bumpy sphere, a point cloud and a folder of two scans, as files."""
import numpy as np
import pytest
from helpers.meshes import fibonacci_sphere, icosphere

from hht3d import Surface
from hht3d.io import write_ply


def _bumpy(subdivisions=2, waves=5, scale=1.0):
    v, f = icosphere(subdivisions)
    return scale * v * (1 + 0.06 * np.sin(waves * v[:, [0]]) * np.cos(4 * v[:, [1]])), f


@pytest.fixture
def mesh_file(tmp_path):
    path = tmp_path / "in" / "bumpy.ply"
    path.parent.mkdir(exist_ok=True)
    write_ply(path, Surface(*_bumpy(), name="bumpy"))
    return path


@pytest.fixture
def cloud_file(tmp_path):
    path = tmp_path / "in" / "cloud.ply"
    path.parent.mkdir(exist_ok=True)
    points = fibonacci_sphere(300)
    write_ply(path, Surface(points * (1 + 0.06 * np.sin(5 * points[:, [0]])), name="cloud"))
    return path


@pytest.fixture
def folder(tmp_path):
    path = tmp_path / "scans"
    path.mkdir()
    for i in range(2):
        write_ply(path / f"part{i}.ply", Surface(*_bumpy(waves=5 + i, scale=1 + i)))
    return path
