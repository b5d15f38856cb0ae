"""Fixtures of the geometry tests."""

import pytest

from helpers.meshes import icosphere
from hht3d import Surface


@pytest.fixture(scope="module")
def sphere():
    return Surface(*icosphere(5))
