"""Fixtures of the geometry tests."""
import pytest

from hht3d import Surface
from helpers.meshes import icosphere


@pytest.fixture(scope="module")
def sphere():
    return Surface(*icosphere(5))
