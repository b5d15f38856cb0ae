"""Fixtures of the io tests."""

import pytest

from helpers.meshes import icosphere
from hht3d import Surface


@pytest.fixture
def sphere():
    return Surface(*icosphere(2), name="sphere")
