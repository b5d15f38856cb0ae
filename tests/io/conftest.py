"""Fixtures of the io tests."""
import pytest

from hht3d import Surface
from helpers.meshes import icosphere


@pytest.fixture
def sphere():
    return Surface(*icosphere(2), name="sphere")
