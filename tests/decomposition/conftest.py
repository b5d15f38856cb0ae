"""Fixtures of the EMD tests."""
import pytest

from hht3d import Surface
from helpers.meshes import icosphere


@pytest.fixture(scope="module")
def sphere():
    """Icosphere with 10,242 nearly uniform vertices."""
    return Surface(*icosphere(5), name="icosphere5")


@pytest.fixture(scope="module")
def small_sphere():
    return Surface(*icosphere(3), name="icosphere3")
