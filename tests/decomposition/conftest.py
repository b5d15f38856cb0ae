"""Fixtures of the EMD tests."""

import pytest

from helpers.meshes import icosphere
from hht3d import Surface


@pytest.fixture(scope="module")
def sphere():
    """Icosphere with 10,242 nearly uniform vertices."""
    return Surface(*icosphere(5), name="icosphere5")


@pytest.fixture(scope="module")
def small_sphere():
    return Surface(*icosphere(3), name="icosphere3")
