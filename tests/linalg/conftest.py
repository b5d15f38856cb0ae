"""Fixtures of the solver-backend tests."""

from pathlib import Path

import pytest

import hht3d

SPOT = Path(hht3d.__file__).parent / "data" / "spot.ply"


@pytest.fixture(scope="module")
def spot():
    return hht3d.load(SPOT)
