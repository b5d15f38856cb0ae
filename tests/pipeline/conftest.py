"""Fixtures of the pipeline tests: a bumpy sphere, a point cloud and a folder of two scans, as files."""

import numpy as np
import pytest

from helpers.meshes import bumpy_sphere, fibonacci_sphere
from helpers.pipelines import bumpy_file
from hht3d import Surface
from hht3d.io import write_ply


@pytest.fixture
def mesh_file(tmp_path):
    return bumpy_file(tmp_path / "in")


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
        write_ply(path / f"part{i}.ply", Surface(*bumpy_sphere(waves=5 + i, scale=1 + i)))
    return path
